//! Scenes: the TOML format (`format`), validation into a `Scene`, meshes and environment maps.

mod albedo_texture;
mod asset;
mod camera_toml;
mod environment;
mod equal_area_map;
mod format;
pub mod framing;
pub mod grid_volume;
pub mod import;
mod light;
mod material_maps;
mod medium;
mod mesh;
mod optics;
mod toml_error;

pub use asset::{
    downsample_to_fit, load_asset, load_asset_from, load_asset_part, srgb_to_linear, Asset, AssetError, Wrap,
    MAX_TEXTURE_BYTES,
};
pub use camera_toml::camera_toml;
pub use environment::{angular_map_uv, Environment, EnvironmentMap, MapProjection};
pub use format::{Filter, LightSelection, Microfacet, Sampler};
pub use light::{Light, MIN_DISK_DEGREES};
pub use medium::{Medium, Phase, MAX_MEDIA};
pub use mesh::{AssetCamera, Instance, Mesh, MeshImporter, Sides, Texture};
pub use optics::{average_fresnel, fresnel_dielectric, metal, METALS};

use crate::input_file::{InputFiles, InputKind};
use anyhow::{bail, Context as _, Result};
use format::{
    Array, CameraFile, FilmFile, IntegratorFile, MaterialFile, MeshFile, Placement, Scale, SceneFile, Triple,
};
use glam::{Mat4, Quat, Vec3};
use std::collections::{BTreeMap, HashMap};
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
    /// Thin-lens radius; 0 is a pinhole.
    pub aperture: f32,
    /// Distance of the plane in focus along the viewing axis.
    pub focus_distance: f32,
}

impl Camera {
    /// A pinhole camera (focused on look_at, which only matters once an aperture is set).
    pub fn pinhole(position: Vec3, look_at: Vec3, up: Vec3, fov_deg: f32) -> Camera {
        Camera { position, look_at, up, fov_deg, aperture: 0.0, focus_distance: (look_at - position).length() }
    }
}

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub filter: Filter,
}

#[derive(Clone, Debug)]
pub struct Integrator {
    pub rr_start: u32,
    pub absorption: Option<f32>,
    pub nee: bool,
    pub max_bounces: u32,
    pub sample_environment: bool,
    /// Per-sample cap on the largest radiance component (biased); None: off.
    pub clamp: Option<f32>,
    pub sampler: Sampler,
    pub light_selection: LightSelection,
}

/// GGX alpha below which a lobe is smooth, a delta lobe (`ALPHA_DELTA` of shaders/microfacet.glsl):
/// the scene clamps anisotropic alphas to it, and the kernel's specialization (render::features)
/// compiles rough lobes in for materials at or above it.
pub const ALPHA_DELTA: f32 = 1e-3;

