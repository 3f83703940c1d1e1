//! Every buffer the kernel binds, declared once in [`BINDINGS`]: its binding number, its name and
//! element type in GLSL, whether it may be split across bindings (chunks.rs) or is read as texels,
//! whether the kernel writes it, and which kernel variants bind it. The kernel's declarations are generated from the
//! table (interface.rs writes the kernel's `interface.glsl`, which layout.glsl includes), and the renderer
//! creates and binds its buffers from it, so no binding number is written anywhere else. The tests
//! compile every variant and check the SPIR-V's bindings and block layouts against the table.

use super::glsl_block::{GlslBlock, GlslMember, GlslTexels, GlslType, Texel};
use super::layout::{
    FrameParams, GpuAliasEntry, GpuInstance, GpuLightTreeNode, GpuMaterial, GpuMedium, GpuMeshTriangle, GpuPrimitive,
    GpuPunctualLight, GpuStats, GpuTexture,
};
use super::variant::KernelVariant;
use super::walk_records::WalkRecords;
use crate::bvh::WideNode;
use crate::gpu::TexelWords;

/// Bindings of windows past the first of a split array (chunks.rs): the array that [`KernelBuffer`]
/// `k` names uses `EXTRA_BINDING_BASE + MAX_CHUNKS * k + (window - 1)`, clear of the table's own
/// bindings, which are all below it.
pub const EXTRA_BINDING_BASE: u32 = 64;

/// Names a buffer of the kernel on the host: the key of [`BINDINGS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KernelBuffer {
    Frame,
    Nodes,
    Primitives,
    Materials,
    Lights,
    EnvTexels,
    Accum,
    Stats,
    Instances,
    MeshTriangles,
    TriangleMaterials,
    VertexNormals,
    VertexUvs,
    TextureInfos,
    Texels,
    EnvCdf,
    LightAlias,
    PunctualLights,
    TriangleEmission,
    VertexTangents,
    AovAlbedoDepth,
    AovNormalHits,
    PathStates,
    SceneStructure,
    LightTree,
    LightTreeIndex,
    VertexColors,
    Media,
    MediumDensities,
}

impl KernelBuffer {
    /// How many buffers there are: the last variant's index + 1 (a variant added after it takes its
    /// place here).
    pub const COUNT: usize = KernelBuffer::MediumDensities as usize + 1;

    /// The table's entry for this buffer.
    pub fn entry(self) -> &'static BufferBinding {
        &BINDINGS[self as usize]
    }
}

/// How the kernel declares a binding.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// `uniform <Block> { ... } <name>;` (std140), the members of a host struct.
    UniformBlock(Block),
    /// `buffer <Block> { ... } <name>;` (std430), the members of a host struct.
    StorageBlock(Block),
    /// `buffer { <element> <name>[]; }` (std430). A `chunked` array may span several bindings
    /// (chunks.rs); the kernel reads it with `load_<name>(i)` and writes it with `store_<name>`.
    Array { element: Element, chunked: bool },
    /// `uniform utextureBuffer <name>_0;`: an array of records read as consecutive unsigned
    /// texels of 1, 2 or 4 words (R32UI, RG32UI, RGBA32UI) of a uniform texel buffer, by
    /// `load_<name>(i)`, and split like a chunked array. For every array the kernel reads at a
    /// per-lane index: lavapipe fetches a texel for all of a subgroup's lanes as straight-line
    /// code, where it loads a storage buffer with a per-lane index one lane at a time, each lane's
    /// load behind a branch of its own (docs/benchmarks/history.md, 2026-12-02, `093d897`, `6ce9ade`). GPUs have read
    /// BVHs through the texture path since Aila and Laine (2009). Which is faster depends on the CPU
    /// under lavapipe too: [`WALK_RECORDS`] become storage arrays where the device reads them so
    /// ([`BufferBinding::in_variant`], walk_records.rs).
    TexelBuffer { element: Element, texels: &'static [Texel] },
    /// `uniform accelerationStructureEXT <name>;`: the scene's top-level acceleration structure,
    /// which ray queries trace (ray_query.glsl); built from the scene's data, not uploaded as it
    /// (ray_query_scene.rs).
    AccelerationStructure,
}

