// A pixel's samples traced through the walk queue (walk_queue.glsl), two paths at a time: rounds
// in which each lane queues its paths' rays, the subgroup walks the queue, and each lane takes
// its paths through the vertices their rays met. Two paths a lane give the queue twice the walks
// to share out (docs/benchmarks/history.md: one path a lane gained half as much).
//
// The sums are the plain kernel's bit for bit: each vertex is path_vertex's, its shadow ray traced
// in the next round beside the path's next ray and its light added before that vertex's, in the
// order the plain kernel adds them; and the samples are added in sample order, a path whose
// sample ends before the other's earlier one holding it (and starting no other) until that one
// is added.

// One of a lane's two paths in flight.
struct QueuedPath {
    Rng rng;
    Path path;
    FirstHit first_hit;
    uint sample_index;  // which of the pixel's samples it is
    bool tracing;     // its ray is traced this round
    bool shadowing;   // its last vertex's shadow ray is traced this round
    bool ended;       // no vertex is left: once its shadow ray is in, its sample waits to be added
    ShadowRay shadow;
    Hit path_hit;
    Hit shadow_hit;
    uint path_first;
    uint path_walks;
    uint shadow_first;
    uint shadow_walks;
};

QueuedPath idle_path() {
    QueuedPath p;
    p.tracing = false;
    p.shadowing = false;
    p.ended = false;
    return p;
}

bool path_is_idle(QueuedPath p) {
    return !p.tracing && !p.shadowing && !p.ended;
}

// Starts sample `s` of the pixel on idle path p.
void start_queued_sample(inout QueuedPath p, uvec2 pixel, uint index, uint s) {
    start_sample(pixel, index, s, p.rng, p.path, p.first_hit);
    p.sample_index = s;
    p.tracing = path_ray_wanted(p.path, p.rng);
    p.ended = !p.tracing;
}

// Adds p's sample to the sums if it is complete and the next in order.
void add_if_next(inout QueuedPath p, inout uint next_sample, inout PixelSums sums) {
    if (p.ended && !p.shadowing && p.sample_index == next_sample) {
        add_sample(sums, p.path.radiance, p.first_hit);
        p.ended = false;
        next_sample += 1u;
    }
}

// Queues p's rays for this round.
void queue_path_rays(inout QueuedPath p, inout uint rays) {
    p.path_walks = 0u;
    p.shadow_walks = 0u;
    if (p.tracing) {
        rays += 1u;
        p.path_walks = queue_ray(p.path.origin, p.path.dir, 1e30, false, p.path_hit, p.path_first);
    }
    if (p.shadowing) p.shadow_walks = queue_ray(p.shadow.origin, p.shadow.dir, p.shadow.t_max, true, p.shadow_hit, p.shadow_first);
}

// Takes p through what its rays met this round: the shadow ray's light first, then the vertex.
void take_path_hits(inout QueuedPath p, inout uint rays) {
    if (p.shadowing) {
        p.shadowing = false;
        queued_hit(p.shadow_first, p.shadow_walks, p.shadow_hit);
        if (p.shadow_hit.prim == NO_INDEX) p.path.radiance += p.shadow.contribution;
    }
    if (p.tracing) {
        queued_hit(p.path_first, p.path_walks, p.path_hit);
        bool goes_on = path_vertex(p.path, p.rng, rays, p.first_hit, p.path_hit.prim != NO_INDEX, p.path_hit, p.shadowing, p.shadow);
        p.tracing = goes_on && path_ray_wanted(p.path, p.rng);
        p.ended = !p.tracing;
    }
}

// Brings the pixel's sums from sample `s` up to `target`, as pathtrace.comp's own loop does.
// Every lane of the subgroup calls it, those with nothing to render too (target == s): the
// queue is walked by all of them until every lane's samples are in.
void render_queued_samples(uvec2 pixel, uint index, uint s, uint target, inout PixelSums sums, inout uint rays) {
    QueuedPath a = idle_path();
    QueuedPath b = idle_path();
    uint next_sample = s;
    queue_clear();
    while (true) {
        // Add what is complete, in order, and start the next samples on idle paths (a path whose
        // ray max_bounces forbids is complete at once, hence the loop).
        while (true) {
            add_if_next(a, next_sample, sums);
            add_if_next(b, next_sample, sums);
            add_if_next(a, next_sample, sums);
            bool started = false;
            if (path_is_idle(a) && s < target) { start_queued_sample(a, pixel, index, s++); started = true; }
            if (path_is_idle(b) && s < target) { start_queued_sample(b, pixel, index, s++); started = true; }
            if (!started) break;
        }
        if (!subgroupAny(a.tracing || a.shadowing || b.tracing || b.shadowing)) break;
        for (uint k = 0u; k < 2u; ++k) {
            QueuedPath p = k == 0u ? a : b;
            queue_path_rays(p, rays);
            if (k == 0u) a = p;
            else b = p;
        }
        queue_barrier();
        walk_queue();
        queue_barrier();
        // The vertex code inlined once a path: 3-6 % faster on lavapipe than one call site that a
        // and b are copied through, for a longer first compile (Mesa caches it): the queue
        // kernel's takes about 3 s more than the plain kernel's.
        take_path_hits(a, rays);
        take_path_hits(b, rays);
        queue_clear();
    }
}
