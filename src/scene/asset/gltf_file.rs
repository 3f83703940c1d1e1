//! glTF 2.0 (`.gltf` with external or data-URI buffers and images, and binary `.glb`), via the
//! gltf crate for parsing and accessors. Buffers and images are loaded here rather than with
//! `gltf::import`, so that only the textures we read are decoded, under our size limit, and every
//! file is read through [`InputFiles`] (regular files, size caps, `--confine`).
//!
//! Material mapping (metallic-roughness PBR onto the renderer's diffuse/mirror/glass mix):
//! - `baseColorFactor.rgb` → albedo; `baseColorTexture` → albedo texture; `COLOR_0` (RGB or
//!   RGBA; floats, or normalized unsigned bytes or shorts) multiplies both per vertex,
//!   interpolated across each triangle (SCENE_VERTEX_COLORS; white for a primitive without it).
//!   Its alpha is not read: a warning names a MASK or BLEND material it would have thinned.
//! - Texture coordinates: a material's textures are read through one `texCoord` set (0 or 1) and
//!   one `KHR_texture_transform` (offset, rotation, scale, its `texCoord` override), those of its
//!   first texture among base colour, emissive, metallic-roughness and normal; they are applied
//!   to its primitives' coordinates on load (the kernel keeps one set a vertex). A texture of the
//!   material that names another set or transform is read through the first's, with a warning.
//!   Each texture's sampler gives its wrap modes (REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT); the
//!   filters are ignored (lookups are bilinear).
//! - `alphaMode` `MASK` (with `alphaCutoff`, 0.5 by default) and `BLEND` → [`Alpha`]: the opacity
//!   is `baseColorFactor.a` times the base colour texture's alpha; MASK keeps the surface where it
//!   reaches the cutoff, BLEND meets it with that probability (stochastic opacity). `OPAQUE`
//!   ignores alpha, as glTF says.
//! - `emissiveFactor` × `KHR_materials_emissive_strength` → emission; `emissiveTexture`
//!   (sRGB) multiplies it per texel. Its triangles are lights for next-event
//!   estimation, picked by their texture-weighted power (src/render/textured_emission.rs).
//! - `normalTexture` (linear) with its `scale` → a tangent-space normal map, read along
//!   the file's TANGENTs when every primitive of the mesh has them, else MikkTSpace's.
//! - `metallicFactor` → reflectivity R, a conductor with the base colour as F0 (Schlick);
//!   `roughnessFactor` → roughness (both perceptual) of every lobe.
//! - `KHR_materials_transmission` factor → transparency T = (1 − metallic) × transmission, a
//!   rough dielectric; `KHR_materials_ior` → ior (1.5 by default).
//! - `metallicRoughnessTexture` (linear, B = metallic, G = roughness) scales the two
//!   factors per texel: the kernel recomputes R, T and roughness there as above.
//! - The rest (1 − R − T) is a plastic: the base colour under a dielectric coat of that ior.
//! - `KHR_materials_clearcoat` → [`Clearcoat`]: `clearcoatFactor` and `clearcoatRoughnessFactor`,
//!   `clearcoatTexture` (R) and `clearcoatRoughnessTexture` (G) scaling them per texel, read
//!   through the material's one texture mapping. The coat is glTF's `fresnel_coat` layer (index
//!   1.5, Fresnel on the viewing direction) over everything above. `clearcoatNormalTexture` is not
//!   read: the coat uses the material's normal (a warning).
//! - `KHR_materials_volume` → [`Attenuation`] of a transmissive material: `attenuationColor` and
//!   `attenuationDistance` (world units) as Beer–Lambert absorption along each path inside.
//!   `thicknessFactor` and `thicknessTexture` are ignored: they stand in for the thickness a
//!   rasterizer cannot trace, and a path tracer has the real one.
//! - `doubleSided: false` (the default) → a one-sided material, black from behind (the back
//!   faces a rasterizer culls), unless it transmits; `doubleSided: true` → two-sided.
//! - Primitives without a material get [`Material::default`] (0.8 grey diffuse, two-sided).
//!
//! `KHR_lights_punctual` lights become [`Light`]s, converted from glTF's photometric units to
//! caustica's radiometric ones at 683 lm/W (the luminous efficacy that defines the candela):
//! a point's or spot's intensity in candela (lm/sr) / 683 → W/sr, a directional light's in lux
//! (lm/m^2) / 683 → W/m^2, each times its linear `color`. They shine down their node's −Z. A spot's
//! `innerConeAngle` becomes `falloff_start` and `outerConeAngle` `cone_angle`: between the two
//! caustica falls off linearly in the angle (Mitsuba 3's spot), where glTF suggests a curve in
//! the cosine; the ends agree. `range` is ignored (a note on stderr): the light falls off by the
//! inverse square without a cut-off, which the extension allows as the physical limit.
//!
//! Extensions: the seven above (`KHR_lights_punctual`, `KHR_materials_emissive_strength`,
//! `KHR_materials_transmission`, `KHR_materials_ior`, `KHR_texture_transform`,
//! `KHR_materials_clearcoat`, `KHR_materials_volume`) and `KHR_mesh_quantization` are read: the
//! last lets positions, normals, tangents, texture coordinates and morph targets be stored as
//! (normalized) integers, which are read as the numbers they stand for (gltf_accessors.rs). A file that requires any other is
//! an error naming the file and the extension; one that merely uses another renders without it,
//! with one warning per extension. Occlusion textures are ignored (a path tracer computes
//! occlusion), with one warning per file that has them.
//!
//! Morph targets (POSITION, NORMAL, TANGENT displacements) are applied once on load with the
//! node's `weights`, else the mesh's (a node with weights of its own gets its own morphed copy of
//! the mesh); animations do not move them. Skins (JOINTS_0/1, WEIGHTS_0/1, inverseBindMatrices)
//! pose their meshes on load by the joints' node transforms (gltf_skin.rs). Animations are not
//! played (a warning), nor are orthographic cameras read (a warning); a file with several
//! cameras renders through the first one its node hierarchy reaches (a warning).
//!
//! Each glTF mesh becomes one [`MeshData`] (its primitives merged). Triangle strips and fans are
//! converted to triangles; points and lines are skipped with a note on stderr.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use base64::Engine as _;
use glam::{Affine2, Mat2, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::{Document, Semantic};

use super::gltf_accessors::{read_floats, AccessorLimits, DIRECTION_TYPES, QUANTIZED_TYPES};
use super::gltf_skin::{self, VertexInfluences};
use super::{
    texture, unit_normals, Alpha, AlphaMode, Asset, AssetCamera, AssetError, Attenuation, Clearcoat, Conductor, Light,
    Material, MeshData, MetallicRoughness, NormalMap, TextureMaps, Wrap,
};
use crate::input_file::{InputFiles, InputKind};
use gltf::accessor::Item;

/// Lumens per watt of radiant flux at 555 nm, the constant of the candela's definition: glTF's
/// photometric light units over this are radiometric.
const LUMENS_PER_WATT: f32 = 683.0;

/// The glTF extensions caustica reads (see the mapping above).
const IMPLEMENTED_EXTENSIONS: [&str; 8] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_texture_transform",
    "KHR_materials_clearcoat",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
];

/// Deeper node hierarchies are rejected: real files stay far below, and the walk recurses.
const MAX_NODE_DEPTH: usize = 1000;