/// A block's GLSL type name and members, from the host struct it is declared by.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    pub type_name: &'static str,
    pub members: &'static [GlslMember],
}

impl Block {
    const fn of<T: GlslBlock>() -> Self {
        Block { type_name: T::NAME, members: T::MEMBERS }
    }
}

/// An array element: its GLSL type and the bytes of the host type uploaded for it.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    pub glsl_type: &'static str,
    pub bytes: u64,
}

impl Element {
    const fn of<T: GlslType>() -> Self {
        Element { glsl_type: T::NAME, bytes: size_of::<T>() as u64 }
    }
}

/// Whether the kernel writes a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Scene data the kernel only reads (`readonly`).
    Read,
    /// What the kernel accumulates or counts.
    ReadWrite,
}

/// Which kernel variants ([`KernelVariant`]) bind a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundIn {
    EveryKernel,
    /// Only kernels built with `AOVS` 1.
    AovKernels,
    /// Only the wavefront's kernels (wavefront.rs).
    WavefrontKernels,
    /// Only kernels that trace with ray queries (`KernelVariant::traversal`).
    RayQueryKernels,
}

/// One binding of the kernel's descriptor set 0.
#[derive(Clone, Copy, Debug)]
pub struct BufferBinding {
    pub buffer: KernelBuffer,
    pub binding: u32,
    /// The name the kernel knows it by: the block's instance, or the array.
    pub name: &'static str,
    pub shape: Shape,
    pub access: Access,
    pub bound_in: BoundIn,
    /// What the host's messages call it.
    pub what: &'static str,
}

impl BufferBinding {
    pub fn is_bound_in(&self, variant: KernelVariant) -> bool {
        match self.bound_in {
            BoundIn::EveryKernel => true,
            BoundIn::AovKernels => variant.aovs,
            BoundIn::WavefrontKernels => variant.wavefront.is_some(),
            BoundIn::RayQueryKernels => variant.traversal == crate::gpu::Traversal::RayQuery,
        }
    }

    pub fn is_written(&self) -> bool {
        self.access == Access::ReadWrite
    }

    /// The element of an array that may span several bindings.
    pub fn chunked_element(&self) -> Option<Element> {
        match self.shape {
            Shape::Array { element, chunked: true } | Shape::TexelBuffer { element, .. } => Some(element),
            _ => None,
        }
    }

    /// How wide the texels are where the kernel reads it as texels (bound as uniform texel
    /// buffers); `None` for a buffer bound as one.
    pub fn texel_words(&self) -> Option<TexelWords> {
        match self.shape {
            Shape::TexelBuffer { texels, .. } => Some(texels[0].words()),
            _ => None,
        }
    }

    /// Whether it is an acceleration structure rather than a buffer.
    pub fn is_acceleration_structure(&self) -> bool {
        matches!(self.shape, Shape::AccelerationStructure)
    }

    /// Whether the kernel reads it as texels.
    pub fn is_texel_buffer(&self) -> bool {
        self.texel_words().is_some()
    }

    /// This binding as `variant` declares it: the walk's records ([`WALK_RECORDS`]) as the
    /// table's texels, or as chunked storage arrays of the same element where the variant reads
    /// them so (walk_records.rs).
    pub fn in_variant(&self, variant: KernelVariant) -> BufferBinding {
        match (self.shape, variant.walk_records) {
            (Shape::TexelBuffer { element, .. }, WalkRecords::Storage) if WALK_RECORDS.contains(&self.buffer) => {
                BufferBinding { shape: Shape::Array { element, chunked: true }, ..*self }
            }
            _ => *self,
        }
    }
}

/// The buffers of the BVH walk's records, read as texels or from storage buffers per device
/// (walk_records.rs); the table declares them as texels.
pub const WALK_RECORDS: [KernelBuffer; 2] = [KernelBuffer::Nodes, KernelBuffer::MeshTriangles];

