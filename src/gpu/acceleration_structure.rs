//! Vulkan acceleration structures for the ray-query traversal (traversal.rs): one bottom-level
//! structure per geometry the caller lists (a mesh's triangles, or the boxes of the scene's own
//! shapes), built once however often it is placed, and one top-level structure over the
//! placements with their transforms. The kernel binds the top level (`scene_structure`,
//! src/render/bindings.rs) and meets the bottom levels through it.

use super::buffer::{Buffer, BufferKind};
use super::context::GpuContext;
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// One bottom level's geometry.
pub enum BottomGeometry {
    /// Triangles by their three vertices each (so `positions.len()` is three times the
    /// triangles'). `opaque`: no triangle of it needs the kernel's look before a hit counts (no
    /// alpha); else every one is a candidate the kernel confirms or passes through.
    Triangles { positions: Vec<[f32; 3]>, opaque: bool },
    /// Axis-aligned boxes (min, max), one a shape the kernel intersects exactly on each candidate.
    Boxes(Vec<[[f32; 3]; 2]>),
}

impl BottomGeometry {
    fn primitive_count(&self) -> u32 {
        match self {
            Self::Triangles { positions, .. } => (positions.len() / 3) as u32,
            Self::Boxes(boxes) => boxes.len() as u32,
        }
    }

    fn bytes(&self) -> &[u8] {
        match self {
            Self::Triangles { positions, .. } => bytemuck::cast_slice(positions),
            Self::Boxes(boxes) => bytemuck::cast_slice(boxes),
        }
    }
}

/// One placement of a bottom level in the top level.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// Index into the bottom levels.
    pub bottom: usize,
    /// Rows of the 3x4 affine object-to-world transform.
    pub object_to_world: [[f32; 4]; 3],
    /// What the kernel reads back as the hit's instance custom index (24 bits).
    pub custom_index: u32,
    /// Rays whose cull mask shares no bit with it pass it by (8 bits; 0: never met).
    pub mask: u8,
}

/// Largest custom index a placement can carry (24 bits).
pub const MAX_CUSTOM_INDEX: u32 = (1 << 24) - 1;

/// An acceleration structure and the buffer that holds it.
struct Structure {
    handle: vk::AccelerationStructureKHR,
    buffer: Buffer,
    address: vk::DeviceAddress,
}

/// The scene's acceleration structures: the bottom levels and the top level over them.
pub struct SceneStructure {
    top: Structure,
    bottoms: Vec<Structure>,
}

fn buffer_address(ctx: &GpuContext, buffer: &Buffer) -> vk::DeviceAddress {
    // SAFETY: `buffer` is alive and was created with SHADER_DEVICE_ADDRESS usage on a device whose
    // bufferDeviceAddress feature is enabled (ray queries only, which is when this is called).
    unsafe { ctx.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(buffer.buffer)) }
}

/// A device-local buffer holding `bytes`, that a build reads through its device address.
fn build_input(ctx: &GpuContext, name: &str, bytes: &[u8]) -> Result<Buffer> {
    let usage = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
        | vk::BufferUsageFlags::TRANSFER_DST;
    let buffer = Buffer::create(ctx, name, bytes.len() as u64, usage, MemoryLocation::GpuOnly, BufferKind::Storage)?;
    buffer.upload(ctx, bytes)?;
    Ok(buffer)
}

/// Scratch memory of at least `size` bytes whose address is aligned as the device requires.
fn scratch(ctx: &GpuContext, size: u64, alignment: u64) -> Result<(Buffer, vk::DeviceAddress)> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    let buffer = Buffer::create(
        ctx,
        "acceleration structure scratch",
        size + alignment,
        usage,
        MemoryLocation::GpuOnly,
        BufferKind::Storage,
    )?;
    let address = buffer_address(ctx, &buffer).next_multiple_of(alignment);
    Ok((buffer, address))
}

