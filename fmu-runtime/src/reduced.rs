//! The reduced flexible body as the runtime sees it: modal coordinates q with unit modal mass and
//! diagonal stiffness, the flange shapes, and the inertia invariants of the floating frame.
//! Everything is resolved in the body frame B, whose origin is the mount flange's reference point
//! and whose axes are the world axes of the undeformed part.

use crate::format::{Container, FormatError};

#[derive(Debug, Clone, PartialEq)]
pub struct FlangeShapes {
    pub name: String,
    /// Reference point of the flange in B [m].
    pub position: [f64; 3],
    /// 6 x n, row-major: rows 0..3 translation u, rows 3..6 rotation phi of the flange per unit q.
    pub shapes: Vec<f64>,
}

/// A node where the FMU recovers stresses.
#[derive(Debug, Clone, PartialEq)]
pub struct StressPoint {
    /// Variable name stem (`stress.<name>.sxx`, ...).
    pub name: String,
    /// Which node and why (node set, nearest to a point, hot spot), for the variables'
    /// descriptions.
    pub description: String,
    /// Position of the node in B [m].
    pub position: [f64; 3],
    /// 6 x n, row-major: stress components xx, yy, zz, xy, yz, zx in B [Pa] per unit q.
    pub modes: Vec<f64>,
}

/// Rotating-frame invariants (docs/ARCHITECTURE.md, "Equations"), row-major:
/// G_a = Phi^T M E_a Phi (3 x r x r, skew), O_ab = Phi^T M E_a E_b Phi (3 x 3 x r x r),
/// o_ab = Phi^T M E_a E_b X (3 x 3 x r). (c_a = Phi^T M E_a X are the rows of C_r.)
#[derive(Debug, Clone, PartialEq)]
pub struct RotationTerms {
    pub g: Vec<f64>,
    pub o_mat: Vec<f64>,
    pub o_vec: Vec<f64>,
}

/// Reduced geometric stiffness per unit load, row-major r x r blocks: the stiffness added by the
/// prestress of the present loads is the sum of these scaled by the loads.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Stiffening {
    /// Per w_a w_b (3 x 3 x r x r): sum_ab w_a w_b K_ab is the centrifugal prestress stiffness.
    pub centrifugal: Option<Vec<f64>>,
    /// Per angular acceleration component (3 x r x r).
    pub euler: Option<Vec<f64>>,
    /// Per component of a_B = A^T (a - g) (3 x r x r).
    pub translation: Option<Vec<f64>>,
    /// Per force flange, per body-frame wrench component f_x..t_z (6 x r x r); empty: none.
    pub flanges: Vec<Vec<f64>>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ReducedBody {
    pub guid: String,
    pub model_name: String,
    /// Name of the mount (motion) flange carrying the body frame.
    pub mount: String,
    /// Modal angular frequencies [rad/s], ascending; reduced stiffness = diag(omega^2), mass = I.
    pub omega: Vec<f64>,
    /// Rayleigh damping defaults (D = alpha M + beta K), the FMU parameters' start values.
    pub alpha: f64,
    pub beta: f64,
    /// Fixed modal damping added per mode, 2 zeta_k omega_k [1/s] (zeros: none).
    pub modal_damping: Vec<f64>,
    pub mass: f64,
    /// m * c: first moment of mass about the body origin, undeformed [kg m].
    pub first_moment: [f64; 3],
    /// Inertia tensor about the body origin, undeformed, row-major [kg m^2].
    pub inertia: [f64; 9],
    /// C_t = T^T M Phi (3 x n): momentum of the elastic motion per unit q'.
    pub c_t: Vec<f64>,
    /// C_r = R_X^T M Phi (3 x n): angular momentum about the origin per unit q'.
    pub c_r: Vec<f64>,
    /// Force flanges (loaded or free), in the order of the FMU's variables.
    pub flanges: Vec<FlangeShapes>,
    /// Stress recovery points, in the order of the FMU's variables.
    pub stress_points: Vec<StressPoint>,
    /// Present when the body may rotate; without it the mount must not rotate.
    pub rotation: Option<RotationTerms>,
    pub stiffening: Option<Stiffening>,
    /// No mount: the FMU integrates the rigid-body motion; the body frame is at the centre of
    /// mass with mean axes (C_t = 0, C_r = 0), and `mount` is empty.
    pub free_floating: bool,
    /// Modes up to this angular frequency [rad/s] carry the scene's dynamics; those above it are
    /// quasi-static in Model Exchange (algebraic: solved from the loads and the dynamic modes at
    /// every evaluation), so the host's integrator never sees their stiffness. Infinite: every
    /// mode is dynamic.
    pub dynamic_cutoff: f64,
}

