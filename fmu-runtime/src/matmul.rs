//! Dense row-major products for the coupled propagator's matrix exponential, out = a b (a r x k,
//! b k x c). The exponential of a 100-mode body is some 30 products of 212 x 212 matrices, so
//! their speed is the renewal's. The kernel keeps a 6 x 8 block of `out` in registers (twelve
//! 4-wide accumulators of the sixteen AVX2 registers) while it runs down the shared dimension,
//! reading a's six rows from a copy packed one shared index after the other (one stream of
//! broadcasts instead of six rows apart) and b's eight columns in place. Where the processor has
//! them (x86-64 with AVX2 and FMA, detected at run time: the cdylib is built for the baseline)
//! it is compiled a second time with fused multiply-adds on 256-bit vectors. Each value of `out`
//! is one chain of multiply-adds in the order of the shared index, whatever the blocking, so
//! the result does not depend on it. Nothing is allocated: the packed panels live on the stack
//! (28 KiB) and the caller lends `out`.

/// Rows and columns of `out` that the kernel's block holds.
const ROWS: usize = 6;
const COLS: usize = 8;
/// Length of the shared dimension packed at a time: a's panel (12 KiB) and b's edge panel
/// (16 KiB) stay in the first-level cache.
const DEPTH: usize = 256;

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

/// a . b with four partial sums (independent chains the compiler can keep in flight).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// acc + x y, fused where `FUSED` (one rounding; a call into libm without the FMA unit, hence
/// the separate instantiation).
#[inline(always)]
fn mul_add<const FUSED: bool>(x: f64, y: f64, acc: f64) -> f64 {
    if FUSED { x.mul_add(y, acc) } else { acc + x * y }
}

#[inline(always)]
fn blocked<const FUSED: bool>(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    if r == 0 || c == 0 {
        return;
    }
    if k == 0 {
        for row in out[..r * c].chunks_exact_mut(c) {
            row.fill(0.0);
        }
        return;
    }
    let c_full = c - c % COLS;
    let mut a_panel = [[0.0f64; ROWS]; DEPTH];
    let mut b_edge = [[0.0f64; COLS]; DEPTH];
    // the shared dimension outermost: b's edge columns are packed once per panel, not once per
    // block of rows (a 212-column b packed its last four columns 35 times a panel, one short
    // copy per shared index: a fifth of the product's time)
    for k0 in (0..k).step_by(DEPTH) {
        let depth = DEPTH.min(k - k0);
        let cols = c - c_full;
        if cols > 0 {
            for (l, edge) in b_edge[..depth].iter_mut().enumerate() {
                let row = &b[(k0 + l) * c + c_full..(k0 + l + 1) * c];
                for (col, e) in edge.iter_mut().enumerate() {
                    *e = if col < cols { row[col] } else { 0.0 };
                }
            }
        }
        for i in (0..r).step_by(ROWS) {
            // rows past r stay zero in the panel: their block rows are computed and dropped
            let rows = ROWS.min(r - i);
            for (l, packed) in a_panel[..depth].iter_mut().enumerate() {
                for (row, v) in packed.iter_mut().enumerate() {
                    *v = if row < rows { a[(i + row) * k + k0 + l] } else { 0.0 };
                }
            }
            let panel = &a_panel[..depth];
            for j in (0..c_full).step_by(COLS) {
                block::<FUSED>(
                    panel,
                    |l| b[(k0 + l) * c + j..(k0 + l) * c + j + COLS].try_into().expect("COLS values"),
                    k0 > 0,
                    (i, rows),
                    (j, COLS),
                    c,
                    out,
                );
            }
            if cols > 0 {
                let edge = &b_edge[..depth];
                block::<FUSED>(panel, |l| &edge[l], k0 > 0, (i, rows), (c_full, cols), c, out);
            }
        }
    }
}

/// out[i.., j..] (`rows` x `cols` of the block) = (its value so far where `resume`, else 0)
/// + the packed rows of a times the rows of b that `b_row` gives, one shared index at a time.
#[inline(always)]
fn block<'b, const FUSED: bool>(
    panel: &[[f64; ROWS]],
    b_row: impl Fn(usize) -> &'b [f64; COLS],
    resume: bool,
    (i, rows): (usize, usize),
    (j, cols): (usize, usize),
    c: usize,
    out: &mut [f64],
) {
    let mut acc = [[0.0f64; COLS]; ROWS];
    if resume {
        for (row, acc_row) in acc[..rows].iter_mut().enumerate() {
            acc_row[..cols].copy_from_slice(&out[(i + row) * c + j..(i + row) * c + j + cols]);
        }
    }
    for (l, xs) in panel.iter().enumerate() {
        let bl = b_row(l);
        for (acc_row, &x) in acc.iter_mut().zip(xs) {
            for (s, y) in acc_row.iter_mut().zip(bl) {
                *s = mul_add::<FUSED>(x, *y, *s);
            }
        }
    }
    for (row, acc_row) in acc[..rows].iter().enumerate() {
        out[(i + row) * c + j..(i + row) * c + j + cols].copy_from_slice(&acc_row[..cols]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product in the textbook's order of sums, for shapes on and off the kernel's blocks.
    #[test]
    fn equals_the_textbook_product_for_any_shape() {
        for &(r, k, c) in &[
            (1, 1, 1),
            (4, 3, 8),
            (5, 7, 9),
            (13, 11, 17),
            (24, 24, 12),
            (3, 0, 5),
            (0, 4, 4),
            (7, 300, 13),
            (12, 513, 16),
        ] {
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

    /// Each value is one chain of multiply-adds in the order of the shared index, whatever the
    /// blocking (rows and columns on and off the kernel's block, a shared dimension over two
    /// packed panels): the same bits as the plain loop, so the exponential does not change with
    /// the kernel.
    #[test]
    fn each_value_is_the_plain_chain_to_the_bit() {
        for &(r, k, c) in &[(6, 5, 8), (13, 11, 17), (212, 212, 212), (212, 212, 106), (9, 600, 3)] {
            let a: Vec<f64> = (0..r * k).map(|v| ((v * 37 % 101) as f64 - 50.0) / 7.3).collect();
            let b: Vec<f64> = (0..k * c).map(|v| ((v * 53 % 97) as f64 - 48.0) / 11.9).collect();
            let mut generic = vec![f64::NAN; r * c];
            blocked::<false>(r, k, c, &a, &b, &mut generic);
            let mut fused = vec![f64::NAN; r * c];
            blocked::<true>(r, k, c, &a, &b, &mut fused);
            assert_eq!((generic.len(), fused.len()), (r * c, r * c));
            for i in 0..r {
                for j in 0..c {
                    let (mut plain, mut chain) = (0.0f64, 0.0f64);
                    for l in 0..k {
                        plain += a[i * k + l] * b[l * c + j];
                        chain = a[i * k + l].mul_add(b[l * c + j], chain);
                    }
                    assert_eq!(generic[i * c + j].to_bits(), plain.to_bits(), "{r}x{k}x{c} [{i},{j}]");
                    assert_eq!(fused[i * c + j].to_bits(), chain.to_bits(), "{r}x{k}x{c} [{i},{j}]");
                }
            }
        }
    }
}
