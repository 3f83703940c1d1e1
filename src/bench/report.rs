//! How measurements are shown: one scene in detail (geometry, BVH, memory, throughput), a suite as
//! one table, and the suite as one JSON document.

use super::{device_json, Measurement, SuiteOutcome};
use crate::gpu::DeviceInfo;
use crate::render::{BvhWidth, GeometryReport, KernelChoice, ShadowWalk, WalkRecords};
use serde_json::{json, Value};

/// `value / scale` to `digits` decimals, or "-" when nothing was timed (a render too quick to
/// measure gives no rate rather than an infinite one).
fn figure(value: Option<f64>, scale: f64, digits: usize) -> String {
    value.map_or("-".to_owned(), |v| format!("{:.digits$}", v / scale))
}

/// The device and its driver in one line: `llvmpipe (LLVM 15.0.6, 256 bits) (CPU), driver
/// llvmpipe, Mesa 22.3.6 (LLVM 15.0.6)`.
fn device_line(device: &DeviceInfo) -> String {
    let driver = match (device.driver_name.as_str(), device.driver_info.as_str()) {
        ("", "") => format!("driver version {}", device.driver),
        (name, "") => format!("driver {name}"),
        (name, info) => format!("driver {name}, {info}"),
    };
    format!("{} ({}), {driver}", device.name, device.kind.label())
}

/// `bench SCENE` without `--json`.
pub fn print_measurement(m: &Measurement, device: &DeviceInfo) {
    println!("scene:        {}", m.scene);
    println!("device:       {}", device_line(device));
    println!("image:        {}x{}, {} spp, AOVs: {}", m.width, m.height, m.spp, m.aovs);
    let kernel = match m.kernel {
        KernelChoice::ForScene => "compiled for the scene",
        KernelChoice::General => "general (--general-kernel)",
    };
    let walks = m.walk_queue.map_or(String::new(), |q| {
        let barriers = if q.subgroup_barriers { ", subgroup barriers" } else { "" };
        format!("; rays walked from the subgroup's queue (up to {} instances a ray{barriers})", q.walks_per_ray)
    });
    let tiles = if m.take_tiles { "; subgroups take tiles from a counter" } else { "" };
    let records = match m.walk_records {
        WalkRecords::Texels => "",
        WalkRecords::Storage => "; nodes and triangles from storage buffers",
    };
    let width = match m.bvh_width {
        BvhWidth::Four => "",
        BvhWidth::Eight => "; eight-wide nodes in octant order (CAUSTICA_BVH_WIDTH)",
    };
    let shadows = match m.shadow_walk {
        ShadowWalk::Sorted => "",
        ShadowWalk::Unsorted => "; shadow rays' children unsorted (CAUSTICA_SHADOW_WALK)",
    };
    let wavefront = if m.wavefront { "; the wavefront's three kernels (CAUSTICA_WAVEFRONT)" } else { "" };
    println!(
        "kernel:       {kernel}: {}; workgroups {}, rows {}, traversal {}{tiles}{records}{width}{shadows}{walks}{wavefront}",
        m.features.names().join(", "),
        m.workgroup.label(),
        m.group_order.label(),
        m.traversal.name()
    );
    if !m.kernel_statistics.is_empty() {
        // The driver's own figures: on a GPU, registers and spills bound the invocations in flight.
        let figures: Vec<String> = m.kernel_statistics.iter().map(|s| format!("{} {}", s.name, s.value)).collect();
        println!("compiled:     {}", figures.join("; "));
    }
    print_geometry(&m.geometry);
    println!("setup:        {:.3} s (load excluded: BVH, upload, kernel compile)", m.setup_seconds);
    let shown = |value: Option<f64>, scale: f64, digits: usize| {
        value.map_or("none measured".to_owned(), |v| format!("{:.digits$}", v / scale))
    };
    println!("render:       {:.3} s", m.seconds);
    if let Some(gpu) = m.gpu_seconds {
        // The device's own timestamps around each dispatch: no submission or fence costs.
        println!("device time:  {gpu:.3} s ({} M samples/s)", shown(m.samples_per_gpu_second(), 1e6, 3));
    }
    if let Some(cpu) = m.cpu_seconds {
        // On lavapipe the device is this process's threads: a throughput that other load barely moves.
        println!("host CPU:     {cpu:.3} s");
    }
    println!("samples/s:    {} M", shown(m.samples_per_second, 1e6, 3));
    println!("rays/s:       {} M", shown(m.rays_per_second, 1e6, 3));
    println!("rays/sample:  {}", shown(m.rays_per_sample, 1.0, 2));
    println!("non-finite:   {} samples dropped", m.nonfinite_samples);
    if let Some(limit) = m.loop_limit {
        // Such a device ends shader loops early: dispatches are sized to stay within the limit.
        println!("loop limit:   {limit} iterations per invocation; {} dispatches repeated", m.repeated_dispatches);
    }
}

