//! Draws an egui overlay over a swapchain image that already holds the picture: a render pass
//! that loads the image, egui-ash-renderer's pipeline, and a framebuffer per swapchain image.

use super::context::GpuContext;
use super::swapchain::Swapchain;
use anyhow::{anyhow, Context as _, Result};
use ash::vk;
use egui_ash_renderer::{Options, RenderMode, Renderer};

/// What egui asks to be drawn in one frame.
pub struct OverlayDraw<'a> {
    pub primitives: &'a [egui::ClippedPrimitive],
    pub textures: &'a egui::TexturesDelta,
    pub pixels_per_point: f32,
}

pub(super) struct OverlayPass {
    render_pass: vk::RenderPass,
    format: vk::Format,
    framebuffers: Vec<vk::Framebuffer>,
    renderer: Option<Renderer<egui_ash_renderer::allocator::DefaultAllocator>>,
}

fn is_srgb(format: vk::Format) -> bool {
    matches!(format, vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB)
}

impl OverlayPass {
    pub(super) fn new(ctx: &GpuContext, swapchain: &Swapchain) -> Result<Self> {
        // The picture was copied into the image (TRANSFER_DST_OPTIMAL) just before: load it, draw
        // over it, and leave it ready to present.
        let attachment = [vk::AttachmentDescription::default()
            .format(swapchain.format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)
            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .final_layout(vk::ImageLayout::PRESENT_SRC_KHR)];
        let color =
            [vk::AttachmentReference::default().attachment(0).layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
        let subpass = [vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color)];
        // The copy of the picture must land before the pass loads the image.
        let dependency = [vk::SubpassDependency::default()
            .src_subpass(vk::SUBPASS_EXTERNAL)
            .dst_subpass(0)
            .src_stage_mask(vk::PipelineStageFlags::TRANSFER)
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
            .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE)];
        let info =
            vk::RenderPassCreateInfo::default().attachments(&attachment).subpasses(&subpass).dependencies(&dependency);
        // SAFETY: `info` borrows `attachment`, `subpass` (which borrows `color`) and `dependency`, locals alive
        // until the call returns; the device is the context's, alive while `ctx` is.
        let render_pass =
            unsafe { ctx.device.create_render_pass(&info, None) }.context("creating the overlay's render pass")?;
        let options =
            Options { in_flight_frames: 1, srgb_framebuffer: is_srgb(swapchain.format), ..Default::default() };
        let renderer = Renderer::with_default_allocator(
            &ctx.instance,
            ctx.physical_device,
            ctx.device.clone(),
            RenderMode::RenderPass(render_pass),
            options,
        );
        let mut pass = Self { render_pass, format: swapchain.format, framebuffers: vec![], renderer: None };
        match renderer {
            Ok(r) => pass.renderer = Some(r),
            Err(e) => {
                pass.destroy(ctx);
                return Err(anyhow!("creating the overlay's renderer: {e}"));
            }
        }
        pass.recreate_framebuffers(ctx, swapchain)?;
        Ok(pass)
    }

    /// Framebuffers for a (re-created) swapchain of the same format.
    pub(super) fn recreate_framebuffers(&mut self, ctx: &GpuContext, swapchain: &Swapchain) -> Result<()> {
        anyhow::ensure!(swapchain.format == self.format, "the swapchain changed format");
        self.destroy_framebuffers(ctx);
        for &view in &swapchain.views {
            let views = [view];
            let info = vk::FramebufferCreateInfo::default()
                .render_pass(self.render_pass)
                .attachments(&views)
                .width(swapchain.extent.width)
                .height(swapchain.extent.height)
                .layers(1);
            // SAFETY: `info` borrows `views` (alive to the end of this iteration) naming a live view of the
            // swapchain, whose extent it takes, and the render pass made for the swapchain's format (checked
            // above).
            self.framebuffers.push(
                unsafe { ctx.device.create_framebuffer(&info, None) }.context("creating an overlay framebuffer")?,
            );
        }
        Ok(())
    }

    /// Uploads the textures egui changed; before recording the frame that uses them.
    pub(super) fn update_textures(&mut self, ctx: &GpuContext, textures: &egui::TexturesDelta) -> Result<()> {
        let renderer = self.renderer.as_mut().expect("renderer lives until destroy");
        for (id, deltas) in &textures.set {
            for delta in deltas {
                renderer
                    .set_texture(ctx.queue, ctx.command_pool, *id, delta)
                    .map_err(|e| anyhow!("uploading an overlay texture: {e}"))?;
            }
        }
        Ok(())
    }

    /// Frees the textures egui let go of; after the frame that last used them has finished.
    pub(super) fn free_textures(&mut self, textures: &egui::TexturesDelta) -> Result<()> {
        let renderer = self.renderer.as_mut().expect("renderer lives until destroy");
        for id in &textures.free {
            renderer.free_texture(*id).map_err(|e| anyhow!("freeing an overlay texture: {e}"))?;
        }
        Ok(())
    }

    /// Records the pass over swapchain image `index` (in TRANSFER_DST_OPTIMAL; left PRESENT_SRC_KHR).
    pub(super) fn record(
        &mut self,
        device: &ash::Device,
        cb: vk::CommandBuffer,
        index: usize,
        extent: vk::Extent2D,
        draw: &OverlayDraw,
    ) -> Result<()> {
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(self.render_pass)
            .framebuffer(self.framebuffers[index])
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent });
        // SAFETY: `cb` is recording (Presenter::record), the framebuffer is this pass's for swapchain image `index`
        // and the render area is that swapchain's extent; `begin` is a local.
        unsafe { device.cmd_begin_render_pass(cb, &begin, vk::SubpassContents::INLINE) };
        let renderer = self.renderer.as_mut().expect("renderer lives until destroy");
        let drawn = renderer.cmd_draw(cb, extent, draw.pixels_per_point, draw.primitives);
        // SAFETY: ends the render pass begun above on the same recording `cb`, whatever cmd_draw returned.
        unsafe { device.cmd_end_render_pass(cb) };
        drawn.map_err(|e| anyhow!("recording the overlay: {e}"))
    }

    fn destroy_framebuffers(&mut self, ctx: &GpuContext) {
        for fb in self.framebuffers.drain(..) {
            // SAFETY: framebuffers are destroyed only with the device idle: by destroy() (after the device is idle)
            // or on re-creation, which Presenter::recreate begins by waiting for the device; each handle is drained
            // from the list as it goes.
            unsafe { ctx.device.destroy_framebuffer(fb, None) };
        }
    }

    /// After the device is idle.
    pub(super) fn destroy(mut self, ctx: &GpuContext) {
        self.destroy_framebuffers(ctx);
        drop(self.renderer.take());
        // SAFETY: as its doc says, destroy() runs with the device idle; the framebuffers and egui's renderer, which
        // use the render pass, are gone first, and `self` is consumed, so the pass is destroyed once.
        unsafe { ctx.device.destroy_render_pass(self.render_pass, None) };
    }
}
