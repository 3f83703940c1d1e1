//! The samplers of shaders/rng.glsl. The sequence itself is checked by running rng.glsl in a small
//! test kernel (the kernel's own code, not a host copy): Owen-scrambled Sobol draws are (0,m,2)-nets
//! at every power of two, also over aligned sample ranges not starting at 0, and pixels and draws
//! are decorrelated. Renders check that Sobol agrees in the mean with independent numbers, lowers
//! the error at equal sample counts, and is deterministic per seed.

mod common;

use caustica::gpu::{compile_compute, Binding, Buffer, BufferKind, ComputeKernel, GpuContext};
use caustica::image::compare;
use caustica::render::assemble_with_kernel_files;
use caustica::render::layout::{SAMPLER_INDEPENDENT, SAMPLER_SOBOL};
use caustica::scene::{Sampler, Scene};
use common::*;

/// Numbers each test-kernel sample draws: a 1D draw, two 2D draws, then a 1D draw past the window.
const VALUES: usize = 6;

const TEST_KERNEL: &str = r#"#version 460
layout(local_size_x = 64) in;
#include "rng.glsl"
layout(push_constant) uniform Params { uint pixels; uint samples; uint sample_base; uint kind; } params;
layout(std430, set = 0, binding = 0) buffer Out { float values[]; };
void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= params.pixels * params.samples) return;
    uint pixel = id / params.samples;
    Rng rng = rng_for_sample(7u, pixel, params.sample_base + id % params.samples, params.kind);
    rng_set_dimensions(rng, 0u, 5u);
    float a = rng_next(rng);
    vec2 b = rng_next2(rng);
    vec2 c = rng_next2(rng);
    float d = rng_next(rng);
    values[id * 6u] = a;
    values[id * 6u + 1u] = b.x;
    values[id * 6u + 2u] = b.y;
    values[id * 6u + 3u] = c.x;
    values[id * 6u + 4u] = c.y;
    values[id * 6u + 5u] = d;
}
"#;

/// `samples` consecutive samples from `sample_base` for each of `pixels` pixels, as
/// [pixel][sample][value].
fn draws(ctx: &GpuContext, kind: u32, pixels: u32, samples: u32, sample_base: u32) -> Vec<Vec<[f32; VALUES]>> {
    let spirv = compile_compute(&assemble_with_kernel_files(TEST_KERNEL).unwrap()).expect("test kernel compiles");
    let count = (pixels * samples) as usize;
    let out = Buffer::with_data(ctx, "draws", BufferKind::HostStorage, &vec![0u8; count * VALUES * 4]).unwrap();
    let kernel = ComputeKernel::new(ctx, &spirv, &[Binding::whole(0, &out)], 16).unwrap();
    let push: Vec<u8> = [pixels, samples, sample_base, kind].iter().flat_map(|v| v.to_le_bytes()).collect();
    kernel.dispatch(ctx, &push, [(count as u32).div_ceil(64), 1, 1]).unwrap();
    let values: Vec<f32> = bytemuck::cast_slice(&out.read().unwrap()[..count * VALUES * 4]).to_vec();
    kernel.destroy(ctx);
    out.destroy(ctx);
    ctx.check_validation().expect("no validation messages");
    values
        .chunks(VALUES * samples as usize)
        .map(|p| p.chunks(VALUES).map(|s| s.try_into().unwrap()).collect())
        .collect()
}

/// Whether the points are a (0,m,2)-net for n = 2^m points: every elementary rectangle of area 1/n
/// (2^a by 2^(m-a) cells, every a) holds exactly one point.
fn is_net(points: &[(f32, f32)]) -> bool {
    let n = points.len();
    let m = n.trailing_zeros();
    assert_eq!(n, 1 << m);
    (0..=m).all(|a| {
        let mut seen = vec![false; n];
        points.iter().all(|&(x, y)| {
            let cell = ((x * (1u32 << a) as f32) as usize) << (m - a) | (y * (1u32 << (m - a)) as f32) as usize;
            !std::mem::replace(&mut seen[cell], true)
        })
    })
}

/// Whether n values fall one into each of n equal intervals.
fn is_stratified(values: &[f32]) -> bool {
    let n = values.len();
    let mut seen = vec![false; n];
    values.iter().all(|&v| !std::mem::replace(&mut seen[(v * n as f32) as usize], true))
}