fn print_geometry(g: &GeometryReport) {
    let a = &g.acceleration;
    let mib = |b: u64| b as f64 / 1048576.0;
    println!(
        "geometry:     {} primitives, {} mesh triangles stored, {} in the world, {} instances, {} lights",
        a.primitives, a.mesh_triangles, a.instanced_triangles, a.instances, g.lights
    );
    let rate = a.mesh_triangles as f64 / a.build_seconds.max(1e-9) / 1e6;
    println!("BVH build:    {:.3} s ({rate:.2} M triangles/s), {} nodes", a.build_seconds, a.nodes);
    if let Some(b) = &a.largest_mesh {
        println!("largest mesh: {} nodes, depth {}, SAH cost {:.2}", b.nodes, b.max_depth, b.sah_cost);
    }
    if let Some(t) = &a.top {
        println!("top level:    {} nodes, depth {}, SAH cost {:.2}", t.nodes, t.max_depth, t.sah_cost);
    }
    let per_triangle = if a.mesh_triangles > 0 {
        format!(", {:.1} B/triangle", a.bytes_per_triangle(g.geometry_bytes))
    } else {
        String::new()
    };
    println!(
        "GPU memory:   {:.1} MiB geometry + BVH{per_triangle}, {:.1} MiB textures, {:.1} MiB in all",
        mib(g.geometry_bytes),
        mib(g.texture_bytes),
        mib(g.gpu_bytes)
    );
    if let Some(t) = &g.light_tree {
        println!(
            "light tree:   {} nodes, {:.1} KiB, built in {:.4} s",
            t.nodes,
            t.bytes as f64 / 1024.0,
            t.build_seconds
        );
    }
    if g.acceleration_structure_bytes > 0 {
        println!("ray queries:  {:.1} MiB of acceleration structures", mib(g.acceleration_structure_bytes));
    }
    if !g.split_arrays.is_empty() {
        let split: Vec<String> = g.split_arrays.iter().map(|(name, windows)| format!("{name} x{windows}")).collect();
        println!("split:        {} (larger than one storage binding of this device)", split.join(", "));
    }
}

/// The column titles of the suite table, in order.
pub const SUITE_COLUMNS: [&str; 7] = ["scene", "size", "spp", "Msamples/s", "Mrays/s", "rays/sample", "seconds"];

/// `bench --suite` without `--json`: the device, then one row per scene measured. Skips and
/// failures were said on stderr as they happened and are repeated there at the end.
pub fn print_suite(outcome: &SuiteOutcome, device: &DeviceInfo) {
    println!("device: {}", device_line(device));
    let rows: Vec<[String; 7]> = outcome
        .rows
        .iter()
        .map(|m| {
            [
                m.scene.clone(),
                format!("{}x{}", m.width, m.height),
                m.spp.to_string(),
                figure(m.samples_per_second, 1e6, 3),
                figure(m.rays_per_second, 1e6, 3),
                figure(m.rays_per_sample, 1.0, 2),
                format!("{:.2}", m.seconds),
            ]
        })
        .collect();
    let width = |c: usize| rows.iter().map(|r| r[c].len()).chain([SUITE_COLUMNS[c].len()]).max().unwrap_or(0);
    let widths: Vec<usize> = (0..SUITE_COLUMNS.len()).map(width).collect();
    // The scene name left-aligned, the figures right-aligned so their decimals line up.
    let line = |cells: &[String]| -> String {
        let mut text = format!("{:<w$}", cells[0], w = widths[0]);
        for (cell, w) in cells.iter().zip(&widths).skip(1) {
            text.push_str(&format!("  {cell:>w$}"));
        }
        text
    };
    println!("{}", line(&SUITE_COLUMNS.map(str::to_owned)));
    for row in &rows {
        println!("{}", line(row));
    }
    print_left_out(outcome);
}

/// Repeats on stderr, after the table, what the suite did not measure: a skipped scene is easy to
/// miss among the progress lines of a long run.
pub fn print_left_out(outcome: &SuiteOutcome) {
    if !outcome.skipped.is_empty() {
        let names: Vec<&str> = outcome.skipped.iter().map(|(name, _)| name.as_str()).collect();
        log::warn!("caustica: SKIPPED {} of the suite's scenes: {}", names.len(), names.join(", "));
    }
    if !outcome.failed.is_empty() {
        let names: Vec<&str> = outcome.failed.iter().map(|(name, _)| name.as_str()).collect();
        log::warn!("caustica: FAILED {} of the suite's scenes: {}", names.len(), names.join(", "));
    }
}

/// `bench --suite --json`: one document with the device and driver, a row per scene (the keys of
/// `bench SCENE --json`, less the device's), and the scenes skipped or failed with the reason.
pub fn suite_json(outcome: &SuiteOutcome, device: &DeviceInfo) -> Value {
    let reasons = |list: &[(String, String)], key: &str| -> Vec<Value> {
        list.iter().map(|(name, why)| json!({ "scene": name, key: why })).collect()
    };
    let mut document = device_json(device);
    if let Value::Object(fields) = &mut document {
        fields.insert("rows".into(), outcome.rows.iter().map(Measurement::json).collect());
        fields.insert("skipped".into(), reasons(&outcome.skipped, "reason").into());
        fields.insert("failed".into(), reasons(&outcome.failed, "error").into());
    }
    document
}
