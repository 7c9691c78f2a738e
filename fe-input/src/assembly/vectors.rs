//! The little 3-vector algebra an assembly's input needs: norms, normalising, rotation matrices
//! (row-major `[f64; 9]`) and the principal values of a symmetric 3x3 matrix.

pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a` at unit length (`a` must not be zero).
pub fn normalised(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    a.map(|c| c / n)
}

pub const IDENTITY: [f64; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

/// The rotation by `angle_deg` degrees (right-handed) about `axis` (not zero; any length), by
/// Rodrigues' formula R = cos(a) I + sin(a) [k]x + (1 - cos(a)) k k^T, row-major.
pub fn rotation_matrix(axis: [f64; 3], angle_deg: f64) -> [f64; 9] {
    let k = normalised(axis);
    let a = angle_deg.to_radians();
    let (s, c) = a.sin_cos();
    let t = 1.0 - c;
    [
        c + t * k[0] * k[0],
        t * k[0] * k[1] - s * k[2],
        t * k[0] * k[2] + s * k[1],
        t * k[1] * k[0] + s * k[2],
        c + t * k[1] * k[1],
        t * k[1] * k[2] - s * k[0],
        t * k[2] * k[0] - s * k[1],
        t * k[2] * k[1] + s * k[0],
        c + t * k[2] * k[2],
    ]
}

/// The eigenvalues, ascending, of the symmetric matrix [[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]]
/// given as [xx, yy, zz, xy, yz, zx] (the trigonometric solution of the characteristic cubic).
pub fn symmetric_eigenvalues(m: [f64; 6]) -> [f64; 3] {
    let [xx, yy, zz, xy, yz, zx] = m;
    let off = xy * xy + yz * yz + zx * zx;
    let q = (xx + yy + zz) / 3.0;
    let p2 = (xx - q).powi(2) + (yy - q).powi(2) + (zz - q).powi(2) + 2.0 * off;
    if p2 == 0.0 || off == 0.0 {
        let mut d = [xx, yy, zz];
        d.sort_by(f64::total_cmp);
        return d;
    }
    let p = (p2 / 6.0).sqrt();
    let (bxx, byy, bzz, bxy, byz, bzx) = ((xx - q) / p, (yy - q) / p, (zz - q) / p, xy / p, yz / p, zx / p);
    let det = bxx * (byy * bzz - byz * byz) - bxy * (bxy * bzz - byz * bzx) + bzx * (bxy * byz - byy * bzx);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    let mid = 3.0 * q - hi - lo;
    let mut e = [lo, mid, hi];
    e.sort_by(f64::total_cmp);
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(r: &[f64; 9], v: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| r[3 * i] * v[0] + r[3 * i + 1] * v[1] + r[3 * i + 2] * v[2])
    }

    #[test]
    fn rotations_turn_the_right_way() {
        // 90 degrees about z takes x to y; 45 about y takes x to (1, 0, -1)/sqrt 2
        let r = rotation_matrix([0.0, 0.0, 2.0], 90.0);
        let v = apply(&r, [1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-15 && (v[1] - 1.0).abs() < 1e-15 && v[2].abs() < 1e-15, "{v:?}");
        let v = apply(&rotation_matrix([0.0, 1.0, 0.0], 45.0), [1.0, 0.0, 0.0]);
        let h = 0.5f64.sqrt();
        assert!((v[0] - h).abs() < 1e-15 && v[1].abs() < 1e-15 && (v[2] + h).abs() < 1e-15, "{v:?}");
        assert_eq!(rotation_matrix([1.0, 1.0, 1.0], 0.0), IDENTITY);
    }

    #[test]
    fn eigenvalues_of_a_rotated_diagonal() {
        // diag(1, 2, 3) turned by 30 degrees about z: xx = 1.25, yy = 1.75, xy = sqrt(3)/4
        let s = 3f64.sqrt() / 4.0;
        let e = symmetric_eigenvalues([1.25, 1.75, 3.0, s, 0.0, 0.0]);
        for (got, want) in e.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-14, "{e:?}");
        }
        assert_eq!(symmetric_eigenvalues([3.0, 1.0, 2.0, 0.0, 0.0, 0.0]), [1.0, 2.0, 3.0]);
    }
}