/// Every draw of every pixel is stratified over every aligned power-of-two run of samples: the
/// first 2^m, and 2^m starting at a multiple of 2^m (how farm partials and resumed renders split).
#[test]
fn sobol_draws_are_nets_over_aligned_sample_runs() {
    let (_lock, ctx) = gpu();
    for (base, samples) in [(0, 256), (768, 256), (1 << 20, 64)] {
        let all = draws(&ctx, SAMPLER_SOBOL, 8, samples, base);
        for (pixel, samples) in all.iter().enumerate() {
            for m in 0..=samples.len().trailing_zeros() {
                let n = 1usize << m;
                for run in samples.chunks(n) {
                    let what = format!("pixel {pixel}, samples {base}+{n}");
                    assert!(is_stratified(&run.iter().map(|s| s[0]).collect::<Vec<_>>()), "{what}: 1D draw");
                    assert!(is_net(&run.iter().map(|s| (s[1], s[2])).collect::<Vec<_>>()), "{what}: first 2D draw");
                    assert!(is_net(&run.iter().map(|s| (s[3], s[4])).collect::<Vec<_>>()), "{what}: second 2D draw");
                }
            }
        }
    }
}

/// The same check fails for independent numbers, and for the Sobol draw past the window (an
/// independent number): what the net test sees is the sampler, not the test.
#[test]
fn independent_numbers_are_not_nets() {
    let (_lock, ctx) = gpu();
    let independent = draws(&ctx, SAMPLER_INDEPENDENT, 8, 16, 0);
    let sobol = draws(&ctx, SAMPLER_SOBOL, 8, 16, 0);
    for pixel in 0..8 {
        assert!(!is_net(&independent[pixel].iter().map(|s| (s[1], s[2])).collect::<Vec<_>>()), "pixel {pixel}");
        assert!(
            !is_stratified(&sobol[pixel].iter().map(|s| s[5]).collect::<Vec<_>>()),
            "pixel {pixel}: draw past the window"
        );
    }
}

/// Pearson correlation of two equally long series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let (va, vb): (f64, f64) = (a.iter().map(|x| (x - ma).powi(2)).sum(), b.iter().map(|y| (y - mb).powi(2)).sum());
    cov / (va * vb).sqrt()
}

/// Across pixels, a sample's draws are uniform and unrelated to each other and to the same draw of
/// the neighbouring pixel. A shared scramble would make every pixel alike.
#[test]
fn sobol_draws_are_uniform_and_decorrelated_across_pixels() {
    let (_lock, ctx) = gpu();
    let pixels = 4096;
    let all = draws(&ctx, SAMPLER_SOBOL, pixels, 1, 0);
    let column = |sample: usize, value: usize| all.iter().map(|p| p[sample][value] as f64).collect::<Vec<_>>();
    // Uniform: 16 bins, chi-square with 15 degrees of freedom below its 0.999 quantile (37.7).
    for value in 0..VALUES - 1 {
        let mut bins = [0f64; 16];
        for v in column(0, value) {
            bins[(v * 16.0) as usize] += 1.0;
        }
        let expected = pixels as f64 / 16.0;
        let chi2: f64 = bins.iter().map(|b| (b - expected).powi(2) / expected).sum();
        assert!(chi2 < 37.7, "value {value} of sample 0 over pixels: chi-square {chi2:.1}, bins {bins:?}");
    }
    // Uncorrelated: |r| under 4 standard errors (1 / sqrt(n)) of zero.
    let limit = 4.0 / (pixels as f64).sqrt();
    let shifted = |v: Vec<f64>| v[1..].iter().chain(&v[..1]).copied().collect::<Vec<_>>();
    for (what, a, b) in [
        ("1D draw and first 2D draw", column(0, 0), column(0, 1)),
        ("the two 2D draws", column(0, 1), column(0, 3)),
        ("x and y of a 2D draw", column(0, 3), column(0, 4)),
        ("neighbouring pixels", column(0, 1), shifted(column(0, 1))),
    ] {
        let r = correlation(&a, &b);
        assert!(r.abs() < limit, "{what}: correlation {r:.4} over {pixels} pixels");
    }
}

/// The Cornell box (common's) with `sampler`.
fn cornell(size: u32, spp: u32, sampler: Sampler) -> Scene {
    let mut scene = common::cornell(size, spp);
    scene.integrator.sampler = sampler;
    scene
}

#[test]
fn sobol_agrees_in_the_mean_with_independent_numbers() {
    let (_lock, ctx) = gpu();
    let sobol = render(&ctx, &cornell(16, 64, Sampler::Sobol), 3);
    let independent = render(&ctx, &cornell(16, 64, Sampler::Independent), 4);
    assert_same_mean(&sobol, &independent, 5.0, "Cornell box, Sobol against independent numbers");
}

