//! Progressive rendering: uploads a scene, then adds samples in dispatches sized to take about
//! `GPU_DISPATCH_TARGET_S` each on a GPU, so a desktop GPU's watchdog never fires and progress
//! stays smooth, and `CPU_DISPATCH_TARGET_S` on a CPU device, which has no watchdog.
//! Every dispatch is checked: each pixel of its band must hold the target sample count afterwards.
//! On devices that end shader loops early (llvmpipe before Mesa 24, see shaders/loop_limit.glsl)
//! dispatches are also sized from the loop iterations the kernel counts, and a band cut short is
//! repeated in smaller steps, which gives the same sums bit for bit.

use super::acceleration::AccelerationStats;
use super::aov::{AovSet, AovSums};
use super::bindings::{BufferBinding, KernelBuffer};
use super::bvh_width::BvhWidth;
use super::features::SceneFeatures;
use super::frame::set_camera_params;
use super::group_order::GroupOrder;
use super::kernel_options::KernelOptions;
use super::kernel_setup::{scene_hash, Initial, KernelPlan, Kernels, CLEARED_STATS};
use super::layout::{FrameParams, GpuStats, PassParams, LOOP_CHECK_ITERATIONS};
use super::shadow_walk::ShadowWalk;
use super::variant::KernelChoice;
use super::walk_queue::WalkQueue;
use super::walk_records::WalkRecords;
use super::workgroup::Workgroup;
use crate::gpu::{Buffer, DeviceType, GpuContext, KernelStatistic, SceneStructure, Traversal};
use crate::image::{mean_image, RgbImage};
use crate::scene::{Camera, Scene};
use anyhow::Result;
use std::time::Instant;

/// Wall time one dispatch aims for on a GPU. Windows' GPU watchdog fires at 2 s.
const GPU_DISPATCH_TARGET_S: f64 = 0.2;
/// Wall time one dispatch aims for on a CPU device (lavapipe). Every dispatch ends in a tail, lanes
/// whose pixels are done idling beside those still on their last paths, and a thread whose share
/// of the workgroups is done idling beside the other; longer dispatches pay it less often. 1 s
/// against 0.2 s: the mesh scenes up to 1.3x on Mesa 25 and 1.4x on Mesa 22.3, the Cornell box
/// level (docs/benchmarks/history.md, 2026-12-01, `7a44715`). A time budget or an interrupt waits for the pass in
/// progress, so about this long at most.
const CPU_DISPATCH_TARGET_S: f64 = 1.0;

/// The wall time a dispatch aims for on a device of `kind`.
fn dispatch_target_for(kind: DeviceType) -> f64 {
    if kind == DeviceType::Cpu {
        CPU_DISPATCH_TARGET_S
    } else {
        GPU_DISPATCH_TARGET_S
    }
}

/// Upper bound on pixel-samples in one dispatch, so the 32-bit counters cannot wrap in practice.
const MAX_PIXEL_SAMPLES_PER_DISPATCH: u64 = 1 << 24;
/// Most samples one pixel can hold: the kernel keeps each pixel's count in a float, exact to 2^24.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 1 << 24;
/// Share of a device's loop limit that one invocation is planned to use; the rest is margin for
/// pixels costlier than any measured so far (a dispatch that exceeds it anyway is repeated).
const LOOP_LIMIT_SHARE: f64 = 0.5;

