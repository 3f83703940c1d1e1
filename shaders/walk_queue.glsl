// The walk queue (kernels with WALK_QUEUE 1: src/render/walk_queue.rs decides where). Where each
// lane walks its own ray, a subgroup runs its longest walk with the other lanes masked: on a mesh
// in a box, lavapipe's node visits run with 1.7 of 8 lanes busy (docs/benchmarks/history.md, 2026-12-01, `7a44715`).
// Here each lane tests its rays against the few shapes and the flat top level itself and queues a
// walk of each instance a ray enters, its ray already in the instance's object space; then every
// lane of the subgroup takes walks from the queue, the next as soon as it has finished one, until
// none is left, so the subgroup's lanes stay busy. Each lane then takes the nearest of its walks'
// hits, in the order it queued them (nearest entry first): the hit trace_ray finds, bit for bit.
//
// Each subgroup has its own queue, so nothing waits for another subgroup. The lanes of a subgroup
// hand walks to each other through shared memory, so queueing, walking and reading must be ordered
// across them: queue_barrier() between the steps of a round. Where the device runs a subgroup's
// lanes in step, as lavapipe's gallivm does (one SIMD thread, each instruction for all lanes
// before the next, so a store by one lane is seen by every later load of another), the host
// compiles it empty (QUEUE_SUBGROUP_BARRIERS 0): gallivm (Mesa 25.0) makes subgroupBarrier() a
// workgroup barrier, which cuts later loops short where the workgroup's subgroups run different
// numbers of rounds. Every other device gets the barrier (src/render/walk_queue.rs).

// Each lane carries two paths (queued_paths.glsl), each with a path ray and a shadow ray, each
// walking at most QUEUE_WALKS_PER_RAY instances (the host's count of walked instances under the
// root, at most four).
const uint QUEUE_WALKS_PER_LANE = 2u * 2u * QUEUE_WALKS_PER_RAY;
const uint QUEUE_LANES = gl_WorkGroupSize.x * gl_WorkGroupSize.y;
// A walk: its object-space origin and t_max (once walked: its hit's t, prim as bits and bary),
// its direction and 1 for any hit (a shadow ray), its instance (with its kind in bit 31) and root
// node. The host keeps these within the device's shared memory (walk_queue.rs, SHARED_BYTES_PER_WALK).
shared vec4 queue_origin[QUEUE_LANES * QUEUE_WALKS_PER_LANE];
shared vec4 queue_dir[QUEUE_LANES * QUEUE_WALKS_PER_LANE];
shared uvec2 queue_instance[QUEUE_LANES * QUEUE_WALKS_PER_LANE];
// Per subgroup: walks queued, and walks taken.
shared uint queue_walk_count[QUEUE_LANES];
shared uint queue_next_walk[QUEUE_LANES];
const uint INSTANCE_KIND_BIT = 0x80000000u;

// Orders one step of a round's shared-memory traffic before the next across the subgroup's lanes.
// Every lane of the subgroup calls it, in uniform control flow.
void queue_barrier() {
#if QUEUE_SUBGROUP_BARRIERS
    subgroupBarrier();
#endif
}

// The first walk of this subgroup's part of the queue.
uint queue_base() {
    return gl_SubgroupID * gl_SubgroupSize * QUEUE_WALKS_PER_LANE;
}

// Empties this subgroup's queue (each round, after every lane has read its hits).
void queue_clear() {
    queue_barrier();
    if (subgroupElect()) {
        queue_walk_count[gl_SubgroupID] = 0u;
        queue_next_walk[gl_SubgroupID] = 0u;
    }
    queue_barrier();
}

// Queues walk `walk` of instance `instance` by the world ray o + t d, 0 < t < t_max, in the
// instance's object space as walk_placed puts it.
void queue_walk(uint walk, uint instance, vec3 o, vec3 d, float t_max, bool any_hit) {
    uvec4 info = load_instances(instance).info;
    vec3 ro, rd;
    uint instance_kind = placed_ray(instance, info, o, d, ro, rd);
    queue_origin[walk] = vec4(ro, t_max);
    queue_dir[walk] = vec4(rd, any_hit ? 1.0 : 0.0);
    queue_instance[walk] = uvec2(instance | (instance_kind == INSTANCE_MESH ? INSTANCE_KIND_BIT : 0u), info.y);
}

