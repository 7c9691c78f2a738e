//! The body's equations against d'Alembert's principle summed over a cloud of particles with
//! arbitrary mode shapes: the invariants are formed by their definitions, the particles'
//! accelerations by plain kinematics, nothing of the equations' derivation is shared.

use super::*;

/// A deterministic pseudo-random sequence in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn vec3(&mut self) -> Vec3 {
        [self.next(), self.next(), self.next()]
    }
}

pub(crate) struct Cloud {
    pub masses: Vec<f64>,
    pub x: Vec<Vec3>,
    /// shapes[k][p]: mode k's displacement of particle p
    pub shapes: Vec<Vec<Vec3>>,
}

pub(crate) fn cloud(particles: usize, n: usize, seed: u64) -> Cloud {
    let mut rng = Lcg(seed);
    let masses: Vec<f64> = (0..particles).map(|_| 1.0 + 0.5 * rng.next()).collect();
    let x: Vec<Vec3> = (0..particles).map(|_| rng.vec3()).collect();
    let mut shapes: Vec<Vec<Vec3>> = Vec::new();
    for _ in 0..n {
        let mut s: Vec<Vec3> = (0..particles).map(|_| rng.vec3()).collect();
        // mass-orthonormal against the earlier modes (Gram-Schmidt in the particles' mass)
        for prev in &shapes {
            let d: f64 = (0..particles).map(|p| masses[p] * k3::dot(prev[p], s[p])).sum();
            for p in 0..particles {
                s[p] = k3::sub(s[p], k3::scale(d, prev[p]));
            }
        }
        let norm: f64 = (0..particles).map(|p| masses[p] * k3::dot(s[p], s[p])).sum::<f64>().sqrt();
        shapes.push(s.iter().map(|v| k3::scale(1.0 / norm, *v)).collect());
    }
    Cloud { masses, x, shapes }
}

fn e(a: usize) -> Vec3 {
    let mut v = [0.0; 3];
    v[a] = 1.0;
    v
}

/// The invariants of the cloud by their definitions, no stiffness or damping, marker 0 at the
/// origin.
pub(crate) fn inertia_of(c: &Cloud) -> Inertia {
    let (np, n) = (c.masses.len(), c.shapes.len());
    let sum = |f: &dyn Fn(usize) -> f64| (0..np).map(f).sum::<f64>();
    let mass = sum(&|p| c.masses[p]);
    let first_moment: Vec3 = std::array::from_fn(|a| sum(&|p| c.masses[p] * c.x[p][a]));
    let inertia: Mat3 = std::array::from_fn(|ij| {
        let (i, j) = (ij / 3, ij % 3);
        sum(&|p| c.masses[p] * (if i == j { k3::dot(c.x[p], c.x[p]) } else { 0.0 } - c.x[p][i] * c.x[p][j]))
    });
    let mut c_t = vec![0.0; 3 * n];
    let mut c_r = vec![0.0; 3 * n];
    let mut g = vec![0.0; 3 * n * n];
    let mut o_mat = vec![0.0; 9 * n * n];
    let mut o_vec = vec![0.0; 9 * n];
    for k in 0..n {
        for a in 0..3 {
            c_t[a * n + k] = sum(&|p| c.masses[p] * c.shapes[k][p][a]);
            c_r[a * n + k] = sum(&|p| c.masses[p] * k3::cross(c.x[p], c.shapes[k][p])[a]);
            for j in 0..n {
                g[a * n * n + k * n + j] =
                    sum(&|p| c.masses[p] * k3::dot(c.shapes[k][p], k3::cross(e(a), c.shapes[j][p])));
            }
            for b in 0..3 {
                let ab = 3 * a + b;
                o_vec[ab * n + k] =
                    sum(&|p| c.masses[p] * k3::dot(c.shapes[k][p], k3::cross(e(a), k3::cross(e(b), c.x[p]))));
                for j in 0..n {
                    o_mat[ab * n * n + k * n + j] = sum(&|p| {
                        c.masses[p] * k3::dot(c.shapes[k][p], k3::cross(e(a), k3::cross(e(b), c.shapes[j][p])))
                    });
                }
            }
        }
    }
    Inertia {
        mass,
        first_moment,
        inertia,
        stiffness: vec![0.0; n],
        n_dynamic: n,
        n_moving: n,
        damping: vec![0.0; n],
        c_t,
        c_r,
        o_vec,
        quadratic: super::QuadraticTerms::of(&g, &super::symmetric_sums(&o_mat, n), n),
        markers: vec![Marker { name: "base".into(), position: [0.0; 3], shapes: vec![0.0; 6 * n] }],
    }
}

