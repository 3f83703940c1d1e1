//! Wavefront OBJ with its MTL material library, via tobj.
//!
//! MTL → [`Material`] mapping:
//! - `Kd` → albedo (0.8 grey when missing), clamped to [0, 1]; `map_Kd` → albedo texture, a path
//!   relative to the OBJ's directory (options such as `-bm 1` before the name are skipped).
//! - `norm`, else `map_Bump` / `bump` → a tangent-space normal map (linear; `-bm` its scale) read
//!   along MikkTSpace tangents (tangents.rs).
//! - `Ke` → emission; `map_Ke` (sRGB) multiplies it per texel. Older files (Embree's `cornell_box.mtl`) mark lights with an ambient colour
//!   above 1 instead (`Ka 20 20 20`), so without `Ke` a `Ka` with a channel > 1 is the emission.
//! - `illum 3` or `5` → mirror: reflectivity = largest channel of `Ks`, or 1 when `Ks` is zero.
//! - Opacity (alpha, tested during traversal): `d` (else 1 - `Tr`) times `map_d`, whose alpha
//!   channel is the opacity, or its grey level (R) when every texel is opaque (a greyscale map).
//!   The surface is met with that probability (stochastic opacity, [`AlphaMode::Blend`]), so a
//!   cut-out texture of 0 and 1 cuts out exactly. Not for the glass illumination models:
//! - Glass: `illum 4`, `6` or `7` (MTL's transparent models) with transparency = 1 - `d` when `d`
//!   < 1, else `Tr` when > 0, else 1 for `illum 7`; `illum 4` and `6` alone, with `d` 1, stay
//!   opaque (exporters write them for opaque surfaces). Such a material has no alpha.
//! - `Ni` → ior, 1.5 when missing or not positive. R + T <= 1 is kept by lowering R.
//!
//! Faces without a material get [`Material::default`] (0.8 grey diffuse).
//!
//! tobj parses bytes that [`InputFiles`] read (the OBJ and each `mtllib`), never a path: its own
//! file reading would skip the checks on devices, sizes and `--confine`.

use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::{
    single_mesh_asset, texture, unit_normals, Alpha, AlphaMode, Asset, AssetError, Material, MeshData, NormalMap,
    TextureImage, TextureMaps,
};
use crate::input_file::{InputError, InputFiles, InputKind};