pub struct Renderer<'a> {
    ctx: &'a GpuContext,
    /// What a pass runs (always there until drop).
    kernels: Option<Kernels>,
    /// What the driver says of each compiled kernel (the wavefront's named by their stage).
    statistics: Vec<KernelStatistic>,
    /// What the kernel was compiled for.
    pub features: SceneFeatures,
    /// The walk queue the kernel was compiled with, if any (walk_queue.rs).
    pub walk_queue: Option<WalkQueue>,
    /// Whether the kernel's subgroups take their tiles from a counter (tile_taking.rs).
    pub take_tiles: bool,
    /// How the kernel reads the walk's nodes and triangles (walk_records.rs).
    pub walk_records: WalkRecords,
    /// The node format of the meshes' and shapes' BVHs the kernel walks (bvh_width.rs).
    pub bvh_width: BvhWidth,
    /// How a shadow ray's four-wide walk orders a node's children (shadow_walk.rs).
    pub shadow_walk: ShadowWalk,
    /// The kernel's workgroup shape (workgroup.rs).
    pub workgroup: Workgroup,
    /// How the kernel finds what rays hit: the device's choice (`GpuContext::traversal`), or the
    /// compute walk's code for a scene with no walk at all (a few shapes tested in turn).
    pub traversal: Traversal,
    /// The scene's acceleration structures, where the kernel traces with ray queries.
    structure: Option<SceneStructure>,
    /// Every buffer the kernel binds (the AOV sums only when the render has kernel AOVs).
    buffers: Vec<(KernelBuffer, Buffer)>,
    aovs: AovSet,
    width: u32,
    height: u32,
    seed: u32,
    /// Samples per pixel accumulated so far.
    pub samples_done: u32,
    /// Index of the first sample of this render's stream: sample `sample_offset + i` is the i-th
    /// accumulated, so renders with disjoint ranges add up to one render of their union.
    sample_offset: u32,
    /// BLAKE3 of everything uploaded that decides the image, the seed aside: see [`scene_hash`].
    pub scene_hash: String,
    pub rays_traced: u64,
    /// Samples whose radiance was NaN or infinite, dropped by the kernel (counted as black).
    pub nonfinite_samples: u64,
    /// Wall-clock seconds of the dispatches, submission and fences included.
    pub seconds: f64,
    /// Seconds the device itself spent on the dispatches, by its timestamps; `None` on a device
    /// whose queue records none.
    pub gpu_seconds: Option<f64>,
    pub geometry: GeometryReport,
    /// Estimated seconds per pixel-row-sample, refined after every dispatch.
    cost_per_row_sample: Option<f64>,
    /// See [`GpuContext::loop_limit`].
    loop_limit: Option<u32>,
    /// Most loop iterations one subgroup has run per sample so far (devices with a loop limit).
    loop_iterations_per_sample: f64,
    /// Samples per pixel of every dispatch when the caller fixed them, instead of sizing
    /// dispatches by time ([`Self::fix_samples_per_dispatch`]).
    fixed_samples_per_dispatch: Option<u32>,
    /// Most samples per pixel in one dispatch since the loop limit cut one short.
    samples_per_dispatch_after_repeat: u32,
    /// Whether dispatches are sized to stay within the loop limit (off only to test the repeat).
    plan_for_loop_limit: bool,
    /// Dispatches repeated in smaller steps because the device's loop limit cut them short.
    pub repeated_dispatches: u32,
    /// Wall time one dispatch aims for (the device's [`dispatch_target_for`] unless
    /// [`Self::set_dispatch_target`]).
    dispatch_target_s: f64,
    /// The frame parameters uploaded, kept so that [`Self::set_camera`] can change the camera alone.
    params: FrameParams,
    /// Bytes of scene data in each buffer of `buffers` that [`scene_hash`] covers (`None`: not
    /// covered), so that the hash can be recomputed from the device after a camera change.
    hashed_bytes: Vec<Option<u64>>,
    /// The pass whose bands [`Self::render_step`] is dispatching, between calls.
    pass_in_progress: Option<PassInProgress>,
    /// Order of the workgroups' rows (the device's unless [`Self::set_group_order`]).
    group_order: GroupOrder,
}

/// A pass cut into bands and dispatched a band per [`Renderer::render_step`]: rows before
/// `next_row` hold `target` samples per pixel, the rest `samples_done`.
#[derive(Clone, Copy, Debug)]
struct PassInProgress {
    target: u32,
    band: u32,
    next_row: u32,
}

