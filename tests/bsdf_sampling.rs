//! BSDF sampling against the kernel's own pdf, on lavapipe, with the real shaders/materials.glsl
//! (no host copy of the BSDFs): the chi-square goodness-of-fit test of pbrt and Mitsuba. A test
//! kernel picks a lobe and samples it 2^20 times for a fixed incoming direction; the same kernel
//! evaluates eval_lobe's pdf on a Gauss-Legendre grid inside every (theta, phi) bin of the sphere,
//! so each bin's expected count is the integral of the pdf the path tracer uses for MIS. Samples
//! that sample_lobe rejects (below the horizon) fall in one more cell whose expected share is what
//! the pdf leaves of 1. The test also checks, sample by sample, that the reported pdf is the one
//! eval_lobe gives for the same direction and that the weight is eval_lobe's f cos over that pdf.
//!
//! The two checks see different bugs. Dropping the refraction Jacobian from refraction_pdf fails
//! both (p = 0 in all four dielectric cases); taking the half-disk warp out of sample_vndf, which
//! leaves every weight equal to eval / pdf, fails only the chi-square (p = 0 in 9 of the 12 GGX
//! lobes; near-normal incidence at low alpha barely feels it). The lobe tests are conditioned on
//! the lobe picked: the plastic's choice between coat and base, and a clear coat's over the
//! material, are not tested here (tests/coat_and_volume.rs renders them against closed forms).

mod common;

use bytemuck::Zeroable;
use caustica::gpu::{compile_compute, Binding, Buffer, BufferKind, ComputeKernel, GpuContext};
use caustica::render::bindings::KernelBuffer;
use caustica::render::layout::{
    GpuMaterial, ALPHA_OPAQUE, CONDUCTOR_ALBEDO, CONDUCTOR_COMPLEX, MATERIAL_BECKMANN, MATERIAL_THIN, NO_TEXTURE,
};
use caustica::render::{assemble_with_kernel_files, shader_file};
use caustica::scene::{average_fresnel, fresnel_dielectric};
use common::chi_square::{chi_square, gamma_q};
use common::*;
use std::f64::consts::PI;

/// The test kernel. It includes layout.glsl for `struct Material` and binds only `materials` (at
/// its binding in the kernel's table, src/render/bindings.rs, as texels); the other buffers, the frame uniform
/// and the pass push constants that layout.glsl also declares are unused (the pipeline still has
/// the 16-byte push range). Its own buffers sit at bindings 30-32, clear of the table's.
/// Mode 0: invocation i picks a lobe with random stream i and samples it, writing
///   (dir, lobe code, or -1 - code when sample_lobe fails), (weight, pdf), (eval_lobe's f cos, its pdf).
/// Mode 1: finds the lobe with the requested code (pick_lobe with successive streams) and writes
///   eval_lobe's pdf for every direction of `dirs`.
/// Mode 2: writes the weak white furnace integrand D(h) G1(wo) / (4 wo.z) of the material's
///   microfacet distribution for every direction wi of `dirs` (h the half vector, wo = -d), in
///   the frame whose x axis is the query's tangent (that of an anisotropic lobe).
/// Every lobe is given the query's tangent as the surface's u direction.
/// A lobe's code is kind * 4 + fresnel, which tells the plastic's coat from a conductor.
const TEST_KERNEL: &str = r#"#version 460
#extension GL_EXT_samplerless_texture_functions : require
layout(local_size_x = 64) in;
#include "layout.glsl"
#include "rng.glsl"
#include "sampling.glsl"
#include "materials.glsl"
// d.xyz = the incoming ray direction (towards the surface), d.w = 1 when the ray enters (comes
// from the front side); info = mode, invocation count, lobe code (mode 1), seed; tangent.xyz =
// the surface's u direction.
layout(std430, set = 0, binding = 30) readonly buffer Query { vec4 d; uvec4 info; vec4 tangent; } query;
layout(std430, set = 0, binding = 31) readonly buffer Dirs { vec4 dirs[]; };
layout(std430, set = 0, binding = 32) writeonly buffer Results { vec4 results[]; };

// The lobe frame's normal is +z on the side the ray comes from: the shading normal is +z for an
// entering ray and -z for a leaving one (pick_lobe flips it).
Lobe lobe_for(inout Rng rng) {
    bool entering = query.d.w > 0.5;
    return pick_lobe(load_materials(0), query.d.xyz, vec3(0.0, 0.0, entering ? 1.0 : -1.0), query.tangent.xyz, entering, rng);
}