/// Loads every object of an OBJ file into one mesh with per-triangle materials.
pub(super) fn load(files: &InputFiles, path: &Path) -> Result<Asset, AssetError> {
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    let bytes = files.read(path, InputKind::Mesh)?;
    let directory = path.parent().unwrap_or(Path::new("."));
    let libraries =
        MaterialLibraries { files, directory, read: RefCell::new(HashSet::new()), failure: RefCell::new(None) };
    let (models, mtl) = tobj::load_obj_buf(&mut bytes.as_slice(), &options, |name| libraries.load(name))
        .map_err(|e| AssetError::invalid(path, format!("cannot load OBJ: {e}")))?;
    if let Some(failure) = libraries.failure.into_inner() {
        return Err(AssetError::invalid(path, format!("cannot load its MTL material library: {failure}")));
    }
    let mtl = mtl.map_err(|e| AssetError::invalid(path, format!("cannot load its MTL material library: {e}")))?;
    drop(bytes);

    let mut textures = Textures { files, directory, by_path: HashMap::new(), images: Vec::new() };
    let mut materials = mtl.iter().map(|m| convert_material(path, m, &mut textures)).collect::<Result<Vec<_>, _>>()?;
    let mut default_material = None;

    let mut mesh = MeshData::default();
    let mut all_normals = true;
    let mut all_uvs = true;
    let mut normals = Vec::new();
    for model in &models {
        let source = &model.mesh;
        let vertex_count = source.positions.len() / 3;
        let base = u32::try_from(mesh.positions.len() + vertex_count)
            .map(|end| end - vertex_count as u32)
            .map_err(|_| AssetError::invalid(path, "more than 2^32 vertices"))?;
        for (i, p) in source.positions.chunks_exact(3).enumerate() {
            let p = Vec3::new(p[0], p[1], p[2]);
            if !p.is_finite() {
                return Err(AssetError::invalid(
                    path,
                    format!("object '{}': vertex {} has a non-finite coordinate {p}", model.name, i + 1),
                ));
            }
            mesh.positions.push(p);
        }
        all_normals &= source.normals.len() == 3 * vertex_count;
        if all_normals {
            normals.extend(source.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
        }
        all_uvs &= source.texcoords.len() == 2 * vertex_count;
        if all_uvs {
            mesh.uvs.extend(source.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])));
        }

        let material = match source.material_id {
            Some(id) if id < materials.len() => id as u32,
            Some(id) => {
                return Err(AssetError::invalid(
                    path,
                    format!("object '{}' uses material {id} but the MTL file has {}", model.name, materials.len()),
                ));
            }
            None => *default_material.get_or_insert_with(|| {
                materials.push(Material::default());
                materials.len() as u32 - 1
            }),
        };
        for (face, corners) in source.indices.chunks_exact(3).enumerate() {
            if let Some(&bad) = corners.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(AssetError::invalid(
                    path,
                    format!(
                        "object '{}': triangle {} uses vertex {} but the object has {vertex_count} vertices",
                        model.name,
                        face + 1,
                        bad + 1
                    ),
                ));
            }
            mesh.triangles.push([corners[0] + base, corners[1] + base, corners[2] + base]);
            mesh.triangle_materials.push(material);
        }
    }
    mesh.normals = if all_normals { unit_normals(&normals) } else { Vec::new() };
    if !all_uvs || mesh.uvs.iter().any(|uv| !uv.is_finite()) {
        mesh.uvs.clear();
    }
    let dropped = mesh.drop_degenerate();
    Ok(single_mesh_asset(mesh, materials, textures.images, dropped))
}

/// The MTL libraries an OBJ names, read when tobj meets their `mtllib` line. A library named again
/// is not read again: a short OBJ repeating one `mtllib` line must not make caustica read a large
/// library thousands of times (tobj would append its materials each time). tobj's errors carry no
/// message, so the first read failure is kept here and reported instead.
struct MaterialLibraries<'a> {
    files: &'a InputFiles,
    directory: &'a Path,
    read: RefCell<HashSet<PathBuf>>,
    failure: RefCell<Option<InputError>>,
}

impl MaterialLibraries<'_> {
    fn load(&self, name: &Path) -> tobj::MTLLoadResult {
        let path = self.directory.join(name);
        if !self.read.borrow_mut().insert(path.clone()) {
            return Ok((Vec::new(), Default::default()));
        }
        match self.files.read(&path, InputKind::MaterialLibrary) {
            Ok(bytes) => tobj::load_mtl_buf(&mut bytes.as_slice()),
            Err(e) => {
                self.failure.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    }
}

/// Decodes each texture image once per way it is read, however many materials share it.
struct Textures<'a> {
    files: &'a InputFiles,
    directory: &'a Path,
    /// (file, how it is read) → index into `images`.
    by_path: HashMap<(PathBuf, Decoding), usize>,
    images: Vec<TextureImage>,
}

/// How a texture's texels are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Decoding {
    /// sRGB-encoded colour (`map_Kd`, `map_Ke`).
    Colour,
    /// Linear data (normal maps).
    Data,
    /// Opacity in the alpha channel (`map_d`): a greyscale image's grey level moved there.
    Opacity,
}