/// The one material model inside caustica: the TOML scene format, the importers and the mesh
/// loaders all produce it (their own file structs stay at the edges: format.rs's `MaterialFile`,
/// glTF's and MTL's), and render/scene_data.rs packs it for the kernel. A base (diffuse, or a
/// plastic when `coat`) that is, per bounce, replaced with probability `reflectivity` by a
/// reflector (mirror or conductor) and with probability `transparency` by a Fresnel dielectric,
/// each GGX-rough by `roughness`. `Material::default()` is 0.8 grey diffuse, the material of
/// faces that name none; build others as `Material { albedo, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub albedo: Vec3,
    pub reflectivity: f32,
    pub transparency: f32,
    pub ior: f32,
    pub emission: Vec3,
    pub two_sided: bool,
    /// Index into `Scene::textures`; multiplies `albedo`.
    pub albedo_texture: Option<u32>,
    /// Perceptual GGX roughness in [0, 1] of the R and T lobes and of the coat (alpha is its
    /// square); 0 is a perfect mirror and smooth glass. Along the surface's u direction where
    /// `roughness_v` differs.
    pub roughness: f32,
    /// Perceptual roughness along the surface's v direction, in [0, 1]: anisotropic lobes (the
    /// scene format's `roughness_v`, Mitsuba's `alpha_v`, pbrt's `vroughness`); None: `roughness`.
    pub roughness_v: Option<f32>,
    /// Fresnel of the R lobe.
    pub conductor: Conductor,
    /// The base (1 - R - T) is a plastic: the albedo under a dielectric coat of index `ior` and
    /// roughness `roughness`; false: plain diffuse.
    pub coat: bool,
    /// The coat reflects light back down onto the base, which scatters it again (Mitsuba's
    /// `nonlinear` plastic; pbrt's `coateddiffuse` follows it by random walks).
    pub coat_internal_reflections: bool,
    /// The microfacet distribution of the rough R and T lobes and of the coat.
    pub microfacet: Microfacet,
    /// The T lobe is a thin sheet: reflects 2F / (1 + F), passes the rest straight through.
    pub thin: bool,
    /// Black from behind: scatters on its front side only.
    pub one_sided: bool,
    /// glTF: `reflectivity`, `transparency` and `roughness` come per texel from a texture.
    pub metallic_roughness: Option<MetallicRoughness>,
    /// Emission, normal and alpha textures (mesh files only).
    pub maps: TextureMaps,
    /// A clear coat over the whole material (glTF `KHR_materials_clearcoat`); None: uncoated.
    pub clearcoat: Option<Clearcoat>,
    /// Absorption inside the material, a dielectric (`transparency` > 0); None: clear.
    pub attenuation: Option<Attenuation>,
    /// The medium (an index into `Scene::media`) inside closed shapes of this material, behind
    /// their geometric normal; None: empty space.
    pub interior: Option<u32>,
    /// Not a surface: only the boundary of `interior` (the TOML's `type = "null"`, Mitsuba's
    /// `null` BSDF, pbrt's `interface`). Rays pass it unchanged.
    pub null_surface: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".to_owned(),
            albedo: Vec3::splat(0.8),
            reflectivity: 0.0,
            transparency: 0.0,
            ior: 1.5,
            emission: Vec3::ZERO,
            two_sided: false,
            albedo_texture: None,
            roughness: 0.0,
            roughness_v: None,
            conductor: Conductor::Mirror,
            coat: false,
            coat_internal_reflections: false,
            microfacet: Microfacet::Ggx,
            thin: false,
            one_sided: false,
            metallic_roughness: None,
            maps: TextureMaps::default(),
            clearcoat: None,
            attenuation: None,
            interior: None,
            null_surface: false,
        }
    }
}

/// glTF's clear coat (`KHR_materials_clearcoat`): a smooth or GGX-rough dielectric layer of index
/// 1.5 over the material, which reflects `factor` x F(cos of the viewing angle) of the light and
/// leaves the rest to the material beneath (glTF's `fresnel_coat` mix).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearcoat {
    /// `clearcoatFactor`, in [0, 1]; 0 is no coat.
    pub factor: f32,
    /// `clearcoatRoughnessFactor`: perceptual GGX roughness in [0, 1] (alpha is its square).
    pub roughness: f32,
    /// `clearcoatTexture` (linear): its R channel multiplies `factor` per texel.
    pub texture: Option<u32>,
    /// `clearcoatRoughnessTexture` (linear): its G channel multiplies `roughness` per texel.
    pub roughness_texture: Option<u32>,
}

/// Beer-Lambert absorption inside a dielectric (glTF `KHR_materials_volume`, the scene format's
/// `attenuation_color` and `attenuation_distance`): white light that travels `distance` inside
/// is left with `color`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    /// Per channel in (0, 1].
    pub color: Vec3,
    /// Finite and > 0, in world units.
    pub distance: f32,
}

impl Attenuation {
    /// The absorption coefficient per world unit, sigma_a = -ln(color) / distance, so that a
    /// path of length t inside keeps exp(-sigma_a t) = color^(t / distance).
    pub fn sigma_a(&self) -> Vec3 {
        Vec3::from(self.color.to_array().map(|c| -c.ln() / self.distance))
    }
}

/// The textures of a material beyond albedo and metallic-roughness, each an index into the
/// scene's (or, in an asset, the asset's) textures. Each costs the kernel only in scenes that use
/// it (a `SceneFeatures` flag of its own).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureMaps {
    /// sRGB colour that multiplies `emission` per texel (glTF `emissiveTexture`, MTL `map_Ke`).
    pub emission: Option<u32>,
    /// A tangent-space normal map (glTF `normalTexture`, MTL `norm` / `map_Bump`).
    pub normal: Option<NormalMap>,
    /// How much of the surface is there (glTF `alphaMode`, MTL `d` / `map_d`); None: all of it.
    pub alpha: Option<Alpha>,
}