/// Builds one structure of `ty` from `geometry` of `count` primitives (`what` names it in errors)
/// and waits for it; the build's writes are made visible to later builds and to compute shaders.
fn build(
    ctx: &GpuContext,
    ty: vk::AccelerationStructureTypeKHR,
    geometry: vk::AccelerationStructureGeometryKHR,
    count: u32,
    what: &str,
) -> Result<Structure> {
    let (loader, scratch_alignment) = ctx
        .acceleration_structures
        .as_ref()
        .ok_or_else(|| anyhow!("{} was opened without ray queries", ctx.info.name))?;
    let geometries = [geometry];
    let mut info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(&geometries);
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: `info` borrows `geometries`, a local alive until the call returns; the loader is the
    // live device's, made where the acceleration-structure extension is enabled.
    unsafe {
        loader.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[count],
            &mut sizes,
        )
    };
    let buffer = Buffer::create(
        ctx,
        what,
        sizes.acceleration_structure_size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
        BufferKind::Storage,
    )?;
    let create = vk::AccelerationStructureCreateInfoKHR::default()
        .buffer(buffer.buffer)
        .size(sizes.acceleration_structure_size)
        .ty(ty);
    // SAFETY: `buffer` is alive, device-local and at least the size the build asked for; the
    // structure is destroyed (Structure::destroy) before its buffer.
    let handle = match unsafe { loader.create_acceleration_structure(&create, None) } {
        Ok(handle) => handle,
        Err(e) => {
            buffer.destroy(ctx);
            bail!("creating the {what} on {}: {e}", ctx.info.name);
        }
    };
    let built = (|| -> Result<()> {
        let (scratch, scratch_address) = scratch(ctx, sizes.build_scratch_size, *scratch_alignment)?;
        info = info
            .dst_acceleration_structure(handle)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch_address });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
        // SAFETY: `cb` is recording; `info` and `range` are locals that outlive the recording, and
        // the input, scratch and destination buffers stay alive until submit_and_wait has waited
        // for the build's fence.
        let result = ctx.submit_and_wait(|device, cb| unsafe {
            loader.cmd_build_acceleration_structures(cb, &[info], &[&range]);
            // The build's writes reach the top level's build and the kernel's ray queries.
            let barrier = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR)
                .dst_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR);
            device.cmd_pipeline_barrier(
                cb,
                vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR | vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
        });
        scratch.destroy(ctx);
        result.with_context(|| format!("building the {what} on {}", ctx.info.name))
    })();
    let structure = Structure { handle, address: 0, buffer };
    if let Err(e) = built {
        structure.destroy(ctx);
        return Err(e);
    }
    // SAFETY: `handle` is the structure just built and alive; the device has bufferDeviceAddress.
    let address = unsafe {
        loader.get_acceleration_structure_device_address(
            &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(handle),
        )
    };
    Ok(Structure { address, ..structure })
}

impl Structure {
    fn destroy(self, ctx: &GpuContext) {
        if let Some((loader, _)) = &ctx.acceleration_structures {
            // SAFETY: the structure is this one's own; no submission that reads it is in flight
            // (builds and dispatches are waited for), and its buffer is destroyed after it.
            unsafe { loader.destroy_acceleration_structure(self.handle, None) };
        }
        self.buffer.destroy(ctx);
    }
}

/// A bottom level of `geometry`.
fn bottom_level(ctx: &GpuContext, geometry: &BottomGeometry) -> Result<Structure> {
    let count = geometry.primitive_count();
    let input = build_input(ctx, "acceleration structure geometry", geometry.bytes())?;
    let address = vk::DeviceOrHostAddressConstKHR { device_address: buffer_address(ctx, &input) };
    let (data, flags) = match geometry {
        BottomGeometry::Triangles { positions, opaque } => (
            vk::AccelerationStructureGeometryDataKHR {
                triangles: vk::AccelerationStructureGeometryTrianglesDataKHR::default()
                    .vertex_format(vk::Format::R32G32B32_SFLOAT)
                    .vertex_data(address)
                    .vertex_stride(12)
                    .max_vertex(positions.len().saturating_sub(1) as u32)
                    .index_type(vk::IndexType::NONE_KHR),
            },
            if *opaque { vk::GeometryFlagsKHR::OPAQUE } else { vk::GeometryFlagsKHR::empty() },
        ),
        BottomGeometry::Boxes(_) => (
            vk::AccelerationStructureGeometryDataKHR {
                aabbs: vk::AccelerationStructureGeometryAabbsDataKHR::default().data(address).stride(24),
            },
            // Every box is a candidate the kernel intersects exactly; the hit it reports is opaque.
            vk::GeometryFlagsKHR::empty(),
        ),
    };
    let ty = match geometry {
        BottomGeometry::Triangles { .. } => vk::GeometryTypeKHR::TRIANGLES,
        BottomGeometry::Boxes(_) => vk::GeometryTypeKHR::AABBS,
    };
    let geometry = vk::AccelerationStructureGeometryKHR::default().geometry_type(ty).geometry(data).flags(flags);
    let built = build(ctx, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, geometry, count, "bottom-level structure");
    input.destroy(ctx);
    built
}

