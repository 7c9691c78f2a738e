//! Sparse matrix times dense block, summed in double-double.

use super::Sparse;
use crate::dot2::add_product;
use faer::{Mat, MatRef};

/// C + sign * A X, each entry accumulated in double-double (Ogita-Rump-Oishi Dot2: exact products
/// by FMA, error-free sums) and rounded once. Stiffness matrices of slender parts multiply static
/// shapes into reactions that are 1e-6 of the terms summed; plain sums would lose those digits.
///
/// The residual of every refined solve is one of these, so it is made fast: columns go in groups
/// of at most `GROUP` (A is read once per group, the group's sums of one row side by side, a
/// fixed width the compiler unrolls into vector instructions), as many groups as it takes to
/// give every thread one (26 columns on two threads: four of 7, 7, 6, 6, not 8, 8, 8, 2), groups
/// on rayon's threads, and the product's rounding error is one FMA instruction where the CPU has
/// it.
pub fn mul_compensated(c: Option<MatRef<'_, f64>>, sign: f64, a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    use rayon::prelude::*;
    let (n, k) = (a.nrows(), x.ncols());
    let mut out = Mat::<f64>::zeros(n, k);
    if k == 0 {
        return out;
    }
    let threads = rayon::current_num_threads().max(1);
    let count = k.div_ceil(GROUP).next_multiple_of(threads).min(k);
    let groups: Vec<(usize, usize)> = (0..count).map(|g| (g * k / count, (g + 1) * k / count)).collect();
    let columns: Vec<Mat<f64>> = groups
        .par_iter()
        .map(|&(first, end)| {
            let c = c.map(|c| c.subcols(first, end - first));
            compensated_group(c, sign, a, x.subcols(first, end - first))
        })
        .collect();
    for (&(first, _), group) in groups.iter().zip(&columns) {
        out.as_mut().subcols_mut(first, group.ncols()).copy_from(group);
    }
    out
}

/// Most columns summed side by side: enough to amortise reading A, few enough for the running
/// sums of a row to stay in one cache line pair.
const GROUP: usize = 8;

/// A group of at most `GROUP` columns, at the narrowest fixed width that holds it.
fn compensated_group(c: Option<MatRef<'_, f64>>, sign: f64, a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    match x.ncols() {
        0..=1 => compensated_width::<1>(c, sign, a, x),
        2 => compensated_width::<2>(c, sign, a, x),
        3..=4 => compensated_width::<4>(c, sign, a, x),
        _ => compensated_width::<GROUP>(c, sign, a, x),
    }
}

fn compensated_width<const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has the FMA instructions the function is compiled for
        return unsafe { compensated_fma::<W>(c, sign, a, x) };
    }
    compensated_generic::<false, W>(c, sign, a, x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn compensated_fma<const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    compensated_generic::<true, W>(c, sign, a, x)
}

/// `x` has at most W columns; the rest of the width is zero.
#[inline(always)]
pub(super) fn compensated_generic<const FMA: bool, const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    let (n, w) = (a.nrows(), x.ncols());
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    // running sums row-major: row i's W sums side by side
    let mut hi = vec![[0.0; W]; n];
    let mut lo = vec![[0.0; W]; n];
    if let Some(c) = c {
        for col in 0..w {
            for (i, h) in hi.iter_mut().enumerate() {
                h[col] = c[(i, col)];
            }
        }
    }
    let mut xj = [0.0; W];
    for j in 0..a.ncols() {
        let mut any = false;
        for col in 0..w {
            xj[col] = sign * x[(j, col)];
            any |= xj[col] != 0.0;
        }
        if !any {
            continue;
        }
        for p in col_ptr[j]..col_ptr[j + 1] {
            let i = row_idx[p];
            let aij = val[p];
            let (hi, lo) = (&mut hi[i], &mut lo[i]);
            for col in 0..W {
                add_product::<FMA>(&mut hi[col], &mut lo[col], aij, xj[col]);
            }
        }
    }
    Mat::from_fn(n, w, |i, col| hi[i][col] + lo[i][col])
}