/// Loads a `.gltf` or `.glb` file: its default scene (else scene 0, else every root node).
pub(super) fn load(files: &InputFiles, path: &Path) -> Result<Asset, AssetError> {
    let bytes = files.read(path, InputKind::Mesh)?;
    // gltf 1.4 computes `length - 12` from a GLB header without checking it, which overflows
    // (a panic with overflow checks on) for a length field below 12 (found by fuzzing).
    if bytes.starts_with(b"glTF") && bytes.len() >= 12 {
        let length = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if length < 12 {
            return Err(AssetError::invalid(
                path,
                format!("cannot parse glTF: GLB header length {length} is shorter than the 12-byte header"),
            ));
        }
    }
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| AssetError::invalid(path, format!("cannot parse glTF: {e}")))?;
    // gltf-json 1.4's validation indexes `accessors` with a primitive's POSITION accessor before
    // checking that it exists, and panics on an out-of-range one (found by fuzzing), so check
    // that first and validate afterwards.
    let mut json = document.into_json();
    if let Some(required) = unimplemented_required_extension(&json) {
        return Err(AssetError::invalid(
            path,
            format!("requires the glTF extension {required}, which caustica does not implement"),
        ));
    }
    // Every required extension is one caustica reads; the crate's validation would refuse those
    // it does not list itself (gltf 1.4.1 lists neither KHR_materials_clearcoat, which it leaves
    // as JSON, nor KHR_materials_volume, which it parses).
    json.extensions_required.retain(|e| gltf::json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()));
    for warning in ignored_features(&json) {
        log::warn!("caustica: warning: {}: {warning}", path.display());
    }
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &primitive.attributes {
                if accessor.value() >= json.accessors.len() {
                    return Err(AssetError::invalid(
                        path,
                        format!(
                            "cannot parse glTF: meshes[{m}].primitives[{p}].attributes[{semantic:?}]: accessor {} does not exist ({} accessors)",
                            accessor.value(),
                            json.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let document =
        gltf::Document::from_json(json).map_err(|e| AssetError::invalid(path, format!("cannot parse glTF: {e}")))?;
    // The blob is a copy: the file's bytes are not needed past here, only their count.
    let file_bytes = bytes.len() as u64;
    drop(bytes);
    let sources =
        Sources { files, directory: path.parent().unwrap_or(Path::new(".")), read: RefCell::new(HashMap::new()) };
    let buffers = load_buffers(&document, blob, &sources).map_err(|m| AssetError::invalid(path, m))?;

    let mut asset = Asset::default();
    let mut decoded_images = DecodedImages::new();
    let mut uv_mappings = Vec::new();
    for material in document.materials() {
        let (converted, uv_mapping) =
            convert_material(&material, &document, &buffers, &sources, &mut decoded_images, &mut asset)
                .map_err(|m| AssetError::invalid(path, m))?;
        if uv_mapping.mixed {
            log::warn!("caustica: warning: {}: material '{}': its textures use different texture coordinates or KHR_texture_transforms; all are read through its first texture's", path.display(), converted.name);
        }
        asset.materials.push(converted);
        uv_mappings.push(uv_mapping.mapping);
    }
    let mut notes = MeshNotes::default();
    let mut default_material = None;
    let mut limits = AccessorLimits::new(&buffers, file_bytes);
    // Each mesh morphed by its own default weights, then once more for every node that gives
    // its morph targets other weights (that node's instance uses the extra copy).
    let morph_variants = document.nodes().filter_map(|node| {
        let (mesh, weights) = (node.mesh()?, node.weights()?);
        let has_targets = mesh.primitives().any(|p| p.morph_targets().len() > 0);
        (has_targets && Some(weights) != mesh.weights()).then_some((Some(node.index()), mesh, weights))
    });
    let mut node_meshes = HashMap::new();
    let mut mesh_influences = Vec::new();
    let variants: Vec<_> = document
        .meshes()
        .map(|mesh| (None, mesh.clone(), mesh.weights().unwrap_or(&[])))
        .chain(morph_variants)
        .collect();
    for (node, mesh, weights) in variants {
        let (mut converted, influences) = convert_mesh(
            &mesh,
            &uv_mappings,
            &mut limits,
            &mut asset.materials,
            &mut default_material,
            &mut notes,
            weights,
        )
        .map_err(|m| AssetError::invalid(path, format!("mesh {}: {m}", mesh.index())))?;
        asset.dropped_triangles += converted.drop_degenerate();
        if let Some(node) = node {
            node_meshes.insert(node, asset.meshes.len());
        }
        asset.meshes.push(converted);
        mesh_influences.push(influences);
    }
    let MeshNotes { skipped_primitives, colour_alpha_ignored } = notes;
    if skipped_primitives > 0 {
        log::warn!("caustica: {}: skipped {skipped_primitives} point or line primitive(s)", path.display());
    }
    if colour_alpha_ignored {
        log::warn!(
            "caustica: warning: {}: COLOR_0 alpha is not implemented: vertex colours' alpha below 1 on MASK or BLEND materials is ignored (their RGB is read)",
            path.display()
        );
    }

    let mut walk = Walk {
        ancestors: Vec::new(),
        visited: vec![false; document.nodes().len()],
        node_meshes: &node_meshes,
        worlds: vec![None; document.nodes().len()],
        skinned: Vec::new(),
        asset: &mut asset,
    };
    for root in root_nodes(&document) {
        walk.visit(root, Mat4::IDENTITY).map_err(|m| AssetError::invalid(path, m))?;
    }
    let (worlds, skinned) = (walk.worlds, walk.skinned);
    // Skinned instances: their mesh posed by the joints' world transforms, in world space.
    for (instance, node) in skinned {
        let node = document.nodes().nth(node).expect("a visited node");
        let skin = node.skin().expect("a skinned node");
        let mesh = asset.instances[instance].0;
        if mesh_influences[mesh].is_empty() {
            continue;
        }
        let joint_worlds = skin
            .joints()
            .map(|joint| {
                worlds[joint.index()].ok_or_else(|| {
                    format!("skin {}: joint node {} is not in the rendered scene", skin.index(), joint.index())
                })
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|m| AssetError::invalid(path, m))?;
        let node_world = worlds[node.index()].expect("a visited node");
        let posed =
            gltf_skin::pose(&asset.meshes[mesh], &mesh_influences[mesh], &skin, &joint_worlds, node_world, &mut limits)
                .map_err(|m| AssetError::invalid(path, format!("node {}: {m}", node.index())))?;
        asset.instances[instance] = (asset.meshes.len(), Mat4::IDENTITY);
        asset.meshes.push(posed);
    }
    if document.lights().into_iter().flatten().any(|l| l.range().is_some()) {
        log::warn!(
            "caustica: {}: KHR_lights_punctual range ignored (lights fall off by the inverse square)",
            path.display()
        );
    }
    Ok(asset)
}

/// The first extension the file requires that caustica does not implement: the file cannot be
/// rendered as its author meant.
fn unimplemented_required_extension(json: &gltf::json::Root) -> Option<&str> {
    json.extensions_required.iter().map(String::as_str).find(|e| !IMPLEMENTED_EXTENSIONS.contains(e))
}

/// What of the file is left out, each said once: every extension it uses that caustica does not
/// implement (the file stays valid without it), and occlusion textures.
fn ignored_features(json: &gltf::json::Root) -> Vec<String> {
    let unimplemented: std::collections::BTreeSet<&str> =
        json.extensions_used.iter().map(String::as_str).filter(|e| !IMPLEMENTED_EXTENSIONS.contains(e)).collect();
    let mut ignored: Vec<String> = unimplemented
        .into_iter()
        .map(|e| format!("glTF extension {e} is not implemented: rendering without it"))
        .collect();
    if json.materials.iter().any(|m| m.occlusion_texture.is_some()) {
        ignored.push("occlusion textures are ignored (a path tracer computes occlusion)".to_owned());
    }
    let coat_normal = |m: &gltf::json::Material| {
        let coat = m.extensions.as_ref().and_then(|e| e.others.get("KHR_materials_clearcoat"));
        coat.is_some_and(|c| c.get("clearcoatNormalTexture").is_some())
    };
    if !json.animations.is_empty() {
        ignored.push(format!(
            "{} animation(s) are not played: nodes, morph targets and skins stand as the file saves them",
            json.animations.len()
        ));
    }
    let orthographic = json
        .cameras
        .iter()
        .filter(|c| matches!(c.type_, gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Orthographic)))
        .count();
    if orthographic > 0 {
        ignored.push(format!(
            "{orthographic} orthographic camera(s) are not implemented: the first perspective camera is used"
        ));
    }
    if json.cameras.len() - orthographic > 1 {
        ignored.push(format!(
            "the file has {} perspective cameras: the first one the node hierarchy reaches is used",
            json.cameras.len() - orthographic
        ));
    }
    let extra_influences = json.meshes.iter().flat_map(|m| &m.primitives).any(|p| {
        p.attributes.keys().any(
            |s| matches!(s, gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Joints(n)) if *n >= 2),
        )
    });
    if extra_influences {
        ignored.push("JOINTS_2 and later sets are ignored: skins are posed by at most 8 joints a vertex".to_owned());
    }
    let extra_colours = json.meshes.iter().flat_map(|m| &m.primitives).any(|p| {
        p.attributes.keys().any(
            |s| matches!(s, gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Colors(n)) if *n >= 1),
        )
    });
    if extra_colours {
        ignored.push("COLOR_1 and later sets are ignored: COLOR_0 multiplies the base colour".to_owned());
    }
    if json.materials.iter().any(coat_normal) {
        ignored.push(
            "KHR_materials_clearcoat clearcoatNormalTexture is not implemented: clear coats use the material's normal"
                .to_owned(),
        );
    }
    ignored
}

/// Where a glTF's URIs lead: data URIs, or files relative to the glTF read through `files`.
struct Sources<'a> {
    files: &'a InputFiles,
    directory: &'a Path,
    /// Files read so far. A glTF naming one file for many buffers or images reads it once: a
    /// short JSON listing a large file a thousand times must not read it a thousand times.
    read: RefCell<HashMap<PathBuf, Rc<Vec<u8>>>>,
}

impl Sources<'_> {
    /// The file a URI names (a percent-encoded path relative to the glTF), or `None` for a
    /// `data:` URI.
    fn file_of(&self, uri: &str) -> Result<Option<PathBuf>, String> {
        if uri.starts_with("data:") {
            return Ok(None);
        }
        if uri.contains("://") {
            return Err(format!("'{uri}' is not a local file"));
        }
        let relative = urlencoding::decode(uri).map_err(|e| format!("bad URI '{uri}': {e}"))?;
        Ok(Some(self.directory.join(relative.as_ref())))
    }

    /// The bytes behind a URI: a base64 `data:` URI, or a file read as `kind`.
    fn read_uri(&self, uri: &str, kind: InputKind) -> Result<Rc<Vec<u8>>, String> {
        let Some(file) = self.file_of(uri)? else {
            let (_, payload) = uri.split_once(";base64,").ok_or("only base64 data URIs are supported")?;
            return base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map(Rc::new)
                .map_err(|e| format!("bad base64 data URI: {e}"));
        };
        if let Some(bytes) = self.read.borrow().get(&file) {
            return Ok(Rc::clone(bytes));
        }
        let bytes = Rc::new(self.files.read(&file, kind).map_err(|e| e.to_string())?);
        self.read.borrow_mut().insert(file, Rc::clone(&bytes));
        Ok(bytes)
    }
}

