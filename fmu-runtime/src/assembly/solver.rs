//! The step of an assembly: generalised-alpha on the Lie group of the bodies' poses (Arnold and
//! Brüls 2007; Brüls, Cardona and Arnold 2012) for the index-3 equations of motion with the
//! joints' multipliers, solved by Newton's method at every step.
//!
//! Per step h, with the pseudo-accelerations a~ and the accelerations a = v':
//!
//! ```text
//! dx      = h v_n + h^2 (1/2 - beta) a~_n + h^2 beta a~_{n+1}     (r + dr, R exp(dtheta~), q + dq)
//! v_{n+1} = v_n + h (1 - gamma) a~_n + h gamma a~_{n+1}
//! (1 - alpha_m) a~_{n+1} + alpha_m a~_n = (1 - alpha_f) a_{n+1} + alpha_f a_n
//! forces(x_{n+1}, v_{n+1}, a_{n+1}) - applied - B^T lambda = 0,   phi(x_{n+1}, t_{n+1}) = 0
//! ```
//!
//! Second order; with spectral radius 1 (trapezoidal) a linear undamped system keeps its energy
//! exactly, lower radii damp what the step does not resolve. The joints hold at position level
//! at every step (to Newton's tolerance): no drift. The iteration matrix is the bodies' mass
//! matrices with their modes' stiffness and damping scaled by the step, and the joints'
//! Jacobian (the rotation's and the spin's terms, of order |w| h against the inertia, left
//! out); it is kept over steps while Newton converges fast with it (modified Newton) and formed
//! again when an iteration stalls. Where Newton stalls with a fresh one too, the matrix comes
//! from finite differences of the whole residual (ten times the work). Both this matrix and the
//! outputs' index-1 one are factored with the bodies' modes condensed out first
//! ([`super::condensed`]). Every buffer is allocated when the solver is made.

use super::condensed::Condensation;
use super::description::SolverSettings;
use super::error::AssemblyError;
use super::inertia::Inertia;
use super::system::{Instant, System};

/// Newton iterations of a step after which the next step forms the iteration matrix again: the
/// bodies turn away from the poses it was formed at, and its contraction decays over a swing
/// long before an iteration stalls (the double pendulum's first 5 s at 1 ms: 3.8 iterations a
/// step with the matrix kept until a stall, 126 formations; 2.9 and 373 with this, a formation
/// costing about three iterations: a quarter less per step).
const REFORM_AFTER: usize = 4;

/// Generalised-alpha's coefficients of a spectral radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl Coefficients {
    pub fn of(rho: f64) -> Self {
        let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
        let alpha_f = rho / (rho + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        Self { alpha_m, alpha_f, beta: 0.25 * (gamma + 0.5) * (gamma + 0.5), gamma }
    }

    /// d(dx)/d(a_{n+1}) per unit h^2.
    fn position_gain(&self) -> f64 {
        self.beta * (1.0 - self.alpha_f) / (1.0 - self.alpha_m)
    }
}

/// The assembly's evolving state: what a saved FMU state holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    pub pos: Vec<f64>,
    pub vel: Vec<f64>,
    pub acc: Vec<f64>,
    pub pseudo: Vec<f64>,
    pub lambda: Vec<f64>,
}

/// Buffers of a step.
#[derive(Debug, Clone)]
struct Work {
    pos: Vec<f64>,
    vel: Vec<f64>,
    acc: Vec<f64>,
    pseudo: Vec<f64>,
    lambda: Vec<f64>,
    dx: Vec<f64>,
    forces: Vec<f64>,
    /// The bodies' forces of the last full residual: a difference column of one body's
    /// acceleration evaluates that body's again, the others' are these.
    base_forces: Vec<f64>,
    phi: Vec<f64>,
    jac: Vec<f64>,
    residual: Vec<f64>,
    probe: Vec<f64>,
    /// The kept iteration matrix as formed, and its factors with the modes condensed out.
    matrix: Vec<f64>,
    factors: Condensation,
    /// The index-1 system of [`Solver::consistent`], apart from the kept iteration matrix, and
    /// its factors without the modes that have no inertia (no acceleration: their rows and
    /// columns drop out). Only the bodies' diagonal blocks and the joints' rows and columns are
    /// ever written: the rest stays zero from the start.
    consistent_matrix: Vec<f64>,
    consistent_factors: Condensation,
    cr_q: Vec<f64>,
}