impl ReducedBody {
    pub fn n_modes(&self) -> usize {
        self.omega.len()
    }

    /// Whether the modes can couple: a mounted body with rotation or stiffening terms (the
    /// coupled propagator, its scratch and the coupling-term norms exist only then).
    pub fn modes_couple(&self) -> bool {
        !self.free_floating && (self.rotation.is_some() || self.stiffening.is_some())
    }

    /// Number of dynamic modes: the first ones (omega ascending) up to the cutoff.
    pub fn n_dynamic(&self) -> usize {
        self.omega.iter().take_while(|&&w| w <= self.dynamic_cutoff).count()
    }

    /// d of mode j's q'' + d q' + omega^2 q = p under Rayleigh alpha, beta (the built ones or
    /// the run-time parameters) and the modal damping: alpha + beta omega^2 + 2 zeta omega [1/s].
    pub fn damping_rate(&self, j: usize, alpha: f64, beta: f64) -> f64 {
        alpha + beta * self.omega[j] * self.omega[j] + self.modal_damping[j]
    }

    /// Rate [1/s] at which mode j settles once its inertia is dropped and its damping kept,
    /// omega^2 / (alpha + beta omega^2 + 2 zeta omega); infinite for an undamped mode.
    pub fn relaxation_rate(&self, j: usize, alpha: f64, beta: f64) -> f64 {
        let d = self.damping_rate(j, alpha, beta);
        if d > 0.0 { self.omega[j] * self.omega[j] / d } else { f64::INFINITY }
    }

    /// Number of dynamic modes without damping at alpha, beta: a variable-step host's error in
    /// them is never forgotten, so loose tolerances drift over long runs.
    pub fn n_undamped_dynamic(&self, alpha: f64, beta: f64) -> usize {
        (0..self.n_dynamic()).filter(|&j| self.damping_rate(j, alpha, beta) <= 0.0).count()
    }

    /// The longest step [s] at which explicit Euler stays stable for every Model Exchange state
    /// at damping alpha, beta (|1 + h lambda| <= 1 for each eigenvalue lambda), and the mode that
    /// limits it; 0 where a dynamic mode is undamped (no step is stable: each one multiplies its
    /// amplitude by sqrt(1 + h^2 omega^2)).
    pub fn explicit_euler_limit(&self, alpha: f64, beta: f64) -> (f64, Option<usize>) {
        let nd = self.n_dynamic();
        let mut limit = (f64::INFINITY, None);
        for j in 0..nd + self.n_relaxing() {
            let h = self.explicit_euler_step(j, alpha, beta, j >= nd);
            if h < limit.0 {
                limit = (h, Some(j));
            }
        }
        limit
    }

    /// The longest stable explicit Euler step of mode j as a dynamic state (q, q') or, with
    /// `relaxing`, as a first-order one (q' = -(omega^2 / d) q).
    pub fn explicit_euler_step(&self, j: usize, alpha: f64, beta: f64, relaxing: bool) -> f64 {
        let (w2, d) = (self.omega[j] * self.omega[j], self.damping_rate(j, alpha, beta));
        if relaxing {
            2.0 * d / w2
        } else if d < 2.0 * self.omega[j] {
            // |1 + h lambda|^2 = 1 - h d + h^2 omega^2
            d / w2
        } else {
            2.0 / (0.5 * d + (0.25 * d * d - w2).sqrt())
        }
    }

    /// Number of relaxing modes: the quasi-static modes, next after the dynamic ones, that
    /// settle slower than the cutoff (overdamped by stiffness-proportional damping, whose
    /// relaxation tends to 1/beta whatever their frequency). Model Exchange keeps them as
    /// first-order states (damping without inertia) instead of solving them algebraically,
    /// so a load change creeps through them as the material damping says. The rate grows
    /// with omega for Rayleigh and constant modal damping, so they are the leading ones.
    pub fn n_relaxing(&self) -> usize {
        (self.n_dynamic()..self.n_modes())
            .take_while(|&j| self.relaxation_rate(j, self.alpha, self.beta) < self.dynamic_cutoff)
            .count()
    }

