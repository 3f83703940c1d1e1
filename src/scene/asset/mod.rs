//! Mesh assets (OBJ + MTL, PLY, glTF 2.0, Mitsuba's serialized meshes) loaded into one GPU-agnostic form: meshes, materials,
//! textures, instances and an optional camera. The renderer turns an [`Asset`] into GPU buffers;
//! nothing here knows about Vulkan.

mod gltf_accessors;
mod gltf_file;
mod gltf_skin;
mod obj;
mod ply;
mod serialized;
mod tangents;
mod texture;

pub use texture::{downsample_to_fit, load_texture, srgb_to_linear, MAX_TEXTURE_BYTES};

use super::{
    Alpha, AlphaMode, Attenuation, Clearcoat, Conductor, Light, Material, MetallicRoughness, NormalMap, TextureMaps,
};
use crate::input_file::{InputError, InputFiles};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};

/// Everything a mesh file contributes to a scene.
#[derive(Debug, Clone, Default)]
pub struct Asset {
    pub meshes: Vec<MeshData>,
    /// The scene's material model, with texture indices into `textures` (mesh.rs rebases them
    /// into the scene's).
    pub materials: Vec<Material>,
    pub textures: Vec<TextureImage>,
    /// Placements of meshes: (index into meshes, object-to-world transform). OBJ and PLY give one
    /// instance of their single mesh with the identity; glTF gives one per node that has a mesh,
    /// with the node hierarchy's transforms composed (parent * child).
    pub instances: Vec<(usize, Mat4)>,
    /// glTF only: the first camera found in the node hierarchy, in world space.
    pub camera: Option<AssetCamera>,
    /// glTF only: the `KHR_lights_punctual` lights of the node hierarchy, in world space.
    pub lights: Vec<Light>,
    /// Zero-area or degenerate triangles dropped while loading (for a note on stderr by the caller).
    pub dropped_triangles: usize,
}

/// One indexed triangle mesh in object space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    /// Empty, or exactly one unit vector per position (empty: the renderer uses flat normals).
    pub normals: Vec<Vec3>,
    /// Empty, or exactly one per position. (0, 0) is the top-left corner of a texture (the glTF
    /// convention); OBJ and PLY store v upwards, so their v is flipped to 1 - v on load.
    pub uvs: Vec<Vec2>,
    /// Empty, or exactly one per position: the unit tangent (along growing u) and the bitangent's
    /// sign in w, as glTF's TANGENT; from the file, or MikkTSpace (tangents.rs) for meshes with a
    /// normal-mapped material.
    pub tangents: Vec<Vec4>,
    /// Empty, or exactly one per position: a linear RGB colour that multiplies the base colour
    /// of the vertex's material (glTF's COLOR_0; white where a primitive has none).
    pub colors: Vec<Vec3>,
    /// Indices into positions, counter-clockwise = front.
    pub triangles: Vec<[u32; 3]>,
    /// One per triangle: index into [`Asset::materials`].
    pub triangle_materials: Vec<u32>,
}

/// An 8-bit RGBA texture as stored in the file, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureImage {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
    /// RGB is sRGB-encoded colour (albedo); false: linear data (glTF metallic-roughness).
    pub srgb: bool,
    /// How lookups outside [0, 1] find texels, along u and along v (a glTF sampler's wrapS and
    /// wrapT).
    pub wrap: [Wrap; 2],
}

/// What a texture shows outside [0, 1] along one axis (glTF's sampler wrap modes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The texture tiles (glTF REPEAT, and every texture of OBJ files).
    #[default]
    Repeat,
    /// The edge texels extend (CLAMP_TO_EDGE).
    ClampToEdge,
    /// Every other tile is mirrored (MIRRORED_REPEAT).
    MirroredRepeat,
}

/// A perspective camera in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssetCamera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub yfov_degrees: f32,
    /// Width / height, when the file gives one.
    pub aspect: Option<f32>,
}

/// Every way loading can fail; the message always starts with the file's path.
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    /// The file itself could not be read (missing, not a regular file, over its size cap, outside
    /// `--confine`).
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error("{}: unsupported mesh format '{extension}' (expected .obj, .ply, .gltf, .glb or .serialized)", path.display())]
    UnsupportedExtension { path: PathBuf, extension: String },
}

