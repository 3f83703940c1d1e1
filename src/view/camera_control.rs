//! Camera moves of the viewer, on the scene's own [`Camera`] (position, look-at point, up, field
//! of view), so that what key P prints is a camera of the scene format. The look-at point is the
//! pivot: orbiting turns around it, the wheel dollies towards it, panning and flying carry it along.
//!
//! A camera whose focus distance is the distance to its look-at point (the scene format's default)
//! keeps it so through every move, so a thin lens stays focused on the pivot.

use crate::scene::Camera;
use glam::Vec3;

/// Closest the polar angle between the view offset and `up` comes to either pole (radians): the
/// camera never looks straight along `up`, where its frame would be undefined.
const POLE_MARGIN: f32 = 0.01;
/// Factor of the distance to the pivot per wheel step towards it.
const DOLLY_PER_STEP: f32 = 0.85;

fn distance(camera: &Camera) -> f32 {
    (camera.look_at - camera.position).length()
}

/// Whether the camera focuses on its look-at point, within rounding.
fn focuses_on_pivot(camera: &Camera) -> bool {
    (camera.focus_distance - distance(camera)).abs() <= 1e-4 * distance(camera).max(1e-6)
}

/// Applies `change` and keeps a focus on the pivot as such.
fn keeping_focus(camera: &mut Camera, change: impl FnOnce(&mut Camera)) {
    let on_pivot = focuses_on_pivot(camera);
    change(camera);
    if on_pivot {
        camera.focus_distance = distance(camera);
    }
}

/// `direction` turned by `yaw` about `up` and tilted by `pitch` towards `up` (radians), its polar
/// angle kept off the poles; the length is kept.
fn turn(direction: Vec3, up: Vec3, yaw: f32, pitch: f32) -> Vec3 {
    let up = up.normalize();
    let length = direction.length();
    let d = direction / length;
    let polar = d.dot(up).clamp(-1.0, 1.0).acos();
    let horizontal = (d - d.dot(up) * up).try_normalize().unwrap_or_else(|| up.any_orthonormal_vector());
    let horizontal = glam::Quat::from_axis_angle(up, yaw) * horizontal;
    let polar = (polar - pitch).clamp(POLE_MARGIN, std::f32::consts::PI - POLE_MARGIN);
    length * (polar.sin() * horizontal + polar.cos() * up)
}

/// The camera's right and true-up unit vectors.
fn frame(camera: &Camera) -> (Vec3, Vec3, Vec3) {
    let forward = (camera.look_at - camera.position).normalize();
    let right = forward.cross(camera.up).normalize();
    (forward, right, right.cross(forward))
}

/// Left drag: turns the camera around the pivot by `yaw` about `up` (right-handed) and raises it
/// by `pitch` towards `up` (radians); the distance to the pivot is kept.
pub fn orbit(camera: &mut Camera, yaw: f32, pitch: f32) {
    keeping_focus(camera, |c| {
        let offset = c.position - c.look_at;
        c.position = c.look_at + turn(offset, c.up, yaw, pitch);
    });
}

/// Middle drag (or shift + left): moves camera and pivot across the view so that the pivot's
/// plane follows the cursor, which moved `dx`, `dy` pixels in a view `view_height` pixels high.
pub fn pan(camera: &mut Camera, dx: f32, dy: f32, view_height: f32) {
    let (_, right, up) = frame(camera);
    let per_pixel = 2.0 * distance(camera) * (camera.fov_deg.to_radians() * 0.5).tan() / view_height.max(1.0);
    let shift = (-dx * right + dy * up) * per_pixel;
    camera.position += shift;
    camera.look_at += shift;
}

/// Wheel: `steps` towards the pivot (negative: away), each [`DOLLY_PER_STEP`] of the distance.
pub fn dolly(camera: &mut Camera, steps: f32) {
    keeping_focus(camera, |c| {
        let offset = c.position - c.look_at;
        c.position = c.look_at + offset * DOLLY_PER_STEP.powf(steps);
    });
}

/// Right drag: turns the view around the camera's position (`yaw` to the left, `pitch` up, in
/// radians); the pivot stays as far ahead.
pub fn look(camera: &mut Camera, yaw: f32, pitch: f32) {
    keeping_focus(camera, |c| {
        let ahead = c.look_at - c.position;
        c.look_at = c.position + turn(ahead, c.up, yaw, pitch);
    });
}

