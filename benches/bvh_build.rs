//! BVH build throughput: `cargo bench --bench bvh_build`. Builds each input three times (or
//! $BVH_BENCH_RUNS, for a noisy machine) and reports the best time, throughput and the tree's
//! shape and SAH cost. Real meshes are read with the crate's loader from $CAUSTICA_DATA (default
//! ../shared/data next to the crate) and skipped when missing. The wide columns are the four-wide
//! tree the kernel walks (src/bvh/wide_node.rs): its nodes, their bytes a triangle, its
//! surface-area cost with the boxes as stored, and what their 8-bit steps add to that cost.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use caustica::bvh::{self, Aabb};
use caustica::scene::{load_asset, AssetError};
use glam::Vec3;

type Triangle = [Vec3; 3];

fn main() {
    println!(
        "{:<24} {:>9} {:>9} {:>8} {:>9} {:>10} {:>8} {:>6} {:>10} {:>10} {:>9} {:>9}",
        "input",
        "tris",
        "build ms",
        "Mtris/s",
        "nodes",
        "nodes/tri",
        "SAH",
        "depth",
        "wide nodes",
        "wide B/tri",
        "wide SAH",
        "8-bit +%"
    );
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    report("random 1M", &random_triangles(&mut rng, 1_000_000));
    report("terrain 1M", &terrain(708));
    report("terrain 100k", &terrain(224));
    report("terrain 70k", &terrain(187));
    let data = std::env::var_os("CAUSTICA_DATA")
        .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"), PathBuf::from);
    let bunny = load_mesh(&data.join("meshes/bunny/bun_zipper.ply"));
    let lucy = load_mesh(&data.join("meshes/lucy/Lucy100k.ply"));
    for (name, mesh) in [("bunny 69k", &bunny), ("lucy 100k", &lucy)] {
        match mesh {
            Ok(tris) => report(name, tris),
            Err(e) => println!("{name:<24} SKIPPED ({e})"),
        }
    }
    if let (Ok(bunny), Ok(lucy)) = (&bunny, &lucy) {
        report("20 bunnies + 5 lucy", &crowd(bunny, lucy));
    }
}

/// All triangles of a mesh file's meshes, in the file's object space.
fn load_mesh(path: &Path) -> Result<Vec<Triangle>, AssetError> {
    let asset = load_asset(path)?;
    Ok(asset.meshes.iter().flat_map(|m| m.triangles.iter().map(|t| t.map(|v| m.positions[v as usize]))).collect())
}

/// A ~1.9M-triangle scene: a 5 x 4 grid of bunnies and a row of five Lucys scaled to twice a
/// bunny's height behind it, so instances of dense meshes sit side by side with gaps between them.
fn crowd(bunny: &[Triangle], lucy: &[Triangle]) -> Vec<Triangle> {
    let bounds = |tris: &[Triangle]| {
        tris.iter().flatten().fold(Aabb::EMPTY, |mut b, &v| {
            b.grow(v);
            b
        })
    };
    let (bunny_box, lucy_box) = (bounds(bunny), bounds(lucy));
    let step = bunny_box.extent() * 1.2;
    let lucy_scale = 2.0 * bunny_box.extent().y / lucy_box.extent().y;
    let mut tris = Vec::with_capacity(20 * bunny.len() + 5 * lucy.len());
    for i in 0..20 {
        let offset = Vec3::new((i % 5) as f32 * step.x, 0.0, (i / 5) as f32 * step.z);
        tris.extend(bunny.iter().map(|t| t.map(|v| v + offset)));
    }
    for i in 0..5 {
        let offset = Vec3::new(i as f32 * step.x, 0.0, -2.0 * step.z);
        let place = |v: Vec3| (v - lucy_box.min) * lucy_scale + bunny_box.min + offset;
        tris.extend(lucy.iter().map(|t| t.map(place)));
    }
    tris
}

fn report(name: &str, tris: &[Triangle]) {
    let bounds: Vec<Aabb> =
        tris.iter().map(|t| Aabb::new(t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))).collect();
    let runs = std::env::var("BVH_BENCH_RUNS").map_or(3, |r| r.parse().expect("BVH_BENCH_RUNS"));
    let mut best = Duration::MAX;
    let mut built = None;
    for _ in 0..runs {
        let start = Instant::now();
        let bvh = std::hint::black_box(bvh::build(std::hint::black_box(&bounds)));
        best = best.min(start.elapsed());
        built = Some(bvh);
    }
    let bvh = built.unwrap();
    let stats = bvh.stats();
    let n = tris.len() as f64;
    // The tree the kernel walks: its nodes' bytes a triangle, and the surface-area cost it was
    // shaped by, with the boxes as stored and what their 8-bit steps add to it.
    let wide = bvh::wide_nodes(&bvh.nodes, bvh::MAX_LEAF_SIZE);
    let wide_cost = bvh::WideCost::of(&wide, &bvh, &bounds);
    println!(
        "{:<24} {:>9} {:>9.1} {:>8.2} {:>9} {:>10.3} {:>8.2} {:>6} {:>10} {:>10.2} {:>9.2} {:>9.2}",
        name,
        tris.len(),
        best.as_secs_f64() * 1e3,
        n / best.as_secs_f64() / 1e6,
        stats.nodes,
        stats.nodes as f64 / n,
        stats.sah_cost,
        stats.max_depth,
        wide.len(),
        (wide.len() * size_of::<bvh::WideNode>()) as f64 / n,
        wide_cost.stored,
        100.0 * (wide_cost.stored / wide_cost.exact - 1.0)
    );
}

/// xorshift64*: fixed-seed inputs without a dependency.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec3(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.unit(), self.unit(), self.unit()) * (hi - lo) + lo
    }
}

/// Small triangles (edges up to 1% of the box) scattered through the unit cube.
fn random_triangles(rng: &mut Rng, count: usize) -> Vec<Triangle> {
    (0..count)
        .map(|_| {
            let v0 = rng.vec3(0.0, 1.0);
            [v0, v0 + rng.vec3(-0.01, 0.01), v0 + rng.vec3(-0.01, 0.01)]
        })
        .collect()
}

/// A height field over the unit square, `cells`² quads of two triangles: mesh-like adjacency.
fn terrain(cells: usize) -> Vec<Triangle> {
    let vertex = |i: usize, j: usize| {
        let (x, z) = (i as f32 / cells as f32, j as f32 / cells as f32);
        let y = 0.1 * (7.0 * x).sin() * (5.0 * z).cos() + 0.03 * (31.0 * x + 17.0 * z).sin();
        Vec3::new(x, y, z)
    };
    let mut tris = Vec::with_capacity(2 * cells * cells);
    for i in 0..cells {
        for j in 0..cells {
            let [a, b, c, d] = [vertex(i, j), vertex(i + 1, j), vertex(i, j + 1), vertex(i + 1, j + 1)];
            tris.extend([[a, b, c], [b, d, c]]);
        }
    }
    tris
}
