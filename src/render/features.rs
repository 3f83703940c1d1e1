//! What of the kernel a scene uses. The kernel is compiled for the scene (issue 11, item 4): code
//! for what the scene lacks (meshes, analytic primitives, a top-level BVH over several instances,
//! textures, emission textures, normal maps, alpha, an environment map, rough lobes, coated bases,
//! clear coats, absorption, Beckmann lobes, anisotropic lobes, thin dielectrics, one-sided
//! surfaces, reflection and refraction lobes, metals' complex Fresnel, each kind of shape and of
//! light) is left out by `#if` and by constants the compiler folds, so the scene pays nothing for
//! it: fewer instructions and live values a path. Mesa 22.3's lavapipe runs every branch of a
//! subgroup even where no lane takes it, so there the code a scene does not use costs as much as
//! the code it does (docs/benchmarks/history.md, 2026-12-01, `be8847b`).
//! A feature wrongly detected as absent changes the image; tests/specialization.rs renders every
//! checked-in scene with both kernels and requires the same sums bit for bit.

use super::layout::ENV_CONSTANT;
use super::layout::{
    GpuMaterial, GpuPrimitive, ALPHA_OPAQUE, CONDUCTOR_COMPLEX, INSTANCE_MESH, INSTANCE_PRIMITIVES, LIGHT_DIRECTIONAL,
    MATERIAL_BECKMANN, MATERIAL_INTERIOR_SHIFT, MATERIAL_NULL, MATERIAL_ONE_SIDED, MATERIAL_THIN, NO_TEXTURE,
    PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE,
};
use super::scene_data::SceneData;
use crate::bvh::{CHILD_INTERIOR, WIDTH};

/// Most shapes a scene may have for its rays to test each in turn rather than walk them in its BVH
/// (`few_shapes`; with no mesh, the `bvh` feature off). Measured on lavapipe with each shape's test
/// compiled in as straight-line code of its kind (docs/benchmarks/history.md, 2026-12-01, `7e4cc16`): at 32 shapes it
/// beats the walk 3-5x on Mesa 25 and 1.3-1.6x on Mesa 22.3; at 48 and 64 Mesa 22.3 is level, and
/// the kernel's compile grows.
pub const FEW_PRIMITIVES: usize = 32;

/// Most few shapes for which a hit's shape record is picked by selects among loads at constant
/// indices (`SCENE_FEW_SHAPE_SELECTS`, shaders/surface.glsl) rather than loaded at each lane's own
/// index, which lavapipe does lane by lane. Measured on Mesa 25 (docs/benchmarks/history.md, 2026-12-06, `ee3ce82`):
/// the selects gain 1.14x on the Cornell box's 9 shapes, are level at 17 and lose 0.90x at 31.
pub const FEW_SHAPE_SELECTS: usize = 12;

pub use crate::scene::ALPHA_DELTA;

/// The bits of a material's flags that hold its interior medium's code (MEDIUM_CODES).
const MEDIUM_CODE_MASK: u32 = 0xff << MATERIAL_INTERIOR_SHIFT;

/// The kinds (PRIM_*) of a scene's few shapes in the order they are stored: its rays test them as
/// straight-line code, each shape by its own kind's test, before walking any mesh (bvh.glsl,
/// `SCENE_FEW_SHAPES`). Empty where the walk meets the shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FewShapes {
    count: u8,
    kinds: [u8; FEW_PRIMITIVES],
}

impl FewShapes {
    /// No shapes listed: the walk meets them, or there are none.
    pub const NONE: Self = Self { count: 0, kinds: [0; FEW_PRIMITIVES] };

    /// The shapes of these kinds, in this order; `None` past FEW_PRIMITIVES or for a kind the
    /// kernel does not know.
    pub fn new(kinds: impl IntoIterator<Item = u32>) -> Option<Self> {
        let mut shapes = Self::NONE;
        for kind in kinds {
            if shapes.count as usize == FEW_PRIMITIVES || kind_name(kind).is_none() {
                return None;
            }
            shapes.kinds[shapes.count as usize] = kind as u8;
            shapes.count += 1;
        }
        Some(shapes)
    }