#[derive(Debug, Clone)]
pub struct Solver {
    pub settings: SolverSettings,
    pub coefficients: Coefficients,
    work: Work,
    /// The step the kept iteration matrix was formed for (None: none kept).
    matrix_step: Option<f64>,
    /// Whether the next step is a run's first: taken with spectral radius 0, which moves the modes
    /// the step cannot resolve straight to their equilibrium with the start's loads (a reduced
    /// mode far above the band stands for the part's whole spectrum there, whose ringing is no
    /// response of the part: the bodies' own Co-Simulation starts them so, too).
    first: bool,
    /// Newton iterations of the last step, and matrices formed so far.
    pub last_iterations: usize,
    pub matrices_formed: u64,
}

impl Solver {
    pub fn new(system: &System, settings: SolverSettings) -> Self {
        let (nv, ne, np) = (system.n_vel, system.n_eq, system.n_pos);
        let dim = nv + ne;
        let modes: Vec<usize> = system.bodies.iter().flat_map(|b| b.slot + 6..b.slot + 6 + b.n_modes()).collect();
        let (mut with_inertia, mut without) = (vec![], vec![]);
        for b in &system.bodies {
            for k in 0..b.n_modes() {
                let list = if k < b.inertia.n_dynamic { &mut with_inertia } else { &mut without };
                list.push(b.slot + 6 + k);
            }
        }
        Self {
            settings,
            coefficients: Coefficients::of(settings.spectral_radius),
            work: Work {
                pos: vec![0.0; np],
                vel: vec![0.0; nv],
                acc: vec![0.0; nv],
                pseudo: vec![0.0; nv],
                lambda: vec![0.0; ne],
                dx: vec![0.0; nv],
                forces: vec![0.0; nv],
                base_forces: vec![0.0; nv],
                phi: vec![0.0; ne],
                jac: vec![0.0; ne * nv],
                residual: vec![0.0; dim],
                probe: vec![0.0; dim],
                matrix: vec![0.0; dim * dim],
                factors: Condensation::new(dim, modes),
                consistent_matrix: vec![0.0; dim * dim],
                consistent_factors: Condensation::without(dim, with_inertia, &without),
                cr_q: vec![0.0; Inertia::scratch_len(system.max_modes())],
            },
            matrix_step: None,
            first: false,
            last_iterations: 0,
            matrices_formed: 0,
        }
    }

    /// What a saved state needs beside the motion to continue bit for bit: whether the next
    /// step is a run's first, the step the kept iteration matrix was formed for (None: none),
    /// and that matrix as formed (factoring it again gives the same factors).
    pub fn kept(&self) -> (bool, Option<f64>, &[f64]) {
        (self.first, self.matrix_step, &self.work.matrix)
    }

    /// Take what [`Self::kept`] gave (`matrix` of this solver's size); a matrix that does not
    /// factor is dropped (the next step forms one).
    pub fn restore_kept(&mut self, first: bool, matrix_step: Option<f64>, matrix: &[f64]) {
        self.first = first;
        self.work.matrix.copy_from_slice(matrix);
        self.matrix_step = matrix_step.filter(|_| self.work.factors.factor(&self.work.matrix).is_ok());
    }

    /// Whether the next step is a run's first (a restored state without a kept matrix).
    pub fn set_first(&mut self, first: bool) {
        self.first = first;
    }

    /// The iteration system's dimension (velocity slots and joint equations).
    pub fn dimension(&self) -> usize {
        self.work.residual.len()
    }

    /// Forget the kept iteration matrix (after the state was replaced).
    pub fn invalidate(&mut self) {
        self.matrix_step = None;
    }

    /// Accelerations and multipliers consistent with the positions and velocities of `m` at
    /// `now` (the start of a run): the equations of motion with the joints' equations twice
    /// differentiated in time.
    pub fn settle_accelerations(
        &mut self,
        system: &System,
        m: &mut Motion,
        now: &Instant,
    ) -> Result<(), AssemblyError> {
        let (mut acc, mut lambda) = (std::mem::take(&mut m.acc), std::mem::take(&mut m.lambda));
        let done = self.consistent(system, m, now, &mut acc, &mut lambda);
        (m.acc, m.lambda) = (acc, lambda);
        done?;
        m.pseudo.copy_from_slice(&m.acc);
        self.invalidate();
        self.first = true;
        Ok(())
    }

