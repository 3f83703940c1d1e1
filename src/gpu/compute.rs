//! A compute pipeline with one descriptor set of buffers and a push-constant block. A buffer is
//! bound as a storage or uniform buffer, or as a uniform texel buffer of 1, 2 or 4 32-bit words a
//! texel.

use super::acceleration_structure::SceneStructure;
use super::buffer::{Buffer, BufferKind};
use super::context::GpuContext;
use super::device_info::DeviceInfo;
use super::pipeline_statistics::{self, KernelStatistic};
use anyhow::{anyhow, Context as _, Result};
use ash::vk;

/// A buffer, or the window `offset..offset + range` of one, bound at `binding` of descriptor set 0.
pub struct Binding<'a> {
    pub binding: u32,
    pub buffer: &'a Buffer,
    pub offset: u64,
    pub range: u64,
    /// Bound as a uniform texel buffer of texels this wide (the kernel's `utextureBuffer`) rather
    /// than as the buffer's kind says.
    pub as_texels: Option<TexelWords>,
    /// The acceleration structure bound here instead of a buffer (`buffer` is the one holding it):
    /// see [`Binding::acceleration_structure`].
    pub structure: Option<BoundStructure>,
}

/// An acceleration structure a [`Binding`] binds; only [`Binding::acceleration_structure`] makes one.
#[derive(Clone, Copy)]
pub struct BoundStructure(vk::AccelerationStructureKHR);

/// How wide the texels of a buffer bound as texels are: 1, 2 or 4 32-bit unsigned words, formats
/// every Vulkan device must support for uniform texel buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelWords {
    One,
    Two,
    Four,
}

impl TexelWords {
    pub const fn bytes(self) -> u64 {
        match self {
            TexelWords::One => 4,
            TexelWords::Two => 8,
            TexelWords::Four => 16,
        }
    }

    fn format(self) -> vk::Format {
        match self {
            TexelWords::One => vk::Format::R32_UINT,
            TexelWords::Two => vk::Format::R32G32_UINT,
            TexelWords::Four => vk::Format::R32G32B32A32_UINT,
        }
    }
}

impl DeviceInfo {
    /// Bytes one uniform texel buffer of texels `words` wide can see.
    pub fn max_texel_buffer_range(&self, words: TexelWords) -> u64 {
        (self.max_texel_buffer_elements * words.bytes()).min(self.texel_binding_limit)
    }
}

impl<'a> Binding<'a> {
    /// The whole buffer.
    pub fn whole(binding: u32, buffer: &'a Buffer) -> Self {
        Self { binding, buffer, offset: 0, range: vk::WHOLE_SIZE, as_texels: None, structure: None }
    }

    /// The top level of `scene` (the kernel's `accelerationStructureEXT`).
    pub fn acceleration_structure(binding: u32, scene: &'a SceneStructure) -> Self {
        Self { structure: Some(BoundStructure(scene.top_handle())), ..Self::whole(binding, scene.top_buffer()) }
    }

    fn descriptor_type(&self) -> vk::DescriptorType {
        match self.buffer.kind {
            _ if self.structure.is_some() => vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
            _ if self.as_texels.is_some() => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
            BufferKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
            BufferKind::Storage | BufferKind::HostStorage => vk::DescriptorType::STORAGE_BUFFER,
        }
    }
}

pub struct ComputeKernel {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    /// The views of the buffers bound as texels.
    texel_views: Vec<vk::BufferView>,
    push_size: u32,
    /// Two timestamps around each dispatch, where the device's queue records them.
    timestamps: Option<vk::QueryPool>,
    /// What the driver says of the compiled kernel (registers, spills), where it says anything.
    pub statistics: Vec<KernelStatistic>,
}

