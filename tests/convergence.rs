//! Monte Carlo convergence: the error of an unbiased render falls as 1 / spp, measured with the
//! same metric `caustica compare` prints.

mod common;

use caustica::image::compare;
use common::*;

/// Against an independent 256 spp reference, the relative MSE is the render's variance plus the
/// reference's: (1/8 + 1/256) / (1/32 + 1/256) = 3.7 from 8 to 32 spp. Independent numbers: the
/// 1 / spp rate is theirs (Sobol's error falls faster where the integrand is smooth).
#[test]
fn error_falls_as_one_over_spp() {
    let (_lock, ctx) = gpu();
    let mut scene = caustica::scene::Scene::default_scene();
    scene.integrator.sampler = caustica::scene::Sampler::Independent;
    scene.film.width = 24;
    scene.film.height = 24;
    scene.film.spp = 256;
    let reference = render(&ctx, &scene, 1);
    let mut error_at = |spp: u32| {
        scene.film.spp = spp;
        compare(&render(&ctx, &scene, 1 + spp), &reference, ("render", "reference")).unwrap().relative_mse
    };
    let (coarse, fine) = (error_at(8), error_at(32));
    let ratio = coarse / fine;
    // Heavy-tailed caustic paths make the estimate itself noisy.
    assert!(
        (2.5..6.4).contains(&ratio),
        "relative MSE at 8 spp {coarse:.4e}, at 32 spp {fine:.4e}: ratio {ratio:.2}, expected about 3.7"
    );
}
