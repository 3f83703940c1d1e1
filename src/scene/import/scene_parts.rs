//! Pieces of caustica's scene file that both importers build the same way: triples, the path
//! length cap for an unbounded foreign depth, unique material names, file names relative to the
//! scene's folder, and the uniform scale a sphere's radius can follow.

use super::super::format::{Array, MaterialFile, Triple};
use glam::{DMat4, DVec3, DVec4};
use std::collections::BTreeMap;
use std::path::Path;

/// caustica's cap on the path length (`integrator.max_bounces`' default), for a foreign renderer's
/// unbounded depth (Mitsuba's `max_depth = -1`, pbrt's negative `maxdepth`): roulette survival is
/// at most 0.95 a vertex, so a path reaches it with probability below 1e-22.
pub const UNBOUNDED_DEPTH: u32 = 1024;

/// `v` in single precision, -0 made 0 (for the converted file's sake).
pub fn f32x3(v: DVec3) -> Triple {
    Array((v + DVec3::ZERO).as_vec3().to_array())
}

/// `name`, primed until no material of `materials` has it.
pub fn unique_name(materials: &BTreeMap<String, MaterialFile>, name: String) -> String {
    let mut name = name;
    while materials.contains_key(&name) {
        name.push('\'');
    }
    name
}

/// `path` relative to the scene's folder `base` where it lies inside it, else as it is.
pub fn relative_to(path: &Path, base: &Path) -> String {
    match path.strip_prefix(base) {
        Ok(relative) => relative.display().to_string(),
        Err(_) => path.display().to_string(),
    }
}

/// The scale of a similarity transform (rotation, uniform scale, translation), else None.
pub fn uniform_scale(m: DMat4) -> Option<f64> {
    let axes = [m.x_axis, m.y_axis, m.z_axis].map(|a: DVec4| a.truncate());
    let s = axes[0].length();
    let even = axes.iter().all(|a| (a.length() - s).abs() <= 1e-6 * s);
    let orthogonal =
        axes[0].dot(axes[1]).abs() + axes[1].dot(axes[2]).abs() + axes[0].dot(axes[2]).abs() <= 1e-6 * s * s;
    (s > 0.0 && even && orthogonal).then_some(s)
}
