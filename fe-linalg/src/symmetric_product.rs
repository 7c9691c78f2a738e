//! Products with exactly symmetric sparse matrices (stiffness, mass and their blocks, which
//! assembly and rigid coupling make exactly symmetric) in gather form: column i of A is its row
//! i, so every entry of A X is one sum over a column of A with the rows of X it names, kept in
//! registers and written once. The general (scatter) products of `sparse` add into every output
//! row many times over, and the running sums of a compensated product then miss the cache on
//! each addition (249k-DoF bracket, 26 columns: 1.07 s compensated, 0.20 s plain).
//!
//! Where X has fewer rows than A (k), the products are those of A's leading block A[0..k, 0..k]
//! (the mass of a mounted body inside the whole model's, without a copy of it).
//!
//! X goes to the kernel in groups of at most `GROUP` columns, copied row by row so that a
//! row's group is one cache line pair; the rows of the output are split between the threads by
//! entries of A, so A is read once per group in all.

use crate::dot2::add_product;
use faer::reborrow::ReborrowMut;
use faer::sparse::SparseColMat;
use faer::{Mat, MatMut, MatRef};

/// Most columns per group: one row of a group fills two cache lines, and its sums (with their
/// compensation, four 256-bit registers each) stay in registers.
const GROUP: usize = 16;

/// out = A x, A exactly symmetric.
pub fn mul(out: MatMut<'_, f64>, a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) {
    product(out, false, 1.0, a, x, false);
}

pub fn mul_new(a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(x.nrows(), x.ncols());
    mul(out.as_mut(), a, x);
    out
}

/// C + sign * A X, A exactly symmetric, every entry accumulated in double-double and rounded
/// once (`sparse::mul_compensated`'s arithmetic, Ogita-Rump-Oishi Dot2).
pub fn mul_compensated(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    let mut out = match c {
        Some(c) => c.to_owned(),
        None => Mat::zeros(x.nrows(), x.ncols()),
    };
    product(out.as_mut(), c.is_some(), sign, a, x, true);
    out
}

/// r - A X in place of r (each row read before it is written), A exactly symmetric, in
/// double-double as `mul_compensated`: a residual without a copy of the right-hand sides.
pub fn subtract_compensated(r: MatMut<'_, f64>, a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) {
    product(r, true, -1.0, a, x, true);
}

/// out = A x times sign, plus out's own entries where `accumulate`.
fn product(
    mut out: MatMut<'_, f64>,
    accumulate: bool,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: MatRef<'_, f64>,
    compensated: bool,
) {
    let (n, k) = (x.nrows(), x.ncols());
    debug_assert_eq!(a.ncols(), a.nrows(), "a symmetric matrix is square");
    debug_assert!(n <= a.nrows() && out.nrows() == n);
    if k == 0 || n == 0 {
        return;
    }
    let groups = k.div_ceil(GROUP);
    let threads = rayon::current_num_threads().clamp(1, 8);
    let col_ptr = a.symbolic().col_ptr();
    // row ranges of about equal entries of A, one per thread
    let mut bounds = vec![0usize];
    for t in 1..threads {
        let target = col_ptr[n] * t / threads;
        let row = col_ptr.partition_point(|&p| p < target).min(n);
        bounds.push(row.max(*bounds.last().unwrap_or(&0)));
    }
    bounds.push(n);
    for g in 0..groups {
        let (first, end) = (g * k / groups, (g + 1) * k / groups);
        let w = end - first;
        let xg = x.subcols(first, w);
        let og = out.rb_mut().subcols_mut(first, w);
        // the group's own width: wider rows would be read (and gathered) for nothing
        match w {
            0..=1 => group::<1>(og, accumulate, sign, a, xg, compensated, &bounds),
            2 => group::<2>(og, accumulate, sign, a, xg, compensated, &bounds),
            3 => group::<3>(og, accumulate, sign, a, xg, compensated, &bounds),
            4 => group::<4>(og, accumulate, sign, a, xg, compensated, &bounds),
            5 => group::<5>(og, accumulate, sign, a, xg, compensated, &bounds),
            6 => group::<6>(og, accumulate, sign, a, xg, compensated, &bounds),
            7 => group::<7>(og, accumulate, sign, a, xg, compensated, &bounds),
            8 => group::<8>(og, accumulate, sign, a, xg, compensated, &bounds),
            9 => group::<9>(og, accumulate, sign, a, xg, compensated, &bounds),
            10 => group::<10>(og, accumulate, sign, a, xg, compensated, &bounds),
            11 => group::<11>(og, accumulate, sign, a, xg, compensated, &bounds),
            12 => group::<12>(og, accumulate, sign, a, xg, compensated, &bounds),
            13 => group::<13>(og, accumulate, sign, a, xg, compensated, &bounds),
            14 => group::<14>(og, accumulate, sign, a, xg, compensated, &bounds),
            15 => group::<15>(og, accumulate, sign, a, xg, compensated, &bounds),
            _ => group::<GROUP>(og, accumulate, sign, a, xg, compensated, &bounds),
        }
    }
}

