//! Puts frames in a window: each frame runs a display kernel that writes the picture's bytes into
//! a buffer, copies them into a swapchain image, draws the overlay over them, presents, and (for
//! a screenshot) reads the presented image back. The swapchain is re-created when the window's
//! size changes or the surface says it is out of date; a minimized window gets no frames.

use super::buffer::{Buffer, BufferKind};
use super::compute::ComputeKernel;
use super::context::GpuContext;
use super::failure::VulkanError;
use super::overlay_pass::{OverlayDraw, OverlayPass};
use super::swapchain::{ChannelOrder, Swapchain, COLOR_RANGE};
use anyhow::{anyhow, bail, ensure, Context as _, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The picture of a frame: a dispatch of `kernel` writes `pixels`, one u32 per pixel whose bytes
/// are in the swapchain's [`ChannelOrder`], rows top first, `size` pixels. It is copied into the
/// swapchain image as it is: the swapchain converts nothing.
pub struct Picture<'a> {
    pub kernel: &'a ComputeKernel,
    pub push: &'a [u8],
    pub groups: [u32; 3],
    pub pixels: &'a Buffer,
    pub size: [u32; 2],
}

pub struct Frame<'a> {
    /// `None` shows black.
    pub picture: Option<Picture<'a>>,
    pub overlay: Option<OverlayDraw<'a>>,
    /// Read the presented image back ([`Presented::Shown`] then carries it).
    pub read_back: bool,
}

/// What the window showed, read back from the presented swapchain image: RGB bytes, rows top first.
pub struct Screen {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

pub enum Presented {
    Shown(Option<Screen>),
    /// Nothing was presented: the window is minimized, or its swapchain was out of date (it is
    /// re-created for the next frame).
    NotShown,
}

pub struct Presenter {
    swapchain: Option<Swapchain>,
    overlay: Option<OverlayPass>,
    /// The window's size in pixels, which the swapchain follows.
    size: [u32; 2],
    /// The swapchain no longer matches the window: re-create it before the next frame.
    stale: bool,
    command_buffer: vk::CommandBuffer,
    image_available: vk::Semaphore,
    /// One per swapchain image: a semaphore a presentation waits on is reused only once that
    /// image is acquired again.
    render_finished: Vec<vk::Semaphore>,
    frame_done: vk::Fence,
}

impl Presenter {
    pub fn new(ctx: &GpuContext, size: [u32; 2]) -> Result<Self> {
        let device = &ctx.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(ctx.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the context's command pool (RESET_COMMAND_BUFFER, so the buffer may be reset each frame) and
        // create-infos without borrowed arrays, on the live device; each handle is freed in destroy().
        let command_buffer = unsafe { device.allocate_command_buffers(&alloc) }?[0];
        let image_available = unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }?;
        let frame_done = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        let mut presenter = Self {
            swapchain: None,
            overlay: None,
            size,
            stale: true,
            command_buffer,
            image_available,
            render_finished: vec![],
            frame_done,
        };
        if let Err(e) = presenter.recreate(ctx) {
            presenter.destroy(ctx);
            return Err(e);
        }
        Ok(presenter)
    }

    /// The window now has `size` pixels.
    pub fn resize(&mut self, size: [u32; 2]) {
        if size != self.size {
            self.size = size;
            self.stale = true;
        }
    }

    /// Byte order the pictures must have (`None` while there is no swapchain: minimized).
    pub fn channel_order(&self) -> Option<ChannelOrder> {
        self.swapchain.as_ref().map(|s| s.order)
    }

    /// The size of the images presented (`None` while minimized).
    pub fn extent(&self) -> Option<[u32; 2]> {
        self.swapchain.as_ref().map(|s| [s.extent.width, s.extent.height])
    }

