// Owen-scrambled Sobol points, padded (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)).
//
// Every draw (one number or a pair) is its own 1D or 2D Sobol sequence: the first one or two Sobol
// dimensions, a (0,2)-sequence, so any 2^m consecutive aligned samples of a draw stratify its
// unit interval or square into 2^m intervals or elementary rectangles. Draws are decorrelated by
// shuffling the sample index with a nested uniform (Owen) scramble keyed by the draw's seed, and
// each coordinate is Owen-scrambled with its own seed. Padding rather than one high-dimensional
// Sobol sequence: higher Sobol dimensions stratify badly in their 2D projections at low sample
// counts, and the draws of a path need no table of direction numbers this way.
//
// The index shuffle maps each aligned block of 2^m indices onto an aligned block of 2^m indices, so
// samples 0..2^m of a pixel, or any aligned run of them (a farm partial, a resumed render), keep
// the stratification.

// Sobol dimension 1's direction numbers follow v_{k+1} = v_k ^ (v_k >> 1) from v_0 = 1/2
// (primitive polynomial x + 1, m = 1, 3, 5, 15, 17, ...), so v_k holds bit j (from the top) exactly
// when C(k, j) is odd, that is (Lucas) when j's bits are a subset of k's. Bit j of the result is then
// the XOR of the index bits k over the supersets k of j: five butterfly steps, one per bit of j,
// then a reversal to count from the top. No loop: on llvmpipe loops cost a shared iteration budget
// (loop_limit.glsl), and a loop over the index's bits spent up to 32 of it per draw.
// Dimension 0 is bitfieldReverse(index).
uint sobol_dimension1(uint index) {
    uint x = index;
    x ^= (x >> 1u) & 0x55555555u;
    x ^= (x >> 2u) & 0x33333333u;
    x ^= (x >> 4u) & 0x0f0f0f0fu;
    x ^= (x >> 8u) & 0x00ff00ffu;
    x ^= (x >> 16u) & 0x0000ffffu;
    return bitfieldReverse(x);
}

// A random permutation of 32-bit integers in which bit k is flipped by a function of the bits
// below it only (Laine-Karras); Vegdahl's 2021 constants, which scramble better than Burley's.
uint laine_karras_permutation(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Owen scramble of a 0.32 fixed-point number: bit k (from the top) is flipped by a function of the
// bits above it.
uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

// boost::hash_combine, then PCG's output hash so that nearby inputs give unrelated seeds.
uint sobol_hash_combine(uint seed, uint v) {
    return pcg_hash(seed ^ (v + 0x9e3779b9u + (seed << 6u) + (seed >> 2u)));
}

// Top 24 bits as a float in [0, 1).
float sobol_unit(uint x) {
    return float(x >> 8u) * (1.0 / 16777216.0);
}

float sobol_sample1(uint index, uint seed) {
    uint i = nested_uniform_scramble(index, seed);
    return sobol_unit(nested_uniform_scramble(bitfieldReverse(i), sobol_hash_combine(seed, 0u)));
}

vec2 sobol_sample2(uint index, uint seed) {
    uint i = nested_uniform_scramble(index, seed);
    uint x = nested_uniform_scramble(bitfieldReverse(i), sobol_hash_combine(seed, 0u));
    uint y = nested_uniform_scramble(sobol_dimension1(i), sobol_hash_combine(seed, 1u));
    return vec2(sobol_unit(x), sobol_unit(y));
}