impl SceneStructure {
    /// Builds every bottom level, then the top level over `placements`, in their order: the
    /// kernel's `rayQueryGetIntersectionInstanceIdEXT` is a placement's index there.
    pub fn build(ctx: &GpuContext, bottoms: &[BottomGeometry], placements: &[Placement]) -> Result<Self> {
        let mut built = Vec::with_capacity(bottoms.len());
        for geometry in bottoms {
            match bottom_level(ctx, geometry) {
                Ok(structure) => built.push(structure),
                Err(e) => {
                    built.into_iter().for_each(|s: Structure| s.destroy(ctx));
                    return Err(e);
                }
            }
        }
        let top = Self::top_level(ctx, &built, placements);
        match top {
            Ok(top) => Ok(Self { top, bottoms: built }),
            Err(e) => {
                built.into_iter().for_each(|s| s.destroy(ctx));
                Err(e)
            }
        }
    }

    fn top_level(ctx: &GpuContext, bottoms: &[Structure], placements: &[Placement]) -> Result<Structure> {
        let instances = placements
            .iter()
            .map(|p| {
                if p.custom_index > MAX_CUSTOM_INDEX {
                    bail!("a placement's custom index {} is beyond 24 bits", p.custom_index);
                }
                let bottom = bottoms.get(p.bottom).ok_or_else(|| anyhow!("placement of bottom level {}", p.bottom))?;
                let matrix: [f32; 12] = bytemuck::cast(p.object_to_world);
                Ok(vk::AccelerationStructureInstanceKHR {
                    transform: vk::TransformMatrixKHR { matrix },
                    instance_custom_index_and_mask: vk::Packed24_8::new(p.custom_index, p.mask),
                    // Both faces of every triangle count: surfaces are two-sided to rays.
                    instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                        0,
                        vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                    ),
                    acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                        device_handle: bottom.address,
                    },
                })
            })
            .collect::<Result<Vec<_>>>()?;
        // SAFETY: the pointer and length come from the `instances` vector, alive for the slice's use;
        // VkAccelerationStructureInstanceKHR is repr(C), 64 bytes with no padding, so every byte is
        // initialised, and those bytes are the records the build reads.
        let bytes = unsafe {
            std::slice::from_raw_parts(instances.as_ptr().cast::<u8>(), std::mem::size_of_val(&instances[..]))
        };
        let input = build_input(ctx, "acceleration structure instances", bytes)?;
        let data = vk::AccelerationStructureGeometryDataKHR {
            instances: vk::AccelerationStructureGeometryInstancesDataKHR::default()
                .data(vk::DeviceOrHostAddressConstKHR { device_address: buffer_address(ctx, &input) }),
        };
        let geometry = vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(data);
        let built = build(
            ctx,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            geometry,
            instances.len() as u32,
            "top-level structure",
        );
        input.destroy(ctx);
        built
    }

    /// Bytes the structures take on the device.
    pub fn bytes(&self) -> u64 {
        self.top.buffer.size + self.bottoms.iter().map(|b| b.buffer.size).sum::<u64>()
    }

    /// The top level, which the kernel binds.
    pub(super) fn top_handle(&self) -> vk::AccelerationStructureKHR {
        self.top.handle
    }

    /// The buffer holding the top level (what a [`super::Binding`] of it names).
    pub(super) fn top_buffer(&self) -> &Buffer {
        &self.top.buffer
    }

    pub fn destroy(self, ctx: &GpuContext) {
        self.top.destroy(ctx);
        for bottom in self.bottoms {
            bottom.destroy(ctx);
        }
    }
}
