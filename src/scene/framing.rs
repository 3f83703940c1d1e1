//! Cameras that frame a scene's bounding box: the one a mesh file without a camera of its own is
//! rendered through (a three-quarter view from above the box's largest face), and the command
//! line's `--camera-orbit AZ,EL` and `--camera-fit`.
//!
//! Orbit angles are about the world's +y (up): azimuth 0 looks from +z towards -z, 90 from +x;
//! elevation 0 is level, 90 straight down from above. A fitted camera stands as close as it can
//! while every corner of the box lies inside its view, with a 5 % margin.

use glam::Vec3;

use super::{Camera, Scene, Shape};

/// The field of view of the cameras made here, in degrees (vertical).
pub const FRAMING_FOV_DEGREES: f32 = 40.0;

/// How far off the largest face's normal the default view turns (azimuth), and how high it
/// looks down on a box whose largest face is upright, in degrees: a three-quarter view.
const THREE_QUARTER_AZIMUTH: f32 = 35.0;
const THREE_QUARTER_ELEVATION: f32 = 25.0;
/// The elevation over a box whose largest face is horizontal (a flat model in the xz plane).
const FLAT_ELEVATION: f32 = 55.0;

/// The world-space bounding box (min, max) of every mesh instance and shape; None when the scene
/// has neither.
pub fn scene_bounds(scene: &Scene) -> Option<(Vec3, Vec3)> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let mut add = |p: Vec3| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    for instance in &scene.instances {
        for &p in &scene.meshes[instance.mesh as usize].positions {
            add(instance.transform.transform_point3(p));
        }
    }
    for shape in &scene.shapes {
        match *shape {
            Shape::Sphere { center, radius, .. } => {
                add(center - Vec3::splat(radius));
                add(center + Vec3::splat(radius));
            }
            Shape::Quad { origin, u, v, .. } => {
                [origin, origin + u, origin + v, origin + u + v].into_iter().for_each(&mut add)
            }
            Shape::Triangle { v, .. } => v.into_iter().for_each(&mut add),
        }
    }
    (lo.cmple(hi).all()).then_some((lo, hi))
}

/// The default view of a box: a three-quarter view from above its largest face. A box whose
/// largest face is horizontal is seen from high above (+y side), one whose largest face is upright
/// from a little above, turned off that face's normal (+z or +x side).
pub fn default_orbit(bounds: (Vec3, Vec3)) -> (f32, f32) {
    let e = bounds.1 - bounds.0;
    let (xy, xz, yz) = (e.x * e.y, e.x * e.z, e.y * e.z);
    if xz >= xy && xz >= yz {
        (THREE_QUARTER_AZIMUTH, FLAT_ELEVATION)
    } else if xy >= yz {
        (THREE_QUARTER_AZIMUTH, THREE_QUARTER_ELEVATION)
    } else {
        (90.0 - THREE_QUARTER_AZIMUTH, THREE_QUARTER_ELEVATION)
    }
}

/// The unit direction from the box towards a camera at these orbit angles (degrees).
fn orbit_direction(azimuth: f32, elevation: f32) -> Vec3 {
    let (az, el) = (azimuth.to_radians(), elevation.to_radians());
    Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
}

/// A pinhole camera at orbit angles (degrees) around the box's centre, fitted to it (see
/// [`fit_along`]) for a film of `aspect` (width / height).
pub fn orbit_camera(bounds: (Vec3, Vec3), azimuth: f32, elevation: f32, aspect: f32) -> Camera {
    let centre = 0.5 * (bounds.0 + bounds.1);
    let towards_camera = orbit_direction(azimuth, elevation);
    // Straight above or below, the view's up is -z (the image's top towards -z).
    let up = if towards_camera.cross(Vec3::Y).length_squared() < 1e-8 { Vec3::NEG_Z } else { Vec3::Y };
    let distance = fit_along(bounds, centre, -towards_camera, up, FRAMING_FOV_DEGREES, aspect);
    Camera::pinhole(centre + towards_camera * distance, centre, up, FRAMING_FOV_DEGREES)
}

/// `camera` moved along its viewing axis, keeping its direction, field of view and up, to the
/// nearest place from which the box fills its view: the axis passes through the box's centre.
pub fn fit_camera(camera: &Camera, bounds: (Vec3, Vec3), aspect: f32) -> Camera {
    let centre = 0.5 * (bounds.0 + bounds.1);
    let forward = (camera.look_at - camera.position).normalize();
    let up = if forward.cross(camera.up).length_squared() < 1e-8 { Vec3::Y } else { camera.up };
    let distance = fit_along(bounds, centre, forward, up, camera.fov_deg, aspect);
    Camera { position: centre - forward * distance, look_at: centre, up, focus_distance: distance, ..*camera }
}