/// Loads every buffer: the GLB binary chunk, a base64 data URI, or a file next to the glTF.
fn load_buffers(document: &Document, mut blob: Option<Vec<u8>>, sources: &Sources) -> Result<Vec<Rc<Vec<u8>>>, String> {
    document
        .buffers()
        .map(|buffer| {
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .take()
                    .map(Rc::new)
                    .ok_or_else(|| format!("buffer {} refers to a missing GLB binary chunk", buffer.index()))?,
                gltf::buffer::Source::Uri(uri) => {
                    sources.read_uri(uri, InputKind::Mesh).map_err(|m| format!("buffer {}: {m}", buffer.index()))?
                }
            };
            if data.len() < buffer.length() {
                return Err(format!(
                    "buffer {} has {} bytes but declares {}",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                ));
            }
            Ok(data)
        })
        .collect()
}

/// What an image's bytes come from: images sharing a buffer view or a file are decoded once.
#[derive(Clone, PartialEq, Eq, Hash)]
enum ImageSource {
    /// A data URI of this image.
    Image(usize),
    View(usize),
    File(PathBuf),
}

/// Textures decoded so far: (source, sRGB, wrap modes) → index into `asset.textures`. An image used
/// as both colour and data, or with two samplers' wrap modes, is stored twice.
type DecodedImages = HashMap<(ImageSource, bool, [Wrap; 2]), usize>;

/// A glTF sampler's wrap mode.
fn wrap(mode: gltf::texture::WrappingMode) -> Wrap {
    match mode {
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    }
}

/// Decodes each texture's image the first time a material uses it in a colour space (sRGB for base
/// colour, linear for metallic-roughness) with its sampler's wrap modes, into `asset.textures`.
fn image_texture(
    texture: gltf::Texture,
    srgb: bool,
    buffers: &[Rc<Vec<u8>>],
    sources: &Sources,
    decoded_images: &mut DecodedImages,
    asset: &mut Asset,
) -> Result<usize, String> {
    let image = texture.source();
    let sampler = texture.sampler();
    let wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
    let source = match image.source() {
        gltf::image::Source::View { view, .. } => ImageSource::View(view.index()),
        gltf::image::Source::Uri { uri, .. } => sources
            .file_of(uri)
            .map_err(|m| format!("image {}: {m}", image.index()))?
            .map_or(ImageSource::Image(image.index()), ImageSource::File),
    };
    if let Some(&index) = decoded_images.get(&(source.clone(), srgb, wrap)) {
        return Ok(index);
    }
    let file_bytes;
    let (bytes, name) = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let bytes = view_bytes(&view, buffers)
                .ok_or_else(|| format!("image {}: its buffer view lies outside the buffer", image.index()))?;
            (bytes, image.name().map_or_else(|| format!("image {}", image.index()), str::to_owned))
        }
        gltf::image::Source::Uri { uri, .. } => {
            let name = image.name().map_or_else(
                || {
                    if uri.starts_with("data:") {
                        format!("image {}", image.index())
                    } else {
                        uri.to_owned()
                    }
                },
                str::to_owned,
            );
            file_bytes =
                sources.read_uri(uri, InputKind::Texture).map_err(|m| format!("image {}: {m}", image.index()))?;
            (file_bytes.as_slice(), name)
        }
    };
    let mut decoded = texture::decode_texture(bytes, name, srgb)?;
    decoded.wrap = wrap;
    asset.textures.push(decoded);
    decoded_images.insert((source, srgb, wrap), asset.textures.len() - 1);
    Ok(asset.textures.len() - 1)
}

fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Rc<Vec<u8>>]) -> Option<&'b [u8]> {
    let end = view.offset().checked_add(view.length())?;
    buffers.get(view.buffer().index())?.get(view.offset()..end)
}

/// Where a material's textures are read: a TEXCOORD set, and the affine map of it that
/// `KHR_texture_transform` gives (T x R x S of the extension: offset, rotation, scale).
#[derive(Clone, Copy, Debug, PartialEq)]
struct UvMapping {
    set: u32,
    transform: Affine2,
}

impl UvMapping {
    const PLAIN: UvMapping = UvMapping { set: 0, transform: Affine2::IDENTITY };

    /// The mapping a texture reference names.
    fn of(tex_coord: u32, transform: Option<gltf::texture::TextureTransform>) -> UvMapping {
        UvMapping::of_parts(tex_coord, transform.map(|t| (t.offset(), t.rotation(), t.scale(), t.tex_coord())))
    }

    /// The mapping of a texture reference read from the JSON (an extension's, which the gltf
    /// crate does not parse).
    fn of_json(tex_coord: u32, transform: Option<&gltf::json::extensions::texture::TextureTransform>) -> UvMapping {
        UvMapping::of_parts(tex_coord, transform.map(|t| (t.offset.0, t.rotation.0, t.scale.0, t.tex_coord)))
    }

    fn of_parts(tex_coord: u32, transform: Option<TransformParts>) -> UvMapping {
        let Some((offset, rotation, scale, set)) = transform else {
            return UvMapping { set: tex_coord, ..UvMapping::PLAIN };
        };
        let (sin, cos) = rotation.sin_cos();
        // The extension's rotation matrix has rows (cos, sin) and (-sin, cos); glam's columns.
        let rotation = Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos));
        let scale = Mat2::from_diagonal(Vec2::from(scale));
        UvMapping {
            set: set.unwrap_or(tex_coord),
            transform: Affine2::from_mat2_translation(rotation * scale, Vec2::from(offset)),
        }
    }
}

/// A `KHR_texture_transform`'s offset, rotation, scale and texCoord override.
type TransformParts = ([f32; 2], f32, [f32; 2], Option<u32>);

/// A material's one [`UvMapping`], and whether its textures named others (which it replaces).
struct MaterialUvs {
    mapping: UvMapping,
    mixed: bool,
}

/// The mapping of the material's first texture among base colour, emissive, metallic-roughness,
/// normal (normal textures carry no transform the gltf crate reads) and the clear coat's.
fn material_uvs(material: &gltf::Material, clearcoat: Option<&ClearcoatJson>) -> MaterialUvs {
    let pbr = material.pbr_metallic_roughness();
    let info = |i: Option<gltf::texture::Info>| i.map(|i| UvMapping::of(i.tex_coord(), i.texture_transform()));
    let coat_textures =
        clearcoat.map_or([None, None], |c| [c.clearcoat_texture.as_ref(), c.clearcoat_roughness_texture.as_ref()]);
    let mappings: Vec<UvMapping> = [
        info(pbr.base_color_texture()),
        info(material.emissive_texture()),
        info(pbr.metallic_roughness_texture()),
        material.normal_texture().map(|n| UvMapping::of(n.tex_coord(), None)),
    ]
    .into_iter()
    .chain(coat_textures.map(|t| t.map(TextureRefJson::mapping)))
    .flatten()
    .collect();
    let mapping = mappings.first().copied().unwrap_or(UvMapping::PLAIN);
    MaterialUvs { mapping, mixed: mappings.iter().any(|m| *m != mapping) }
}

/// `KHR_materials_clearcoat` as the file gives it (the gltf crate does not parse it).
#[derive(serde::Deserialize, Default)]
#[serde(rename_all = "camelCase", default)]
struct ClearcoatJson {
    clearcoat_factor: f32,
    clearcoat_texture: Option<TextureRefJson>,
    clearcoat_roughness_factor: f32,
    clearcoat_roughness_texture: Option<TextureRefJson>,
}

/// A `textureInfo` inside an extension the gltf crate does not parse.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct TextureRefJson {
    index: usize,
    #[serde(default)]
    tex_coord: u32,
    #[serde(default)]
    extensions: TextureRefExtensionsJson,
}

#[derive(serde::Deserialize, Default)]
struct TextureRefExtensionsJson {
    #[serde(rename = "KHR_texture_transform")]
    texture_transform: Option<gltf::json::extensions::texture::TextureTransform>,
}

impl TextureRefJson {
    fn mapping(&self) -> UvMapping {
        UvMapping::of_json(self.tex_coord, self.extensions.texture_transform.as_ref())
    }
}

/// The material's `KHR_materials_clearcoat`, if it has one; an error for one that is malformed.
fn clearcoat_json(material: &gltf::Material) -> Result<Option<ClearcoatJson>, String> {
    let Some(value) = material.extensions().and_then(|e| e.get("KHR_materials_clearcoat")) else {
        return Ok(None);
    };
    let index = material.index().unwrap_or(0);
    serde_json::from_value(value.clone())
        .map(Some)
        .map_err(|e| format!("material {index}: KHR_materials_clearcoat: {e}"))
}

