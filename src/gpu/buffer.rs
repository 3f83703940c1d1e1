//! Storage, uniform and staging buffers with their memory.

use super::context::GpuContext;
use anyhow::{anyhow, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferKind {
    /// Read-mostly data the kernel reads (scene, BVH, environment): device-local, filled by staging.
    Storage,
    /// Per-render parameters.
    Uniform,
    /// Small host-visible storage the kernel writes and the host reads every dispatch (counters).
    HostStorage,
}

pub struct Buffer {
    pub(super) buffer: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
    pub kind: BufferKind,
}

// Vulkan forbids zero-sized buffers; empty arrays (a scene without lights) get this much.
const MIN_SIZE: u64 = 16;

impl Buffer {
    pub(super) fn create(
        ctx: &GpuContext,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        kind: BufferKind,
    ) -> Result<Self> {
        let size = size.max(MIN_SIZE);
        let device = &ctx.device;
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: `info` is a complete create-info on the stack with no borrowed arrays, and `device` is the
        // context's live logical device; the new handle is queried at once, while nothing else knows it.
        let buffer = unsafe { device.create_buffer(&info, None) }.with_context(|| format!("creating buffer {name}"))?;
        let requirements = unsafe { device.get_buffer_memory_requirements(buffer) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: `buffer` was created just above, has no memory bound and was handed to nobody: destroying
                // it leaks nothing and nothing can still use it.
                unsafe { device.destroy_buffer(buffer, None) };
                return Err(anyhow!(
                    "allocating {:.1} MiB for {name} on {}: {e}",
                    size as f64 / 1048576.0,
                    ctx.info.name
                ));
            }
        };
        // SAFETY: the allocation was made for this buffer's own memory requirements (size and alignment), so its
        // memory and offset satisfy vkBindBufferMemory; the buffer has no memory bound yet.
        unsafe { device.bind_buffer_memory(buffer, allocation.memory(), allocation.offset()) }?;
        Ok(Self { buffer, allocation: Some(allocation), size, kind })
    }

    /// A device-local buffer of `kind` holding `bytes`, uploaded through a staging buffer.
    pub fn with_data(ctx: &GpuContext, name: &str, kind: BufferKind, bytes: &[u8]) -> Result<Self> {
        let usage = match kind {
            BufferKind::Uniform => vk::BufferUsageFlags::UNIFORM_BUFFER,
            // Any of the kernel's arrays may be bound as texels (src/render/bindings.rs).
            BufferKind::Storage | BufferKind::HostStorage => {
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            }
        };
        if kind == BufferKind::HostStorage {
            let mut buffer = Self::create(ctx, name, bytes.len() as u64, usage, MemoryLocation::GpuToCpu, kind)?;
            buffer.write(bytes)?;
            return Ok(buffer);
        }
        let usage = usage | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
        let buffer = Self::create(ctx, name, bytes.len() as u64, usage, MemoryLocation::GpuOnly, kind)?;
        buffer.upload(ctx, bytes)?;
        Ok(buffer)
    }

    /// Replaces the start of a device-local buffer's contents with `bytes`.
    pub fn upload(&self, ctx: &GpuContext, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        let mut staging = Self::create(
            ctx,
            "staging upload",
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
            BufferKind::HostStorage,
        )?;
        staging.write(bytes)?;
        let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes.len() as u64 };
        // SAFETY: `cb` is the recording command buffer submit_and_wait gives, and both buffers are alive until the
        // call has waited for the copy: `staging` is destroyed after it, `self` is borrowed. The region lies inside
        // both: `staging` holds `bytes.len()` bytes and the caller's buffer at least as many.
        let result = ctx.submit_and_wait(|device, cb| unsafe {
            device.cmd_copy_buffer(cb, staging.buffer, self.buffer, &[region])
        });
        staging.destroy(ctx);
        result
    }

    /// Copies the first `len` bytes of a device-local buffer back to the host.
    pub fn download(&self, ctx: &GpuContext, len: u64) -> Result<Vec<u8>> {
        let staging = Self::create(
            ctx,
            "staging readback",
            len,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
            BufferKind::HostStorage,
        )?;
        let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: len };
        let result = ctx
            // SAFETY: `cb` is recording (submit_and_wait), both buffers outlive the wait for the copy (`staging` is
            // destroyed after it), and the region of `len` bytes lies inside both: `staging` was made `len` bytes
            // long and the caller asks for no more than its buffer holds.
            .submit_and_wait(|device, cb| unsafe { device.cmd_copy_buffer(cb, self.buffer, staging.buffer, &[region]) })
            .and_then(|_| Ok(staging.read()?[..len as usize].to_vec()));
        staging.destroy(ctx);
        result
    }

    /// Host-visible buffers only.
    pub fn write(&mut self, bytes: &[u8]) -> Result<()> {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| anyhow!("buffer is not host-visible"))?;
        slice[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Host-visible buffers only.
    pub fn read(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..self.size as usize])
            .ok_or_else(|| anyhow!("buffer is not host-visible"))
    }

    pub fn destroy(mut self, ctx: &GpuContext) {
        // SAFETY: `self` is consumed, so this handle is destroyed once; every copy or dispatch that used it was
        // waited for (submit_and_wait) or the device was made idle (the viewer) before its owner lets it go.
        unsafe { ctx.device.destroy_buffer(self.buffer, None) };
        if let Some(a) = self.allocation.take() {
            let _ = ctx.allocator().free(a);
        }
    }
}
