//! A pbrt-v4 [`Model`] onto caustica's scene file: camera, film, sampler, integrator, filter,
//! shapes (with their instances), lights and, through `materials.rs`, materials. Each directive
//! reads the parameters it understands with pbrt's defaults and refuses the rest
//! (`Directive::check_all_used`). docs/importers.md ("pbrt-v4") documents each mapping.
//!
//! Handedness: pbrt's camera puts camera +x on the image's right with +y up and +z forward, so a
//! `LookAt` shows the world the other way round from caustica's right-handed camera (whose image
//! right is forward x up). caustica therefore reads pbrt's world through a mirror across x = 0
//! ([`Mapper::world`]): the mirrored world seen by caustica's camera is pbrt's image exactly. A
//! camera transformation that mirrors already (`Scale -1 1 1`, common in exported scenes) needs
//! no mirror. The mirror turns every winding, which the shapes undo, so fronts stay where pbrt
//! has them.

use super::super::super::material_maps::needs_mesh;
use super::super::scene_parts::{f32x3, relative_to, uniform_scale, unique_name, UNBOUNDED_DEPTH};
use super::super::{spectrum, transform, Location, Notes, MAX_SHAPES};
use super::params::Directive;
use super::parser::{MaterialRef, Model, ShapeUse};
use super::texture_value::TextureValue;
use crate::image::RgbImage;
use crate::input_file::InputFiles;
use crate::scene::equal_area_map;
use crate::scene::format::{
    Array, CameraFile, DirectionalLightFile, Encoding, EnvironmentFile, FilmFile, Filter, ImageTextureFile, InlineMesh,
    IntegratorFile, LightFile, LightSelection, MaterialFile, MeshFile, PointLightFile, QuadFile, Sampler, SceneFile,
    SphereFile, SpotLightFile, TriangleFile,
};
use anyhow::{bail, Result};
use glam::{DMat4, DVec2, DVec3, Vec3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// The most bytes the scene file's shape entries may take with their material names, beside
/// their number (MAX_SHAPES).
const MAX_SHAPE_BYTES: usize = 1 << 30;

/// A mesh written in the scene: vertices, polygon corners (indices into them), normals and
/// texture coordinates (pbrt's, v up).
struct MeshArrays {
    positions: Vec<DVec3>,
    indices: Vec<usize>,
    normals: Option<Vec<DVec3>>,
    /// Read only where a texture needs them (an error then).
    uvs: Result<Option<Vec<[f64; 2]>>>,
}

pub struct Mapper<'a> {
    pub(super) model: &'a Model,
    notes: &'a mut Notes,
    files: &'a InputFiles,
    /// The main scene's folder: pbrt resolves every relative file name against it.
    pub(super) base: &'a Path,
    out: SceneFile,
    /// caustica's world from pbrt's: the mirror across x = 0, or the identity (module docs).
    world: DMat4,
    /// (material, area light) by address, to the caustica material made of them (None: an
    /// `interface` without emission, which is no surface).
    material_names: HashMap<(usize, usize), Option<String>>,
    /// Materials of area lights given by their `power`, emitting per unit of `scale`: the power
    /// and whether both sides emit. pbrt-v4 gives each shape (each triangle of a mesh) that
    /// power, so each area has its own material ([`Mapper::emitter_of_area`]).
    powered: HashMap<String, (f64, bool)>,
    /// (powered material, area's bits) to its material of that area.
    powered_names: HashMap<(String, u64), String>,
    /// Shapes written so far, and an estimate of their bytes (for MAX_SHAPES, MAX_SHAPE_BYTES).
    shapes: usize,
    shape_bytes: usize,
    /// Textures evaluated, by (value type, name): a texture referred to many times (a `mix` of
    /// one texture twice, chained) is evaluated once, not once per reference.
    pub(super) textures_evaluated: HashMap<(String, String), TextureValue>,
}

/// The scene file of `model`, read from `scene` (for messages).
pub fn map(model: &Model, files: &InputFiles, base: &Path, scene: &Path, notes: &mut Notes) -> Result<SceneFile> {
    let camera = CameraFile {
        position: Array([0.0; 3]),
        look_at: Array([0.0, 0.0, -1.0]),
        up: Array([0.0, 1.0, 0.0]),
        fov: 90.0,
        aperture: 0.0,
        focus_distance: None,
        medium: None,
    };
    let out = SceneFile::empty(camera, FilmFile::default(), IntegratorFile::default());
    let mut mapper = Mapper {
        model,
        notes,
        files,
        base,
        out,
        world: DMat4::IDENTITY,
        material_names: HashMap::new(),
        powered: HashMap::new(),
        powered_names: HashMap::new(),
        shapes: 0,
        shape_bytes: 0,
        textures_evaluated: HashMap::new(),
    };
    let start = Location { file: Rc::from(scene.display().to_string().as_str()), line: 1 };
    let absent = |directive: &'static str, kind: &str| Directive {
        directive,
        kind: kind.to_owned(),
        at: start.clone(),
        params: vec![],
    };
    let film = mapper.film(model.film.as_ref().unwrap_or(&absent("Film", "rgb")))?;
    let (camera_directive, camera_from_world) = match &model.camera {
        Some(c) => (&c.camera, c.camera_from_world),
        None => (&absent("Camera", "perspective"), DMat4::IDENTITY),
    };
    mapper.out.camera = mapper.camera(camera_directive, camera_from_world, film.width as f64 / film.height as f64)?;
    mapper.out.film = film;
    mapper.out.film.filter = mapper.filter(model.filter.as_ref().unwrap_or(&absent("PixelFilter", "gaussian")))?;
    let (spp, sampler) = mapper.sampler(model.sampler.as_ref().unwrap_or(&absent("Sampler", "zsobol")))?;
    mapper.out.film.spp = spp;
    mapper.out.integrator = mapper.integrator(model.integrator.as_ref().unwrap_or(&absent("Integrator", "volpath")))?;
    mapper.out.integrator.sampler = sampler;
    for s in &model.shapes {
        mapper.shape(s, DMat4::IDENTITY)?;
    }
    for instance in &model.instances {
        let Some((shapes, _)) = model.objects.get(&instance.name) else {
            bail!("{}: ObjectInstance \"{}\": no object of that name (ObjectBegin)", instance.at, instance.name)
        };
        for s in shapes {
            mapper.shape(s, instance.transform)?;
        }
    }
    for (light, transform) in &model.lights {
        mapper.light(light, *transform)?;
    }
    // A powered area light's own material only stands for its copies of each area.
    for name in mapper.powered.keys() {
        mapper.out.materials.remove(name);
    }
    Ok(mapper.out)
}

