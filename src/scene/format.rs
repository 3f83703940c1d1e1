//! The TOML scene file as written by people: serde structs that reject unknown keys. `scene::load`
//! turns them into a validated `Scene`.

use serde::Deserialize;

#[derive(Deserialize, Debug)]
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
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov: f32,
    /// Thin-lens radius in scene units; 0 is a pinhole.
    #[serde(default)]
    pub aperture: f32,
    /// Distance of the plane in focus along the viewing axis; absent: the distance to look_at.
    pub focus_distance: Option<f32>,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    40.0
}

#[derive(Deserialize, Debug)]
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
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LightSelection {
    /// In proportion to each light's power (an alias table).
    Power,
    /// Every light equally likely (for comparisons).
    Uniform,
}

/// Pixel reconstruction filter, importance sampled: each sample's film position is drawn from it.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// Uniform over the pixel.
    Box,
    /// Triangle of radius 1 pixel per axis.
    Tent,
    /// Gaussian of standard deviation 0.5 pixel.
    Gaussian,
}

#[derive(Deserialize, Debug)]
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
        Self { rr_start: 4, absorption: None, nee: true, max_bounces: 1024, sample_environment: true, clamp: None, sampler: Sampler::Sobol, light_selection: LightSelection::Power }
    }
}

/// The random numbers behind each sample's decisions (shaders/rng.glsl).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Padded Owen-scrambled Sobol: each decision stratified across a pixel's samples.
    Sobol,
    /// An independent pseudo-random stream per sample.
    Independent,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialFile {
    pub albedo: [f32; 3],
    /// R; absent: 0, or 1 when `metal` or `eta`/`k` make the material a conductor.
    pub reflectivity: Option<f32>,
    pub transparency: f32,
    pub ior: f32,
    pub emission: [f32; 3],
    pub two_sided: bool,
    /// Perceptual GGX roughness of the R and T lobes and the coat, in [0, 1].
    pub roughness: f32,
    /// A named conductor for the R lobe (see `optics::METALS`), or "albedo" for Schlick's form
    /// with the albedo as F0.
    pub metal: Option<String>,
    /// Complex IOR eta + i k of the R lobe (both or neither; not with `metal`).
    pub eta: Option<[f32; 3]>,
    pub k: Option<[f32; 3]>,
    /// The base is a plastic: the albedo under a dielectric coat of index `ior`.
    pub coat: bool,
}

impl Default for MaterialFile {
    fn default() -> Self {
        Self {
            albedo: [0.8; 3],
            reflectivity: None,
            transparency: 0.0,
            ior: 1.5,
            emission: [0.0; 3],
            two_sided: false,
            roughness: 0.0,
            metal: None,
            eta: None,
            k: None,
            coat: false,
        }
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SphereFile {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: String,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct QuadFile {
    pub origin: [f32; 3],
    pub edge_u: [f32; 3],
    pub edge_v: [f32; 3],
    pub material: String,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct TriangleFile {
    pub vertices: [[f32; 3]; 3],
    pub material: String,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    /// OBJ (with its MTL), PLY, glTF or GLB.
    pub file: String,
    /// Replaces every material the file defines.
    pub material: Option<String>,
    /// Where the file's meshes go (after the file's own node transforms). Listed here rather than
    /// as a flattened `Placement`, which serde cannot combine with deny_unknown_fields.
    #[serde(default)]
    pub translate: [f32; 3],
    #[serde(default)]
    pub scale: Option<Scale>,
    #[serde(default)]
    pub rotate: [f32; 3],
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

#[derive(Deserialize, Debug, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    #[serde(default)]
    pub translate: [f32; 3],
    /// Uniform scale, or per axis.
    #[serde(default)]
    pub scale: Option<Scale>,
    /// Euler angles in degrees, applied about x, then y, then z.
    #[serde(default)]
    pub rotate: [f32; 3],
}

#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentFile {
    /// Constant sky radiance (when no map is given).
    pub color: Option<[f32; 3]>,
    /// Debevec angular-map light probe (PFM).
    pub probe: Option<String>,
    /// Equirectangular (lat-long) map, PFM or EXR.
    pub latlong: Option<String>,
    #[serde(default = "one")]
    pub intensity: f32,
    /// Degrees about +y.
    #[serde(default)]
    pub rotation: f32,
}

fn one() -> f32 {
    1.0
}
