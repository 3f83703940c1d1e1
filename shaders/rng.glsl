// Counter-based random numbers: the stream of a sample depends only on (seed, pixel, sample index),
// so an image is the same however the samples are split into dispatches.

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng {
    uint state;
};

Rng rng_for_sample(uint seed, uint pixel, uint sample_index) {
    Rng rng;
    rng.state = pcg_hash(pixel + pcg_hash(sample_index + pcg_hash(seed)));
    return rng;
}

// Uniform float in [0, 1): PCG step, permuted output, top 24 bits.
float rng_next(inout Rng rng) {
    rng.state = rng.state * 747796405u + 2891336453u;
    uint word = ((rng.state >> ((rng.state >> 28u) + 4u)) ^ rng.state) * 277803737u;
    word = (word >> 22u) ^ word;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_next2(inout Rng rng) {
    float x = rng_next(rng);
    return vec2(x, rng_next(rng));
}