uint lobe_code(Lobe l) { return l.kind * 4u + l.fresnel; }

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= query.info.y) return;
    vec3 d = query.d.xyz;
    if (query.info.x == 2u) {
        Material m = load_materials(0);
        uint distribution = (material_flags(m) & MATERIAL_BECKMANN) != 0u ? MICROFACET_BECKMANN : MICROFACET_GGX;
        vec2 alpha = vec2(m.params.w, m.volume.w > 0.0 ? m.volume.w : m.params.w);
        vec3 t = normalize(vec3(query.tangent.xy, 0.0));
        vec3 b = cross(vec3(0.0, 0.0, 1.0), t);
        vec3 wo = vec3(dot(-d, t), dot(-d, b), -d.z);
        vec3 wi = dirs[id].xyz;
        vec3 h = wo + vec3(dot(wi, t), dot(wi, b), wi.z);
        float value = 0.0;
        if (dot(h, h) > 0.0 && dot(wo, normalize(h)) > 0.0) {
            h = normalize(h);
            value = microfacet_d(h, alpha, distribution) * microfacet_g1(wo, alpha, distribution) / (4.0 * wo.z);
        }
        results[id] = vec4(value);
        return;
    }
    if (query.info.x == 0u) {
        Rng rng = rng_for_sample(query.info.w, id, 0u, SAMPLER_INDEPENDENT);
        Lobe l = lobe_for(rng);
        BsdfSample s;
        bool ok = sample_lobe(l, d, rng, s);
        float pdf = 0.0;
        vec3 f = ok ? eval_lobe(l, d, s.dir, pdf) : vec3(0.0);
        results[3u * id] = vec4(s.dir, ok ? float(lobe_code(l)) : -1.0 - float(lobe_code(l)));
        results[3u * id + 1u] = vec4(s.weight, s.pdf);
        results[3u * id + 2u] = vec4(f, pdf);
        return;
    }
    for (uint stream = 0u; stream < 65536u; stream++) {
        Rng rng = rng_for_sample(query.info.w, stream, 0u, SAMPLER_INDEPENDENT);
        Lobe l = lobe_for(rng);
        if (lobe_code(l) == query.info.z) {
            float pdf;
            eval_lobe(l, d, dirs[id].xyz, pdf);
            results[id] = vec4(pdf, 0.0, 0.0, 0.0);
            return;
        }
    }
    results[id] = vec4(-1.0);
}
"#;

const SAMPLES: u32 = 1 << 20;
/// The surface's u direction given to every lobe: 30 degrees from x and not normal to the lobe's
/// normal (+-z), so an anisotropic lobe must make it normal, and its frame differs from the
/// arbitrary one onb() builds about +-z (whose x axis is +x).
const TANGENT: [f64; 4] = [0.866_025_403_784_438_6, 0.5, 0.4, 0.0];
/// Bins over the whole sphere: theta in [0, pi] (uniform in angle, which resolves the narrow
/// near-specular peaks better than uniform cos theta), phi in [0, 2 pi).
const THETA_BINS: usize = 80;
const PHI_BINS: usize = 160;
/// Gauss-Legendre nodes and weights on [-1, 1] (5 points: exact for degree 9 in each variable).
const GL_NODES: [f64; 5] =
    [-0.906_179_845_938_664, -0.538_469_310_105_683_1, 0.0, 0.538_469_310_105_683_1, 0.906_179_845_938_664];
const GL_WEIGHTS: [f64; 5] = [
    0.236_926_885_056_189_1,
    0.478_628_670_499_366_5,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
];
/// Number of chi-square tests in this file (lobes tested), for the Bonferroni correction.
const TESTS: f64 = 28.0;
const SIGNIFICANCE: f64 = 1e-4 / TESTS;

struct Case {
    name: String,
    material: GpuMaterial,
    /// Cosine of the angle between the direction towards the viewer and the lobe's normal.
    cos_o: f64,
    entering: bool,
}

struct Sample {
    dir: [f32; 3],
    /// Code of the lobe picked.
    lobe: u32,
    /// Whether sample_lobe yielded a direction.
    ok: bool,
    weight: [f32; 3],
    pdf: f32,
    eval: [f32; 3],
    eval_pdf: f32,
}

struct Kernel<'a> {
    ctx: &'a GpuContext,
    kernel: ComputeKernel,
    material: Buffer,
    query: Buffer,
    dirs: Buffer,
    results: Buffer,
}

