// Counter-based random numbers: the stream of a sample depends only on (seed, pixel, sample index),
// so an image is the same however the samples are split into dispatches.
//
// Two samplers behind one interface (rng_next, rng_next2):
// - SAMPLER_INDEPENDENT: a PCG stream per sample, seeded by hashing (seed, pixel, sample index).
// - SAMPLER_SOBOL: padded Owen-scrambled Sobol (sobol.glsl). The caller names a window of
//   dimensions with rng_set_dimensions; each draw takes the next one (a pair takes two) and is the
//   Sobol draw of seed hash(pixel key, dimension) at the global sample index, where the pixel key
//   is hash(seed, pixel). A decision that always draws at the same dimension is stratified across
//   the pixel's samples. Draws past the window's end, and all draws before the first window is
//   set, come from the PCG stream.

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

#include "sobol.glsl"

const uint SAMPLER_INDEPENDENT = 0u;
const uint SAMPLER_SOBOL = 1u;

struct Rng {
    uint state;         // PCG state (independent draws, and Sobol draws past the window)
    uint kind;          // SAMPLER_*
    uint pixel_key;     // hash of (seed, pixel): keys every Sobol draw of the pixel
    uint sample_index;  // global sample index
    uint dim;           // next Sobol dimension
    uint dim_end;       // end of the current window
};

Rng rng_for_sample(uint seed, uint pixel, uint sample_index, uint kind) {
    Rng rng;
    rng.state = pcg_hash(pixel + pcg_hash(sample_index + pcg_hash(seed)));
    rng.kind = kind;
    // A different salt from the PCG seeding, so the two never share a hash chain.
    rng.pixel_key = pcg_hash(pixel + pcg_hash(seed ^ 0x5bd1e995u));
    rng.sample_index = sample_index;
    rng.dim = 0u;
    rng.dim_end = 0u;
    return rng;
}

// The next `count` draws use Sobol dimensions first..first + count (no-op for independent numbers).
void rng_set_dimensions(inout Rng rng, uint first, uint count) {
    if (rng.kind == SAMPLER_SOBOL) {
        rng.dim = first;
        rng.dim_end = first + count;
    }
}

float pcg_next(inout Rng rng) {
    rng.state = rng.state * 747796405u + 2891336453u;
    uint word = ((rng.state >> ((rng.state >> 28u) + 4u)) ^ rng.state) * 277803737u;
    word = (word >> 22u) ^ word;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

// Uniform float in [0, 1).
float rng_next(inout Rng rng) {
    if (rng.dim < rng.dim_end) {
        uint d = rng.dim;
        rng.dim += 1u;
        return sobol_sample1(rng.sample_index, sobol_hash_combine(rng.pixel_key, d));
    }
    return pcg_next(rng);
}

// A pair stratified jointly (Sobol) or two independent numbers.
vec2 rng_next2(inout Rng rng) {
    if (rng.dim + 1u < rng.dim_end) {
        uint d = rng.dim;
        rng.dim += 2u;
        return sobol_sample2(rng.sample_index, sobol_hash_combine(rng.pixel_key, d));
    }
    float x = pcg_next(rng);
    return vec2(x, pcg_next(rng));
}