/// The material's clear coat: factors checked, textures decoded (linear data: R scales the factor,
/// G the roughness). A coat of factor 0 is none. `clearcoatNormalTexture` is not read: the coat
/// shares the material's shading normal (a warning per file, from `ignored_features`).
fn convert_clearcoat(
    index: usize,
    coat: &ClearcoatJson,
    document: &Document,
    buffers: &[Rc<Vec<u8>>],
    sources: &Sources,
    decoded_images: &mut DecodedImages,
    asset: &mut Asset,
) -> Result<Option<Clearcoat>, String> {
    let (factor, roughness) = (coat.clearcoat_factor, coat.clearcoat_roughness_factor);
    if !factor.is_finite() || !roughness.is_finite() {
        return Err(format!(
            "material {index}: KHR_materials_clearcoat clearcoatFactor or clearcoatRoughnessFactor is not finite"
        ));
    }
    if factor <= 0.0 {
        return Ok(None);
    }
    let mut texture = |reference: &Option<TextureRefJson>, what: &str| -> Result<Option<u32>, String> {
        let Some(reference) = reference else { return Ok(None) };
        let texture = document.textures().nth(reference.index).ok_or_else(|| {
            format!("material {index}: KHR_materials_clearcoat {what}: texture {} does not exist", reference.index)
        })?;
        Ok(Some(image_texture(texture, false, buffers, sources, decoded_images, asset)? as u32))
    };
    Ok(Some(Clearcoat {
        factor: factor.min(1.0),
        roughness: roughness.clamp(0.0, 1.0),
        texture: texture(&coat.clearcoat_texture, "clearcoatTexture")?,
        roughness_texture: texture(&coat.clearcoat_roughness_texture, "clearcoatRoughnessTexture")?,
    }))
}

/// The material's `KHR_materials_volume` absorption, for a transmissive material (no light
/// enters any other). `thicknessFactor` and `thicknessTexture` are ignored: they stand in for the
/// thickness that rasterizers cannot trace, and a path tracer measures the real one along each
/// ray (every transmissive mesh refracts at its faces in caustica, so it is always a volume).
fn convert_volume(index: usize, material: &gltf::Material, transmission: f32) -> Result<Option<Attenuation>, String> {
    let Some(volume) = material.volume() else { return Ok(None) };
    let (color, distance) = (Vec3::from(volume.attenuation_color()), volume.attenuation_distance());
    if !color.is_finite() || distance.is_nan() || distance <= 0.0 {
        return Err(format!(
            "material {index}: KHR_materials_volume attenuationColor is not finite or attenuationDistance is not > 0"
        ));
    }
    // The default distance is infinite: no absorption.
    if transmission <= 0.0 || distance == f32::INFINITY || color.min_element() >= 1.0 {
        return Ok(None);
    }
    // glTF's colours lie in [0, 1]; 0 (all absorbed at once) is kept finite.
    Ok(Some(Attenuation { color: color.clamp(Vec3::splat(1e-6), Vec3::ONE), distance }))
}

#[allow(clippy::too_many_arguments)]
fn convert_material(
    material: &gltf::Material,
    document: &Document,
    buffers: &[Rc<Vec<u8>>],
    sources: &Sources,
    decoded_images: &mut DecodedImages,
    asset: &mut Asset,
) -> Result<(Material, MaterialUvs), String> {
    let index = material.index().unwrap_or(0);
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, opacity] = pbr.base_color_factor();
    let albedo_texture = match pbr.base_color_texture() {
        Some(info) => Some(image_texture(info.texture(), true, buffers, sources, decoded_images, asset)?),
        _ => None,
    };
    let emission = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
    // Decoded only when it can show: glTF's default factor is black, and black times the texture
    // is nothing to render.
    let emission_texture = match material.emissive_texture() {
        Some(info) if emission.max_element() > 0.0 => {
            Some(image_texture(info.texture(), true, buffers, sources, decoded_images, asset)? as u32)
        }
        _ => None,
    };
    let normal = match material.normal_texture() {
        Some(info) => Some(NormalMap {
            texture: image_texture(info.texture(), false, buffers, sources, decoded_images, asset)? as u32,
            scale: info.scale(),
        }),
        _ => None,
    };
    if normal.is_some_and(|n| !n.scale.is_finite()) {
        return Err(format!("material {index}: normalTexture.scale is not finite"));
    }
    if !emission.is_finite() {
        return Err(format!("material {index}: emission overflows"));
    }
    // glTF's mix: the metal covers `metallic`, the dielectric the rest, of which `transmission`
    // is transmitted and the remainder the coated base.
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let transmission = material.transmission().map_or(0.0, |t| t.transmission_factor()).clamp(0.0, 1.0);
    let roughness = pbr.roughness_factor();
    if !roughness.is_finite() {
        return Err(format!("material {index}: roughnessFactor is not finite"));
    }
    let roughness = roughness.clamp(0.0, 1.0);
    let metallic_roughness = match pbr.metallic_roughness_texture() {
        Some(info) => Some(MetallicRoughness {
            texture: image_texture(info.texture(), false, buffers, sources, decoded_images, asset)? as u32,
            metallic,
            roughness,
            transmission,
        }),
        _ => None,
    };
    let mode = match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        gltf::material::AlphaMode::Mask => Some(AlphaMode::Mask { cutoff: material.alpha_cutoff().unwrap_or(0.5) }),
        gltf::material::AlphaMode::Blend => Some(AlphaMode::Blend),
    };
    if !opacity.is_finite() || matches!(mode, Some(AlphaMode::Mask { cutoff }) if !cutoff.is_finite()) {
        return Err(format!("material {index}: baseColorFactor alpha or alphaCutoff is not finite"));
    }
    let alpha =
        mode.map(|mode| Alpha { factor: opacity.clamp(0.0, 1.0), texture: albedo_texture.map(|t| t as u32), mode });
    let clearcoat_json = clearcoat_json(material)?;
    let clearcoat = match &clearcoat_json {
        Some(coat) => convert_clearcoat(index, coat, document, buffers, sources, decoded_images, asset)?,
        None => None,
    };
    let attenuation = convert_volume(index, material, transmission)?;
    let uvs = material_uvs(material, clearcoat_json.as_ref().filter(|_| clearcoat.is_some()));
    if !uvs.mapping.transform.is_finite() {
        return Err(format!("material {index}: KHR_texture_transform is not finite"));
    }
    let converted = Material {
        name: material.name().map_or_else(|| format!("material {index}"), str::to_owned),
        albedo: Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE),
        albedo_texture: albedo_texture.map(|t| t as u32),
        emission: emission.max(Vec3::ZERO),
        reflectivity: metallic,
        transparency: (1.0 - metallic) * transmission,
        ior: material.ior().filter(|&n| n > 0.0).unwrap_or(1.5),
        roughness,
        conductor: Conductor::Albedo,
        coat: true,
        metallic_roughness,
        maps: TextureMaps { emission: emission_texture, normal, alpha },
        clearcoat,
        attenuation,
        // `doubleSided: false` (glTF's default) culls back faces in a rasterizer; here the
        // surface is black from behind. A transmissive material stays two-sided: the light it
        // lets in leaves through its back.
        one_sided: !material.double_sided() && transmission == 0.0,
        ..Material::default()
    };
    Ok((converted, uvs))
}

/// The error for primitive `p`'s accessor `what` that reads past its buffer.
fn outside_buffer(p: usize, what: &str) -> String {
    format!("primitive {p}: the {what} accessor lies outside its buffer")
}

/// A vertex attribute that a merged mesh keeps only when every primitive has it (normals,
/// tangents): floats, or the normalized signed integers of `KHR_mesh_quantization`.
struct VertexAttribute {
    semantic: Semantic,
    name: &'static str,
    dimensions: Dimensions,
}

impl VertexAttribute {
    /// Appends `primitive`'s values to `values` while the primitives before it all had some
    /// (`complete`); returns whether the merged mesh still has one per vertex of its `vertices`.
    fn append<T, const N: usize>(
        &self,
        primitive: &gltf::Primitive,
        limits: &mut AccessorLimits,
        complete: bool,
        values: &mut Vec<T>,
        vertices: usize,
        convert: impl Fn([f32; N]) -> T,
    ) -> Result<bool, String>
    where
        [f32; N]: Item,
        [i8; N]: Item,
        [u8; N]: Item,
        [i16; N]: Item,
        [u16; N]: Item,
        [u32; N]: Item,
    {
        let p = primitive.index();
        match primitive.get(&self.semantic) {
            Some(accessor) if complete => {
                limits
                    .admit(&accessor, self.dimensions, &DIRECTION_TYPES)
                    .map_err(|m| format!("primitive {p}: {} {m}", self.name))?;
                let read = read_floats::<N>(accessor, limits.buffers()).ok_or_else(|| outside_buffer(p, self.name))?;
                values.extend(read.into_iter().map(convert));
                Ok(values.len() == vertices)
            }
            _ => Ok(false),
        }
    }
}

/// What converting meshes left out, said once per file after all are converted.
#[derive(Default)]
struct MeshNotes {
    /// Point and line primitives skipped.
    skipped_primitives: usize,
    /// A MASK or BLEND material's primitive has COLOR_0 alpha below 1, which is not read.
    colour_alpha_ignored: bool,
}