/// What was uploaded, for logs and `caustica bench`.
#[derive(Clone, Debug)]
pub struct GeometryReport {
    pub acceleration: AccelerationStats,
    /// Geometry and BVH bytes (nodes, instances, primitives, triangles, vertex attributes).
    pub geometry_bytes: u64,
    pub texture_bytes: u64,
    pub texture_bytes_requested: u64,
    pub lights: usize,
    /// Everything the scene occupies on the device, the image excluded.
    pub gpu_bytes: u64,
    /// Arrays too large for one storage binding of this device, with the bindings each spans.
    pub split_arrays: Vec<(&'static str, u32)>,
    /// Bytes of the acceleration structures ray queries trace (ray_query_scene.rs), beside
    /// `gpu_bytes`; 0 where the kernel walks its own BVH.
    pub acceleration_structure_bytes: u64,
    /// The light tree (light_tree.rs), where the scene picks its lights by one.
    pub light_tree: Option<LightTreeReport>,
}

/// The light tree's size and build time, for `bench`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightTreeReport {
    pub nodes: usize,
    /// Its nodes and its index (light_tree_index.rs) on the device.
    pub bytes: u64,
    pub build_seconds: f64,
}

impl<'a> Renderer<'a> {
    /// A renderer of the beauty alone.
    pub fn new(ctx: &'a GpuContext, scene: &Scene, seed: u32) -> Result<Self> {
        Self::with_aovs(ctx, scene, seed, AovSet::default())
    }

    /// A renderer that also produces `aovs`. The beauty is the same bit for bit: the features
    /// draw no random numbers.
    pub fn with_aovs(ctx: &'a GpuContext, scene: &Scene, seed: u32, aovs: AovSet) -> Result<Self> {
        Self::with_kernel(ctx, scene, seed, aovs, KernelChoice::ForScene)
    }

    /// A renderer whose kernel is compiled as `choice` says, and runs as the `CAUSTICA_*`
    /// environment variables ask (kernel_options.rs). The image is the same bit for bit either way
    /// (tests/specialization.rs); only the speed differs.
    pub fn with_kernel(
        ctx: &'a GpuContext,
        scene: &Scene,
        seed: u32,
        aovs: AovSet,
        choice: KernelChoice,
    ) -> Result<Self> {
        Self::with_options(ctx, scene, seed, aovs, choice, &KernelOptions::from_env()?)
    }

    /// A renderer whose kernel is compiled as `choice` says and runs as `options` ask, over the
    /// device's defaults (kernel_options.rs): planned, its buffers uploaded, bound and compiled
    /// (kernel_setup.rs).
    pub fn with_options(
        ctx: &'a GpuContext,
        scene: &Scene,
        seed: u32,
        aovs: AovSet,
        choice: KernelChoice,
        options: &KernelOptions,
    ) -> Result<Self> {
        let plan = KernelPlan::new(ctx, scene, seed, aovs, choice, options)?;
        let buffers = plan.upload(ctx)?;
        let structure = plan.build_structure(ctx, scene)?;
        let descriptors = plan.bind(&buffers, structure.as_ref());
        let (kernels, statistics) = plan.compile(ctx, &descriptors)?;
        let KernelPlan { data, params, loop_limit, choices, scene_hash, hashed_bytes, split_arrays, variant, .. } =
            plan;
        let acceleration_structure_bytes = structure.as_ref().map_or(0, SceneStructure::bytes);
        let (width, height) = (scene.film.width, scene.film.height);
        Ok(Self {
            ctx,
            kernels: Some(kernels),
            statistics,
            features: variant.features,
            walk_queue: choices.walk_queue,
            take_tiles: choices.take_tiles,
            walk_records: choices.walk_records,
            bvh_width: choices.bvh_width,
            shadow_walk: choices.shadow_walk,
            workgroup: choices.workgroup,
            traversal: variant.traversal,
            structure,
            buffers,
            aovs,
            width,
            height,
            seed,
            samples_done: 0,
            sample_offset: 0,
            scene_hash,
            rays_traced: 0,
            nonfinite_samples: 0,
            seconds: 0.0,
            gpu_seconds: ctx.timestamp_period_ns.map(|_| 0.0),
            geometry: GeometryReport {
                acceleration: data.acceleration.stats.clone(),
                geometry_bytes: data.acceleration.gpu_bytes(),
                texture_bytes: data.texture_bytes(),
                texture_bytes_requested: data.texture_bytes_requested,
                lights: data.lights.len(),
                gpu_bytes: data.gpu_bytes(),
                split_arrays,
                acceleration_structure_bytes,
                light_tree: data.light_tree.as_ref().map(|t| LightTreeReport {
                    nodes: t.tree.nodes.len(),
                    bytes: t.gpu_bytes(),
                    build_seconds: t.tree.build_seconds,
                }),
            },
            cost_per_row_sample: None,
            loop_limit,
            loop_iterations_per_sample: 0.0,
            fixed_samples_per_dispatch: None,
            samples_per_dispatch_after_repeat: u32::MAX,
            plan_for_loop_limit: true,
            repeated_dispatches: 0,
            dispatch_target_s: dispatch_target_for(ctx.info.kind),
            params,
            hashed_bytes,
            pass_in_progress: None,
            group_order: GroupOrder::for_device(ctx.info.kind),
        })
    }