    pub fn to_container(&self) -> Container {
        let n = self.n_modes();
        let mut c = Container::new();
        c.put_text("guid", &self.guid);
        c.put_text("model_name", &self.model_name);
        c.put_text("mount.name", &self.mount);
        c.put_array("omega", &[n], &self.omega);
        c.put_array("damping.alpha", &[1], &[self.alpha]);
        c.put_array("damping.beta", &[1], &[self.beta]);
        c.put_array("damping.modal", &[n], &self.modal_damping);
        c.put_array("mass", &[1], &[self.mass]);
        c.put_array("first_moment", &[3], &self.first_moment);
        c.put_array("inertia", &[3, 3], &self.inertia);
        c.put_array("c_t", &[3, n], &self.c_t);
        c.put_array("c_r", &[3, n], &self.c_r);
        c.put_array("flange.count", &[1], &[self.flanges.len() as f64]);
        for (i, f) in self.flanges.iter().enumerate() {
            c.put_text(&format!("flange.{i}.name"), &f.name);
            c.put_array(&format!("flange.{i}.position"), &[3], &f.position);
            c.put_array(&format!("flange.{i}.shapes"), &[6, n], &f.shapes);
        }
        if !self.stress_points.is_empty() {
            c.put_array("stress.count", &[1], &[self.stress_points.len() as f64]);
        }
        for (i, p) in self.stress_points.iter().enumerate() {
            c.put_text(&format!("stress.{i}.name"), &p.name);
            c.put_text(&format!("stress.{i}.description"), &p.description);
            c.put_array(&format!("stress.{i}.position"), &[3], &p.position);
            c.put_array(&format!("stress.{i}.modes"), &[6, n], &p.modes);
        }
        if self.free_floating {
            c.put_array("free_floating", &[1], &[1.0]);
        }
        if self.dynamic_cutoff.is_finite() {
            c.put_array("dynamic_cutoff", &[1], &[self.dynamic_cutoff]);
        }
        if let Some(rot) = &self.rotation {
            c.put_array("rotation.G", &[3, n, n], &rot.g);
            c.put_array("rotation.O", &[3, 3, n, n], &rot.o_mat);
            c.put_array("rotation.o", &[3, 3, n], &rot.o_vec);
        }
        if let Some(st) = &self.stiffening {
            c.put_array("stiffening", &[1], &[1.0]);
            if let Some(k) = &st.centrifugal {
                c.put_array("stiffening.centrifugal", &[3, 3, n, n], k);
            }
            if let Some(k) = &st.euler {
                c.put_array("stiffening.euler", &[3, n, n], k);
            }
            if let Some(k) = &st.translation {
                c.put_array("stiffening.translation", &[3, n, n], k);
            }
            for (i, k) in st.flanges.iter().enumerate() {
                if !k.is_empty() {
                    c.put_array(&format!("stiffening.flange.{i}"), &[6, n, n], k);
                }
            }
        }
        c
    }

    pub fn from_container(c: &Container) -> Result<Self, FormatError> {
        let omega = read_omega(c)?;
        let n = omega.len();
        let dynamic_cutoff = if c.contains("dynamic_cutoff") { c.scalar("dynamic_cutoff")? } else { f64::INFINITY };
        if !(dynamic_cutoff > 0.0) {
            return Err(FormatError::Malformed(format!("dynamic_cutoff = {dynamic_cutoff} is not a positive number")));
        }
        let flanges = read_flanges(c, n)?;
        let stress_points = read_stress_points(c, n)?;
        let rotation = read_rotation(c, n)?;
        let stiffening = read_stiffening(c, n, flanges.len())?;
        let mass = read_mass_and_check_damping(c, n)?;
        let mut inertia = [0.0; 9];
        inertia.copy_from_slice(c.array("inertia", &[3, 3])?);
        Ok(Self {
            guid: c.text("guid")?.to_owned(),
            model_name: c.text("model_name")?.to_owned(),
            mount: c.text("mount.name")?.to_owned(),
            omega,
            alpha: c.scalar("damping.alpha")?,
            beta: c.scalar("damping.beta")?,
            modal_damping: c.array("damping.modal", &[n])?.to_vec(),
            mass,
            first_moment: to3(c.array("first_moment", &[3])?),
            inertia,
            c_t: c.array("c_t", &[3, n])?.to_vec(),
            c_r: c.array("c_r", &[3, n])?.to_vec(),
            flanges,
            stress_points,
            rotation,
            stiffening,
            free_floating: c.contains("free_floating"),
            dynamic_cutoff,
        })
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        self.to_container().to_bytes()
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        Self::from_container(&Container::from_bytes(bytes)?)
    }

