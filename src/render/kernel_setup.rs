//! Making a renderer's kernel, in four steps: plan (the scene's data, the kernel variant for it on
//! this device, how its arrays split across bindings, checked against the device's limits before
//! anything is uploaded), upload (a buffer per binding, with what it starts as), bind (each
//! buffer, or each window of a split one, to its binding) and compile (the megakernel, or the
//! wavefront's three kernels).

use super::aov::AovSet;
use super::bindings::{self, BufferBinding, KernelBuffer, Shape};
use super::chunks::{self, SplitPlans, UNSPLIT};
use super::features::SceneFeatures;
use super::frame::{frame_params, TEXTURE_BUDGET_BYTES};
use super::kernel::kernel_spirv;
use super::kernel_options::{KernelChoices, KernelOptions, SceneShape};
use super::layout::{FrameParams, GpuStats, PassParams};
use super::scene_data::SceneData;
use super::variant::{KernelChoice, KernelVariant};
use super::wavefront::{self, WavefrontKernels, WavefrontStage};
use crate::gpu::{
    Binding, Buffer, BufferKind, ComputeKernel, DeviceInfo, GpuContext, KernelStatistic, SceneStructure, Traversal,
};
use crate::scene::Scene;
use anyhow::{Context as _, Result};

/// What a pass runs: the megakernel, or the wavefront's three kernels.
pub(super) enum Kernels {
    Megakernel(ComputeKernel),
    Wavefront(WavefrontKernels),
}

/// Everything decided before the first upload.
pub(super) struct KernelPlan {
    pub scene_name: String,
    pub data: SceneData,
    /// The frame parameters uploaded.
    pub params: FrameParams,
    /// See [`GpuContext::loop_limit`].
    pub loop_limit: Option<u32>,
    /// The kernel options applied to this device and scene.
    pub choices: KernelChoices,
    /// The kernel compiled (the wavefront's first stage standing for its three, which bind the
    /// same buffers).
    pub variant: KernelVariant,
    /// How each array splits across bindings.
    pub plans: SplitPlans,
    /// See `Renderer::scene_hash`.
    pub scene_hash: String,
    /// Bytes of scene data in each bound buffer that the scene hash covers (`None`: not covered).
    pub hashed_bytes: Vec<Option<u64>>,
    /// Arrays too large for one binding, with the bindings each spans.
    pub split_arrays: Vec<(&'static str, u32)>,
    /// Bytes of the accumulation image (16 a pixel).
    image_bytes: u64,
}

impl KernelPlan {
    /// The plan for rendering `scene` with `aovs` on `ctx`'s device, its kernel compiled as
    /// `choice` says and run as `options` ask; an error where the scene cannot fit the device or
    /// an option asks for what cannot run there.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        seed: u32,
        aovs: AovSet,
        choice: KernelChoice,
        options: &KernelOptions,
    ) -> Result<KernelPlan> {
        // One texel buffer holds every texture: it must fit the bindings it can be split across.
        let texels = KernelBuffer::Texels.entry();
        let texel_bytes = texels.chunked_element().expect("texels may be split").bytes;
        let texture_budget =
            TEXTURE_BUDGET_BYTES.min(chunks::capacity_bytes(texel_bytes, binding_range(&ctx.info, texels)));
        let loop_limit = ctx.loop_limit()?;
        let data = SceneData::with_bvh_width(scene, texture_budget, options.bvh_width(&ctx.info, loop_limit.is_some()));
        if data.texture_bytes() < data.texture_bytes_requested {
            log::warn!(
                "caustica: {}: textures downsampled from {:.1} MiB to {:.1} MiB to fit the texture budget",
                scene.name,
                data.texture_bytes_requested as f64 / 1048576.0,
                data.texture_bytes() as f64 / 1048576.0
            );
        }
        let image_bytes = scene.film.width as u64 * scene.film.height as u64 * 16;
        let params = frame_params(scene, &data, seed);
        let features = match choice {
            KernelChoice::ForScene => SceneFeatures::of(&data),
            KernelChoice::General => SceneFeatures::ALL,
        };
        // Ray queries (the device's choice, gpu/traversal.rs) replace the walk; a scene tested
        // shape by shape has none to replace.
        let traversal = if features.bvh() { ctx.traversal } else { Traversal::Compute };
        let shape = SceneShape {
            features: &features,
            root: data.acceleration.nodes.first(),
            instances: &data.acceleration.instances,
            ray_queries: traversal == Traversal::RayQuery,
        };
        let choices = options.choose(&ctx.info, loop_limit.is_some(), shape)?;
        let variant = KernelVariant {
            aovs: aovs.needs_kernel(),
            count_loop_iterations: loop_limit.is_some(),
            features,
            walk_queue: choices.walk_queue,
            workgroup: choices.workgroup,
            take_tiles: choices.take_tiles,
            wavefront: choices.wavefront.then_some(WavefrontStage::Extend),
            walk_records: choices.walk_records,
            bvh_width: choices.bvh_width,
            shadow_walk: choices.shadow_walk,
            traversal,
        };
        let mut plan = KernelPlan {
            scene_name: scene.name.clone(),
            data,
            params,
            loop_limit,
            choices,
            variant,
            plans: UNSPLIT,
            scene_hash: String::new(),
            hashed_bytes: Vec::new(),
            split_arrays: Vec::new(),
            image_bytes,
        };
        let contents = plan.contents();
        let plans = plan_bindings(ctx, &plan.scene_name, contents.iter().map(|(b, c)| (b, c.bytes())))?;
        let scene_hash = scene_hash(&frame_params(scene, &plan.data, 0), &contents);
        let hashed_bytes = contents.iter().map(|(b, c)| is_hashed(b).then(|| c.bytes())).collect();
        let split_arrays = contents
            .iter()
            .map(|(b, _)| (b.what, plans[b.buffer].chunks))
            .filter(|&(_, windows)| windows > 1)
            .collect();
        drop(contents);
        (plan.plans, plan.scene_hash, plan.hashed_bytes, plan.split_arrays) =
            (plans, scene_hash, hashed_bytes, split_arrays);
        Ok(plan)
    }