impl Textures<'_> {
    /// The colour (sRGB) texture that `map` names.
    fn get(&mut self, map: &str) -> Result<usize, AssetError> {
        self.get_decoded(map, Decoding::Colour)
    }

    /// The texture that `map` names, read as `decoding` says.
    fn get_decoded(&mut self, map: &str, decoding: Decoding) -> Result<usize, AssetError> {
        // Options (`-bm 1 -clamp on name.png`) precede the file name, which then has no spaces.
        let name = if map.starts_with('-') { map.split_whitespace().last().unwrap_or(map) } else { map };
        let path = self.directory.join(name);
        if let Some(&index) = self.by_path.get(&(path.clone(), decoding)) {
            return Ok(index);
        }
        let mut image = texture::load_texture(self.files, &path)?;
        image.srgb = decoding == Decoding::Colour;
        if decoding == Decoding::Opacity {
            opacity_in_alpha(&mut image);
        }
        self.images.push(image);
        self.by_path.insert((path, decoding), self.images.len() - 1);
        Ok(self.images.len() - 1)
    }
}

/// `map_d` is a scalar map: an image with an alpha channel gives it there, a greyscale one (every
/// texel opaque, as decoding fills a missing alpha) as its grey level, which is moved into alpha,
/// where the kernel reads opacity.
fn opacity_in_alpha(image: &mut TextureImage) {
    if image.texels.iter().all(|t| t[3] == u8::MAX) {
        for t in &mut image.texels {
            t[3] = t[0];
        }
    }
}

/// The value of option `-name` in a texture statement (`-bm 0.5 normal.png`), if it has one.
fn map_option(map: &str, name: &str) -> Option<String> {
    let mut words = map.split_whitespace();
    words.by_ref().find(|&w| w == name)?;
    words.next().map(str::to_owned)
}

fn convert_material(path: &Path, m: &tobj::Material, textures: &mut Textures) -> Result<Material, AssetError> {
    let bad = |what: &str| AssetError::invalid(path, format!("material '{}': {what}", m.name));
    let vec3 = |v: Option<[f32; 3]>| v.map(Vec3::from_array);
    if [m.ambient, m.diffuse, m.specular, m.emissive].iter().flatten().flatten().any(|c| !c.is_finite())
        || [m.dissolve, m.optical_density].iter().flatten().any(|c| !c.is_finite())
    {
        return Err(bad("non-finite colour or coefficient"));
    }
    let ambient = vec3(m.ambient).unwrap_or(Vec3::ZERO);
    let emission = match vec3(m.emissive) {
        Some(ke) => ke,
        None if ambient.max_element() > 1.0 => ambient,
        None => Vec3::ZERO,
    };

    let illum = m.illumination_model.unwrap_or(2);
    let reflectivity = if matches!(illum, 3 | 5) {
        match vec3(m.specular).map_or(0.0, |ks| ks.max_element()) {
            ks if ks > 0.0 => ks,
            _ => 1.0,
        }
    } else {
        0.0
    };
    let dissolve = m.dissolve.unwrap_or(1.0);
    let tr = match m.unknown_param.get("Tr") {
        Some(text) => text
            .trim()
            .parse::<f32>()
            .ok()
            .filter(|t| t.is_finite())
            .ok_or_else(|| bad(&format!("cannot read Tr '{text}'")))?,
        None => 0.0,
    };
    // MTL's transparent illumination models make `d` the glass's transmission; otherwise `d`
    // (written by some exporters as `Tr` = 1 - d) is the opacity.
    let glass = matches!(illum, 4 | 6 | 7);
    let transparency = if !glass {
        0.0
    } else if dissolve < 1.0 {
        1.0 - dissolve
    } else if tr > 0.0 {
        tr
    } else if illum == 7 {
        1.0
    } else {
        0.0
    };
    let transparency = transparency.clamp(0.0, 1.0);
    let opacity = match (m.dissolve, tr) {
        (Some(d), _) => d,
        (None, tr) => 1.0 - tr,
    }
    .clamp(0.0, 1.0);
    let opacity_texture = match &m.dissolve_texture {
        Some(map) if !glass => Some(textures.get_decoded(map, Decoding::Opacity)? as u32),
        _ => None,
    };
    let alpha = (!glass && (opacity < 1.0 || opacity_texture.is_some())).then_some(Alpha {
        factor: opacity,
        texture: opacity_texture,
        mode: AlphaMode::Blend,
    });
    let albedo_texture = m.diffuse_texture.as_deref().map(|map| textures.get(map)).transpose()?;
    // tobj keeps `map_Ke` among the keys it does not know. Like glTF's, the texture is read only
    // where it can show: black `Ke` times it is nothing.
    let emission_texture = match m.unknown_param.get("map_Ke") {
        Some(map) if emission.max_element() > 0.0 => Some(textures.get(map)? as u32),
        _ => None,
    };
    // `norm` names a tangent-space normal map; `map_Bump` (and `bump`) do in the files that pair
    // them with glTF-style assets, which is how caustica reads them (not as heights). `-bm` scales.
    let normal_statement = m.unknown_param.get("norm").or(m.normal_texture.as_ref());
    let normal = match normal_statement {
        Some(map) => {
            let scale = match map_option(map, "-bm") {
                Some(text) => text
                    .parse::<f32>()
                    .ok()
                    .filter(|s| s.is_finite())
                    .ok_or_else(|| bad(&format!("cannot read the normal map's -bm '{text}'")))?,
                None => 1.0,
            };
            Some(NormalMap { texture: textures.get_decoded(map, Decoding::Data)? as u32, scale })
        }
        None => None,
    };
    Ok(Material {
        name: m.name.clone(),
        albedo: vec3(m.diffuse).unwrap_or(Vec3::splat(0.8)).clamp(Vec3::ZERO, Vec3::ONE),
        albedo_texture: albedo_texture.map(|t| t as u32),
        emission: emission.max(Vec3::ZERO),
        reflectivity: reflectivity.clamp(0.0, 1.0 - transparency),
        transparency,
        ior: m.optical_density.filter(|&n| n > 0.0).unwrap_or(1.5),
        maps: TextureMaps { emission: emission_texture, normal, alpha },
        ..Material::default()
    })
}

