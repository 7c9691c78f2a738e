//! One body of an assembly as its equations of motion see it: mass properties about the body
//! frame's origin and, for a flexible body, its reduced modes and the floating-frame invariants.
//! A rigid body is the same with no modes.
//!
//! Velocities are the frame origin's v (world), the frame's angular velocity w (body axes) and
//! the modal rates q'; the same slots hold the accelerations a, w', q''. With gravity g, a material
//! point's position is p = r + R (x + Phi q), and d'Alembert's principle over the virtual motions
//! (dr, R dtheta, dq) gives (S = m c(q) = S_0 + C_t q, J(q), C_r(q) = C_r0 + [G_a q]_a):
//!
//! ```text
//! translation (world): m (a - g) + R (w' x S + C_t q'' + 2 w x C_t q' + w x (w x S))
//! rotation (body):     S x a_B + J w' + C_r q'' + w x (J w + C_r q') + J' w
//! modes:               C_t^T a_B + C_r^T w' + q'' + D q' + Lambda q
//!                        + 2 sum_a w_a G_a q' + sum_ab w_a w_b (o_ab + O_ab q)
//! ```
//!
//! with a_B = R^T (a - g), each equal to the generalised external and joint forces. The unit test
//! puts these against the same principle summed over a cloud of particles. An algebraic mode
//! (no inertia, no damping: [`Inertia::n_moving`]) has no rate; its row is
//! Lambda q + C_t^T (w x v_B - R^T g) + sum_a w_a G_a q' + sum_ab w_a w_b (o_ab + O_ab q).

use super::error::AssemblyError;
use super::mat_vec::mat_vec;
use crate::body::dense::dot;
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::reduced::ReducedBody;

/// The axis pairs (p, r), p <= r, of [`Inertia::o_sym`].
pub const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// [`Inertia::o_sym`] of O_ab (9 x n x n).
pub fn symmetric_sums(o_mat: &[f64], n: usize) -> Vec<f64> {
    let nn = n * n;
    let o = |p: usize, r: usize| &o_mat[(3 * p + r) * nn..][..nn];
    PAIRS
        .iter()
        .flat_map(|&(p, r)| (0..nn).map(move |i| if p == r { o(p, p)[i] } else { o(p, r)[i] + o(r, p)[i] }))
        .collect()
}

/// The matrices the equations multiply q (and G_a also q') by, stacked into one: G_0, G_1,
/// G_2, then O_ab's symmetric sums in [`PAIRS`]' order (O_pp, then O_pr + O_rp for p < r; O_rp =
/// O_pr^T, so every product the equations take with q is one of these: six where the nine O_ab
/// would need nine). Each row is padded with zeros to a multiple of four values, so that all
/// nine products with q are one matrix-vector product with no remainder columns.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadraticTerms {
    /// 9 n rows of `stride` values.
    pub rows: Vec<f64>,
    pub stride: usize,
}

impl QuadraticTerms {
    /// From G_a (3 x n x n) and the symmetric sums (6 x n x n, [`symmetric_sums`]).
    pub fn of(g: &[f64], o_sym: &[f64], n: usize) -> Self {
        let stride = n.div_ceil(4) * 4;
        let mut rows = vec![0.0; 9 * n * stride];
        if n > 0 {
            for (r, row) in g.chunks_exact(n).chain(o_sym.chunks_exact(n)).enumerate() {
                rows[r * stride..r * stride + n].copy_from_slice(row);
            }
        }
        Self { rows, stride }
    }
}