/// Directions at the Gauss-Legendre nodes of every bin, bin by bin (theta bin major), with the
/// weight (quadrature weight times sin theta times the bin's half-widths) of each.
fn quadrature() -> (Vec<[f32; 4]>, Vec<f64>) {
    let (dt, dp) = (PI / THETA_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let mut dirs = Vec::new();
    let mut weights = Vec::new();
    for i in 0..THETA_BINS {
        for j in 0..PHI_BINS {
            for (a, wa) in GL_NODES.iter().zip(GL_WEIGHTS) {
                let theta = (i as f64 + 0.5 + 0.5 * a) * dt;
                for (b, wb) in GL_NODES.iter().zip(GL_WEIGHTS) {
                    let phi = (j as f64 + 0.5 + 0.5 * b) * dp;
                    let (st, ct) = theta.sin_cos();
                    dirs.push([(st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32, 0.0]);
                    weights.push(wa * wb * st * 0.25 * dt * dp);
                }
            }
        }
    }
    (dirs, weights)
}

fn bin_of(dir: [f32; 3]) -> usize {
    let [x, y, z] = dir.map(|v| v as f64);
    let theta = (z / (x * x + y * y + z * z).sqrt()).clamp(-1.0, 1.0).acos();
    let phi = y.atan2(x).rem_euclid(2.0 * PI);
    let i = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let j = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    i * PHI_BINS + j
}

impl<'a> Kernel<'a> {
    fn new(ctx: &'a GpuContext) -> Self {
        let spirv = compile_compute(&assemble_with_kernel_files(TEST_KERNEL).unwrap()).expect("test kernel compiles");
        let dirs_len = THETA_BINS * PHI_BINS * GL_NODES.len() * GL_NODES.len();
        let results_len = (3 * SAMPLES as usize).max(dirs_len);
        let material =
            Buffer::with_data(ctx, "material", BufferKind::HostStorage, bytemuck::bytes_of(&GpuMaterial::zeroed()))
                .unwrap();
        let query = Buffer::with_data(ctx, "query", BufferKind::HostStorage, &[0u8; 48]).unwrap();
        let dirs =
            Buffer::with_data(ctx, "dirs", BufferKind::HostStorage, bytemuck::cast_slice(&quadrature().0)).unwrap();
        let results = Buffer::with_data(ctx, "results", BufferKind::HostStorage, &vec![0u8; results_len * 16]).unwrap();
        let materials = Binding {
            as_texels: KernelBuffer::Materials.entry().texel_words(),
            ..Binding::whole(KernelBuffer::Materials.entry().binding, &material)
        };
        let bindings = [materials, Binding::whole(30, &query), Binding::whole(31, &dirs), Binding::whole(32, &results)];
        let kernel = ComputeKernel::new(ctx, &spirv, &bindings, 16).unwrap();
        Kernel { ctx, kernel, material, query, dirs, results }
    }

    fn run(&mut self, case: &Case, mode: u32, count: u32, lobe: u32) -> Vec<[f32; 4]> {
        let sin_o = (1.0 - case.cos_o * case.cos_o).sqrt();
        // The ray travels towards the surface, against wo = (sin, 0, cos) in the lobe frame.
        let d = [-sin_o as f32, 0.0, -case.cos_o as f32, if case.entering { 1.0 } else { 0.0 }];
        let mut query: Vec<u8> = bytemuck::cast_slice(&d).to_vec();
        query.extend(bytemuck::cast_slice(&[mode, count, lobe, 12345u32]));
        query.extend(bytemuck::cast_slice(&TANGENT.map(|c| c as f32)));
        self.query.write(&query).unwrap();
        self.material.write(bytemuck::bytes_of(&case.material)).unwrap();
        self.kernel.dispatch(self.ctx, &[0u8; 16], [count.div_ceil(64), 1, 1]).unwrap();
        self.ctx.check_validation().expect("no validation messages");
        let per_invocation = if mode == 0 { 3 } else { 1 };
        bytemuck::cast_slice(&self.results.read().unwrap()[..count as usize * per_invocation * 16]).to_vec()
    }

    fn samples(&mut self, case: &Case) -> Vec<Sample> {
        self.run(case, 0, SAMPLES, 0)
            .chunks(3)
            .map(|r| Sample {
                dir: [r[0][0], r[0][1], r[0][2]],
                lobe: if r[0][3] >= 0.0 { r[0][3] as u32 } else { (-1.0 - r[0][3]) as u32 },
                ok: r[0][3] >= 0.0,
                weight: [r[1][0], r[1][1], r[1][2]],
                pdf: r[1][3],
                eval: [r[2][0], r[2][1], r[2][2]],
                eval_pdf: r[2][3],
            })
            .collect()
    }

    /// Integral of the lobe's pdf over each bin.
    fn bin_probabilities(&mut self, case: &Case, lobe: u32, weights: &[f64]) -> Vec<f64> {
        let pdf = self.run(case, 1, weights.len() as u32, lobe);
        assert!(
            pdf.iter().all(|p| p[0] >= 0.0 && p[0].is_finite()),
            "{}: eval_lobe pdf negative or not finite (or lobe {lobe} never picked)",
            case.name
        );
        let per_bin = GL_NODES.len() * GL_NODES.len();
        pdf.chunks(per_bin)
            .zip(weights.chunks(per_bin))
            .map(|(p, w)| p.iter().zip(w).map(|(p, w)| p[0] as f64 * w).sum())
            .collect()
    }

    fn destroy(self) {
        self.kernel.destroy(self.ctx);
        for b in [self.material, self.query, self.dirs, self.results] {
            b.destroy(self.ctx);
        }
    }
}

/// Relative difference, with `floor` as the scale below which values count as equal.
fn rel(a: f32, b: f32, floor: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(floor)
}

/// The per-sample consistency checks, then the chi-square test of every lobe the case's material
/// picks; returns what failed.
fn check_case(kernel: &mut Kernel, weights: &[f64], case: &Case, kind: u32) -> Vec<String> {
    let samples = kernel.samples(case);
    // A lobe's code is kind * 4 + fresnel.
    assert!(
        samples.iter().any(|s| s.lobe / 4 == kind),
        "{}: never picks the lobe of kind {kind} it is a case of",
        case.name
    );
    // Consistency: sample_lobe's pdf is eval_lobe's for the same direction, and its weight is
    // eval_lobe's f cos over that pdf. Float rounding (the half vector recomputed from wo + wi)
    // leaves a few samples near the horizon off by more; allow 1 in 10^4 beyond 1e-3.
    let mut bad = 0;
    let mut worst = (0.0f32, String::new());
    for s in samples.iter().filter(|s| s.ok) {
        let pdf_err = rel(s.pdf, s.eval_pdf, 1e-6);
        let weight_err = (0..3).map(|c| rel(s.weight[c], s.eval[c] / s.eval_pdf, 1e-6)).fold(0.0, f32::max);
        let err = pdf_err.max(weight_err);
        if err.is_nan() || err > 1e-3 {
            bad += 1;
        }
        if err.is_nan() || err > worst.0 {
            worst = (
                err,
                format!(
                    "dir {:?}: pdf {} against eval_lobe's {}, weight {:?} against eval / pdf {:?}",
                    s.dir,
                    s.pdf,
                    s.eval_pdf,
                    s.weight,
                    s.eval.map(|e| e / s.eval_pdf)
                ),
            );
        }
    }
    eprintln!("{}: {bad} samples off eval_lobe by more than 1e-3, worst relative error {:.1e}", case.name, worst.0);
    let mut failures = Vec::new();
    if bad > SAMPLES as usize / 10_000 {
        failures
            .push(format!("{}: {bad} samples disagree with eval_lobe by more than 1e-3; worst {}", case.name, worst.1));
    }

    let mut lobes: Vec<u32> = samples.iter().map(|s| s.lobe).collect();
    lobes.sort_unstable();
    lobes.dedup();
    for lobe in lobes {
        let probabilities = kernel.bin_probabilities(case, lobe, weights);
        // Samples that picked this lobe, with a direction or failed: the sampled distribution is
        // that of the lobe, given the pick.
        let picked: Vec<&Sample> = samples.iter().filter(|s| s.lobe == lobe).collect();
        let n = picked.len() as f64;
        let mut observed = vec![0.0; THETA_BINS * PHI_BINS + 1];
        for s in &picked {
            observed[if s.ok { bin_of(s.dir) } else { THETA_BINS * PHI_BINS }] += 1.0;
        }
        let total: f64 = probabilities.iter().sum();
        let mut expected: Vec<f64> = probabilities.iter().map(|p| p * n).collect();
        expected.push((1.0 - total).max(0.0) * n);
        let (statistic, dof, p) = chi_square(&observed, &expected);
        let failed = observed[THETA_BINS * PHI_BINS];
        eprintln!(
            "{} lobe {lobe}: chi-square {statistic:.1}, {dof} degrees of freedom, p = {p:.3e}; pdf integrates to {total:.5}, {failed} of {n} samples failed",
            case.name
        );
        if p.is_nan() || p <= SIGNIFICANCE {
            failures.push(format!("{} lobe {lobe}: sampling disagrees with eval_lobe's pdf: chi-square {statistic:.1}, {dof} dof, p = {p:.3e} < {SIGNIFICANCE:.1e}", case.name));
        }
    }
    failures
}

fn material(albedo: f32, r: f32, t: f32, ior: f32, alpha: f32) -> GpuMaterial {
    GpuMaterial {
        albedo_r: [albedo, albedo * 0.8, albedo * 0.6, r],
        emission_t: [0.0, 0.0, 0.0, t],
        params: [ior, 0.0, f32::from_bits(NO_TEXTURE), alpha],
        conductor_eta: [0.0, 0.0, 0.0, f32::from_bits(CONDUCTOR_ALBEDO)],
        conductor_k: [0.0; 4],
        metallic_roughness: [f32::from_bits(NO_TEXTURE), 0.0, 0.0, 0.0],
        maps: [f32::from_bits(NO_TEXTURE), 0.0, 0.0, 0.0],
        alpha: [f32::from_bits(NO_TEXTURE), 1.0, 0.0, f32::from_bits(ALPHA_OPAQUE)],
        coat: [0.0, 0.0, f32::from_bits(NO_TEXTURE), f32::from_bits(NO_TEXTURE)],
        volume: [0.0; 4],
    }
}

/// `m` with Beckmann's distribution instead of GGX.
fn beckmann(mut m: GpuMaterial) -> GpuMaterial {
    m.maps[3] = f32::from_bits(MATERIAL_BECKMANN);
    m
}

/// `m` anisotropic: alpha `alpha_v` along v (across the tangent), its own alpha along u.
fn anisotropic(mut m: GpuMaterial, alpha_v: f32) -> GpuMaterial {
    m.volume[3] = alpha_v;
    m
}

/// Gold's complex index (roughly, at R, G, B).
fn gold(alpha: f32) -> GpuMaterial {
    let mut m = material(1.0, 1.0, 0.0, 1.0, alpha);
    m.conductor_eta = [0.18, 0.42, 1.37, f32::from_bits(CONDUCTOR_COMPLEX)];
    m.conductor_k = [3.42, 2.35, 1.77, 0.0];
    m
}

/// Runs every case; each must pick the lobe of kind `kind` for some of its samples.
fn run_cases(cases: &[Case], kind: u32) {
    let (_lock, ctx) = gpu();
    let mut kernel = Kernel::new(&ctx);
    let (_, weights) = quadrature();
    let failures: Vec<String> = cases.iter().flat_map(|case| check_case(&mut kernel, &weights, case, kind)).collect();
    kernel.destroy();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The lobes of shaders/materials.glsl, by the name of their LOBE_* kind, each with the cases that
/// pick it: a lobe added to the kernel without cases here (or a test of its own in DELTA_LOBES)
/// fails `every_lobe_of_the_kernel_has_chi_square_cases`.
/// A lobe's chi-square cases.
type Cases = fn() -> Vec<Case>;

const LOBES: [(&str, Cases); 4] = [
    ("LOBE_DIFFUSE", diffuse_cases),
    ("LOBE_REFLECT", reflector_cases),
    ("LOBE_DIELECTRIC", dielectric_cases),
    ("LOBE_COATED_DIFFUSE", coated_diffuse_cases),
];

/// Lobes that are always delta (no pdf to test against), each with the test that checks it.
const DELTA_LOBES: [(&str, &str); 1] =
    [("LOBE_THIN_DIELECTRIC", "a_thin_sheet_reflects_two_f_over_one_plus_f_and_passes_the_rest_straight")];

fn diffuse_cases() -> Vec<Case> {
    vec![Case {
        name: "diffuse (cos 0.6)".into(),
        material: material(0.7, 0.0, 0.0, 1.5, 0.0),
        cos_o: 0.6,
        entering: true,
    }]
}

/// Rough conductors (the plastic's coat reflects by this lobe too, tested with the plastic).
fn reflector_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for alpha in [0.05, 0.3, 1.0] {
        for (cos_o, incidence) in [(0.9, "near-normal"), (0.2, "grazing")] {
            let name = format!("conductor, alpha {alpha}, {incidence} (cos {cos_o})");
            let material = if alpha == 0.3 { material(0.9, 1.0, 0.0, 1.0, alpha) } else { gold(alpha) };
            cases.push(Case { name, material, cos_o, entering: true });
        }
    }
    // Beckmann samples all normals by D cos rather than the visible ones: grazing incidence at
    // high alpha is where its rejected samples (normals facing away) and its weights differ most.
    for (alpha, cos_o) in [(0.05, 0.2), (0.3, 0.9), (1.0, 0.2)] {
        cases.push(Case {
            name: format!("Beckmann conductor, alpha {alpha} (cos {cos_o})"),
            material: beckmann(gold(alpha)),
            cos_o,
            entering: true,
        });
    }
    // Anisotropic, the viewer at 30 degrees from the tangent's azimuth (TANGENT): narrow along u
    // and wide along v, or the other way round for Beckmann.
    for cos_o in [0.9, 0.2] {
        cases.push(Case {
            name: format!("anisotropic conductor, alpha 0.05 along u, 0.5 along v (cos {cos_o})"),
            material: anisotropic(gold(0.05), 0.5),
            cos_o,
            entering: true,
        });
    }
    cases.push(Case {
        name: "anisotropic Beckmann conductor, alpha 0.5 along u, 0.05 along v (cos 0.2)".into(),
        material: anisotropic(beckmann(gold(0.5)), 0.05),
        cos_o: 0.2,
        entering: true,
    });
    cases
}

fn dielectric_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for alpha in [0.3, 0.8] {
        for (entering, side) in [(true, "from outside"), (false, "from inside")] {
            let name = format!("dielectric ior 1.5, alpha {alpha}, {side} (cos 0.7)");
            cases.push(Case { name, material: material(1.0, 0.0, 1.0, 1.5, alpha), cos_o: 0.7, entering });
        }
    }
    for (entering, side) in [(true, "from outside"), (false, "from inside")] {
        let name = format!("Beckmann dielectric ior 1.5, alpha 0.3, {side} (cos 0.7)");
        cases.push(Case { name, material: beckmann(material(1.0, 0.0, 1.0, 1.5, 0.3)), cos_o: 0.7, entering });
    }
    for (entering, side) in [(true, "from outside"), (false, "from inside")] {
        let glass = material(1.0, 0.0, 1.0, 1.5, 0.1);
        let name = format!("anisotropic dielectric ior 1.5, alpha 0.1 along u, 0.6 along v, {side} (cos 0.7)");
        cases.push(Case { name, material: anisotropic(glass, 0.6), cos_o: 0.7, entering });
        let name = format!("anisotropic Beckmann dielectric ior 1.5, alpha 0.6 along u, 0.1 along v, {side} (cos 0.7)");
        cases.push(Case {
            name,
            material: anisotropic(beckmann(material(1.0, 0.0, 1.0, 1.5, 0.6)), 0.1),
            cos_o: 0.7,
            entering,
        });
    }
    cases
}

/// A plastic: its coated base, and its coat (a reflector lobe with the coat's Fresnel). Then the
/// same plastic under a glTF clear coat of roughness 0.5 (a reflector lobe without a Fresnel of
/// its own, at its own alpha): three lobes, each tested given its pick.
fn coated_diffuse_cases() -> Vec<Case> {
    let mut plastic = material(0.5, 0.0, 0.0, 1.5, 0.2 * 0.2);
    plastic.conductor_k[3] = 1.0 / (1.0 - average_fresnel(1.5));
    let mut clearcoated = plastic;
    clearcoated.coat[..2].copy_from_slice(&[1.0, 0.5]);
    vec![
        Case { name: "plastic ior 1.5, roughness 0.2 (cos 0.6)".into(), material: plastic, cos_o: 0.6, entering: true },
        Case {
            name: "clear coat roughness 0.5 over that plastic (cos 0.3)".into(),
            material: clearcoated,
            cos_o: 0.3,
            entering: true,
        },
    ]
}

/// The kernel's lobe kinds: every `const uint LOBE_<NAME> = <n>u;` of materials.glsl (as the
/// kernel reads it, so a mutant's list too).
fn kernel_lobes() -> Vec<(String, u32)> {
    let glsl = shader_file("materials.glsl").expect("materials.glsl");
    glsl.lines()
        .filter_map(|line| line.strip_prefix("const uint LOBE_"))
        .map(|rest| {
            let (name, value) = rest.split_once(" = ").expect("const uint LOBE_X = Nu;");
            let value = value.split_once("u;").expect("a uint literal").0.parse().expect("a number");
            (format!("LOBE_{name}"), value)
        })
        .collect()
}

#[test]
fn every_lobe_of_the_kernel_has_chi_square_cases() {
    let mut kernel: Vec<String> = kernel_lobes().into_iter().map(|(name, _)| name).collect();
    let mut tested: Vec<String> = LOBES
        .iter()
        .map(|(name, _)| name.to_string())
        .chain(DELTA_LOBES.iter().map(|(name, _)| name.to_string()))
        .collect();
    kernel.sort();
    tested.sort();
    assert_eq!(kernel, tested, "the lobes of materials.glsl and the lobes with chi-square cases here differ");
    let cases: usize = LOBES.iter().map(|(_, cases)| cases().len()).sum();
    // The plastic case tests two lobes (its coat and its base), the clear-coated one three.
    assert_eq!(cases as f64 + 3.0, TESTS, "TESTS (the Bonferroni correction) counts the lobes tested");
}

/// Runs the cases of `lobe` (a LOBE_* name); each must pick that lobe among those it tests.
fn run_lobe(lobe: &str) {
    let kind = kernel_lobes()
        .into_iter()
        .find(|(name, _)| name == lobe)
        .unwrap_or_else(|| panic!("materials.glsl has no {lobe}"))
        .1;
    let cases = LOBES.iter().find(|(name, _)| *name == lobe).expect("listed in LOBES").1();
    run_cases(&cases, kind);
}

#[test]
fn diffuse_samples_follow_its_pdf() {
    run_lobe("LOBE_DIFFUSE");
}

#[test]
fn rough_conductor_samples_follow_its_pdf() {
    run_lobe("LOBE_REFLECT");
}

#[test]
fn rough_dielectric_samples_follow_its_pdf() {
    run_lobe("LOBE_DIELECTRIC");
}

#[test]
fn plastic_samples_follow_its_pdfs() {
    run_lobe("LOBE_COATED_DIFFUSE");
}

/// A thin sheet of glass (ior 1.5, Mitsuba's and pbrt-v4's thindielectric) reflects 2F / (1 + F)
/// of the light (every inner reflection summed) exactly in the mirror direction and passes the rest
/// exactly along the incoming ray, with weight 1, from either side. At cos 0.7, F = 0.0509 and
/// 2F / (1 + F) = 0.0969; 2^20 samples put five binomial standard errors at 0.0014, so a sheet
/// that reflected F alone (one interface), or refracted, fails by far.
#[test]
fn a_thin_sheet_reflects_two_f_over_one_plus_f_and_passes_the_rest_straight() {
    let (_lock, ctx) = gpu();
    let mut kernel = Kernel::new(&ctx);
    let kind = kernel_lobes()
        .into_iter()
        .find(|(name, _)| name == "LOBE_THIN_DIELECTRIC")
        .expect("materials.glsl has LOBE_THIN_DIELECTRIC")
        .1;
    let mut sheet = material(1.0, 0.0, 1.0, 1.5, 0.0);
    sheet.maps[3] = f32::from_bits(MATERIAL_THIN);
    let cos_o = 0.7f64;
    let f = fresnel_dielectric(cos_o, 1.5);
    let expected = 2.0 * f / (1.0 + f);
    let sin_o = (1.0 - cos_o * cos_o).sqrt();
    for entering in [true, false] {
        let case = Case { name: format!("thin sheet, entering {entering}"), material: sheet, cos_o, entering };
        let samples = kernel.samples(&case);
        // The ray arrives along d = (-sin, 0, -cos) (kernel.run) and the lobe's normal faces it,
        // +z from either side (lobe_for), so the mirror direction is (-sin, 0, cos).
        let d = [-sin_o as f32, 0.0, -cos_o as f32];
        let mirror = [-sin_o as f32, 0.0, cos_o as f32];
        let mut reflected = 0usize;
        for s in &samples {
            assert!(
                s.ok && s.lobe / 4 == kind,
                "{}: sample_lobe failed or picked another lobe ({})",
                case.name,
                s.lobe
            );
            assert!(
                s.weight.iter().all(|&w| (w - 1.0).abs() < 1e-6),
                "{}: weight {:?}, expected 1",
                case.name,
                s.weight
            );
            let is = |v: [f32; 3]| (0..3).all(|c| (s.dir[c] - v[c]).abs() < 1e-5);
            if is(mirror) {
                reflected += 1;
            } else {
                assert!(
                    is(d),
                    "{}: direction {:?} is neither the mirror direction {mirror:?} nor straight on {d:?}",
                    case.name,
                    s.dir
                );
            }
        }
        let n = samples.len() as f64;
        let share = reflected as f64 / n;
        let five_sigma = 5.0 * (expected * (1.0 - expected) / n).sqrt();
        eprintln!(
            "{}: reflected {share:.5}, expected 2F / (1 + F) = {expected:.5} (five standard errors {five_sigma:.5})",
            case.name
        );
        assert!((share - expected).abs() <= five_sigma, "{}: reflects {share:.5} of the light, expected 2F / (1 + F) = {expected:.5} (F = {f:.5}); five standard errors {five_sigma:.5}", case.name);
    }
    kernel.destroy();
}

/// The weak white furnace (Heitz 2014): for any wo, the integral over all wi of
/// D(h) G1(wo) / (4 wo.z), h the half vector, is 1: visible normals are a distribution. It ties
/// Smith's Lambda to D, which the sampling tests cannot (sample and eval share both), so a wrong
/// Lambda or an unnormalised D fails: the tolerance, 2e-3, is ten times the quadrature's error at
/// these alphas, and GGX's Lambda with alpha in place of alpha^2 is off by 8 % at alpha 0.3.
/// The anisotropic distributions (alpha 0.6 along u, 0.15 along v) are seen from 30 degrees off
/// the tangent's azimuth, so their Lambda must weigh both alphas by that azimuth: an isotropic
/// Lambda of either alpha, or the alphas swapped in Lambda alone, is off by far more than 2e-3.
#[test]
fn visible_normals_integrate_to_one_for_ggx_and_beckmann() {
    let (_lock, ctx) = gpu();
    let mut kernel = Kernel::new(&ctx);
    let (_, weights) = quadrature();
    let mut failures = Vec::new();
    for (name, distribution) in [("GGX", 0), ("Beckmann", MATERIAL_BECKMANN)] {
        for (alpha, alpha_v) in [(0.3f32, 0.0), (0.6, 0.0), (0.6, 0.15)] {
            for cos_o in [0.9, 0.3] {
                let mut m = anisotropic(material(1.0, 1.0, 0.0, 1.0, alpha), alpha_v);
                m.maps[3] = f32::from_bits(distribution);
                let case = Case {
                    name: format!(
                        "{name}, alpha {alpha} along u, {} along v, cos {cos_o}",
                        if alpha_v > 0.0 { alpha_v } else { alpha }
                    ),
                    material: m,
                    cos_o,
                    entering: true,
                };
                let values = kernel.run(&case, 2, weights.len() as u32, 0);
                let integral: f64 = values.iter().zip(&weights).map(|(v, w)| v[0] as f64 * w).sum();
                eprintln!("{}: the visible normals integrate to {integral:.5}", case.name);
                if integral.is_nan() || (integral - 1.0).abs() > 2e-3 {
                    failures.push(format!("{}: the visible normals integrate to {integral:.5}, not 1", case.name));
                }
            }
        }
    }
    kernel.destroy();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Of the microfacet normals an anisotropic lobe (alpha `ax` along u, `ay` along v; `beckmann` or
/// GGX) reflects a ray at normal incidence by, those that send it above the horizon (slope below
/// 1), measured in a frame turned by `turn` radians from the lobe's: the share whose slope is
/// steeper along x than along y, and the share in the first and third quadrants. At normal
/// incidence both samplers draw the slopes' density P22 (GGX's visible normals are D cos there),
/// which in polar coordinates (r, phi) is f(k r^2) / (pi ax ay), k = cos^2 phi / ax^2 +
/// sin^2 phi / ay^2, f(s) = 1 / (1 + s)^2 (GGX) or exp(-s) (Beckmann); over r in [0, 1] that
/// leaves 1 / (2 (1 + k)) and (1 - exp(-k)) / (2 k), integrated over phi here.
fn slope_shares(ax: f64, ay: f64, turn: f64, beckmann: bool) -> (f64, f64) {
    const STEPS: usize = 100_000;
    let (mut steeper_along_x, mut first_and_third, mut total) = (0.0, 0.0, 0.0);
    for i in 0..STEPS {
        let theta = (i as f64 + 0.5) / STEPS as f64 * 2.0 * PI;
        let (s, c) = (theta - turn).sin_cos();
        let k = c * c / (ax * ax) + s * s / (ay * ay);
        let w = if beckmann { (1.0 - (-k).exp()) / k } else { 1.0 / (1.0 + k) };
        let (s, c) = theta.sin_cos();
        total += w;
        if c.abs() > s.abs() {
            steeper_along_x += w;
        }
        if c * s > 0.0 {
            first_and_third += w;
        }
    }
    (steeper_along_x / total, first_and_third / total)
}

/// An anisotropic lobe lies along the surface's tangent, rough by alpha_u along it and alpha_v
/// across it, which the chi-square tests cannot see (sampling and eval_lobe share the frame and
/// the alphas). A conductor with alpha 0.5 along u and 0.1 along v is sampled at normal incidence,
/// the tangent given 30 degrees from x and tilted out of the surface (TANGENT); each reflected
/// direction's half vector is the microfacet normal, whose slopes along the tangent made normal
/// and across it are compared with the closed form of slope_shares: the share steeper along the
/// tangent (0.861 for GGX, 0.874 for Beckmann; 0.139 and 0.126 with the alphas swapped) and the
/// share in the first and third quadrants (exactly 1/2 by symmetry; 0.84 and 0.86 with the
/// arbitrary frame of an ignored tangent). The tolerance is five binomial standard errors (about
/// 0.002 and 0.003); the test checks here that an alpha off by 3 % or a tangent turned by a
/// quarter of a degree moves a share by more than that.
#[test]
fn anisotropic_lobes_are_rough_by_alpha_u_along_the_tangent_and_alpha_v_across() {
    let (_lock, ctx) = gpu();
    let mut kernel = Kernel::new(&ctx);
    let kind =
        kernel_lobes().into_iter().find(|(name, _)| name == "LOBE_REFLECT").expect("materials.glsl has LOBE_REFLECT").1;
    let (alpha_u, alpha_v) = (0.5f32, 0.1f32);
    let tangent_length = TANGENT[0].hypot(TANGENT[1]);
    let (t, b) = (
        [TANGENT[0] / tangent_length, TANGENT[1] / tangent_length],
        [-TANGENT[1] / tangent_length, TANGENT[0] / tangent_length],
    );
    let mut failures = Vec::new();
    for (name, beckmann_lobe) in [("GGX", false), ("Beckmann", true)] {
        let conductor = anisotropic(material(1.0, 1.0, 0.0, 1.0, alpha_u), alpha_v);
        let case = Case {
            name: format!("{name} anisotropic conductor"),
            material: if beckmann_lobe { beckmann(conductor) } else { conductor },
            cos_o: 1.0,
            entering: true,
        };
        let (mut steeper_along_x, mut first_and_third, mut n) = (0usize, 0usize, 0usize);
        for s in kernel.samples(&case).iter().filter(|s| s.ok) {
            assert_eq!(s.lobe / 4, kind, "{}: picked lobe {}", case.name, s.lobe);
            // The half vector of wo = +z and the reflected direction, as slopes.
            let h = [s.dir[0] as f64, s.dir[1] as f64, s.dir[2] as f64 + 1.0];
            let x = (h[0] * t[0] + h[1] * t[1]) / h[2];
            let y = (h[0] * b[0] + h[1] * b[1]) / h[2];
            steeper_along_x += usize::from(x.abs() > y.abs());
            first_and_third += usize::from(x * y > 0.0);
            n += 1;
        }
        let (ax, ay) = (alpha_u as f64, alpha_v as f64);
        let expected = slope_shares(ax, ay, 0.0, beckmann_lobe);
        let measured = (steeper_along_x as f64 / n as f64, first_and_third as f64 / n as f64);
        let tolerance = |p: f64| 5.0 * (p * (1.0 - p) / n as f64).sqrt();
        let tolerances = (tolerance(expected.0), tolerance(expected.1));
        // What the tolerances let through is smaller than these errors.
        let alpha_off = slope_shares(ax, ay * 1.03, 0.0, beckmann_lobe).0;
        let turned = slope_shares(ax, ay, 0.25f64.to_radians(), beckmann_lobe).1;
        assert!((alpha_off - expected.0).abs() > tolerances.0 && (turned - expected.1).abs() > tolerances.1, "{}: the tolerances {tolerances:?} would pass alpha_v off by 3 % ({alpha_off}) or a tangent turned by 0.25 degrees ({turned})", case.name);
        eprintln!("{}: steeper along the tangent {:.4} (expected {:.4} +- {:.4}), first and third quadrants {:.4} (expected {:.4} +- {:.4}), of {n} samples", case.name, measured.0, expected.0, tolerances.0, measured.1, expected.1, tolerances.1);
        if !((measured.0 - expected.0).abs() <= tolerances.0 && (measured.1 - expected.1).abs() <= tolerances.1) {
            failures
                .push(format!("{}: slope shares {measured:?}, expected {expected:?} within {tolerances:?}", case.name));
        }
    }
    kernel.destroy();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The p-value routine itself, against known chi-square quantiles.
#[test]
fn chi_square_p_values_match_tables() {
    for (x, dof, p) in [(37.697, 15.0, 0.001), (3.841, 1.0, 0.05), (124.342, 100.0, 0.05), (1_143.917, 1_000.0, 0.001)]
    {
        let q = gamma_q(dof / 2.0, x / 2.0);
        assert!((q / p - 1.0).abs() < 0.02, "chi-square {x} with {dof} dof: p {q:.4e}, expected {p:.1e}");
    }
}
