//! The eight-wide walk (`bvh-width=8`, src/render/bvh_width.rs, shaders/bvh_eight_wide.glsl) finds
//! the closest hit the four-wide walk finds, on every checked-in scene: with the same seed a path
//! is the same wherever its hits are, so the two images are the same pixel for pixel except where
//! a ray meets two primitives at the same distance (an edge two triangles share), which the walks
//! may settle differently, the eight-wide build storing the primitives in another order. So at
//! most MAX_DIFFERING_SHARE of a scene's pixels may differ at all, and the rest must be equal bit
//! for bit. A walk that loses one child slot in eight (tests/mutations.toml), or a node box
//! quantized inwards, misses hits on whole regions of the image and fails this.
//! The four-wide walk with shadow rays' children unsorted (`shadow-walk=unsorted`,
//! src/render/shadow_walk.rs) renders the sorted walk's images bit for bit: a shadow ray's answer
//! does not depend on the order it finds an occluder in.
//! The rest of the tests that trace rays run with the eight-wide walk too: scripts/test.sh runs
//! them again under CAUSTICA_BVH_WIDTH=8.

mod common;

use caustica::render::{AovSet, BvhWidth, KernelChoice, KernelOptions, QueueRequest, Renderer, ShadowWalk};
use caustica::scene::Scene;
use common::{checked_in_scenes, gpu};

/// Image size and samples per pixel each scene is rendered at: small, as every scene renders twice.
const WIDTH: u32 = 40;
const HEIGHT: u32 = 30;
const SPP: u32 = 2;

/// Most pixels, as a share of the image, that may differ at all: ties between primitives at the
/// same distance are rare (none on most scenes); a lost child slot changes far more.
const MAX_DIFFERING_SHARE: f64 = 0.01;

/// The image's pixels as bits, rendered with `width`'s walk, shadow rays' children as `shadows`
/// says, and no walk queue (which walks four-wide nodes alone); `None` for a scene with no walk
/// (a few shapes tested in turn).
fn pixels(
    ctx: &caustica::gpu::GpuContext,
    scene: &Scene,
    width: BvhWidth,
    shadows: ShadowWalk,
) -> Option<Vec<[u32; 3]>> {
    let options = KernelOptions {
        bvh_width: Some(width),
        shadow_walk: Some(shadows),
        walk_queue: Some(QueueRequest::Off),
        ..Default::default()
    };
    let mut renderer = Renderer::with_options(ctx, scene, 3, AovSet::default(), KernelChoice::ForScene, &options)
        .expect("scene uploads");
    assert_eq!((renderer.bvh_width, renderer.shadow_walk), (width, shadows));
    if !renderer.features.bvh() {
        return None;
    }
    renderer.render(SPP, |_| {}).expect("render succeeds without validation messages");
    Some(renderer.image().expect("readback").pixels.iter().map(|p| p.map(f32::to_bits)).collect())
}

#[test]
fn the_eight_wide_walk_renders_the_four_wide_walk_s_images() {
    let (_lock, ctx) = gpu();
    let mut walked = 0;
    for (name, mut scene) in checked_in_scenes() {
        (scene.film.width, scene.film.height) = (WIDTH, HEIGHT);
        let Some(four) = pixels(&ctx, &scene, BvhWidth::Four, ShadowWalk::Sorted) else { continue };
        let eight = pixels(&ctx, &scene, BvhWidth::Eight, ShadowWalk::Sorted).expect("the same scene walks");
        let unsorted = pixels(&ctx, &scene, BvhWidth::Four, ShadowWalk::Unsorted).expect("the same scene walks");
        assert!(unsorted == four, "{name}: shadow rays' children unsorted change the image");
        assert!(four.iter().any(|p| p.iter().any(|&c| c != 0)), "{name}: nothing rendered");
        let differing = four.iter().zip(&eight).filter(|(a, b)| a != b).count();
        eprintln!("{name}: {differing} of {} pixels differ", four.len());
        assert!(
            differing as f64 <= MAX_DIFFERING_SHARE * four.len() as f64,
            "{name}: {differing} of {} pixels differ between the four- and eight-wide walks",
            four.len()
        );
        walked += 1;
    }
    // The meshes' scenes and the Cornell boxes of more shapes than are tested in turn.
    assert!(walked >= 4, "only {walked} scenes walk a BVH");
}

/// Asking for the walk queue with the eight-wide walk is an error that says why.
#[test]
fn the_walk_queue_is_refused_with_eight_wide_nodes() {
    let (_lock, ctx) = gpu();
    let scene = common::cornell(16, 1);
    let options =
        KernelOptions { bvh_width: Some(BvhWidth::Eight), walk_queue: Some(QueueRequest::On), ..Default::default() };
    let error = Renderer::with_options(&ctx, &scene, 3, AovSet::default(), KernelChoice::ForScene, &options)
        .err()
        .expect("refused")
        .to_string();
    assert!(error.contains("bvh-width=8") && error.contains("walk-queue"), "{error}");
}