/// Merges a mesh's triangle primitives. An attribute (normals, uvs) is kept only when every
/// primitive has it, since the result needs exactly one per position.
fn convert_mesh(
    mesh: &gltf::Mesh,
    uv_mappings: &[UvMapping],
    limits: &mut AccessorLimits,
    materials: &mut Vec<Material>,
    default_material: &mut Option<u32>,
    notes: &mut MeshNotes,
    weights: &[f32],
) -> Result<(MeshData, VertexInfluences), String> {
    let mut out = MeshData::default();
    let mut influences = VertexInfluences::default();
    let (mut all_normals, mut all_uvs, mut all_tangents) = (true, true, true);
    let (mut normals, mut tangents) = (Vec::new(), Vec::new());
    for primitive in mesh.primitives() {
        let p = primitive.index();
        if matches!(primitive.mode(), Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
            notes.skipped_primitives += 1;
            continue;
        }
        let buffers = limits.buffers();
        let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|b| b.as_slice()));
        let outside = |what: &str| outside_buffer(p, what);

        let position_accessor =
            primitive.get(&Semantic::Positions).ok_or_else(|| format!("primitive {p} has no POSITION"))?;
        limits
            .admit(&position_accessor, Dimensions::Vec3, &QUANTIZED_TYPES)
            .map_err(|m| format!("primitive {p}: POSITION {m}"))?;
        let mut positions: Vec<Vec3> = read_floats::<3>(position_accessor, buffers)
            .ok_or_else(|| outside("POSITION"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        influences.append(&primitive, positions.len(), limits)?;
        let first_normal = normals.len();
        let first_tangent = tangents.len();
        if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
            return Err(format!("primitive {p}: vertex {i} has a non-finite position"));
        }
        let base = u32::try_from(out.positions.len() + positions.len())
            .map_err(|_| "more than 2^32 vertices".to_owned())?
            - positions.len() as u32;

        let vertices = out.positions.len() + positions.len();
        let normal = VertexAttribute { semantic: Semantic::Normals, name: "NORMAL", dimensions: Dimensions::Vec3 };
        all_normals = normal.append(&primitive, limits, all_normals, &mut normals, vertices, Vec3::from)?;
        let tangent = VertexAttribute { semantic: Semantic::Tangents, name: "TANGENT", dimensions: Dimensions::Vec4 };
        all_tangents = tangent.append(&primitive, limits, all_tangents, &mut tangents, vertices, Vec4::from)?;
        // Morph targets displace the vertices by their weights (the node's, else the mesh's:
        // `weights`), once, here: the kernel sees the morphed mesh.
        let morphed = Morphed {
            positions: &mut positions,
            normals: (all_normals && normals.len() == vertices).then(|| &mut normals[first_normal..]),
            tangents: (all_tangents && tangents.len() == vertices).then(|| &mut tangents[first_tangent..]),
        };
        morphed.apply(&primitive, weights, limits)?;
        if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
            return Err(format!("primitive {p}: morphed vertex {i} has a non-finite position"));
        }
        // The coordinates its material's textures are read through, mapped as they say.
        let uv_mapping =
            primitive.material().index().and_then(|m| uv_mappings.get(m)).copied().unwrap_or(UvMapping::PLAIN);
        let set = uv_mapping.set;
        match primitive.get(&Semantic::TexCoords(set)) {
            Some(accessor) if all_uvs => {
                limits
                    .admit(&accessor, Dimensions::Vec2, &QUANTIZED_TYPES)
                    .map_err(|m| format!("primitive {p}: TEXCOORD_{set} {m}"))?;
                out.uvs.extend(
                    read_floats::<2>(accessor, buffers)
                        .ok_or_else(|| outside(&format!("TEXCOORD_{set}")))?
                        .into_iter()
                        .map(|uv| uv_mapping.transform.transform_point2(Vec2::from(uv))),
                );
                all_uvs = out.uvs.len() == out.positions.len() + positions.len();
            }
            _ => all_uvs = false,
        }

        // COLOR_0 multiplies the base colour; a primitive without it is white, so a merged mesh
        // keeps colours when any primitive has them.
        if let Some(accessor) = primitive.get(&Semantic::Colors(0)) {
            let dimensions = match accessor.dimensions() {
                Dimensions::Vec4 => Dimensions::Vec4,
                _ => Dimensions::Vec3,
            };
            limits
                .admit(&accessor, dimensions, &[DataType::F32, DataType::U8, DataType::U16])
                .map_err(|m| format!("primitive {p}: COLOR_0 {m}"))?;
            let read: Vec<[f32; 4]> =
                reader.read_colors(0).ok_or_else(|| outside("COLOR_0"))?.into_rgba_f32().collect();
            if read.len() != positions.len() {
                return Err(format!(
                    "primitive {p}: COLOR_0 has {} values for {} vertices",
                    read.len(),
                    positions.len()
                ));
            }
            if read.iter().any(|c| c[3] < 1.0) && primitive.material().alpha_mode() != gltf::material::AlphaMode::Opaque
            {
                notes.colour_alpha_ignored = true;
            }
            out.colors.resize(out.positions.len(), Vec3::ONE);
            // glTF's colours lie in [0, 1]; a float outside it (or not a number) would create or
            // destroy energy, so it is clamped (NaN to black).
            out.colors.extend(read.iter().map(|&[r, g, b, _]| {
                Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE).map(|c| if c.is_nan() { 0.0 } else { c })
            }));
        } else if !out.colors.is_empty() {
            out.colors.resize(out.positions.len() + positions.len(), Vec3::ONE);
        }

        let indices: Vec<u32> = match primitive.indices() {
            Some(accessor) => {
                limits
                    .admit(&accessor, Dimensions::Scalar, &[DataType::U8, DataType::U16, DataType::U32])
                    .map_err(|m| format!("primitive {p}: indices {m}"))?;
                reader.read_indices().ok_or_else(|| outside("indices"))?.into_u32().collect()
            }
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!("primitive {p} uses vertex {bad} but has {} vertices", positions.len()));
        }
        let material = match primitive.material().index() {
            Some(m) => m as u32,
            None => *default_material.get_or_insert_with(|| {
                materials.push(Material::default());
                materials.len() as u32 - 1
            }),
        };
        let triangles = triangulate(primitive.mode(), &indices);
        out.triangle_materials.extend(std::iter::repeat_n(material, triangles.len()));
        out.triangles.extend(triangles.into_iter().map(|t| t.map(|i| i + base)));
        out.positions.extend(positions);
    }
    if !out.colors.is_empty() {
        out.colors.resize(out.positions.len(), Vec3::ONE);
    }
    out.normals = if all_normals { unit_normals(&normals) } else { Vec::new() };
    if !all_uvs || out.uvs.iter().any(|uv| !uv.is_finite()) {
        out.uvs.clear();
    }
    // The file's tangents serve only with the normals and coordinates they were made for, and
    // only when every one has a direction (else MikkTSpace builds them all: tangents.rs).
    if all_tangents && !out.normals.is_empty() && !out.uvs.is_empty() {
        let unit: Option<Vec<Vec4>> = tangents
            .iter()
            .map(|t| {
                let direction = t.truncate().normalize_or_zero();
                (direction != Vec3::ZERO && t.w.is_finite())
                    .then(|| direction.extend(if t.w < 0.0 { -1.0 } else { 1.0 }))
            })
            .collect();
        out.tangents = unit.unwrap_or_default();
    }
    Ok((out, influences))
}

/// One primitive's vertex data as read, which its morph targets displace.
struct Morphed<'m> {
    positions: &'m mut [Vec3],
    /// The primitive's normals and tangents, where the merged mesh still keeps them.
    normals: Option<&'m mut [Vec3]>,
    tangents: Option<&'m mut [Vec4]>,
}

impl Morphed<'_> {
    /// Adds each morph target's displacements times its weight (glTF: targets beyond `weights`
    /// weigh 0). Normals and tangents are renormalized later with the rest of the mesh's.
    fn apply(self, primitive: &gltf::Primitive, weights: &[f32], limits: &mut AccessorLimits) -> Result<(), String> {
        let p = primitive.index();
        let count = self.positions.len();
        let Morphed { positions, mut normals, mut tangents } = self;
        for (k, target) in primitive.morph_targets().enumerate() {
            let weight = weights.get(k).copied().unwrap_or(0.0);
            if weight == 0.0 {
                continue;
            }
            if !weight.is_finite() {
                return Err(format!("primitive {p}: morph target {k}'s weight is not finite"));
            }
            let displacements = |accessor: Option<gltf::Accessor>, what: &str, limits: &mut AccessorLimits| {
                let Some(accessor) = accessor else { return Ok(None) };
                limits
                    .admit(&accessor, Dimensions::Vec3, &QUANTIZED_TYPES)
                    .map_err(|m| format!("primitive {p}: morph target {k} {what} {m}"))?;
                let read = read_floats::<3>(accessor, limits.buffers())
                    .ok_or_else(|| outside_buffer(p, &format!("morph target {k} {what}")))?;
                if read.len() != count {
                    return Err(format!(
                        "primitive {p}: morph target {k} {what} has {} values for {count} vertices",
                        read.len()
                    ));
                }
                Ok(Some(read))
            };
            if let Some(d) = displacements(target.positions(), "POSITION", limits)? {
                positions.iter_mut().zip(d).for_each(|(v, d)| *v += weight * Vec3::from(d));
            }
            if let (Some(normals), Some(d)) =
                (normals.as_deref_mut(), displacements(target.normals(), "NORMAL", limits)?)
            {
                normals.iter_mut().zip(d).for_each(|(n, d)| *n += weight * Vec3::from(d));
            }
            if let (Some(tangents), Some(d)) =
                (tangents.as_deref_mut(), displacements(target.tangents(), "TANGENT", limits)?)
            {
                tangents.iter_mut().zip(d).for_each(|(t, d)| *t += weight * Vec3::from(d).extend(0.0));
            }
        }
        Ok(())
    }
}

