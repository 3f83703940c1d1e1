//! Pearson's chi-square goodness-of-fit test and the incomplete gamma function behind its p-value,
//! for the tests that compare a sampler's counts with the pdf it reports (BSDF lobes, the light
//! tree's pick, phase functions).

use std::f64::consts::PI;

/// Cells with fewer expected samples are pooled, as the textbook test requires.
pub const MIN_EXPECTED: f64 = 5.0;

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9; about 15 digits).
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let sum = C[0] + C[1..].iter().enumerate().map(|(i, c)| c / (x + i as f64 + 1.0)).sum::<f64>();
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

/// The regularized upper incomplete gamma function Q(a, x) (Numerical Recipes: the series below
/// a + 1, Lentz's continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let prefactor = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
        while term.abs() > sum.abs() * 1e-15 {
            n += 1.0;
            term *= x / n;
            sum += term;
        }
        return 1.0 - sum * prefactor;
    }
    let tiny = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / tiny;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..100_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        d = if d.abs() < tiny { tiny } else { d };
        c = b + an / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-15 {
            break;
        }
    }
    prefactor * h
}

/// Pearson's chi-square of observed against expected counts, cells with fewer than MIN_EXPECTED
/// expected pooled (smallest first) into cells of at least that; returns (statistic, degrees of
/// freedom, p-value).
pub fn chi_square(observed: &[f64], expected: &[f64]) -> (f64, usize, f64) {
    let mut order: Vec<usize> = (0..observed.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut cells = Vec::new();
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for &i in &order {
        if expected[i] < MIN_EXPECTED || pool_e > 0.0 && pool_e < MIN_EXPECTED {
            pool_o += observed[i];
            pool_e += expected[i];
            if pool_e >= MIN_EXPECTED {
                cells.push((pool_o, pool_e));
                (pool_o, pool_e) = (0.0, 0.0);
            }
        } else {
            cells.push((observed[i], expected[i]));
        }
    }
    if pool_o > 0.0 || pool_e > 0.0 {
        // What is left over joins the smallest cell (or stands alone: one sample where the pdf
        // says there should be none is then caught as a huge term).
        match cells.first_mut() {
            Some(c) if pool_e > 0.0 => (c.0, c.1) = (c.0 + pool_o, c.1 + pool_e),
            _ => cells.push((pool_o, pool_e.max(1e-12))),
        }
    }
    let statistic: f64 = cells.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = cells.len() - 1;
    (statistic, dof, gamma_q(dof as f64 / 2.0, statistic / 2.0))
}