/// A surface's opacity: `factor` times, with a texture, the texture's A channel (bilinearly
/// filtered, never sRGB-decoded). It is tested where a ray meets the surface, during traversal, so
/// a surface that is not there is not hit by any ray (camera, bounce or shadow).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alpha {
    pub factor: f32,
    /// An RGBA texture whose A channel is the opacity (glTF `baseColorTexture`, MTL `map_d`).
    pub texture: Option<u32>,
    pub mode: AlphaMode,
}

/// How opacity decides whether a ray meets the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// glTF `MASK`: there where the opacity is at least `cutoff`, absent elsewhere.
    Mask { cutoff: f32 },
    /// glTF `BLEND`, MTL `d`: met with probability equal to the opacity (stochastic opacity, an
    /// unbiased estimate of blending the surface over what lies behind it).
    Blend,
}

/// A tangent-space normal map (linear RGB = (normal + 1) / 2 in the frame of the tangent, the
/// bitangent and the interpolated normal, glTF's convention) and glTF's `scale`, which multiplies
/// the normal's x and y before it is normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalMap {
    pub texture: u32,
    pub scale: f32,
}

impl TextureMaps {
    /// The same maps with their texture indices moved up by `base` (an asset's textures appended
    /// after the scene's).
    pub fn rebased(self, base: u32) -> TextureMaps {
        TextureMaps {
            emission: self.emission.map(|t| t + base),
            normal: self.normal.map(|n| NormalMap { texture: n.texture + base, ..n }),
            alpha: self.alpha.map(|a| Alpha { texture: a.texture.map(|t| t + base), ..a }),
        }
    }
}

impl Clearcoat {
    /// The same coat with its texture indices moved up by `base` (as [`TextureMaps::rebased`]).
    pub fn rebased(self, base: u32) -> Clearcoat {
        Clearcoat {
            texture: self.texture.map(|t| t + base),
            roughness_texture: self.roughness_texture.map(|t| t + base),
            ..self
        }
    }
}

/// A glTF metallic-roughness texture (linear; G = roughness, B = metallic) and the factors it
/// scales. The kernel recomputes the R/T mix per texel as the glTF loader does from factors
/// alone: R = metallic, T = (1 - metallic) x transmission, roughness for every lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    /// Index into the scene's (or, in an asset, the asset's) textures.
    pub texture: u32,
    pub metallic: f32,
    pub roughness: f32,
    pub transmission: f32,
}

/// How much the reflector (R) lobe reflects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Conductor {
    /// Everything: a perfect reflector (the original mirror).
    Mirror,
    /// A conductor of complex index eta + i k per RGB channel.
    Complex { eta: Vec3, k: Vec3 },
    /// Schlick's approximation with the albedo as the reflectance at normal incidence (glTF).
    Albedo,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// The microfacet alphas (roughness squared) along u and v of the R and T lobes and the coat;
    /// None for v where the lobes are isotropic. A material rough along one direction only is
    /// given ALPHA_DELTA along the other, the least alpha the kernel does not take for a delta
    /// lobe (a lobe cannot be smooth along one axis and rough along the other); one smooth
    /// along both is a delta lobe, isotropic.
    pub fn microfacet_alphas(&self) -> (f32, Option<f32>) {
        let alpha_u = self.roughness * self.roughness;
        match self.roughness_v {
            Some(v) if v != self.roughness => {
                let alpha_v = v * v;
                if alpha_u.max(alpha_v) < ALPHA_DELTA {
                    (alpha_u, None)
                } else {
                    (alpha_u.max(ALPHA_DELTA), Some(alpha_v.max(ALPHA_DELTA)))
                }
            }
            _ => (alpha_u, None),
        }
    }

    /// Whether its rough lobes are anisotropic, oriented by the surface's tangent.
    pub fn is_anisotropic(&self) -> bool {
        self.microfacet_alphas().1.is_some()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
    },
    /// Parallelogram origin + s u + t v, s and t in [0, 1]; front side faces u x v.
    Quad {
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        material: u32,
    },
    /// Front side faces (v1 - v0) x (v2 - v0).
    Triangle {
        v: [Vec3; 3],
        material: u32,
    },
}

