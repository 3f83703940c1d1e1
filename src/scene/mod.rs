//! Scenes: the TOML format (`format`), validation into a `Scene`, meshes and environment maps.

mod environment;
mod format;
mod mesh;

pub use environment::{angular_map_uv, Environment, EnvironmentMap, MapProjection};

use anyhow::{bail, Context as _, Result};
use format::{Scale, SceneFile};
use glam::{Mat4, Quat, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The built-in default scene: the Cornell box with a mirror sphere, a glass sphere and a small light.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../scenes/cornell.toml");

#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
}

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

#[derive(Clone, Debug)]
pub struct Integrator {
    pub rr_start: u32,
    pub absorption: Option<f32>,
    pub nee: bool,
    pub max_bounces: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub albedo: Vec3,
    pub reflectivity: f32,
    pub transparency: f32,
    pub ior: f32,
    pub emission: Vec3,
    pub two_sided: bool,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Sphere { center: Vec3, radius: f32, material: u32 },
    /// Parallelogram origin + s u + t v, s and t in [0, 1]; front side faces u x v.
    Quad { origin: Vec3, u: Vec3, v: Vec3, material: u32 },
    /// Front side faces (v1 - v0) x (v2 - v0).
    Triangle { v: [Vec3; 3], material: u32 },
}