#[cfg(test)]
mod tests {
    use super::super::{load_asset, real_data, test_dir, write_files, WrittenFiles};
    use super::*;

    const QUAD_OBJ: &str = "mtllib quad.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vn 0 0 2
vn 0 0 2
vn 0 0 2
vn 0 0 2
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl lamp
f 1/1/1 2/2/2 3/3/3
usemtl mirror
f 1/1/1 3/3/3 4/4/4
o second
usemtl glass
f 1/1/1 2/2/2 4/4/4
";

    const QUAD_MTL: &str = "newmtl lamp
Kd 0.5 0.25 0.125
Ke 10 9 8
newmtl mirror
illum 3
Ks 0.9 0.7 0.5
newmtl glass
illum 7
Kd 1 1 1
d 0.25
Ni 1.33
newmtl ambient_light
Ka 20 20 20
newmtl tr_glass
Tr 0.6
illum 6
newmtl veil
illum 2
d 0.25
newmtl tr_veil
Tr 0.6
";

    fn write_obj(tag: &str, obj: &str, mtl: &str) -> WrittenFiles {
        write_files(tag, &[("quad.obj", obj), ("quad.mtl", mtl)])
    }

    #[test]
    fn quad_with_materials_normals_and_uvs() {
        let asset = load_asset(&write_obj("obj-quad", QUAD_OBJ, QUAD_MTL)).unwrap();
        assert_eq!(asset.meshes.len(), 1);
        assert_eq!(asset.instances, vec![(0, glam::Mat4::IDENTITY)]);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(mesh.positions.len(), mesh.normals.len());
        assert_eq!(mesh.positions.len(), mesh.uvs.len());
        assert!(mesh.normals.iter().all(|n| *n == Vec3::Z), "normals are normalized");
        let names: Vec<&str> =
            mesh.triangle_materials.iter().map(|&m| asset.materials[m as usize].name.as_str()).collect();
        assert_eq!(names, ["lamp", "mirror", "glass"]);
        // v is flipped: OBJ's (0, 0) is the bottom-left corner.
        let first = mesh.triangles[0][0] as usize;
        assert_eq!((mesh.positions[first], mesh.uvs[first]), (Vec3::ZERO, Vec2::new(0.0, 1.0)));

        let material = |name: &str| asset.materials.iter().find(|m| m.name == name).unwrap();
        let lamp = material("lamp");
        assert_eq!(
            (lamp.albedo, lamp.emission, lamp.reflectivity, lamp.transparency),
            (Vec3::new(0.5, 0.25, 0.125), Vec3::new(10.0, 9.0, 8.0), 0.0, 0.0)
        );
        assert_eq!((material("mirror").reflectivity, material("mirror").transparency), (0.9, 0.0));
        let glass = material("glass");
        assert_eq!((glass.transparency, glass.ior, glass.reflectivity), (0.75, 1.33, 0.0));
        assert_eq!(material("ambient_light").emission, Vec3::splat(20.0), "old Ka > 1 light convention");
        assert_eq!(glass.maps.alpha, None, "d of a glass illumination model is its transmission");
        let tr = material("tr_glass");
        assert_eq!((tr.transparency, tr.ior, tr.maps.alpha), (0.6, 1.5, None));
        let blend = |factor| Some(Alpha { factor, texture: None, mode: AlphaMode::Blend });
        let veil = material("veil");
        assert_eq!((veil.transparency, veil.maps.alpha), (0.0, blend(0.25)), "d is opacity");
        let tr_veil = material("tr_veil");
        assert_eq!(tr_veil.transparency, 0.0);
        assert!((tr_veil.maps.alpha.unwrap().factor - 0.4).abs() < 1e-6, "Tr is 1 - d");
        assert_eq!(asset.dropped_triangles, 0);
    }