/// The distance from `centre` back along unit `forward` at which a camera with this up, vertical
/// field of view (degrees) and aspect sees every corner of the box, with a 5 % margin.
fn fit_along(bounds: (Vec3, Vec3), centre: Vec3, forward: Vec3, up: Vec3, fov_deg: f32, aspect: f32) -> f32 {
    let right = forward.cross(up).normalize();
    let up = right.cross(forward);
    let tan_y = (0.5 * fov_deg).to_radians().tan();
    let tan_x = tan_y * aspect;
    let extent = (bounds.1 - bounds.0).length().max(1e-3);
    let mut distance: f32 = 0.0;
    for k in 0..8 {
        let corner = Vec3::new(
            if k & 1 == 0 { bounds.0.x } else { bounds.1.x },
            if k & 2 == 0 { bounds.0.y } else { bounds.1.y },
            if k & 4 == 0 { bounds.0.z } else { bounds.1.z },
        ) - centre;
        // At distance D the corner lies D + depth in front, and must be within the view's slopes.
        let depth = corner.dot(forward);
        distance = distance
            .max(corner.dot(right).abs() / tan_x - depth)
            .max(corner.dot(up).abs() / tan_y - depth)
            // In front of the near side of the box, never inside it.
            .max(0.01 * extent - depth);
    }
    1.05 * distance
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every corner of the box lies inside the camera's view, and one touches its margin.
    fn assert_frames(camera: &Camera, bounds: (Vec3, Vec3), aspect: f32) {
        let forward = (camera.look_at - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let tan_y = (0.5 * camera.fov_deg).to_radians().tan();
        let mut widest: f32 = 0.0;
        for k in 0..8 {
            let p = Vec3::new(
                if k & 1 == 0 { bounds.0.x } else { bounds.1.x },
                if k & 2 == 0 { bounds.0.y } else { bounds.1.y },
                if k & 4 == 0 { bounds.0.z } else { bounds.1.z },
            ) - camera.position;
            let depth = p.dot(forward);
            assert!(depth > 0.0, "corner {k} is behind the camera");
            let (x, y) = (p.dot(right) / (depth * tan_y * aspect), p.dot(up) / (depth * tan_y));
            assert!(x.abs() <= 1.0 && y.abs() <= 1.0, "corner {k} is outside the view: {x}, {y}");
            widest = widest.max(x.abs()).max(y.abs());
        }
        assert!(widest > 0.85, "the box fills the view: its widest corner reaches {widest}");
    }

    /// A flat model in the xz plane is seen from above it (the old framing looked along it, edge
    /// on, and saw nothing); an upright one from a little above, facing its largest face.
    #[test]
    fn the_default_view_looks_down_on_a_flat_model_and_at_an_upright_one() {
        let flat = (Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 1.0));
        let (az, el) = default_orbit(flat);
        assert!(el >= 45.0, "elevation {el}");
        let camera = orbit_camera(flat, az, el, 1.0);
        assert!(camera.position.y > 0.5 * (camera.position - camera.look_at).length(), "{camera:?}");
        assert_frames(&camera, flat, 1.0);

        let upright = (Vec3::new(-1.0, 0.0, -0.1), Vec3::new(1.0, 3.0, 0.1));
        let (az, el) = default_orbit(upright);
        let camera = orbit_camera(upright, az, el, 0.5);
        let towards = (camera.position - camera.look_at).normalize();
        assert!(towards.z > 0.7 && towards.y > 0.0 && towards.y < 0.5, "{towards}");
        assert_frames(&camera, upright, 0.5);

        let sideways = (Vec3::new(-0.1, 0.0, -1.0), Vec3::new(0.1, 3.0, 1.0));
        let towards = orbit_direction(default_orbit(sideways).0, default_orbit(sideways).1);
        assert!(towards.x > 0.7, "{towards}");
    }

    /// Orbit angles: azimuth 0 is +z, 90 is +x; elevation 90 is straight above (with an up that
    /// is not parallel to the view).
    #[test]
    fn orbit_angles_and_fitting() {
        let unit = (Vec3::splat(-1.0), Vec3::splat(1.0));
        for (az, el, towards) in [(0.0, 0.0, Vec3::Z), (90.0, 0.0, Vec3::X), (0.0, 90.0, Vec3::Y)] {
            let camera = orbit_camera(unit, az, el, 2.0);
            let got = (camera.position - camera.look_at).normalize();
            assert!((got - towards).length() < 1e-5, "({az}, {el}): {got}");
            assert_frames(&camera, unit, 2.0);
        }
        // Fitting keeps the direction and field of view, and moves the camera to the box.
        let far = Camera::pinhole(Vec3::new(0.0, 0.0, 100.0), Vec3::new(0.0, 0.0, 99.0), Vec3::Y, 30.0);
        let fitted = fit_camera(&far, unit, 1.0);
        assert_eq!(fitted.fov_deg, 30.0);
        assert!((fitted.position - fitted.look_at).normalize().dot(Vec3::Z) > 0.9999);
        assert_frames(&fitted, unit, 1.0);
    }
}
