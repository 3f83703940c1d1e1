//! Mitsuba 3's participating media as `[[media]]` entries: `homogeneous` (sigma_t, albedo, scale)
//! and `heterogeneous` whose sigma_t is a `gridvolume` (a `.vol` file placed by its `to_world`,
//! which maps the unit cube onto the grid's box), each with an `isotropic` or `hg` phase function.

use super::super::format::{Array, MediumFile, MediumKind, PhaseKind};
use super::mitsuba_xml::{Object, Resolver};
use super::scene_parts::{f32x3, relative_to};
use anyhow::Result;
use glam::{DMat4, DVec3};
use std::path::Path;

/// The `[[media]]` entry named `name` of Mitsuba medium `m`; `base` is the folder file names are
/// written relative to.
pub fn medium_file(m: &Object, name: String, resolver: &Resolver, base: &Path) -> Result<MediumFile> {
    let (phase, g) = match m.child("phase")? {
        None => (PhaseKind::Isotropic, None),
        Some(p) => {
            let phase = match p.plugin.as_str() {
                "isotropic" => (PhaseKind::Isotropic, None),
                // Mitsuba's default g is 0.8.
                "hg" => (PhaseKind::Hg, Some(p.float("g", 0.8)? as f32)),
                _ => return Err(p.error("only isotropic and hg phase functions are supported")),
            };
            p.check_all_used()?;
            phase
        }
    };
    let albedo = m.color("albedo", &mut |_| {})?.unwrap_or(DVec3::splat(0.75));
    let scale = m.float("scale", 1.0)? as f32;
    // Emission of media is not modelled; Mitsuba's own default samples none.
    if m.boolean("sample_emitted", true)? && m.color("radiance", &mut |_| {})?.is_some() {
        return Err(m.error("emitting media (radiance) are not supported"));
    }
    let file = match m.plugin.as_str() {
        "homogeneous" => {
            let sigma_t = m.color("sigma_t", &mut |_| {})?.unwrap_or(DVec3::ONE);
            MediumFile {
                name,
                kind: MediumKind::Homogeneous,
                density: None,
                bounds: None,
                sigma_a: None,
                sigma_s: None,
                sigma_t: Some(f32x3(sigma_t)),
                albedo: Some(f32x3(albedo)),
                scale,
                phase,
                g,
            }
        }
        "heterogeneous" => {
            let grids: Vec<_> = m.children_tagged("volume")?;
            let [grid] = grids.as_slice() else {
                return Err(m.error("a heterogeneous medium needs one <volume type=\"gridvolume\" name=\"sigma_t\"> (and a constant albedo)"));
            };
            if grid.plugin != "gridvolume" {
                return Err(grid.error("only gridvolume volumes are supported"));
            }
            let Some(filename) = grid.string("filename")?.map(str::to_owned) else {
                return Err(grid.error("needs a filename"));
            };
            let to_world = grid.transform("to_world")?.unwrap_or(DMat4::IDENTITY);
            let (lo, hi) = (to_world.transform_point3(DVec3::ZERO), to_world.transform_point3(DVec3::ONE));
            // An axis-aligned box only: the unit cube's other corners must land on its corners.
            let axis_aligned = (0..8).all(|k| {
                let corner = DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64);
                let p = to_world.transform_point3(corner);
                let expected = DVec3::select(corner.cmpgt(DVec3::splat(0.5)), hi, lo);
                (p - expected).length() <= 1e-9 * (1.0 + p.length())
            });
            if !axis_aligned || lo.cmpge(hi).any() {
                return Err(grid.error("its to_world must scale and translate only (an axis-aligned box, min < max)"));
            }
            // Mitsuba's gridvolume options caustica reads as its own defaults.
            if grid.string("filter_type")?.is_some_and(|f| f != "trilinear") {
                return Err(grid.error("only filter_type trilinear is supported"));
            }
            grid.check_all_used()?;
            let path = resolver.resolve(&filename, Path::new(&*grid.at.file));
            MediumFile {
                name,
                kind: MediumKind::Heterogeneous,
                density: Some(relative_to(&path, base)),
                bounds: Some(Array([f32x3(lo), f32x3(hi)])),
                sigma_a: None,
                sigma_s: None,
                sigma_t: Some(Array([1.0; 3])),
                albedo: Some(f32x3(albedo)),
                scale,
                phase,
                g,
            }
        }
        _ => return Err(m.error("only homogeneous and heterogeneous media are supported")),
    };
    m.check_all_used()?;
    Ok(file)
}