    fn recreate(&mut self, ctx: &GpuContext) -> Result<()> {
        // SAFETY: the device is alive as long as `ctx`; after the wait nothing in flight uses the old swapchain,
        // its views and framebuffers, which are destroyed below.
        unsafe { ctx.device.device_wait_idle() }.map_err(VulkanError)?;
        let old = self.swapchain.take();
        let created = Swapchain::new(ctx, self.size, old.as_ref().map_or(vk::SwapchainKHR::null(), |s| s.handle));
        if let Some(old) = old {
            old.destroy(ctx);
        }
        self.stale = false;
        let Some(swapchain) = created? else {
            return Ok(());
        };
        match &mut self.overlay {
            Some(overlay) => overlay.recreate_framebuffers(ctx, &swapchain)?,
            None => self.overlay = Some(OverlayPass::new(ctx, &swapchain)?),
        }
        for s in self.render_finished.drain(..) {
            // SAFETY: the device was made idle at the top of recreate(), so no presentation still waits on these
            // semaphores; each was created by this presenter and is drained from the list as it is destroyed.
            unsafe { ctx.device.destroy_semaphore(s, None) };
        }
        for _ in &swapchain.images {
            // SAFETY: a create-info without borrowed arrays on the live device; the semaphore is kept in
            // `render_finished` and destroyed by recreate() or destroy().
            self.render_finished
                .push(unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }?);
        }
        self.swapchain = Some(swapchain);
        Ok(())
    }