impl Shape {
    pub fn material(&self) -> u32 {
        match *self {
            Shape::Sphere { material, .. } | Shape::Quad { material, .. } | Shape::Triangle { material, .. } => {
                material
            }
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
    /// The scene's own spheres, quads and triangles.
    pub shapes: Vec<Shape>,
    /// Triangle meshes, each stored once, and their placements.
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
    pub textures: Vec<Texture>,
    pub environment: Environment,
    /// Point, spot and directional lights (`[[lights]]`, glTF KHR_lights_punctual).
    pub lights: Vec<Light>,
    /// Participating media (`[[media]]`), named by materials' `interior` and `camera_medium`.
    pub media: Vec<Medium>,
    /// The medium the camera is in, which fills the space outside every closed boundary.
    pub camera_medium: Option<u32>,
}

impl Scene {
    /// Reads a scene file and every file it names from anywhere; see [`Scene::load_from`].
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_from(&InputFiles::anywhere(), path)
    }

    /// Reads a scene file (TOML, or a mesh file rendered on its own) through `files`, and every
    /// file it names (meshes, textures, environment maps) too; relative paths inside it are
    /// relative to the file. [`confinement`] gives the `files` of `render --confine`.
    pub fn load_from(files: &InputFiles, path: &Path) -> Result<Scene> {
        Scene::load_with(files, path, &[])
    }

    /// As [`Scene::load_from`], reading Mitsuba 3 XML and pbrt-v4 too (`import`), with `defines` setting Mitsuba's
    /// `<default>` parameters (`-D name=value`); the import's warnings go to stderr.
    pub fn load_with(files: &InputFiles, path: &Path, defines: &[(String, String)]) -> Result<Scene> {
        if import::is_foreign_scene(path) {
            let imported = import::import(files, path, defines)?;
            for warning in &imported.warnings {
                log::warn!("caustica: warning: {warning}");
            }
            return imported.into_scene(files);
        }
        if let Some((name, _)) = defines.first() {
            bail!("-D {name}=...: parameters are for Mitsuba XML scenes, not {}", path.display());
        }
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if matches!(extension.as_str(), "gltf" | "glb" | "obj" | "ply") {
            return Scene::model_from(files, path);
        }
        let text = files.read_to_string(path, InputKind::Scene)?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse_from(files, &text, &path.display().to_string(), &base)
    }

    /// A mesh file as a whole scene: its own camera (glTF) or one framing it in a three-quarter
    /// view from above its largest face (framing.rs), under a white sky, with the default film and
    /// integrator.
    pub fn from_model(path: &Path) -> Result<Scene> {
        Scene::model_from(&InputFiles::anywhere(), path)
    }

    fn model_from(files: &InputFiles, path: &Path) -> Result<Scene> {
        let name = path.display().to_string();
        let film = FilmFile::default();
        let mut scene = Scene {
            name: name.clone(),
            camera: Camera::pinhole(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0),
            film: Film { width: film.width, height: film.height, spp: film.spp, filter: film.filter },
            integrator: integrator_from(&IntegratorFile::default())?,
            materials: vec![],
            shapes: vec![],
            meshes: vec![],
            instances: vec![],
            textures: vec![],
            environment: Environment::Constant(Vec3::ONE),
            lights: vec![],
            media: vec![],
            camera_medium: None,
        };
        match MeshImporter::new(files).place(&mut scene, path, None, Mat4::IDENTITY)? {
            Some(c) => {
                scene.camera = Camera::pinhole(c.position, c.look_at, c.up, c.yfov_degrees);
                if let Some(aspect) = c.aspect.filter(|a| a.is_finite() && *a > 0.0) {
                    scene.film.height = ((scene.film.width as f32 / aspect).round() as u32).clamp(1, 16384);
                }
            }
            None => scene.camera = framing_camera(&scene),
        }
        Ok(scene)
    }

    /// The built-in Cornell box.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, "built-in cornell.toml", Path::new(".")).expect("the built-in scene is valid")
    }

    /// Parses scene text, reading the files it names from anywhere; see [`Scene::parse_from`].
    pub fn parse(text: &str, name: &str, base: &Path) -> Result<Scene> {
        Scene::parse_from(&InputFiles::anywhere(), text, name, base)
    }