/// The Cornell box with its mirror and glass spheres made diffuse: caustics, which no sampler helps
/// at these counts, would otherwise dominate the error.
fn diffuse_cornell(size: u32, spp: u32, sampler: Sampler) -> Scene {
    let mut scene = cornell(size, spp, sampler);
    for m in scene.materials.iter_mut().filter(|m| m.reflectivity > 0.0 || m.transparency > 0.0) {
        (m.albedo, m.reflectivity, m.transparency) = (glam::Vec3::splat(0.5), 0.0, 0.0);
    }
    scene
}

/// Relative MSE against an independent 1024 spp reference, the mean over three seeds. Measured on
/// lavapipe: Sobol's is about half of independent numbers' (0.45 at 16x16, 32 spp).
#[test]
fn sobol_lowers_the_error_at_equal_samples() {
    let (_lock, ctx) = gpu();
    let reference = render(&ctx, &diffuse_cornell(16, 1024, Sampler::Independent), 99);
    let error = |sampler: Sampler| {
        (1..=3)
            .map(|seed| {
                compare(&render(&ctx, &diffuse_cornell(16, 32, sampler), seed), &reference, ("render", "reference"))
                    .unwrap()
                    .relative_mse
            })
            .sum::<f64>()
            / 3.0
    };
    let (sobol, independent) = (error(Sampler::Sobol), error(Sampler::Independent));
    eprintln!(
        "relative MSE at 32 spp: Sobol {sobol:.4e}, independent {independent:.4e}, ratio {:.3}",
        sobol / independent
    );
    assert!(sobol < 0.7 * independent, "relative MSE at 32 spp: Sobol {sobol:.4e}, independent {independent:.4e}");
}

#[test]
fn sobol_renders_depend_on_the_seed_only() {
    let (_lock, ctx) = gpu();
    let scene = cornell(8, 4, Sampler::Sobol);
    let (a, b, c) = (render(&ctx, &scene, 5), render(&ctx, &scene, 5), render(&ctx, &scene, 6));
    assert!(a.pixels == b.pixels, "the same seed gave two images");
    let differing = a.pixels.iter().zip(&c.pixels).filter(|(p, q)| p != q).count();
    assert!(differing > a.pixels.len() / 2, "seeds 5 and 6 differ in {differing} of {} pixels only", a.pixels.len());
}

/// Sobol dimension 1 by its definition: direction numbers v_{k+1} = v_k ^ (v_k >> 1) from
/// v_0 = 2^31, XORed for the index's set bits.
fn sobol_dimension1_reference(mut index: u32) -> u32 {
    let (mut result, mut v) = (0u32, 0x8000_0000u32);
    while index != 0 {
        if index & 1 != 0 {
            result ^= v;
        }
        v ^= v >> 1;
        index >>= 1;
    }
    result
}

/// sobol.glsl computes dimension 1 without a loop (butterfly steps over the index's bits): it must
/// equal the definition for every index, here the first 2^20 and the last 2^20.
#[test]
fn sobol_dimension1_without_a_loop_equals_its_definition() {
    const KERNEL: &str = r#"#version 460
layout(local_size_x = 64) in;
#include "rng.glsl"
layout(push_constant) uniform Params { uint first; } params;
layout(std430, set = 0, binding = 0) buffer Out { uint values[]; };
void main() { values[gl_GlobalInvocationID.x] = sobol_dimension1(params.first + gl_GlobalInvocationID.x); }
"#;
    let (_lock, ctx) = gpu();
    let spirv = compile_compute(&assemble_with_kernel_files(KERNEL).unwrap()).expect("test kernel compiles");
    const COUNT: u32 = 1 << 20;
    let out =
        Buffer::with_data(&ctx, "sobol dimension 1", BufferKind::HostStorage, &vec![0u8; COUNT as usize * 4]).unwrap();
    let kernel = ComputeKernel::new(&ctx, &spirv, &[Binding::whole(0, &out)], 4).unwrap();
    for first in [0u32, u32::MAX - COUNT + 1] {
        kernel.dispatch(&ctx, &first.to_le_bytes(), [COUNT / 64, 1, 1]).unwrap();
        let values: &[u32] = bytemuck::cast_slice(&out.read().unwrap()[..COUNT as usize * 4]);
        for (i, &value) in values.iter().enumerate() {
            let index = first + i as u32;
            assert_eq!(value, sobol_dimension1_reference(index), "sobol_dimension1({index})");
        }
    }
    kernel.destroy(&ctx);
    out.destroy(&ctx);
    ctx.check_validation().expect("no validation messages");
}
