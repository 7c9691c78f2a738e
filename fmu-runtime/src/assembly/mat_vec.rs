//! Products of a constant row-major matrix with a vector, the inner loop of a flexible body's
//! inertia in an assembly (C_r(q) = C_r0 + [G_a q], the O_ab sums times q, G_a q'): about half
//! of a Newton iteration's work.
//!
//! Each row's dot product is summed in four interleaved partial sums, combined as
//! (s0 + s1) + (s2 + s3), then the rows' last n mod 4 terms in order: the order of
//! [`crate::body::dense::dot`]. On a processor with AVX2 and FMA (checked once, at run time: the
//! FMU's binary is built for any x86-64) four rows go at once, their partial sums in one
//! register each and multiply-adds fused (one rounding instead of two); elsewhere the same
//! order in plain arithmetic.

use crate::body::dense::dot;

/// out[i] = m[i * stride..][..x.len()] . x for i < out.len().
pub fn mat_vec(m: &[f64], stride: usize, x: &[f64], out: &mut [f64]) {
    let cols = x.len();
    assert!(cols <= stride && (out.is_empty() || m.len() >= (out.len() - 1) * stride + cols));
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        // SAFETY: the features are present, and the bounds were checked above.
        unsafe { fused::mat_vec(m, stride, x, out) };
        return;
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = dot(&m[i * stride..i * stride + cols], x);
    }
}

#[cfg(target_arch = "x86_64")]
mod fused {
    use std::arch::x86_64::*;

    /// [`super::mat_vec`] four rows at a time. Safety: AVX2 and FMA present; m holds
    /// (out.len() - 1) * stride + x.len() values.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn mat_vec(m: &[f64], stride: usize, x: &[f64], out: &mut [f64]) {
        let cols = x.len();
        let full = cols - cols % 4;
        let rows = out.len();
        let (m, xp) = (m.as_ptr(), x.as_ptr());
        let mut i = 0;
        while i + 4 <= rows {
            unsafe {
                let r = [m.add(i * stride), m.add((i + 1) * stride), m.add((i + 2) * stride), m.add((i + 3) * stride)];
                let mut acc = [_mm256_setzero_pd(); 4];
                let mut j = 0;
                while j < full {
                    let v = _mm256_loadu_pd(xp.add(j));
                    for k in 0..4 {
                        acc[k] = _mm256_fmadd_pd(_mm256_loadu_pd(r[k].add(j)), v, acc[k]);
                    }
                    j += 4;
                }
                // [s0 + s1 of rows 0, 1, s2 + s3 of rows 0, 1] and the same of rows 2, 3
                let h01 = _mm256_hadd_pd(acc[0], acc[1]);
                let h23 = _mm256_hadd_pd(acc[2], acc[3]);
                let sums =
                    _mm256_add_pd(_mm256_permute2f128_pd(h01, h23, 0x20), _mm256_permute2f128_pd(h01, h23, 0x31));
                let mut s = [0.0; 4];
                _mm256_storeu_pd(s.as_mut_ptr(), sums);
                for k in 0..4 {
                    for jj in full..cols {
                        s[k] += *r[k].add(jj) * x[jj];
                    }
                    out[i + k] = s[k];
                }
            }
            i += 4;
        }
        while i < rows {
            out[i] = unsafe { single_row(m.add(i * stride), x) };
            i += 1;
        }
    }

    /// One row's dot product in the same order. Safety: AVX2 and FMA; x.len() values at `row`.
    #[target_feature(enable = "avx2,fma")]
    unsafe fn single_row(row: *const f64, x: &[f64]) -> f64 {
        let cols = x.len();
        let full = cols - cols % 4;
        let mut acc = _mm256_setzero_pd();
        let mut j = 0;
        unsafe {
            while j < full {
                acc = _mm256_fmadd_pd(_mm256_loadu_pd(row.add(j)), _mm256_loadu_pd(x.as_ptr().add(j)), acc);
                j += 4;
            }
            let mut l = [0.0; 4];
            _mm256_storeu_pd(l.as_mut_ptr(), acc);
            let mut s = (l[0] + l[1]) + (l[2] + l[3]);
            for jj in full..cols {
                s += *row.add(jj) * x[jj];
            }
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_is_its_dot_product_to_rounding() {
        for (rows, cols, stride) in [(0, 3, 3), (1, 1, 1), (3, 5, 7), (4, 8, 8), (7, 18, 18), (18, 13, 18), (9, 2, 4)] {
            let m: Vec<f64> = (0..rows * stride + cols).map(|i| ((i * 37 % 101) as f64 - 50.0) * 0.013).collect();
            let x: Vec<f64> = (0..cols).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut out = vec![f64::NAN; rows];
            mat_vec(&m, stride, &x, &mut out);
            for i in 0..rows {
                let row = &m[i * stride..i * stride + cols];
                let exact: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
                let size: f64 = row.iter().zip(&x).map(|(a, b)| (a * b).abs()).sum();
                // a few roundings of the terms' magnitude, fused or not
                assert!(
                    (out[i] - exact).abs() <= 8.0 * f64::EPSILON * size.max(f64::MIN_POSITIVE),
                    "{rows} x {cols}: row {i}"
                );
            }
        }
    }
}