/// Every buffer `variant` binds, in binding order, as it declares them ([`BufferBinding::in_variant`]).
pub fn bound_in(variant: KernelVariant) -> impl Iterator<Item = BufferBinding> {
    BINDINGS.iter().filter(move |b| b.is_bound_in(variant)).map(move |b| b.in_variant(variant))
}

use Access::{Read, ReadWrite};
use BoundIn::{AovKernels, EveryKernel, RayQueryKernels, WavefrontKernels};
use KernelBuffer::*;

/// An array of `T`s that always fits one binding.
const fn array<T: GlslType>() -> Shape {
    Shape::Array { element: Element::of::<T>(), chunked: false }
}

/// An array of `T`s that may outgrow one binding: split by chunks.rs, read by `load_<name>(i)`.
const fn chunked<T: GlslType>() -> Shape {
    Shape::Array { element: Element::of::<T>(), chunked: true }
}

/// An array of `T`s read as texels, `T::TEXELS` a record (bound as uniform texel buffers).
const fn texel_buffer<T: GlslTexels>() -> Shape {
    let width = T::TEXELS[0].words().bytes();
    let mut k = 0;
    while k < T::TEXELS.len() {
        assert!(T::TEXELS[k].words().bytes() == width, "a record's texels are all as wide: one texel format a buffer");
        k += 1;
    }
    assert!(
        Texel::record_texels(T::TEXELS) as u64 * width == size_of::<T>() as u64,
        "a record read as texels is a whole number of its texels"
    );
    Shape::TexelBuffer { element: Element::of::<T>(), texels: T::TEXELS }
}

