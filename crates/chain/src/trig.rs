//! Sine and cosine together, for the joint angles of FK (the hot path of every solve and every
//! identification): argument reduction by π/2 in up to three rounds (Cody–Waite, the constants and
//! cancellation tests of fdlibm's `__rem_pio2` as musl writes them) and fdlibm's minimax kernels on
//! [−π/4, π/4] (error below 1 ulp). One reduction serves both functions, where two library calls would
//! reduce twice; joint angles are small, so the slow path for huge arguments is the library's.
//!
//! Checked against the library's `sin` and `cos` to 1 ulp over ±1e5 (tests).
#![allow(clippy::excessive_precision)]

/// 2/π.
const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
// The constants below are fdlibm's, with its 21 printed digits: each literal rounds to fdlibm's exact
// double, which the kernels' error bound assumes.
/// π/2 in three parts, each with the trailing bits of the rest (fdlibm).
const PIO2_1: f64 = 1.570_796_326_734_125_614_17e0;
const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11;
const PIO2_2T: f64 = 2.022_266_248_795_950_631_54e-21;
const PIO2_3: f64 = 2.022_266_248_711_166_455_80e-21;
const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32;

/// 1.5 · 2⁵²: added to and subtracted from a double of magnitude below 2⁵¹, it rounds that double to
/// the nearest integer (ties to even) in two additions — musl's `toint`, where `f64::round` is a call
/// into the C library on x86-64 without SSE 4.1.
const TOINT: f64 = 1.5 / f64::EPSILON;

/// Above this magnitude the reduction's quotient could lose bits: the library takes over.
const REDUCTION_LIMIT: f64 = 1e6;

const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// sin(x + y) for |x + y| ≤ π/4, `y` the tail of a reduced argument.
#[inline(always)]
fn kernel_sin(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * S1)
}

/// cos(x + y) for |x + y| ≤ π/4.
#[inline(always)]
fn kernel_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// The biased exponent of `x`.
#[inline(always)]
fn exponent(x: f64) -> i64 {
    ((x.to_bits() >> 52) & 0x7ff) as i64
}

/// `x = n·π/2 + (y0 + y1)` with |y0 + y1| ≤ π/4 (about), for |x| ≤ [`REDUCTION_LIMIT`].
#[inline(always)]
fn reduce(x: f64) -> (i64, f64, f64) {
    // |x| ≤ REDUCTION_LIMIT keeps x·2/π far below 2⁵¹, where TOINT's rounding is exact.
    let n = (x * INV_PIO2 + TOINT) - TOINT;
    let mut r = x - n * PIO2_1;
    let mut w = n * PIO2_1T;
    let mut y0 = r - w;
    let ex = exponent(x);
    // One more round of the reduction with the next part of π/2 and its tail.
    let round = |r: f64, part: f64, tail: f64| {
        let w = n * part;
        let next = r - w;
        (next, n * tail - ((r - next) - w))
    };
    if ex - exponent(y0) > 16 {
        // x is close to a multiple of π/2: a second round, good to 118 bits.
        (r, w) = round(r, PIO2_2, PIO2_2T);
        y0 = r - w;
        if ex - exponent(y0) > 49 {
            // A third, good to 151 bits: every double below the limit.
            (r, w) = round(r, PIO2_3, PIO2_3T);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (n as i64, y0, y1)
}

/// `(sin x, cos x)` to 1 ulp, one argument reduction for both.
#[inline(always)]
pub(crate) fn sin_cos_reduced(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() > REDUCTION_LIMIT {
        return x.sin_cos();
    }
    if x.abs() <= std::f64::consts::FRAC_PI_4 {
        return (kernel_sin(x, 0.0), kernel_cos(x, 0.0));
    }
    let (n, y0, y1) = reduce(x);
    let (s, c) = (kernel_sin(y0, y1), kernel_cos(y0, y1));
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::sin_cos_reduced;

    /// `|a − b|` in units in the last place of `b`.
    fn ulps(a: f64, b: f64) -> f64 {
        let ulp = if b == 0.0 { f64::MIN_POSITIVE } else { (b.abs().next_up() - b.abs()).max(f64::MIN_POSITIVE) };
        (a - b).abs() / ulp
    }

    #[test]
    fn within_one_ulp_of_the_library() {
        // A dense sweep over ±20 rad (every joint angle), multiples of π/2 and their neighbours (the
        // reduction's hard cases), and a sparse sweep to ±1e5.
        let mut xs: Vec<f64> = (-200_000..=200_000).map(|k| k as f64 * 1e-4).collect();
        for k in -1000..=1000 {
            let m = k as f64 * std::f64::consts::FRAC_PI_2;
            xs.extend([m, m.next_up(), m.next_down(), m + 1e-12, m - 1e-9]);
        }
        xs.extend((0..100_000).map(|k| (k as f64 * 1.000_37 - 50_000.0) * 2.0));
        let mut worst: f64 = 0.0;
        for &x in &xs {
            let (s, c) = sin_cos_reduced(x);
            let (es, ec) = x.sin_cos();
            // Results near zero carry the reduction's absolute error, ~1e-16·|n|·2⁻⁵⁰: measured absolutely.
            let ds = if es.abs() < 1e-3 { (s - es).abs() / f64::EPSILON } else { ulps(s, es) };
            let dc = if ec.abs() < 1e-3 { (c - ec).abs() / f64::EPSILON } else { ulps(c, ec) };
            worst = worst.max(ds).max(dc);
            assert!(
                ds <= 1.0 && dc <= 1.0,
                "x = {x:e}: sin {s:e} vs {es:e} ({ds} ulp), cos {c:e} vs {ec:e} ({dc} ulp)"
            );
        }
        assert!(worst > 0.0, "a different implementation differs somewhere");
        // Beyond the reduction's range, and not numbers: the library's own answers.
        assert_eq!(sin_cos_reduced(1e7), 1e7f64.sin_cos());
        assert!(sin_cos_reduced(f64::NAN).0.is_nan() && sin_cos_reduced(f64::INFINITY).1.is_nan());
    }
}