    /// Every buffer the kernel variant binds, in binding order, as it declares them, with what it
    /// starts as; the acceleration structure is built apart ([`Self::build_structure`]).
    fn contents(&self) -> Vec<(BufferBinding, Initial<'_>)> {
        bindings::bound_in(self.variant)
            .filter(|b| !b.is_acceleration_structure())
            .map(|b| {
                let initial = initial_contents(b.buffer, &self.params, &self.data, self.image_bytes);
                (b, initial)
            })
            .collect()
    }

    /// A device buffer for each binding, holding what it starts as.
    pub fn upload(&self, ctx: &GpuContext) -> Result<Vec<(KernelBuffer, Buffer)>> {
        let mut buffers = Vec::new();
        for (binding, initial) in &self.contents() {
            let kind = match binding.shape {
                Shape::UniformBlock(_) => BufferKind::Uniform,
                // Cleared before and read after every dispatch: kept where the host sees it.
                _ if binding.buffer == KernelBuffer::Stats => BufferKind::HostStorage,
                _ => BufferKind::Storage,
            };
            let zeroes;
            let bytes = match initial {
                Initial::Data(data) => *data,
                Initial::Zeroes(n) => {
                    zeroes = vec![0u8; *n as usize];
                    &zeroes[..]
                }
            };
            let buffer = Buffer::with_data(ctx, binding.what, kind, bytes)
                .with_context(|| format!("uploading {}", self.scene_name))?;
            buffers.push((binding.buffer, buffer));
        }
        Ok(buffers)
    }

    /// The scene's acceleration structures, where the kernel traces with ray queries
    /// (ray_query_scene.rs); `None` where it walks its own BVH.
    pub fn build_structure(&self, ctx: &GpuContext, scene: &Scene) -> Result<Option<SceneStructure>> {
        match self.variant.traversal {
            Traversal::RayQuery => {
                Ok(Some(super::ray_query_scene::build(ctx, scene, &self.data, &self.variant.features)?))
            }
            Traversal::Compute => Ok(None),
        }
    }