/// Every buffer of the kernel, in [`KernelBuffer`] order (checked at compile time below).
#[rustfmt::skip]
pub const BINDINGS: [BufferBinding; KernelBuffer::COUNT] = [
    // The camera, film, integrator settings and scene counts (see FrameParams).
    BufferBinding { buffer: Frame, binding: 0, name: "frame", shape: Shape::UniformBlock(Block::of::<FrameParams>()), access: Read, bound_in: EveryKernel, what: "frame parameters" },
    // BVH wide nodes (src/bvh/wide_node.rs): the top level over instances, its root at node 0,
    // then every bottom-level BVH. A storage array where the device reads the walk's records so
    // (WALK_RECORDS, walk_records.rs), as are the mesh triangles.
    BufferBinding { buffer: Nodes, binding: 1, name: "nodes", shape: texel_buffer::<WideNode>(), access: Read, bound_in: EveryKernel, what: "BVH nodes" },
    // The scene's own spheres, quads and triangles, in their BVH's leaf order.
    BufferBinding { buffer: Primitives, binding: 2, name: "prims", shape: array::<GpuPrimitive>(), access: Read, bound_in: EveryKernel, what: "primitives" },
    BufferBinding { buffer: Materials, binding: 3, name: "materials", shape: texel_buffer::<GpuMaterial>(), access: Read, bound_in: EveryKernel, what: "materials" },
    // Every emitter in world space, in Primitive form (mesh triangles transformed by the host).
    BufferBinding { buffer: Lights, binding: 4, name: "lights", shape: texel_buffer::<GpuPrimitive>(), access: Read, bound_in: EveryKernel, what: "lights" },
    // The environment map's texels, rgb, row-major, top row first (one texel for a constant sky).
    BufferBinding { buffer: EnvTexels, binding: 5, name: "env_texels", shape: texel_buffer::<[f32; 4]>(), access: Read, bound_in: EveryKernel, what: "environment map" },
    // Per pixel: rgb = sum of sample radiance, a = samples accumulated.
    BufferBinding { buffer: Accum, binding: 6, name: "accum", shape: chunked::<[f32; 4]>(), access: ReadWrite, bound_in: EveryKernel, what: "accumulation image" },
    // Per-dispatch counters, cleared and read by the host (see GpuStats).
    BufferBinding { buffer: Stats, binding: 7, name: "stats", shape: Shape::StorageBlock(Block::of::<GpuStats>()), access: ReadWrite, bound_in: EveryKernel, what: "statistics" },
    // Placements of bottom-level BVHs; the top-level BVH's leaves index them. Read as texels: each
    // lane reads its own ray's and hit's (mesh box 1.055x on lavapipe, docs/benchmarks/history.md, 2026-12-06,
    // `badf81e`).
    BufferBinding { buffer: Instances, binding: 8, name: "instances", shape: texel_buffer::<GpuInstance>(), access: Read, bound_in: EveryKernel, what: "instances" },
    // Every mesh's triangles by value (MeshTriangle) and their materials, in their BVH's leaf order.
    BufferBinding { buffer: MeshTriangles, binding: 9, name: "mesh_triangles", shape: texel_buffer::<GpuMeshTriangle>(), access: Read, bound_in: EveryKernel, what: "mesh triangles" },
    BufferBinding { buffer: TriangleMaterials, binding: 10, name: "triangle_materials", shape: texel_buffer::<u32>(), access: Read, bound_in: EveryKernel, what: "triangle materials" },
    // Vertex attributes of every mesh, indexed by global vertex index: normals octahedral
    // snorm16x2, texture coordinates.
    BufferBinding { buffer: VertexNormals, binding: 11, name: "vertex_normals", shape: texel_buffer::<u32>(), access: Read, bound_in: EveryKernel, what: "vertex normals" },
    BufferBinding { buffer: VertexUvs, binding: 12, name: "vertex_uvs", shape: texel_buffer::<[f32; 2]>(), access: Read, bound_in: EveryKernel, what: "vertex texture coordinates" },
    // Where each texture's texels lie in `texels`, its size and TEXTURE_* flags.
    BufferBinding { buffer: TextureInfos, binding: 13, name: "texture_infos", shape: array::<GpuTexture>(), access: Read, bound_in: EveryKernel, what: "texture descriptors" },
    // Every texture's texels, RGBA8, one after another.
    BufferBinding { buffer: Texels, binding: 14, name: "texels", shape: texel_buffer::<u32>(), access: Read, bound_in: EveryKernel, what: "textures" },
    // The environment map's sampling distribution: marginal CDF over rows (height + 1 values), then
    // one CDF per row (width + 1 values each); see env_sampling.rs. Empty when it is not sampled.
    BufferBinding { buffer: EnvCdf, binding: 15, name: "env_cdf", shape: texel_buffer::<f32>(), access: Read, bound_in: EveryKernel, what: "environment distribution" },
    // Alias table over `lights` and then `punctual_lights` for picking them by power (light_selection.rs); empty when they
    // are picked uniformly.
    BufferBinding { buffer: LightAlias, binding: 16, name: "light_alias", shape: array::<GpuAliasEntry>(), access: Read, bound_in: EveryKernel, what: "light alias table" },
    // Point, spot and directional lights (src/scene/light.rs), picked after the area lights: entry
    // light_count + i of the alias table is punctual light i.
    BufferBinding { buffer: PunctualLights, binding: 17, name: "punctual_lights", shape: array::<GpuPunctualLight>(), access: Read, bound_in: EveryKernel, what: "point, spot and directional lights" },
    // Per entry of `mesh_triangles`: the mean luminance of a textured emitter's emission over the
    // triangle (src/render/textured_emission.rs), which light selection weighs it by; 0 for other
    // triangles, and empty when no material has an emission texture.
    BufferBinding { buffer: TriangleEmission, binding: 18, name: "triangle_emission", shape: texel_buffer::<f32>(), access: Read, bound_in: EveryKernel, what: "textured emitters' mean luminance" },
    // Tangents of the vertices of meshes with a normal-mapped material, by global vertex index:
    // xyz = unit tangent (along growing u), w = the bitangent's sign.
    BufferBinding { buffer: VertexTangents, binding: 19, name: "vertex_tangents", shape: texel_buffer::<[f32; 4]>(), access: Read, bound_in: EveryKernel, what: "vertex tangents" },
    // Denoiser features (AOVs), per pixel, summed over samples like `accum`: rgb = albedo and
    // xyz = camera-facing shading normal at the first non-specular vertex, and a = distance to the
    // first hit summed over the samples that hit something, w = how many those were.
    BufferBinding { buffer: AovAlbedoDepth, binding: 20, name: "aov_albedo_depth", shape: chunked::<[f32; 4]>(), access: ReadWrite, bound_in: AovKernels, what: "albedo and depth sums" },
    BufferBinding { buffer: AovNormalHits, binding: 21, name: "aov_normal_hits", shape: chunked::<[f32; 4]>(), access: ReadWrite, bound_in: AovKernels, what: "normal sums" },
    // Each pixel's path between the wavefront's kernels (wavefront.glsl), WAVEFRONT_STATE_VEC4S a pixel.
    BufferBinding { buffer: PathStates, binding: 22, name: "path_states", shape: array::<[u32; 4]>(), access: ReadWrite, bound_in: WavefrontKernels, what: "wavefront path states" },
    // The top-level acceleration structure over the instances, in `instances` order, each
    // instance's bottom level its mesh's triangles or the boxes of the scene's own shapes
    // (ray_query_scene.rs): what ray queries trace in place of `nodes` (ray_query.glsl).
    BufferBinding { buffer: SceneStructure, binding: 23, name: "scene_structure", shape: Shape::AccelerationStructure, access: Read, bound_in: RayQueryKernels, what: "acceleration structures" },
    // The light tree's nodes (light_tree.rs, GpuLightTreeNode), root first; empty unless the
    // scene picks its lights by the tree (SCENE_LIGHT_TREE).
    BufferBinding { buffer: LightTree, binding: 24, name: "light_tree", shape: array::<GpuLightTreeNode>(), access: Read, bound_in: EveryKernel, what: "light tree" },
    // Where the light tree meets the lights (light_tree_index.rs): per light its leaf, per
    // instance where its hits find their lights, per shape its light, per mesh triangle its rank
    // among its mesh's emitters. Empty with the tree.
    BufferBinding { buffer: LightTreeIndex, binding: 25, name: "light_tree_index", shape: texel_buffer::<u32>(), access: Read, bound_in: EveryKernel, what: "light tree index" },
    // Linear RGB colours of the vertices of meshes with vertex colours (glTF COLOR_0), by global
    // vertex index (w unused); empty when no mesh has them.
    BufferBinding { buffer: VertexColors, binding: 26, name: "vertex_colors", shape: texel_buffer::<[f32; 4]>(), access: Read, bound_in: EveryKernel, what: "vertex colours" },
    // Participating media (scene::Medium), by the index in their codes (MEDIUM_CODES); empty
    // without media.
    BufferBinding { buffer: Media, binding: 27, name: "media", shape: array::<GpuMedium>(), access: Read, bound_in: EveryKernel, what: "participating media" },
    // The density grids of heterogeneous media, one after another (GpuMedium::grid says where
    // each starts); empty without them.
    BufferBinding { buffer: MediumDensities, binding: 28, name: "medium_densities", shape: texel_buffer::<f32>(), access: Read, bound_in: EveryKernel, what: "medium density grids" },
];

