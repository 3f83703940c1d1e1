//! Subgroups that take their tiles from a counter (src/render/tile_taking.rs, pathtrace.comp's
//! `TAKE_TILES`) render the sums of workgroups that render their own pixels, bit for bit: every
//! pixel once, with its own samples, whichever subgroup took its tile. The film is no multiple of
//! the workgroup, so tiles straddle its edges, and one render goes in bands of one workgroup row
//! (each dispatch's tiles counted from its own band). A tile mapped to the wrong workgroup or lane,
//! or a counter that skips or repeats a tile, leaves a pixel short or doubled: the renderer's
//! check that every pixel reached its target fails the render, or the sums differ (the mutations
//! `tiles-*` of tests/mutations.toml).

mod common;

use caustica::render::{AovSet, KernelChoice, Renderer, TAKE_TILES_VAR};
use common::two_meshes::{rendered_sums, two_meshes_in_a_room};
use common::{gpu, loops_end_early};

#[test]
fn subgroups_taking_tiles_render_the_same_sums_as_workgroups_rendering_their_own() {
    let (_lock, ctx) = gpu();
    if loops_end_early(&ctx, "tile counter") {
        return;
    }
    let mut scene = two_meshes_in_a_room();
    // 37 x 29: five workgroups across and four down, the last of each partly off the film.
    (scene.film.width, scene.film.height) = (37, 29);
    let spp = scene.film.spp;
    let renderer = |take_tiles: &str| {
        // Read when a renderer is made; the lock keeps other tests of this binary from making one.
        std::env::set_var(TAKE_TILES_VAR, take_tiles);
        let made = Renderer::with_kernel(&ctx, &scene, 11, AovSet::ALL, KernelChoice::ForScene);
        std::env::remove_var(TAKE_TILES_VAR);
        made.expect("scene uploads")
    };
    let mut own = renderer("0");
    assert!(!own.take_tiles, "{TAKE_TILES_VAR}=0 still took tiles");
    let (reference, reference_aovs) = rendered_sums(&mut own, &[spp]);

    let mut taking = renderer("1");
    assert!(taking.take_tiles, "{TAKE_TILES_VAR}=1 on {} took no tiles", ctx.info.driver_info);
    let (taken, taken_aovs) = rendered_sums(&mut taking, &[2, 3, spp - 5]);
    let differing = taken.iter().zip(&reference).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ when subgroups take their tiles", reference.len());
    assert!(taken_aovs == reference_aovs, "the AOV sums differ when subgroups take their tiles");

    // Dispatches far shorter than one pass: bands of one workgroup row, one sample each.
    let mut banded = renderer("1");
    banded.set_dispatch_target(1e-9);
    let (in_bands, in_bands_aovs) = rendered_sums(&mut banded, &[spp]);
    assert!(
        in_bands == reference && in_bands_aovs == reference_aovs,
        "the sums differ when subgroups take the tiles of bands"
    );
}
