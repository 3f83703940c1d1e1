//! The thin-lens camera, pixel filters, radiance clamp and non-finite sample count, on scenes of
//! emitting quads seen directly (albedo 0, black sky), where a pixel's exact value is known: the
//! emission times the fraction of its samples that hit the quad.

mod common;

use caustica::image::RgbImage;
use caustica::render::Renderer;
use caustica::scene::Scene;
use common::*;

/// A camera at the origin looking down -z, `width` x 8 pixels at a 20 degree vertical fov.
fn scene(width: u32, spp: u32, camera: &str, film: &str, integrator: &str, quads: &str) -> Scene {
    parse(&format!(
        "[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov = 20.0\n{camera}\n\
         [film]\nwidth = {width}\nheight = 8\nspp = {spp}\n{film}\n[integrator]\n{integrator}\n{quads}"
    ))
}

/// An emitting quad facing the camera at depth `z`, spanning x in [x0, x1] and well past the view
/// vertically.
fn quad(name: &str, emission: [f32; 3], z: f32, x0: f32, x1: f32) -> String {
    format!(
        "[materials.{name}]\nalbedo = [0.0, 0.0, 0.0]\nemission = {emission:?}\n\
         [[quads]]\norigin = [{x0}, -10.0, {}]\nedge_u = [{}, 0.0, 0.0]\nedge_v = [0.0, 20.0, 0.0]\nmaterial = \"{name}\"\n",
        -z,
        x1 - x0
    )
}

/// The left half of the view (x < 0) covered by a unit emitter at depth z: the edge falls on the
/// boundary between the two middle columns.
fn half_plane(z: f32) -> String {
    quad("light", [1.0; 3], z, -10.0, 0.0)
}

/// Pixels of row `y` that are neither fully on the unit emitter nor fully off it.
fn mixed_in_row(img: &RgbImage, y: u32) -> usize {
    (0..img.width).filter(|&x| img.get(x, y).iter().any(|&c| c != 0.0 && c != 1.0)).count()
}

fn mixed_per_row(img: &RgbImage) -> Vec<usize> {
    (0..img.height).map(|y| mixed_in_row(img, y)).collect()
}

/// Mean of the first channel of column x.
fn column_mean(img: &RgbImage, x: u32) -> f64 {
    (0..img.height).map(|y| img.get(x, y)[0] as f64).sum::<f64>() / img.height as f64
}

fn assert_every_pixel(img: &RgbImage, x_range: std::ops::Range<u32>, expected: [f32; 3], what: &str) {
    for y in 0..img.height {
        for x in x_range.clone() {
            let p = img.get(x, y);
            assert!(
                (0..3).all(|c| (p[c] - expected[c]).abs() <= 1e-6 * expected[c]),
                "{what}: pixel ({x},{y}) is {p:?}, expected {expected:?}"
            );
        }
    }
}

#[test]
fn the_focal_plane_stays_sharp_and_nearer_edges_blur() {
    let (_lock, ctx) = gpu();
    let lens = "aperture = 1.0\nfocus_distance = 4.0";
    let pinhole = "focus_distance = 4.0";
    // A pixel is 0.18 units wide on the focal plane; an edge at depth 2 blurs into a disk of radius
    // 1.0 * (4 - 2) / 2 = 1 unit there, about 11 pixels across.
    let in_focus = render(&ctx, &scene(32, 64, lens, "", "", &half_plane(4.0)), 1);
    let near = render(&ctx, &scene(32, 64, lens, "", "", &half_plane(2.0)), 1);
    let near_pinhole = render(&ctx, &scene(32, 64, pinhole, "", "", &half_plane(2.0)), 1);
    assert!(mixed_per_row(&in_focus).iter().all(|&n| n <= 2), "in focus: {:?}", mixed_per_row(&in_focus));
    assert!(mixed_per_row(&near).iter().all(|&n| n >= 8), "out of focus: {:?}", mixed_per_row(&near));
    assert!(mixed_per_row(&near_pinhole).iter().all(|&n| n <= 1), "pinhole: {:?}", mixed_per_row(&near_pinhole));
    // The blur is symmetric about the edge: half the light leaks right of it, as much as is lost left.
    let mean = (0..32).map(|x| column_mean(&near, x)).sum::<f64>() / 32.0;
    assert!((mean - 0.5).abs() < 0.02, "mean over the image {mean}");
}