// Tests the ray o + t d, 0 < t < t_max, against the few shapes and the top level (its root alone)
// in this lane and queues a walk of each instance it enters, nearest first. `hit` is what the lane
// found itself; the queued walks are `count` from `first`. Returns the count.
uint queue_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit, out uint first) {
    hit = Hit(t_max, NO_INDEX, NO_INDEX, vec2(0.0));
    first = 0u;
    if (few_shapes_hit(o, d, any_hit, hit)) return 0u;
    if (frame.node_count == 0u) return 0u;
    float t0, t1, t2, t3;
    uvec2 c0, c1, c2, c3;
    uint entered = sorted_children(0u, o, safe_inverse(d), hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
    uint count = 0u;
    uint i0 = 0u, i1 = 0u, i2 = 0u, i3 = 0u;
    for (uint k = 1u; k <= entered; ++k) {
        if (kth_entry(k, t0, t1, t2, t3) > hit.t) break;
        uint instance = kth_child(k, c0, c1, c2, c3).x;
        if (!instance_walked(load_instances(instance).info)) continue;
        if (count == 0u) i0 = instance;
        else if (count == 1u) i1 = instance;
        else if (count == 2u) i2 = instance;
        else i3 = instance;
        ++count;
    }
    if (count == 0u) return 0u;
    first = queue_base() + atomicAdd(queue_walk_count[gl_SubgroupID], count);
    // One call site: each is a transform and three stores, and the kernel's size is lavapipe's
    // compile time.
    for (uint j = 0u; j < count; ++j) queue_walk(first + j, j == 0u ? i0 : j == 1u ? i1 : j == 2u ? i2 : i3, o, d, hit.t, any_hit);
    return count;
}

// The nearest of `hit` and the hits of the ray's walks first..first + count, taken in the order
// they were queued: with ties kept by the earlier, as trace_ray keeps them.
void queued_hit(uint first, uint count, inout Hit hit) {
    for (uint k = first; k < first + count; ++k) {
        vec4 r = queue_origin[k];
        if (r.x < hit.t) hit = Hit(r.x, floatBitsToUint(r.y), queue_instance[k].x & ~INSTANCE_KIND_BIT, r.zw);
    }
}

// Walks this subgroup's queued walks, each from its instance's root as walk_instance does, a lane
// taking the next as soon as it has finished one, until none is left; each walk's hit replaces
// its origin. Every lane of the subgroup calls it.
void walk_queue() {
    uint count = queue_walk_count[gl_SubgroupID];
    uint base = queue_base();
    uint walk = NO_INDEX;
    Hit hit;
    vec3 ro, rd, inv_d;
    bool any_hit = false;
    uint instance_kind = INSTANCE_MESH;
    uint instance = 0u;
    uint stack[STACK_SIZE];
    uint sp = 0u;
    uint node_index = NO_INDEX;
    while (true) {
        if (node_index == NO_INDEX && sp == 0u) {
            // This lane's walk is done (or it has none yet): record it and take the next.
            if (walk != NO_INDEX) queue_origin[walk] = vec4(hit.t, uintBitsToFloat(hit.prim), hit.bary);
            walk = atomicAdd(queue_next_walk[gl_SubgroupID], 1u);
            if (walk >= count) break;
            walk += base;
            vec4 o = queue_origin[walk];
            vec4 d = queue_dir[walk];
            uvec2 w = queue_instance[walk];
            instance = w.x & ~INSTANCE_KIND_BIT;
            instance_kind = (w.x & INSTANCE_KIND_BIT) != 0u ? INSTANCE_MESH : INSTANCE_PRIMITIVES;
            ro = o.xyz;
            rd = d.xyz;
            inv_d = safe_inverse(rd);
            any_hit = d.w != 0.0;
            hit = Hit(o.w, NO_INDEX, instance, vec2(0.0));
            node_index = w.y;
        } else if (node_index == NO_INDEX) {
            // As walk_instance pops: a node entered beyond the hit is left unloaded.
            uint entry = stack[--sp];
            if (entry_bound(entry) > hit.t) continue;
            node_index = entry_node(entry);
        }
        // One node, as walk_instance's walk down: leaf children intersected, the nearest interior
        // child next, the others on the stack.
        float t0, t1, t2, t3;
        uvec2 c0, c1, c2, c3;
        uint entered = sorted_children(node_index, ro, inv_d, hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
        uint next = NO_INDEX;
        float t_next = 0.0;
        bool done = false;
        for (uint k = entered; k > 0u; --k) {
            float t_k = kth_entry(k, t0, t1, t2, t3);
            uvec2 c = kth_child(k, c0, c1, c2, c3);
            if (t_k > hit.t) continue;
            if (c.y == WIDE_CHILD_INTERIOR) {
                if (next != NO_INDEX) stack[sp++] = stack_entry(next, t_next);
                next = c.x;
                t_next = t_k;
            } else if (leaf_hit(c.x, c.y, instance, instance_kind, ro, rd, any_hit, hit)) {
                done = true;
                break;
            }
        }
        // A shadow ray's walk ends at its first hit.
        if (done) { sp = 0u; next = NO_INDEX; }
        node_index = next;
    }
}