    /// Dispatches `samples` samples per pixel over the whole image at a time (at least 1; fewer
    /// where the device's loop limit requires it) instead of sizing dispatches to take the
    /// device's dispatch target. The image does not depend on it: renders split into any
    /// dispatches agree bit for bit.
    pub fn fix_samples_per_dispatch(&mut self, samples: u32) {
        self.fixed_samples_per_dispatch = Some(samples.max(1));
    }

    /// Takes the workgroups' rows in `order` instead of the device's choice (the image is the same
    /// bit for bit; `caustica bench --group-order` measures what it changes).
    pub fn set_group_order(&mut self, order: GroupOrder) {
        self.group_order = order;
    }

    /// The order the workgroups' rows are taken in.
    pub fn group_order(&self) -> GroupOrder {
        self.group_order
    }

    /// Sizes dispatches as if the device had no loop limit, so that the limit cuts them short and
    /// they are repeated: for tests of that repeat on devices with a limit.
    pub fn ignore_loop_limit_in_planning(&mut self) {
        self.plan_for_loop_limit = false;
    }

    /// Whether the render runs the wavefront's kernels rather than the megakernel (wavefront.rs).
    pub fn runs_wavefront(&self) -> bool {
        matches!(self.kernels, Some(Kernels::Wavefront(_)))
    }

    /// What the driver says of the compiled kernels (registers, spills; see
    /// [`crate::gpu::KernelStatistic`]); empty where it says nothing.
    pub fn kernel_statistics(&self) -> &[KernelStatistic] {
        &self.statistics
    }

    /// The device's loop limit (see [`GpuContext::loop_limit`]).
    pub fn loop_limit(&self) -> Option<u32> {
        self.loop_limit
    }

    /// Samples per pixel this render can still add: its stream ends at sample index `u32::MAX`,
    /// and a pixel holds at most [`MAX_SAMPLES_PER_PIXEL`].
    pub fn samples_left(&self) -> u32 {
        MAX_SAMPLES_PER_PIXEL
            .saturating_sub(self.samples_done)
            .min((u32::MAX - self.sample_offset).saturating_sub(self.samples_done))
    }

    /// Starts this render's sample stream at `first_sample` instead of 0 (farm renders: one range
    /// per machine). Only before the first sample.
    pub fn set_sample_offset(&mut self, first_sample: u32) {
        assert_eq!(self.samples_done, 0, "the sample offset is set before rendering");
        self.sample_offset = first_sample;
    }