    /// The accelerations and multipliers of `m`'s positions and velocities at `now`, from the
    /// equations of motion and the joints' equations differentiated twice (index 1): the
    /// step's own (index 3) alternate about these from step to step at spectral radius 1 and
    /// lag them by O(h) below it, so the outputs that need them (reactions, accelerations) take
    /// these. Allocates nothing; the kept iteration matrix stays.
    pub fn consistent(
        &mut self,
        system: &System,
        m: &Motion,
        now: &Instant,
        acc: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), AssemblyError> {
        let (nv, ne) = (system.n_vel, system.n_eq);
        let dim = nv + ne;
        let w = &mut self.work;
        // phi'' at a = 0: second differences along the present velocities (geodesics of the
        // poses) and in time
        let eps = 1e-4;
        w.probe[..ne].fill(0.0);
        for sign in [1.0, -1.0] {
            for (d, v) in w.dx.iter_mut().zip(&m.vel) {
                *d = sign * eps * v;
            }
            system.advance(&m.pos, &w.dx, &mut w.pos);
            let at = Instant { t: now.t + sign * eps, ..*now };
            system.constraint_values(&w.pos, &at, &mut w.phi);
            for k in 0..ne {
                w.probe[k] += w.phi[k];
            }
        }
        system.constraints(&m.pos, now, &mut w.phi, &mut w.jac);
        for k in 0..ne {
            w.residual[nv + k] = -(w.probe[k] - 2.0 * w.phi[k]) / (eps * eps);
        }
        // the forces at a = 0 less the applied ones
        w.acc.fill(0.0);
        system.forces_and_mass(&m.pos, &m.vel, &w.acc, &mut w.cr_q, &mut w.forces, &mut w.consistent_matrix, dim);
        w.forces.iter_mut().for_each(|x| *x = -*x);
        system.add_applied(&m.pos, now, &mut w.forces);
        w.residual[..nv].copy_from_slice(&w.forces);
        put_joint_blocks(&mut w.consistent_matrix, &w.jac, nv, ne);
        w.consistent_factors.factor(&w.consistent_matrix).map_err(|_| AssemblyError::Singular { time: now.t })?;
        w.consistent_factors.solve(&mut w.residual);
        if w.residual.iter().any(|x| !x.is_finite()) {
            return Err(AssemblyError::NotFinite { time: now.t });
        }
        acc.copy_from_slice(&w.residual[..nv]);
        lambda.copy_from_slice(&w.residual[nv..]);
        Ok(())
    }

    /// The residual at the trial accelerations and multipliers in `work.acc`, `work.lambda`:
    /// fills work's pos, vel, pseudo, phi, jac and `out`.
    fn residual(&mut self, system: &System, m: &Motion, h: f64, now: &Instant, out_probe: bool) {
        self.residual_of(system, m, h, now, out_probe, None);
    }

    /// The positions, velocities and pseudo-accelerations of the trial accelerations.
    fn trial_motion(&mut self, system: &System, m: &Motion, h: f64) {
        let c = self.coefficients;
        let w = &mut self.work;
        for i in 0..system.n_vel {
            let p = ((1.0 - c.alpha_f) * w.acc[i] + c.alpha_f * m.acc[i] - c.alpha_m * m.pseudo[i]) / (1.0 - c.alpha_m);
            w.pseudo[i] = p;
            w.dx[i] = h * m.vel[i] + h * h * ((0.5 - c.beta) * m.pseudo[i] + c.beta * p);
            w.vel[i] = m.vel[i] + h * ((1.0 - c.gamma) * m.pseudo[i] + c.gamma * p);
        }
        system.advance(&m.pos, &w.dx, &mut w.pos);
    }

    /// [`Self::residual`]; `only`: the body whose acceleration alone changed since the last full
    /// residual (the other bodies' forces are taken from it).
    fn residual_of(
        &mut self,
        system: &System,
        m: &Motion,
        h: f64,
        now: &Instant,
        out_probe: bool,
        only: Option<usize>,
    ) {
        let c = self.coefficients;
        let (nv, ne) = (system.n_vel, system.n_eq);
        self.trial_motion(system, m, h);
        let w = &mut self.work;
        match only {
            Some(b) => {
                w.forces.copy_from_slice(&w.base_forces);
                system.body_force(b, &w.pos, &w.vel, &w.acc, &mut w.cr_q, &mut w.forces);
            }
            None => {
                system.body_forces(&w.pos, &w.vel, &w.acc, &mut w.cr_q, &mut w.forces);
                w.base_forces.copy_from_slice(&w.forces);
            }
        }
        for x in &mut w.forces {
            *x = -*x;
        }
        system.add_applied(&w.pos, now, &mut w.forces);
        system.constraints(&w.pos, now, &mut w.phi, &mut w.jac);
        let out = if out_probe { &mut w.probe } else { &mut w.residual };
        for i in 0..nv {
            out[i] = -w.forces[i];
        }
        for k in 0..ne {
            let l = w.lambda[k];
            if l != 0.0 {
                for (o, b) in out[..nv].iter_mut().zip(&w.jac[k * nv..(k + 1) * nv]) {
                    *o -= l * b;
                }
            }
        }
        let scale = 1.0 / (h * h * c.position_gain());
        for k in 0..ne {
            out[nv + k] = w.phi[k] * scale;
        }
    }

