//! Small 3-vector and rotation helpers for the body equations (row-major 3x3 matrices), generic
//! over the scalar so the same formulas give values and directional derivatives.

use crate::scalar::{Scalar, c};

pub type Vec3<T = f64> = [T; 3];
pub type Mat3<T = f64> = [T; 9];

pub const IDENTITY: Mat3 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

#[inline]
pub fn cross<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub fn add<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn sub<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> Vec3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn scale<T: Scalar>(s: T, a: Vec3<T>) -> Vec3<T> {
    [s * a[0], s * a[1], s * a[2]]
}

/// A x
#[inline]
pub fn mul<T: Scalar>(a: &Mat3<T>, x: Vec3<T>) -> Vec3<T> {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[3] * x[0] + a[4] * x[1] + a[5] * x[2],
        a[6] * x[0] + a[7] * x[1] + a[8] * x[2],
    ]
}

/// A^T x
#[inline]
pub fn mul_t<T: Scalar>(a: &Mat3<T>, x: Vec3<T>) -> Vec3<T> {
    [
        a[0] * x[0] + a[3] * x[1] + a[6] * x[2],
        a[1] * x[0] + a[4] * x[1] + a[7] * x[2],
        a[2] * x[0] + a[5] * x[1] + a[8] * x[2],
    ]
}

pub fn mat_mul<T: Scalar>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    std::array::from_fn(|ij| {
        let (i, j) = (ij / 3, ij % 3);
        a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j]
    })
}

/// Rotation matrix of the rotation vector phi (Rodrigues): exactly orthonormal for any size, so a
/// flange frame output is always a proper rotation even though the model is linear in phi.
pub fn rotation_of<T: Scalar>(phi: Vec3<T>) -> Mat3<T> {
    let t2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    // the series in t^2 keeps small angles (and their derivatives at zero) exact
    let (a, b) = if t2.value() < 1e-8 {
        (c::<T>(1.0) - t2 / 6.0 + t2 * t2 / 120.0, c::<T>(0.5) - t2 / 24.0 + t2 * t2 / 720.0)
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (c::<T>(1.0) - t.cos()) / t2)
    };
    let [x, y, z] = phi;
    let one = c::<T>(1.0);
    [
        one - b * (y * y + z * z),
        -(a * z) + b * x * y,
        a * y + b * x * z,
        a * z + b * x * y,
        one - b * (x * x + z * z),
        -(a * x) + b * y * z,
        -(a * y) + b * x * z,
        a * x + b * y * z,
        one - b * (x * x + y * y),
    ]
}

