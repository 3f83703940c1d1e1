//! Meshes in a scene: shared triangle geometry, its placements (instances), and the import of
//! mesh files (OBJ + MTL, PLY, glTF) into the scene's materials, meshes and textures.

use super::asset::{self, Asset};
use super::format::InlineMesh;
use super::{Light, Material, MetallicRoughness, Scene};
use crate::input_file::InputFiles;
use anyhow::{bail, Context as _, Result};
use glam::{Affine2, Mat4, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use asset::{AssetCamera, TextureImage as Texture};

/// Triangles in object space; `Instance`s place them in the world, so a mesh used several times
/// is stored once.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Where it came from, for messages.
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Empty, or one unit normal a vertex.
    pub normals: Vec<Vec3>,
    /// Empty, or one a vertex; (0, 0) is the texture's top-left corner.
    pub uvs: Vec<Vec2>,
    /// Empty, or one a vertex (with normals and texture coordinates) where a material has a normal
    /// map or is anisotropic (its lobes' x axis): the unit tangent along which u grows, and in w the sign (+-1) that makes
    /// cross(normal, tangent) x w the bitangent (glTF's TANGENT).
    pub tangents: Vec<Vec4>,
    /// Empty, or one a vertex: a linear RGB colour multiplying the albedo of the vertex's
    /// material (glTF's COLOR_0), interpolated across each triangle.
    pub colors: Vec<Vec3>,
    /// Front side faces (v1 - v0) x (v2 - v0).
    pub triangles: Vec<[u32; 3]>,
    /// One a triangle: index into `Scene::materials`.
    pub triangle_materials: Vec<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    pub mesh: u32,
    /// Object to world; invertible.
    pub transform: Mat4,
}

/// A loaded file: where its meshes sit in the scene, with the file's own placements of them, and
/// its camera.
struct LoadedFile {
    placements: Vec<(u32, Mat4)>,
    camera: Option<AssetCamera>,
    /// The file's own lights (glTF KHR_lights_punctual), in its world space.
    lights: Vec<Light>,
}

/// What a loaded file is known by: (file, mesh of the file, material override, sides).
type LoadKey = (PathBuf, Option<u32>, Option<u32>, Sides);

/// Loads each (file, material override) once: later placements of the same file share its
/// meshes, materials and textures.
pub struct MeshImporter<'a> {
    /// How the files are read (and from where).
    files: &'a InputFiles,
    /// The file's own placements of its meshes, as scene mesh indices, by (file, mesh of the file,
    /// material override, sides).
    loaded: HashMap<LoadKey, LoadedFile>,
    /// Textured scene materials and the maps of texture coordinates (their `to_uv`) of the meshes
    /// they replace the materials of.
    uv_maps: HashMap<u32, Affine2>,
}

impl<'a> MeshImporter<'a> {
    /// An importer reading every file through `files`.
    pub fn new(files: &'a InputFiles) -> Self {
        MeshImporter { files, loaded: HashMap::new(), uv_maps: HashMap::new() }
    }

    /// The same importer, mapping the texture coordinates of every mesh placed with one of these
    /// materials (which must have texture coordinates) through its map.
    pub fn with_uv_maps(self, uv_maps: HashMap<u32, Affine2>) -> Self {
        MeshImporter { uv_maps, ..self }
    }

    /// Places the meshes of `path` with `transform` applied after the file's own node transforms.
    /// `material` replaces every material of the file. Returns the file's camera, if it has one.
    pub fn place(
        &mut self,
        scene: &mut Scene,
        path: &Path,
        material: Option<u32>,
        transform: Mat4,
    ) -> Result<Option<AssetCamera>> {
        self.place_part(scene, path, None, material, Sides::default(), transform)
    }

    /// As [`MeshImporter::place`], for mesh `shape_index` of a file that holds several (Mitsuba's
    /// `.serialized`; `asset::load_asset_part`).
    pub fn place_part(
        &mut self,
        scene: &mut Scene,
        path: &Path,
        shape_index: Option<u32>,
        material: Option<u32>,
        sides: Sides,
        transform: Mat4,
    ) -> Result<Option<AssetCamera>> {
        let key = (path.canonicalize().unwrap_or_else(|_| path.to_path_buf()), shape_index, material, sides);
        let files = self.files;
        self.place_loaded(
            scene,
            key,
            path,
            || Ok(asset::load_asset_part(files, path, shape_index)?),
            material,
            sides,
            transform,
        )
    }

