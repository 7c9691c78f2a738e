//! Dense row-major products for the coupled propagator's matrix exponential, out = a b (a r x k,
//! b k x c). The exponential of a 100-mode body is some 30 products of 212 x 212 matrices, so
//! their speed is the renewal's: the kernel keeps a 4 x 8 block of `out` in registers while it
//! runs down the shared dimension (eight multiply-adds per row of `b` loaded instead of one),
//! and where the processor has them (x86-64 with AVX2 and FMA, detected at run time: the
//! cdylib is built for the baseline) it is compiled a second time with fused multiply-adds on
//! 256-bit vectors. Neither allocates; the caller lends `out`.

/// Rows and columns of `out` that the kernel's block holds.
const ROWS: usize = 4;
const COLS: usize = 8;

/// out = a b; `out` must not alias `a` or `b`, and holds at least r c values.
pub fn mat_mul(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    assert!(a.len() >= r * k && b.len() >= k * c && out.len() >= r * c, "mat_mul: operands too short");
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the processor has the features the function is compiled for
            unsafe { mat_mul_fma(r, k, c, a, b, out) };
            return;
        }
    }
    blocked::<false>(r, k, c, a, b, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn mat_mul_fma(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    blocked::<true>(r, k, c, a, b, out);
}

/// acc + x y, fused where `FUSED` (one rounding; a call into libm without the FMA unit, hence
/// the separate instantiation).
#[inline(always)]
fn mul_add<const FUSED: bool>(x: f64, y: f64, acc: f64) -> f64 {
    if FUSED { x.mul_add(y, acc) } else { acc + x * y }
}

#[inline(always)]
fn blocked<const FUSED: bool>(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    let (r_full, c_full) = (r - r % ROWS, c - c % COLS);
    // a panel of b's columns (k x COLS) stays in the first-level cache while a's rows stream by
    for j in (0..c_full).step_by(COLS) {
        for i in (0..r_full).step_by(ROWS) {
            let mut acc = [[0.0f64; COLS]; ROWS];
            for l in 0..k {
                let bl: &[f64; COLS] = b[l * c + j..l * c + j + COLS].try_into().expect("COLS values");
                for (row, acc_row) in acc.iter_mut().enumerate() {
                    let x = a[(i + row) * k + l];
                    for (s, y) in acc_row.iter_mut().zip(bl) {
                        *s = mul_add::<FUSED>(x, *y, *s);
                    }
                }
            }
            for (row, acc_row) in acc.iter().enumerate() {
                out[(i + row) * c + j..(i + row) * c + j + COLS].copy_from_slice(acc_row);
            }
        }
    }
    // the columns past the last full block, ROWS rows at a time (b's rows read in order)
    if c_full < c {
        let rem = c - c_full;
        for i in (0..r_full).step_by(ROWS) {
            let mut acc = [[0.0f64; COLS]; ROWS];
            for l in 0..k {
                let bl = &b[l * c + c_full..(l + 1) * c];
                for (row, acc_row) in acc.iter_mut().enumerate() {
                    let x = a[(i + row) * k + l];
                    for (s, y) in acc_row[..rem].iter_mut().zip(bl) {
                        *s = mul_add::<FUSED>(x, *y, *s);
                    }
                }
            }
            for (row, acc_row) in acc.iter().enumerate() {
                out[(i + row) * c + c_full..(i + row + 1) * c].copy_from_slice(&acc_row[..rem]);
            }
        }
    }
    for row in r_full..r {
        for j in (0..c_full).step_by(COLS) {
            let mut acc = [0.0f64; COLS];
            for l in 0..k {
                let x = a[row * k + l];
                for (s, y) in acc.iter_mut().zip(&b[l * c + j..l * c + j + COLS]) {
                    *s = mul_add::<FUSED>(x, *y, *s);
                }
            }
            out[row * c + j..row * c + j + COLS].copy_from_slice(&acc);
        }
        edge::<FUSED>(row, c_full, k, c, a, b, out);
    }
}

/// out[row, from..c] one value at a time.
#[inline(always)]
fn edge<const FUSED: bool>(row: usize, from: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    for j in from..c {
        let mut s = 0.0;
        for l in 0..k {
            s = mul_add::<FUSED>(a[row * k + l], b[l * c + j], s);
        }
        out[row * c + j] = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product in the textbook's order of sums, for shapes on and off the kernel's blocks.
    #[test]
    fn equals_the_textbook_product_for_any_shape() {
        for &(r, k, c) in &[(1, 1, 1), (4, 3, 8), (5, 7, 9), (13, 11, 17), (24, 24, 12), (3, 0, 5), (0, 4, 4)] {
            let a: Vec<f64> = (0..r * k).map(|v| ((v * 37 % 101) as f64 - 50.0) / 7.0).collect();
            let b: Vec<f64> = (0..k * c).map(|v| ((v * 53 % 97) as f64 - 48.0) / 11.0).collect();
            let mut out = vec![f64::NAN; r * c];
            mat_mul(r, k, c, &a, &b, &mut out);
            let mut generic = vec![f64::NAN; r * c];
            blocked::<false>(r, k, c, &a, &b, &mut generic);
            assert_eq!(out.len(), r * c);
            for i in 0..r {
                for j in 0..c {
                    let expected: f64 = (0..k).map(|l| a[i * k + l] * b[l * c + j]).sum();
                    let scale: f64 = (0..k).map(|l| (a[i * k + l] * b[l * c + j]).abs()).sum::<f64>().max(1e-300);
                    // round-off of k sums in another order (and fused), 1e-15 per term
                    assert!((out[i * c + j] - expected).abs() <= 1e-15 * k as f64 * scale, "{r}x{k}x{c} [{i},{j}]");
                    assert!((generic[i * c + j] - expected).abs() <= 1e-15 * k as f64 * scale, "{r}x{k}x{c} [{i},{j}]");
                }
            }
        }
    }
}