#[test]
fn flat_regions_keep_their_value_with_every_filter_and_lens() {
    let (_lock, ctx) = gpu();
    let emission = [0.25, 1.0, 4.0];
    let wall = quad("light", emission, 4.0, -10.0, 10.0);
    for filter in ["box", "tent", "gaussian"] {
        for camera in ["", "aperture = 0.3\nfocus_distance = 2.5"] {
            let img = render(&ctx, &scene(16, 16, camera, &format!("filter = \"{filter}\""), "", &wall), 3);
            assert_every_pixel(&img, 0..16, emission, &format!("{filter} filter, camera '{camera}'"));
        }
    }
}

#[test]
fn tent_and_gaussian_filters_widen_an_edge_by_their_footprint() {
    let (_lock, ctx) = gpu();
    let edge =
        |filter: &str| render(&ctx, &scene(16, 256, "", &format!("filter = \"{filter}\""), "", &half_plane(4.0)), 5);
    let boxed = edge("box");
    assert!(mixed_per_row(&boxed).iter().all(|&n| n == 0), "box: {:?}", mixed_per_row(&boxed));
    // Columns 7 and 8 have their centres half a pixel from the edge: the share of each filter
    // beyond half a pixel leaks across, 1/8 for the tent, P(Z > 1) = 0.1587 for the Gaussian.
    for (filter, leak) in [("tent", 0.125), ("gaussian", 0.158_655)] {
        let img = edge(filter);
        let (left, right) = (column_mean(&img, 7), column_mean(&img, 8));
        assert!(
            (left - (1.0 - leak)).abs() < 0.03 && (right - leak).abs() < 0.03,
            "{filter}: columns 7 and 8 are {left:.4}, {right:.4}, expected {:.4}, {leak:.4}",
            1.0 - leak
        );
        assert!(mixed_per_row(&img).iter().all(|&n| n >= 2), "{filter}: {:?}", mixed_per_row(&img));
    }
    // The tent's radius is 1 pixel: columns 6 and 9, 1.5 pixels from the edge, never see across.
    let tent = edge("tent");
    assert!((0..8).all(|y| tent.get(6, y)[0] == 1.0 && tent.get(9, y)[0] == 0.0), "the tent reaches past 1 pixel");
}

#[test]
fn the_clamp_caps_each_sample_and_leaves_dim_ones_alone() {
    let (_lock, ctx) = gpu();
    let quads = quad("bright", [40.0, 20.0, 5.0], 4.0, -10.0, 0.0) + &quad("dim", [4.0, 2.0, 1.0], 4.0, 0.0, 10.0);
    let clamped = render(&ctx, &scene(16, 8, "", "", "clamp = 10.0", &quads), 7);
    assert_every_pixel(&clamped, 0..8, [10.0, 5.0, 1.25], "bright half, clamped");
    assert_every_pixel(&clamped, 8..16, [4.0, 2.0, 1.0], "dim half, clamped");
    let unclamped = render(&ctx, &scene(16, 8, "", "", "", &quads), 7);
    assert_every_pixel(&unclamped, 0..8, [40.0, 20.0, 5.0], "bright half, no clamp");
}

#[test]
fn a_normal_render_drops_no_non_finite_samples() {
    let (_lock, ctx) = gpu();
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height) = (16, 16);
    let mut r = Renderer::new(&ctx, &scene, 1).expect("scene uploads");
    r.render(4, |_| {}).expect("render succeeds");
    assert!(r.rays_traced > 0, "the stats buffer's ray count is read back");
    assert_eq!(r.nonfinite_samples, 0);
}