    /// Give the body the GUID of its content (what the builder does before writing it).
    pub fn seal(&mut self) {
        self.guid.clear();
        self.guid = self.to_container().content_guid();
    }

    /// [`Self::from_bytes`] for a file of an FMU: the stored GUID must be the content's, so a
    /// file changed after the build (however consistent) is refused rather than run under the
    /// modelDescription.xml of another model.
    pub fn from_sealed_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        Self::from_container(&Container::from_sealed_bytes(bytes)?)
    }
}

/// The modal frequencies: positive, ascending.
fn read_omega(c: &Container) -> Result<Vec<f64>, FormatError> {
    let n = match c.dims("omega")? {
        [n] => *n,
        other => {
            return Err(FormatError::Shape { name: "omega".into(), found: other.to_vec(), expected: vec![0] });
        }
    };
    let omega = c.array("omega", &[n])?.to_vec();
    if let Some(bad) = omega.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(FormatError::Malformed(format!(
            "modal frequency omega[{bad}] = {} is not a positive number",
            omega[bad]
        )));
    }
    if let Some(k) = (1..n).find(|&k| omega[k] < omega[k - 1]) {
        return Err(FormatError::Malformed(format!(
            "modal frequencies must ascend: omega[{k}] = {} < omega[{}] = {}",
            omega[k],
            k - 1,
            omega[k - 1]
        )));
    }
    Ok(omega)
}

fn read_flanges(c: &Container, n: usize) -> Result<Vec<FlangeShapes>, FormatError> {
    let count = c.scalar("flange.count")?;
    if !(count >= 0.0 && count.fract() == 0.0 && count < 1e4) {
        return Err(FormatError::Malformed(format!("flange.count = {count}")));
    }
    let mut flanges = Vec::new();
    for i in 0..count as usize {
        flanges.push(FlangeShapes {
            name: c.text(&format!("flange.{i}.name"))?.to_owned(),
            position: to3(c.array(&format!("flange.{i}.position"), &[3])?),
            shapes: c.array(&format!("flange.{i}.shapes"), &[6, n])?.to_vec(),
        });
    }
    Ok(flanges)
}

fn read_stress_points(c: &Container, n: usize) -> Result<Vec<StressPoint>, FormatError> {
    let stress_count = if c.contains("stress.count") { c.scalar("stress.count")? } else { 0.0 };
    if !(stress_count >= 0.0 && stress_count.fract() == 0.0 && stress_count <= 1e4) {
        return Err(FormatError::Malformed(format!("stress.count = {stress_count}")));
    }
    let mut stress_points = Vec::new();
    for i in 0..stress_count as usize {
        stress_points.push(StressPoint {
            name: c.text(&format!("stress.{i}.name"))?.to_owned(),
            description: c.text(&format!("stress.{i}.description"))?.to_owned(),
            position: to3(c.array(&format!("stress.{i}.position"), &[3])?),
            modes: c.array(&format!("stress.{i}.modes"), &[6, n])?.to_vec(),
        });
    }
    Ok(stress_points)
}

fn read_rotation(c: &Container, n: usize) -> Result<Option<RotationTerms>, FormatError> {
    Ok(if c.contains("rotation.G") {
        Some(RotationTerms {
            g: c.array("rotation.G", &[3, n, n])?.to_vec(),
            o_mat: c.array("rotation.O", &[3, 3, n, n])?.to_vec(),
            o_vec: c.array("rotation.o", &[3, 3, n])?.to_vec(),
        })
    } else {
        None
    })
}

fn read_stiffening(c: &Container, n: usize, n_flanges: usize) -> Result<Option<Stiffening>, FormatError> {
    let optional = |name: &str, dims: &[usize]| -> Result<Option<Vec<f64>>, FormatError> {
        if c.contains(name) { Ok(Some(c.array(name, dims)?.to_vec())) } else { Ok(None) }
    };
    Ok(if c.contains("stiffening") {
        let mut flange_k = Vec::new();
        for i in 0..n_flanges {
            flange_k.push(optional(&format!("stiffening.flange.{i}"), &[6, n, n])?.unwrap_or_default());
        }
        Some(Stiffening {
            centrifugal: optional("stiffening.centrifugal", &[3, 3, n, n])?,
            euler: optional("stiffening.euler", &[3, n, n])?,
            translation: optional("stiffening.translation", &[3, n, n])?,
            flanges: flange_k,
        })
    } else {
        None
    })
}