    /// The kernel's descriptors for `buffers` (as [`Self::upload`] made them) and `structure`:
    /// each buffer at its binding, a split array's windows at theirs, the acceleration structure
    /// at its own.
    pub fn bind<'b>(
        &self,
        buffers: &'b [(KernelBuffer, Buffer)],
        structure: Option<&'b SceneStructure>,
    ) -> Vec<Binding<'b>> {
        let mut descriptors = Vec::new();
        for ((binding, initial), (_, buffer)) in self.contents().iter().zip(buffers) {
            let plan = self.plans[binding.buffer];
            match binding.chunked_element() {
                Some(element) if plan.chunks > 1 => {
                    for (c, (offset, range)) in plan.windows(element.bytes, initial.bytes()).into_iter().enumerate() {
                        descriptors.push(Binding {
                            binding: chunks::window_binding(binding, c as u32),
                            buffer,
                            offset,
                            range,
                            as_texels: binding.texel_words(),
                            structure: None,
                        });
                    }
                }
                // Unsplit arrays keep their own binding: window 0's is the array's.
                _ => descriptors
                    .push(Binding { as_texels: binding.texel_words(), ..Binding::whole(binding.binding, buffer) }),
            }
        }
        if let Some(structure) = structure {
            descriptors.push(Binding::acceleration_structure(KernelBuffer::SceneStructure.entry().binding, structure));
        }
        descriptors
    }

    /// The kernels a pass runs, bound to `descriptors`, and what the driver says of each.
    pub fn compile(&self, ctx: &GpuContext, descriptors: &[Binding]) -> Result<(Kernels, Vec<KernelStatistic>)> {
        let push_size = std::mem::size_of::<PassParams>() as u32;
        if !self.choices.wavefront {
            let k = ComputeKernel::new(ctx, kernel_spirv(&self.plans, self.variant)?, descriptors, push_size)?;
            let statistics = k.statistics.clone();
            return Ok((Kernels::Megakernel(k), statistics));
        }
        let mut kernels = Vec::new();
        let mut statistics = Vec::new();
        for stage in WavefrontStage::ALL {
            let variant = KernelVariant { wavefront: Some(stage), ..self.variant };
            let k = ComputeKernel::new(ctx, kernel_spirv(&self.plans, variant)?, descriptors, push_size)?;
            statistics.extend(
                k.statistics
                    .iter()
                    .map(|s| KernelStatistic { name: format!("{stage:?}: {}", s.name), value: s.value.clone() }),
            );
            kernels.push(k);
        }
        Ok((Kernels::Wavefront(WavefrontKernels { kernels }), statistics))
    }
}

/// The statistics buffer's contents at the start of every dispatch.
pub(super) const CLEARED_STATS: GpuStats = GpuStats {
    ray_count: 0,
    nonfinite_samples: 0,
    pixels_complete: 0,
    samples_added: 0,
    max_loop_iterations: 0,
    paths_in_flight_even: 0,
    paths_in_flight_odd: 0,
    tiles_taken: 0,
};

/// What a buffer holds when a render starts: data, or zeroes to accumulate into.
pub(super) enum Initial<'d> {
    Data(&'d [u8]),
    Zeroes(u64),
}

impl Initial<'_> {
    fn bytes(&self) -> u64 {
        match self {
            Initial::Data(data) => data.len() as u64,
            Initial::Zeroes(bytes) => *bytes,
        }
    }
}

/// What `buffer` starts as in a render of `data` with these parameters and image size.
pub(super) fn initial_contents<'d>(
    buffer: KernelBuffer,
    params: &'d FrameParams,
    data: &'d SceneData,
    image_bytes: u64,
) -> Initial<'d> {
    use KernelBuffer::*;
    let a = &data.acceleration;
    Initial::Data(match buffer {
        Frame => bytemuck::bytes_of(params),
        Nodes => bytemuck::cast_slice(&a.nodes),
        Primitives => bytemuck::cast_slice(&a.primitives),
        Materials => bytemuck::cast_slice(&data.materials),
        Lights => bytemuck::cast_slice(&data.lights),
        EnvTexels => bytemuck::cast_slice(&data.env_texels),
        Accum | AovAlbedoDepth | AovNormalHits => return Initial::Zeroes(image_bytes),
        // Each pixel's path state (wavefront.rs): image_bytes is 16 bytes a pixel.
        PathStates => return Initial::Zeroes(image_bytes * wavefront::STATE_VEC4S),
        Stats => bytemuck::bytes_of(&CLEARED_STATS),
        Instances => bytemuck::cast_slice(&a.instances),
        MeshTriangles => bytemuck::cast_slice(&a.triangles),
        TriangleMaterials => bytemuck::cast_slice(&a.triangle_materials),
        VertexNormals => bytemuck::cast_slice(&a.normals),
        VertexUvs => bytemuck::cast_slice(&a.uvs),
        TextureInfos => bytemuck::cast_slice(&data.textures),
        Texels => bytemuck::cast_slice(&data.texels),
        EnvCdf => bytemuck::cast_slice(&data.env_cdf),
        LightAlias => bytemuck::cast_slice(&data.light_distribution.table),
        PunctualLights => bytemuck::cast_slice(&data.punctual_lights),
        TriangleEmission => bytemuck::cast_slice(&data.triangle_emission),
        VertexTangents => bytemuck::cast_slice(&a.tangents),
        VertexColors => bytemuck::cast_slice(&a.colors),
        Media => bytemuck::cast_slice(&data.media),
        MediumDensities => bytemuck::cast_slice(&data.medium_densities),
        // Built from the scene's data rather than uploaded (ray_query_scene.rs).
        SceneStructure => &[],
        LightTree => data.light_tree.as_ref().map_or(&[][..], |t| bytemuck::cast_slice(&t.tree.nodes)),
        LightTreeIndex => data.light_tree.as_ref().map_or(&[][..], |t| bytemuck::cast_slice(&t.index)),
    })
}

