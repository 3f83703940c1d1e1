//! Mitsuba 3 scenes onto caustica's scene file model: one function per kind of object (sensor,
//! film, sampler, integrator, shape, BSDF, emitter), each reading the parameters it understands
//! with Mitsuba's defaults and refusing the rest (`Object::check_all_used`). The mapping of each
//! parameter is documented in docs/importers.md ("Mitsuba 3").

use super::super::format::{
    AlbedoTextureFile, Array, CameraFile, DirectionalLightFile, Encoding, EnvironmentFile, FilmFile, Filter,
    ImageTextureFile, IntegratorFile, LightFile, MaterialFile, MaterialKind, MediumFile, MeshFile, Microfacet,
    PointLightFile, QuadFile, Sampler, SceneFile, SphereFile, SpotLightFile, TriangleFile, Triple,
};
use super::super::material_maps::needs_mesh;
use super::mitsuba_xml::{self, Object, Resolver};
use super::scene_parts::{f32x3, relative_to, uniform_scale, unique_name, UNBOUNDED_DEPTH};
use super::{transform, Location, Notes, MAX_SHAPES};
use crate::input_file::InputFiles;
use anyhow::{bail, Result};
use glam::{DMat3, DMat4, DVec3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Sides of the polygon a `disk` becomes.
const DISK_SEGMENTS: usize = 64;

/// Mitsuba's conductor presets that caustica has measured indices of (`optics::METALS`).
const NAMED_METALS: [(&str, &str); 4] = [("Au", "gold"), ("Ag", "silver"), ("Cu", "copper"), ("Al", "aluminium")];

/// Mitsuba's named indices of refraction (its `ior.h`).
const NAMED_IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The scene file of the Mitsuba scene at `path`, and the folder its relative paths are from.
pub fn import(
    files: &InputFiles,
    path: &Path,
    defines: &[(String, String)],
    notes: &mut Notes,
) -> Result<(SceneFile, PathBuf)> {
    let mut resolver = Resolver::new(path);
    let document = mitsuba_xml::read(files, path, defines, &mut resolver)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut mapper = Mapper {
        notes,
        resolver,
        base: base.clone(),
        scene_file: path.to_path_buf(),
        materials: BTreeMap::new(),
        material_names: HashMap::new(),
        open_adapters: vec![],
        file: None,
        media: vec![],
        medium_names: HashMap::new(),
        camera_medium: None,
    };
    let file = mapper.scene(&document.objects)?;
    Ok((file, base))
}

struct Mapper<'a> {
    notes: &'a mut Notes,
    resolver: Resolver,
    base: PathBuf,
    scene_file: PathBuf,
    materials: BTreeMap<String, MaterialFile>,
    /// (BSDF, area emitter) objects, by address, and the interior medium, to the material made
    /// of them.
    material_names: HashMap<(usize, usize, Option<String>), String>,
    /// The adapter BSDFs (twosided, mask, normalmap) whose nested BSDF is being read, outermost
    /// first, so that one containing itself through a `<ref>` is refused instead of recursing.
    open_adapters: Vec<*const Object>,
    file: Option<SceneFile>,
    /// Media mapped (mitsuba_media.rs), by object address to their `[[media]]` names.
    media: Vec<MediumFile>,
    medium_names: HashMap<usize, String>,
    /// The sensor's medium: what lies outside every shape's interior.
    camera_medium: Option<String>,
}

fn point(m: DMat4, p: DVec3) -> DVec3 {
    m.transform_point3(p)
}

fn vector(m: DMat4, v: DVec3) -> DVec3 {
    m.transform_vector3(v)
}