/// Triangles of a triangle-list, strip or fan primitive; strips alternate winding so that every
/// triangle keeps the orientation of the first.
fn triangulate(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => indices
            .windows(3)
            .enumerate()
            .map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] })
            .collect(),
        Mode::TriangleFan => indices.windows(2).skip(1).map(|w| [indices[0], w[0], w[1]]).collect(),
        _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// The default scene's nodes, else scene 0's, else every node that is no other node's child.
fn root_nodes(document: &Document) -> Vec<gltf::Node<'_>> {
    if let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) {
        return scene.nodes().collect();
    }
    let mut is_child = vec![false; document.nodes().len()];
    for child in document.nodes().flat_map(|node| node.children()) {
        is_child[child.index()] = true;
    }
    document.nodes().filter(|node| !is_child[node.index()]).collect()
}

/// Depth-first walk of the node hierarchy collecting instances and the first camera. Each node
/// may be reached once: a cycle or a node with two parents is an invalid file, not a hang.
struct Walk<'a> {
    ancestors: Vec<usize>,
    visited: Vec<bool>,
    /// Nodes whose morph weights differ from their mesh's: the index of their own morphed copy
    /// in `asset.meshes`.
    node_meshes: &'a HashMap<usize, usize>,
    /// Every visited node's world transform, for skins' joints.
    worlds: Vec<Option<Mat4>>,
    /// (index into `asset.instances`, node) of every instance of a skinned node.
    skinned: Vec<(usize, usize)>,
    asset: &'a mut Asset,
}

impl Walk<'_> {
    fn visit(&mut self, node: gltf::Node, parent: Mat4) -> Result<(), String> {
        let index = node.index();
        if self.ancestors.contains(&index) {
            return Err(format!("node {index} is its own ancestor (cyclic node graph)"));
        }
        if std::mem::replace(&mut self.visited[index], true) {
            return Err(format!("node {index} is reached twice (it has two parents, or two scenes list it)"));
        }
        if self.ancestors.len() >= MAX_NODE_DEPTH {
            return Err(format!("node {index} is nested deeper than {MAX_NODE_DEPTH} levels"));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !local.is_finite() {
            return Err(format!("node {index} has a non-finite transform"));
        }
        let world = parent * local;
        self.worlds[index] = Some(world);
        if let Some(mesh) = node.mesh() {
            let mesh = self.node_meshes.get(&index).copied().unwrap_or(mesh.index());
            if node.skin().is_some() {
                self.skinned.push((self.asset.instances.len(), index));
            }
            self.asset.instances.push((mesh, world));
        }
        if let (None, Some(camera)) = (&self.asset.camera, node.camera()) {
            if let gltf::camera::Projection::Perspective(perspective) = camera.projection() {
                self.asset.camera = Some(world_camera(index, world, &perspective)?);
            }
        }
        if let Some(light) = node.light() {
            self.asset.lights.push(world_light(index, world, &light)?);
        }
        self.ancestors.push(index);
        for child in node.children() {
            self.visit(child, world)?;
        }
        self.ancestors.pop();
        Ok(())
    }
}

/// A `KHR_lights_punctual` light of node `node` in caustica's units (see the module's notes); it
/// shines down the node's −Z.
fn world_light(node: usize, world: Mat4, light: &gltf::khr_lights_punctual::Light) -> Result<Light, String> {
    let what = format!("node {node}: KHR_lights_punctual light {}", light.index());
    let color = Vec3::from(light.color());
    if !color.is_finite() || color.min_element() < 0.0 {
        return Err(format!("{what}: color must be finite and >= 0, got {color:?}"));
    }
    let intensity = light.intensity();
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(format!("{what}: intensity must be finite and >= 0, got {intensity}"));
    }
    let value = color * (intensity / LUMENS_PER_WATT);
    let local = match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => Light::Point { position: Vec3::ZERO, intensity: value },
        gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let quarter = std::f32::consts::FRAC_PI_2;
            if !(outer_cone_angle > 0.0
                && outer_cone_angle <= quarter
                && (0.0..outer_cone_angle).contains(&inner_cone_angle))
            {
                return Err(format!(
                    "{what}: spot angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2, got {inner_cone_angle} and {outer_cone_angle}"
                ));
            }
            Light::Spot {
                position: Vec3::ZERO,
                axis: Vec3::NEG_Z,
                intensity: value,
                cone_angle: outer_cone_angle,
                falloff_start: inner_cone_angle,
            }
        }
        gltf::khr_lights_punctual::Kind::Directional => {
            Light::Directional { direction: Vec3::NEG_Z, irradiance: value, angular_diameter: 0.0 }
        }
    };
    local.transformed(world).ok_or_else(|| format!("{what}: the node's transform collapses its direction"))
}