    /// Parses scene text; `name` appears in messages, `base` resolves relative file paths and the
    /// files they name are read through `files`.
    pub fn parse_from(files: &InputFiles, text: &str, name: &str, base: &Path) -> Result<Scene> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| anyhow::anyhow!("{name}: {}", toml_error::describe(&e, text)))?;
        build(file, name, base, files).with_context(|| name.to_string())
    }

    /// The smallest box holding every shape and every placed mesh vertex, as (min, max) corners;
    /// `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let mut add = |p: Vec3| {
            lo = lo.min(p);
            hi = hi.max(p);
        };
        for shape in &self.shapes {
            match *shape {
                Shape::Sphere { center, radius, .. } => {
                    add(center - Vec3::splat(radius.abs()));
                    add(center + Vec3::splat(radius.abs()));
                }
                Shape::Quad { origin, u, v, .. } => {
                    [origin, origin + u, origin + v, origin + u + v].into_iter().for_each(&mut add)
                }
                Shape::Triangle { v, .. } => v.into_iter().for_each(&mut add),
            }
        }
        for inst in &self.instances {
            for p in &self.meshes[inst.mesh as usize].positions {
                add(inst.transform.transform_point3(*p));
            }
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    /// Emissive shapes plus emissive mesh triangles, each instance counted.
    pub fn light_count(&self) -> usize {
        let emissive = |m: u32| self.materials[m as usize].is_emissive();
        let mesh_lights: Vec<usize> =
            self.meshes.iter().map(|m| m.triangle_materials.iter().filter(|&&t| emissive(t)).count()).collect();
        self.shapes.iter().filter(|s| emissive(s.material())).count()
            + self.instances.iter().map(|i| mesh_lights[i.mesh as usize]).sum::<usize>()
    }
}

