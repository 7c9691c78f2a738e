//! Small 3-vector and rotation helpers for the body equations (row-major 3x3 matrices).

pub type Vec3 = [f64; 3];
pub type Mat3 = [f64; 9];

pub const IDENTITY: Mat3 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

#[inline]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn scale(s: f64, a: Vec3) -> Vec3 {
    [s * a[0], s * a[1], s * a[2]]
}

/// A x
#[inline]
pub fn mul(a: &Mat3, x: Vec3) -> Vec3 {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[3] * x[0] + a[4] * x[1] + a[5] * x[2],
        a[6] * x[0] + a[7] * x[1] + a[8] * x[2],
    ]
}

/// A^T x
#[inline]
pub fn mul_t(a: &Mat3, x: Vec3) -> Vec3 {
    [
        a[0] * x[0] + a[3] * x[1] + a[6] * x[2],
        a[1] * x[0] + a[4] * x[1] + a[7] * x[2],
        a[2] * x[0] + a[5] * x[1] + a[8] * x[2],
    ]
}

pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            c[3 * i + j] = (0..3).map(|k| a[3 * i + k] * b[3 * k + j]).sum();
        }
    }
    c
}

/// Rotation matrix of the rotation vector phi (Rodrigues): exactly orthonormal for any size, so a
/// flange frame output is always a proper rotation even though the model is linear in phi.
pub fn rotation_of(phi: Vec3) -> Mat3 {
    let t2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    let (a, b) = if t2 < 1e-8 {
        (1.0 - t2 / 6.0 + t2 * t2 / 120.0, 0.5 - t2 / 24.0 + t2 * t2 / 720.0)
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let [x, y, z] = phi;
    [
        1.0 - b * (y * y + z * z),
        -a * z + b * x * y,
        a * y + b * x * z,
        a * z + b * x * y,
        1.0 - b * (x * x + z * z),
        -a * x + b * y * z,
        -a * y + b * x * z,
        a * x + b * y * z,
        1.0 - b * (x * x + y * y),
    ]
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
    let det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
        + a[2] * (a[3] * a[7] - a[4] * a[6]);
    if det <= 0.0 { f64::INFINITY } else { worst }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let r = rotation_of([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let ex = mul(&r, [1.0, 0.0, 0.0]);
        assert!((ex[1] - 1.0).abs() < 1e-15 && ex[0].abs() < 1e-15);
    }
}
