//! The TOML scene file as written by people: serde structs that reject unknown keys and arrays of
//! the wrong length. `scene::load` turns them into a validated `Scene`.

use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;
use std::marker::PhantomData;

/// A TOML array of exactly `N` values. Serde's own `[T; N]` reads N elements and never looks at
/// the rest, so `position = [0.0, 1.0, 3.9, 7.0]` was silently taken as a 3-vector; every
/// fixed-length array of the format is read through this type instead, which refuses (with the
/// expected length, the key and the line) one element too many as firmly as one too few.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Array<T, const N: usize>(pub [T; N]);

/// Zeros (an origin, no rotation).
impl<T: Default, const N: usize> Default for Array<T, N> {
    fn default() -> Self {
        Array(std::array::from_fn(|_| T::default()))
    }
}

/// Three numbers: a point, a direction, a colour, angles, per-axis factors.
pub type Triple = Array<f32, 3>;

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Array<T, N> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_seq(ArrayVisitor(PhantomData))
    }
}

/// Written as a plain TOML array (for `caustica convert`).
impl<T: Serialize, const N: usize> Serialize for Array<T, N> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.as_slice().serialize(serializer)
    }
}

struct ArrayVisitor<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for ArrayVisitor<T, N> {
    type Value = Array<T, N>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "an array of exactly {N} elements")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut values = Vec::with_capacity(N);
        while values.len() < N {
            match seq.next_element()? {
                Some(value) => values.push(value),
                None => return Err(de::Error::invalid_length(values.len(), &self)),
            }
        }
        let mut extra = 0;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            extra += 1;
        }
        match values.try_into() {
            Ok(array) if extra == 0 => Ok(Array(array)),
            _ => Err(de::Error::invalid_length(N + extra, &self)),
        }
    }
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: CameraFile,
    #[serde(default)]
    pub film: FilmFile,
    #[serde(default)]
    pub integrator: IntegratorFile,
    #[serde(default)]
    pub materials: std::collections::BTreeMap<String, MaterialFile>,
    #[serde(default)]
    pub spheres: Vec<SphereFile>,
    #[serde(default)]
    pub quads: Vec<QuadFile>,
    #[serde(default)]
    pub triangles: Vec<TriangleFile>,
    #[serde(default)]
    pub meshes: Vec<MeshFile>,
    pub environment: Option<EnvironmentFile>,
    /// Lights without a surface: point, spot and directional (radiometric units).
    #[serde(default)]
    pub lights: Vec<LightFile>,
    /// Participating media (fog, smoke, milk), named for the materials' `interior` and the
    /// camera's `medium` (scene/medium.rs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub media: Vec<MediumFile>,
    /// Meshes an importer found written in its scene and keeps as meshes (they need texture
    /// coordinates, which `[[triangles]]` lack). No key of the TOML format: `caustica convert`
    /// writes each as a PLY file and lists it in `[[meshes]]`.
    #[serde(skip)]
    pub inline_meshes: Vec<InlineMesh>,
}

/// A mesh written in an imported scene: the ASCII PLY text of its world-space triangles, read as
/// the PLY file `convert` writes of it would be, and its material.
#[derive(Debug, Clone)]
pub struct InlineMesh {
    /// Where it was written (`scene.pbrt:12`), which names it in messages.
    pub name: String,
    pub ply: String,
    pub material: String,
}

impl SceneFile {
    /// A scene with this camera, film and integrator and nothing in it yet: what the importers
    /// fill.
    pub fn empty(camera: CameraFile, film: FilmFile, integrator: IntegratorFile) -> Self {
        Self {
            camera,
            film,
            integrator,
            materials: Default::default(),
            spheres: vec![],
            quads: vec![],
            triangles: vec![],
            meshes: vec![],
            environment: None,
            lights: vec![],
            media: vec![],
            inline_meshes: vec![],
        }
    }
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: Triple,
    pub look_at: Triple,
    #[serde(default = "default_up")]
    pub up: Triple,
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov: f32,
    /// Thin-lens radius in scene units; 0 is a pinhole.
    #[serde(default)]
    pub aperture: f32,
    /// Distance of the plane in focus along the viewing axis; absent: the distance to look_at.
    pub focus_distance: Option<f32>,
    /// The `[[media]]` entry the camera is in (fog that fills the scene); absent: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<String>,
}