impl AssetError {
    fn invalid(path: &Path, message: impl Into<String>) -> Self {
        AssetError::Invalid { path: path.to_owned(), message: message.into() }
    }
}

/// Loads a mesh file from anywhere; see [`load_asset_from`].
pub fn load_asset(path: &Path) -> Result<Asset, AssetError> {
    load_asset_from(&InputFiles::anywhere(), path)
}

/// Loads a mesh file, choosing the format by its extension (case-insensitive). It and every file
/// it names (MTL libraries, textures, glTF buffers and images) are read through `files`. A file
/// that ends up without a single triangle is an error: there would be nothing to render.
pub fn load_asset_from(files: &InputFiles, path: &Path) -> Result<Asset, AssetError> {
    load_asset_part(files, path, None)
}

/// As [`load_asset_from`], for one of the meshes of a file that holds several: `shape_index`
/// picks a mesh of a Mitsuba `.serialized` file (absent: the first) and is an error for any other
/// format.
pub fn load_asset_part(files: &InputFiles, path: &Path, shape_index: Option<u32>) -> Result<Asset, AssetError> {
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if shape_index.is_some() && extension != "serialized" {
        return Err(AssetError::invalid(path, "shape_index picks a mesh of a Mitsuba .serialized file only"));
    }
    let asset = match extension.as_str() {
        "obj" => obj::load(files, path)?,
        "ply" => ply::load(files, path)?,
        "gltf" | "glb" => gltf_file::load(files, path)?,
        "serialized" => serialized::load(files, path, shape_index.unwrap_or(0))?,
        _ => return Err(AssetError::UnsupportedExtension { path: path.to_owned(), extension }),
    };
    let instanced_triangles: usize =
        asset.instances.iter().map(|&(mesh, _)| asset.meshes.get(mesh).map_or(0, |m| m.triangles.len())).sum();
    if instanced_triangles == 0 {
        return Err(AssetError::invalid(path, "no triangles to render"));
    }
    let mut asset = asset;
    add_tangents(path, &mut asset);
    Ok(asset)
}

/// The mesh of an ASCII or binary PLY held in memory (an importer's mesh written in its scene,
/// which `caustica convert` writes out as this very file), read exactly as a PLY file is;
/// `name` stands for the file in messages.
pub fn load_ply_bytes(bytes: &[u8], name: &Path) -> Result<Asset, AssetError> {
    ply::parse(bytes, name)
}

/// Gives every mesh with a normal-mapped material the tangents its map is read along: MikkTSpace's
/// (tangents.rs) where the file has none. A mesh without normals or texture coordinates has no
/// tangent frame: its normal maps are ignored, with a note on stderr.
fn add_tangents(path: &Path, asset: &mut Asset) {
    let normal_mapped: Vec<bool> = asset.materials.iter().map(|m| m.maps.normal.is_some()).collect();
    for (k, mesh) in asset.meshes.iter_mut().enumerate() {
        if mesh.triangle_materials.iter().any(|&m| normal_mapped[m as usize]) {
            give_tangents(path, k, mesh, "its normal maps are ignored");
        }
    }
}

/// Gives every mesh of `asset` tangents, for the anisotropic material that replaces the file's:
/// its lobes' x axis is the surface's u direction, MikkTSpace's tangent. A mesh without normals
/// or texture coordinates keeps an arbitrary frame about the normal (as Mitsuba's
/// coordinate_system(n) for meshes without texture coordinates), with a note on stderr.
pub fn add_anisotropy_tangents(path: &Path, asset: &mut Asset) {
    for (k, mesh) in asset.meshes.iter_mut().enumerate() {
        give_tangents(path, k, mesh, "its anisotropic material is oriented arbitrarily about the normal");
    }
}

/// MikkTSpace tangents for mesh `k` unless it has tangents; where it cannot have them, a warning
/// (the log) naming what is missing and, in `consequence`, what that does.
fn give_tangents(path: &Path, k: usize, mesh: &mut MeshData, consequence: &str) {
    if let Err(missing) = ensure_tangents(mesh) {
        log::warn!("caustica: {}: mesh {k} has no {missing}: {consequence}", path.display());
    }
}