/// The mass, after the checks of mass and damping.
fn read_mass_and_check_damping(c: &Container, n: usize) -> Result<f64, FormatError> {
    // the builder never writes these (finiteness is the container's check)
    let mass = c.scalar("mass")?;
    if !(mass > 0.0) {
        return Err(FormatError::Malformed(format!("mass = {mass} is not positive")));
    }
    for name in ["damping.alpha", "damping.beta"] {
        if c.scalar(name)? < 0.0 {
            return Err(FormatError::Malformed(format!("{name} = {} is negative", c.scalar(name)?)));
        }
    }
    if let Some(j) = c.array("damping.modal", &[n])?.iter().position(|&d| d < 0.0) {
        return Err(FormatError::Malformed(format!("damping.modal[{j}] is negative")));
    }
    Ok(mass)
}

fn to3(s: &[f64]) -> [f64; 3] {
    [s[0], s[1], s[2]]
}

/// A two-mode body with one force flange: a small, valid body for tests (here and in the
/// builder's packaging tests). Not in the FMU's binary: compiled for this crate's tests and
/// with the `fixtures` feature, which only dev-dependencies enable.
#[cfg(any(test, feature = "fixtures"))]
#[doc(hidden)]
pub fn two_mode_body() -> ReducedBody {
    ReducedBody {
        guid: "{test}".into(),
        model_name: "Test".into(),
        mount: "base".into(),
        omega: vec![10.0, 2000.0],
        alpha: 0.5,
        beta: 1e-4,
        modal_damping: vec![0.0, 0.0],
        mass: 2.0,
        first_moment: [1.0, 0.0, 0.0],
        inertia: [0.1, 0.0, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 0.7],
        c_t: vec![0.0, 0.1, 0.3, 0.0, 0.0, 0.2],
        c_r: vec![0.0, 0.0, 0.0, -0.2, 0.0, 0.0],
        flanges: vec![FlangeShapes {
            name: "tip".into(),
            position: [1.0, 0.0, 0.0],
            shapes: vec![0.0, 0.1, 0.5, 0.0, 0.0, 0.3, 0.2, 0.0, 0.0, -0.6, 0.0, 0.0],
        }],
        stress_points: Vec::new(),
        rotation: None,
        stiffening: None,
        free_floating: false,
        dynamic_cutoff: f64::INFINITY,
    }
}

/// [`two_mode_body`] with rotating-frame terms and geometric stiffening: a spinning mount's
/// gyroscopic coupling and prestress for tests.
#[cfg(any(test, feature = "fixtures"))]
#[doc(hidden)]
pub fn rotating_two_mode_body() -> ReducedBody {
    let mut body = two_mode_body();
    let n = body.n_modes();
    body.rotation = Some(fixture_rotation_terms(n));
    let diag = |scale: f64, blocks: usize| {
        let mut k = vec![0.0; blocks * n * n];
        for b in 0..blocks {
            for j in 0..n {
                k[b * n * n + j * n + j] = scale * (b + 1) as f64;
            }
        }
        k
    };
    body.stiffening = Some(Stiffening {
        centrifugal: Some(diag(0.05, 9)),
        euler: Some(diag(0.01, 3)),
        translation: Some(diag(0.002, 3)),
        flanges: vec![diag(0.003, 6)],
    });
    body
}

/// [`two_mode_body`] free-floating: no mount, body frame at the centre of mass, rotation terms.
#[cfg(any(test, feature = "fixtures"))]
#[doc(hidden)]
pub fn free_two_mode_body() -> ReducedBody {
    let mut body = two_mode_body();
    let n = body.n_modes();
    body.free_floating = true;
    body.mount = String::new();
    body.c_t = vec![0.0; 3 * n];
    body.c_r = vec![0.0; 3 * n];
    body.first_moment = [0.0; 3];
    body.rotation = Some(fixture_rotation_terms(n));
    body
}