fn vec3(key: &str, Array(v): Triple) -> Result<Vec3> {
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

/// A finite value in [0, 1] (a roughness, a factor, an opacity), or an error naming `key`.
fn unit_interval(key: &str, v: f32) -> Result<f32> {
    let v = finite(key, v)?;
    if !(0.0..=1.0).contains(&v) {
        bail!("{key} must be in [0, 1], got {v}");
    }
    Ok(v)
}

fn non_negative3(key: &str, v: Triple) -> Result<Vec3> {
    let v = vec3(key, v)?;
    if v.min_element() < 0.0 {
        bail!("{key} must not be negative, got {v:?}");
    }
    Ok(v)
}

/// The validated scene of a parsed file: one validator per section, in the file's order of
/// dependence (shapes and meshes name materials).
fn build(file: SceneFile, name: &str, base: &Path, files: &InputFiles) -> Result<Scene> {
    let camera = camera_from(&file.camera)?;
    let film = Film { width: file.film.width, height: file.film.height, spp: file.film.spp, filter: file.film.filter };
    check_film(&film)?;
    let integrator = integrator_from(&file.integrator)?;
    let mut materials = materials_from(&file.materials)?;
    let media = medium::media_from(&file.media, base, files)?;
    for ((mname, m), material) in file.materials.iter().zip(materials.iter_mut()) {
        if let Some(interior) = &m.interior {
            material.interior = Some(medium::medium_named(&media, &format!("materials.{mname}.interior"), interior)?);
        }
    }
    let camera_medium =
        file.camera.medium.as_deref().map(|name| medium::medium_named(&media, "camera.medium", name)).transpose()?;
    let mut textures = vec![];
    let mut uv_maps = HashMap::new();
    for (index, (mname, m)) in file.materials.iter().enumerate() {
        if let Some(to_uv) = material_maps::attach(mname, m, &mut materials[index], &mut textures, base, files)? {
            uv_maps.insert(index as u32, to_uv);
        }
    }
    // Materials are numbered in name order, as materials_from lists them.
    let by_name: HashMap<&str, u32> =
        file.materials.keys().enumerate().map(|(i, name)| (name.as_str(), i as u32)).collect();
    let material = |key: String, mname: &str| -> Result<u32> {
        by_name.get(mname).copied().with_context(|| {
            let known: Vec<_> = file.materials.keys().map(String::as_str).collect();
            format!("{key}: unknown material '{mname}' (defined: {})", known.join(", "))
        })
    };
    let shapes = shapes_from(&file, &material)?;
    for shape in &shapes {
        let name = &materials[shape.material() as usize].name;
        if let Some(field) = material_maps::needs_mesh(&file.materials[name]) {
            bail!("materials.{name}.{field} needs a mesh (its texture coordinates and triangles); spheres, quads and triangles have none ({shape:?})");
        }
    }
    let environment = match &file.environment {
        None => Environment::Constant(Vec3::ZERO),
        Some(e) => environment::from_file(e, base, files)?,
    };
    let lights = light::lights_from(&file.lights)?;
    let mut scene = Scene {
        name: name.to_string(),
        camera,
        film,
        integrator,
        materials,
        shapes,
        meshes: vec![],
        instances: vec![],
        textures,
        environment,
        lights,
        media,
        camera_medium,
    };
    let mut importer = MeshImporter::new(files).with_uv_maps(uv_maps);
    place_meshes(&mut scene, &file.meshes, &material, base, &mut importer)?;
    for m in &file.inline_meshes {
        let index = material(format!("the mesh written at {}", m.name), &m.material)?;
        importer.place_inline(&mut scene, m, index)?;
    }
    Ok(scene)
}

/// A name's material index, or an error naming the key and the materials defined.
type MaterialLookup<'a> = dyn Fn(String, &str) -> Result<u32> + 'a;

fn camera_from(c: &CameraFile) -> Result<Camera> {
    let mut camera = Camera::pinhole(
        vec3("camera.position", c.position)?,
        vec3("camera.look_at", c.look_at)?,
        vec3("camera.up", c.up)?,
        finite("camera.fov", c.fov)?,
    );
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
    camera.aperture = finite("camera.aperture", c.aperture)?;
    if camera.aperture < 0.0 {
        bail!("camera.aperture must be >= 0, got {}", camera.aperture);
    }
    if let Some(f) = c.focus_distance {
        camera.focus_distance = finite("camera.focus_distance", f)?;
        if camera.focus_distance <= 0.0 {
            bail!("camera.focus_distance must be > 0, got {f}");
        }
    }
    Ok(camera)
}

/// Every `[materials.NAME]`, in name order (their indices).
fn materials_from(file: &BTreeMap<String, MaterialFile>) -> Result<Vec<Material>> {
    file.iter().map(|(mname, m)| material_from(mname, m)).collect()
}

fn material_from(mname: &str, m: &MaterialFile) -> Result<Material> {
    let key = |field: &str| format!("materials.{mname}.{field}");
    if m.kind == Some(format::MaterialKind::Null) {
        // A boundary and nothing else: any other key would describe a surface that is not there.
        let bare = MaterialFile { kind: None, interior: None, ..m.clone() };
        if bare != MaterialFile::default() {
            bail!(
                "materials.{mname}: type = \"null\" is only a medium's boundary; it takes `interior` and no other key"
            );
        }
        return Ok(Material { name: mname.to_owned(), null_surface: true, ..Material::default() });
    }
    let conductor = conductor_from(m, &key)?;
    let default_r = if conductor == Conductor::Mirror { 0.0 } else { 1.0 };
    let material = Material {
        name: mname.to_owned(),
        albedo: non_negative3(&key("albedo"), m.albedo)?,
        reflectivity: finite(&key("reflectivity"), m.reflectivity.unwrap_or(default_r))?,
        transparency: finite(&key("transparency"), m.transparency)?,
        ior: finite(&key("ior"), m.ior)?,
        emission: non_negative3(&key("emission"), m.emission)?,
        two_sided: m.two_sided,
        roughness: unit_interval(&key("roughness"), m.roughness)?,
        roughness_v: m.roughness_v.map(|r| unit_interval(&key("roughness_v"), r)).transpose()?,
        conductor,
        coat: m.coat,
        coat_internal_reflections: m.coat_internal_reflections,
        microfacet: m.distribution,
        thin: m.thin,
        one_sided: m.one_sided,
        clearcoat: clearcoat_from(m, &key)?,
        attenuation: attenuation_from(m, &key)?,
        // Textures come from the scene's `albedo_texture` table below and from mesh files.
        ..Material::default()
    };
    if material.coat_internal_reflections && !material.coat {
        bail!("{} needs coat = true (it describes the coat of a plastic)", key("coat_internal_reflections"));
    }
    if material.albedo.max_element() > 1.0 {
        bail!("{} must be at most 1 per channel (energy conservation), got {:?}", key("albedo"), material.albedo);
    }
    if material.reflectivity < 0.0
        || material.transparency < 0.0
        || material.reflectivity + material.transparency > 1.0 + 1e-6
    {
        bail!(
            "materials.{mname}: reflectivity and transparency must be >= 0 with R + T <= 1, got R = {}, T = {}",
            material.reflectivity,
            material.transparency
        );
    }
    if material.ior <= 0.0 {
        bail!("{} must be > 0, got {}", key("ior"), material.ior);
    }
    if material.one_sided && material.transparency > 0.0 {
        bail!("{}: a one-sided material cannot be transparent (light it lets in must leave through its back), got transparency {}", key("one_sided"), material.transparency);
    }
    if material.attenuation.is_some() && material.transparency <= 0.0 {
        bail!("{} needs {} > 0: absorption happens inside a dielectric", key("attenuation_color"), key("transparency"));
    }
    // A path enters the inside by refracting through the surface: only a solid dielectric (or a
    // null boundary) has one to enter.
    if m.interior.is_some() && (material.transparency <= 0.0 || material.thin) {
        bail!(
            "{} needs {} > 0 and not thin (or type = \"null\"): a path enters the medium through the surface",
            key("interior"),
            key("transparency")
        );
    }
    Ok(material)
}

/// `attenuation_color` and `attenuation_distance`, given together: the share of white light left
/// after that distance inside, per channel in (0, 1] (0 would absorb everything at once; above 1
/// would amplify), and a finite distance > 0.
fn attenuation_from(m: &MaterialFile, key: &dyn Fn(&str) -> String) -> Result<Option<Attenuation>> {
    let (color, distance) = match (m.attenuation_color, m.attenuation_distance) {
        (None, None) => return Ok(None),
        (Some(color), Some(distance)) => {
            (vec3(&key("attenuation_color"), color)?, finite(&key("attenuation_distance"), distance)?)
        }
        (Some(_), None) => bail!("{} needs {}", key("attenuation_color"), key("attenuation_distance")),
        (None, Some(_)) => bail!("{} needs {}", key("attenuation_distance"), key("attenuation_color")),
    };
    if color.min_element() <= 0.0 || color.max_element() > 1.0 {
        bail!("{} must be in (0, 1] per channel, got {:?}", key("attenuation_color"), color.to_array());
    }
    if distance <= 0.0 {
        bail!("{} must be > 0, got {distance}", key("attenuation_distance"));
    }
    Ok(Some(Attenuation { color, distance }))
}

/// `clearcoat` (the factor) and `clearcoat_roughness`, each in [0, 1]; the roughness only with a
/// factor. A factor of 0 is kept (it renders exactly as no coat).
fn clearcoat_from(m: &MaterialFile, key: &dyn Fn(&str) -> String) -> Result<Option<Clearcoat>> {
    let factor = match (m.clearcoat, m.clearcoat_roughness) {
        (None, None) => return Ok(None),
        (None, Some(_)) => bail!("{} needs {}", key("clearcoat_roughness"), key("clearcoat")),
        (Some(factor), _) => unit_interval(&key("clearcoat"), factor)?,
    };
    let roughness = unit_interval(&key("clearcoat_roughness"), m.clearcoat_roughness.unwrap_or(0.0))?;
    Ok(Some(Clearcoat { factor, roughness, texture: None, roughness_texture: None }))
}

/// `[[spheres]]`, `[[quads]]` and `[[triangles]]`, in that order.
fn shapes_from(file: &SceneFile, material: &MaterialLookup) -> Result<Vec<Shape>> {
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
        let Array([a, b, c]) = t.vertices;
        let v = [vec3(&key, a)?, vec3(&key, b)?, vec3(&key, c)?];
        if (v[1] - v[0]).cross(v[2] - v[0]).length() == 0.0 {
            bail!("{key}: the triangle has no area");
        }
        shapes.push(Shape::Triangle { v, material: material(format!("triangles[{k}].material"), &t.material)? });
    }
    Ok(shapes)
}