#[inline]
pub fn dot<T: Scalar>(a: Vec3<T>, b: Vec3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Rotation matrix of a unit quaternion (w, x, y, z).
pub fn rotation_of_quaternion<T: Scalar>(q: [T; 4]) -> Mat3<T> {
    let [w, x, y, z] = q;
    let one = c::<T>(1.0);
    [
        one - (y * y + z * z) * 2.0,
        (x * y - w * z) * 2.0,
        (x * z + w * y) * 2.0,
        (x * y + w * z) * 2.0,
        one - (x * x + z * z) * 2.0,
        (y * z - w * x) * 2.0,
        (x * z - w * y) * 2.0,
        (y * z + w * x) * 2.0,
        one - (x * x + y * y) * 2.0,
    ]
}

/// Unit quaternion (w, x, y, z, w >= 0) of a rotation matrix (Shepperd's method).
pub fn quaternion_of(a: &Mat3) -> [f64; 4] {
    let tr = a[0] + a[4] + a[8];
    let q = if tr > 0.0 {
        let s = 2.0 * (1.0 + tr).sqrt();
        [0.25 * s, (a[7] - a[5]) / s, (a[2] - a[6]) / s, (a[3] - a[1]) / s]
    } else if a[0] > a[4] && a[0] > a[8] {
        let s = 2.0 * (1.0 + a[0] - a[4] - a[8]).sqrt();
        [(a[7] - a[5]) / s, 0.25 * s, (a[1] + a[3]) / s, (a[2] + a[6]) / s]
    } else if a[4] > a[8] {
        let s = 2.0 * (1.0 + a[4] - a[0] - a[8]).sqrt();
        [(a[2] - a[6]) / s, (a[1] + a[3]) / s, 0.25 * s, (a[5] + a[7]) / s]
    } else {
        let s = 2.0 * (1.0 + a[8] - a[0] - a[4]).sqrt();
        [(a[3] - a[1]) / s, (a[2] + a[6]) / s, (a[5] + a[7]) / s, 0.25 * s]
    };
    if q[0] < 0.0 { q.map(|c| -c) } else { q }
}

/// Hamilton product a (x) b of quaternions (w, x, y, z).
pub fn quaternion_multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The rotation nearest to a nearly orthonormal A (orthogonal polar factor, by Newton's iteration
/// X <- (X + X^-T) / 2, quadratically convergent from near a rotation).
pub fn nearest_rotation<T: Scalar>(a: &Mat3<T>) -> Mat3<T> {
    let mut x = *a;
    for _ in 0..8 {
        let det = x[0] * (x[4] * x[8] - x[5] * x[7]) - x[1] * (x[3] * x[8] - x[5] * x[6])
            + x[2] * (x[3] * x[7] - x[4] * x[6]);
        // X^-T = cof(X) / det
        let cof = [
            x[4] * x[8] - x[5] * x[7],
            x[5] * x[6] - x[3] * x[8],
            x[3] * x[7] - x[4] * x[6],
            x[2] * x[7] - x[1] * x[8],
            x[0] * x[8] - x[2] * x[6],
            x[1] * x[6] - x[0] * x[7],
            x[1] * x[5] - x[2] * x[4],
            x[2] * x[3] - x[0] * x[5],
            x[0] * x[4] - x[1] * x[3],
        ];
        let next: Mat3<T> = std::array::from_fn(|i| (x[i] + cof[i] / det) * 0.5);
        // converged in value; a derivative converges with it (it follows the same contraction,
        // and at a rotation one iteration removes its symmetric part exactly)
        let change = next.iter().zip(&x).fold(0.0f64, |m, (p, q)| m.max((p.value() - q.value()).abs()));
        x = next;
        if change < 1e-16 {
            break;
        }
    }
    x
}

/// Largest entry of |A^T A - I| and whether det A > 0: how far an input is from a rotation.
pub fn rotation_defect(a: &Mat3) -> f64 {
    let mut worst: f64 = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| a[3 * k + i] * a[3 * k + j]).sum();
            worst = worst.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    let det =
        a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
    if det <= 0.0 { f64::INFINITY } else { worst }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rotation_repairs_interpolated_matrices() {
        // entrywise average of two rotations 0.1 rad apart: off orthonormal by ~1e-3
        let (r1, r2) = (rotation_of([0.0, 0.0, 0.3]), rotation_of([0.0, 0.0, 0.4]));
        let mean: Mat3 = std::array::from_fn(|i| 0.5 * (r1[i] + r2[i]));
        assert!(rotation_defect(&mean) > 1e-3);
        let fixed = nearest_rotation(&mean);
        assert!(rotation_defect(&fixed) < 1e-15);
        let expected = rotation_of([0.0, 0.0, 0.35]);
        for i in 0..9 {
            assert!((fixed[i] - expected[i]).abs() < 1e-15);
        }
    }

    #[test]
    fn rodrigues_is_orthonormal_and_rotates_about_its_axis() {
        for phi in [[0.0, 0.0, 0.0], [1e-6, -2e-6, 3e-7], [0.3, -0.2, 1.1], [0.0, 0.0, std::f64::consts::FRAC_PI_2]] {
            let r = rotation_of(phi);
            assert!(rotation_defect(&r) < 1e-14);
            let back = mul(&r, phi);
            for i in 0..3 {
                assert!((back[i] - phi[i]).abs() < 1e-14);
            }
        }
        for phi in [[0.3, -0.2, 1.1], [3.0, 0.1, 0.0], [0.0, -3.1, 0.2], [0.1, 0.0, 3.1]] {
            let r = rotation_of(phi);
            let back = rotation_of_quaternion(quaternion_of(&r));
            for i in 0..9 {
                assert!((back[i] - r[i]).abs() < 1e-14, "{phi:?}");
            }
        }
        let r = rotation_of([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let ex = mul(&r, [1.0, 0.0, 0.0]);
        assert!((ex[1] - 1.0).abs() < 1e-15 && ex[0].abs() < 1e-15);
    }
}
