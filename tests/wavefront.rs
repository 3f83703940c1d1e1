//! The wavefront split (src/render/wavefront.rs, shaders/wavefront.glsl) renders the megakernel's
//! sums bit for bit: every vertex, shadow ray and sample the same, the shadow ray's light added
//! before the next vertex's, the samples in sample order, however the render is split into passes
//! and bands. Any change to what a round's kernels compute or to the state they hand each other
//! (a word of it dropped or swapped, a shadow ray's light added twice or never, a sample added
//! before its shadow ray is in) changes the sums: the mutations `wavefront-*` of
//! tests/mutations.toml.

mod common;

use caustica::render::{KernelChoice, Renderer, WAVEFRONT_VAR};
use caustica::scene::Scene;
use common::two_meshes::{sums, two_meshes_in_a_room};
use common::{gpu, loops_end_early};

/// Sums of `scene` with the wavefront (`CAUSTICA_WAVEFRONT=1`, read when a renderer is made; the
/// lock `gpu()` holds keeps this binary's other tests from making one meanwhile).
fn wavefront_sums(
    ctx: &caustica::gpu::GpuContext,
    scene: &Scene,
    steps: &[u32],
) -> (Vec<[u32; 4]>, caustica::render::AovSums) {
    std::env::set_var(WAVEFRONT_VAR, "1");
    let (bits, aovs, queue, wavefront) = sums(ctx, scene, KernelChoice::ForScene, steps);
    std::env::remove_var(WAVEFRONT_VAR);
    assert!(wavefront && queue.is_none(), "the render ran the wavefront, without the walk queue");
    (bits, aovs)
}

#[test]
fn the_wavefront_renders_the_megakernels_sums_bit_for_bit() {
    let (_lock, ctx) = gpu();
    if loops_end_early(&ctx, "wavefront") {
        return;
    }
    // Two meshes, clay and glass (paths of very different lengths), every AOV; the Cornell box
    // (spheres and quads, an area light); and rough metals and plastics, whose sampled directions
    // can fail after the light was sampled, so that a path ends with its shadow ray still to trace.
    let mut cornell = Scene::default_scene();
    (cornell.film.width, cornell.film.height, cornell.film.spp) = (40, 24, 6);
    let mut materials =
        Scene::load(std::path::Path::new("scenes/materials.toml")).expect("scenes/materials.toml loads");
    (materials.film.width, materials.film.height, materials.film.spp) = (48, 32, 6);
    for scene in [two_meshes_in_a_room(), cornell, materials] {
        let spp = scene.film.spp;
        let (mega, mega_aovs, _, mega_wavefront) = sums(&ctx, &scene, KernelChoice::General, &[spp]);
        assert!(!mega_wavefront, "without the variable the megakernel runs");
        // Passes of 2, then 3, then the rest: a pixel's next pass starts from the sums it holds.
        let (wave, wave_aovs) = wavefront_sums(&ctx, &scene, &[2, 3, spp - 5]);
        let differing = wave.iter().zip(&mega).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing,
            0,
            "{}: {differing} of {} pixels differ between the wavefront and the megakernel",
            scene.name,
            mega.len()
        );
        assert!(wave_aovs == mega_aovs, "{}: the AOV sums differ between the wavefront and the megakernel", scene.name);
    }
}

#[test]
fn the_wavefront_renders_in_bands_as_in_one_dispatch() {
    let (_lock, ctx) = gpu();
    if loops_end_early(&ctx, "wavefront") {
        return;
    }
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height, scene.film.spp) = (24, 72, 3);
    std::env::set_var(WAVEFRONT_VAR, "1");
    let mut whole = Renderer::new(&ctx, &scene, 5).expect("scene uploads");
    let mut banded = Renderer::new(&ctx, &scene, 5).expect("scene uploads");
    std::env::remove_var(WAVEFRONT_VAR);
    whole.fix_samples_per_dispatch(scene.film.spp);
    whole.render(scene.film.spp, |_| {}).expect("render succeeds");
    // A tiny dispatch target: the first pass's band of 32 rows, then bands of a workgroup row.
    banded.set_dispatch_target(1e-9);
    banded.render(scene.film.spp, |_| {}).expect("render succeeds");
    assert!(whole.runs_wavefront() && banded.runs_wavefront());
    let bits =
        |r: &Renderer| r.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    let (a, b) = (bits(&whole), bits(&banded));
    assert!(a.iter().all(|p| f32::from_bits(p[3]) == 3.0), "every pixel holds its 3 samples");
    let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ between one dispatch and bands", a.len());
}

#[test]
fn a_bad_value_of_the_variable_is_an_error() {
    let (_lock, ctx) = gpu();
    std::env::set_var(WAVEFRONT_VAR, "yes");
    let made = Renderer::new(&ctx, &Scene::default_scene(), 1);
    std::env::remove_var(WAVEFRONT_VAR);
    let error = made.err().expect("an unknown value is refused").to_string();
    assert!(error.contains(WAVEFRONT_VAR) && error.contains("expected"), "{error}");
}