/// Hex BLAKE3 of the frame parameters (seed zeroed) and every scene buffer (the storage buffers the
/// kernel only reads), in binding order. It covers what the scene file references (meshes,
/// textures, probes) and the film size as they reach the kernel, so partial renders that hash
/// alike rendered the same image.
pub(super) fn scene_hash(params_without_seed: &FrameParams, contents: &[(BufferBinding, Initial)]) -> String {
    let mut hasher = blake3::Hasher::new();
    hasher.update(bytemuck::bytes_of(params_without_seed));
    for (binding, contents) in contents {
        if let (true, Initial::Data(bytes)) = (is_hashed(binding), contents) {
            // Length-prefixed so that bytes cannot move between neighbouring buffers unnoticed.
            hasher.update(&(bytes.len() as u64).to_le_bytes());
            hasher.update(bytes);
        }
    }
    hasher.finalize().to_hex().to_string()
}

/// Whether [`scene_hash`] covers the buffer: the scene data the kernel only reads.
pub(super) fn is_hashed(binding: &BufferBinding) -> bool {
    !binding.is_written() && !matches!(binding.shape, Shape::UniformBlock(_))
}

/// Bytes one binding of `binding` can see on `device`: a texel buffer's as many texels as the
/// device allows in one, a storage buffer's its storage range.
pub(super) fn binding_range(device: &DeviceInfo, binding: &BufferBinding) -> u64 {
    match binding.texel_words() {
        Some(words) => device.max_texel_buffer_range(words),
        None => device.max_storage_buffer_range,
    }
}

/// How each large array is split across bindings (see chunks.rs), or why the scene cannot fit the
/// device: an array larger than its bindings can see, more storage bindings than the kernel may
/// have, or more bytes than the device's memory. Checked before any upload; the message says how
/// much is needed and how much there is.
fn plan_bindings<'b>(
    ctx: &GpuContext,
    scene: &str,
    sizes: impl Iterator<Item = (&'b BufferBinding, u64)> + Clone,
) -> Result<SplitPlans> {
    let mib = |b: u64| b as f64 / 1048576.0;
    let device = &ctx.info;
    let range = device.max_storage_buffer_range;
    let mut plans = UNSPLIT;
    let (mut storage_bindings, mut texel_bindings) = (0, 0);
    for (binding, bytes) in sizes.clone() {
        let name = binding.what;
        match (binding.shape, binding.chunked_element()) {
            (Shape::UniformBlock(_), _) => {}
            (_, Some(element)) => {
                let (alignment, count) = match binding.is_texel_buffer() {
                    true => (device.min_texel_buffer_offset_alignment, &mut texel_bindings),
                    false => (device.min_storage_buffer_offset_alignment, &mut storage_bindings),
                };
                let plan = &mut plans[binding.buffer];
                *plan = chunks::plan(element.bytes, bytes, binding_range(device, binding), alignment).map_err(|e| {
                    anyhow::anyhow!("{scene}: the {name} need {:.1} MiB but {} allows {e}", mib(bytes), device.name)
                })?;
                *count += plan.chunks;
            }
            _ if bytes > range => anyhow::bail!(
                "{scene}: the {name} need {:.1} MiB but {} allows at most {:.1} MiB per storage buffer",
                mib(bytes),
                device.name,
                mib(range)
            ),
            _ => storage_bindings += 1,
        }
    }
    if storage_bindings > device.max_storage_buffers_per_stage {
        anyhow::bail!(
            "{scene}: the scene needs {storage_bindings} storage buffer bindings but {} allows {} (its arrays are too large to split further)",
            device.name,
            device.max_storage_buffers_per_stage
        );
    }
    if texel_bindings > device.max_texel_buffers_per_stage {
        anyhow::bail!(
            "{scene}: the scene needs {texel_bindings} texel buffer bindings but {} allows {} (its arrays are too large to split further)",
            device.name,
            device.max_texel_buffers_per_stage
        );
    }
    let total: u64 = sizes.map(|(_, b)| b).sum();
    if device.device_local_bytes > 0 && total > device.device_local_bytes {
        anyhow::bail!(
            "{scene}: the scene needs {:.1} MiB of GPU memory but {} has {:.1} MiB",
            mib(total),
            device.name,
            mib(device.device_local_bytes)
        );
    }
    Ok(plans)
}
