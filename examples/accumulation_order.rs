//! Would an order-independent accumulation make every merge bit-exact with one render? Measures it
//! on real samples (docs/farm.md, "Merging bit for bit"):
//!
//!   cargo run --release --example accumulation_order [-- SIZE SAMPLES]
//!
//! Renders the built-in Cornell box one sample at a time (each sample's radiance per pixel, exactly
//! as the kernel adds it), checks that adding them in order in f32 reproduces the kernel's own
//! accumulation bit for bit, then adds the same samples split into 2, 4, 8, ... parts (each part
//! summed in order from zero, the parts then added as `caustica merge` does) in three number
//! formats: f32 (today's), f64, and 64-bit integer fixed point, and prints how many pixel values
//! differ from one uninterrupted render, the error each format makes against exact sums, how
//! much range fixed point leaves, and what one add costs on this CPU.

use caustica::gpu::{ContextOptions, GpuContext};
use caustica::render::Renderer;
use caustica::scene::Scene;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<u32> = std::env::args().skip(1).map(|a| a.parse().expect("SIZE SAMPLES")).collect();
    let (size, samples) = (args.first().copied().unwrap_or(32), args.get(1).copied().unwrap_or(1024));
    let ctx = GpuContext::new(&ContextOptions::default())?;
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height) = (size, size);
    let pixels = (size * size) as usize;

    // values[i][p * 3 + c]: sample i's radiance, pixel p, channel c.
    let started = Instant::now();
    let mut renderer = Renderer::new(&ctx, &scene, 1)?;
    let zeros = vec![[0.0f32; 4]; pixels];
    let mut values: Vec<Vec<f32>> = Vec::with_capacity(samples as usize);
    for i in 0..samples {
        renderer.restore(&zeros, 0)?;
        renderer.set_sample_offset(i);
        renderer.render(1, |_| {})?;
        values.push(renderer.accumulation()?.iter().flat_map(|a| [a[0], a[1], a[2]]).collect());
    }
    let mut whole = Renderer::new(&ctx, &scene, 1)?;
    whole.render(samples, |_| {})?;
    let kernel: Vec<f32> = whole.accumulation()?.iter().flat_map(|a| [a[0], a[1], a[2]]).collect();
    println!(
        "{size}x{size} Cornell box, {samples} samples, one at a time, on {} ({:.1} s)",
        ctx.info.name,
        started.elapsed().as_secs_f64()
    );

    let in_order_f32 = sum_f32(&values, 0..samples as usize);
    let same = in_order_f32.iter().zip(&kernel).filter(|(a, b)| a.to_bits() == b.to_bits()).count();
    println!("f32 in order vs the kernel's accumulation: {same} of {} values bit for bit", kernel.len());
    assert_eq!(same, kernel.len(), "the per-sample values do not add up to the kernel's accumulation");

    // Exact sums for the error columns: f64 with compensation is exact far beyond f32's precision.
    let exact: Vec<f64> = (0..kernel.len()).map(|j| kahan(values.iter().map(|v| f64::from(v[j])))).collect();
    let largest = values.iter().flatten().fold(0.0f32, |m, &v| m.max(v.abs()));
    let largest_sum = exact.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
    let relative_error = |sums: &[f64]| -> f64 {
        sums.iter().zip(&exact).filter(|(_, e)| **e > 0.0).map(|(s, e)| ((s - e) / e).abs()).fold(0.0, f64::max)
    };
    println!("largest sample value {largest:.4}, largest pixel sum {largest_sum:.1}");
    println!(
        "f32 in order (today): largest relative error against the exact sum {:.2e}",
        relative_error(&in_order_f32.iter().map(|&v| f64::from(v)).collect::<Vec<_>>())
    );

    println!("\nparts | f32: values differing from one render, largest relative difference | f64 (rounded to f32): differing | i64 Q32.31: differing");
    let fixed = |v: f32, bits: u32| (f64::from(v) * 2f64.powi(bits as i32)).round() as i64;
    let fraction_bits = 31;
    let q_in_order = sum_i64(&values, 0..samples as usize, |v| fixed(v, fraction_bits));
    let f64_in_order: Vec<f32> = sum_f64(&values, 0..samples as usize).iter().map(|&v| v as f32).collect();
    let mut parts = 2;
    while parts <= samples.min(64) as usize {
        let per = samples as usize / parts;
        let ranges: Vec<_> =
            (0..parts).map(|k| k * per..if k + 1 == parts { samples as usize } else { (k + 1) * per }).collect();
        // f32 merge: part sums added in order of their first sample, from zero.
        let mut merged = vec![0.0f32; kernel.len()];
        let mut merged64 = vec![0.0f64; kernel.len()];
        let mut merged_q = vec![0i64; kernel.len()];
        for r in &ranges {
            for (m, p) in merged.iter_mut().zip(sum_f32(&values, r.clone())) {
                *m += p;
            }
            for (m, p) in merged64.iter_mut().zip(sum_f64(&values, r.clone())) {
                *m += p;
            }
            for (m, p) in merged_q.iter_mut().zip(sum_i64(&values, r.clone(), |v| fixed(v, fraction_bits))) {
                *m += p;
            }
        }
        let differ_f32 = merged.iter().zip(&kernel).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
        let largest_diff = merged
            .iter()
            .zip(&kernel)
            .filter(|(_, b)| **b != 0.0)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0f32, f32::max);
        let differ_f64 =
            merged64.iter().zip(&f64_in_order).filter(|(a, b)| (**a as f32).to_bits() != b.to_bits()).count();
        let differ_q = merged_q.iter().zip(&q_in_order).filter(|(a, b)| a != b).count();
        println!(
            "{parts:5} | {differ_f32:6} of {} ({:.1} %), {largest_diff:.1e} | {differ_f64:6} | {differ_q}",
            kernel.len(),
            100.0 * differ_f32 as f64 / kernel.len() as f64
        );
        parts *= 2;
    }

    // Fixed point's costs: range and precision. With F fraction bits an i64 sum holds up to 2^(63-F)
    // and each sample is rounded to 2^-(F+1).
    println!("\nfixed point, i64 with F fraction bits: largest sum, samples of the largest value that fit, error");
    for bits in [16u32, 24, 31, 40] {
        let limit = 2f64.powi(63 - bits as i32);
        let q = sum_i64(&values, 0..samples as usize, |v| fixed(v, bits));
        let as_f64: Vec<f64> = q.iter().map(|&s| s as f64 / 2f64.powi(bits as i32)).collect();
        println!(
            "F = {bits:2}: sums up to {limit:.2e}, {:.2e} samples of {largest:.2}; largest relative error against the exact sum {:.2e}",
            limit / f64::from(largest),
            relative_error(&as_f64)
        );
    }

    // One add per value, as a merge (and the kernel, per sample) does it, timed on this CPU.
    let reps = 200;
    let a32: Vec<f32> = values[0].clone();
    let a64: Vec<f64> = a32.iter().map(|&v| f64::from(v)).collect();
    let aq: Vec<i64> = a32.iter().map(|&v| fixed(v, fraction_bits)).collect();
    let time = |add: &mut dyn FnMut()| {
        let t = Instant::now();
        for _ in 0..reps {
            add();
        }
        t.elapsed().as_secs_f64() * 1e9 / (reps as f64 * a32.len() as f64)
    };
    let (mut s32, mut s64, mut sq) = (vec![0.0f32; a32.len()], vec![0.0f64; a32.len()], vec![0i64; a32.len()]);
    let t32 = time(&mut || s32.iter_mut().zip(&a32).for_each(|(s, a)| *s += std::hint::black_box(*a)));
    let t64 = time(&mut || s64.iter_mut().zip(&a64).for_each(|(s, a)| *s += std::hint::black_box(*a)));
    let tq =
        time(&mut || sq.iter_mut().zip(&a32).for_each(|(s, a)| *s += fixed(std::hint::black_box(*a), fraction_bits)));
    let tq_add = time(&mut || sq.iter_mut().zip(&aq).for_each(|(s, a)| *s = s.wrapping_add(std::hint::black_box(*a))));
    println!(
        "\nhost, ns per value added: f32 {t32:.2}, f64 {t64:.2}, i64 converting from f32 {tq:.2}, i64 from i64 {tq_add:.2} ({})",
        std::hint::black_box(s32[0] as f64 + s64[0] + sq[0] as f64)
    );
    Ok(())
}

