//! Throughput measurement: how many samples and rays per second one device renders a scene at
//! (`caustica bench SCENE`), and the same for every checked-in scene in one run (`bench --suite`),
//! so that a kernel change can be judged by one table before and after. Both go through
//! [`measure`], so a single scene and a suite row are measured the same way.
//!
//! `suite` says which scenes the suite runs and at what size; `report` prints measurements as text
//! and JSON.

mod denoise_timing;
mod report;
mod suite;

pub use denoise_timing::{time_denoise, DenoiseTiming};
pub use report::{print_left_out, print_measurement, print_suite, suite_json, SUITE_COLUMNS};
pub use suite::{run_suite, suite_entries, FilmOverrides, SuiteEntry, SuiteOutcome, SuiteSize};

use crate::farm::per_second;
use crate::gpu::{DeviceInfo, GpuContext, KernelStatistic, Traversal};
use crate::process_time::cpu_seconds;
use crate::render::{
    AovSet, BvhWidth, GeometryReport, GroupOrder, KernelChoice, KernelOptions, Renderer, SceneFeatures, ShadowWalk,
    WalkQueue, WalkRecords, Workgroup,
};
use crate::scene::Scene;
use anyhow::Result;
use serde_json::{json, Value};
use std::time::Instant;

/// How the kernel measured is compiled and dispatched: the A/B switches of `caustica bench`.
#[derive(Clone, Debug, Default)]
pub struct KernelSetup {
    pub choice: KernelChoice,
    /// The order of the workgroups' rows; `None`: the device's own ([`GroupOrder::for_device`]).
    pub group_order: Option<GroupOrder>,
    /// The kernel options over the device's defaults (`--kernel-option`, render/kernel_options.rs).
    pub options: KernelOptions,
}

/// Wall time the warm-up renders for at least, before the timed samples: a GPU idles at a
/// fraction of its clock (an H200 at 345 MHz against 1980) and raises it only under load, and
/// renders of a tenth of a second timed straight after a kernel's compile ran up to 3.5x slower
/// on one in some runs than in others (docs/benchmarks/history.md, 2026-12-04, `3e96a5c`). It also lets the renderer
/// size its dispatches from measured costs before any is timed.
const WARM_UP_SECONDS: f64 = 0.3;

/// Most warm-up samples per pixel, however fast the device: 0.3 s of the fastest scene at
/// 1024x768 on an H200 (15 G samples/s) is about 6,000.
const MAX_WARM_UP_SAMPLES: u32 = 8192;

/// One scene's throughput on one device. The timed samples follow warm-up samples (at least one,
/// and [`WARM_UP_SECONDS`] of them), whose first-dispatch costs (pipeline caches, page faults) and
/// rising clocks are not throughput.
pub struct Measurement {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel timed (the warm-up samples excluded).
    pub spp: u32,
    pub aovs: AovSet,
    /// The kernel measured: compiled for the scene, or the general one (`--general-kernel`).
    pub kernel: KernelChoice,
    /// The scene features that kernel was compiled with.
    pub features: SceneFeatures,
    /// The order its workgroups took the image's rows in.
    pub group_order: GroupOrder,
    /// The walk queue the kernel was compiled with (lavapipe, a flat top level), or none.
    pub walk_queue: Option<WalkQueue>,
    /// Whether its subgroups took their tiles from a counter (CPU devices; `CAUSTICA_TAKE_TILES`).
    pub take_tiles: bool,
    /// How it read the walk's nodes and triangles (`CAUSTICA_WALK_RECORDS`).
    pub walk_records: WalkRecords,
    /// The node format of the meshes' and shapes' BVHs (`CAUSTICA_BVH_WIDTH`).
    pub bvh_width: BvhWidth,
    /// How a shadow ray's four-wide walk ordered a node's children (`CAUSTICA_SHADOW_WALK`).
    pub shadow_walk: ShadowWalk,
    /// Whether the wavefront's kernels ran instead of the megakernel (`CAUSTICA_WAVEFRONT`).
    pub wavefront: bool,
    /// The kernel's workgroup shape.
    pub workgroup: Workgroup,
    /// How its rays found what they hit: the compute walk or the device's ray queries
    /// (`--traversal`).
    pub traversal: Traversal,
    /// BVH build, upload and kernel compile (the scene's loading excluded).
    pub setup_seconds: f64,
    /// Wall time of the timed dispatches, fences included.
    pub seconds: f64,
    pub samples_per_second: Option<f64>,
    /// The device's own timestamps around the timed dispatches (no submission or fence costs);
    /// None where the queue records no timestamps.
    pub gpu_seconds: Option<f64>,
    /// CPU time of this process during the timed render: on lavapipe the device is the process's
    /// threads, so samples per CPU-second barely move with other load on a shared machine.
    pub cpu_seconds: Option<f64>,
    pub rays_per_second: Option<f64>,
    /// Camera, bounce and shadow rays per sample (every `trace_ray` of the kernel).
    pub rays_per_sample: Option<f64>,
    pub nonfinite_samples: u64,
    /// Shader loop iterations the device allows per invocation, where it ends loops early.
    pub loop_limit: Option<u32>,
    pub repeated_dispatches: u32,
    pub geometry: GeometryReport,
    /// What the driver says of the kernel (registers per invocation, spills), where it says any.
    pub kernel_statistics: Vec<KernelStatistic>,
}

