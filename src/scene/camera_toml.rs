//! A camera written back in the scene format: the `[camera]` table the viewer prints (key P) for
//! pasting into a scene file.

use super::Camera;
use std::fmt::Write as _;

/// The `[camera]` table of a scene file that gives `camera` exactly: every key written,
/// `focus_distance` included, and every number such that reading it back (TOML numbers are read
/// as f64, then rounded to f32) gives the same f32.
pub fn camera_toml(camera: &Camera) -> String {
    let triple = |v: glam::Vec3| format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z));
    let mut text = String::from("[camera]\n");
    let _ = writeln!(text, "position = {}", triple(camera.position));
    let _ = writeln!(text, "look_at = {}", triple(camera.look_at));
    let _ = writeln!(text, "up = {}", triple(camera.up));
    let _ = writeln!(text, "fov = {}", number(camera.fov_deg));
    let _ = writeln!(text, "aperture = {}", number(camera.aperture));
    let _ = writeln!(text, "focus_distance = {}", number(camera.focus_distance));
    text
}

/// The shortest decimal that reads back as `x` (Rust's `{:?}`), unless reading it as f64 first
/// lands on another f32 (a double rounding, rare): then the exact value of `x`, which f64 holds.
fn number(x: f32) -> String {
    let short = format!("{x:?}");
    if short.parse::<f64>().map(|v| v as f32) == Ok(x) {
        short
    } else {
        format!("{:?}", f64::from(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use glam::Vec3;
    use std::path::Path;

    #[test]
    fn a_printed_camera_reads_back_bit_for_bit() {
        let camera = Camera {
            position: Vec3::new(0.1, -2.5e-7, 1234.5678),
            look_at: Vec3::new(1.0 / 3.0, 0.0, -0.0),
            up: Vec3::new(0.0, 1.0, 1e-3),
            fov_deg: 37.123,
            aperture: 0.05,
            focus_distance: 3.3333333,
        };
        let text = format!("{}\n[film]\nwidth = 8\nheight = 8\n", camera_toml(&camera));
        let scene = Scene::parse(&text, "printed.toml", Path::new(".")).unwrap();
        let read = scene.camera;
        for (a, b) in [(read.position, camera.position), (read.look_at, camera.look_at), (read.up, camera.up)] {
            assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits), "{text}");
        }
        assert_eq!(
            [read.fov_deg, read.aperture, read.focus_distance].map(f32::to_bits),
            [camera.fov_deg, camera.aperture, camera.focus_distance].map(f32::to_bits)
        );
    }

    #[test]
    fn numbers_are_short_where_they_can_be() {
        assert_eq!(number(0.1), "0.1");
        assert_eq!(number(40.0), "40.0");
        assert_eq!(number(-0.0), "-0.0");
        for bits in (0x3000_0000u32..0x5000_0000).step_by(9973) {
            let x = f32::from_bits(bits);
            assert_eq!(number(x).parse::<f64>().unwrap() as f32, x);
        }
    }
}