    pub fn sample_offset(&self) -> u32 {
        self.sample_offset
    }

    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// The AOVs this render produces.
    pub fn aovs(&self) -> AovSet {
        self.aovs
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Takes over `accumulation` (as from [`Self::accumulation`]) holding the first `samples` samples
    /// of this render's stream, so that rendering on adds the samples that follow them: the result
    /// is bit for bit that of an uninterrupted render.
    pub fn restore(&mut self, accumulation: &[[f32; 4]], samples: u32) -> Result<()> {
        anyhow::ensure!(
            samples <= MAX_SAMPLES_PER_PIXEL,
            "the accumulation holds {samples} samples per pixel; a render holds at most {MAX_SAMPLES_PER_PIXEL}"
        );
        anyhow::ensure!(
            accumulation.iter().all(|a| a[3] == samples as f32),
            "the accumulation's per-pixel sample counts are not all {samples}"
        );
        anyhow::ensure!(
            accumulation.len() == self.width as usize * self.height as usize,
            "the accumulation has {} pixels, the image {}x{}",
            accumulation.len(),
            self.width,
            self.height
        );
        self.buffer(KernelBuffer::Accum)
            .expect("every kernel binds the accumulation")
            .upload(self.ctx, bytemuck::cast_slice(accumulation))?;
        self.samples_done = samples;
        Ok(())
    }

    /// Takes over AOV sums (as from [`Self::aov_sums`]) of the samples given to [`Self::restore`].
    pub fn restore_aovs(&mut self, sums: &AovSums) -> Result<()> {
        let (Some(albedo_depth), Some(normal_hits)) =
            (self.buffer(KernelBuffer::AovAlbedoDepth), self.buffer(KernelBuffer::AovNormalHits))
        else {
            anyhow::bail!("this render has no albedo, normal or depth AOVs to restore");
        };
        let pixels = self.width as usize * self.height as usize;
        anyhow::ensure!(
            sums.pixels() == pixels,
            "the AOV sums have {} pixels, the image {}x{}",
            sums.pixels(),
            self.width,
            self.height
        );
        albedo_depth.upload(self.ctx, bytemuck::cast_slice(&sums.albedo_depth))?;
        normal_hits.upload(self.ctx, bytemuck::cast_slice(&sums.normal_hits))?;
        Ok(())
    }

    /// Adds `spp` samples per pixel, calling `progress(samples_done)` after each full pass.
    pub fn render(&mut self, spp: u32, mut progress: impl FnMut(u32)) -> Result<()> {
        self.render_while(spp, |done| {
            progress(done);
            true
        })
    }

    /// Adds up to `spp` samples per pixel, calling `keep_going(samples_done)` after each full pass and
    /// stopping early when it says no. Ends at [`Self::samples_left`].
    pub fn render_while(&mut self, spp: u32, mut keep_going: impl FnMut(u32) -> bool) -> Result<()> {
        let target = self.samples_done + spp.min(self.samples_left());
        while self.samples_done < target {
            let (samples, band) = self.plan_pass(target - self.samples_done);
            let pass_target = self.samples_done + samples;
            let mut row = 0;
            while row < self.height {
                let rows = band.min(self.height - row);
                self.fill_band(row, rows, pass_target)?;
                row += rows;
            }
            self.samples_done = pass_target;
            if !keep_going(self.samples_done) {
                break;
            }
        }
        self.ctx.check_validation()
    }

    /// Adds at most one dispatch towards `spp` samples per pixel in all (a band of a pass, or a
    /// whole pass where one dispatch holds it), for callers that must keep control between
    /// dispatches, such as an interactive viewer. Returns whether a pass was completed, after
    /// which every pixel holds [`Self::samples_done`] samples.
    pub fn render_step(&mut self, spp: u32) -> Result<bool> {
        let pass = match self.pass_in_progress {
            Some(pass) => pass,
            None => {
                let target = spp.min(self.samples_done + self.samples_left());
                if self.samples_done >= target {
                    return Ok(false);
                }
                let (samples, band) = self.plan_pass(target - self.samples_done);
                PassInProgress { target: self.samples_done + samples, band, next_row: 0 }
            }
        };
        let rows = pass.band.min(self.height - pass.next_row);
        self.fill_band(pass.next_row, rows, pass.target)?;
        let next_row = pass.next_row + rows;
        let completed = next_row == self.height;
        self.pass_in_progress = (!completed).then_some(PassInProgress { next_row, ..pass });
        if completed {
            self.samples_done = pass.target;
        }
        self.ctx.check_validation()?;
        Ok(completed)
    }

    /// Dispatches the rest of a pass [`Self::render_step`] began, so that every pixel holds the same
    /// number of samples (as [`Self::accumulation`] must for a snapshot).
    pub fn finish_pass(&mut self) -> Result<()> {
        while self.pass_in_progress.is_some() {
            self.render_step(u32::MAX)?;
        }
        Ok(())
    }

    /// The samples per pixel that the pixels of the pass in progress reach (`None` between
    /// passes): while a pass is cut into bands, pixels hold either this or [`Self::samples_done`].
    pub fn pass_target(&self) -> Option<u32> {
        self.pass_in_progress.map(|p| p.target)
    }

    /// Sizes dispatches to take about `seconds` of wall time instead of the device's default: an
    /// interactive viewer needs shorter ones to keep drawing its window.
    pub fn set_dispatch_target(&mut self, seconds: f64) {
        self.dispatch_target_s = seconds;
    }

    /// Moves the camera and starts the image over: the accumulation (and AOV sums) are cleared and
    /// the sample stream restarts at its offset. The scene stays on the device, and the speed
    /// measurements that size dispatches are kept. The scene hash depends on the camera: it reads
    /// empty until [`Self::refresh_scene_hash`].
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        set_camera_params(&mut self.params, camera);
        let params = self.params;
        self.buffer(KernelBuffer::Frame)
            .expect("every kernel binds the frame parameters")
            .upload(self.ctx, bytemuck::bytes_of(&params))?;
        let zeroes = vec![0u8; self.width as usize * self.height as usize * 16];
        for which in [KernelBuffer::Accum, KernelBuffer::AovAlbedoDepth, KernelBuffer::AovNormalHits] {
            if let Some(buffer) = self.buffer(which) {
                buffer.upload(self.ctx, &zeroes)?;
            }
        }
        self.samples_done = 0;
        self.pass_in_progress = None;
        self.rays_traced = 0;
        self.nonfinite_samples = 0;
        self.seconds = 0.0;
        self.gpu_seconds = self.gpu_seconds.map(|_| 0.0);
        self.scene_hash.clear();
        Ok(())
    }