/// Rotating-frame invariants of the right structure (G skew, O symmetric per mode pair).
#[cfg(any(test, feature = "fixtures"))]
fn fixture_rotation_terms(n: usize) -> RotationTerms {
    let nn = n * n;
    let mut g = vec![0.0; 3 * nn];
    for (a, s) in [0.05, 0.1, 0.02].into_iter().enumerate() {
        g[a * nn + 1] = s;
        g[a * nn + n] = -s;
    }
    let mut o_mat = vec![0.0; 9 * nn];
    for a in 0..3 {
        for b in 0..3 {
            for j in 0..n {
                o_mat[(3 * a + b) * nn + j * n + j] = if a == b { 0.3 / (j + 1) as f64 } else { 0.01 };
            }
        }
    }
    let o_vec = (0..9 * n).map(|i| 0.01 * ((i % 5) as f64 - 2.0)).collect();
    RotationTerms { g, o_mat, o_vec }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The growth of explicit Euler's step matrix [[1, h], [-h w^2, 1 - h d]] over many steps,
    /// by iterating it: independent of the closed form the limit uses.
    fn euler_growth(w: f64, d: f64, h: f64) -> f64 {
        let (mut x, mut v) = (1.0f64, 0.0f64);
        for _ in 0..20_000 {
            (x, v) = (x + h * v, v - h * (w * w * x + d * v));
        }
        x.hypot(v / w)
    }

    #[test]
    fn explicit_euler_limit_is_where_the_step_matrix_stops_growing() {
        let mut body = two_mode_body();
        // 1 % of critical on the 10 rad/s mode, Rayleigh alpha 0.5, beta 1e-4 (the 2000 rad/s
        // mode: d = 0.5 + 400 + 40, underdamped)
        body.modal_damping = vec![2.0 * 0.01 * 10.0, 0.0];
        let (h, mode) = body.explicit_euler_limit(body.alpha, body.beta);
        assert!(h > 0.0 && h.is_finite());
        let j = mode.unwrap();
        let d = body.damping_rate(j, body.alpha, body.beta);
        assert!(euler_growth(body.omega[j], d, 0.99 * h) < 1.0, "stable just below the limit");
        assert!(euler_growth(body.omega[j], d, 1.01 * h) > 1.0, "unstable just above it");
        // undamped: no step is stable
        let (h0, _) = body.explicit_euler_limit(0.0, 0.0);
        body.modal_damping = vec![0.0, 0.0];
        assert_eq!(body.explicit_euler_limit(0.0, 0.0).0, 0.0, "{h0}");
        // above the cutoff a mode is no state and does not limit the step
        body.dynamic_cutoff = 100.0;
        body.modal_damping = vec![2.0 * 0.01 * 10.0, 0.0];
        let (h1, mode1) = body.explicit_euler_limit(0.0, 0.0);
        assert_eq!(mode1, Some(0));
        assert!((h1 - 0.2 / 100.0).abs() < 1e-15, "d / w^2 = 0.2 / 100: {h1}");
    }
    use crate::reduced::two_mode_body;

    #[test]
    fn round_trip_through_bytes() {
        let b = two_mode_body();
        assert_eq!(ReducedBody::from_bytes(&b.to_bytes()).unwrap(), b);
    }

    #[test]
    fn missing_entry_is_named() {
        let mut c = two_mode_body().to_container();
        let mut c2 = Container::new();
        // rebuild without c_r
        for name in ["guid", "model_name", "mount.name"] {
            c2.put_text(name, c.text(name).unwrap());
        }
        c2.put_array("omega", &[2], &[10.0, 2000.0]);
        let err = ReducedBody::from_container(&c2).unwrap_err();
        assert!(matches!(err, FormatError::Missing(_)), "{err}");
        c.put_array("omega", &[2], &[10.0, -1.0]);
        assert!(ReducedBody::from_container(&c).unwrap_err().to_string().contains("omega[1]"));
        c.put_array("omega", &[2], &[10.0, 5.0]);
        let err = ReducedBody::from_container(&c).unwrap_err().to_string();
        assert!(err.contains("must ascend"), "{err}");
    }

    #[test]
    fn the_cutoff_splits_dynamic_from_quasi_static_modes_and_round_trips() {
        let mut b = two_mode_body();
        assert_eq!(b.n_dynamic(), 2, "no cutoff: every mode dynamic");
        b.dynamic_cutoff = 100.0;
        assert_eq!(b.n_dynamic(), 1);
        assert_eq!(ReducedBody::from_bytes(&b.to_bytes()).unwrap(), b);
        let mut c = b.to_container();
        c.put_array("dynamic_cutoff", &[1], &[-1.0]);
        let err = ReducedBody::from_container(&c).unwrap_err().to_string();
        assert!(err.contains("dynamic_cutoff"), "{err}");
    }
}
