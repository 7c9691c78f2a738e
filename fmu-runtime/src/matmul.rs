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
    mat_mul_strided(r, k, c, (a, k), (b, c), (out, c));
}

/// out = a b with rows `lda`, `ldb`, `ldc` values apart (a row's values beyond k, c left alone):
/// rows of whole cache lines (a multiple of 8 values) keep each block's eight columns in one
/// line, where rows of 212 values put every other row's eight across two (a sixth of the time).
pub fn mat_mul_strided(
    r: usize,
    k: usize,
    c: usize,
    (a, lda): (&[f64], usize),
    (b, ldb): (&[f64], usize),
    (out, ldc): (&mut [f64], usize),
) {
    let fits = |len: usize, rows: usize, ld: usize, cols: usize| {
        rows == 0 || cols == 0 || (ld >= cols && len >= (rows - 1) * ld + cols)
    };
    assert!(
        fits(a.len(), r, lda, k) && fits(b.len(), k, ldb, c) && fits(out.len(), r, ldc, c),
        "mat_mul: operands too short"
    );
    let strides = Strides { a: lda, b: ldb, out: ldc };
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the processor has the features the function is compiled for
            unsafe { mat_mul_fma(r, k, c, a, b, out, strides) };
            return;
        }
    }
    blocked::<false>(r, k, c, a, b, out, strides);
}

/// Values between consecutive rows of each operand.
#[derive(Clone, Copy)]
struct Strides {
    a: usize,
    b: usize,
    out: usize,
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn mat_mul_fma(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64], ld: Strides) {
    blocked::<true>(r, k, c, a, b, out, ld);
}

/// acc + x y, fused where `FUSED` (one rounding; a call into libm without the FMA unit, hence
/// the separate instantiation).
#[inline(always)]
fn mul_add<const FUSED: bool>(x: f64, y: f64, acc: f64) -> f64 {
    if FUSED { x.mul_add(y, acc) } else { acc + x * y }
}

#[inline(always)]
fn blocked<const FUSED: bool>(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64], ld: Strides) {
    if r == 0 || c == 0 {
        return;
    }
    if k == 0 {
        for i in 0..r {
            out[i * ld.out..i * ld.out + c].fill(0.0);
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
                let row = &b[(k0 + l) * ld.b + c_full..(k0 + l) * ld.b + c];
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
                    *v = if row < rows { a[(i + row) * ld.a + k0 + l] } else { 0.0 };
                }
            }
            let panel = &a_panel[..depth];
            for j in (0..c_full).step_by(COLS) {
                block::<FUSED>(
                    panel,
                    |l| b[(k0 + l) * ld.b + j..(k0 + l) * ld.b + j + COLS].try_into().expect("COLS values"),
                    k0 > 0,
                    (i, rows),
                    (j, COLS),
                    ld.out,
                    out,
                );
            }
            if cols > 0 {
                let edge = &b_edge[..depth];
                block::<FUSED>(panel, |l| &edge[l], k0 > 0, (i, rows), (c_full, cols), ld.out, out);
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
            blocked::<false>(r, k, c, &a, &b, &mut generic, Strides { a: k, b: c, out: c });
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
            let ld = Strides { a: k, b: c, out: c };
            let mut generic = vec![f64::NAN; r * c];
            blocked::<false>(r, k, c, &a, &b, &mut generic, ld);
            let mut fused = vec![f64::NAN; r * c];
            blocked::<true>(r, k, c, &a, &b, &mut fused, ld);
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

    /// Rows apart by more than their length: the same bits as the packed product, and the
    /// values between the rows left as they were.
    #[test]
    fn strided_rows_give_the_same_product_and_leave_the_gaps() {
        for &(r, k, c) in &[(13usize, 11usize, 17usize), (212, 212, 212), (212, 212, 106), (7, 300, 5)] {
            let (lda, ldb, ldc) = (k.next_multiple_of(8) + 8, c.next_multiple_of(8), c + 3);
            let a: Vec<f64> = (0..r * k).map(|v| ((v * 37 % 101) as f64 - 50.0) / 7.3).collect();
            let b: Vec<f64> = (0..k * c).map(|v| ((v * 53 % 97) as f64 - 48.0) / 11.9).collect();
            let spread = |x: &[f64], rows: usize, cols: usize, ld: usize| -> Vec<f64> {
                let mut y = vec![-7.0; rows * ld];
                for i in 0..rows {
                    y[i * ld..i * ld + cols].copy_from_slice(&x[i * cols..(i + 1) * cols]);
                }
                y
            };
            let (sa, sb) = (spread(&a, r, k, lda), spread(&b, k, c, ldb));
            let mut packed = vec![f64::NAN; r * c];
            mat_mul(r, k, c, &a, &b, &mut packed);
            let mut strided = vec![-3.0; r * ldc];
            mat_mul_strided(r, k, c, (&sa, lda), (&sb, ldb), (&mut strided, ldc));
            assert_eq!(packed.len(), r * c);
            for i in 0..r {
                for j in 0..ldc {
                    let found = strided[i * ldc + j];
                    if j < c {
                        assert_eq!(found.to_bits(), packed[i * c + j].to_bits(), "{r}x{k}x{c} [{i},{j}]");
                    } else {
                        assert_eq!(found, -3.0, "{r}x{k}x{c}: the gap [{i},{j}] was written");
                    }
                }
            }
        }
    }
}