    /// Draws and presents one frame.
    pub fn present(&mut self, ctx: &GpuContext, frame: &Frame) -> Result<Presented> {
        if self.stale {
            self.recreate(ctx)?;
        }
        let Some(swapchain) = &self.swapchain else {
            return Ok(Presented::NotShown);
        };
        let (handle, extent, order, readable) =
            (swapchain.handle, swapchain.extent, swapchain.order, swapchain.readable);
        let loader = &ctx.presentation.as_ref().expect("a swapchain implies a presentation").swapchain_loader;
        // SAFETY: `handle` is the live swapchain of this presenter (made for ctx's surface, whose loader this is),
        // and `image_available` has no signal pending: the frame submitted after each successful acquire waits
        // on it and is waited for (a frame that fails before its submission ends the viewer with the error).
        let index =
            match unsafe { loader.acquire_next_image(handle, u64::MAX, self.image_available, vk::Fence::null()) } {
                Ok((index, suboptimal)) => {
                    self.stale |= suboptimal;
                    index as usize
                }
                Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                    self.stale = true;
                    return Ok(Presented::NotShown);
                }
                Err(vk::Result::ERROR_SURFACE_LOST_KHR) => {
                    bail!("the window's surface is lost (did another program destroy the window?)")
                }
                Err(e) => return Err(anyhow!("acquiring a swapchain image: {e}")),
            };
        if let Some(draw) = &frame.overlay {
            self.overlay.as_mut().expect("a swapchain has an overlay pass").update_textures(ctx, draw.textures)?;
        }
        ensure!(
            !frame.read_back || readable,
            "{} cannot copy from the window's images, so the screen cannot be read back",
            ctx.info.name
        );
        let readback = match frame.read_back {
            true => Some(Buffer::create(
                ctx,
                "screen readback",
                extent.width as u64 * extent.height as u64 * 4,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                BufferKind::HostStorage,
            )?),
            false => None,
        };
        let recorded = self.record(ctx, index, frame, readback.as_ref());
        let submitted = recorded.and_then(|()| self.submit(ctx, index));
        let screen = submitted.and_then(|()| readback.as_ref().map(|b| screen_from(b, extent, order)).transpose());
        if let Some(b) = readback {
            b.destroy(ctx);
        }
        let screen = screen?;
        if let Some(draw) = &frame.overlay {
            self.overlay.as_mut().expect("a swapchain has an overlay pass").free_textures(draw.textures)?;
        }
        let semaphores = [self.render_finished[index]];
        let swapchains = [handle];
        let indices = [index as u32];
        let present =
            vk::PresentInfoKHR::default().wait_semaphores(&semaphores).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: `present` borrows `semaphores`, `swapchains` and `indices`, locals alive until the call returns;
        // `index` was acquired above, and the semaphore is signalled by the frame submitted for that image.
        match unsafe { loader.queue_present(ctx.queue, &present) } {
            Ok(suboptimal) => {
                self.stale |= suboptimal;
                Ok(Presented::Shown(screen))
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                Ok(Presented::NotShown)
            }
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => {
                bail!("the window's surface is lost (did another program destroy the window?)")
            }
            Err(e) => Err(anyhow!("presenting: {e}")),
        }
    }

    fn record(&mut self, ctx: &GpuContext, index: usize, frame: &Frame, readback: Option<&Buffer>) -> Result<()> {
        let device = &ctx.device;
        let cb = self.command_buffer;
        let swapchain = self.swapchain.as_ref().expect("recording needs a swapchain");
        let (image, extent) = (swapchain.images[index], swapchain.extent);
        // SAFETY: `cb` is this presenter's buffer from a pool that allows resets, and the last frame that used it
        // was waited for (submit); `image` is the acquired swapchain image, `p.pixels` a live buffer of the
        // picture's size, and the copy region lies inside both (the extent is the smaller of the two). Barriers and
        // regions are locals the calls only read.
        unsafe {
            device.reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())?;
            device.begin_command_buffer(
                cb,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            if let Some(p) = &frame.picture {
                p.kernel.record(device, cb, p.push, p.groups);
                let written = vk::BufferMemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                    .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .buffer(p.pixels.buffer)
                    .size(vk::WHOLE_SIZE);
                device.cmd_pipeline_barrier(
                    cb,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[written],
                    &[],
                );
            }
            // The acquire semaphore is waited on at the transfer stage: this transition comes after it.
            image_barrier(
                device,
                cb,
                image,
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
                (vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::TRANSFER),
                (vk::AccessFlags::empty(), vk::AccessFlags::TRANSFER_WRITE),
            );
            let covered = frame.picture.as_ref().is_some_and(|p| p.size == [extent.width, extent.height]);
            if !covered {
                let black = vk::ClearColorValue { float32: [0.0, 0.0, 0.0, 1.0] };
                device.cmd_clear_color_image(cb, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &black, &[COLOR_RANGE]);
                image_barrier(
                    device,
                    cb,
                    image,
                    (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
                    (vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::TRANSFER),
                    (vk::AccessFlags::TRANSFER_WRITE, vk::AccessFlags::TRANSFER_WRITE),
                );
            }
            if let Some(p) = &frame.picture {
                // A picture of another size (the window is being resized) shows its top-left part.
                let region = vk::BufferImageCopy::default()
                    .buffer_row_length(p.size[0])
                    .buffer_image_height(p.size[1])
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D {
                        width: p.size[0].min(extent.width),
                        height: p.size[1].min(extent.height),
                        depth: 1,
                    });
                device.cmd_copy_buffer_to_image(
                    cb,
                    p.pixels.buffer,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                );
            }
        }
        match &frame.overlay {
            Some(draw) => self
                .overlay
                .as_mut()
                .expect("a swapchain has an overlay pass")
                .record(device, cb, index, extent, draw)?,
            // SAFETY: `cb` is recording (above), and `image` the acquired swapchain image, left in
            // TRANSFER_DST_OPTIMAL by the copy above.
            None => unsafe {
                image_barrier(
                    device,
                    cb,
                    image,
                    (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::PRESENT_SRC_KHR),
                    (vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::BOTTOM_OF_PIPE),
                    (vk::AccessFlags::TRANSFER_WRITE, vk::AccessFlags::empty()),
                );
            },
        }
        if let Some(readback) = readback {
            let written = vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT;
            let write_access = vk::AccessFlags::TRANSFER_WRITE | vk::AccessFlags::COLOR_ATTACHMENT_WRITE;
            // SAFETY: `cb` is recording; `image` is in PRESENT_SRC_KHR (the overlay pass or the barrier above put
            // it there), `readback` holds extent.width x extent.height x 4 bytes (made for this extent in
            // present()), and the image was made with TRANSFER_SRC usage (`readable`, checked in present()).
            unsafe {
                image_barrier(
                    device,
                    cb,
                    image,
                    (vk::ImageLayout::PRESENT_SRC_KHR, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
                    (written, vk::PipelineStageFlags::TRANSFER),
                    (write_access, vk::AccessFlags::TRANSFER_READ),
                );
                let region = vk::BufferImageCopy::default()
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
                device.cmd_copy_image_to_buffer(
                    cb,
                    image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    readback.buffer,
                    &[region],
                );
                image_barrier(
                    device,
                    cb,
                    image,
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::PRESENT_SRC_KHR),
                    (vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::BOTTOM_OF_PIPE),
                    (vk::AccessFlags::empty(), vk::AccessFlags::empty()),
                );
                let to_host = vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                    .dst_access_mask(vk::AccessFlags::HOST_READ);
                device.cmd_pipeline_barrier(
                    cb,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &[to_host],
                    &[],
                    &[],
                );
            }
        }
        // SAFETY: `cb` is in the recording state begun above.
        unsafe { device.end_command_buffer(cb) }?;
        Ok(())
    }

    /// Submits the recorded frame and waits for it: the viewer's kernel dispatches wait for their
    /// own fences too, so one frame in flight costs nothing.
    fn submit(&self, ctx: &GpuContext, index: usize) -> Result<()> {
        let waits = [self.image_available];
        let stages = [vk::PipelineStageFlags::TRANSFER];
        let cbs = [self.command_buffer];
        let signals = [self.render_finished[index]];
        let submit = [vk::SubmitInfo::default()
            .wait_semaphores(&waits)
            .wait_dst_stage_mask(&stages)
            .command_buffers(&cbs)
            .signal_semaphores(&signals)];
        // SAFETY: `submit` borrows `waits`, `stages`, `cbs` and `signals`, locals alive until the call returns;
        // `cb` was recorded by record(), and waiting for `frame_done` then resetting it leaves it unsignalled for
        // the next frame. The context is used from one thread, which is the queue's external synchronisation.
        unsafe {
            ctx.device
                .queue_submit(ctx.queue, &submit, self.frame_done)
                .map_err(VulkanError)
                .context("submitting a frame")?;
            ctx.device.wait_for_fences(&[self.frame_done], true, u64::MAX).map_err(VulkanError)?;
            ctx.device.reset_fences(&[self.frame_done])?;
        }
        Ok(())
    }

    pub fn destroy(mut self, ctx: &GpuContext) {
        // SAFETY: the device is waited idle first, so no frame or presentation still uses what is destroyed; `self`
        // is consumed, so each handle is destroyed once, and the command buffer goes back to the context's pool it
        // came from.
        unsafe {
            let _ = ctx.device.device_wait_idle();
            if let Some(overlay) = self.overlay.take() {
                overlay.destroy(ctx);
            }
            if let Some(swapchain) = self.swapchain.take() {
                swapchain.destroy(ctx);
            }
            for s in self.render_finished.drain(..) {
                ctx.device.destroy_semaphore(s, None);
            }
            ctx.device.destroy_semaphore(self.image_available, None);
            ctx.device.destroy_fence(self.frame_done, None);
            ctx.device.free_command_buffers(ctx.command_pool, &[self.command_buffer]);
        }
    }
}

