//! The viewer's picture on the GPU: shaders/display.comp over a renderer's accumulation (or its
//! AOV sums), with the 8-bit code tables of PNG output (see src/image/display_codes.rs), so that
//! the window shows exactly what `render -o FILE.png` writes.

use crate::gpu::{compile_compute, Binding, Buffer, BufferKind, ChannelOrder, ComputeKernel, GpuContext, Picture};
use crate::image::display_codes::{code_thresholds, CODES};
use crate::image::Tonemap;
use crate::render::Renderer;
use anyhow::{Context as _, Result};
use bytemuck::{Pod, Zeroable};

/// What the window shows (keys 1 to 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Beauty,
    Albedo,
    Normal,
    Depth,
}

impl View {
    pub fn name(self) -> &'static str {
        match self {
            View::Beauty => "beauty",
            View::Albedo => "albedo",
            View::Normal => "normal",
            View::Depth => "depth",
        }
    }

    /// Whether the kernel must keep AOV sums to show it.
    pub fn needs_aovs(self) -> bool {
        self != View::Beauty
    }
}

/// How the picture is made from the accumulation: PNG output's settings and the view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplaySettings {
    pub exposure: f32,
    pub tonemap: Tonemap,
    pub view: View,
    /// Distance shown black in the depth view.
    pub depth_far: f32,
}

/// `DisplayParams` of display.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DisplayParams {
    width: u32,
    height: u32,
    count_low: f32,
    count_high: f32,
    view: u32,
    bgra: u32,
    depth_far: f32,
    unused: u32,
}

const WORKGROUP: u32 = 8;

/// display.comp compiled; once per viewer, shared by every [`Display`].
pub fn display_spirv() -> Result<Vec<u32>> {
    compile_compute(include_str!("../../shaders/display.comp")).context("compiling shaders/display.comp")
}

/// The display kernel bound to one renderer's buffers (made anew with each renderer).
pub struct Display {
    kernel: ComputeKernel,
    /// Two tables of [`CODES`] thresholds: for pixels holding `tables_for.0` samples, then `.1`.
    thresholds: Buffer,
    pixels: Buffer,
    size: [u32; 2],
    /// (count low, count high, exposure, tonemap) the tables in `thresholds` are for.
    tables_for: Option<(f32, f32, f32, Tonemap)>,
    params: DisplayParams,
}

impl Display {
    pub fn new(ctx: &GpuContext, spirv: &[u32], renderer: &Renderer) -> Result<Self> {
        let (width, height) = renderer.size();
        let thresholds = Buffer::with_data(ctx, "display code tables", BufferKind::HostStorage, &[0u8; 2 * CODES * 4])?;
        let pixels = Buffer::with_data(
            ctx,
            "display pixels",
            BufferKind::Storage,
            &vec![0u8; width as usize * height as usize * 4],
        )?;
        let (accumulation, aovs) = renderer.image_buffers();
        // Without AOV sums the AOV bindings see the accumulation; the views that read them are
        // only chosen with a renderer that keeps them.
        let (albedo_depth, normal_hits) = aovs.unwrap_or((accumulation, accumulation));
        let bindings = [
            Binding::whole(0, accumulation),
            Binding::whole(1, albedo_depth),
            Binding::whole(2, normal_hits),
            Binding::whole(3, &thresholds),
            Binding::whole(4, &pixels),
        ];
        let kernel = ComputeKernel::new(ctx, spirv, &bindings, std::mem::size_of::<DisplayParams>() as u32)?;
        Ok(Self {
            kernel,
            thresholds,
            pixels,
            size: [width, height],
            tables_for: None,
            params: DisplayParams::zeroed(),
        })
    }

    /// The picture of `renderer`'s image now, for the presenter: `order` is the swapchain's.
    pub fn picture(
        &mut self,
        renderer: &Renderer,
        settings: &DisplaySettings,
        order: ChannelOrder,
    ) -> Result<Picture<'_>> {
        let low = renderer.samples_done as f32;
        let high = renderer.pass_target().map_or(low, |t| t as f32);
        let wanted = (low, high, settings.exposure, settings.tonemap);
        if settings.view == View::Beauty && self.tables_for != Some(wanted) {
            let mut tables = code_thresholds(low, settings.exposure, settings.tonemap).to_vec();
            tables.extend(code_thresholds(high, settings.exposure, settings.tonemap));
            self.thresholds.write(bytemuck::cast_slice(&tables))?;
            self.tables_for = Some(wanted);
        }
        let view = match settings.view {
            View::Beauty => 0,
            View::Albedo => 1,
            View::Normal => 2,
            View::Depth => 3,
        };
        let [width, height] = self.size;
        self.params = DisplayParams {
            width,
            height,
            count_low: low,
            count_high: high,
            view,
            bgra: u32::from(order == ChannelOrder::Bgra),
            depth_far: settings.depth_far,
            unused: 0,
        };
        Ok(Picture {
            kernel: &self.kernel,
            push: bytemuck::bytes_of(&self.params),
            groups: [width.div_ceil(WORKGROUP), height.div_ceil(WORKGROUP), 1],
            pixels: &self.pixels,
            size: self.size,
        })
    }

    /// After the device has finished with it.
    pub fn destroy(self, ctx: &GpuContext) {
        self.kernel.destroy(ctx);
        self.thresholds.destroy(ctx);
        self.pixels.destroy(ctx);
    }
}