/// WASD/QE: moves camera and pivot by `along` in the camera's frame (x right, y up, z forward).
pub fn fly(camera: &mut Camera, along: Vec3) {
    let (forward, right, up) = frame(camera);
    let shift = along.x * right + along.y * up + along.z * forward;
    camera.position += shift;
    camera.look_at += shift;
}

/// F: looks at the centre of `bounds` (min, max corners) from the current direction, from as far
/// as a view of `aspect` (width / height) needs to hold the bounding sphere.
pub fn frame_bounds(camera: &mut Camera, bounds: (Vec3, Vec3), aspect: f32) {
    let (forward, _, _) = frame(camera);
    let center = 0.5 * (bounds.0 + bounds.1);
    let radius = (0.5 * (bounds.1 - bounds.0).length()).max(1e-3);
    let half_v = (camera.fov_deg.to_radians() * 0.5).min(1.5);
    let half_h = (half_v.tan() * aspect).atan();
    let distance = radius / half_v.min(half_h).sin() * 1.05;
    keeping_focus(camera, |c| {
        c.look_at = center;
        c.position = center - forward * distance;
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::pinhole(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0)
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn orbit_keeps_the_pivot_and_its_distance() {
        let mut c = camera();
        orbit(&mut c, std::f32::consts::FRAC_PI_2, 0.0);
        assert!(close(c.look_at, Vec3::new(0.0, 1.0, 0.0)));
        // A quarter turn about +y takes +z to +x.
        assert!(close(c.position, Vec3::new(5.0, 1.0, 0.0)), "{:?}", c.position);
        orbit(&mut c, 0.0, 0.3);
        assert!((distance(&c) - 5.0).abs() < 1e-4);
        assert!(c.position.y > 1.0, "a positive pitch raises the camera: {:?}", c.position);
        assert!((c.focus_distance - 5.0).abs() < 1e-4);
    }

    #[test]
    fn orbit_never_reaches_the_poles() {
        let mut c = camera();
        orbit(&mut c, 0.0, 10.0);
        let d = (c.look_at - c.position).normalize();
        assert!(d.dot(Vec3::Y).abs() < 1.0 - 1e-5, "{d:?}");
    }

    #[test]
    fn dolly_moves_towards_the_pivot_and_keeps_the_focus_on_it() {
        let mut c = camera();
        dolly(&mut c, 1.0);
        assert!((distance(&c) - 5.0 * DOLLY_PER_STEP).abs() < 1e-5);
        assert!((c.focus_distance - distance(&c)).abs() < 1e-5);
        dolly(&mut c, -1.0);
        assert!(close(c.position, camera().position));
    }

    #[test]
    fn a_focus_off_the_pivot_is_kept() {
        let mut c = Camera { focus_distance: 2.0, ..camera() };
        dolly(&mut c, 2.0);
        assert_eq!(c.focus_distance, 2.0);
    }

    #[test]
    fn pan_and_fly_carry_the_pivot_along() {
        let mut c = camera();
        pan(&mut c, 10.0, 0.0, 100.0);
        assert!(
            c.position.x < 0.0 && (c.position.x - c.look_at.x).abs() < 1e-6,
            "dragging right moves the camera left"
        );
        let mut c = camera();
        fly(&mut c, Vec3::new(0.0, 0.0, 1.0));
        assert!(close(c.position, Vec3::new(0.0, 1.0, 4.0)) && close(c.look_at, Vec3::new(0.0, 1.0, -1.0)));
    }

    #[test]
    fn look_turns_around_the_position() {
        let mut c = camera();
        look(&mut c, std::f32::consts::FRAC_PI_2, 0.0);
        assert!(close(c.position, camera().position));
        // Yaw left by a quarter turn: looking along -z becomes looking along -x.
        assert!(close(c.look_at, Vec3::new(-5.0, 1.0, 5.0)), "{:?}", c.look_at);
    }

    #[test]
    fn frame_holds_the_bounds_in_view() {
        let mut c = camera();
        frame_bounds(&mut c, (Vec3::splat(-10.0), Vec3::splat(10.0)), 1.0);
        assert!(close(c.look_at, Vec3::ZERO));
        let radius = Vec3::splat(10.0).length();
        assert!(distance(&c) > radius / 20f32.to_radians().sin(), "{}", distance(&c));
        assert!((c.look_at - c.position).normalize().dot(Vec3::NEG_Z) > 0.999, "the direction is kept");
    }
}