/// A layout transition of a whole swapchain image.
///
/// # Safety
/// `cb` must be a command buffer of `device` in the recording state, and `image` a live image of
/// `device` (a swapchain image) in layout `layouts.0` when the barrier runs.
unsafe fn image_barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    image: vk::Image,
    layouts: (vk::ImageLayout, vk::ImageLayout),
    stages: (vk::PipelineStageFlags, vk::PipelineStageFlags),
    access: (vk::AccessFlags, vk::AccessFlags),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(layouts.0)
        .new_layout(layouts.1)
        .src_access_mask(access.0)
        .dst_access_mask(access.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(COLOR_RANGE);
    device.cmd_pipeline_barrier(cb, stages.0, stages.1, vk::DependencyFlags::empty(), &[], &[], &[barrier]);
}

/// RGB bytes from a read-back image of `extent` pixels in `order`.
fn screen_from(readback: &Buffer, extent: vk::Extent2D, order: ChannelOrder) -> Result<Screen> {
    let bytes = readback.read()?;
    let pixels = extent.width as usize * extent.height as usize;
    let rgb = bytes[..pixels * 4]
        .chunks_exact(4)
        .flat_map(|p| match order {
            ChannelOrder::Rgba => [p[0], p[1], p[2]],
            ChannelOrder::Bgra => [p[2], p[1], p[0]],
        })
        .collect();
    Ok(Screen { width: extent.width, height: extent.height, rgb })
}