/// A flange of a body where joints and external loads attach.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub name: String,
    /// Reference point in the body frame, undeformed [m].
    pub position: Vec3,
    /// 6 x n row-major: translation (rows 0..3) and small rotation (rows 3..6) per unit q.
    pub shapes: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Inertia {
    pub mass: f64,
    /// m c of the undeformed body about the frame origin [kg m].
    pub first_moment: Vec3,
    /// Inertia tensor about the frame origin, undeformed, row-major [kg m^2].
    pub inertia: Mat3,
    /// Modal angular frequencies squared (the reduced stiffness).
    pub stiffness: Vec<f64>,
    /// The first modes carry inertia; those above the body's dynamic cutoff are quasi-static:
    /// their rates are taken as zero and their coordinates solved from the loads in every step
    /// (the mode-acceleration method: a reduced mode far above the band stands for the part's
    /// whole spectrum there, whose statics it carries exactly and whose ringing is no response
    /// of the part; the body's own FMU treats them so, too).
    pub n_dynamic: usize,
    /// Modes n_dynamic..n_moving relax: no inertia, their damping kept (an overdamped mode
    /// creeps toward its equilibrium at omega^2 / d; solved algebraically it would jump). The
    /// modes above n_moving (undamped ones) are algebraic: without a rate they have no
    /// momentum, and their equation is the Lagrangian's derivative in their coordinate (the
    /// weight, the frame's w x v_B, the spin's terms), so an undamped assembly keeps its energy;
    /// the mode-acceleration load (the momentum's rate C_t^T R^T a + C_r^T w') would feed it.
    pub n_moving: usize,
    /// d_k of q''_k + d_k q'_k + omega_k^2 q_k [1/s].
    pub damping: Vec<f64>,
    /// 3 x n: C_t = T^T M Phi, C_r0 = R_X^T M Phi.
    pub c_t: Vec<f64>,
    pub c_r: Vec<f64>,
    /// o_ab (9 x n), as in [`crate::reduced::RotationTerms`].
    pub o_vec: Vec<f64>,
    /// G_a (3 x n x n, as in [`crate::reduced::RotationTerms`]) and O_ab's symmetric sums,
    /// stacked ([`QuadraticTerms`]).
    pub quadratic: QuadraticTerms,
    pub markers: Vec<Marker>,
}

impl Inertia {
    pub fn n_modes(&self) -> usize {
        self.stiffness.len()
    }

    /// A flexible body from its reduction: the mount flange is its frame (marker 0, no shapes),
    /// the force flanges follow. `alpha`, `beta`: the Rayleigh damping it runs with.
    pub fn flexible(name: &str, body: &ReducedBody, alpha: f64, beta: f64) -> Result<Self, AssemblyError> {
        if body.free_floating {
            return Err(AssemblyError::Body {
                body: name.into(),
                reason: "it is free-floating: an assembly's flexible body needs a motion flange as its frame".into(),
            });
        }
        let rot = body.rotation.as_ref().ok_or_else(|| AssemblyError::Body {
            body: name.into(),
            reason: "it has no rotating-frame terms (its input declares a scene without rotation)".into(),
        })?;
        let n = body.n_modes();
        let mut markers = vec![Marker { name: body.mount.clone(), position: [0.0; 3], shapes: vec![0.0; 6 * n] }];
        markers.extend(body.flanges.iter().map(|f| Marker {
            name: f.name.clone(),
            position: f.position,
            shapes: f.shapes.clone(),
        }));
        Ok(Self {
            mass: body.mass,
            first_moment: body.first_moment,
            inertia: body.inertia,
            stiffness: body.omega.iter().map(|w| w * w).collect(),
            n_dynamic: body.n_dynamic(),
            n_moving: n,
            damping: (0..n).map(|j| body.damping_rate(j, alpha, beta)).collect(),
            c_t: body.c_t.clone(),
            c_r: body.c_r.clone(),
            o_vec: rot.o_vec.clone(),
            quadratic: QuadraticTerms::of(&rot.g, &symmetric_sums(&rot.o_mat, n), n),
            markers,
        })
    }