    /// The iteration matrix at the present trial (work.acc, work.lambda), factored.
    fn form_matrix(&mut self, system: &System, m: &Motion, h: f64, now: &Instant) -> Result<(), AssemblyError> {
        let (nv, ne) = (system.n_vel, system.n_eq);
        let dim = nv + ne;
        self.residual(system, m, h, now, false);
        // the multipliers' columns: -B^T over the body rows
        for k in 0..ne {
            for j in 0..nv {
                self.work.matrix[j * dim + nv + k] = -self.work.jac[k * nv + j];
            }
            for i in 0..ne {
                self.work.matrix[(nv + i) * dim + nv + k] = 0.0;
            }
        }
        // the accelerations' columns by forward differences: a step that moves the positions by
        // about 1e-8 (forces are linear in the accelerations, nonlinear in the positions)
        let delta = 1e-8 / (h * h * self.coefficients.position_gain());
        for (b, body) in system.bodies.iter().enumerate() {
            for j in body.slot..body.slot + 6 + body.n_modes() {
                let keep = self.work.acc[j];
                self.work.acc[j] = keep + delta;
                self.residual_of(system, m, h, now, true, Some(b));
                self.work.acc[j] = keep;
                for i in 0..dim {
                    self.work.matrix[i * dim + j] = (self.work.probe[i] - self.work.residual[i]) / delta;
                }
            }
        }
        let w = &mut self.work;
        self.matrix_step = None;
        w.factors.factor(&w.matrix).map_err(|_| AssemblyError::Singular { time: now.t })?;
        self.matrix_step = Some(h);
        self.matrices_formed += 1;
        Ok(())
    }

    /// The iteration matrix from the bodies' equations at the present trial (work.acc,
    /// work.lambda), factored: [`System::iteration_blocks`] and the joints' Jacobian, about a
    /// tenth of [`Self::form_matrix`]'s work, which it stands in for until Newton stalls with it.
    fn form_model_matrix(&mut self, system: &System, m: &Motion, h: f64, now: &Instant) -> Result<(), AssemblyError> {
        let (nv, ne) = (system.n_vel, system.n_eq);
        let dim = nv + ne;
        self.residual(system, m, h, now, false);
        let c = self.coefficients;
        let pos_gain = h * h * c.position_gain();
        let vel_gain = h * c.gamma * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let w = &mut self.work;
        w.matrix.fill(0.0);
        system.iteration_blocks(&w.pos, &w.vel, &mut w.cr_q, pos_gain, vel_gain, &mut w.matrix, dim);
        put_joint_blocks(&mut w.matrix, &w.jac, nv, ne);
        self.matrix_step = None;
        w.factors.factor(&w.matrix).map_err(|_| AssemblyError::Singular { time: now.t })?;
        self.matrix_step = Some(h);
        self.matrices_formed += 1;
        Ok(())
    }

