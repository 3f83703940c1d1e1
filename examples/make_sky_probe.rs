//! Writes scenes/probes/sky_probe.pfm: a small synthetic light probe (Debevec angular map) with a
//! sky gradient, a ground and a sun, so the probe-lit scene needs no downloaded data. Made here, CC0.
//!
//!     cargo run --example make_sky_probe

use caustica::image::{pfm, RgbImage};
use glam::Vec3;

const SIZE: u32 = 128;

/// Radiance of the synthetic sky in world direction `d` (+y up).
fn sky(d: Vec3) -> [f32; 3] {
    let sun = Vec3::new(0.55, 0.45, -0.7).normalize();
    if d.dot(sun) > 5f32.to_radians().cos() {
        return [60.0, 52.0, 40.0];
    }
    if d.y < 0.0 {
        return [0.18, 0.16, 0.14];
    }
    let t = d.y.sqrt();
    let horizon = Vec3::new(1.1, 1.05, 1.0);
    let zenith = Vec3::new(0.25, 0.45, 1.0);
    horizon.lerp(zenith, t).into()
}

fn main() {
    let mut image = RgbImage::new(SIZE, SIZE);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let u = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
            let v = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
            let r = (u * u + v * v).sqrt();
            if r > 1.0 {
                continue; // outside the circle: black, as in Debevec's probes
            }
            // Inverse of the angular map: angle from -z is pi r, azimuth atan2(v, u).
            let phi = std::f32::consts::PI * r;
            let theta = v.atan2(u);
            let d = Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), -phi.cos());
            image.set(x, y, sky(d));
        }
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/probes/sky_probe.pfm");
    pfm::write(&path, &image).expect("write the probe");
    println!("wrote {}", path.display());
}