impl Mapper<'_> {
    fn scene(&mut self, objects: &[Rc<Object>]) -> Result<SceneFile> {
        let of = |tag: &str| objects.iter().filter(|o| o.tag == tag).cloned().collect::<Vec<_>>();
        let sensors = of("sensor");
        let sensor = match sensors.as_slice() {
            [s] => s.clone(),
            [] => bail!("{}: the scene has no <sensor> (caustica needs a camera)", self.scene_file.display()),
            [_, second, ..] => return Err(second.error("a second sensor: caustica renders one camera")),
        };
        let (camera, film, sampler) = self.sensor(&sensor)?;
        let mut integrator = self.integrator(&of("integrator"))?;
        integrator.sampler = sampler;
        self.file = Some(SceneFile::empty(camera, film, integrator));
        let mut placed = 0;
        for shape in of("shape") {
            placed += shapes_placed(&shape);
            if placed > MAX_SHAPES {
                return Err(shape.error(format!(
                    "the scene places more than {MAX_SHAPES} shapes, counting each shape of a shapegroup once per instance"
                )));
            }
        }
        for shape in of("shape") {
            match shape.plugin.as_str() {
                // A definition, placed by the instances that <ref> it.
                "shapegroup" => {}
                "instance" => self.instance(&shape)?,
                _ => self.shape(&shape, DMat4::IDENTITY)?,
            }
        }
        for emitter in of("emitter") {
            // Area emitters at the top level are definitions for shapes to <ref>.
            if emitter.plugin != "area" {
                self.emitter(&emitter)?;
            }
        }
        if let Some(o) = objects.iter().find(|o| matches!(o.tag.as_str(), "film" | "sampler" | "rfilter")) {
            return Err(o.error("belongs inside a <sensor>"));
        }
        let mut file = self.file.take().expect("set above");
        file.materials = std::mem::take(&mut self.materials);
        file.media = std::mem::take(&mut self.media);
        file.camera.medium = self.camera_medium.clone();
        Ok(file)
    }

    fn warn(&mut self, kind: &'static str, message: impl FnOnce() -> String) {
        self.notes.warn_once(kind, message);
    }

    /// A colour parameter; a sampled spectrum is reduced to RGB with a warning.
    fn color(&mut self, o: &Object, name: &str, default: f64) -> Result<DVec3> {
        let mut sampled_at: Option<Location> = None;
        let c = o.color(name, &mut |at| sampled_at = Some(at.clone()))?;
        self.warn_sampled(sampled_at);
        Ok(c.unwrap_or(DVec3::splat(default)))
    }

    fn warn_sampled(&mut self, sampled_at: Option<Location>) {
        if let Some(at) = sampled_at {
            self.warn("spectrum", || format!("{at}: spectra given as wavelengths are reduced to linear sRGB (CIE 1931 fit; reflectances under D65, as Mitsuba's RGB modes)"));
        }
    }

    /// A reflectance: a colour each channel of which lies in [0, 1] (errors name its line).
    fn reflectance(&mut self, o: &Object, name: &str, default: f64) -> Result<DVec3> {
        let mut sampled_at: Option<Location> = None;
        let c = o.reflectance_color(name, &mut |at| sampled_at = Some(at.clone()))?;
        self.warn_sampled(sampled_at);
        let c = c.unwrap_or(DVec3::splat(default));
        if !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
            return Err(o.error(format!("{name} must be in [0, 1] per channel (energy conservation), got {c}")));
        }
        Ok(c)
    }

    fn sensor(&mut self, s: &Object) -> Result<(CameraFile, FilmFile, Sampler)> {
        let thin_lens = match s.plugin.as_str() {
            "perspective" => false,
            "thinlens" => true,
            _ => return Err(s.error("only perspective and thinlens sensors are supported")),
        };
        let film = match s.child("film")? {
            Some(f) => self.film(&f)?,
            None => FilmFile { width: 768, height: 576, spp: 4, filter: Filter::Gaussian },
        };
        let (spp, sampler) = match s.child("sampler")? {
            Some(sampler) => self.sampler(&sampler)?,
            None => (4, Sampler::Independent),
        };
        let film = FilmFile { spp, ..film };
        let m = s.transform("to_world")?.unwrap_or(DMat4::IDENTITY);
        let position = point(m, DVec3::ZERO);
        let (forward, up, left) = (
            vector(m, DVec3::Z).normalize_or_zero(),
            vector(m, DVec3::Y).normalize_or_zero(),
            vector(m, DVec3::X).normalize_or_zero(),
        );
        // caustica's image right is forward x up; Mitsuba's is -x of the camera frame.
        if forward.cross(up).dot(-left) < 0.9999 {
            return Err(s.error("its to_world is not a rotation and translation (it mirrors, shears or collapses the view); caustica's camera cannot follow"));
        }
        let fov = self.vertical_fov(s, film.width as f64 / film.height as f64)?;
        for clip in ["near_clip", "far_clip"] {
            if s.float_if_given(clip)?.is_some() {
                self.warn("clip", || {
                    format!(
                        "{}: {}: near_clip and far_clip are ignored (caustica has no clipping planes)",
                        s.at,
                        s.describe()
                    )
                });
            }
        }
        if let Some(medium) = s.child("medium")? {
            self.camera_medium = Some(self.medium(&medium)?);
        }
        let focus_distance = s.float_if_given("focus_distance")?;
        let aperture = if thin_lens { s.float("aperture_radius", 1.0)? } else { 0.0 };
        if thin_lens && focus_distance.is_none() {
            return Err(s.error("a thinlens sensor needs focus_distance"));
        }
        s.check_all_used()?;
        let camera = CameraFile {
            position: f32x3(position),
            look_at: f32x3(position + forward),
            up: f32x3(up),
            fov: fov as f32,
            aperture: aperture as f32,
            focus_distance: focus_distance.map(|f| f as f32),
            medium: None,
        };
        Ok((camera, film, sampler))
    }

    /// caustica's vertical field of view from Mitsuba's `fov` along `fov_axis`, or its
    /// `focal_length` (on a 36 x 24 mm film's diagonal; default 50mm).
    fn vertical_fov(&mut self, s: &Object, aspect: f64) -> Result<f64> {
        let (fov, axis) = match (s.float_if_given("fov")?, s.string("focal_length")?) {
            (Some(_), Some(_)) => return Err(s.error("give fov or focal_length, not both")),
            (Some(fov), None) => (fov, s.string("fov_axis")?.unwrap_or("x").to_owned()),
            (None, focal) => {
                let focal = focal.unwrap_or("50mm");
                let mm: f64 = focal
                    .strip_suffix("mm")
                    .unwrap_or(focal)
                    .trim()
                    .parse()
                    .map_err(|_| s.error(format!("focal_length '{focal}' is not a length in mm")))?;
                if s.string("fov_axis")?.is_some() {
                    return Err(s.error("fov_axis goes with fov, not focal_length"));
                }
                (2.0 * (36f64.hypot(24.0) / (2.0 * mm)).atan().to_degrees(), "diagonal".to_owned())
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(s.error(format!("fov must be in (0, 180) degrees, got {fov}")));
        }
        let half = (0.5 * fov.to_radians()).tan();
        // tan(half vertical angle) from tan(half angle) along the axis, the film being aspect x 1.
        let vertical_half = match axis.as_str() {
            "x" => half / aspect,
            "y" => half,
            "diagonal" => half / aspect.hypot(1.0),
            "smaller" if aspect < 1.0 => half / aspect,
            "smaller" => half,
            "larger" if aspect > 1.0 => half / aspect,
            "larger" => half,
            other => return Err(s.error(format!("fov_axis '{other}' is not x, y, diagonal, smaller or larger"))),
        };
        Ok(2.0 * vertical_half.atan().to_degrees())
    }

    fn film(&mut self, f: &Object) -> Result<FilmFile> {
        if f.plugin != "hdrfilm" {
            return Err(f.error("only hdrfilm is supported"));
        }
        let size = |name: &str, default: i64| -> Result<u32> {
            let v = f.integer(name, default)?;
            u32::try_from(v)
                .ok()
                .filter(|v| (1..=16384).contains(v))
                .ok_or_else(|| f.error(format!("{name} must be in [1, 16384], got {v}")))
        };
        let (width, height) = (size("width", 768)?, size("height", 576)?);
        // What the file looks like, not what is in it: caustica writes what -o says.
        if let Some(format) = f.string("pixel_format")? {
            if !matches!(format, "rgb" | "rgba") {
                return Err(f.error(format!("pixel_format '{format}' is not supported (rgb, rgba)")));
            }
        }
        f.string("component_format")?;
        f.string("file_format")?;
        let filter = match f.child("rfilter")? {
            None => Filter::Gaussian,
            Some(r) => {
                let filter = match r.plugin.as_str() {
                    "box" => Filter::Box,
                    "tent" if r.float("radius", 1.0)? == 1.0 => Filter::Tent,
                    "gaussian" if r.float("stddev", 0.5)? == 0.5 => Filter::Gaussian,
                    "tent" | "gaussian" => {
                        return Err(
                            r.error("only the default radius (tent: 1) and stddev (gaussian: 0.5) are supported")
                        )
                    }
                    _ => return Err(r.error("only box, tent and gaussian filters are supported")),
                };
                r.check_all_used()?;
                filter
            }
        };
        f.check_all_used()?;
        Ok(FilmFile { width, height, spp: 4, filter })
    }

    fn sampler(&mut self, s: &Object) -> Result<(u32, Sampler)> {
        let sampler = match s.plugin.as_str() {
            "independent" => Sampler::Independent,
            "stratified" | "multijitter" | "orthogonal" | "ldsampler" => {
                self.warn("sampler", || format!("{}: {}: stratified samplers become caustica's Owen-scrambled Sobol (the same image, other noise)", s.at, s.describe()));
                Sampler::Sobol
            }
            _ => return Err(s.error("this sampler is not supported")),
        };
        let spp = s.integer("sample_count", 4)?;
        if s.integer("seed", 0)? != 0 {
            self.warn("seed", || format!("{}: the sampler's seed is ignored: caustica takes it from --seed", s.at));
        }
        s.boolean("jitter", true)?;
        s.check_all_used()?;
        let spp = u32::try_from(spp)
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| s.error(format!("sample_count must be at least 1, got {spp}")))?;
        Ok((spp, sampler))
    }

    /// Mitsuba's `max_depth` counts path segments, the camera ray included, and so does caustica's
    /// `max_bounces`: 1 shows the emitters seen directly, 2 adds direct lighting, -1 is unbounded.
    /// `rr_depth` becomes `rr_start`: roulette first plays on reaching that vertex (Mitsuba
    /// before counting its emission, caustica after; both unbiased). Next-event estimation picks
    /// an emitter by caustica's default, the light tree (Mitsuba picks uniformly, by each
    /// emitter's `sampling_weight`): selection by power alone starved small bright lights, and on
    /// mitsuba-data's Veach scene (five spheres, one holding 98 % of the power) left 5x the error
    /// of the uniform pick, which the tree's distance and orientation terms avoid.
    fn integrator(&mut self, integrators: &[Rc<Object>]) -> Result<IntegratorFile> {
        let mut file = IntegratorFile { rr_start: 5, max_bounces: UNBOUNDED_DEPTH, ..IntegratorFile::default() };
        let i = match integrators {
            [] => return Ok(file),
            [i] => i,
            [_, second, ..] => return Err(second.error("a second integrator")),
        };
        // volpath and volpathmis trace media as caustica's path tracer does where a scene has
        // them (spectral MIS over the channels, as volpathmis).
        if !matches!(i.plugin.as_str(), "path" | "volpath" | "volpathmis") {
            return Err(i.error("only the path, volpath and volpathmis integrators are supported"));
        }
        file.max_bounces = match i.integer("max_depth", -1)? {
            -1 => UNBOUNDED_DEPTH,
            d if d >= 1 => u32::try_from(d).unwrap_or(u32::MAX),
            d => return Err(i.error(format!("max_depth {d} is not supported (-1 or at least 1)"))),
        };
        let rr_depth = i.integer("rr_depth", 5)?;
        file.rr_start =
            u32::try_from(rr_depth).map_err(|_| i.error(format!("rr_depth must be >= 0, got {rr_depth}")))?;
        if i.boolean("hide_emitters", false)? {
            return Err(i.error("hide_emitters is not supported"));
        }
        i.check_all_used()?;
        Ok(file)
    }

    fn out(&mut self) -> &mut SceneFile {
        self.file.as_mut().expect("the scene file exists while shapes are mapped")
    }

    /// An `instance` of a `shapegroup`: each shape of the group placed by the instance's
    /// `to_world` after its own. Meshes placed again are stored once (caustica shares every
    /// `[[meshes]]` entry of the same file and material); other shapes are copied.
    fn instance(&mut self, i: &Object) -> Result<()> {
        let m = i.transform("to_world")?.unwrap_or(DMat4::IDENTITY);
        let groups = i.children_tagged("shape")?;
        let [group] = groups.as_slice() else {
            return Err(i.error("an instance needs exactly one <ref> to a shapegroup"));
        };
        if group.plugin != "shapegroup" {
            return Err(i.error(format!("instances place a shapegroup, not {}", group.describe())));
        }
        i.check_all_used()?;
        for shape in group.children_tagged("shape")? {
            if matches!(shape.plugin.as_str(), "shapegroup" | "instance") {
                return Err(shape.error("a shapegroup inside a shapegroup is not supported"));
            }
            self.shape(&shape, m)?;
        }
        group.check_all_used()
    }

    /// A shape, placed by `parent` (an instance's transform) after its own `to_world`.
    fn shape(&mut self, s: &Rc<Object>, parent: DMat4) -> Result<()> {
        let m = parent * s.transform("to_world")?.unwrap_or(DMat4::IDENTITY);
        let flip = s.boolean("flip_normals", false)?;
        let material = self.shape_material(s)?;
        // A mirroring transform turns the winding, so Mitsuba's normals (transformed as normals)
        // face the other way round the edges.
        let reverse = flip != (m.determinant() < 0.0);
        let mesh_only = needs_mesh(&self.materials[&material]);
        let textured = mesh_only.is_some();
        let mesh = matches!(s.plugin.as_str(), "obj" | "ply" | "serialized");
        if let (Some(what), false) = (mesh_only, mesh) {
            return Err(s.error(format!("a BSDF with {what} on this shape is not supported (caustica's spheres and quads have no texture coordinates or alpha tests; meshes do)")));
        }
        match s.plugin.as_str() {
            "obj" | "ply" | "serialized" => {
                let Some(name) = s.string("filename")?.map(str::to_owned) else { return Err(s.error("needs a filename")) };
                // A mirroring to_world turns the winding with the normals (Mitsuba transforms
                // normals as normals), so only flip_normals turns the front round.
                let face_normals = s.boolean("face_normals", false)?;
                let shape_index = if s.plugin == "serialized" {
                    let index = s.integer("shape_index", 0)?;
                    Some(u32::try_from(index).map_err(|_| s.error(format!("shape_index must be >= 0, got {index}")))?)
                } else {
                    // caustica turns OBJ and PLY texture coordinates upside down as Mitsuba does by
                    // default; they only matter to textures.
                    if !s.boolean("flip_tex_coords", true)? && textured {
                        return Err(s.error("flip_tex_coords = false is not supported on a textured mesh"));
                    }
                    None
                };
                let path = self.resolver.resolve(&name, Path::new(&*s.at.file));
                let file = relative_to(&path, &self.base);
                let placement = transform::placement(m).map_err(|e| s.error(e))?;
                self.out().meshes.push(MeshFile {
                    file,
                    material: Some(material),
                    shape_index,
                    flip_normals: flip,
                    face_normals,
                    translate: placement.translate,
                    scale: placement.scale,
                    rotate: placement.rotate,
                    instances: vec![],
                });
            }
            "sphere" => {
                if flip {
                    return Err(s.error("flip_normals on a sphere is not supported (caustica's spheres face outwards)"));
                }
                let center = s.point("center")?.unwrap_or(DVec3::ZERO);
                let radius = s.float("radius", 1.0)?;
                let scale = uniform_scale(m).ok_or_else(|| s.error("its to_world scales unevenly or shears; a sphere needs a uniform scale"))?;
                let material = material.clone();
                self.out().spheres.push(SphereFile { center: f32x3(point(m, center)), radius: (radius * scale) as f32, material });
            }
            "rectangle" => self.quad(m, DVec3::new(-1.0, -1.0, 0.0), DVec3::X * 2.0, DVec3::Y * 2.0, reverse, &material),
            "cube" => {
                let faces = [
                    (DVec3::new(1.0, -1.0, -1.0), DVec3::Y, DVec3::Z),
                    (DVec3::new(-1.0, -1.0, -1.0), DVec3::Z, DVec3::Y),
                    (DVec3::new(-1.0, 1.0, -1.0), DVec3::Z, DVec3::X),
                    (DVec3::new(-1.0, -1.0, -1.0), DVec3::X, DVec3::Z),
                    (DVec3::new(-1.0, -1.0, 1.0), DVec3::X, DVec3::Y),
                    (DVec3::new(-1.0, -1.0, -1.0), DVec3::Y, DVec3::X),
                ];
                for (origin, u, v) in faces {
                    self.quad(m, origin, u * 2.0, v * 2.0, reverse, &material);
                }
            }
            "disk" => {
                self.warn("disk", || format!("{}: {}: disks become {DISK_SEGMENTS}-sided polygons (0.16% less area)", s.at, s.describe()));
                let rim = |k: usize| {
                    let a = std::f64::consts::TAU * k as f64 / DISK_SEGMENTS as f64;
                    point(m, DVec3::new(a.cos(), a.sin(), 0.0))
                };
                let center = point(m, DVec3::ZERO);
                for k in 0..DISK_SEGMENTS {
                    let (a, b) = if reverse { (rim(k + 1), rim(k)) } else { (rim(k), rim(k + 1)) };
                    let vertices = Array([f32x3(center), f32x3(a), f32x3(b)]);
                    self.out().triangles.push(TriangleFile { vertices, material: material.clone() });
                }
            }
            _ => return Err(s.error("this shape is not supported (obj, ply, serialized, sphere, rectangle, cube, disk, shapegroup, instance)")),
        }
        s.check_all_used()
    }

    /// The parallelogram origin + [0, 1] u + [0, 1] v placed by `m`, facing u x v (v x u when
    /// `reverse`).
    fn quad(&mut self, m: DMat4, origin: DVec3, u: DVec3, v: DVec3, reverse: bool, material: &str) {
        let (u, v) = if reverse { (v, u) } else { (u, v) };
        let quad = QuadFile {
            origin: f32x3(point(m, origin)),
            edge_u: f32x3(vector(m, u)),
            edge_v: f32x3(vector(m, v)),
            material: material.to_owned(),
        };
        self.out().quads.push(quad);
    }

    /// The `[[media]]` name of Mitsuba medium `m`, mapped once.
    fn medium(&mut self, m: &Rc<Object>) -> Result<String> {
        let address = Rc::as_ptr(m) as usize;
        if let Some(name) = self.medium_names.get(&address) {
            return Ok(name.clone());
        }
        let mut name = object_name(m);
        while self.media.iter().any(|f| f.name == name) {
            name += "'";
        }
        let file = super::mitsuba_media::medium_file(m, name.clone(), &self.resolver, &self.base)?;
        self.media.push(file);
        self.medium_names.insert(address, name.clone());
        Ok(name)
    }

    /// The material of a shape's BSDF (Mitsuba's default: diffuse 0.5) with its area emitter's
    /// radiance and its interior medium, made once per combination. Its exterior medium must be
    /// the sensor's: caustica's media nest (docs/scene-format.md), entering a shape pushes its
    /// interior and leaving returns to what was outside.
    fn shape_material(&mut self, s: &Object) -> Result<String> {
        let bsdf = s.child("bsdf")?;
        let emitter = s.child("emitter")?;
        let interior = match s.named_child("medium", "interior")? {
            Some(m) => Some(self.medium(&m)?),
            None => None,
        };
        if let Some(exterior) = s.named_child("medium", "exterior")? {
            let exterior = self.medium(&exterior)?;
            if self.camera_medium.as_ref() != Some(&exterior) {
                return Err(s.error(format!("its exterior medium '{exterior}' is not the sensor's: caustica's media nest, and what lies outside every shape is the sensor's medium")));
            }
        }
        if let Some(e) = &emitter {
            if e.plugin != "area" {
                return Err(e.error("only area emitters can be attached to a shape"));
            }
        }
        let address = |o: &Option<Rc<Object>>| o.as_ref().map_or(0, |o| Rc::as_ptr(o) as usize);
        let key = (address(&bsdf), address(&emitter), interior.clone());
        if let Some(name) = self.material_names.get(&key) {
            return Ok(name.clone());
        }
        let mut material = match &bsdf {
            Some(b) => self.bsdf(b, false)?,
            None => MaterialFile { albedo: Array([0.5; 3]), ..MaterialFile::default() },
        };
        let mut name = bsdf.as_ref().map_or("default diffuse".to_owned(), |b| object_name(b));
        if let Some(e) = &emitter {
            if material.kind.is_some() {
                return Err(e.error("an emitter on a null BSDF (a medium's boundary only) is not supported"));
            }
            material.emission = f32x3(self.color(e, "radiance", 1.0)?);
            e.check_all_used()?;
            name = format!("{name} + {}", object_name(e));
        }
        if let Some(interior) = &interior {
            if material.kind.is_none() && material.transparency <= 0.0 {
                return Err(s.error("an interior medium inside a shape whose BSDF is neither null nor a dielectric: no path could enter it"));
            }
            material.interior = Some(interior.clone());
            name = format!("{name} + {interior}");
        }
        let name = unique_name(&self.materials, name);
        self.materials.insert(name.clone(), material);
        self.material_names.insert(key, name.clone());
        Ok(name)
    }

    /// The material of the one BSDF nested in adapter `b` (`error` if not one), refusing a BSDF
    /// that contains itself (`<bsdf type="mask" id="a"><ref id="a"/></bsdf>`).
    fn nested_material(&mut self, b: &Object, error: &str, two_sided: bool) -> Result<MaterialFile> {
        let inner = nested_bsdf(b, error)?;
        self.open_adapters.push(b);
        if self.open_adapters.contains(&Rc::as_ptr(&inner)) {
            self.open_adapters.clear();
            return Err(b.error(format!("contains itself (its nested BSDF is {})", inner.describe())));
        }
        let material = self.bsdf(&inner, two_sided);
        self.open_adapters.pop();
        material
    }

    /// A BSDF as a caustica material; `two_sided`: inside a `twosided`. Mitsuba's reflecting
    /// BSDFs are black from behind unless wrapped in `twosided` (caustica's `one_sided`); its
    /// dielectrics scatter from both sides.
    fn bsdf(&mut self, b: &Object, two_sided: bool) -> Result<MaterialFile> {
        let defaults = MaterialFile { one_sided: !two_sided, ..MaterialFile::default() };
        let see_through = MaterialFile::default();
        let material = match b.plugin.as_str() {
            "twosided" if two_sided => return Err(b.error("a twosided inside a twosided")),
            "twosided" => self.nested_material(b, "only a twosided with one nested BSDF (the same on both sides) is supported", true)?,
            "mask" => {
                let mut material = self.nested_material(b, "a mask needs one nested BSDF", two_sided)?;
                if material.opacity.is_some() || material.opacity_texture.is_some() {
                    return Err(b.error("a mask inside a mask is not supported"));
                }
                match b.texture("opacity")? {
                    Some(t) => material.opacity_texture = Some(self.data_texture(&t)?),
                    None => material.opacity = Some(b.float("opacity", 0.5)? as f32),
                }
                material
            }
            "normalmap" => {
                let mut material = self.nested_material(b, "a normalmap needs one nested BSDF", two_sided)?;
                if material.normal_texture.is_some() {
                    return Err(b.error("a normalmap inside a normalmap is not supported"));
                }
                let Some(t) = b.texture("normalmap")? else { return Err(b.error("needs a normalmap texture")) };
                material.normal_texture = Some(self.data_texture(&t)?);
                material
            }
            // Only a medium's boundary: caustica's type = "null" (its interior from the shape).
            "null" => MaterialFile { kind: Some(MaterialKind::Null), ..MaterialFile::default() },
            "diffuse" => {
                match b.texture("reflectance")? {
                    Some(t) => MaterialFile { albedo: Array([1.0; 3]), albedo_texture: Some(self.albedo_texture(&t)?), ..defaults },
                    None => MaterialFile { albedo: f32x3(self.reflectance(b, "reflectance", 0.5)?), ..defaults },
                }
            }
            "conductor" | "roughconductor" => {
                let (roughness, roughness_v, distribution) = self.microfacet(b, b.plugin == "roughconductor")?;
                self.unit_factor(b, "specular_reflectance")?;
                let given = (b.color("eta", &mut |_| {})?, b.color("k", &mut |_| {})?);
                let (metal, eta, k) = match (b.string("material")?, given) {
                    (Some(_), (Some(_), _) | (_, Some(_))) => return Err(b.error("give material or eta and k, not both")),
                    (_, (Some(eta), Some(k))) => (None, Some(f32x3(eta)), Some(f32x3(k))),
                    (_, (Some(_), None) | (None, Some(_))) => return Err(b.error("eta needs k and k needs eta")),
                    (None | Some("none"), (None, None)) => (None, None, None),
                    (Some(name), (None, None)) => match NAMED_METALS.iter().find(|(m, _)| *m == name) {
                        Some((_, caustica)) => (Some((*caustica).to_owned()), None, None),
                        None => {
                            let known: Vec<_> = NAMED_METALS.iter().map(|(m, _)| *m).collect();
                            return Err(b.error(format!("the conductor '{name}' is not supported (known: none, {}; or give eta and k)", known.join(", "))));
                        }
                    },
                };
                MaterialFile { reflectivity: Some(1.0), roughness, roughness_v, distribution, metal, eta, k, ..defaults }
            }
            "dielectric" | "roughdielectric" => {
                let (roughness, roughness_v, distribution) = self.microfacet(b, b.plugin == "roughdielectric")?;
                self.unit_factor(b, "specular_reflectance")?;
                self.unit_factor(b, "specular_transmittance")?;
                let ior = relative_ior(b, "bk7")?;
                MaterialFile { transparency: 1.0, ior, roughness, roughness_v, distribution, ..see_through }
            }
            "thindielectric" => {
                self.unit_factor(b, "specular_reflectance")?;
                self.unit_factor(b, "specular_transmittance")?;
                MaterialFile { transparency: 1.0, ior: relative_ior(b, "bk7")?, thin: true, ..see_through }
            }
            "plastic" | "roughplastic" => {
                // A smooth plastic is Mitsuba's model exactly: its diffuse term
                // rho / (1 - Fdr_in) / eta^2 is caustica's rho / (1 - Fdr_out), by reciprocity.
                if b.plugin == "roughplastic" {
                    self.warn("roughplastic", || {
                        format!("{}: {}: roughplastic's base is seen through the smooth coat's Fresnel terms (Mitsuba tabulates the rough coat's transmittance: a little brighter at grazing angles)", b.at, b.describe())
                    });
                }
                let (roughness, roughness_v, distribution) = self.microfacet(b, b.plugin == "roughplastic")?;
                self.unit_factor(b, "specular_reflectance")?;
                let coat_internal_reflections = b.boolean("nonlinear", false)?;
                let albedo = f32x3(self.reflectance(b, "diffuse_reflectance", 0.5)?);
                MaterialFile { albedo, coat: true, coat_internal_reflections, ior: relative_ior(b, "polypropylene")?, roughness, roughness_v, distribution, ..defaults }
            }
            _ => return Err(b.error("this BSDF is not supported (diffuse, conductor, roughconductor, dielectric, roughdielectric, thindielectric, plastic, roughplastic, twosided, mask, normalmap)")),
        };
        b.check_all_used()?;
        Ok(material)
    }

    /// A `checkerboard` or `bitmap` texture as caustica's albedo texture, with its `to_uv`.
    fn albedo_texture(&mut self, t: &Object) -> Result<AlbedoTextureFile> {
        let mut texture = match t.plugin.as_str() {
            "checkerboard" => {
                let colors = [self.reflectance(t, "color0", 0.4)?, self.reflectance(t, "color1", 0.2)?];
                AlbedoTextureFile { file: None, checkerboard: Some(Array(colors.map(f32x3))), to_uv: None }
            }
            "bitmap" => {
                let (file, raw) = self.bitmap(t)?;
                if raw {
                    return Err(t.error("raw (linear) bitmaps are not supported for a reflectance; caustica reads colour images as sRGB"));
                }
                AlbedoTextureFile { file: Some(file), checkerboard: None, to_uv: None }
            }
            _ => return Err(t.error("this texture is not supported for a diffuse reflectance (checkerboard, bitmap)")),
        };
        texture.to_uv = to_uv(t)?;
        t.check_all_used()?;
        Ok(texture)
    }

    /// A `bitmap` of data (a mask's opacity, a normal map), decoded from sRGB unless `raw` as
    /// Mitsuba does.
    fn data_texture(&mut self, t: &Object) -> Result<ImageTextureFile> {
        if t.plugin != "bitmap" {
            return Err(t.error("only bitmap textures are supported here"));
        }
        let (file, raw) = self.bitmap(t)?;
        let texture = ImageTextureFile {
            file,
            to_uv: to_uv(t)?,
            encoding: Some(if raw { Encoding::Linear } else { Encoding::Srgb }),
        };
        t.check_all_used()?;
        Ok(texture)
    }

    /// A `bitmap` texture's file (relative to the scene's folder) and whether it is `raw`.
    fn bitmap(&mut self, t: &Object) -> Result<(String, bool)> {
        let Some(name) = t.string("filename")?.map(str::to_owned) else { return Err(t.error("needs a filename")) };
        // What Mitsuba does by default, and caustica always: bilinear lookups that tile.
        if t.string("filter_type")?.is_some_and(|f| f != "bilinear") {
            return Err(t.error("only filter_type bilinear is supported"));
        }
        if t.string("wrap_mode")?.is_some_and(|w| w != "repeat") {
            return Err(t.error("only wrap_mode repeat is supported"));
        }
        let raw = t.boolean("raw", false)?;
        let path = self.resolver.resolve(&name, Path::new(&*t.at.file));
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if !matches!(extension.as_str(), "png" | "jpg" | "jpeg") {
            return Err(t.error(format!("'{name}': only PNG and JPEG bitmaps are supported")));
        }
        Ok((relative_to(&path, &self.base), raw))
    }

    /// caustica's roughness (sqrt(alpha), alpha defaulting to Mitsuba's 0.1), its roughness_v
    /// (sqrt(alpha_v) where alpha_u and alpha_v differ; alpha_u is then along u, the roughness)
    /// and distribution (Mitsuba's default Beckmann, or GGX) of a rough BSDF.
    fn microfacet(&mut self, b: &Object, rough: bool) -> Result<(f32, Option<f32>, Microfacet)> {
        if !rough {
            return Ok((0.0, None, Microfacet::Ggx));
        }
        let distribution = match b.string("distribution")?.unwrap_or("beckmann") {
            "ggx" => Microfacet::Ggx,
            "beckmann" => Microfacet::Beckmann,
            other => return Err(b.error(format!("distribution '{other}' is not supported (beckmann, ggx)"))),
        };
        b.boolean("sample_visible", true)?;
        let (alpha, alpha_v) =
            match (b.float_if_given("alpha")?, b.float_if_given("alpha_u")?, b.float_if_given("alpha_v")?) {
                (Some(a), None, None) => (a, None),
                (None, None, None) => (0.1, None),
                (None, Some(u), Some(v)) if u == v => (u, None),
                (None, Some(u), Some(v)) => (u, Some(v)),
                _ => return Err(b.error("give alpha, or alpha_u and alpha_v")),
            };
        for (name, a) in [("alpha", Some(alpha)), ("alpha_v", alpha_v)] {
            match a {
                Some(a) if !(0.0..=1.0).contains(&a) => {
                    return Err(b.error(format!("{name} must be in [0, 1], got {a}")))
                }
                _ => {}
            }
        }
        Ok((alpha.sqrt() as f32, alpha_v.map(|v| v.sqrt() as f32), distribution))
    }

    /// A scale factor caustica has no place for: only its default, 1, is accepted.
    fn unit_factor(&mut self, b: &Object, name: &str) -> Result<()> {
        match self.color(b, name, 1.0)? {
            c if c == DVec3::ONE => Ok(()),
            _ => Err(b.error(format!("{name} other than 1 is not supported"))),
        }
    }

    fn emitter(&mut self, e: &Object) -> Result<()> {
        let m = e.transform("to_world")?;
        let light = match e.plugin.as_str() {
            "point" => {
                let position = match (e.point("position")?, m) {
                    (Some(_), Some(_)) => return Err(e.error("give position or to_world, not both")),
                    (Some(p), None) => p,
                    (None, m) => point(m.unwrap_or(DMat4::IDENTITY), DVec3::ZERO),
                };
                Some(LightFile::Point(PointLightFile {
                    position: f32x3(position),
                    intensity: f32x3(self.color(e, "intensity", 1.0)?),
                }))
            }
            "spot" => {
                let m = m.unwrap_or(DMat4::IDENTITY);
                let cutoff = e.float("cutoff_angle", 20.0)?;
                let beam = e.float("beam_width", cutoff * 0.75)?;
                if !(cutoff > 0.0 && cutoff <= 180.0 && (0.0..=cutoff).contains(&beam)) {
                    return Err(e.error(format!(
                        "needs 0 < cutoff_angle <= 180 and 0 <= beam_width <= cutoff_angle, got {cutoff} and {beam}"
                    )));
                }
                Some(LightFile::Spot(SpotLightFile {
                    position: f32x3(point(m, DVec3::ZERO)),
                    look_at: f32x3(point(m, DVec3::Z)),
                    intensity: f32x3(self.color(e, "intensity", 1.0)?),
                    cone_angle: cutoff as f32,
                    falloff_start: beam as f32,
                }))
            }
            "directional" => {
                let direction = match (e.point("direction")?, m) {
                    (Some(_), Some(_)) => return Err(e.error("give direction or to_world, not both")),
                    (Some(d), None) => d,
                    (None, m) => vector(m.unwrap_or(DMat4::IDENTITY), DVec3::Z),
                };
                Some(LightFile::Directional(DirectionalLightFile {
                    direction: f32x3(direction),
                    irradiance: f32x3(self.color(e, "irradiance", 1.0)?),
                    angular_diameter: 0.0,
                }))
            }
            "constant" => {
                if m.is_some() {
                    return Err(e.error("a constant emitter has no to_world"));
                }
                let color = f32x3(self.color(e, "radiance", 1.0)?);
                self.environment(e, EnvironmentFile { color: Some(color), ..Default::default() })?;
                None
            }
            "envmap" => {
                let Some(name) = e.string("filename")?.map(str::to_owned) else {
                    return Err(e.error("needs a filename"));
                };
                let path = self.resolver.resolve(&name, Path::new(&*e.at.file));
                let latlong = relative_to(&path, &self.base);
                let m = m.unwrap_or(DMat4::IDENTITY);
                let scale = e.float("scale", 1.0)?;
                // Mitsuba's u = 0 column looks down -z, caustica's centre column does: half a turn.
                let (rotation, axes) = match y_rotation_degrees(m) {
                    Some(rotation) => (((rotation + 180.0) % 360.0) as f32, None),
                    None => {
                        // Any other orientation: the map's axes, to which caustica resamples it.
                        let turned = DMat3::from_mat4(m) * DMat3::from_rotation_y(std::f64::consts::PI);
                        if !(turned.is_finite() && (turned.transpose() * turned).abs_diff_eq(DMat3::IDENTITY, 1e-4)) {
                            return Err(e.error("an envmap's to_world must rotate (and may mirror and translate) but not scale or shear"));
                        }
                        (0.0, Some(Array(turned.to_cols_array_2d().map(|c| Array(c.map(|v| v as f32))))))
                    }
                };
                self.environment(
                    e,
                    EnvironmentFile {
                        latlong: Some(latlong),
                        axes,
                        intensity: scale as f32,
                        rotation,
                        ..Default::default()
                    },
                )?;
                None
            }
            _ => {
                return Err(e.error("this emitter is not supported (area, point, spot, directional, constant, envmap)"))
            }
        };
        e.check_all_used()?;
        if let Some(light) = light {
            self.out().lights.push(light);
        }
        Ok(())
    }

    fn environment(&mut self, e: &Object, environment: EnvironmentFile) -> Result<()> {
        if self.out().environment.is_some() {
            return Err(e.error("a second environment emitter (constant or envmap): caustica has one environment"));
        }
        self.out().environment = Some(environment);
        Ok(())
    }
}