    /// Recomputes [`Self::scene_hash`] for the current camera from the scene data on the device
    /// (read back, as the host keeps no copy): after [`Self::set_camera`], before a snapshot.
    pub fn refresh_scene_hash(&mut self) -> Result<()> {
        if !self.scene_hash.is_empty() {
            return Ok(());
        }
        let mut contents = Vec::new();
        for ((which, buffer), hashed) in self.buffers.iter().zip(&self.hashed_bytes) {
            let binding = which.entry();
            contents.push(match *hashed {
                Some(0) => (binding, vec![]),
                Some(bytes) => (binding, buffer.download(self.ctx, bytes)?),
                None => continue,
            });
        }
        let contents: Vec<(BufferBinding, Initial)> =
            contents.iter().map(|(b, bytes)| (**b, Initial::Data(bytes))).collect();
        self.scene_hash = scene_hash(&FrameParams { seed: 0, ..self.params }, &contents);
        Ok(())
    }

    /// The buffers a display of the image reads: the accumulation (per pixel: radiance sum and
    /// sample count), and the AOV sums (albedo and depth, normal and hits) where the kernel keeps them.
    pub fn image_buffers(&self) -> (&Buffer, Option<(&Buffer, &Buffer)>) {
        let accumulation = self.buffer(KernelBuffer::Accum).expect("every kernel binds the accumulation");
        (accumulation, self.buffer(KernelBuffer::AovAlbedoDepth).zip(self.buffer(KernelBuffer::AovNormalHits)))
    }

    /// Samples per pixel and rows per dispatch for the next pass.
    fn plan_pass(&self, remaining: u32) -> (u32, u32) {
        if let Some(samples) = self.fixed_samples_per_dispatch {
            return (samples.min(self.loop_safe_samples()).min(remaining), self.height);
        }
        let Some(cost) = self.cost_per_row_sample else {
            // First dispatch: one sample over a band small enough for any device.
            return (1, self.height.min(32));
        };
        let budget_row_samples = (self.dispatch_target_s / cost.max(1e-12)).max(1.0);
        let max_samples = (MAX_PIXEL_SAMPLES_PER_DISPATCH / (self.width as u64 * self.height as u64)).max(1) as f64;
        if budget_row_samples >= self.height as f64 {
            let samples = (budget_row_samples / self.height as f64)
                .min(max_samples)
                .min(self.loop_safe_samples() as f64)
                .min(remaining as f64)
                .max(1.0);
            (samples as u32, self.height)
        } else {
            // Bands of about equal height, in whole workgroup rows: a budget of 104 of 120 rows
            // would otherwise leave a last band of 16 rows, a dispatch that keeps few of the
            // device's threads busy (Mesa 22.3's lavapipe lost about a tenth of its rate so).
            let bands = (self.height as f64 / budget_row_samples).ceil() as u32;
            (1, self.height.div_ceil(bands).next_multiple_of(self.workgroup.height).min(self.height))
        }
    }