/// Loads every `[[meshes]]` file and places it once, or at each of its instances.
fn place_meshes(
    scene: &mut Scene,
    meshes: &[MeshFile],
    material: &MaterialLookup,
    base: &Path,
    importer: &mut MeshImporter,
) -> Result<()> {
    for (k, m) in meshes.iter().enumerate() {
        let key = format!("meshes[{k}]");
        let override_material =
            m.material.as_ref().map(|name| material(format!("{key}.material"), name)).transpose()?;
        let outer = placement(&key, &m.placement())?;
        let path = resolve(base, &m.file);
        let sides = Sides { flip_normals: m.flip_normals, face_normals: m.face_normals };
        if m.instances.is_empty() {
            importer.place_part(scene, &path, m.shape_index, override_material, sides, outer)?;
        }
        for (j, p) in m.instances.iter().enumerate() {
            importer.place_part(
                scene,
                &path,
                m.shape_index,
                override_material,
                sides,
                placement(&format!("{key}.instances[{j}]"), p)? * outer,
            )?;
        }
    }
    Ok(())
}

/// The R lobe's Fresnel from `metal` or `eta` + `k` (absent: a perfect mirror).
fn conductor_from(m: &MaterialFile, key: &dyn Fn(&str) -> String) -> Result<Conductor> {
    match (&m.metal, m.eta, m.k) {
        (None, None, None) => Ok(Conductor::Mirror),
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            bail!("{} and eta/k both set the conductor's IOR: give one", key("metal"))
        }
        (Some(name), None, None) if name == "albedo" => Ok(Conductor::Albedo),
        (Some(name), None, None) => {
            let (eta, k) = metal(name).with_context(|| {
                let known: Vec<_> = METALS.iter().map(|(n, _, _)| *n).collect();
                format!("{}: unknown metal '{name}' (known: {}, albedo)", key("metal"), known.join(", "))
            })?;
            Ok(Conductor::Complex { eta, k })
        }
        (None, Some(_), None) => bail!("{} needs {} as well", key("eta"), key("k")),
        (None, None, Some(_)) => bail!("{} needs {} as well", key("k"), key("eta")),
        (None, Some(eta), Some(k)) => {
            let eta = vec3(&key("eta"), eta)?;
            if eta.min_element() <= 0.0 {
                bail!("{} must be > 0 per channel, got {eta:?}", key("eta"));
            }
            Ok(Conductor::Complex { eta, k: non_negative3(&key("k"), k)? })
        }
    }
}