/// A glTF camera looks down its node's −Z with +Y up.
fn world_camera(node: usize, world: Mat4, perspective: &gltf::camera::Perspective) -> Result<AssetCamera, String> {
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if forward == Vec3::ZERO || up == Vec3::ZERO || forward.cross(up) == Vec3::ZERO {
        return Err(format!("camera node {node} has a degenerate transform"));
    }
    let yfov_degrees = perspective.yfov().to_degrees();
    if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
        return Err(format!("camera node {node} has a vertical field of view of {yfov_degrees} degrees"));
    }
    Ok(AssetCamera {
        position,
        look_at: position + forward,
        up,
        yfov_degrees,
        aspect: perspective.aspect_ratio().filter(|&a| a > 0.0),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{load_asset, real_data, write_file};
    use super::*;

    /// One triangle: positions, normals (length 2, to be normalized), uvs, u16 indices.
    fn triangle_bin() -> Vec<u8> {
        let floats: [f32; 24] =
            [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 2., 0., 0., 2., 0., 0., 2., 0., 0., 1., 0., 0., 1.];
        let mut bin: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        bin.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
        bin.extend([0, 0]);
        bin
    }

    fn png_bytes() -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, 1, 1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.write_header().unwrap().write_image_data(&[10, 20, 30]).unwrap();
        bytes
    }

    /// A glTF document around `buffer` (its JSON object) and `images` (a JSON array): node 0
    /// (translated) and its child node 1 (scaled) both place mesh 0, node 2 holds a camera.
    /// Mesh 0 has an indexed primitive with material 0 and a non-indexed one without normals
    /// or material.
    fn document(buffer: &str, images: &str) -> String {
        let base64 = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
        format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior"],
  "scene": 0,
  "scenes": [{{"nodes": [0, 2]}}],
  "nodes": [
    {{"translation": [1, 2, 3], "children": [1], "mesh": 0}},
    {{"scale": [2, 2, 2], "mesh": 0}},
    {{"translation": [0, 0, 5], "camera": 0}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [
    {{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3, "material": 0}},
    {{"attributes": {{"POSITION": 0, "TEXCOORD_0": 2}}}}
  ]}}],
  "materials": [{{
    "name": "glowing glass",
    "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.6, 0.7, 0.75], "baseColorTexture": {{"index": 0}}, "metallicFactor": 1, "roughnessFactor": 0.2, "metallicRoughnessTexture": {{"index": 0}}}},
    "emissiveFactor": [1, 0.5, 0.25],
    "emissiveTexture": {{"index": 0}},
    "alphaMode": "MASK",
    "alphaCutoff": 0.25,
    "normalTexture": {{"index": 0, "scale": 0.75}},
    "extensions": {{
      "KHR_materials_emissive_strength": {{"emissiveStrength": 4}},
      "KHR_materials_transmission": {{"transmissionFactor": 0.5}},
      "KHR_materials_ior": {{"ior": 1.4}}
    }}
  }}],
  "textures": [{{"source": 0}}, {{"source": 1}}],
  "images": {images},
  "buffers": [{buffer}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 72, "byteLength": 24}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 104, "byteLength": {png_len}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}}"#,
            png_len = png_bytes().len(),
        )
        // The emissive image (index 1) is garbage: it must never be decoded.
        .replace("GARBAGE", &format!("data:image/png;base64,{}", base64(b"garbage")))
        .replace("PNG_URI", &format!("data:image/png;base64,{}", base64(&png_bytes())))
    }

    fn check_scene(asset: &Asset) {
        assert_eq!(asset.meshes.len(), 1);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        assert!(mesh.normals.is_empty(), "the second primitive has no normals");
        assert_eq!(mesh.uvs[1], Vec2::new(1.0, 0.0), "glTF uvs are kept as stored");
        assert_eq!(mesh.uvs[2], Vec2::new(0.0, 1.0));
        assert_eq!(mesh.triangle_materials, vec![0, 1]);

        let parent = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(asset.instances, vec![(0, parent), (0, parent * Mat4::from_scale(Vec3::splat(2.0)))]);

        let glass = &asset.materials[0];
        assert_eq!(glass.name, "glowing glass");
        assert_eq!(glass.albedo, Vec3::new(0.5, 0.6, 0.7));
        assert_eq!(glass.emission, Vec3::new(4.0, 2.0, 1.0));
        assert_eq!(
            (glass.transparency, glass.reflectivity, glass.ior, glass.roughness),
            (0.0, 1.0, 1.4, 0.2),
            "metallic 1 covers the surface: its transmission 0.5 weighs (1 - metallic) x 0.5 = 0"
        );
        assert_eq!((glass.conductor, glass.coat), (Conductor::Albedo, true));
        assert_eq!(asset.materials[1], Material::default());
        assert_eq!(glass.albedo_texture, Some(0));
        assert_eq!(glass.maps.emission, Some(0), "the emissive texture is image 0 as colour, decoded once for both");
        assert_eq!(
            glass.maps.normal,
            Some(NormalMap { texture: 1, scale: 0.75 }),
            "the normal map is image 0 as data, shared with metallic-roughness"
        );
        let mask = Alpha { factor: 0.75, texture: Some(0), mode: AlphaMode::Mask { cutoff: 0.25 } };
        assert_eq!(
            glass.maps.alpha,
            Some(mask),
            "baseColorFactor alpha times the base colour texture's, cut at alphaCutoff"
        );
        assert_eq!(
            glass.metallic_roughness,
            Some(MetallicRoughness { texture: 1, metallic: 1.0, roughness: 0.2, transmission: 0.5 }),
            "the texture scales the factors; the kernel weighs transmission by 1 - metallic per texel"
        );
        assert_eq!(
            asset.textures.len(),
            2,
            "image 0 is decoded once as colour (base colour, emission) and once as data (metallic-roughness, normals); image 1 never"
        );
        for (texture, srgb) in asset.textures.iter().zip([true, false]) {
            assert_eq!(texture.texels, vec![[10, 20, 30, 255]]);
            assert_eq!(texture.srgb, srgb, "base colour is sRGB, metallic-roughness linear");
        }

        let camera = asset.camera.unwrap();
        assert_eq!(
            (camera.position, camera.look_at, camera.up),
            (Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 4.0), Vec3::Y)
        );
        assert!((camera.yfov_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
        assert_eq!(camera.aspect, Some(1.5));
    }

    /// The test document with three KHR_lights_punctual lights on nodes of their own.
    fn document_with_lights(lights: &str) -> String {
        let bin = triangle_bin();
        let json = document(
            &format!(
                r#"{{"uri": "data:application/octet-stream;base64,{}", "byteLength": {}}}"#,
                base64::engine::general_purpose::STANDARD.encode(&bin),
                bin.len()
            ),
            r#"[{"uri": "PNG_URI"}, {"uri": "GARBAGE"}]"#,
        );
        let down = r#""rotation": [-0.70710678, 0, 0, 0.70710678]"#;
        json.replacen(
            r#""asset": {"version": "2.0"},"#,
            &format!(
                r#""asset": {{"version": "2.0"}}, "extensions": {{"KHR_lights_punctual": {{"lights": {lights}}}}},"#
            ),
            1,
        )
        .replacen(r#""scenes": [{"nodes": [0, 2]}],"#, r#""scenes": [{"nodes": [0, 2, 3, 4, 5]}],"#, 1)
        .replacen(
            r#"{"translation": [0, 0, 5], "camera": 0}"#,
            &format!(
                r#"{{"translation": [0, 0, 5], "camera": 0}},
    {{"translation": [1, 2, 3], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"translation": [0, 3, 0], {down}, "extensions": {{"KHR_lights_punctual": {{"light": 1}}}}}},
    {{{down}, "scale": [4, 4, 4], "extensions": {{"KHR_lights_punctual": {{"light": 2}}}}}}"#
            ),
            1,
        )
    }

    /// Candela and lux over 683 lm/W, times the colour; placed and aimed down the node's -Z.
    #[test]
    fn khr_lights_punctual_become_radiometric_lights() {
        let lights = r#"[
          {"type": "point", "color": [1, 0.5, 0.25], "intensity": 683, "range": 10},
          {"type": "spot", "intensity": 1366, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}},
          {"type": "directional", "intensity": 6830}
        ]"#;
        let json = document_with_lights(lights);
        let path = write_file("gltf-lights", "lights.gltf", json.as_bytes());
        let asset = match load_asset(&path) {
            Ok(asset) => asset,
            Err(e) => panic!("{e}\n{json}"),
        };
        assert_eq!(asset.lights.len(), 3);
        assert_eq!(
            asset.lights[0],
            Light::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::new(1.0, 0.5, 0.25) }
        );
        let Light::Spot { position, axis, intensity, cone_angle, falloff_start } = asset.lights[1] else {
            panic!("{:?}", asset.lights[1])
        };
        assert_eq!(
            (position, intensity, cone_angle, falloff_start),
            (Vec3::new(0.0, 3.0, 0.0), Vec3::splat(2.0), 0.4, 0.2)
        );
        assert!((axis - Vec3::NEG_Y).length() < 1e-6, "{axis}");
        let Light::Directional { direction, irradiance, angular_diameter } = asset.lights[2] else {
            panic!("{:?}", asset.lights[2])
        };
        assert!((direction - Vec3::NEG_Y).length() < 1e-6, "{direction}: a scaled node still gives a unit direction");
        assert_eq!((irradiance, angular_diameter), (Vec3::splat(10.0), 0.0));
        // A scene's placement moves them too, twice for two instances.
        let toml = format!("camera = {{ position = [0, 0, 3], look_at = [0, 0, 0] }}\n[[meshes]]\nfile = {:?}\ntranslate = [0, 0, 10]\ninstances = [{{}}, {{ translate = [5, 0, 0] }}]", path.display().to_string());
        let scene = crate::scene::Scene::parse(&toml, "placed.toml", Path::new(".")).unwrap();
        assert_eq!(scene.lights.len(), 6);
        assert_eq!(
            scene.lights[3],
            Light::Point { position: Vec3::new(6.0, 2.0, 13.0), intensity: Vec3::new(1.0, 0.5, 0.25) }
        );

        let negative =
            document_with_lights(r#"[{"type": "point", "intensity": -1}, {"type": "point"}, {"type": "point"}]"#);
        let err = load_asset(&write_file("gltf-lights", "negative.gltf", negative.as_bytes())).unwrap_err().to_string();
        assert!(
            err.contains("negative.gltf")
                && err.contains("KHR_lights_punctual light 0: intensity must be finite and >= 0"),
            "{err}"
        );
        let wide = document_with_lights(
            r#"[{"type": "point"}, {"type": "spot", "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.4}}, {"type": "point"}]"#,
        );
        let err = load_asset(&write_file("gltf-lights", "wide.gltf", wide.as_bytes())).unwrap_err().to_string();
        assert!(err.contains("KHR_lights_punctual light 1: spot angles"), "{err}");
    }

    #[test]
    fn gltf_with_external_bin_and_data_uri_images() {
        let bin = triangle_bin();
        let json = document(
            &format!(r#"{{"uri": "tri%20angle.bin", "byteLength": {}}}"#, bin.len()),
            r#"[{"uri": "PNG_URI"}, {"uri": "GARBAGE"}]"#,
        );
        let path = write_file("gltf-external", "scene.gltf", json.as_bytes());
        std::fs::write(path.with_file_name("tri angle.bin"), &bin).unwrap();
        check_scene(&load_asset(&path).unwrap());

        std::fs::remove_file(path.with_file_name("tri angle.bin")).unwrap();
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains("scene.gltf") && err.contains("tri angle.bin"), "{err}");
    }

    #[test]
    fn glb_with_embedded_image() {
        let mut bin = triangle_bin();
        bin.extend(png_bytes());
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let json = document(
            &format!(r#"{{"byteLength": {}}}"#, bin.len()),
            r#"[{"bufferView": 4, "mimeType": "image/png"}, {"uri": "GARBAGE"}]"#,
        );
        let mut json = json.into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut glb = Vec::new();
        glb.extend(b"glTF");
        glb.extend(2u32.to_le_bytes());
        glb.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
        glb.extend((json.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(&json);
        glb.extend((bin.len() as u32).to_le_bytes());
        glb.extend(b"BIN\0");
        glb.extend(&bin);
        check_scene(&load_asset(&write_file("glb", "scene.GLB", &glb)).unwrap());

        let err = load_asset(&write_file("glb-cut", "cut.glb", &glb[..glb.len() - 40])).unwrap_err().to_string();
        assert!(err.contains("cut.glb"), "{err}");
    }

    /// A required extension caustica lacks is an error naming the file and the extension; used
    /// ones it lacks and occlusion textures are warned about once each.
    #[test]
    fn unimplemented_extensions_are_errors_when_required_and_warnings_when_used() {
        let encode = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
        let buffer = format!(
            r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
            triangle_bin().len(),
            encode(&triangle_bin())
        );
        let png = format!(r#"{{"uri": "data:image/png;base64,{}"}}"#, encode(&png_bytes()));
        let images = format!("[{png}, {png}]");
        let plain = document(&buffer, &images);
        let path = write_file(
            "gltf-required-extension",
            "required.gltf",
            plain
                .replacen(r#""scene": 0,"#, r#""extensionsRequired": ["KHR_draco_mesh_compression"], "scene": 0,"#, 1)
                .as_bytes(),
        );
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()) && err.contains("KHR_draco_mesh_compression"), "{err}");

        let used = plain
            .replacen(
                r#""KHR_materials_ior"]"#,
                r#""KHR_materials_ior", "KHR_materials_sheen", "KHR_materials_sheen", "EXT_texture_webp"]"#,
                1,
            )
            .replacen(r#""normalTexture""#, r#""occlusionTexture": {"index": 0}, "normalTexture""#, 1);
        let json = gltf::Gltf::from_slice_without_validation(used.as_bytes()).unwrap().document.into_json();
        assert_eq!(unimplemented_required_extension(&json), None);
        assert_eq!(
            ignored_features(&json),
            [
                "glTF extension EXT_texture_webp is not implemented: rendering without it",
                "glTF extension KHR_materials_sheen is not implemented: rendering without it",
                "occlusion textures are ignored (a path tracer computes occlusion)",
            ]
        );
        let path = write_file("gltf-used-extension", "used.gltf", used.as_bytes());
        assert!(load_asset(&path).is_ok(), "a used extension caustica lacks is no error");
    }

    /// The test document with `extensions` (JSON members) added to material 0's, which has
    /// transmission 0.5 (`transmission` replaces it), and both clear coat and volume required.
    fn document_with_material_extensions(extensions: &str, transmission: &str) -> String {
        let encode = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
        let buffer = format!(
            r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
            triangle_bin().len(),
            encode(&triangle_bin())
        );
        let png = format!(r#"{{"uri": "data:image/png;base64,{}"}}"#, encode(&png_bytes()));
        document(&buffer, &format!("[{png}, {png}]"))
            .replacen(
                r#""KHR_materials_ior": {"ior": 1.4}"#,
                &format!(r#""KHR_materials_ior": {{"ior": 1.4}}, {extensions}"#),
                1,
            )
            .replacen(r#""transmissionFactor": 0.5"#, &format!(r#""transmissionFactor": {transmission}"#), 1)
            .replacen(
                r#""scene": 0,"#,
                r#""extensionsRequired": ["KHR_materials_clearcoat", "KHR_materials_volume"], "scene": 0,"#,
                1,
            )
    }

    /// KHR_materials_clearcoat (which the gltf crate leaves as JSON) and KHR_materials_volume are
    /// read, and may be required: factors, the coat's two textures (decoded as linear data, the
    /// roughness one shared with the normal map that reads the same texture linearly), and the
    /// attenuation with thicknessFactor ignored.
    #[test]
    fn clearcoat_and_volume_are_read() {
        let coat = r#""KHR_materials_clearcoat": {"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.5, "clearcoatTexture": {"index": 1}, "clearcoatRoughnessTexture": {"index": 0}}"#;
        let volume = r#""KHR_materials_volume": {"thicknessFactor": 3, "attenuationColor": [0.5, 0.25, 1], "attenuationDistance": 2}"#;
        let path = write_file(
            "gltf-coat-volume",
            "coated.gltf",
            document_with_material_extensions(&format!("{coat}, {volume}"), "0.5").as_bytes(),
        );
        let asset = load_asset(&path).unwrap_or_else(|e| panic!("{e}"));
        let m = &asset.materials[0];
        let normal_texture = m.maps.normal.expect("the normal map").texture;
        let coat = m.clearcoat.expect("the clear coat");
        assert_eq!((coat.factor, coat.roughness, coat.roughness_texture), (0.75, 0.5, Some(normal_texture)));
        let texture = coat.texture.expect("the clear coat texture") as usize;
        assert!(
            texture != normal_texture as usize && !asset.textures[texture].srgb,
            "texture 1, decoded as data: {texture}"
        );
        assert_eq!(m.attenuation, Some(Attenuation { color: Vec3::new(0.5, 0.25, 1.0), distance: 2.0 }));
        assert!(
            (m.attenuation.unwrap().sigma_a() - Vec3::new(2f32.ln() / 2.0, 4f32.ln() / 2.0, 0.0)).abs().max_element()
                < 1e-6
        );

        // No coat at factor 0 (its default), no absorption at the default infinite distance or
        // without transmission.
        for (extensions, transmission) in [
            (
                r#""KHR_materials_clearcoat": {"clearcoatRoughnessFactor": 0.5}, "KHR_materials_volume": {"thicknessFactor": 1}"#,
                "0.5",
            ),
            (volume, "0"),
        ] {
            let path = write_file(
                "gltf-no-coat-volume",
                "plain.gltf",
                document_with_material_extensions(extensions, transmission).as_bytes(),
            );
            let asset = load_asset(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!((asset.materials[0].clearcoat, asset.materials[0].attenuation), (None, None), "{extensions}");
        }
    }

    /// A malformed clear coat or volume is an error naming the file, the material and the fault.
    #[test]
    fn malformed_clearcoat_and_volume_are_errors() {
        for (extensions, fault) in [
            (
                r#""KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatTexture": {"index": 7}}"#,
                "clearcoatTexture: texture 7 does not exist",
            ),
            (
                r#""KHR_materials_clearcoat": {"clearcoatFactor": "thick"}"#,
                "material 0: KHR_materials_clearcoat: invalid type",
            ),
            (
                r#""KHR_materials_clearcoat": {"clearcoatFactor": 1e39}"#,
                "clearcoatFactor or clearcoatRoughnessFactor is not finite",
            ),
            (
                r#""KHR_materials_volume": {"attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 0}"#,
                "attenuationDistance is not > 0",
            ),
        ] {
            let path = write_file(
                "gltf-bad-coat-volume",
                "bad.gltf",
                document_with_material_extensions(extensions, "0.5").as_bytes(),
            );
            let err = load_asset(&path).unwrap_err().to_string();
            assert!(err.contains("bad.gltf") && err.contains(fault), "{extensions}: {err}");
        }
    }

    /// The coat's own normal map is not read: a warning says the material's normal serves.
    #[test]
    fn clearcoat_normal_texture_is_warned_about() {
        let json = document_with_material_extensions(
            r#""KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatNormalTexture": {"index": 0}}"#,
            "0.5",
        );
        let json = gltf::Gltf::from_slice_without_validation(json.as_bytes()).unwrap().document.into_json();
        assert_eq!(unimplemented_required_extension(&json), None);
        assert_eq!(ignored_features(&json), ["KHR_materials_clearcoat clearcoatNormalTexture is not implemented: clear coats use the material's normal"]);
    }

    #[test]
    fn cyclic_node_graph_is_an_error() {
        let json = r#"{"asset": {"version": "2.0"}, "nodes": [{"children": [1]}, {"children": [0]}], "scenes": [{"nodes": [0]}]}"#;
        let path = write_file("gltf-cycle", "cycle.gltf", json.as_bytes());
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains("cycle.gltf") && err.contains("cyclic"), "{err}");
    }

    #[test]
    fn out_of_range_index_is_an_error() {
        let mut bin = triangle_bin();
        bin[96..98].copy_from_slice(&7u16.to_le_bytes());
        let json = document(
            &format!(r#"{{"uri": "t.bin", "byteLength": {}}}"#, bin.len()),
            r#"[{"uri": "PNG_URI"}, {"uri": "GARBAGE"}]"#,
        );
        let path = write_file("gltf-index", "scene.gltf", json.as_bytes());
        std::fs::write(path.with_file_name("t.bin"), &bin).unwrap();
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains("mesh 0") && err.contains("uses vertex 7 but has 3 vertices"), "{err}");
    }

    #[test]
    fn strips_and_fans_keep_winding() {
        assert_eq!(triangulate(Mode::TriangleStrip, &[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(triangulate(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(triangulate(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
    }

    #[test]
    fn real_damaged_helmet() {
        let Some(path) = real_data("meshes/DamagedHelmet/glTF/DamagedHelmet.gltf") else {
            return;
        };
        let start = std::time::Instant::now();
        let asset = load_asset(&path).unwrap();
        let triangles: usize = asset.meshes.iter().map(|m| m.triangles.len()).sum();
        println!(
            "{}: {triangles} triangles, {} textures in {:?}",
            path.display(),
            asset.textures.len(),
            start.elapsed()
        );
        assert_eq!(
            asset.textures.len(),
            4,
            "the base colour, metallic-roughness, emission and normal textures are decoded (not occlusion)"
        );
        assert!(asset.materials[0].maps.normal.is_some());
        assert_eq!(asset.meshes[0].tangents.len(), asset.meshes[0].positions.len(), "tangents for its normal map");
        let emission = asset.materials[0].maps.emission.expect("the helmet glows through a texture");
        assert!(asset.textures[emission as usize].srgb);
        for texture in &asset.textures {
            assert_eq!((texture.width, texture.height), (2048, 2048));
        }
        let metallic_roughness = asset.materials[0].metallic_roughness.unwrap();
        assert!(!asset.textures[metallic_roughness.texture as usize].srgb);
        assert_eq!(asset.instances.len(), 1);
        assert_eq!(asset.meshes[0].normals.len(), asset.meshes[0].positions.len());
        assert_eq!(asset.meshes[0].uvs.len(), asset.meshes[0].positions.len());
    }
}