/// How many shapes top-level `shape` places: a shapegroup's (when it is one) for an instance, none
/// for the shapegroup itself, one for any other (a malformed instance is refused by its mapping).
fn shapes_placed(shape: &Object) -> usize {
    match shape.plugin.as_str() {
        "shapegroup" => 0,
        "instance" => match shape.children_tagged("shape").ok().as_deref() {
            Some([group]) => group.children_tagged("shape").map_or(1, |shapes| shapes.len()),
            _ => 1,
        },
        _ => 1,
    }
}

/// The id of an object, or where it was written.
/// The one BSDF nested in an adapter (`twosided`, `mask`, `normalmap`); `error` if not one.
fn nested_bsdf(b: &Object, error: &str) -> Result<Rc<Object>> {
    match b.children_tagged("bsdf")?.as_slice() {
        [inner] => Ok(inner.clone()),
        _ => Err(b.error(error)),
    }
}

/// A texture's `to_uv` as caustica's rows. Mitsuba keeps the 2D affine part of a 4x4 to_uv: its
/// upper-left 2x2 and the translation's first two components.
fn to_uv(t: &Object) -> Result<Option<Array<Triple, 2>>> {
    Ok(t.transform("to_uv")?.map(|m| {
        let row = |r: usize| Array([m.col(0)[r] as f32, m.col(1)[r] as f32, m.col(3)[r] as f32]);
        Array([row(0), row(1)])
    }))
}