/// One group of at most W columns: X copied row by row (zero beyond its width), the output's
/// rows split at `bounds` between the threads.
fn group<const W: usize>(
    out: MatMut<'_, f64>,
    accumulate: bool,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: MatRef<'_, f64>,
    compensated: bool,
    bounds: &[usize],
) {
    // A's rows: X's rows beyond its own are zero (the leading-block product)
    let (n, m) = (a.nrows(), x.nrows());
    let w = x.ncols();
    // the copy goes row by row (each column of X one sequential stream), on every thread, into
    // the calling thread's buffer (`PACKED`)
    PACKED.with_borrow_mut(|buffer| {
        if buffer.len() < n * W {
            buffer.clear();
            buffer.resize(n * W, 0.0);
        }
        let (rows, _) = buffer[..n * W].as_chunks_mut::<W>();
        let chunk = n.div_ceil(bounds.len() - 1).max(1);
        rayon::scope(|s| {
            for (c, part) in rows.chunks_mut(chunk).enumerate() {
                s.spawn(move |_| {
                    let first = c * chunk;
                    for (r, row) in part.iter_mut().enumerate() {
                        let i = first + r;
                        for (col, v) in row.iter_mut().enumerate() {
                            *v = if col < w && i < m { x[(i, col)] } else { 0.0 };
                        }
                    }
                });
            }
        });
        let rows = &*rows;
        // the output split into the threads' row ranges, each range written by one thread
        let mut parts = Vec::with_capacity(bounds.len() - 1);
        let mut rest = out;
        for pair in bounds.windows(2).rev() {
            let (head, tail) = rest.split_at_row_mut(pair[0]);
            parts.push((pair[0], tail));
            rest = head;
        }
        rayon::scope(|s| {
            for (start, part) in parts {
                s.spawn(move |_| thread_rows::<W>(part, accumulate, compensated, start, sign, a, rows));
            }
        });
    });
}

thread_local! {
    /// The packed rows of X, kept between products: a fresh n x 16 block each time had its
    /// pages faulted in anew (10 ms of a 30 ms product with the 249k-DoF bracket's mass; the
    /// Lanczos orthogonalisation 3.3 -> 2.7 s). At most 16 doubles per row of the largest
    /// matrix multiplied (32 MB at 249k DoFs).
    static PACKED: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The output rows of one thread (from row `start` of A): dispatch to the FMA build of the
/// kernels where the CPU has it.
fn thread_rows<const W: usize>(
    out: MatMut<'_, f64>,
    accumulate: bool,
    compensated: bool,
    start: usize,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: &[[f64; W]],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has the FMA instructions the function is compiled for
        return unsafe { rows_fma::<W>(out, accumulate, compensated, start, sign, a, x) };
    }
    rows_generic::<false, W>(out, accumulate, compensated, start, sign, a, x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn rows_fma<const W: usize>(
    out: MatMut<'_, f64>,
    accumulate: bool,
    compensated: bool,
    start: usize,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: &[[f64; W]],
) {
    rows_generic::<true, W>(out, accumulate, compensated, start, sign, a, x)
}

/// Double-double sums where `compensated` (onto the output's own entries where `accumulate`),
/// plain ones otherwise.
#[inline(always)]
fn rows_generic<const FMA: bool, const W: usize>(
    mut out: MatMut<'_, f64>,
    accumulate: bool,
    compensated: bool,
    start: usize,
    sign: f64,
    a: &SparseColMat<usize, f64>,
    x: &[[f64; W]],
) {
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    let w = out.ncols();
    for r in 0..out.nrows() {
        let i = start + r;
        let entries = col_ptr[i]..col_ptr[i + 1];
        if !compensated {
            let mut sum = [0.0f64; W];
            for p in entries {
                let (aij, xj) = (val[p], &x[row_idx[p]]);
                for col in 0..W {
                    sum[col] += aij * xj[col];
                }
            }
            for (col, s) in sum.iter().enumerate().take(w) {
                out[(r, col)] = sign * s;
            }
            continue;
        }
        let mut hi = [0.0f64; W];
        let mut lo = [0.0f64; W];
        if accumulate {
            for (col, h) in hi.iter_mut().enumerate().take(w) {
                *h = out[(r, col)];
            }
        }
        for p in entries {
            // sign is +-1: the scaled entry is exact
            let (aij, xj) = (sign * val[p], &x[row_idx[p]]);
            for col in 0..W {
                add_product::<FMA>(&mut hi[col], &mut lo[col], aij, xj[col]);
            }
        }
        for col in 0..w {
            out[(r, col)] = hi[col] + lo[col];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// A row whose terms cancel from 1e16 to 1 keeps the 1 when compensated.
    #[test]
    fn compensated_gather_recovers_cancellation() {
        let t = [
            Triplet::new(0, 0, 1e16),
            Triplet::new(0, 1, 1.0),
            Triplet::new(1, 0, 1.0),
            Triplet::new(0, 2, -1e16),
            Triplet::new(2, 0, -1e16),
            Triplet::new(1, 1, 1.0),
            Triplet::new(2, 2, 1.0),
        ];
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
        let ones = Mat::<f64>::from_fn(3, 1, |_, _| 1.0);
        assert_eq!(mul_compensated(None, 1.0, &a, ones.as_ref())[(0, 0)], 1.0);
        assert_ne!(mul_new(&a, ones.as_ref())[(0, 0)], 1.0, "plain sums lose the 1 (else the test proves nothing)");
    }
}