    /// Places a mesh written in the scene (an importer's, as PLY text: [`InlineMesh`]) as
    /// [`MeshImporter::place`] places a PLY file of that text.
    pub fn place_inline(&mut self, scene: &mut Scene, mesh: &InlineMesh, material: u32) -> Result<()> {
        let name = Path::new(&mesh.name);
        let key = (name.to_path_buf(), None, Some(material), Sides::default());
        self.place_loaded(
            scene,
            key,
            name,
            || Ok(asset::load_ply_bytes(mesh.ply.as_bytes(), name)?),
            Some(material),
            Sides::default(),
            Mat4::IDENTITY,
        )?;
        Ok(())
    }

    /// Places the meshes `load` gives (loaded once per `key`) as [`MeshImporter::place_part`]
    /// describes; `path` names them in messages.
    #[allow(clippy::too_many_arguments)]
    fn place_loaded(
        &mut self,
        scene: &mut Scene,
        key: LoadKey,
        path: &Path,
        load: impl FnOnce() -> Result<Asset>,
        material: Option<u32>,
        sides: Sides,
        transform: Mat4,
    ) -> Result<Option<AssetCamera>> {
        if !self.loaded.contains_key(&key) {
            let mut asset = load()?;
            if asset.dropped_triangles > 0 {
                log::info!("caustica: {}: dropped {} zero-area triangle(s)", path.display(), asset.dropped_triangles);
            }
            sides.apply(&mut asset);
            // Tangents before the texture coordinates are mapped: Mitsuba's and pbrt's frames (of
            // normal maps and anisotropic lobes alike) follow the mesh's own u, not a texture's.
            if let Some(m) = material.filter(|&m| scene.materials[m as usize].maps.normal.is_some()) {
                cross_bitangent_frames(scene, path, &mut asset, m)?;
            }
            if material.is_some_and(|m| scene.materials[m as usize].is_anisotropic()) {
                asset::add_anisotropy_tangents(path, &mut asset);
            }
            if let Some(to_uv) = material.and_then(|m| self.uv_maps.get(&m)) {
                map_uvs(scene, path, &mut asset, material.expect("set"), *to_uv)?;
            }
            let (camera, lights) = (asset.camera, asset.lights.clone());
            let placements = add_asset(scene, path, asset, material)?;
            self.loaded.insert(key.clone(), LoadedFile { placements, camera, lights });
        }
        let file = &self.loaded[&key];
        for &(mesh, local) in &file.placements {
            let world = transform * local;
            if !(world.determinant().abs() > 1e-30 && world.is_finite()) {
                bail!("{}: a placement of its mesh {mesh} is not invertible (zero scale?)", path.display());
            }
            scene.instances.push(Instance { mesh, transform: world });
        }
        for (k, light) in file.lights.iter().enumerate() {
            let placed = light.transformed(transform).with_context(|| {
                format!("{}: a placement of its light {k} collapses its direction (zero scale?)", path.display())
            })?;
            scene.lights.push(placed);
        }
        Ok(file.camera)
    }
}

/// How a `[[meshes]]` entry turns its file's surfaces (Mitsuba's `flip_normals` and
/// `face_normals`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Sides {
    /// The back becomes the front: the winding and the normals turn round.
    pub flip_normals: bool,
    /// Shaded flat with each triangle's own normal: the file's vertex normals are dropped.
    pub face_normals: bool,
}

impl Sides {
    fn apply(self, asset: &mut Asset) {
        for mesh in &mut asset.meshes {
            if self.face_normals {
                mesh.normals.clear();
                mesh.tangents.clear();
            }
            if self.flip_normals {
                mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
                mesh.normals.iter_mut().for_each(|n| *n = -*n);
                // The bitangent cross(n, t) x w keeps its direction with n turned round.
                mesh.tangents.iter_mut().for_each(|t| t.w = -t.w);
            }
        }
    }
}