fn integrator_from(i: &IntegratorFile) -> Result<Integrator> {
    if let Some(a) = i.absorption {
        if !(a.is_finite() && (0.0..1.0).contains(&a)) {
            bail!("integrator.absorption must be in [0, 1), got {a}");
        }
    }
    if i.max_bounces == 0 {
        bail!("integrator.max_bounces must be at least 1");
    }
    if let Some(c) = i.clamp {
        if !(c.is_finite() && c > 0.0) {
            bail!("integrator.clamp must be finite and > 0, got {c}");
        }
    }
    Ok(Integrator {
        rr_start: i.rr_start,
        absorption: i.absorption,
        nee: i.nee,
        max_bounces: i.max_bounces,
        sample_environment: i.sample_environment,
        clamp: i.clamp,
        sampler: i.sampler,
        light_selection: i.light_selection,
    })
}

/// A three-quarter view from above the largest face of the scene's world bounds, fitted to
/// them for its film (framing.rs); a camera at +z looking at the origin when the scene is empty.
fn framing_camera(scene: &Scene) -> Camera {
    let Some(bounds) = framing::scene_bounds(scene) else {
        return Camera::pinhole(Vec3::Z, Vec3::ZERO, Vec3::Y, framing::FRAMING_FOV_DEGREES);
    };
    let (azimuth, elevation) = framing::default_orbit(bounds);
    framing::orbit_camera(bounds, azimuth, elevation, scene.film.width as f32 / scene.film.height as f32)
}

/// Object-to-world transform: scale, then rotate about x, y and z (degrees), then translate.
fn placement(key: &str, p: &Placement) -> Result<Mat4> {
    let scale = match p.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(finite(&format!("{key}.scale"), s)?),
        Some(Scale::PerAxis(s)) => vec3(&format!("{key}.scale"), s)?,
    };
    if scale.x * scale.y * scale.z == 0.0 {
        bail!("{key}.scale must not be zero");
    }
    let r = vec3(&format!("{key}.rotate"), p.rotate)?;
    let rotation = Quat::from_euler(glam::EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians());
    Ok(Mat4::from_scale_rotation_translation(scale, rotation, vec3(&format!("{key}.translate"), p.translate)?))
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

/// Folder of caustica's shared test data: `$CAUSTICA_DATA`, or `../shared/data` from the
/// working directory.
pub fn data_dir() -> PathBuf {
    std::env::var_os("CAUSTICA_DATA").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("../shared/data"))
}

/// What `render --confine` lets a scene read: files inside the scene file's folder and inside the
/// shared data folder ([`data_dir`], where `$CAUSTICA_DATA/` paths lead), after `..` and symbolic
/// links are resolved.
pub fn confinement(scene_path: &Path) -> InputFiles {
    let folder = scene_path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    InputFiles::confined_to([folder, data_dir().as_path()])
}

/// A path in a scene file: absolute, relative to the scene file, or `$CAUSTICA_DATA/...` inside
/// the shared data folder.
fn resolve(base: &Path, file: &str) -> PathBuf {
    if let Some(rest) = file.strip_prefix("$CAUSTICA_DATA/") {
        return data_dir().join(rest);
    }
    let p = Path::new(file);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}