    /// Most samples per pixel one dispatch may add: on a device with a loop limit, what keeps the
    /// costliest subgroup measured so far within LOOP_LIMIT_SHARE of it (one sample until a
    /// dispatch has been measured), and no more than since a dispatch was last cut short.
    fn loop_safe_samples(&self) -> u32 {
        let planned = match self.loop_limit {
            Some(_) if !self.plan_for_loop_limit => u32::MAX,
            Some(_) if self.loop_iterations_per_sample == 0.0 => 1,
            Some(limit) => (limit as f64 * LOOP_LIMIT_SHARE / self.loop_iterations_per_sample).max(1.0) as u32,
            None => u32::MAX,
        };
        planned.min(self.samples_per_dispatch_after_repeat)
    }

    /// Brings every pixel of rows `row..row + rows` from `samples_done` up to `target` samples and
    /// checks that it did. Where invocations were cut short (the device's loop limit), the band is
    /// repeated in halved steps, each pixel continuing from the count it holds, and later
    /// dispatches are planned no larger; a single sample that cannot complete is an error.
    fn fill_band(&mut self, row: u32, rows: u32, target: u32) -> Result<()> {
        let pixels = self.width * rows;
        let mut reached = self.samples_done;
        let mut step = target - reached;
        let mut samples_added = 0u64;
        while reached < target {
            let next = (reached + step).min(target);
            let stats = self.dispatch(row, rows, next, next - reached)?;
            samples_added += stats.samples_added as u64;
            if stats.pixels_complete == pixels {
                reached = next;
                continue;
            }
            let missing = pixels - stats.pixels_complete;
            let why = match self.loop_limit {
                Some(limit) => format!("its loops stop after {limit} iterations in total"),
                None => "it reported no loop limit".to_owned(),
            };
            anyhow::ensure!(
                step > 1,
                "{}: {missing} of {pixels} pixels in rows {row}..{} could not complete one sample: the device cut their shader invocations short ({why}) after {} loop iterations; render on another device or a newer Mesa",
                self.ctx.info.name,
                row + rows,
                stats.max_loop_iterations
            );
            step = (step / 2).max(1);
            self.samples_per_dispatch_after_repeat = self.samples_per_dispatch_after_repeat.min(step);
            self.repeated_dispatches += 1;
        }
        let expected = pixels as u64 * (target - self.samples_done) as u64;
        anyhow::ensure!(
            samples_added == expected,
            "{}: rows {row}..{} received {samples_added} samples where {expected} were dispatched",
            self.ctx.info.name,
            row + rows
        );
        Ok(())
    }

