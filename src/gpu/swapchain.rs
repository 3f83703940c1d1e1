//! The window's swapchain: its images, their views, and the format the viewer writes bytes in.

use super::context::GpuContext;
use anyhow::{anyhow, Context as _, Result};
use ash::vk;

/// Byte order of a swapchain pixel in memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    Rgba,
    Bgra,
}

/// 8-bit formats the viewer can fill by copying bytes, most preferred first. UNORM formats take
/// the sRGB-encoded bytes as they are, which is what the display expects of the sRGB colour space;
/// the _SRGB twins store the same bytes (a copy converts nothing), so they do too.
const FORMATS: [(vk::Format, ChannelOrder); 4] = [
    (vk::Format::B8G8R8A8_UNORM, ChannelOrder::Bgra),
    (vk::Format::R8G8B8A8_UNORM, ChannelOrder::Rgba),
    (vk::Format::B8G8R8A8_SRGB, ChannelOrder::Bgra),
    (vk::Format::R8G8B8A8_SRGB, ChannelOrder::Rgba),
];

pub(super) struct Swapchain {
    pub(super) handle: vk::SwapchainKHR,
    pub(super) images: Vec<vk::Image>,
    pub(super) views: Vec<vk::ImageView>,
    pub(super) format: vk::Format,
    pub(super) order: ChannelOrder,
    pub(super) extent: vk::Extent2D,
    /// Whether its images can be copied from (the screenshot reads the presented image back).
    pub(super) readable: bool,
}

impl Swapchain {
    /// A swapchain of about `size` pixels (the surface may insist on its own extent); `old`, if
    /// any, is handed over to the new one and must be destroyed by the caller afterwards. `None`
    /// while the surface has no area (a minimized window).
    pub(super) fn new(ctx: &GpuContext, size: [u32; 2], old: vk::SwapchainKHR) -> Result<Option<Self>> {
        let p = ctx.presentation.as_ref().ok_or_else(|| anyhow!("this GPU context was not made for a window"))?;
        let (pd, surface) = (ctx.physical_device, p.surface);
        // SAFETY: `pd` is the context's device, chosen among those that can present to `surface`
        // (GpuContext::for_window), and the surface is alive as long as the context; the queries fill what they
        // return.
        let caps = unsafe { p.surface_loader.get_physical_device_surface_capabilities(pd, surface) }
            .context("the window surface's capabilities")?;
        let formats = unsafe { p.surface_loader.get_physical_device_surface_formats(pd, surface) }
            .context("the window surface's formats")?;
        // SAFETY: the same device and surface as the two queries above.
        let modes = unsafe { p.surface_loader.get_physical_device_surface_present_modes(pd, surface) }
            .context("the window surface's present modes")?;
        let (format, order) = FORMATS
            .iter()
            .copied()
            .find(|(f, _)| formats.iter().any(|s| s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR))
            .ok_or_else(|| {
                anyhow!(
                    "the window offers no 8-bit RGBA or BGRA format (it offers {:?})",
                    formats.iter().map(|f| f.format).collect::<Vec<_>>()
                )
            })?;
        // A surface whose current extent is u32::MAX lets the swapchain choose.
        let extent = if caps.current_extent.width == u32::MAX {
            vk::Extent2D {
                width: size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        } else {
            caps.current_extent
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        // Mailbox never blocks the render loop on the display's refresh and never tears; FIFO is
        // what every device offers.
        let mode = if modes.contains(&vk::PresentModeKHR::MAILBOX) {
            vk::PresentModeKHR::MAILBOX
        } else {
            vk::PresentModeKHR::FIFO
        };
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let mut image_count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            image_count = image_count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface)
            .min_image_count(image_count)
            .image_format(format)
            .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: `info` has no borrowed arrays (one queue family, EXCLUSIVE); its format, colour space, extent,
        // image count and usage come from what the surface reported above, and `old` is the caller's live swapchain
        // or null, which the caller destroys only after this call.
        let handle = unsafe { p.swapchain_loader.create_swapchain(&info, None) }.context("creating the swapchain")?;
        // SAFETY: `handle` was just created by this loader.
        let images = unsafe { p.swapchain_loader.get_swapchain_images(handle) }?;
        let mut chain = Self { handle, images, views: vec![], format, order, extent, readable };
        for &image in &chain.images {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(COLOR_RANGE);
            // SAFETY: `view_info` names an image of the swapchain just created, with its own format and its one
            // level and layer.
            match unsafe { ctx.device.create_image_view(&view_info, None) } {
                Ok(view) => chain.views.push(view),
                Err(e) => {
                    chain.destroy(ctx);
                    return Err(anyhow!("creating a swapchain image view: {e}"));
                }
            }
        }
        Ok(Some(chain))
    }

    pub(super) fn destroy(self, ctx: &GpuContext) {
        // SAFETY: the callers destroy a swapchain with the device idle (Presenter::recreate and destroy wait for it
        // first, and Swapchain::new's own error path has submitted nothing); views go before the swapchain that
        // owns their images, and `self` is consumed, so each handle is destroyed once.
        unsafe {
            for view in self.views {
                ctx.device.destroy_image_view(view, None);
            }
            if let Some(p) = &ctx.presentation {
                p.swapchain_loader.destroy_swapchain(self.handle, None);
            }
        }
    }
}

/// The one mip level and layer of a swapchain image.
pub(super) const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};