    /// Keep as dynamic only the modes a step of `h` resolves, omega h <= RESOLVED: the
    /// generalised-alpha step turns a mode of omega h >> 1 into one at the step's Nyquist
    /// frequency, whose transient after a load change is then wrong by O(h); solved
    /// quasi-statically it is right to the mode's own (omega_band / omega)^2.
    pub fn resolve_within(&mut self, h: f64) {
        let limit = RESOLVED / h;
        self.n_dynamic = self.n_dynamic.min(self.stiffness.iter().take_while(|k| k.sqrt() <= limit).count());
        // relaxing: a rate the step follows (trapezoidal at rate h <= 10 damps a jump's
        // alternation by two thirds a step)
        let relaxes = |k: usize| self.damping[k] > 0.0 && self.stiffness[k] / self.damping[k] * h <= 10.0;
        self.n_moving = self.n_dynamic + (self.n_dynamic..self.n_modes()).take_while(|&k| relaxes(k)).count();
    }

    /// A rigid body: `inertia_at_centre` about the centre of mass, body axes; flanges by name
    /// and position in the body frame.
    pub fn rigid(
        name: &str,
        mass: f64,
        centre: Vec3,
        inertia_at_centre: Mat3,
        flanges: &[(String, Vec3)],
    ) -> Result<Self, AssemblyError> {
        if !(mass > 0.0) || !mass.is_finite() {
            return Err(AssemblyError::Body { body: name.into(), reason: format!("mass {mass} is not positive") });
        }
        let c2 = k3::dot(centre, centre);
        let inertia: Mat3 = std::array::from_fn(|ij| {
            let (i, j) = (ij / 3, ij % 3);
            inertia_at_centre[ij] + mass * (if i == j { c2 } else { 0.0 } - centre[i] * centre[j])
        });
        Ok(Self {
            mass,
            first_moment: k3::scale(mass, centre),
            inertia,
            stiffness: vec![],
            n_dynamic: 0,
            n_moving: 0,
            damping: vec![],
            c_t: vec![],
            c_r: vec![],
            o_vec: vec![],
            quadratic: QuadraticTerms::of(&[], &[], 0),
            markers: flanges.iter().map(|(n, p)| Marker { name: n.clone(), position: *p, shapes: vec![] }).collect(),
        })
    }

    /// Scratch the body's equations need: C_r(q) (3 n), the symmetric sums' products with q
    /// (6 n), G_a q' (3 n), then q and q' padded to [`QuadraticTerms::stride`].
    pub fn scratch_len(n: usize) -> usize {
        12 * n.max(1) + 2 * n.div_ceil(4) * 4
    }