fn default_up() -> Triple {
    Array([0.0, 1.0, 0.0])
}
fn default_fov() -> f32 {
    40.0
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields, default)]
pub struct FilmFile {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub filter: Filter,
}

impl Default for FilmFile {
    fn default() -> Self {
        Self { width: 512, height: 512, spp: 64, filter: Filter::Box }
    }
}

/// How next-event estimation picks which area light to sample.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LightSelection {
    /// By a light tree (src/render/light_tree.rs): each light in proportion to an estimate of
    /// what it gives the shading point (power, distance, emission cone), directional lights
    /// beside it.
    Bvh,
    /// In proportion to each light's power (an alias table).
    Power,
    /// Every light equally likely (for comparisons).
    Uniform,
}

/// Pixel reconstruction filter, importance sampled: each sample's film position is drawn from it.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// Uniform over the pixel.
    Box,
    /// Triangle of radius 1 pixel per axis.
    Tent,
    /// Gaussian of standard deviation 0.5 pixel.
    Gaussian,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields, default)]
pub struct IntegratorFile {
    /// Bounces always traced before Russian roulette starts.
    pub rr_start: u32,
    /// Fixed absorption probability per bounce past rr_start; absent: derived from the throughput.
    pub absorption: Option<f32>,
    /// Next-event estimation with MIS; false gives pure BSDF sampling.
    pub nee: bool,
    /// Safety cap on the path length; roulette ends paths long before it.
    pub max_bounces: u32,
    /// Next-event estimation samples the environment map too (by its radiance); false leaves
    /// the map to BSDF sampling alone, as before it was importance sampled (for comparisons).
    pub sample_environment: bool,
    /// Largest radiance component a sample may carry (biased; for previews); absent: no clamp.
    pub clamp: Option<f32>,
    /// Where the random numbers of a sample come from.
    pub sampler: Sampler,
    /// How next-event estimation picks an area light.
    pub light_selection: LightSelection,
}

impl Default for IntegratorFile {
    fn default() -> Self {
        Self {
            rr_start: 4,
            absorption: None,
            nee: true,
            max_bounces: 1024,
            sample_environment: true,
            clamp: None,
            sampler: Sampler::Sobol,
            light_selection: LightSelection::Bvh,
        }
    }
}

/// The random numbers behind each sample's decisions (shaders/rng.glsl).
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Padded Owen-scrambled Sobol: each decision stratified across a pixel's samples.
    Sobol,
    /// An independent pseudo-random stream per sample.
    Independent,
}

