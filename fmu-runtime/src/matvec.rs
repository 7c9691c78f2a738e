//! Row-major matrix times vector, the step's hot loop: the coupled transition [P | G1] and G2
//! applied to the state and the load, and the coupling's drift force. Four rows at a time, each
//! with four partial sums, so that sixteen multiply-adds are in flight: one row's dot product
//! alone waits on its own sums (at 20 modes the transition's 52 rows of 78 values took 1.6 us
//! that way, where the values are in the first-level cache). Compiled a second time with AVX2
//! and fused multiply-adds, chosen at run time as in [`crate::matmul`]. Nothing is allocated.

/// What the product does with `out`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Store {
    /// out[i] = a_i . x
    Set,
    /// out[i] += s (a_i . x)
    AddScaled(f64),
}

/// out[i] (see [`Store`]) for the rows i < out.len() of `a`, `lda` values apart, each of x.len()
/// values.
pub fn mat_vec((a, lda): (&[f64], usize), x: &[f64], out: &mut [f64], mode: Store) {
    let (rows, k) = (out.len(), x.len());
    assert!(rows == 0 || (lda >= k && a.len() >= (rows - 1) * lda + k), "mat_vec: operands too short");
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the processor has the features the function is compiled for
            unsafe { mat_vec_fma(a, lda, x, out, mode) };
            return;
        }
    }
    rows_by_four::<false>(a, lda, x, out, mode);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn mat_vec_fma(a: &[f64], lda: usize, x: &[f64], out: &mut [f64], mode: Store) {
    rows_by_four::<true>(a, lda, x, out, mode);
}

#[inline(always)]
fn mul_add<const FUSED: bool>(x: f64, y: f64, acc: f64) -> f64 {
    if FUSED { x.mul_add(y, acc) } else { acc + x * y }
}

#[inline(always)]
fn rows_by_four<const FUSED: bool>(a: &[f64], lda: usize, x: &[f64], out: &mut [f64], mode: Store) {
    let k = x.len();
    let row = |i: usize| &a[i * lda..i * lda + k];
    let done = out.len() - out.len() % 4;
    for (b, o) in out.chunks_exact_mut(4).enumerate() {
        let i = 4 * b;
        let rows = [row(i), row(i + 1), row(i + 2), row(i + 3)];
        let mut acc = [[0.0f64; 4]; 4];
        let xs = x.chunks_exact(4);
        for (j, xc) in xs.enumerate() {
            for (r, acc_r) in rows.iter().zip(acc.iter_mut()) {
                let rc = &r[4 * j..4 * j + 4];
                for l in 0..4 {
                    acc_r[l] = mul_add::<FUSED>(rc[l], xc[l], acc_r[l]);
                }
            }
        }
        let tail = k - k % 4;
        for ((o, r), acc_r) in o.iter_mut().zip(rows).zip(acc.iter()) {
            let mut s = (acc_r[0] + acc_r[1]) + (acc_r[2] + acc_r[3]);
            for j in tail..k {
                s = mul_add::<FUSED>(r[j], x[j], s);
            }
            store(o, s, mode);
        }
    }
    for (i, o) in out.iter_mut().enumerate().skip(done) {
        let r = row(i);
        let mut acc = [0.0f64; 4];
        for (rc, xc) in r.chunks_exact(4).zip(x.chunks_exact(4)) {
            for l in 0..4 {
                acc[l] = mul_add::<FUSED>(rc[l], xc[l], acc[l]);
            }
        }
        let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        for j in k - k % 4..k {
            s = mul_add::<FUSED>(r[j], x[j], s);
        }
        store(o, s, mode);
    }
}

#[inline(always)]
fn store(o: &mut f64, s: f64, mode: Store) {
    match mode {
        Store::Set => *o = s,
        Store::AddScaled(c) => *o += c * s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row count and length around the blocks of four (and none), rows apart by more than
    /// their length, both ways of storing: against the textbook sum, to round-off of k terms in
    /// another order (1e-15 per term, as for the products of `matmul`).
    #[test]
    fn equals_the_textbook_product_for_any_shape() {
        for rows in [0usize, 1, 3, 4, 5, 8, 13, 52] {
            for k in [0usize, 1, 3, 4, 7, 78, 106] {
                let lda = k + 5;
                let a: Vec<f64> = (0..rows * lda).map(|v| ((v * 37 % 101) as f64 - 50.0) / 7.3).collect();
                let x: Vec<f64> = (0..k).map(|v| ((v * 53 % 97) as f64 - 48.0) / 11.9).collect();
                let expected: Vec<f64> = (0..rows).map(|i| (0..k).map(|j| a[i * lda + j] * x[j]).sum()).collect();
                let scale: Vec<f64> =
                    (0..rows).map(|i| (0..k).map(|j| (a[i * lda + j] * x[j]).abs()).sum::<f64>().max(1e-300)).collect();
                let mut set = vec![f64::NAN; rows];
                mat_vec((&a, lda), &x, &mut set, Store::Set);
                let mut added = vec![1.5; rows];
                mat_vec((&a, lda), &x, &mut added, Store::AddScaled(-2.0));
                let mut generic = vec![f64::NAN; rows];
                rows_by_four::<false>(&a, lda, &x, &mut generic, Store::Set);
                assert_eq!((set.len(), added.len(), generic.len()), (rows, rows, rows));
                for i in 0..rows {
                    let tolerance = 1e-15 * (k as f64).max(1.0) * scale[i];
                    assert!(
                        (set[i] - expected[i]).abs() <= tolerance,
                        "{rows}x{k} row {i}: {} vs {}",
                        set[i],
                        expected[i]
                    );
                    assert!((generic[i] - expected[i]).abs() <= tolerance, "{rows}x{k} row {i} (generic)");
                    let want = 1.5 - 2.0 * expected[i];
                    assert!(
                        (added[i] - want).abs() <= 2.0 * tolerance + 1e-15,
                        "{rows}x{k} row {i}: added {}",
                        added[i]
                    );
                }
            }
        }
    }
}