/// Renders `scene` at its film's size and sample count (seed 1) with the kernel set up as `setup`
/// says and times it.
pub fn measure(ctx: &GpuContext, scene: &Scene, aovs: AovSet, setup: &KernelSetup) -> Result<Measurement> {
    let (width, height, spp) = (scene.film.width, scene.film.height, scene.film.spp);
    let setup_start = Instant::now();
    let mut renderer = Renderer::with_options(ctx, scene, 1, aovs, setup.choice, &setup.options)?;
    if let Some(order) = setup.group_order {
        renderer.set_group_order(order);
    }
    let setup_seconds = setup_start.elapsed().as_secs_f64();
    let warm_up = Instant::now();
    renderer.render_while(MAX_WARM_UP_SAMPLES, |_| warm_up.elapsed().as_secs_f64() < WARM_UP_SECONDS)?;
    let (rays0, secs0, spp0) = (renderer.rays_traced, renderer.seconds, renderer.samples_done);
    let (cpu0, gpu0) = (cpu_seconds(), renderer.gpu_seconds);
    renderer.render(spp, |_| {})?;
    let cpu_seconds = cpu0.zip(cpu_seconds()).map(|(a, b)| b - a);
    let gpu_seconds = gpu0.zip(renderer.gpu_seconds).map(|(a, b)| b - a);
    let seconds = renderer.seconds - secs0;
    let samples = (renderer.samples_done - spp0) as f64 * width as f64 * height as f64;
    let rays = (renderer.rays_traced - rays0) as f64;
    Ok(Measurement {
        scene: scene.name.clone(),
        width,
        height,
        spp,
        aovs,
        kernel: setup.choice,
        features: renderer.features,
        group_order: renderer.group_order(),
        walk_queue: renderer.walk_queue,
        take_tiles: renderer.take_tiles,
        walk_records: renderer.walk_records,
        bvh_width: renderer.bvh_width,
        shadow_walk: renderer.shadow_walk,
        wavefront: renderer.runs_wavefront(),
        workgroup: renderer.workgroup,
        traversal: renderer.traversal,
        setup_seconds,
        seconds,
        samples_per_second: per_second(samples, seconds),
        gpu_seconds,
        cpu_seconds,
        rays_per_second: per_second(rays, seconds),
        rays_per_sample: (samples > 0.0).then(|| rays / samples),
        nonfinite_samples: renderer.nonfinite_samples,
        loop_limit: renderer.loop_limit(),
        repeated_dispatches: renderer.repeated_dispatches,
        geometry: renderer.geometry.clone(),
        kernel_statistics: renderer.kernel_statistics().to_vec(),
    })
}