#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialFile {
    pub albedo: Triple,
    /// R; absent: 0, or 1 when `metal` or `eta`/`k` make the material a conductor.
    pub reflectivity: Option<f32>,
    pub transparency: f32,
    pub ior: f32,
    pub emission: Triple,
    pub two_sided: bool,
    /// Perceptual GGX roughness of the R and T lobes and the coat, in [0, 1]; along the surface's
    /// u direction where `roughness_v` differs.
    pub roughness: f32,
    /// Perceptual roughness along the surface's v direction, in [0, 1] (alpha_v = roughness_v^2):
    /// anisotropic lobes. Absent: `roughness` (isotropic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roughness_v: Option<f32>,
    /// A named conductor for the R lobe (see `optics::METALS`), or "albedo" for Schlick's form
    /// with the albedo as F0.
    pub metal: Option<String>,
    /// Complex IOR eta + i k of the R lobe (both or neither; not with `metal`).
    pub eta: Option<Triple>,
    pub k: Option<Triple>,
    /// The base is a plastic: the albedo under a dielectric coat of index `ior`.
    pub coat: bool,
    /// The coat's internal reflections scatter off the base again: albedo rho acts as
    /// rho (1 - Fin) / (1 - rho Fin), Fin the coat's average internal reflectance (darker and more
    /// saturated; Mitsuba's `nonlinear`, pbrt's `coateddiffuse`). Only with `coat`.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub coat_internal_reflections: bool,
    /// The microfacet distribution of the rough R and T lobes and of the coat.
    pub distribution: Microfacet,
    /// The T lobe is a thin sheet (a window pane, a soap film) rather than the surface of a solid:
    /// it reflects 2F / (1 + F) and passes the rest straight through, smooth whatever `roughness`.
    pub thin: bool,
    /// The surface scatters on its front side only and is black from behind (Mitsuba's BSDFs
    /// without `twosided`); not with `transparency`, whose light must leave through the back.
    pub one_sided: bool,
    /// A texture whose colour multiplies `albedo` (on meshes, which carry texture coordinates).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub albedo_texture: Option<AlbedoTextureFile>,
    /// Beer-Lambert absorption inside a dielectric (transparency > 0): the share of white light
    /// left, per channel in (0, 1], after travelling `attenuation_distance` inside. Both or neither.
    pub attenuation_color: Option<Triple>,
    pub attenuation_distance: Option<f32>,
    /// A clear coat over the whole material (glTF's `KHR_materials_clearcoat`): a dielectric layer
    /// of index 1.5 that reflects `clearcoat` x Fresnel of the light; the factor in [0, 1].
    /// Absent: no coat.
    pub clearcoat: Option<f32>,
    /// The clear coat's perceptual GGX roughness in [0, 1] (default 0, smooth); only with
    /// `clearcoat`.
    pub clearcoat_roughness: Option<f32>,
    /// How much of the surface is there, in [0, 1] (times `opacity_texture`'s): a ray meets it
    /// with that probability (Mitsuba's `mask`, glTF's BLEND). Meshes only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opacity: Option<f32>,
    /// An image whose luminance is the opacity (its alpha channel is not read, as in Mitsuba).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opacity_texture: Option<ImageTextureFile>,
    /// A tangent-space normal map, (normal + 1) / 2 per texel, in Mitsuba's frame: x along the
    /// direction u grows, y along cross(normal, x), z the interpolated normal. Meshes with vertex
    /// normals and texture coordinates only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal_texture: Option<ImageTextureFile>,
    /// "null": the surface is no surface at all, only where the `interior` medium begins (light
    /// passes it unchanged); absent: the material the other keys describe.
    #[serde(rename = "type", skip_serializing_if = "Option::is_none")]
    pub kind: Option<MaterialKind>,
    /// The `[[media]]` entry that fills the inside of closed shapes of this material (behind their
    /// geometric normal), entered where a path refracts or passes through. Absent: the inside is
    /// empty space (or Beer-Lambert absorption, `attenuation_color`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interior: Option<String>,
}

/// A material's `type`.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum MaterialKind {
    /// An index-matched boundary of a medium: no scattering, no refraction.
    Null,
}

/// A `[[media]]` entry: a participating medium, homogeneous or heterogeneous (coefficients per
/// world unit, RGB). Its coefficients are `sigma_a` and `sigma_s`, or `sigma_t` and `albedo`
/// (sigma_s = albedo sigma_t), each times `scale` and, heterogeneous, times the density grid.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MediumFile {
    pub name: String,
    /// "homogeneous" or "heterogeneous" (with `density`).
    #[serde(rename = "type")]
    pub kind: MediumKind,
    /// A heterogeneous medium's density grid: a Mitsuba `.vol` file of one channel, whose values
    /// (trilinearly interpolated between cell centres, 0 outside its box) scale the coefficients.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<String>,
    /// The world box [min, max] the density grid fills; absent: the box the `.vol` file gives.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds: Option<Array<Triple, 2>>,
    /// Absorption coefficient per world unit, per channel, >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_a: Option<Triple>,
    /// Scattering coefficient per world unit, per channel, >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_s: Option<Triple>,
    /// Extinction coefficient per world unit (sigma_a + sigma_s), per channel, >= 0; with `albedo`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_t: Option<Triple>,
    /// Single-scattering albedo sigma_s / sigma_t, per channel in [0, 1]; with `sigma_t`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<Triple>,
    /// Multiplies the coefficients (a unit change: 100 for coefficients per cm in a scene in m).
    #[serde(default = "one")]
    pub scale: f32,
    /// The phase function: "isotropic" (default) or "hg", Henyey-Greenstein (with `g`).
    #[serde(default)]
    pub phase: PhaseKind,
    /// Henyey-Greenstein's mean cosine, in (-1, 1): > 0 forward scattering, < 0 backward.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g: Option<f32>,
}