fn sum_f32(values: &[Vec<f32>], samples: std::ops::Range<usize>) -> Vec<f32> {
    let mut sum = vec![0.0f32; values[0].len()];
    for v in &values[samples] {
        sum.iter_mut().zip(v).for_each(|(s, x)| *s += x);
    }
    sum
}

fn sum_f64(values: &[Vec<f32>], samples: std::ops::Range<usize>) -> Vec<f64> {
    let mut sum = vec![0.0f64; values[0].len()];
    for v in &values[samples] {
        sum.iter_mut().zip(v).for_each(|(s, x)| *s += f64::from(*x));
    }
    sum
}

fn sum_i64(values: &[Vec<f32>], samples: std::ops::Range<usize>, fixed: impl Fn(f32) -> i64) -> Vec<i64> {
    let mut sum = vec![0i64; values[0].len()];
    for v in &values[samples] {
        sum.iter_mut().zip(v).for_each(|(s, x)| *s += fixed(*x));
    }
    sum
}

/// Compensated (Kahan-Babuska) sum.
fn kahan(values: impl Iterator<Item = f64>) -> f64 {
    let (mut sum, mut c) = (0.0f64, 0.0f64);
    for v in values {
        let t = sum + v;
        c += if sum.abs() >= v.abs() { (sum - t) + v } else { (v - t) + sum };
        sum = t;
    }
    sum + c
}