    /// One dispatch: rows `row..row + rows` up to `target` samples per pixel, `samples` of them new
    /// for the pixels furthest behind. Returns the kernel's counters.
    fn dispatch(&mut self, row: u32, rows: u32, target: u32, samples: u32) -> Result<GpuStats> {
        self.buffer_mut(KernelBuffer::Stats)
            .expect("every kernel binds the statistics")
            .write(bytemuck::bytes_of(&CLEARED_STATS))?;
        let groups = [self.width.div_ceil(self.workgroup.width), rows.div_ceil(self.workgroup.height), 1];
        let pass = PassParams {
            stream_offset: self.sample_offset,
            target_samples: target,
            row_offset: row,
            row_count: rows,
            loop_check_iterations: LOOP_CHECK_ITERATIONS,
            group_row_stripes: self.group_order.stripes(groups[1]),
            wavefront_round: 0,
        };
        let start = Instant::now();
        let device_seconds = match self.kernels.as_ref().expect("kernels live until drop") {
            Kernels::Megakernel(kernel) => kernel.dispatch_timed(self.ctx, bytemuck::bytes_of(&pass), groups)?,
            Kernels::Wavefront(wavefront) => {
                // Each round takes every path at least one vertex or shadow ray on, and a sample
                // has at most max_bounces vertices, each with one shadow ray: a bound with room.
                let max_rounds = (samples as u64 + 1) * 2 * (self.params.max_bounces as u64 + 2);
                wavefront.run(
                    self.ctx,
                    groups,
                    max_rounds,
                    |round| bytemuck::bytes_of(&PassParams { wavefront_round: round, ..pass }).to_vec(),
                    || self.read_stats(),
                )?
            }
        };
        let elapsed = start.elapsed().as_secs_f64();
        self.seconds += elapsed;
        self.gpu_seconds = self.gpu_seconds.zip(device_seconds).map(|(sum, s)| sum + s);
        let stats = self.read_stats()?;
        self.rays_traced += stats.ray_count as u64;
        self.nonfinite_samples += stats.nonfinite_samples as u64;
        self.loop_iterations_per_sample =
            self.loop_iterations_per_sample.max(stats.max_loop_iterations as f64 / samples as f64);
        let cost = elapsed / (rows as f64 * samples as f64);
        // Smooth, but follow quickly: scenes differ in cost across the image.
        self.cost_per_row_sample = Some(match self.cost_per_row_sample {
            Some(c) => 0.5 * c + 0.5 * cost,
            None => cost,
        });
        Ok(stats)
    }

    /// The kernels' counters as the last submission left them.
    fn read_stats(&self) -> Result<GpuStats> {
        let stats = self.buffer(KernelBuffer::Stats).expect("every kernel binds the statistics");
        Ok(bytemuck::pod_read_unaligned(&stats.read()?[..std::mem::size_of::<GpuStats>()]))
    }

    /// Raw accumulation: per pixel (sum of radiance, sample count), top row first.
    pub fn accumulation(&self) -> Result<Vec<[f32; 4]>> {
        let accum = self.buffer(KernelBuffer::Accum).expect("every kernel binds the accumulation");
        let bytes = accum.download(self.ctx, self.width as u64 * self.height as u64 * 16)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Raw AOV sums (`None` without albedo, normal or depth AOVs), top row first.
    pub fn aov_sums(&self) -> Result<Option<AovSums>> {
        let (Some(albedo_depth), Some(normal_hits)) =
            (self.buffer(KernelBuffer::AovAlbedoDepth), self.buffer(KernelBuffer::AovNormalHits))
        else {
            return Ok(None);
        };
        let bytes = self.width as u64 * self.height as u64 * 16;
        let read =
            |b: &Buffer| -> Result<Vec<[f32; 4]>> { Ok(bytemuck::pod_collect_to_vec(&b.download(self.ctx, bytes)?)) };
        Ok(Some(AovSums { albedo_depth: read(albedo_depth)?, normal_hits: read(normal_hits)? }))
    }

    /// The buffer the kernel binds as `which`, if this render's kernel binds it.
    fn buffer(&self, which: KernelBuffer) -> Option<&Buffer> {
        self.buffers.iter().find(|(b, _)| *b == which).map(|(_, buffer)| buffer)
    }

    fn buffer_mut(&mut self, which: KernelBuffer) -> Option<&mut Buffer> {
        self.buffers.iter_mut().find(|(b, _)| *b == which).map(|(_, buffer)| buffer)
    }

    /// The mean radiance per pixel so far.
    pub fn image(&self) -> Result<RgbImage> {
        Ok(mean_image(self.width, self.height, &self.accumulation()?))
    }
}

impl Drop for Renderer<'_> {
    fn drop(&mut self) {
        match self.kernels.take() {
            Some(Kernels::Megakernel(k)) => k.destroy(self.ctx),
            Some(Kernels::Wavefront(w)) => w.destroy(self.ctx),
            None => {}
        }
        for (_, b) in self.buffers.drain(..) {
            b.destroy(self.ctx);
        }
        if let Some(structure) = self.structure.take() {
            structure.destroy(self.ctx);
        }
    }
}
