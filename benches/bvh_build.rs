//! BVH build throughput: `cargo bench --bench bvh_build`. Builds each input three times (or
//! $BVH_BENCH_RUNS, for a noisy machine) and reports the best time, throughput and the tree's shape and SAH cost. Real meshes are read from
//! $CAUSTICA_DATA (default ../shared/data next to the crate) and skipped when missing.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use caustica::bvh::{self, Aabb};
use glam::Vec3;

type Triangle = [Vec3; 3];

fn main() {
    println!(
        "{:<24} {:>9} {:>9} {:>8} {:>9} {:>10} {:>10} {:>8} {:>6}",
        "input", "tris", "build ms", "Mtris/s", "nodes", "nodes/tri", "bytes/tri", "SAH", "depth"
    );
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    report("random 1M", &random_triangles(&mut rng, 1_000_000));
    report("terrain 1M", &terrain(708));
    report("terrain 100k", &terrain(224));
    report("terrain 70k", &terrain(187));
    let data = std::env::var_os("CAUSTICA_DATA").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
        PathBuf::from,
    );
    for (name, file) in [
        ("bunny 69k", "meshes/bunny/bun_zipper.ply"),
        ("lucy 100k", "meshes/lucy/Lucy100k.ply"),
    ] {
        match std::fs::read(data.join(file)) {
            Ok(bytes) => report(name, &read_ply(&bytes)),
            Err(e) => println!("{name:<24} SKIPPED ({}: {e})", data.join(file).display()),
        }
    }
}

fn report(name: &str, tris: &[Triangle]) {
    let bounds: Vec<Aabb> = tris
        .iter()
        .map(|t| Aabb::new(t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
        .collect();
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
    println!(
        "{:<24} {:>9} {:>9.1} {:>8.2} {:>9} {:>10.3} {:>10.2} {:>8.2} {:>6}",
        name,
        tris.len(),
        best.as_secs_f64() * 1e3,
        n / best.as_secs_f64() / 1e6,
        stats.nodes,
        stats.nodes as f64 / n,
        stats.nodes as f64 * 32.0 / n,
        stats.sah_cost,
        stats.max_depth
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
            let [a, b, c, d] = [
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i, j + 1),
                vertex(i + 1, j + 1),
            ];
            tris.extend([[a, b, c], [b, d, c]]);
        }
    }
    tris
}

/// Just enough PLY for the scanned meshes: float vertex properties (x, y, z first), polygon faces
/// as `list uchar int`, ASCII or binary little-endian. Polygons are fanned into triangles.
fn read_ply(bytes: &[u8]) -> Vec<Triangle> {
    let header_end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = std::str::from_utf8(&bytes[..header_end]).unwrap();
    let (mut vertices, mut faces, mut vertex_props, mut in_vertex) = (0, 0, 0, false);
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["element", "vertex", n] => (vertices, in_vertex) = (n.parse().unwrap(), true),
            ["element", "face", n] => (faces, in_vertex) = (n.parse().unwrap(), false),
            ["property", "float", _] if in_vertex => vertex_props += 1,
            _ => {}
        }
    }
    let body = &bytes[header_end..];
    let (positions, polygons): (Vec<Vec3>, Vec<Vec<usize>>) = if header.contains("ascii") {
        let mut lines = std::str::from_utf8(body).unwrap().lines();
        let mut numbers = |n: usize| {
            lines
                .next()
                .unwrap()
                .split_whitespace()
                .take(n)
                .map(|w| w.parse::<f32>().unwrap())
                .collect::<Vec<_>>()
        };
        let positions = (0..vertices)
            .map(|_| Vec3::from_slice(&numbers(3)))
            .collect();
        let polygons = (0..faces)
            .map(|_| {
                numbers(usize::MAX)[1..]
                    .iter()
                    .map(|&i| i as usize)
                    .collect()
            })
            .collect();
        (positions, polygons)
    } else {
        let word = |at: usize| <[u8; 4]>::try_from(&body[at..at + 4]).unwrap();
        let positions = (0..vertices)
            .map(|v| {
                Vec3::from_array(std::array::from_fn(|k| {
                    f32::from_le_bytes(word(4 * (v * vertex_props + k)))
                }))
            })
            .collect();
        let mut at = 4 * vertices * vertex_props;
        let polygons = (0..faces)
            .map(|_| {
                let n = body[at] as usize;
                at += 1 + 4 * n;
                (0..n)
                    .map(|k| i32::from_le_bytes(word(at - 4 * (n - k))) as usize)
                    .collect()
            })
            .collect();
        (positions, polygons)
    };
    polygons
        .iter()
        .flat_map(|p| {
            (1..p.len() - 1).map(|k| [positions[p[0]], positions[p[k]], positions[p[k + 1]]])
        })
        .collect()
}
