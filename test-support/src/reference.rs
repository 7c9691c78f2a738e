//! Reference computations for tests, by textbook methods that share nothing with the code under
//! test.

/// Eigenvalues of the symmetric n x n row-major `a`, ascending, by cyclic Jacobi rotations
/// (sweeps until the off-diagonal part is below 1e-15 of the diagonal, in norm).
pub fn jacobi_eigenvalues(mut a: Vec<f64>, n: usize) -> Vec<f64> {
    assert_eq!(a.len(), n * n, "jacobi_eigenvalues: a is not n x n");
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-30 * diag {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    let mut ev: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
    ev.sort_by(f64::total_cmp);
    ev
}

#[cfg(test)]
mod tests {
    /// A diagonal matrix seen in another orthonormal basis gives back its diagonal:
    /// H diag(d) H with H = I - 2 u u^T / |u|^2 (a reflection).
    #[test]
    fn a_reflected_diagonal_gives_back_its_values() {
        let n = 5;
        let d = [-3.0, 0.5, 1.0, 2.0, 7.5];
        let u = [0.3, -1.0, 0.8, 2.0, -0.4];
        let uu: f64 = u.iter().map(|x| x * x).sum();
        let h = |i: usize, j: usize| f64::from(u8::from(i == j)) - 2.0 * u[i] * u[j] / uu;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n).map(|k| h(i, k) * d[k] * h(k, j)).sum();
            }
        }
        let ev = super::jacobi_eigenvalues(a, n);
        assert_eq!(ev.len(), n);
        for (e, x) in ev.iter().zip(d) {
            // round-off of a few rotations of values up to 7.5
            assert!((e - x).abs() < 1e-13, "{e} vs {x}");
        }
    }
}