impl Mapper<'_> {
    pub(super) fn warn(&mut self, kind: &'static str, message: impl FnOnce() -> String) {
        self.notes.warn_once(kind, message);
    }

    /// A file the scene names: relative to the scene's folder, or absolute (which `join` keeps).
    pub(super) fn scene_file(&self, name: &str) -> PathBuf {
        self.base.join(name)
    }

    /// The camera, and with it the mirror caustica reads pbrt's world through.
    fn camera(&mut self, d: &Directive, camera_from_world: DMat4, aspect: f64) -> Result<CameraFile> {
        if d.kind != "perspective" {
            return Err(d.error("only the perspective camera is supported"));
        }
        let world_from_camera = camera_from_world.inverse();
        let eye = world_from_camera.transform_point3(DVec3::ZERO);
        let [right, up, forward] = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| world_from_camera.transform_vector3(a));
        let size = forward.length();
        let rigid = [right, up].iter().all(|a| (a.length() - size).abs() <= 1e-6 * size)
            && (right.dot(up).abs() + up.dot(forward).abs() + right.dot(forward).abs()) <= 1e-6 * size * size
            && size > 0.0;
        if !rigid {
            return Err(d.error("the camera transformation shears or scales unevenly; caustica's camera cannot follow"));
        }
        // pbrt's image right is camera +x; caustica's is forward x up. In the usual left-handed
        // frame (a LookAt) forward x up is -right, and a mirror of the world turns it round.
        self.world = if forward.cross(up).dot(right) < 0.0 {
            DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0))
        } else {
            DMat4::IDENTITY
        };
        let (forward, up) = (self.world.transform_vector3(forward / size), self.world.transform_vector3(up / size));
        let position = self.world.transform_point3(eye);

        let fov = d.float_or("fov", 90.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(d.error(format!("fov must be in (0, 180) degrees, got {fov}")));
        }
        if let Some(frame) = d.float("frameaspectratio")? {
            if (frame - aspect).abs() > 1e-6 * aspect {
                return Err(d.error(format!("a frameaspectratio ({frame}) other than the film's ({aspect}) stretches the image, which caustica's camera cannot")));
            }
        }
        // pbrt's screen window spans [-1, 1] along the shorter image axis, which fov covers.
        let default_half_height = if aspect >= 1.0 { 1.0 } else { 1.0 / aspect };
        let half_height = match d.floats("screenwindow")? {
            None => default_half_height,
            Some(&[x0, x1, y0, y1]) if x0 == -x1 && y0 == -y1 && y1 > 0.0 && (x1 / y1 - aspect).abs() <= 1e-6 * aspect => y1,
            Some(_) => return Err(d.error("only a screenwindow centred on the view and of the film's aspect ratio is supported (caustica's camera is centred)")),
        };
        let vertical = 2.0 * ((0.5 * fov.to_radians()).tan() * half_height).atan().to_degrees();
        if vertical >= 180.0 {
            return Err(d.error("the screenwindow widens the view to 180 degrees or more"));
        }
        let aperture = d.float_or("lensradius", 0.0)?;
        let focus = d.float_or("focaldistance", 1e6)?;
        if aperture < 0.0 || focus <= 0.0 {
            return Err(d.error(format!("lensradius must be >= 0 and focaldistance > 0, got {aperture} and {focus}")));
        }
        // The shutter only matters to animated transformations, which are refused.
        d.float("shutteropen")?;
        d.float("shutterclose")?;
        d.check_all_used()?;
        Ok(CameraFile {
            position: f32x3(position),
            look_at: f32x3(position + forward),
            up: f32x3(up),
            fov: vertical as f32,
            aperture: aperture as f32,
            focus_distance: (aperture > 0.0).then_some(focus as f32),
            medium: None,
        })
    }

    fn film(&mut self, d: &Directive) -> Result<FilmFile> {
        if d.kind != "rgb" {
            return Err(d.error("only the rgb film is supported"));
        }
        let size = |name: &str, default: i64| -> Result<u32> {
            let v = d.integer(name)?.unwrap_or(default);
            u32::try_from(v)
                .ok()
                .filter(|v| (1..=16384).contains(v))
                .ok_or_else(|| d.error(format!("{name} must be in [1, 16384], got {v}")))
        };
        let (width, height) = (size("xresolution", 1280)?, size("yresolution", 720)?);
        // Where and how pbrt writes its image: caustica writes what -o says.
        d.string("filename")?;
        d.boolean("savefp16", true)?;
        // The film's physical size, which only pbrt's realistic camera uses.
        d.float("diagonal")?;
        // The sensor's response: only pbrt's default (the CIE 1931 observer, ISO 100, a unit
        // exposure, no white balance) leaves the colours as caustica renders them.
        if d.string("sensor")?.is_some_and(|s| s != "cie1931")
            || d.float_or("iso", 100.0)? != 100.0
            || d.float_or("exposuretime", 1.0)? != 1.0
            || d.float_or("whitebalance", 0.0)? != 0.0
        {
            return Err(
                d.error("only the default sensor (cie1931, iso 100, exposuretime 1, whitebalance 0) is supported")
            );
        }
        if let Some(clamp) = d.float("maxcomponentvalue")? {
            // pbrt scales a sample down so its largest component is at most this, as caustica's
            // integrator.clamp does.
            if clamp.is_nan() || clamp <= 0.0 {
                return Err(d.error(format!("maxcomponentvalue must be > 0, got {clamp}")));
            }
            self.out.integrator.clamp = Some(clamp as f32);
        }
        d.check_all_used()?;
        Ok(FilmFile { width, height, spp: 16, filter: Filter::Gaussian })
    }

    fn filter(&mut self, d: &Directive) -> Result<Filter> {
        let radii = |default: f64| -> Result<(f64, f64)> {
            Ok((d.float_or("xradius", default)?, d.float_or("yradius", default)?))
        };
        let filter = match d.kind.as_str() {
            "box" if radii(0.5)? == (0.5, 0.5) => Filter::Box,
            "triangle" if radii(2.0)? == (1.0, 1.0) => Filter::Tent,
            "gaussian" if radii(1.5)? == (1.5, 1.5) && d.float_or("sigma", 0.5)? == 0.5 => {
                self.warn("filter", || format!("{}: {}: pbrt's Gaussian (sigma 0.5, cut at 1.5 pixels and lowered to 0 there) becomes caustica's uncut Gaussian of sigma 0.5", d.at, d.describe()));
                Filter::Gaussian
            }
            "box" | "triangle" | "gaussian" => return Err(d.error(
                "only box of radius 0.5, triangle of radius 1 and gaussian of radius 1.5 and sigma 0.5 are supported",
            )),
            _ => return Err(d.error("this filter is not supported (box, triangle, gaussian)")),
        };
        d.check_all_used()?;
        Ok(filter)
    }

    fn sampler(&mut self, d: &Directive) -> Result<(u32, Sampler)> {
        let (spp, sampler) = match d.kind.as_str() {
            "independent" => (d.integer("pixelsamples")?.unwrap_or(16), Sampler::Independent),
            "stratified" => {
                d.boolean("jitter", true)?;
                (
                    d.integer("xsamples")?.unwrap_or(4).saturating_mul(d.integer("ysamples")?.unwrap_or(4)),
                    Sampler::Sobol,
                )
            }
            "zsobol" | "sobol" | "paddedsobol" | "halton" | "pmj02bn" => {
                d.string("randomization")?;
                (d.integer("pixelsamples")?.unwrap_or(16), Sampler::Sobol)
            }
            _ => return Err(d.error("this sampler is not supported")),
        };
        if sampler == Sampler::Sobol {
            self.warn("sampler", || format!("{}: {}: pbrt's samplers other than independent become caustica's Owen-scrambled Sobol (the same image, other noise)", d.at, d.describe()));
        }
        if d.integer("seed")?.is_some() {
            self.warn("seed", || format!("{}: the sampler's seed is ignored: caustica takes it from --seed", d.at));
        }
        d.check_all_used()?;
        let spp = u32::try_from(spp)
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| d.error(format!("the sample count must be at least 1, got {spp}")))?;
        Ok((spp, sampler))
    }

    /// pbrt's `maxdepth` counts bounces: 0 shows the emitters seen directly, 1 adds direct
    /// light. caustica's `max_bounces` counts path segments, the camera ray included, so it is
    /// maxdepth + 1; a negative maxdepth never ends a path (caustica's cap). pbrt first plays
    /// roulette after the first bounce, caustica's `rr_start` 1 (the noise differs, not the
    /// expected image).
    fn integrator(&mut self, d: &Directive) -> Result<IntegratorFile> {
        if !matches!(d.kind.as_str(), "path" | "volpath") {
            return Err(d.error("only the path and volpath integrators are supported"));
        }
        let depth = d.integer("maxdepth")?.unwrap_or(5);
        let max_bounces =
            if depth < 0 { UNBOUNDED_DEPTH } else { u32::try_from(depth + 1).unwrap_or(u32::MAX).min(UNBOUNDED_DEPTH) };
        let light_selection = match d.string("lightsampler")?.unwrap_or("bvh") {
            "bvh" => LightSelection::Bvh,
            "power" => LightSelection::Power,
            "uniform" => LightSelection::Uniform,
            other => return Err(d.error(format!("lightsampler \"{other}\" is not supported (bvh, power, uniform)"))),
        };
        if d.boolean("regularize", false)? {
            return Err(d.error("regularize is not supported"));
        }
        d.check_all_used()?;
        Ok(IntegratorFile {
            max_bounces,
            rr_start: 1,
            light_selection,
            clamp: self.out.integrator.clamp,
            ..IntegratorFile::default()
        })
    }

    /// The caustica material of a shape's material and area light, made once per pair; None
    /// for an `interface` that emits nothing.
    fn shape_material(&mut self, s: &ShapeUse) -> Result<Option<String>> {
        let short = |at: &Location| {
            format!(
                "{}:{}",
                Path::new(&*at.file).file_name().map_or(String::new(), |f| f.to_string_lossy().into_owned()),
                at.line
            )
        };
        let (def, label) = match &s.material {
            MaterialRef::Default => (None, "default diffuse".to_owned()),
            MaterialRef::Anonymous(def) => (Some(def.clone()), format!("{} at {}", def.ty, short(&def.directive.at))),
            MaterialRef::Named(name, at) => match self.model.named_materials.get(name) {
                Some(def) => (Some(def.clone()), name.clone()),
                None => bail!("{at}: NamedMaterial \"{name}\": no material of that name (MakeNamedMaterial)"),
            },
        };
        let key = (
            def.as_ref().map_or(0, |d| Rc::as_ptr(d) as usize),
            s.area_light.as_ref().map_or(0, |l| Rc::as_ptr(l) as usize),
        );
        if let Some(name) = self.material_names.get(&key) {
            return Ok(name.clone());
        }
        let material = match &def {
            None => Some(MaterialFile { albedo: Array([0.5; 3]), ..MaterialFile::default() }),
            Some(def) => self.material(def)?,
        };
        let mut material = match (material, &s.area_light) {
            (Some(m), _) => m,
            (None, None) => {
                self.material_names.insert(key, None);
                return Ok(None);
            }
            // An emitting interface: light passes through unchanged (index 1), as through no surface.
            (None, Some(_)) => MaterialFile { transparency: 1.0, ior: 1.0, ..MaterialFile::default() },
        };
        let mut name = label;
        if let Some(light) = &s.area_light {
            if light.kind != "diffuse" {
                return Err(light.error("only the diffuse area light is supported"));
            }
            material.emission = f32x3(self.light_color(light, "L")? * self.light_scale(light)?);
            material.two_sided = light.boolean("twosided", false)?;
            let power = Self::light_target(light, "power")?;
            light.check_all_used()?;
            name = format!("{name} + area light at {}", short(&light.at));
            if let Some(power) = power {
                let name = unique_name(&self.out.materials, name);
                self.powered.insert(name.clone(), (power, material.two_sided));
                self.out.materials.insert(name.clone(), material);
                self.material_names.insert(key, Some(name.clone()));
                return Ok(Some(name));
            }
        }
        let name = unique_name(&self.out.materials, name);
        self.out.materials.insert(name.clone(), material);
        self.material_names.insert(key, Some(name.clone()));
        Ok(Some(name))
    }

    /// A shape placed by `instance` (an ObjectInstance's transformation) after its own.
    fn shape(&mut self, s: &ShapeUse, instance: DMat4) -> Result<()> {
        let d = &*s.shape;
        let Some(material) = self.shape_material(s)? else {
            // An interface bounds a participating medium, which caustica does not render.
            self.warn("interface", || {
                format!(
                    "{}: {}: shapes with the interface material are left out (they only bound media)",
                    d.at,
                    d.describe()
                )
            });
            return Ok(());
        };
        let to_world = instance * s.transform;
        let m = self.world * to_world;
        let material = self.with_alpha(d, material)?;
        // Textures need texture coordinates, which caustica's meshes have and its spheres, quads
        // and triangles have not, and opacity is tested on mesh triangles; an emitting mesh is
        // written as triangles.
        let textured = needs_mesh(&self.out.materials[&material]);
        if let Some(what) = textured.filter(|_| {
            !matches!(d.kind.as_str(), "plymesh" | "trianglemesh")
                || self.out.materials[&material].emission != Array([0.0; 3])
        }) {
            return Err(d.error(format!("a material with {what} is supported on a plymesh or trianglemesh that does not emit only (caustica's spheres, quads and triangles have no texture coordinates or alpha tests)")));
        }
        let textured = textured.is_some();
        match d.kind.as_str() {
            "sphere" => self.sphere(s, to_world, m, &material)?,
            "trianglemesh" if textured => self.textured_triangle_mesh(s, m, &material)?,
            "trianglemesh" => {
                let MeshArrays { positions, indices, normals, .. } = self.mesh_arrays(d, 3)?;
                for t in indices.chunks_exact(3) {
                    let v = [positions[t[0]], positions[t[1]], positions[t[2]]];
                    let reversed = match &normals {
                        Some(n) => (v[1] - v[0]).cross(v[2] - v[0]).dot(n[t[0]] + n[t[1]] + n[t[2]]) < 0.0,
                        None => s.reverse_orientation,
                    };
                    self.lone_triangle(d, m, v, reversed, &material)?;
                }
            }
            "bilinearmesh" => {
                let MeshArrays { positions, indices, normals, .. } = self.mesh_arrays(d, 4)?;
                for q in indices.chunks_exact(4) {
                    let [p00, p10, p01, p11] = [0, 1, 2, 3].map(|k| positions[q[k]]);
                    let reversed = match &normals {
                        Some(n) => (p10 - p00).cross(p01 - p00).dot(n[q[0]] + n[q[1]] + n[q[2]] + n[q[3]]) < 0.0,
                        None => s.reverse_orientation,
                    };
                    self.bilinear_patch(d, m, [p00, p10, p01, p11], reversed, &material)?;
                }
            }
            "plymesh" => {
                let Some(name) = d.string("filename")?.map(str::to_owned) else {
                    return Err(d.error("needs a filename"));
                };
                let path = self.scene_file(&name);
                if self.out.materials[&material].emission != Array([0.0; 3]) {
                    self.emitting_ply(d, &path, m, s.reverse_orientation, &material)?;
                } else {
                    let placement = transform::placement(m).map_err(|e| d.error(e))?;
                    let file = relative_to(&path, self.base);
                    self.count_shape(d, &material)?;
                    self.out.meshes.push(MeshFile {
                        file,
                        material: Some(material),
                        shape_index: None,
                        flip_normals: false,
                        face_normals: false,
                        translate: placement.translate,
                        scale: placement.scale,
                        rotate: placement.rotate,
                        instances: vec![],
                    });
                }
            }
            _ => return Err(d.error("this shape is not supported (sphere, trianglemesh, bilinearmesh, plymesh)")),
        }
        d.check_all_used()
    }

    /// `material` as the shape `d` wears it: with the opacity of its `alpha` (pbrt's stochastic
    /// cut-out: a ray meets the surface with probability alpha, caustica's `opacity`), a constant
    /// or a float `imagemap` (whose luminance caustica reads, where pbrt averages the channels:
    /// the same for the grey images cut-outs are). A material of its own per shape with alpha.
    fn with_alpha(&mut self, d: &Directive, material: String) -> Result<String> {
        let Some(p) = d.param("alpha") else { return Ok(material) };
        let model = self.model;
        let image = match (p.ty.as_str(), p.strings()) {
            ("texture", [name]) => {
                model.textures.get(&("float".to_owned(), name.clone())).filter(|t| t.class.kind == "imagemap")
            }
            _ => None,
        };
        let (opacity, texture) = match image {
            Some(t) => {
                let (texture, factor) = self.imagemap_file(&t.class)?;
                t.class.check_all_used()?;
                let file = texture.file.expect("an imagemap has a file");
                (factor.x, Some(ImageTextureFile { file, to_uv: texture.to_uv, encoding: Some(Encoding::Srgb) }))
            }
            _ => (self.scalar_param(p)?, None),
        };
        if opacity >= 1.0 && texture.is_none() {
            return Ok(material);
        }
        if !(0.0..=1.0).contains(&opacity) {
            return Err(p.error(format!("alpha must be in [0, 1], got {opacity}")));
        }
        let mut m = self.out.materials[&material].clone();
        m.opacity = Some(opacity as f32);
        m.opacity_texture = texture;
        let name = unique_name(&self.out.materials, format!("{material} + alpha at {}", d.at));
        self.out.materials.insert(name.clone(), m);
        Ok(name)
    }

    fn sphere(&mut self, s: &ShapeUse, to_world: DMat4, m: DMat4, material: &str) -> Result<()> {
        let d = &*s.shape;
        let radius = d.float_or("radius", 1.0)?;
        if radius.is_nan() || radius <= 0.0 {
            return Err(d.error(format!("radius must be > 0, got {radius}")));
        }
        let partial = d.float_or("zmin", -radius)? > -radius
            || d.float_or("zmax", radius)? < radius
            || d.float_or("phimax", 360.0)? < 360.0;
        if partial {
            return Err(d.error("partial spheres (zmin, zmax, phimax) are not supported"));
        }
        let scale = uniform_scale(to_world)
            .ok_or_else(|| d.error("its transformation scales unevenly or shears; a sphere needs a uniform scale"))?;
        // caustica's spheres face outwards; pbrt's turn inside out under ReverseOrientation or a
        // mirroring transformation, which matters where they emit or refract.
        let m_file = &self.out.materials[material];
        let sided = m_file.emission != Array([0.0; 3]) || m_file.transparency > 0.0;
        if sided && s.reverse_orientation != (to_world.determinant() < 0.0) {
            return Err(d.error("a sphere turned inside out (ReverseOrientation or a mirroring transformation) that emits or refracts is not supported"));
        }
        // pbrt-v4's Sphere::Area is in the sphere's own space: its transformation's scale is left out.
        let material = self.emitter_of_area(material, 4.0 * PI * radius * radius);
        self.count_shape(d, &material)?;
        self.out.spheres.push(SphereFile {
            center: f32x3(m.transform_point3(DVec3::ZERO)),
            radius: (radius * scale) as f32,
            material,
        });
        Ok(())
    }

    /// A `trianglemesh` with a textured material: a mesh (its PLY text, `SceneFile::inline_meshes`)
    /// rather than triangles, to keep its texture coordinates, `uv` or pbrt's default (0, 0),
    /// (1, 0), (1, 1) at each triangle's corners. Each triangle gets corners of its own, fronts as
    /// [`Mapper::triangle`] gives them.
    fn textured_triangle_mesh(&mut self, s: &ShapeUse, m: DMat4, material: &str) -> Result<()> {
        use std::fmt::Write as _;
        let d = &*s.shape;
        let MeshArrays { positions, indices, normals, uvs } = self.mesh_arrays(d, 3)?;
        let uvs = uvs?;
        let mut vertices = String::new();
        let mut faces = String::new();
        for (k, t) in indices.chunks_exact(3).enumerate() {
            let v = [positions[t[0]], positions[t[1]], positions[t[2]]];
            let reversed = match &normals {
                Some(n) => (v[1] - v[0]).cross(v[2] - v[0]).dot(n[t[0]] + n[t[1]] + n[t[2]]) < 0.0,
                None => s.reverse_orientation,
            };
            let uv = match &uvs {
                Some(uv) => [uv[t[0]], uv[t[1]], uv[t[2]]],
                None => [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            };
            let mut corners = [0, 1, 2];
            if reversed != (m.determinant() < 0.0) {
                corners.swap(1, 2);
            }
            self.count_shape(d, material)?;
            for c in corners {
                let p = m.transform_point3(v[c]).as_vec3();
                let [u, w] = uv[c].map(|x| x as f32);
                writeln!(vertices, "{} {} {} {u} {w}", p.x, p.y, p.z).expect("writing to a String");
            }
            writeln!(faces, "3 {} {} {}", 3 * k, 3 * k + 1, 3 * k + 2).expect("writing to a String");
        }
        let count = indices.len() / 3;
        let ply = format!(
            "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face {count}\nproperty list uchar int vertex_indices\nend_header\n{vertices}{faces}",
            3 * count
        );
        self.out.inline_meshes.push(InlineMesh {
            name: format!("{}: {} (mesh {})", d.at, d.describe(), self.out.inline_meshes.len()),
            ply,
            material: material.to_owned(),
        });
        Ok(())
    }

    /// A mesh's vertices (`P`), its polygons of `corners` vertices (`indices`, which may be left
    /// out for a single polygon) and its normals (`N`); texture coordinates, tangents and face
    /// indices, which only textures use, are read and left.
    fn mesh_arrays(&mut self, d: &Directive, corners: usize) -> Result<MeshArrays> {
        let positions =
            d.triples("P", &["point3", "point"])?.ok_or_else(|| d.error("needs the vertices \"point3 P\""))?;
        let indices: Vec<usize> = match d.integers("indices")? {
            Some(i) => {
                if let Some(bad) = i.iter().find(|&&k| !(k >= 0.0 && k < positions.len() as f64)) {
                    return Err(d.error(format!("index {bad} is not one of the {} vertices", positions.len())));
                }
                i.iter().map(|&k| k as usize).collect()
            }
            None if positions.len() == corners => (0..corners).collect(),
            None => {
                return Err(
                    d.error(format!("needs \"integer indices\" (it has {} vertices, not {corners})", positions.len()))
                )
            }
        };
        if !indices.len().is_multiple_of(corners) {
            return Err(d.error(format!("the number of indices ({}) is not a multiple of {corners}", indices.len())));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(d.error("a vertex is not finite"));
        }
        let normals = d.triples("N", &["normal", "normal3"])?;
        if let Some(n) = &normals {
            if n.len() != positions.len() {
                return Err(d.error(format!("has {} normals for {} vertices", n.len(), positions.len())));
            }
            self.warn("normals", || format!("{}: {}: the vertex normals of meshes written in the scene are not kept (caustica's own triangles are flat); they decide the front side only", d.at, d.describe()));
        }
        let uvs = match d.param("uv") {
            None => Ok(None),
            Some(p) if p.ty == "point2" && p.numbers().len() == 2 * positions.len() => {
                Ok(Some(p.numbers().chunks_exact(2).map(|c| [c[0], c[1]]).collect()))
            }
            Some(p) => {
                Err(p.error(format!("{}: needs a point2 a vertex ({} numbers)", d.describe(), 2 * positions.len())))
            }
        };
        // Tangents and face indices, which only textures' filtering and Ptex use.
        for name in ["S", "faceIndices"] {
            d.param(name);
        }
        Ok(MeshArrays { positions, indices, normals, uvs })
    }

    /// Counts one more shape entry of `material` against the caps.
    fn count_shape(&mut self, d: &Directive, material: &str) -> Result<()> {
        self.shapes += 1;
        // The entry (at most 13 numbers) and its material name, held once per entry.
        self.shape_bytes += 64 + material.len();
        if self.shapes > MAX_SHAPES || self.shape_bytes > MAX_SHAPE_BYTES {
            return Err(d.error(format!("the scene becomes more than {MAX_SHAPES} shapes (or {} MiB of them), counting each triangle written in the scene and each instance's copy; store large meshes as PLY files", MAX_SHAPE_BYTES >> 20)));
        }
        Ok(())
    }

    /// A triangle with pbrt's front: its winding, turned when `reversed`, carried into caustica's
    /// world by `m`, whose mirror turns the winding once more.
    fn triangle(&mut self, d: &Directive, m: DMat4, v: [DVec3; 3], reversed: bool, material: &str) -> Result<()> {
        let turn = reversed != (m.determinant() < 0.0);
        let w = v.map(|p| m.transform_point3(p).as_vec3());
        let w = if turn { [w[0], w[2], w[1]] } else { w };
        // As caustica checks its triangles: one without area cannot be lit or hit.
        if (w[1] - w[0]).cross(w[2] - w[0]).length() == 0.0 {
            self.warn("degenerate", || format!("{}: {}: triangles without area are left out", d.at, d.describe()));
            return Ok(());
        }
        self.count_shape(d, material)?;
        self.out.triangles.push(TriangleFile {
            vertices: Array(w.map(|p: Vec3| Array(p.to_array()))),
            material: material.to_owned(),
        });
        Ok(())
    }

    /// A triangle of its own, emitting (when its area light gives a power) by its own area.
    fn lone_triangle(&mut self, d: &Directive, m: DMat4, v: [DVec3; 3], reversed: bool, material: &str) -> Result<()> {
        let w = v.map(|p| m.transform_point3(p));
        let material = self.emitter_of_area(material, 0.5 * (w[1] - w[0]).cross(w[2] - w[0]).length());
        self.triangle(d, m, v, reversed, &material)
    }

    /// A bilinear patch (p00, p10, p01, p11), front (p10 - p00) x (p01 - p00): a quad when it
    /// is a parallelogram, else two triangles (exact when it is planar, warned when not).
    fn bilinear_patch(&mut self, d: &Directive, m: DMat4, p: [DVec3; 4], reversed: bool, material: &str) -> Result<()> {
        let [p00, p10, p01, p11] = p;
        let (u, v) = (p10 - p00, p01 - p00);
        let extent = u.length().max(v.length());
        if (p11 - (p10 + v)).length() <= 1e-6 * extent {
            let turn = reversed != (m.determinant() < 0.0);
            let (u, v) = (m.transform_vector3(u), m.transform_vector3(v));
            let (u, v) = if turn { (v, u) } else { (u, v) };
            if u.as_vec3().cross(v.as_vec3()).length() == 0.0 {
                self.warn("degenerate", || format!("{}: {}: patches without area are left out", d.at, d.describe()));
                return Ok(());
            }
            let material = self.emitter_of_area(material, u.cross(v).length());
            self.count_shape(d, &material)?;
            self.out.quads.push(QuadFile {
                origin: f32x3(m.transform_point3(p00)),
                edge_u: f32x3(u),
                edge_v: f32x3(v),
                material,
            });
            return Ok(());
        }
        let normal = u.cross(v);
        if (p11 - p00).dot(normal).abs() > 1e-6 * extent * normal.length() {
            if self.powered.contains_key(material) {
                return Err(d.error("an area light given by its power on a patch that is not planar is not supported (its area is pbrt's integral over the curved patch)"));
            }
            self.warn("bilinear", || {
                format!("{}: {}: patches that are not planar become two triangles each", d.at, d.describe())
            });
        }
        // A planar patch covers its quadrilateral, the two triangles' areas together.
        let w = [p00, p10, p01, p11].map(|p| m.transform_point3(p));
        let area = 0.5 * ((w[1] - w[0]).cross(w[3] - w[0]).length() + (w[3] - w[0]).cross(w[2] - w[0]).length());
        let material = self.emitter_of_area(material, area);
        self.triangle(d, m, [p00, p10, p11], reversed, &material)?;
        self.triangle(d, m, [p00, p11, p01], reversed, &material)
    }

    /// The material of a shape of `area` (in caustica's world, which the mirror leaves pbrt's
    /// render space's size) with `material`: itself, or, when its area light gives a power, a copy
    /// emitting pbrt-v4's L = power / (pi area), halved when both sides emit
    /// (DiffuseAreaLight::Create).
    fn emitter_of_area(&mut self, material: &str, area: f64) -> String {
        let Some(&(power, two_sided)) = self.powered.get(material) else { return material.to_owned() };
        if !(area > 0.0 && area.is_finite()) {
            // Left out as degenerate by the caller.
            return material.to_owned();
        }
        let key = (material.to_owned(), area.to_bits());
        if let Some(name) = self.powered_names.get(&key) {
            return name.clone();
        }
        let mut emitter = self.out.materials[material].clone();
        let unit = DVec3::from(emitter.emission.0.map(f64::from));
        emitter.emission = f32x3(unit * power / (PI * area * if two_sided { 2.0 } else { 1.0 }));
        let name = unique_name(&self.out.materials, format!("{material}, {power} over area {area}"));
        self.out.materials.insert(name.clone(), emitter);
        self.powered_names.insert(key, name.clone());
        name
    }

    /// An emitting PLY mesh, written out triangle by triangle: caustica's mesh files emit from
    /// the side their winding gives, so the front pbrt gives them (by their normals, or
    /// ReverseOrientation) is made their winding.
    fn emitting_ply(&mut self, d: &Directive, path: &Path, m: DMat4, reverse: bool, material: &str) -> Result<()> {
        let asset = crate::scene::load_asset_from(self.files, path).map_err(|e| d.error(e))?;
        for &(index, local) in &asset.instances {
            let mesh = &asset.meshes[index];
            let m = m * local.as_dmat4();
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|k| mesh.positions[k as usize].as_dvec3());
                let reversed = if mesh.normals.is_empty() {
                    reverse
                } else {
                    let n: Vec3 = t.iter().map(|&k| mesh.normals[k as usize]).sum();
                    (b - a).cross(c - a).dot(n.as_dvec3()) < 0.0
                };
                self.lone_triangle(d, m, [a, b, c], reversed, material)?;
            }
        }
        Ok(())
    }

    /// An emitter's spectrum as caustica's RGB: rgb as given; a black body or sampled spectrum
    /// at luminance 1, as pbrt-v4 normalises emission spectra before their `scale`.
    fn light_color(&mut self, d: &Directive, name: &str) -> Result<DVec3> {
        let Some(p) = d.param(name) else { return Ok(DVec3::ONE) };
        let c = match (p.ty.as_str(), p.numbers(), p.strings()) {
            ("rgb", &[r, g, b], _) => DVec3::new(r, g, b),
            ("blackbody", &[kelvin], _) if kelvin > 0.0 => spectrum::blackbody_rgb(kelvin),
            // pbrt's colour space illuminant: white in caustica's linear sRGB.
            ("spectrum", _, [named]) if named == "stdillum-D65" => DVec3::ONE,
            ("spectrum", _, []) => {
                let rgb = self.sampled_spectrum(p)?;
                let y = spectrum::luminance(rgb);
                if y.is_nan() || y <= 0.0 {
                    return Err(p.error("a spectrum without luminance"));
                }
                rgb / y
            }
            ("rgb" | "blackbody", ..) => {
                return Err(p.error("needs 3 numbers (rgb) or one temperature > 0 (blackbody)"))
            }
            ("spectrum", _, _) => {
                return Err(p.error("only the named spectrum stdillum-D65 is supported for an emitter"))
            }
            (ty, ..) => return Err(p.error(format!("an emitter's {name} cannot be given as {ty}"))),
        };
        if !(c.min_element() >= 0.0 && c.is_finite()) {
            return Err(p.error(format!("must be finite and not negative, got {c}")));
        }
        Ok(c)
    }

    fn light_scale(&mut self, d: &Directive) -> Result<f64> {
        let scale = d.float_or("scale", 1.0)?;
        if scale.is_nan() || scale < 0.0 {
            return Err(d.error(format!("scale must be >= 0, got {scale}")));
        }
        Ok(scale)
    }

    /// A light's `power` (pbrt-v4's `power` and `illuminance` read alike): Some(value) when given
    /// and > 0, as pbrt only then scales to it.
    fn light_target(d: &Directive, name: &str) -> Result<Option<f64>> {
        match d.float(name)? {
            Some(v) if !v.is_finite() => Err(d.error(format!("{name} must be finite, got {v}"))),
            v => Ok(v.filter(|&v| v > 0.0)),
        }
    }

    fn light(&mut self, d: &Directive, to_world: DMat4) -> Result<()> {
        let m = self.world * to_world;
        let from = |d: &Directive| -> Result<DVec3> { Ok(d.point("from")?.unwrap_or(DVec3::ZERO)) };
        let light = match d.kind.as_str() {
            "point" => {
                let mut intensity = self.light_color(d, "I")? * self.light_scale(d)?;
                // pbrt-v4's PointLight::Create: the unit-luminance spectrum (light_color) times
                // power / 4 pi, whatever the RGB's own brightness.
                if let Some(power) = Self::light_target(d, "power")? {
                    intensity *= power / (4.0 * PI);
                }
                Some(LightFile::Point(PointLightFile {
                    position: f32x3(m.transform_point3(from(d)?)),
                    intensity: f32x3(intensity),
                }))
            }
            "spot" => {
                let mut intensity = self.light_color(d, "I")? * self.light_scale(d)?;
                let from = from(d)?;
                let to = d.point("to")?.unwrap_or(DVec3::Z);
                let (cone, delta) = (d.float_or("coneangle", 30.0)?, d.float_or("conedeltaangle", 5.0)?);
                if !(cone > 0.0 && cone <= 180.0 && (0.0..=cone).contains(&delta)) || (to - from).length() == 0.0 {
                    return Err(d.error(format!("needs 0 < coneangle <= 180, 0 <= conedeltaangle <= coneangle and from != to, got {cone} and {delta}")));
                }
                // pbrt-v4's SpotLight::Create: power over the solid angle of the full cone plus
                // half that of the falloff ring.
                if let Some(power) = Self::light_target(d, "power")? {
                    let (cos_end, cos_start) = (cone.to_radians().cos(), (cone - delta).to_radians().cos());
                    intensity *= power / (2.0 * PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0));
                }
                self.warn("spot", || format!("{}: {}: pbrt's spot falls off smoothly in the cosine between coneangle - conedelta and coneangle; caustica's falls off linearly in the angle", d.at, d.describe()));
                Some(LightFile::Spot(SpotLightFile {
                    position: f32x3(m.transform_point3(from)),
                    look_at: f32x3(m.transform_point3(to)),
                    intensity: f32x3(intensity),
                    cone_angle: cone as f32,
                    falloff_start: (cone - delta) as f32,
                }))
            }
            "distant" => {
                let mut irradiance = self.light_color(d, "L")? * self.light_scale(d)?;
                // pbrt-v4's DistantLight::Create: illuminance on a patch facing the light.
                if let Some(illuminance) = Self::light_target(d, "illuminance")? {
                    irradiance *= illuminance;
                }
                let from = from(d)?;
                let to = d.point("to")?.unwrap_or(DVec3::Z);
                let direction = m.transform_vector3(to - from);
                if direction.length() == 0.0 {
                    return Err(d.error("from and to coincide, so the light has no direction"));
                }
                Some(LightFile::Directional(DirectionalLightFile {
                    direction: f32x3(direction),
                    irradiance: f32x3(irradiance),
                    angular_diameter: 0.0,
                }))
            }
            "infinite" => {
                if self.out.environment.is_some() {
                    return Err(d.error("a second infinite light: caustica has one environment"));
                }
                let environment = match d.string("filename")?.map(str::to_owned) {
                    None => {
                        let mut color = self.light_color(d, "L")? * self.light_scale(d)?;
                        // pbrt-v4: the illuminance of uniform radiance over a hemisphere is pi L.
                        if let Some(illuminance) = Self::light_target(d, "illuminance")? {
                            color *= illuminance / PI;
                        }
                        EnvironmentFile { color: Some(f32x3(color)), ..Default::default() }
                    }
                    Some(name) => {
                        if d.param("L").is_some() {
                            return Err(d.error("give L or filename, not both"));
                        }
                        // pbrt scales an image's RGB to radiance as it does a constant L's.
                        let mut scale = self.light_scale(d)?;
                        let path = self.scene_file(&name);
                        if let Some(illuminance) = Self::light_target(d, "illuminance")? {
                            let image = crate::image::read_image_from(self.files, &path).map_err(|e| d.error(e))?;
                            if image.width != image.height {
                                return Err(d.error(format!(
                                    "\"{name}\": an equal-area octahedral map must be square, got {} x {}",
                                    image.width, image.height
                                )));
                            }
                            let own = upper_hemisphere_illuminance(&image);
                            if !(own > 0.0 && own.is_finite()) {
                                return Err(d.error(format!("\"{name}\": the map sends no light onto its upper hemisphere (+z), so no scale gives it an illuminance")));
                            }
                            scale *= illuminance / own;
                        }
                        // Where the map's axes point in caustica's world: the light's rotation,
                        // through the mirror.
                        let axes = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| m.transform_vector3(a));
                        let size = axes[0].length();
                        let orthonormal = size > 0.0
                            && axes.iter().all(|a| (a.length() - size).abs() <= 1e-6 * size)
                            && (axes[0].dot(axes[1]).abs() + axes[1].dot(axes[2]).abs() + axes[0].dot(axes[2]).abs())
                                <= 1e-6 * size * size;
                        if !orthonormal {
                            return Err(d.error("an image infinite light's transformation must be a rotation (it shears or scales unevenly)"));
                        }
                        let axes = Array(axes.map(|a| f32x3(a / size)));
                        EnvironmentFile {
                            octahedral: Some(relative_to(&path, self.base)),
                            axes: Some(axes),
                            intensity: scale as f32,
                            ..Default::default()
                        }
                    }
                };
                self.out.environment = Some(environment);
                None
            }
            _ => return Err(d.error("this light is not supported (point, spot, distant, infinite)")),
        };
        d.check_all_used()?;
        if let Some(light) = light {
            self.out.lights.push(light);
        }
        Ok(())
    }
}

/// The illuminance the equal-area map `image` sends onto a patch facing its +z, computed as
/// pbrt-v4 does to scale a map to an `illuminance` (lights.cpp, the image `infinite` light): the
/// luminance times cos(theta) at each texel centre above the horizon, summed, times 2 pi / texels.
/// Each texel covers 4 pi / texels of solid angle, so this is half the map's illuminance, and the
/// map comes out twice as bright as the illuminance asks; following pbrt gives pbrt's image.
fn upper_hemisphere_illuminance(image: &RgbImage) -> f64 {
    let (w, h) = (image.width, image.height);
    let mut sum = 0.0;
    for y in 0..h {
        let v = (f64::from(y) + 0.5) / f64::from(h);
        for x in 0..w {
            let d = equal_area_map::square_to_sphere(DVec2::new((f64::from(x) + 0.5) / f64::from(w), v));
            if d.z > 0.0 {
                sum += spectrum::luminance(DVec3::from(image.get(x, y).map(f64::from))) * d.z;
            }
        }
    }
    sum * 2.0 * PI / (f64::from(w) * f64::from(h))
}