fn object_name(o: &Object) -> String {
    let file = Path::new(&*o.at.file).file_name().map_or(String::new(), |f| f.to_string_lossy().into_owned());
    o.id.clone().unwrap_or_else(|| format!("{} {} at {file}:{}", o.plugin, o.tag, o.at.line))
}

/// int_ior / ext_ior, each a number or one of Mitsuba's named indices.
fn relative_ior(b: &Object, interior_default: &str) -> Result<f32> {
    let ior = |name: &str, default: &str| -> Result<f64> {
        if let Some(v) = b.float_if_given(name).ok().flatten() {
            return Ok(v);
        }
        let named = b.string(name)?.unwrap_or(default);
        NAMED_IORS.iter().find(|(n, _)| *n == named).map(|(_, v)| *v).ok_or_else(|| {
            b.error(format!("{name} '{named}' is neither a number nor a known material (such as water, air, bk7)"))
        })
    };
    let (interior, exterior) = (ior("int_ior", interior_default)?, ior("ext_ior", "air")?);
    if !(interior > 0.0 && exterior > 0.0) {
        return Err(b.error("int_ior and ext_ior must be > 0"));
    }
    Ok((interior / exterior) as f32)
}

/// The angle (degrees) of a rotation about +y, else None.
fn y_rotation_degrees(m: DMat4) -> Option<f64> {
    let x = m.transform_vector3(DVec3::X);
    let angle = (-x.z).atan2(x.x);
    let expected = DMat4::from_rotation_y(angle);
    expected.abs_diff_eq(m, 1e-6).then_some(angle.to_degrees())
}