/// Gives `mesh` MikkTSpace tangents (tangents.rs) unless it has some; the error names what it
/// lacks for them.
pub fn ensure_tangents(mesh: &mut MeshData) -> Result<(), &'static str> {
    if !mesh.tangents.is_empty() {
        return Ok(());
    }
    match (mesh.normals.is_empty(), mesh.uvs.is_empty()) {
        (true, true) => Err("vertex normals and texture coordinates"),
        (true, false) => Err("vertex normals"),
        (false, true) => Err("texture coordinates"),
        (false, false) if tangents::generate(mesh) => Ok(()),
        (false, false) => Err("a tangent frame MikkTSpace can build"),
    }
}

/// Wraps a single object-space mesh (OBJ, PLY) as an asset with one identity instance.
fn single_mesh_asset(
    mesh: MeshData,
    materials: Vec<Material>,
    textures: Vec<TextureImage>,
    dropped_triangles: usize,
) -> Asset {
    Asset {
        meshes: vec![mesh],
        materials,
        textures,
        instances: vec![(0, Mat4::IDENTITY)],
        camera: None,
        lights: Vec::new(),
        dropped_triangles,
    }
}

impl MeshData {
    /// Removes triangles with repeated corners or zero (or non-finite) area, which only cost
    /// BVH nodes and can produce NaN normals; returns how many were removed.
    /// Indices must already be checked against `positions`.
    fn drop_degenerate(&mut self) -> usize {
        let before = self.triangles.len();
        let positions = &self.positions;
        let (triangles, materials) = self
            .triangles
            .iter()
            .zip(&self.triangle_materials)
            .filter(|(&[a, b, c], _)| {
                let [a, b, c] = [a, b, c].map(|i| positions[i as usize]);
                let area2 = (b - a).cross(c - a).length_squared();
                area2 > 0.0 && area2.is_finite()
            })
            .map(|(&triangle, &material)| (triangle, material))
            .unzip();
        self.triangles = triangles;
        self.triangle_materials = materials;
        before - self.triangles.len()
    }
}

/// Normalized copies of per-vertex normals, or nothing when any of them is zero or non-finite:
/// one bad normal would make shading wrong, and flat normals are always correct.
fn unit_normals(normals: &[Vec3]) -> Vec<Vec3> {
    let unit: Vec<Vec3> = normals.iter().map(|n| n.normalize_or_zero()).collect();
    if unit.contains(&Vec3::ZERO) {
        Vec::new()
    } else {
        unit
    }
}

#[cfg(test)]
use crate::test_files::{temp_dir as test_dir, write_file, write_files, WrittenFiles};

/// A file of the shared real-data set ($CAUSTICA_DATA, default ../shared/data), or `None` with a
/// SKIPPED note when it is not there (the data is not part of the repository).
#[cfg(test)]
fn real_data(relative: &str) -> Option<PathBuf> {
    let root = std::env::var("CAUSTICA_DATA")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data").to_owned());
    let path = Path::new(&root).join(relative);
    if path.is_file() {
        Some(path)
    } else {
        println!("SKIPPED: {} not found", path.display());
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_is_named() {
        let err = load_asset(Path::new("scene/model.STL")).unwrap_err().to_string();
        assert!(err.contains("model.STL") && err.contains("'stl'"), "{err}");
    }

    #[test]
    fn degenerate_triangles_are_dropped_with_their_materials() {
        let mut mesh = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(2.0, 0.0, 0.0)],
            triangles: vec![[0, 1, 2], [0, 1, 3], [2, 2, 1]],
            triangle_materials: vec![5, 6, 7],
            ..Default::default()
        };
        assert_eq!(mesh.drop_degenerate(), 2);
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(mesh.triangle_materials, vec![5]);
    }

    #[test]
    fn one_zero_normal_discards_all_normals() {
        assert_eq!(unit_normals(&[Vec3::new(0.0, 2.0, 0.0)]), vec![Vec3::Y]);
        assert!(unit_normals(&[Vec3::Y, Vec3::ZERO]).is_empty());
        assert!(unit_normals(&[Vec3::new(f32::NAN, 0.0, 1.0)]).is_empty());
    }
}