    #[test]
    fn faces_without_material_get_the_default_and_degenerate_ones_are_dropped() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n";
        let asset = load_asset(&write_obj("obj-default", obj, "")).unwrap();
        assert_eq!(asset.materials, vec![Material::default()]);
        assert_eq!(asset.meshes[0].triangle_materials, vec![0]);
        assert_eq!(asset.dropped_triangles, 1);
        assert!(asset.meshes[0].normals.is_empty() && asset.meshes[0].uvs.is_empty());
    }

    #[test]
    fn bad_indices_and_nan_vertices_are_errors() {
        let path = write_obj("obj-bad-index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "");
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");

        let path = write_obj("obj-nan", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "");
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(
            err.contains(&path.display().to_string()) && err.contains("vertex 2") && err.contains("non-finite"),
            "{err}"
        );
    }

    #[test]
    fn missing_material_library_and_texture_are_errors() {
        let dir = test_dir("obj-missing");
        let path = dir.join("m.obj");
        std::fs::write(&path, "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(load_asset(&path).unwrap_err().to_string().contains("MTL"));
        let path = write_obj(
            "obj-missing-tex",
            "mtllib quad.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "newmtl t\nmap_Kd -bm 1 wood.png\n",
        );
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains("wood.png"), "{err}");
    }

    #[test]
    fn real_cornell_boxes() {
        let Some(path) = real_data("meshes/cornell/CornellBox-Original.obj") else {
            return;
        };
        let asset = load_asset(&path).unwrap();
        let lights: Vec<&Material> = asset.materials.iter().filter(|m| m.emission.max_element() > 0.0).collect();
        assert_eq!(lights.len(), 1, "{lights:?}");
        println!("{}: {} triangles, light {:?}", path.display(), asset.meshes[0].triangles.len(), lights[0].emission);

        let Some(path) = real_data("meshes/cornell/cornell_box.obj") else {
            return;
        };
        let asset = load_asset(&path).unwrap();
        assert!(asset.materials.iter().any(|m| m.emission == Vec3::splat(20.0)), "Ka 20 20 20 is the light");
    }
}