/// d'Alembert over the particles: the generalised inertial forces minus the weight.
fn particle_forces(c: &Cloud, rot: &Mat3, q: &[f64], vel: &[f64], acc: &[f64], gravity: Vec3) -> Vec<f64> {
    let n = q.len();
    let (w, a, w_d) = (vel3(vel, 3), vel3(acc, 0), vel3(acc, 3));
    let mut out = vec![0.0; 6 + n];
    for p in 0..c.masses.len() {
        let mode_sum = |x: &[f64]| (0..n).fold([0.0; 3], |s, k| k3::add(s, k3::scale(x[k], c.shapes[k][p])));
        let rho = k3::add(c.x[p], mode_sum(q));
        let (u_d, u_dd) = (mode_sum(&vel[6..]), mode_sum(&acc[6..]));
        let acc_body = k3::add(
            k3::add(k3::cross(w_d, rho), k3::cross(w, k3::cross(w, rho))),
            k3::add(k3::scale(2.0, k3::cross(w, u_d)), u_dd),
        );
        let f_world = k3::scale(c.masses[p], k3::sub(k3::add(a, k3::mul(rot, acc_body)), gravity));
        let f_body = k3::mul_t(rot, f_world);
        for i in 0..3 {
            out[i] += f_world[i];
        }
        let m = k3::cross(rho, f_body);
        for i in 0..3 {
            out[3 + i] += m[i];
        }
        for k in 0..n {
            out[6 + k] += k3::dot(c.shapes[k][p], f_body);
        }
    }
    out
}

#[test]
fn forces_equal_dalembert_over_particles() {
    let n = 3;
    let c = cloud(7, n, 7);
    let body = inertia_of(&c);
    let mut rng = Lcg(99);
    let rot = crate::kinematics::rotation_of(rng.vec3());
    let q: Vec<f64> = (0..n).map(|_| 0.3 * rng.next()).collect();
    let vel: Vec<f64> = (0..6 + n).map(|_| rng.next()).collect();
    let acc: Vec<f64> = (0..6 + n).map(|_| rng.next()).collect();
    let gravity = [0.3, -0.2, -9.81];
    let mut cr_q = vec![0.0; Inertia::scratch_len(n)];
    let mut ours = vec![0.0; 6 + n];
    body.forces(&rot, &q, &vel, &acc, gravity, &mut cr_q, &mut ours);
    let theirs = particle_forces(&c, &rot, &q, &vel, &acc, gravity);
    let scale = theirs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        // round-off of sums over a few particles of O(10) terms
        assert!((a - b).abs() <= 1e-12 * scale, "slot {i}: {a} vs {b}");
    }
}

#[test]
fn kinetic_energy_equals_the_particles() {
    let n = 2;
    let c = cloud(5, n, 3);
    let body = inertia_of(&c);
    let mut rng = Lcg(5);
    let rot = crate::kinematics::rotation_of(rng.vec3());
    let q: Vec<f64> = (0..n).map(|_| 0.3 * rng.next()).collect();
    let vel: Vec<f64> = (0..6 + n).map(|_| rng.next()).collect();
    let (v, w) = (vel3(&vel, 0), vel3(&vel, 3));
    let mut theirs = 0.0;
    for p in 0..c.masses.len() {
        let rho = (0..n).fold(c.x[p], |s, k| k3::add(s, k3::scale(q[k], c.shapes[k][p])));
        let u_d = (0..n).fold([0.0; 3], |s, k| k3::add(s, k3::scale(vel[6 + k], c.shapes[k][p])));
        let pv = k3::add(v, k3::mul(&rot, k3::add(k3::cross(w, rho), u_d)));
        theirs += 0.5 * c.masses[p] * k3::dot(pv, pv);
    }
    let ours = body.kinetic_energy(&rot, &q, &vel, &mut vec![0.0; Inertia::scratch_len(n)]);
    assert!((ours - theirs).abs() <= 1e-13 * theirs, "{ours} vs {theirs}");
}

#[test]
fn rigid_inertia_moves_to_the_origin() {
    // a point mass off the origin: J = m (|c|^2 I - c c^T)
    let body = Inertia::rigid("p", 2.0, [1.0, 2.0, 0.0], [0.0; 9], &[("a".into(), [0.0; 3])]).unwrap();
    assert_eq!(body.inertia, [8.0, -4.0, 0.0, -4.0, 2.0, 0.0, 0.0, 0.0, 10.0]);
    assert_eq!(body.first_moment, [2.0, 4.0, 0.0]);
    assert!(Inertia::rigid("p", 0.0, [0.0; 3], [0.0; 9], &[]).is_err());
}

#[test]
fn mass_matrix_is_the_forces_derivative() {
    let n = 3;
    let c = cloud(6, n, 11);
    let body = inertia_of(&c);
    let mut rng = Lcg(3);
    let rot = crate::kinematics::rotation_of(rng.vec3());
    let q: Vec<f64> = (0..n).map(|_| 0.3 * rng.next()).collect();
    let vel: Vec<f64> = (0..6 + n).map(|_| rng.next()).collect();
    let w = 6 + n;
    let mut cr_q = vec![0.0; Inertia::scratch_len(n)];
    let (s, j, _) = body.deformed(&q, &vel[6..], &mut cr_q);
    let mut m = vec![0.0; w * w];
    body.mass_matrix(&rot, s, &j, &cr_q, &mut m, w);
    let mut f0 = vec![0.0; w];
    let mut f1 = vec![0.0; w];
    let zero = vec![0.0; w];
    body.forces(&rot, &q, &vel, &zero, [0.0; 3], &mut cr_q, &mut f0);
    for col in 0..w {
        let mut acc = vec![0.0; w];
        acc[col] = 1.0;
        body.forces(&rot, &q, &vel, &acc, [0.0; 3], &mut cr_q, &mut f1);
        for row in 0..w {
            let d = f1[row] - f0[row];
            // the forces are linear in the accelerations: exact to round-off
            assert!((d - m[row * w + col]).abs() < 1e-12, "({row}, {col}): {d} vs {}", m[row * w + col]);
        }
    }
}