/// A medium's `type`.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum MediumKind {
    /// The same coefficients everywhere.
    Homogeneous,
    /// The coefficients scaled by a density grid.
    Heterogeneous,
}

/// A medium's `phase`.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum PhaseKind {
    /// Every direction alike.
    #[default]
    Isotropic,
    /// Henyey-Greenstein of mean cosine `g` (Mitsuba's and pbrt's "hg").
    Hg,
}

/// A material's image texture of data (opacity, normals), read at texture coordinates mapped by
/// `to_uv` as `albedo_texture`'s are; a material's textures must share one `to_uv`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageTextureFile {
    /// A PNG or JPEG image.
    pub file: String,
    /// As `albedo_texture.to_uv`. Absent: the identity.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub to_uv: Option<Array<Triple, 2>>,
    /// How the file stores its values: "linear" or "srgb" (decoded before use). Absent: "srgb" for
    /// `opacity_texture` (an image as painted), "linear" for `normal_texture` (data).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub encoding: Option<Encoding>,
}

/// How an image stores its values.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    Linear,
    Srgb,
}

/// The microfacet distribution of a material's rough lobes (shaders/microfacet.glsl).
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Microfacet {
    /// Trowbridge-Reitz: long tails (glTF's and pbrt's).
    #[default]
    Ggx,
    /// Beckmann: a Gaussian of slopes (Mitsuba's default).
    Beckmann,
}

/// A material's albedo texture: an image or Mitsuba's checkerboard, read at texture coordinates
/// mapped by `to_uv`. (0, 0) is the image's top-left corner; outside [0, 1] it tiles.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AlbedoTextureFile {
    /// A PNG or JPEG image of sRGB colour.
    pub file: Option<String>,
    /// Two linear RGB colours: the first where frac(u) and frac(v) are both above 1/2 or both
    /// not, the second elsewhere (Mitsuba's `checkerboard`, one period across [0, 1]).
    pub checkerboard: Option<Array<Triple, 2>>,
    /// The rows [[a, b, c], [d, e, f]] of an affine map: the texture is read at
    /// (a u + b v + c, d u + e v + f). Absent: the identity.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub to_uv: Option<Array<Triple, 2>>,
}

impl Default for MaterialFile {
    fn default() -> Self {
        Self {
            albedo: Array([0.8; 3]),
            reflectivity: None,
            transparency: 0.0,
            ior: 1.5,
            emission: Array([0.0; 3]),
            two_sided: false,
            roughness: 0.0,
            roughness_v: None,
            metal: None,
            eta: None,
            k: None,
            coat: false,
            coat_internal_reflections: false,
            distribution: Microfacet::Ggx,
            thin: false,
            one_sided: false,
            albedo_texture: None,
            attenuation_color: None,
            attenuation_distance: None,
            clearcoat: None,
            clearcoat_roughness: None,
            opacity: None,
            opacity_texture: None,
            normal_texture: None,
            kind: None,
            interior: None,
        }
    }
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SphereFile {
    pub center: Triple,
    pub radius: f32,
    pub material: String,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct QuadFile {
    pub origin: Triple,
    pub edge_u: Triple,
    pub edge_v: Triple,
    pub material: String,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TriangleFile {
    pub vertices: Array<Triple, 3>,
    pub material: String,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    /// OBJ (with its MTL), PLY, glTF or GLB.
    pub file: String,
    /// Replaces every material the file defines.
    pub material: Option<String>,
    /// Which mesh of a Mitsuba `.serialized` file (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape_index: Option<u32>,
    /// The back of every triangle becomes its front (the normals turn round; Mitsuba's
    /// `flip_normals`).
    #[serde(default, skip_serializing_if = "is_false")]
    pub flip_normals: bool,
    /// Shade flat, with each triangle's own normal, ignoring the file's vertex normals (Mitsuba's
    /// `face_normals`).
    #[serde(default, skip_serializing_if = "is_false")]
    pub face_normals: bool,
    /// Where the file's meshes go (after the file's own node transforms). Listed here rather than
    /// as a flattened `Placement`, which serde cannot combine with deny_unknown_fields.
    #[serde(default)]
    pub translate: Triple,
    #[serde(default)]
    pub scale: Option<Scale>,
    #[serde(default)]
    pub rotate: Triple,
    /// Several placements of the same geometry, each applied after the entry's own translate,
    /// scale and rotate (which can thus size and centre the model once); stored once on the GPU.
    #[serde(default)]
    pub instances: Vec<Placement>,
}

impl MeshFile {
    pub fn placement(&self) -> Placement {
        Placement { translate: self.translate, scale: self.scale, rotate: self.rotate }
    }
}

#[derive(Deserialize, Serialize, Debug, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    #[serde(default)]
    pub translate: Triple,
    /// Uniform scale, or per axis.
    #[serde(default)]
    pub scale: Option<Scale>,
    /// Euler angles in degrees, applied about x, then y, then z.
    #[serde(default)]
    pub rotate: Triple,
}

#[derive(Debug, Clone, Copy)]
pub enum Scale {
    Uniform(f32),
    PerAxis(Triple),
}

impl Serialize for Scale {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Scale::Uniform(s) => s.serialize(serializer),
            Scale::PerAxis(s) => s.serialize(serializer),
        }
    }
}