/// Maps the texture coordinates of every mesh of `asset`, whose material is to be the textured
/// `material`, through `to_uv`.
fn map_uvs(scene: &Scene, path: &Path, asset: &mut Asset, material: u32, to_uv: Affine2) -> Result<()> {
    for (k, mesh) in asset.meshes.iter_mut().enumerate() {
        if mesh.uvs.is_empty() {
            bail!(
                "{}: mesh {k} has no texture coordinates, which material '{}' needs for its textures",
                path.display(),
                scene.materials[material as usize].name
            );
        }
        mesh.uvs.iter_mut().for_each(|uv| *uv = to_uv.transform_point2(*uv));
    }
    Ok(())
}

/// Gives every mesh of `asset`, which is to wear the TOML `normal_texture` of `material`, the
/// frame that map is read in: the tangent along growing u (MikkTSpace's, unless the file has its
/// own) and the bitangent cross(normal, tangent) (w = +1) whichever way v grows, as Mitsuba's
/// `normalmap` reads its maps.
fn cross_bitangent_frames(scene: &Scene, path: &Path, asset: &mut Asset, material: u32) -> Result<()> {
    for (k, mesh) in asset.meshes.iter_mut().enumerate() {
        if let Err(missing) = asset::ensure_tangents(mesh) {
            bail!(
                "{}: mesh {k} has no {missing}, which material '{}' needs for its normal_texture",
                path.display(),
                scene.materials[material as usize].name
            );
        }
        mesh.tangents.iter_mut().for_each(|t| t.w = 1.0);
    }
    Ok(())
}

/// Appends the asset's materials (unless overridden), textures and meshes to the scene.
fn add_asset(scene: &mut Scene, path: &Path, asset: Asset, material: Option<u32>) -> Result<Vec<(u32, Mat4)>> {
    let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let material_base = scene.materials.len() as u32;
    if material.is_none() {
        let texture_base = scene.textures.len() as u32;
        for m in &asset.materials {
            scene.materials.push(scene_material(path, &file_name, m, texture_base)?);
        }
        scene.textures.extend(asset.textures);
    }
    let mesh_base = scene.meshes.len() as u32;
    for (k, m) in asset.meshes.into_iter().enumerate() {
        scene.meshes.push(Mesh {
            name: format!("{} mesh {k}", path.display()),
            triangle_materials: m.triangle_materials.iter().map(|&t| material.unwrap_or(material_base + t)).collect(),
            positions: m.positions,
            normals: m.normals,
            uvs: m.uvs,
            tangents: m.tangents,
            // The colours belong to the file's own materials: a material the scene puts in their
            // place is drawn as it says.
            colors: if material.is_none() { m.colors } else { Vec::new() },
            triangles: m.triangles,
        });
    }
    Ok(asset.instances.iter().map(|&(mesh, local)| (mesh_base + mesh as u32, local)).collect())
}

/// A file's material placed in the scene: named after its file, its textures rebased onto the
/// scene's, its albedo above 1 (some MTL files have it) clamped so no surface creates energy.
fn scene_material(path: &Path, file_name: &str, m: &Material, texture_base: u32) -> Result<Material> {
    let values = [m.albedo.to_array(), m.emission.to_array()].concat();
    if values.iter().chain([m.reflectivity, m.transparency, m.ior, m.roughness].iter()).any(|v| !v.is_finite())
        || m.albedo.min_element() < 0.0
        || m.emission.min_element() < 0.0
    {
        bail!("{}: material '{}' has a negative or non-finite value", path.display(), m.name);
    }
    Ok(Material {
        name: format!("{file_name}:{}", m.name),
        albedo: m.albedo.min(Vec3::ONE),
        albedo_texture: m.albedo_texture.map(|t| texture_base + t),
        roughness: m.roughness.clamp(0.0, 1.0),
        metallic_roughness: m
            .metallic_roughness
            .map(|mr| MetallicRoughness { texture: texture_base + mr.texture, ..mr }),
        maps: m.maps.rebased(texture_base),
        clearcoat: m.clearcoat.map(|c| c.rebased(texture_base)),
        ..m.clone()
    })
}