impl ComputeKernel {
    pub fn new(ctx: &GpuContext, spirv: &[u32], bindings: &[Binding], push_size: u32) -> Result<Self> {
        let device = &ctx.device;
        let layout_bindings: Vec<_> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.descriptor_type())
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: `device` is the context's live device, and the create-info borrows `layout_bindings`, a local
        // that outlives the call.
        let set_layout = unsafe {
            device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )
        }?;
        let push_ranges =
            [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).offset(0).size(push_size)];
        let set_layouts = [set_layout];
        // SAFETY: `set_layouts` holds the layout just created and `push_ranges` is a local; both outlive the call,
        // which only reads them.
        let layout = unsafe {
            device.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push_ranges),
                None,
            )
        }?;
        // SAFETY: `spirv` is a slice of u32 words, so the code pointer, its length in bytes and its 4-byte
        // alignment come from one live slice; a malformed module is an error of the call (and of validation), not
        // undefined behaviour of the host.
        let module = unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(spirv), None) }
            .context("creating the shader module")?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        let capture = if ctx.pipeline_statistics.is_some() {
            vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
        } else {
            vk::PipelineCreateFlags::empty()
        };
        // SAFETY: the create-info array is a temporary that lives to the end of the statement; its stage names
        // `module` (alive until the line below) with the entry point a static C string, and `layout` was created
        // above.
        let created = unsafe {
            device.create_compute_pipelines(
                vk::PipelineCache::null(),
                &[vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout).flags(capture)],
                None,
            )
        };
        // SAFETY: the module is needed only while the pipeline is created, which the call above finished
        // (successfully or not); nothing else holds the handle.
        unsafe { device.destroy_shader_module(module, None) };
        let pipeline = created.map_err(|(_, e)| anyhow!("creating the compute pipeline: {e}"))?[0];
        let statistics = ctx
            .pipeline_statistics
            .as_ref()
            .map(|loader| pipeline_statistics::read(loader, pipeline))
            .unwrap_or_default();

        let pool_sizes: Vec<_> = [
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::STORAGE_BUFFER,
            vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
            vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
        ]
        .into_iter()
        .map(|ty| vk::DescriptorPoolSize {
            ty,
            descriptor_count: bindings.iter().filter(|b| b.descriptor_type() == ty).count() as u32,
        })
        .filter(|size| size.descriptor_count > 0)
        .collect();
        // SAFETY: the create-info borrows `pool_sizes`, a local that outlives the call; `device` is alive.
        let pool = unsafe {
            device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&pool_sizes),
                None,
            )
        }?;
        // SAFETY: `pool` was created above with room for one set of these bindings, and `set_layouts` (a local)
        // holds the live layout.
        let set = unsafe {
            device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&set_layouts),
            )
        }?[0];
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .map(|b| [vk::DescriptorBufferInfo::default().buffer(b.buffer.buffer).offset(b.offset).range(b.range)])
            .collect();
        // Each binding's texel view (null for those bound as buffers).
        let views = bindings
            .iter()
            .map(|b| match b.as_texels {
                Some(words) => {
                    let info = vk::BufferViewCreateInfo::default()
                        .buffer(b.buffer.buffer)
                        .format(words.format())
                        .offset(b.offset)
                        .range(b.range);
                    // SAFETY: `info` names `b.buffer`, a live buffer made with UNIFORM_TEXEL_BUFFER usage
                    // (Buffer::with_data), at an offset aligned to min_texel_buffer_offset_alignment by the
                    // renderer's binding plan; it has no borrowed arrays.
                    unsafe { device.create_buffer_view(&info, None) }
                        .map(|view| [view])
                        .context("creating a texel view of a buffer")
                }
                None => Ok([vk::BufferView::null()]),
            })
            .collect::<Result<Vec<_>>>()?;
        let texel_views = views.iter().map(|[view]| *view).filter(|view| *view != vk::BufferView::null()).collect();
        let structures: Vec<[vk::AccelerationStructureKHR; 1]> =
            bindings.iter().map(|b| [b.structure.map(|s| s.0).unwrap_or_default()]).collect();
        let mut structure_writes: Vec<_> = structures
            .iter()
            .map(|s| vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(s))
            .collect();
        let writes: Vec<_> = bindings
            .iter()
            .zip(infos.iter().zip(&views))
            .zip(&mut structure_writes)
            .map(|((b, (info, view)), structure_write)| {
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(b.binding)
                    .descriptor_type(b.descriptor_type());
                match (b.structure, b.as_texels) {
                    (Some(_), _) => write.descriptor_count(1).push_next(structure_write),
                    (None, Some(_)) => write.texel_buffer_view(view),
                    (None, None) => write.buffer_info(info),
                }
            })
            .collect();
        // SAFETY: each write names `set` (allocated above) and borrows an element of `infos` or `views`, locals
        // that outlive the update; the buffers and views they name are alive, and no command buffer uses the set
        // yet.
        unsafe { device.update_descriptor_sets(&writes, &[]) };
        // SAFETY: a create-info without borrowed arrays, on the live device.
        let timestamps = match ctx.timestamp_period_ns {
            Some(_) => Some(unsafe {
                device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2),
                    None,
                )
            }?),
            None => None,
        };
        Ok(Self { set_layout, layout, pipeline, pool, set, texel_views, push_size, timestamps, statistics })
    }

    /// Records one dispatch of `groups` workgroups into `cb`, for work submitted with other
    /// commands (the viewer's frames); the caller orders it with barriers.
    pub(super) fn record(&self, device: &ash::Device, cb: vk::CommandBuffer, push: &[u8], groups: [u32; 3]) {
        assert_eq!(push.len() as u32, self.push_size, "push-constant block size");
        // SAFETY: `cb` is in the recording state (the caller's); the pipeline, layout and set belong to this live
        // kernel, and `push` is exactly the push-constant range's size (asserted above).
        unsafe {
            device.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            device.cmd_bind_descriptor_sets(cb, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[self.set], &[]);
            device.cmd_push_constants(cb, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            device.cmd_dispatch(cb, groups[0], groups[1], groups[2]);
        }
    }

    /// Runs one dispatch of `groups` workgroups and waits for it.
    pub fn dispatch(&self, ctx: &GpuContext, push: &[u8], groups: [u32; 3]) -> Result<()> {
        self.dispatch_timed(ctx, push, groups).map(|_| ())
    }

    /// [`dispatch`](Self::dispatch), returning the seconds the device spent on it by its own
    /// timestamps (`None` where its queue has none): throughput without the submission, fence
    /// and scheduling costs a wall clock also counts.
    pub fn dispatch_timed(&self, ctx: &GpuContext, push: &[u8], groups: [u32; 3]) -> Result<Option<f64>> {
        Self::dispatch_sequence_timed(ctx, &[(self, push, groups)])
    }

    /// Runs `steps` (kernel, push constants, workgroups) in order in one submission, each
    /// dispatch's writes visible to the next, and waits for them; returns the seconds the device
    /// spent on them all by its timestamps (those of the first kernel's pool), where it has them.
    pub fn dispatch_sequence_timed(
        ctx: &GpuContext,
        steps: &[(&ComputeKernel, &[u8], [u32; 3])],
    ) -> Result<Option<f64>> {
        let Some(&(first, _, _)) = steps.first() else {
            return Ok(Some(0.0));
        };
        // SAFETY: `cb` is recording (submit_and_wait), the query pool and every kernel of `steps` are alive while
        // the submission is waited for, and the barrier is a local the call only reads.
        ctx.submit_and_wait(|device, cb| unsafe {
            if let Some(pool) = first.timestamps {
                device.cmd_reset_query_pool(cb, pool, 0, 2);
                device.cmd_write_timestamp(cb, vk::PipelineStageFlags::TOP_OF_PIPE, pool, 0);
            }
            for &(kernel, push, groups) in steps {
                assert_eq!(push.len() as u32, kernel.push_size, "push-constant block size");
                kernel.record(device, cb, push, groups);
                // Each dispatch's writes reach the next, and the host's reads after the last.
                let barrier =
                    vk::MemoryBarrier::default().src_access_mask(vk::AccessFlags::SHADER_WRITE).dst_access_mask(
                        vk::AccessFlags::TRANSFER_READ
                            | vk::AccessFlags::HOST_READ
                            | vk::AccessFlags::SHADER_READ
                            | vk::AccessFlags::SHADER_WRITE,
                    );
                device.cmd_pipeline_barrier(
                    cb,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::TRANSFER
                        | vk::PipelineStageFlags::HOST
                        | vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::DependencyFlags::empty(),
                    &[barrier],
                    &[],
                    &[],
                );
            }
            if let Some(pool) = first.timestamps {
                device.cmd_write_timestamp(cb, vk::PipelineStageFlags::BOTTOM_OF_PIPE, pool, 1);
            }
        })?;
        let (Some(pool), Some(period_ns)) = (first.timestamps, ctx.timestamp_period_ns) else {
            return Ok(None);
        };
        let mut ticks = [0u64; 2];
        // SAFETY: the submission that wrote both timestamps of `pool` was waited for above, `ticks` has room for
        // the two 64-bit results asked for (TYPE_64), and WAIT makes the call return only available values.
        unsafe {
            ctx.device.get_query_pool_results(
                pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        Ok(Some(ticks[1].wrapping_sub(ticks[0]) as f64 * period_ns * 1e-9))
    }

    pub fn destroy(self, ctx: &GpuContext) {
        let device = &ctx.device;
        // SAFETY: `self` is consumed, so each handle is destroyed once, dependents first (views, pipeline, then
        // layouts); every dispatch that used them was waited for (submit_and_wait) or the viewer made the device
        // idle before dropping its kernel.
        unsafe {
            if let Some(pool) = self.timestamps {
                device.destroy_query_pool(pool, None);
            }
            for view in self.texel_views {
                device.destroy_buffer_view(view, None);
            }
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_pool(self.pool, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