/// A number or three. Written out rather than `#[serde(untagged)]`, whose only error is "did not
/// match any variant", so that `scale = [1, 2]` says what length it wants.
impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ScaleVisitor;
        impl<'de> Visitor<'de> for ScaleVisitor {
            type Value = Scale;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a number or an array of exactly 3 numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f32))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f32))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f32))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Scale, A::Error> {
                ArrayVisitor(PhantomData).visit_seq(seq).map(Scale::PerAxis)
            }
        }
        deserializer.deserialize_any(ScaleVisitor)
    }
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentFile {
    /// Constant sky radiance (when no map is given).
    pub color: Option<Triple>,
    /// Debevec angular-map light probe (PFM).
    pub probe: Option<String>,
    /// Equirectangular (lat-long) map, PFM, EXR or Radiance .hdr.
    pub latlong: Option<String>,
    /// pbrt-v4's equal-area octahedral map (square PFM, EXR or Radiance .hdr), resampled to a lat-long map on
    /// load (`scene::equal_area_map`).
    pub octahedral: Option<String>,
    /// With `octahedral` or `latlong`: the world directions of the map's x, y and z axes,
    /// orthonormal (absent: the world's own axes). A lat-long map is resampled to them on load.
    pub axes: Option<Array<Triple, 3>>,
    #[serde(default = "one")]
    pub intensity: f32,
    /// Degrees about +y.
    #[serde(default)]
    pub rotation: f32,
}

/// No sky at all, at intensity 1: what importers fill in the one field they set.
impl Default for EnvironmentFile {
    fn default() -> Self {
        EnvironmentFile {
            color: None,
            probe: None,
            latlong: None,
            octahedral: None,
            axes: None,
            intensity: 1.0,
            rotation: 0.0,
        }
    }
}

fn is_false(b: &bool) -> bool {
    !b
}

fn one() -> f32 {
    1.0
}

/// A `[[lights]]` entry, told apart by its `type`.
#[derive(Deserialize, Serialize, Debug)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum LightFile {
    Point(PointLightFile),
    Spot(SpotLightFile),
    Directional(DirectionalLightFile),
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct PointLightFile {
    pub position: Triple,
    /// Radiant intensity, W/sr: a surface at distance d facing it receives intensity / d^2.
    pub intensity: Triple,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SpotLightFile {
    pub position: Triple,
    /// A point on the axis.
    pub look_at: Triple,
    /// Radiant intensity on the axis, W/sr.
    pub intensity: Triple,
    /// Degrees from the axis where the light ends.
    pub cone_angle: f32,
    /// Degrees from the axis where the falloff begins (full intensity inside); between the two the
    /// intensity falls linearly in the angle, as Mitsuba 3's spot.
    pub falloff_start: f32,
}

#[derive(Deserialize, Serialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct DirectionalLightFile {
    /// The direction the light travels.
    pub direction: Triple,
    /// W/m^2 on a surface facing the light.
    pub irradiance: Triple,
    /// Degrees; > 0 makes it a disk of uniform radiance filling that cone (the sun is 0.53).
    #[serde(default)]
    pub angular_diameter: f32,
}