// The table is in key order, its bindings are distinct and below the extra windows' bindings,
// and only arrays may be split (a compile error otherwise).
const _: () = {
    let mut i = 0;
    while i < BINDINGS.len() {
        assert!(BINDINGS[i].buffer as usize == i, "BINDINGS is out of KernelBuffer order");
        assert!(BINDINGS[i].binding < EXTRA_BINDING_BASE, "a binding collides with the windows of split arrays");
        let mut j = 0;
        while j < i {
            assert!(BINDINGS[i].binding != BINDINGS[j].binding, "two buffers share a binding");
            j += 1;
        }
        if let Shape::UniformBlock(_) = BINDINGS[i].shape {
            assert!(matches!(BINDINGS[i].access, Access::Read), "uniform blocks are read-only");
        }
        i += 1;
    }
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::chunks::{window_binding, ChunkPlan, SplitPlans, MAX_CHUNKS, UNSPLIT};
    use crate::render::features::SceneFeatures;
    use crate::render::interface::glsl;
    use crate::render::kernel::kernel_spirv;
    use crate::render::layout::PassParams;
    use crate::render::spirv_reflect::{
        acceleration_structure_variables, block_variables, texel_buffer_variables, StorageClass,
    };
    use std::collections::BTreeMap;

    /// The general kernel without AOVs or loop counting, in 8x8 workgroups: what each of
    /// [`VARIANTS`] changes.
    const GENERAL: KernelVariant = KernelVariant {
        aovs: false,
        count_loop_iterations: false,
        features: SceneFeatures::ALL,
        walk_queue: None,
        workgroup: crate::render::Workgroup::EIGHT_BY_EIGHT,
        take_tiles: false,
        wavefront: None,
        walk_records: WalkRecords::Texels,
        bvh_width: crate::render::BvhWidth::Four,
        shadow_walk: crate::render::ShadowWalk::Sorted,
        traversal: crate::gpu::Traversal::Compute,
    };

    /// The walk queue's kernel (walk_queue.rs): a top level of its root alone.
    const QUEUE: KernelVariant = KernelVariant {
        aovs: true,
        features: SceneFeatures { top_level_tree: false, ..SceneFeatures::ALL },
        walk_queue: Some(crate::render::WalkQueue { walks_per_ray: 2, subgroup_barriers: false }),
        ..GENERAL
    };

    const VARIANTS: [KernelVariant; 17] = [
        GENERAL,
        // The device's ray queries in place of the walk (ray_query.glsl), which bind the scene's
        // acceleration structure; in the wavefront's kernels too.
        KernelVariant { traversal: crate::gpu::Traversal::RayQuery, ..GENERAL },
        KernelVariant {
            traversal: crate::gpu::Traversal::RayQuery,
            wavefront: Some(crate::render::WavefrontStage::Shadow),
            ..GENERAL
        },
        // The walk's records from storage buffers (walk_records.rs), in the plain and queued walks.
        KernelVariant { walk_records: WalkRecords::Storage, ..GENERAL },
        KernelVariant { walk_records: WalkRecords::Storage, ..QUEUE },
        // The eight-wide walk (bvh_width.rs), its nodes read as texels and from storage buffers.
        KernelVariant { bvh_width: crate::render::BvhWidth::Eight, ..GENERAL },
        KernelVariant { bvh_width: crate::render::BvhWidth::Eight, walk_records: WalkRecords::Storage, ..GENERAL },
        // Shadow rays' four-wide walk without sorting (shadow_walk.rs).
        KernelVariant { shadow_walk: crate::render::ShadowWalk::Unsorted, ..GENERAL },
        KernelVariant { aovs: true, ..GENERAL },
        KernelVariant { count_loop_iterations: true, ..GENERAL },
        KernelVariant { aovs: true, count_loop_iterations: true, ..GENERAL },
        QUEUE,
        // ... with its subgroups taking tiles from the statistics' counter (tile_taking.rs).
        KernelVariant { take_tiles: true, ..QUEUE },
        // ... with the subgroup barriers a GPU's lanes need.
        KernelVariant {
            walk_queue: Some(crate::render::WalkQueue { walks_per_ray: 2, subgroup_barriers: true }),
            ..QUEUE
        },
        // The wavefront's three kernels (wavefront.rs), which bind its paths' states too.
        KernelVariant { aovs: true, wavefront: Some(crate::render::WavefrontStage::Extend), ..GENERAL },
        KernelVariant { aovs: true, wavefront: Some(crate::render::WavefrontStage::Shadow), ..GENERAL },
        KernelVariant { wavefront: Some(crate::render::WavefrontStage::Shade), ..GENERAL },
    ];

    /// What a binding holds: a block of this storage class, or a texel buffer.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Kind {
        Block(StorageClass),
        TexelBuffer,
        AccelerationStructure,
    }

    /// A binding as a compiled kernel declares it: its kind, the block's instance name (or its
    /// array's name, for a block without one; a texel buffer's own), whether it is readonly, and
    /// the array stride in bytes.
    type Declared = (Kind, String, bool, Option<u32>);

    /// What the table says `variant` declares at each binding of set 0, arrays split by `plans`.
    fn declared_by_table(plans: &SplitPlans, variant: KernelVariant) -> BTreeMap<u32, Declared> {
        let mut declared = BTreeMap::new();
        for b in bound_in(variant) {
            let readonly = !b.is_written();
            match b.shape {
                Shape::UniformBlock(_) => {
                    declared.insert(b.binding, (Kind::Block(StorageClass::Uniform), b.name.to_owned(), readonly, None))
                }
                Shape::StorageBlock(_) => declared
                    .insert(b.binding, (Kind::Block(StorageClass::StorageBuffer), b.name.to_owned(), readonly, None)),
                Shape::Array { element, chunked: false } => declared.insert(
                    b.binding,
                    (Kind::Block(StorageClass::StorageBuffer), b.name.to_owned(), readonly, Some(element.bytes as u32)),
                ),
                Shape::Array { element, chunked: true } => {
                    for c in 0..plans[b.buffer].chunks {
                        let window = (
                            Kind::Block(StorageClass::StorageBuffer),
                            format!("{}_{c}", b.name),
                            readonly,
                            Some(element.bytes as u32),
                        );
                        declared.insert(window_binding(&b, c), window);
                    }
                    None
                }
                Shape::AccelerationStructure => {
                    declared.insert(b.binding, (Kind::AccelerationStructure, b.name.to_owned(), true, None))
                }
                Shape::TexelBuffer { .. } => {
                    for c in 0..plans[b.buffer].chunks {
                        declared
                            .insert(window_binding(&b, c), (Kind::TexelBuffer, format!("{}_{c}", b.name), true, None));
                    }
                    None
                }
            };
        }
        declared
    }

    /// What the compiled kernel declares at each binding of set 0.
    fn declared_by_kernel(spirv: &[u32]) -> BTreeMap<u32, Declared> {
        let mut declared = BTreeMap::new();
        for v in block_variables(spirv) {
            let Some(binding) = v.binding else { continue };
            assert_eq!(v.set, Some(0), "binding {binding} is outside descriptor set 0");
            // Uniform blocks are read-only without being marked so.
            let readonly = v.storage_class == StorageClass::Uniform || v.is_readonly();
            let (name, stride) = match (v.name.is_empty(), &v.members[..]) {
                (true, [array]) => (array.name.clone(), array.array_stride),
                _ => (v.name.clone(), None),
            };
            assert!(
                declared.insert(binding, (Kind::Block(v.storage_class), name, readonly, stride)).is_none(),
                "binding {binding} is declared twice"
            );
        }
        for v in texel_buffer_variables(spirv) {
            let Some(binding) = v.binding else { continue };
            assert_eq!(v.set, Some(0), "binding {binding} is outside descriptor set 0");
            assert!(
                declared.insert(binding, (Kind::TexelBuffer, v.name, true, None)).is_none(),
                "binding {binding} is declared twice"
            );
        }
        for v in acceleration_structure_variables(spirv) {
            let Some(binding) = v.binding else { continue };
            assert_eq!(v.set, Some(0), "binding {binding} is outside descriptor set 0");
            assert!(
                declared.insert(binding, (Kind::AccelerationStructure, v.name, true, None)).is_none(),
                "binding {binding} is declared twice"
            );
        }
        declared
    }

    /// Every kernel variant, with its arrays in one binding each and split as far as they go,
    /// declares exactly the table's bindings: the same numbers, names, kinds, access and element
    /// sizes. Whatever a shader file declares by hand, or the generator gets wrong, shows here.
    #[test]
    fn every_kernel_variant_declares_the_table_s_bindings() {
        let split = SplitPlans([ChunkPlan { shift: 10, chunks: MAX_CHUNKS }; KernelBuffer::COUNT]);
        for variant in VARIANTS {
            for plans in [UNSPLIT, split] {
                let spirv = kernel_spirv(&plans, variant).expect("the kernel compiles");
                let (kernel, table) = (declared_by_kernel(spirv), declared_by_table(&plans, variant));
                for (binding, declared) in &table {
                    assert_eq!(
                        kernel.get(binding),
                        Some(declared),
                        "{variant:?}, {} windows: binding {binding}",
                        plans[KernelBuffer::Nodes].chunks
                    );
                }
                for (binding, declared) in &kernel {
                    assert!(
                        table.contains_key(binding),
                        "{variant:?}: the kernel declares binding {binding} ({declared:?}), which the table lacks"
                    );
                }
            }
        }
    }

    /// A variant that reads the walk's records from storage buffers declares those two as chunked
    /// storage arrays of the same records, and every other binding as the table does.
    #[test]
    fn storage_walk_records_swap_the_walk_s_texel_buffers_alone() {
        let storage = KernelVariant { walk_records: WalkRecords::Storage, ..GENERAL };
        for (texels, stored) in bound_in(GENERAL).zip(bound_in(storage)) {
            assert_eq!(texels.buffer, stored.buffer);
            match (texels.shape, stored.shape) {
                (Shape::TexelBuffer { element, .. }, Shape::Array { element: e, chunked: true }) => {
                    assert!(WALK_RECORDS.contains(&texels.buffer), "{} swapped", texels.what);
                    assert_eq!((element.glsl_type, element.bytes), (e.glsl_type, e.bytes));
                }
                _ => assert!(
                    !WALK_RECORDS.contains(&texels.buffer)
                        && format!("{:?}", texels.shape) == format!("{:?}", stored.shape),
                    "{} changed",
                    texels.what
                ),
            }
        }
    }

    /// The kernel's frame parameters, statistics and push constants sit where the host writes and
    /// reads them: the compiler's std140/std430 offsets of every member are the host struct's.
    #[test]
    fn kernel_blocks_have_the_host_structs_offsets() {
        let spirv = kernel_spirv(&UNSPLIT, KernelVariant::default()).expect("the kernel compiles");
        let variables = block_variables(spirv);
        for (block, members) in [
            (FrameParams::NAME, FrameParams::MEMBERS),
            (GpuStats::NAME, GpuStats::MEMBERS),
            (PassParams::NAME, PassParams::MEMBERS),
        ] {
            let variable = variables
                .iter()
                .find(|v| v.block == block)
                .unwrap_or_else(|| panic!("the kernel has no block {block}"));
            let kernel: Vec<(&str, Option<u32>)> =
                variable.members.iter().map(|m| (m.name.as_str(), m.offset)).collect();
            let host: Vec<(&str, Option<u32>)> = members.iter().map(|m| (m.name, Some(m.offset as u32))).collect();
            assert_eq!(kernel, host, "{block}: the kernel's member offsets differ from the host struct's");
        }
    }

    #[test]
    fn the_generated_declarations_say_what_each_buffer_is() {
        let src = glsl(&UNSPLIT, KernelVariant { aovs: true, ..Default::default() });
        let textures = format!(
            "binding = {}) readonly buffer texture_infos_buffer {{ TextureInfo texture_infos[]; }};",
            KernelBuffer::TextureInfos.entry().binding
        );
        assert!(src.contains(&textures), "{src}");
        // A record with matrix rows: each array member built from its texels.
        let instance = "return Instance(vec4[3](uintBitsToFloat(texelFetch(instances_0, t + 0)), uintBitsToFloat(texelFetch(instances_0, t + 1)), \
                        uintBitsToFloat(texelFetch(instances_0, t + 2))), vec4[3](uintBitsToFloat(texelFetch(instances_0, t + 3)), \
                        uintBitsToFloat(texelFetch(instances_0, t + 4)), uintBitsToFloat(texelFetch(instances_0, t + 5))), texelFetch(instances_0, t + 6));";
        assert!(src.contains("int t = int(j * 7u);") && src.contains(instance), "{src}");
        let materials =
            format!("binding = {}) uniform utextureBuffer materials_0;", KernelBuffer::Materials.entry().binding);
        assert!(src.contains(&materials) && src.contains("Material load_materials(uint i)"), "{src}");
        assert!(
            src.contains("    // Number of area lights: the entries of `lights`.\n    uint light_count;\n"),
            "{src}"
        );
        assert!(src.contains("vec4 load_aov_normal_hits(uint i)"), "{src}");
        assert!(
            !glsl(&UNSPLIT, KernelVariant::default()).contains("aov_normal_hits"),
            "a kernel without AOVs does not declare their sums"
        );
    }
}