impl Shape {
    pub fn material(&self) -> u32 {
        match *self {
            Shape::Sphere { material, .. } | Shape::Quad { material, .. } | Shape::Triangle { material, .. } => material,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Scene {
    /// Where the scene came from, for messages.
    pub name: String,
    pub camera: Camera,
    pub film: Film,
    pub integrator: Integrator,
    pub materials: Vec<Material>,
    pub shapes: Vec<Shape>,
    pub environment: Environment,
}

impl Scene {
    /// Reads a scene file; relative paths inside it are relative to the file.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read scene", path.display()))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, &path.display().to_string(), &base)
    }

    /// The built-in Cornell box.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, "built-in cornell.toml", Path::new(".")).expect("the built-in scene is valid")
    }

    /// Parses scene text; `name` appears in messages and `base` resolves relative file paths.
    pub fn parse(text: &str, name: &str, base: &Path) -> Result<Scene> {
        let file: SceneFile = toml::from_str(text).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        build(file, name, base).with_context(|| name.to_string())
    }

    pub fn light_count(&self) -> usize {
        self.shapes.iter().filter(|s| self.materials[s.material() as usize].is_emissive()).count()
    }
}

fn vec3(key: &str, v: [f32; 3]) -> Result<Vec3> {
    if v.iter().any(|c| !c.is_finite()) {
        bail!("{key} must be finite, got {v:?}");
    }
    Ok(Vec3::from(v))
}

fn finite(key: &str, v: f32) -> Result<f32> {
    if !v.is_finite() {
        bail!("{key} must be finite, got {v}");
    }
    Ok(v)
}

fn non_negative3(key: &str, v: [f32; 3]) -> Result<Vec3> {
    let v = vec3(key, v)?;
    if v.min_element() < 0.0 {
        bail!("{key} must not be negative, got {v:?}");
    }
    Ok(v)
}

fn build(file: SceneFile, name: &str, base: &Path) -> Result<Scene> {
    let c = &file.camera;
    let camera = Camera {
        position: vec3("camera.position", c.position)?,
        look_at: vec3("camera.look_at", c.look_at)?,
        up: vec3("camera.up", c.up)?,
        fov_deg: finite("camera.fov", c.fov)?,
    };
    if !(camera.fov_deg > 0.0 && camera.fov_deg < 180.0) {
        bail!("camera.fov must be in (0, 180) degrees, got {}", camera.fov_deg);
    }
    let forward = camera.look_at - camera.position;
    if forward.length() == 0.0 {
        bail!("camera.look_at must differ from camera.position");
    }
    if forward.cross(camera.up).length() <= 1e-6 * forward.length() * camera.up.length() {
        bail!("camera.up must not be parallel to the viewing direction (or zero)");
    }
    let film = Film { width: file.film.width, height: file.film.height, spp: file.film.spp };
    check_film(&film)?;
    let i = &file.integrator;
    if let Some(a) = i.absorption {
        if !(a.is_finite() && (0.0..1.0).contains(&a)) {
            bail!("integrator.absorption must be in [0, 1), got {a}");
        }
    }
    if i.max_bounces == 0 {
        bail!("integrator.max_bounces must be at least 1");
    }
    let integrator = Integrator { rr_start: i.rr_start, absorption: i.absorption, nee: i.nee, max_bounces: i.max_bounces };

    let mut materials = Vec::new();
    let mut by_name = HashMap::new();
    for (mname, m) in &file.materials {
        let key = |field: &str| format!("materials.{mname}.{field}");
        let material = Material {
            name: mname.clone(),
            albedo: non_negative3(&key("albedo"), m.albedo)?,
            reflectivity: finite(&key("reflectivity"), m.reflectivity)?,
            transparency: finite(&key("transparency"), m.transparency)?,
            ior: finite(&key("ior"), m.ior)?,
            emission: non_negative3(&key("emission"), m.emission)?,
            two_sided: m.two_sided,
        };
        if material.albedo.max_element() > 1.0 {
            bail!("{} must be at most 1 per channel (energy conservation), got {:?}", key("albedo"), material.albedo);
        }
        if material.reflectivity < 0.0 || material.transparency < 0.0 || material.reflectivity + material.transparency > 1.0 + 1e-6 {
            bail!(
                "materials.{mname}: reflectivity and transparency must be >= 0 with R + T <= 1, got R = {}, T = {}",
                material.reflectivity,
                material.transparency
            );
        }
        if material.ior <= 0.0 {
            bail!("{} must be > 0, got {}", key("ior"), material.ior);
        }
        by_name.insert(mname.clone(), materials.len() as u32);
        materials.push(material);
    }
    let material = |key: String, mname: &str| -> Result<u32> {
        by_name.get(mname).copied().with_context(|| {
            let known: Vec<_> = file.materials.keys().map(String::as_str).collect();
            format!("{key}: unknown material '{mname}' (defined: {})", known.join(", "))
        })
    };

    let mut shapes = Vec::new();
    for (k, s) in file.spheres.iter().enumerate() {
        let radius = finite(&format!("spheres[{k}].radius"), s.radius)?;
        if radius <= 0.0 {
            bail!("spheres[{k}].radius must be > 0, got {radius}");
        }
        shapes.push(Shape::Sphere {
            center: vec3(&format!("spheres[{k}].center"), s.center)?,
            radius,
            material: material(format!("spheres[{k}].material"), &s.material)?,
        });
    }
    for (k, q) in file.quads.iter().enumerate() {
        let u = vec3(&format!("quads[{k}].edge_u"), q.edge_u)?;
        let v = vec3(&format!("quads[{k}].edge_v"), q.edge_v)?;
        if u.cross(v).length() == 0.0 {
            bail!("quads[{k}]: edge_u and edge_v span no area");
        }
        shapes.push(Shape::Quad {
            origin: vec3(&format!("quads[{k}].origin"), q.origin)?,
            u,
            v,
            material: material(format!("quads[{k}].material"), &q.material)?,
        });
    }
    for (k, t) in file.triangles.iter().enumerate() {
        let key = format!("triangles[{k}].vertices");
        let v = [vec3(&key, t.vertices[0])?, vec3(&key, t.vertices[1])?, vec3(&key, t.vertices[2])?];
        if (v[1] - v[0]).cross(v[2] - v[0]).length() == 0.0 {
            bail!("{key}: the triangle has no area");
        }
        shapes.push(Shape::Triangle { v, material: material(format!("triangles[{k}].material"), &t.material)? });
    }
    for (k, m) in file.meshes.iter().enumerate() {
        let key = format!("meshes[{k}]");
        let mat = material(format!("{key}.material"), &m.material)?;
        let scale = match m.scale {
            None => Vec3::ONE,
            Some(Scale::Uniform(s)) => Vec3::splat(finite(&format!("{key}.scale"), s)?),
            Some(Scale::PerAxis(s)) => vec3(&format!("{key}.scale"), s)?,
        };
        if scale.min_element().abs() == 0.0 {
            bail!("{key}.scale must not be zero");
        }
        let r = vec3(&format!("{key}.rotate"), m.rotate)?;
        let rotation = Quat::from_euler(glam::EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians());
        let transform = Mat4::from_scale_rotation_translation(scale, rotation, vec3(&format!("{key}.translate"), m.translate)?);
        let path = resolve(base, &m.file);
        let triangles = mesh::load_obj(&path, transform)?;
        shapes.extend(triangles.into_iter().map(|v| Shape::Triangle { v, material: mat }));
    }

    let environment = match &file.environment {
        None => Environment::Constant(Vec3::ZERO),
        Some(e) => environment::from_file(e, base)?,
    };
    Ok(Scene { name: name.to_string(), camera, film, integrator, materials, shapes, environment })
}

/// Checks a film after command-line overrides too.
pub fn check_film(film: &Film) -> Result<()> {
    if film.width == 0 || film.height == 0 {
        bail!("film.width and film.height must be at least 1, got {} x {}", film.width, film.height);
    }
    if film.width > 16384 || film.height > 16384 {
        bail!("film of {} x {} is too large (at most 16384 per side)", film.width, film.height);
    }
    if film.spp == 0 {
        bail!("film.spp must be at least 1");
    }
    Ok(())
}

fn resolve(base: &Path, file: &str) -> PathBuf {
    let p = Path::new(file);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}