impl Measurement {
    /// Pixel samples timed (the image's pixels times the timed spp).
    pub fn samples(&self) -> f64 {
        self.width as f64 * self.height as f64 * self.spp as f64
    }

    pub fn samples_per_gpu_second(&self) -> Option<f64> {
        self.gpu_seconds.and_then(|g| per_second(self.samples(), g))
    }

    pub fn samples_per_cpu_second(&self) -> Option<f64> {
        self.cpu_seconds.and_then(|c| per_second(self.samples(), c))
    }

    /// The figures of this scene; the keys are those `bench --json` has always printed (scripts
    /// and tests read them), less the device's, which [`device_json`] gives.
    pub fn json(&self) -> Value {
        json!({
            "scene": self.scene,
            "width": self.width,
            "height": self.height,
            "samples": self.spp,
            "aovs": self.aovs.to_string(),
            "kernel": match self.kernel {
                KernelChoice::ForScene => "scene",
                KernelChoice::General => "general",
            },
            "kernel_features": self.features.names(),
            "group_order": self.group_order.label(),
            // Instances a ray may walk through the queue; null: each lane walks its own rays.
            "walk_queue": self.walk_queue.map(|q| q.walks_per_ray),
            "walk_queue_barriers": self.walk_queue.map(|q| q.subgroup_barriers),
            "take_tiles": self.take_tiles,
            "walk_records": self.walk_records.label(),
            "bvh_width": self.bvh_width.label(),
            "shadow_walk": self.shadow_walk.label(),
            "wavefront": self.wavefront,
            "workgroup": self.workgroup.label(),
            "traversal": self.traversal.name(),
            "setup_seconds": self.setup_seconds,
            "seconds": self.seconds,
            "samples_per_second": self.samples_per_second,
            "gpu_seconds": self.gpu_seconds,
            "samples_per_gpu_second": self.samples_per_gpu_second(),
            "cpu_seconds": self.cpu_seconds,
            "samples_per_cpu_second": self.samples_per_cpu_second(),
            "rays_per_second": self.rays_per_second,
            "rays_per_sample": self.rays_per_sample,
            "nonfinite_samples": self.nonfinite_samples,
            "loop_limit": self.loop_limit,
            "repeated_dispatches": self.repeated_dispatches,
            "primitives": self.geometry.acceleration.primitives,
            "gpu_bytes": self.geometry.gpu_bytes,
            "acceleration_structure_bytes": self.geometry.acceleration_structure_bytes,
            "light_tree_nodes": self.geometry.light_tree.as_ref().map(|t| t.nodes),
            "light_tree_bytes": self.geometry.light_tree.as_ref().map(|t| t.bytes),
            "light_tree_build_seconds": self.geometry.light_tree.as_ref().map(|t| t.build_seconds),
            // The driver's own names and figures, e.g. {"Register Count": "96"}.
            "kernel_statistics": self.kernel_statistics.iter().map(|s| (s.name.clone(), Value::from(s.value.clone()))).collect::<serde_json::Map<_, _>>(),
        })
    }

    /// `bench SCENE --json`: the scene's figures and the device's in one object.
    pub fn json_with_device(&self, device: &DeviceInfo) -> Value {
        let mut summary = self.json();
        if let (Value::Object(figures), Value::Object(device)) = (&mut summary, device_json(device)) {
            figures.extend(device);
        }
        summary
    }
}

/// The device and driver a measurement ran on: a lavapipe figure means little without the Mesa
/// version (`driver_info`), since Mesa 25 runs the same kernel about 3x faster than Mesa 22.3.
pub fn device_json(device: &DeviceInfo) -> Value {
    json!({
        "device": device.name,
        "device_type": device.kind.label(),
        "api_version": device.api_version,
        "driver_name": device.driver_name,
        "driver_info": device.driver_info,
        "driver_version": device.driver,
    })
}