    /// `x` padded with zeros to the stride, at the start of `scratch`.
    fn padded<'a>(&self, x: &[f64], scratch: &'a mut [f64]) -> &'a [f64] {
        let pad = &mut scratch[..self.quadratic.stride];
        pad[..x.len()].copy_from_slice(x);
        pad[x.len()..].fill(0.0);
        pad
    }

    /// S(q) = m c(q), C_r(q) (3 x n into `cr_q`, then O_ab q, 9 x n), J(q) and J'(q, q');
    /// `qd` may hold only the moving modes' rates (the others are zero).
    pub fn deformed(&self, q: &[f64], qd: &[f64], cr_q: &mut [f64]) -> (Vec3, Mat3, Mat3) {
        let n = q.len();
        let mut s = self.first_moment;
        for a in 0..3 {
            s[a] += dot(&self.c_t[a * n..(a + 1) * n], q);
        }
        // C_r(q) - C_r0 = [G_a q] and the symmetric sums times q: one product
        let (cr_q, pad) = cr_q.split_at_mut(12 * n);
        let q_pad = self.padded(q, pad);
        mat_vec(&self.quadratic.rows, self.quadratic.stride, q_pad, &mut cr_q[..9 * n]);
        for (c, c0) in cr_q[..3 * n].iter_mut().zip(&self.c_r) {
            *c += c0;
        }
        let o_q = &cr_q[3 * n..9 * n];
        // q^T O_pr q = q^T O_rp q (a scalar is its transpose): half the pair's sum, and
        // d/dt (q^T O_pr q) = q'^T (O_pr + O_rp) q: no product with q' is needed
        let (mut lin, mut lin_rate, mut quad, mut quad_rate) = ([0.0; 9], [0.0; 9], [0.0; 6], [0.0; 6]);
        mat_vec(&self.o_vec, n, q, &mut lin);
        mat_vec(&self.o_vec, n, qd, &mut lin_rate);
        mat_vec(o_q, n, q, &mut quad);
        mat_vec(o_q, n, qd, &mut quad_rate);
        let mut j = self.inertia;
        let mut j_rate = [0.0; 9];
        for (pair, &(p, r)) in PAIRS.iter().enumerate() {
            let (quad, quad_rate) =
                if p == r { (quad[pair], 2.0 * quad_rate[pair]) } else { (0.5 * quad[pair], quad_rate[pair]) };
            for (a, b) in [(p, r), (r, p)] {
                let (ab, ba) = (3 * a + b, 3 * b + a);
                j[ab] -= lin[ab] + lin[ba] + quad;
                j_rate[ab] = -(lin_rate[ab] + lin_rate[ba] + quad_rate);
                if p == r {
                    break;
                }
            }
        }
        (s, j, j_rate)
    }

    /// The body's inertial, elastic and damping forces minus its weight, in the velocity slots
    /// (module docs), into `out` (6 + n). `cr_q` is scratch of 3 n; it is left holding C_r(q),
    /// and S(q), J(q) are returned (what [`Self::mass_matrix`] takes).
    #[allow(clippy::too_many_arguments)]
    pub fn forces(
        &self,
        rot: &Mat3,
        q: &[f64],
        vel: &[f64],
        acc: &[f64],
        gravity: Vec3,
        cr_q: &mut [f64],
        out: &mut [f64],
    ) -> (Vec3, Mat3) {
        let n = q.len();
        // the origin's velocity drops out: its terms cancel between momentum and its rate
        let (nd, nm) = (self.n_dynamic, self.n_moving);
        let (w, qd) = (vel3(vel, 3), &vel[6..6 + nm]);
        let (a, w_d, qdd) = (vel3(acc, 0), vel3(acc, 3), &acc[6..6 + nd]);
        let a_b = k3::mul_t(rot, k3::sub(a, gravity));
        let (s, j, j_rate) = self.deformed(q, qd, cr_q);
        let (cr_q, rest) = cr_q.split_at_mut(9 * n);
        let (g_qd, pad) = rest.split_at_mut(3 * n);
        let stride = self.quadratic.stride;
        let qd_pad = self.padded(qd, pad);
        mat_vec(&self.quadratic.rows[..3 * n * stride], stride, qd_pad, g_qd);
        let (cr_q, g_qd): (&[f64], &[f64]) = (cr_q, g_qd);
        let ct = |x: &[f64]| -> Vec3 { std::array::from_fn(|i| dot(&self.c_t[i * n..(i + 1) * n], x)) };
        let cr = |x: &[f64]| -> Vec3 { std::array::from_fn(|i| dot(&cr_q[i * n..(i + 1) * n], x)) };
        let (ct_qd, ct_qdd, cr_qd, cr_qdd) = (ct(qd), ct(qdd), cr(qd), cr(qdd));
        // translation, world
        let body_part = k3::add(
            k3::add(k3::cross(w_d, s), ct_qdd),
            k3::add(k3::scale(2.0, k3::cross(w, ct_qd)), k3::cross(w, k3::cross(w, s))),
        );
        let trans = k3::add(k3::scale(self.mass, k3::sub(a, gravity)), k3::mul(rot, body_part));
        // rotation, body axes
        let h = k3::add(k3::mul(&j, w), cr_qd);
        let rotation = k3::add(
            k3::add(k3::cross(s, a_b), k3::add(k3::mul(&j, w_d), cr_qdd)),
            k3::add(k3::cross(w, h), k3::mul(&j_rate, w)),
        );
        out[..3].copy_from_slice(&trans);
        out[3..6].copy_from_slice(&rotation);
        // dT/dq (T without the algebraic modes' rates) of the frame's motion and the weight:
        // C_t^T (w x v_B - R^T g)
        let algebraic_load =
            k3::add(k3::cross(w, k3::mul_t(rot, vel3(vel, 0))), k3::mul_t(rot, k3::scale(-1.0, gravity)));
        for k in 0..n {
            let mut f = self.stiffness[k] * q[k];
            if k < nd {
                f += qdd[k];
            }
            if k < nm {
                f += self.damping[k] * qd[k];
            }
            // an algebraic mode has no rate, so no momentum of its own: its equation is the
            // Lagrangian's derivative in its coordinate alone (its momentum's rate, the inertial
            // load C_t^T R^T a + C_r^T w' + w G q', drops out), which keeps the energy of an
            // undamped assembly where the mode-acceleration load would feed it
            let (load, coriolis) = if k < nm { (a_b, 2.0) } else { (algebraic_load, 1.0) };
            for i in 0..3 {
                f += self.c_t[i * n + k] * load[i];
                if k < nm {
                    f += cr_q[i * n + k] * w_d[i];
                }
                f += coriolis * w[i] * g_qd[i * n + k];
                for b in 0..3 {
                    f += w[i] * w[b] * self.o_vec[(3 * i + b) * n + k];
                }
            }
            // sum_ab w_a w_b O_ab q over the symmetric sums
            for (pair, &(p, r)) in PAIRS.iter().enumerate() {
                let ww = w[p] * w[r];
                if ww != 0.0 {
                    f += ww * cr_q[3 * n + pair * n + k];
                }
            }
            out[6 + k] = f;
        }
        (s, j)
    }

    /// The mass matrix in the velocity slots (the forces' derivative by the accelerations),
    /// into the (6 + n) x (6 + n) block at `out[0]` with row stride `stride`; `cr_q` must hold
    /// C_r(q) (from [`Self::deformed`]). Rows of modes without inertia are left zero.
    pub fn mass_matrix(&self, rot: &Mat3, s: Vec3, j: &Mat3, cr_q: &[f64], out: &mut [f64], stride: usize) {
        let n = self.n_modes();
        let nd = self.n_dynamic;
        let w = 6 + n;
        for r in 0..w {
            out[r * stride..r * stride + w].fill(0.0);
        }
        // translation: m a + R (w' x S + C_t q'')
        let s_cross = [0.0, -s[2], s[1], s[2], 0.0, -s[0], -s[1], s[0], 0.0];
        let r_s = k3::mat_mul(rot, &s_cross);
        for i in 0..3 {
            out[i * stride + i] = self.mass;
            for c in 0..3 {
                out[i * stride + 3 + c] = -r_s[3 * i + c];
            }
            for k in 0..nd {
                out[i * stride + 6 + k] = (0..3).map(|l| rot[3 * i + l] * self.c_t[l * n + k]).sum();
            }
        }
        // rotation: S x (R^T a) + J w' + C_r q''
        let s_rt = k3::mat_mul(&s_cross, &joint_transpose(rot));
        for i in 0..3 {
            for c in 0..3 {
                out[(3 + i) * stride + c] = s_rt[3 * i + c];
                out[(3 + i) * stride + 3 + c] = j[3 * i + c];
            }
            for k in 0..nd {
                out[(3 + i) * stride + 6 + k] = cr_q[i * n + k];
            }
        }
        // modes: C_t^T R^T a + C_r^T w' + q''
        for k in 0..nd {
            let row = &mut out[(6 + k) * stride..];
            for c in 0..3 {
                row[c] = (0..3).map(|l| rot[3 * c + l] * self.c_t[l * n + k]).sum();
                row[3 + c] = cr_q[c * n + k];
            }
            row[6 + k] = 1.0;
        }
    }

    /// The forces' derivative by the accelerations in a step that moves the positions by
    /// `pos_gain` and the rates by `vel_gain` per unit acceleration: the mass matrix, the
    /// relaxing modes' inertial load (their rows' C_t^T R^T a + C_r^T w'), and the modes'
    /// stiffness and damping. The rotation's and the spin's terms are left out (of order |w| h and
    /// (|a - g| / l) h^2 against the inertia): an iteration matrix, not the Jacobian. Into the
    /// (6 + n) block at `out[0]`, row stride `stride`; `cr_q` must hold C_r(q).
    #[allow(clippy::too_many_arguments)]
    pub fn iteration_block(
        &self,
        rot: &Mat3,
        s: Vec3,
        j: &Mat3,
        cr_q: &[f64],
        pos_gain: f64,
        vel_gain: f64,
        out: &mut [f64],
        stride: usize,
    ) {
        let n = self.n_modes();
        self.mass_matrix(rot, s, j, cr_q, out, stride);
        for k in self.n_dynamic..self.n_moving {
            let row = &mut out[(6 + k) * stride..];
            for c in 0..3 {
                row[c] = (0..3).map(|l| rot[3 * c + l] * self.c_t[l * n + k]).sum();
                row[3 + c] = cr_q[c * n + k];
            }
        }
        for k in 0..n {
            let damping = if k < self.n_moving { self.damping[k] } else { 0.0 };
            out[(6 + k) * stride + 6 + k] += pos_gain * self.stiffness[k] + vel_gain * damping;
        }
    }

    /// Kinetic energy of the body at velocities `vel` (module docs' slots).
    pub fn kinetic_energy(&self, rot: &Mat3, q: &[f64], vel: &[f64], cr_q: &mut [f64]) -> f64 {
        let n = q.len();
        let (v, w, qd) = (vel3(vel, 0), vel3(vel, 3), &vel[6..6 + self.n_dynamic]);
        let (s, j, _) = self.deformed(q, qd, cr_q);
        let ct_qd: Vec3 = std::array::from_fn(|i| dot(&self.c_t[i * n..(i + 1) * n], qd));
        let cr_qd: Vec3 = std::array::from_fn(|i| dot(&cr_q[i * n..(i + 1) * n], qd));
        let v_b = k3::mul_t(rot, v);
        0.5 * self.mass * k3::dot(v, v)
            + k3::dot(v_b, k3::add(k3::cross(w, s), ct_qd))
            + 0.5 * k3::dot(w, k3::mul(&j, w))
            + k3::dot(w, cr_qd)
            + 0.5 * qd.iter().map(|x| x * x).sum::<f64>()
    }

    /// Strain energy 1/2 q^T Lambda q.
    pub fn strain_energy(&self, q: &[f64]) -> f64 {
        0.5 * self.stiffness.iter().zip(q).map(|(k, q)| k * q * q).sum::<f64>()
    }

    /// Potential energy of the weight: -g . (m r + R S(q)).
    pub fn gravity_energy(&self, r: Vec3, rot: &Mat3, q: &[f64], gravity: Vec3) -> f64 {
        let n = q.len();
        let mut s = self.first_moment;
        for (a, s) in s.iter_mut().enumerate() {
            *s += dot(&self.c_t[a * n..(a + 1) * n], q);
        }
        -k3::dot(gravity, k3::add(k3::scale(self.mass, r), k3::mul(rot, s)))
    }
}

fn joint_transpose(m: &Mat3) -> Mat3 {
    [m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8]]
}

/// The largest omega h of a dynamic mode in an assembly (see [`Inertia::resolve_within`]).
pub const RESOLVED: f64 = 2.0;

#[inline]
pub(crate) fn vel3(x: &[f64], at: usize) -> Vec3 {
    [x[at], x[at + 1], x[at + 2]]
}

#[cfg(test)]
mod tests;