    /// Newton from the last step's accelerations and multipliers; Ok(true) when converged.
    fn iterate(
        &mut self,
        system: &System,
        m: &Motion,
        h: f64,
        now: &Instant,
        fresh: bool,
    ) -> Result<bool, AssemblyError> {
        // a matrix just formed left the residual of the step's start in work.residual
        let (nv, ne) = (system.n_vel, system.n_eq);
        let gain = h * h * self.coefficients.position_gain();
        let tol = self.settings.tolerance;
        let (mut last, mut last_dl) = (f64::INFINITY, f64::INFINITY);
        for it in 0..self.settings.max_iterations {
            if it > 0 || !fresh {
                self.residual(system, m, h, now, false);
            }
            let w = &mut self.work;
            for x in &mut w.residual {
                *x = -*x;
            }
            w.factors.solve(&mut w.residual);
            let mut size = 0.0f64;
            for i in 0..nv {
                w.acc[i] += w.residual[i];
                size = size.max((w.residual[i] * gain).abs());
            }
            // the multipliers converge too: a kept matrix whose joint directions turned with a
            // body (a crank's) lets them grow while the positions settle
            let (mut dl, mut scale) = (0.0f64, 1.0f64);
            for k in 0..ne {
                w.lambda[k] += w.residual[nv + k];
                dl = dl.max(w.residual[nv + k].abs());
                scale = scale.max(w.lambda[k].abs());
            }
            if !size.is_finite() || !dl.is_finite() {
                return Ok(false);
            }
            self.last_iterations = it + 1;
            if size <= tol && dl <= 1e-4 * scale {
                self.trial_motion(system, m, h);
                return Ok(true);
            }
            // a kept matrix that no longer contracts well is formed again; with a fresh one
            // Newton goes on while it contracts at all (a fast whip's first iterations do slowly)
            let stalled = if fresh { size >= last && dl >= last_dl } else { size > 0.5 * last || dl > 0.5 * last_dl };
            if it >= 2 && stalled {
                return Ok(false);
            }
            (last, last_dl) = (size, dl);
        }
        Ok(false)
    }

    /// One step of length h to `now` (the step's end): `m` becomes the state at its end.
    pub fn step(&mut self, system: &System, m: &mut Motion, h: f64, now: &Instant) -> Result<(), AssemblyError> {
        if self.first {
            self.coefficients = Coefficients::of(0.0);
            self.matrix_step = None;
            let done = self.step_with_kept(system, m, h, now);
            self.coefficients = Coefficients::of(self.settings.spectral_radius);
            self.matrix_step = None;
            if done.is_ok() {
                self.first = false;
                // the pseudo-accelerations of the run's own coefficients start from the step's
                m.pseudo.copy_from_slice(&m.acc);
            }
            return done;
        }
        self.step_with_kept(system, m, h, now)
    }

    fn step_with_kept(&mut self, system: &System, m: &mut Motion, h: f64, now: &Instant) -> Result<(), AssemblyError> {
        // the kept matrix, then one from the bodies' equations, then one by differences
        for attempt in 0..3 {
            self.work.acc.copy_from_slice(&m.acc);
            self.work.lambda.copy_from_slice(&m.lambda);
            // a master's steps that differ by round-off (libcosim's nanosecond clock) keep it
            let stale = self.matrix_step.is_none_or(|kept| (kept - h).abs() > 1e-6 * h);
            let fresh = attempt > 0 || stale;
            if attempt == 2 {
                self.form_matrix(system, m, h, now)?;
            } else if fresh {
                self.form_model_matrix(system, m, h, now)?;
            }
            if self.iterate(system, m, h, now, fresh)? {
                let w = &self.work;
                if w.pos.iter().chain(&w.vel).chain(&w.acc).chain(&w.lambda).any(|x| !x.is_finite()) {
                    return Err(AssemblyError::NotFinite { time: now.t - h });
                }
                m.pos.copy_from_slice(&w.pos);
                m.vel.copy_from_slice(&w.vel);
                m.acc.copy_from_slice(&w.acc);
                m.pseudo.copy_from_slice(&w.pseudo);
                m.lambda.copy_from_slice(&w.lambda);
                for x in [&mut m.acc, &mut m.pseudo] {
                    system.zero_modes_from(x, |b| b.n_dynamic);
                }
                system.zero_modes_from(&mut m.vel, |b| b.n_moving);
                // dropped, not flagged: a saved state without a kept matrix steps on the same
                if self.last_iterations >= REFORM_AFTER {
                    self.matrix_step = None;
                }
                return Ok(());
            }
            if attempt == 2 {
                break;
            }
        }
        let residual = self.work.residual.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        Err(AssemblyError::NotConverged { time: now.t, residual })
    }
}

/// The joints' blocks of a saddle-point matrix (dimension nv + ne, row-major): -B^T in the
/// multipliers' columns of the body rows, B in the joints' rows.
fn put_joint_blocks(matrix: &mut [f64], jac: &[f64], nv: usize, ne: usize) {
    let dim = nv + ne;
    for k in 0..ne {
        for j in 0..nv {
            let b = jac[k * nv + j];
            matrix[j * dim + nv + k] = -b;
            matrix[(nv + k) * dim + j] = b;
        }
    }
}