    /// How many shapes are listed.
    pub fn len(&self) -> usize {
        self.count as usize
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// `SCENE_FEW_SHAPES`: one `FEW_SHAPE(index, kind)` a shape, in order.
    fn define(&self) -> String {
        let kinds = &self.kinds[..self.count as usize];
        kinds
            .iter()
            .enumerate()
            .map(|(i, &kind)| {
                format!("FEW_SHAPE({i}u, {})", kind_name(kind.into()).expect("FewShapes holds known kinds"))
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// A primitive kind's name in the kernel (layout.glsl).
fn kind_name(kind: u32) -> Option<&'static str> {
    match kind {
        PRIM_SPHERE => Some("PRIM_SPHERE"),
        PRIM_QUAD => Some("PRIM_QUAD"),
        PRIM_TRIANGLE => Some("PRIM_TRIANGLE"),
        _ => None,
    }
}

/// The kernel features a scene needs; each is one `SCENE_*` define (0 or 1) of the kernel, but for
/// the list of shapes tested before any walk. Whether there is a walk, and whether it meets shapes,
/// follow from `meshes`, `primitives` and that list ([`Self::bvh`], [`Self::walked_shapes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SceneFeatures {
    /// The shapes rays test one after another, by kind, before any walk: the scene's own, when
    /// there are at most FEW_PRIMITIVES.
    pub few_shapes: FewShapes,
    /// More than one instance: the kernel walks the top-level BVH (bvh.glsl).
    pub top_level: bool,
    /// A top level deeper than its root: some child of the root is a node, not an instance, so
    /// the top level needs a walk of its own. Without it the root's children are the instances,
    /// tested as one node and walked in turn, nearest first, with no top-level stack.
    pub top_level_tree: bool,
    /// Triangle meshes (mesh instances).
    pub meshes: bool,
    /// The scene's own spheres, quads and triangles.
    pub primitives: bool,
    /// Any texture: albedo and metallic-roughness lookups, and the texture coordinates every
    /// texture reads.
    pub textures: bool,
    /// Emission textures (emissive materials with one): texture lookups for emitters hit and
    /// sampled, and their per-triangle mean luminance for light selection.
    pub emissive_textures: bool,
    /// Tangent-space normal maps on meshes with tangents: the shading normal bent per texel.
    pub normal_maps: bool,
    /// Meshes with vertex colours (glTF COLOR_0): the interpolated colour multiplies the albedo.
    pub vertex_colors: bool,
    /// Mesh materials with alpha (glTF MASK or BLEND, MTL `d` / `map_d`): traversal looks up
    /// the material of every triangle a ray meets (shaders/alpha.glsl); without them it never does.
    pub alpha: bool,
    /// An environment map (else the sky is one colour, never importance sampled).
    pub environment_map: bool,
    /// GGX lobes: a material with a roughness at or above ALPHA_DELTA, or a metallic-roughness
    /// texture (which sets roughness per texel).
    pub rough_lobes: bool,
    /// Plastics: a diffuse base under a dielectric coat.
    pub coated: bool,
    /// Rough lobes of Beckmann's distribution (the MATERIAL_BECKMANN flag).
    pub beckmann: bool,
    /// Anisotropic rough lobes (an alpha along v in `volume[3]`): the anisotropic forms of the
    /// microfacet distributions and the surface's tangent, which orients them.
    pub anisotropic: bool,
    /// Thin dielectric sheets (the MATERIAL_THIN flag).
    pub thin_dielectrics: bool,
    /// Surfaces black from behind (the MATERIAL_ONE_SIDED flag).
    pub one_sided: bool,
    /// glTF clear coats (a factor above 0): the coat's pick in pick_lobe and its textures.
    pub clearcoat: bool,
    /// Absorbing dielectrics (Beer-Lambert, KHR_materials_volume): the attenuation of each path
    /// segment that ends on such a surface from inside.
    pub absorption: bool,
    /// Reflection lobes (LOBE_REFLECT): a material with a reflectivity, a metallic factor under a
    /// metallic-roughness texture, a plastic's coat or a clear coat. Else no mirror or metal code.
    pub reflectors: bool,
    /// Transparent materials (LOBE_DIELECTRIC and thin sheets): a transparency, or a transmission
    /// factor under a metallic-roughness texture. Else no refraction code.
    pub dielectrics: bool,
    /// Metals of a complex index of refraction (CONDUCTOR_COMPLEX: gold, copper, ...): their
    /// Fresnel. Mirrors and albedo-tinted metals need none of it.
    pub complex_conductors: bool,
    /// Spheres, quads and triangles (PRIM_* kinds) among the scene's own shapes and its area
    /// lights (each emissive mesh triangle is a triangle light): each kind's case of the switches
    /// on a primitive's kind (intersect.glsl).
    pub sphere_shapes: bool,
    pub quad_shapes: bool,
    pub triangle_shapes: bool,
    /// Emissive spheres: sampling the cone they subtend (lights.glsl).
    pub sphere_lights: bool,
    /// Emissive triangles: sampling the spherical triangle they subtend.
    pub triangle_lights: bool,
    /// Point, spot and directional lights: their share of light selection.
    pub punctual_lights: bool,
    /// A pick among the lights: any number of them (area or punctual) but one. With exactly one,
    /// its index is the constant 0, so that the light and its material are loaded once for a
    /// subgroup (lavapipe loads at an index it cannot prove uniform lane by lane). A scene of no
    /// light keeps the pick, which never runs: with the constant there, a bunny under a sky
    /// measured 18 % slower on Mesa 25 (docs/benchmarks/history.md, 2026-12-01, `7e4cc16`).
    pub light_pick: bool,
    /// Directional lights with an angular size (a sun's disk): what a path that escapes sees of
    /// them.
    pub light_disks: bool,
    /// Lights picked by the light tree (shaders/light_tree.glsl): `light_selection = "bvh"` and
    /// more than one light. Else the alias table or a uniform pick, and no tree walk.
    pub light_tree: bool,
    /// Participating media or null boundaries (shaders/medium.glsl): the medium a path is in,
    /// free-flight sampling and scattering in it, and shadow rays that pass null boundaries and
    /// are attenuated by the media they cross. Without it the kernel is the surface-only one.
    pub media: bool,
}

impl SceneFeatures {
    /// Every feature: the general kernel, which renders any scene (and is what specialization is
    /// measured against: `caustica bench --general-kernel`).
    pub const ALL: Self = Self {
        few_shapes: FewShapes::NONE,
        top_level: true,
        top_level_tree: true,
        meshes: true,
        primitives: true,
        textures: true,
        emissive_textures: true,
        normal_maps: true,
        vertex_colors: true,
        alpha: true,
        environment_map: true,
        rough_lobes: true,
        coated: true,
        beckmann: true,
        anisotropic: true,
        thin_dielectrics: true,
        one_sided: true,
        clearcoat: true,
        absorption: true,
        reflectors: true,
        dielectrics: true,
        complex_conductors: true,
        sphere_shapes: true,
        quad_shapes: true,
        triangle_shapes: true,
        sphere_lights: true,
        triangle_lights: true,
        punctual_lights: true,
        light_pick: true,
        light_disks: true,
        light_tree: true,
        media: true,
    };

    /// What `data` uses.
    pub fn of(data: &SceneData) -> Self {
        let instances = &data.acceleration.instances;
        let has_instance = |kind| instances.iter().any(|i| i.info[0] == kind);
        // A metallic-roughness texture sets roughness, R and T per texel, scaling the material's
        // factors (surface_material).
        let textured = |m: &GpuMaterial| m.metallic_roughness[0].to_bits() != NO_TEXTURE;
        // A material's own R and T lobes are rough: by its roughness, or per texel by a
        // metallic-roughness texture.
        let rough = |m: &GpuMaterial| m.params[3] >= ALPHA_DELTA || textured(m);
        let flags = |m: &GpuMaterial| m.maps[3].to_bits();
        let kind = |p: &GpuPrimitive| p.b[3].to_bits();
        let lights_of = |k| data.lights.iter().any(|l| kind(l) == k);
        let shapes_of = |k| lights_of(k) || data.acceleration.primitives.iter().any(|p| kind(p) == k);
        // Plastics and clear coats reflect through the reflection lobe too.
        let coated = data.materials.iter().any(|m| m.conductor_k[3] > 0.0);
        let clearcoat = data.materials.iter().any(|m| m.coat[0] > 0.0);
        Self {
            // At most FEW_PRIMITIVES shapes, each of a kind the kernel knows; else the walk meets them.
            few_shapes: FewShapes::new(data.acceleration.primitives.iter().map(kind)).unwrap_or(FewShapes::NONE),
            top_level: instances.len() > 1,
            top_level_tree: instances.len() > 1
                && data
                    .acceleration
                    .nodes
                    .first()
                    .is_some_and(|root| (0..WIDTH).any(|k| root.kind(k) == CHILD_INTERIOR)),
            meshes: has_instance(INSTANCE_MESH),
            primitives: has_instance(INSTANCE_PRIMITIVES),
            textures: !data.textures.is_empty(),
            emissive_textures: data
                .materials
                .iter()
                .any(|m| m.maps[0].to_bits() != NO_TEXTURE && m.emission_t[..3].iter().any(|&e| e > 0.0)),
            normal_maps: !data.acceleration.tangents.is_empty()
                && data.materials.iter().any(|m| m.maps[1].to_bits() != NO_TEXTURE),
            vertex_colors: !data.acceleration.colors.is_empty(),
            alpha: has_instance(INSTANCE_MESH) && data.materials.iter().any(|m| m.alpha[3].to_bits() != ALPHA_OPAQUE),
            environment_map: data.env_kind != ENV_CONSTANT,
            rough_lobes: data
                .materials
                .iter()
                .any(|m| rough(m) || (m.coat[0] > 0.0 && m.coat[1] * m.coat[1] >= ALPHA_DELTA)),
            coated,
            beckmann: data.materials.iter().any(|m| flags(m) & MATERIAL_BECKMANN != 0 && rough(m)),
            anisotropic: data.materials.iter().any(|m| m.volume[3] > 0.0 && rough(m)),
            thin_dielectrics: data.materials.iter().any(|m| flags(m) & MATERIAL_THIN != 0),
            one_sided: data.materials.iter().any(|m| flags(m) & MATERIAL_ONE_SIDED != 0),
            clearcoat,
            absorption: data.materials.iter().any(|m| m.volume[..3].iter().any(|&s| s > 0.0)),
            reflectors: coated
                || clearcoat
                || data.materials.iter().any(|m| m.albedo_r[3] > 0.0 || (textured(m) && m.metallic_roughness[1] > 0.0)),
            dielectrics: data
                .materials
                .iter()
                .any(|m| m.emission_t[3] > 0.0 || (textured(m) && m.metallic_roughness[3] > 0.0)),
            complex_conductors: data.materials.iter().any(|m| m.conductor_eta[3].to_bits() == CONDUCTOR_COMPLEX),
            sphere_shapes: shapes_of(PRIM_SPHERE),
            quad_shapes: shapes_of(PRIM_QUAD),
            triangle_shapes: shapes_of(PRIM_TRIANGLE),
            sphere_lights: lights_of(PRIM_SPHERE),
            triangle_lights: lights_of(PRIM_TRIANGLE),
            punctual_lights: !data.punctual_lights.is_empty(),
            light_pick: data.lights.len() + data.punctual_lights.len() != 1,
            light_disks: data
                .punctual_lights
                .iter()
                .any(|l| l.position_kind[3].to_bits() == LIGHT_DIRECTIONAL && l.shape[2] > 0.0),
            light_tree: data.light_tree.is_some(),
            media: !data.media.is_empty()
                || data.materials.iter().any(|m| flags(m) & (MATERIAL_NULL | MEDIUM_CODE_MASK) != 0),
        }
    }

    /// The BVH walk: a scene with meshes, more than FEW_PRIMITIVES shapes, or nothing at all (the
    /// walk then returns at once, finding no node). Without it rays test the scene's few shapes
    /// one after another (bvh.glsl): every lane of a subgroup reads the same shape at once, which
    /// lavapipe loads once for all of them, and no stack or node is touched.
    pub fn bvh(&self) -> bool {
        self.meshes || self.few_shapes.is_empty()
    }

    /// The walk meets shapes: more than FEW_PRIMITIVES of them (else they are few_shapes).
    pub fn walked_shapes(&self) -> bool {
        self.primitives && self.few_shapes.is_empty()
    }

    /// Each feature's name (as `bench --json` reports it), its kernel define, and whether it is on.
    fn table(&self) -> [(&'static str, &'static str, bool); 33] {
        [
            ("bvh", "SCENE_BVH", self.bvh()),
            ("walked_shapes", "SCENE_WALKED_SHAPES", self.walked_shapes()),
            ("top_level", "SCENE_TOP_LEVEL", self.top_level),
            ("top_level_tree", "SCENE_TOP_LEVEL_TREE", self.top_level_tree),
            ("meshes", "SCENE_MESHES", self.meshes),
            ("primitives", "SCENE_PRIMITIVES", self.primitives),
            ("textures", "SCENE_TEXTURES", self.textures),
            ("emissive_textures", "SCENE_EMISSIVE_TEXTURES", self.emissive_textures),
            ("normal_maps", "SCENE_NORMAL_MAPS", self.normal_maps),
            ("vertex_colors", "SCENE_VERTEX_COLORS", self.vertex_colors),
            ("alpha", "SCENE_ALPHA", self.alpha),
            ("environment_map", "SCENE_ENV_MAP", self.environment_map),
            ("rough_lobes", "SCENE_ROUGH_LOBES", self.rough_lobes),
            ("coated", "SCENE_COATED", self.coated),
            ("beckmann", "SCENE_BECKMANN", self.beckmann),
            ("anisotropic", "SCENE_ANISOTROPIC", self.anisotropic),
            ("thin_dielectrics", "SCENE_THIN_DIELECTRICS", self.thin_dielectrics),
            ("one_sided", "SCENE_ONE_SIDED", self.one_sided),
            ("clearcoat", "SCENE_CLEARCOAT", self.clearcoat),
            ("absorption", "SCENE_ABSORPTION", self.absorption),
            ("reflectors", "SCENE_REFLECTORS", self.reflectors),
            ("dielectrics", "SCENE_DIELECTRICS", self.dielectrics),
            ("complex_conductors", "SCENE_COMPLEX_CONDUCTORS", self.complex_conductors),
            ("sphere_shapes", "SCENE_SPHERE_SHAPES", self.sphere_shapes),
            ("quad_shapes", "SCENE_QUAD_SHAPES", self.quad_shapes),
            ("triangle_shapes", "SCENE_TRIANGLE_SHAPES", self.triangle_shapes),
            ("sphere_lights", "SCENE_SPHERE_LIGHTS", self.sphere_lights),
            ("triangle_lights", "SCENE_TRIANGLE_LIGHTS", self.triangle_lights),
            ("punctual_lights", "SCENE_PUNCTUAL_LIGHTS", self.punctual_lights),
            ("light_pick", "SCENE_LIGHT_PICK", self.light_pick),
            ("light_disks", "SCENE_LIGHT_DISKS", self.light_disks),
            ("light_tree", "SCENE_LIGHT_TREE", self.light_tree),
            ("media", "SCENE_MEDIA", self.media),
        ]
    }

    /// The `#define`s that compile the kernel for these features.
    pub fn defines(&self) -> Vec<(&'static str, String)> {
        let mut defines: Vec<_> =
            self.table().into_iter().map(|(_, define, on)| (define, u32::from(on).to_string())).collect();
        defines.push(("SCENE_FEW_SHAPES", self.few_shapes.define()));
        let selects = !self.few_shapes.is_empty() && self.few_shapes.len() <= FEW_SHAPE_SELECTS;
        defines.push(("SCENE_FEW_SHAPE_SELECTS", u32::from(selects).to_string()));
        defines
    }

    /// The names of the features that are on.
    pub fn names(&self) -> Vec<&'static str> {
        self.table().into_iter().filter(|&(_, _, on)| on).map(|(name, _, _)| name).collect()
    }
}

impl Default for SceneFeatures {
    fn default() -> Self {
        Self::ALL
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_delta_matches_glsl() {
        let glsl = include_str!("../../shaders/microfacet.glsl");
        assert!(
            glsl.contains(&format!("const float ALPHA_DELTA = {ALPHA_DELTA:e};")),
            "ALPHA_DELTA = {ALPHA_DELTA:e} not found in microfacet.glsl"
        );
    }

    fn features_of(scene: &crate::scene::Scene) -> SceneFeatures {
        SceneFeatures::of(&SceneData::new(scene, crate::render::TEXTURE_BUDGET_BYTES))
    }

    #[test]
    fn few_shapes_are_tested_apart_from_the_walk_and_many_are_walked() {
        // (walk, shapes tested apart, walked shapes)
        let shape = |f: SceneFeatures| (f.bvh(), f.few_shapes.len(), f.walked_shapes());
        let mut scene = crate::scene::Scene::default_scene();
        let n = scene.shapes.len();
        assert_eq!(shape(features_of(&scene)), (false, n, false), "the Cornell box is tested shape by shape");
        let sphere = crate::scene::Shape::Sphere { center: glam::Vec3::ZERO, radius: 0.1, material: 0 };
        scene.shapes.resize(FEW_PRIMITIVES, sphere);
        assert_eq!(shape(features_of(&scene)), (false, FEW_PRIMITIVES, false), "{FEW_PRIMITIVES} shapes");
        scene.shapes.push(sphere);
        assert_eq!(shape(features_of(&scene)), (true, 0, true), "{} shapes are walked", FEW_PRIMITIVES + 1);
        let mut meshes = crate::scene::Scene::load(std::path::Path::new("scenes/cornell_original.toml"))
            .expect("a checked-in scene loads");
        assert_eq!(shape(features_of(&meshes)), (true, 0, false), "a scene of meshes alone walks them");
        meshes.shapes.push(sphere);
        assert_eq!(
            shape(features_of(&meshes)),
            (true, 1, false),
            "a mesh scene's one sphere is tested before the walk"
        );
    }

    #[test]
    fn a_top_level_of_up_to_four_instances_is_its_root_alone() {
        // (top level, top level deeper than its root)
        let top = |f: SceneFeatures| (f.top_level, f.top_level_tree);
        let mut scene = crate::scene::Scene::load(std::path::Path::new("scenes/cornell_original.toml"))
            .expect("a checked-in scene loads");
        assert_eq!(scene.instances.len(), 1);
        assert_eq!(top(features_of(&scene)), (false, false), "one instance: no top level");
        let placed = scene.instances[0];
        let shifted = |i: usize| crate::scene::Instance {
            transform: glam::Mat4::from_translation(glam::Vec3::new(3.0 * i as f32, 0.0, 0.0)) * placed.transform,
            ..placed
        };
        for count in 2..=WIDTH {
            scene.instances = (0..count).map(shifted).collect();
            assert_eq!(top(features_of(&scene)), (true, false), "{count} instances are the root's children");
        }
        scene.instances = (0..WIDTH + 1).map(shifted).collect();
        assert_eq!(top(features_of(&scene)), (true, true), "{} instances need a top-level walk", WIDTH + 1);
    }

    #[test]
    fn shape_records_are_picked_by_selects_for_a_handful_of_few_shapes() {
        let selects = |count: usize| {
            let few_shapes = FewShapes::new(std::iter::repeat_n(PRIM_QUAD, count)).expect("at most FEW_PRIMITIVES");
            let defines = SceneFeatures { few_shapes, ..SceneFeatures::ALL }.defines();
            defines.into_iter().find(|(name, _)| *name == "SCENE_FEW_SHAPE_SELECTS").expect("defined").1
        };
        assert_eq!(selects(0), "0", "no few shapes: the walk meets the shapes");
        assert_eq!(selects(1), "1");
        assert_eq!(selects(FEW_SHAPE_SELECTS), "1");
        assert_eq!(selects(FEW_SHAPE_SELECTS + 1), "0");
        assert_eq!(selects(FEW_PRIMITIVES), "0");
    }

    #[test]
    fn every_feature_is_one_define_used_by_the_kernel() {
        let kernel: String = crate::render::kernel::SHADERS.iter().map(|(_, text)| *text).collect();
        for (name, value) in SceneFeatures::ALL.defines() {
            // The few shapes are a scene's own: the kernel that serves every scene lists none.
            let expected = match name {
                "SCENE_FEW_SHAPES" => "",
                "SCENE_FEW_SHAPE_SELECTS" => "0",
                _ => "1",
            };
            assert_eq!(value, expected, "{name}");
            assert!(kernel.contains(name), "{name} is defined for the kernel but no shader file uses it");
        }
    }
}
