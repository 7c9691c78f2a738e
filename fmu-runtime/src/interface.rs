//! The FMU's variables and what each one means for the body: the one table from which the builder
//! writes modelDescription.xml and through which the runtime answers fmi2Get/Set. Names follow
//! Naming: flange `tip` has inputs `tip.f[i]`, `tip.t[i]`, outputs `tip.r[i]`, `tip.R[i,j]`, ...

use crate::reduced::ReducedBody;
use fmi2::{Causality, Initial, VarType, Variability};

/// Per-flange output quantities.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlangeOutput {
    Position(usize),
    Rotation(usize, usize),
    Velocity(usize),
    AngularVelocity(usize),
    Acceleration(usize),
    AngularAcceleration(usize),
    Displacement(usize),
    RotationVector(usize),
}

/// What a variable stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    MountPosition(usize),
    MountRotation(usize, usize),
    MountVelocity(usize),
    MountAngularVelocity(usize),
    MountAcceleration(usize),
    MountAngularAcceleration(usize),
    MountForce(usize),
    MountTorque(usize),
    FlangeForce(usize, usize),
    FlangeTorque(usize, usize),
    Flange(usize, FlangeOutput),
    /// Stress at recovery point k, component i: xx, yy, zz, xy, yz, zx (0..6), von Mises (6).
    Stress(usize, usize),
    Gravity(usize),
    RayleighAlpha,
    RayleighBeta,
    StaticStart,
    ModalCoordinate(usize),
    ModalVelocity(usize),
    ModalAcceleration(usize),
    // free-floating bodies
    InitialPosition(usize),
    InitialRotation(usize),
    InitialVelocity(usize),
    InitialAngularVelocity(usize),
    FramePosition(usize),
    FrameQuaternion(usize),
    FrameVelocity(usize),
    FrameAngularVelocity(usize),
    FrameQuaternionRate(usize),
    FrameAcceleration(usize),
    FrameAngularAcceleration(usize),
    BodyRotation(usize, usize),
    BodyAngularVelocity(usize),
    BodyAngularAcceleration(usize),
    BodyEnergy,
    BodyMomentum(usize),
    BodyAngularMomentum(usize),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    Real(f64),
    Boolean(bool),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    pub vr: u32,
    pub name: String,
    pub description: String,
    pub var_type: VarType,
    pub causality: Causality,
    pub variability: Variability,
    /// Written to the XML only where it differs from the FMI default for the causality.
    pub initial: Option<Initial>,
    pub start: Option<Start>,
    pub unit: Option<&'static str>,
    pub quantity: Quantity,
    /// For a state derivative: the value reference of its state.
    pub derivative_of: Option<u32>,
    /// For a continuous state: its expected magnitude, which hosts scale their absolute
    /// tolerance by (FMI 2.0 `nominal`, fmi2GetNominalsOfContinuousStates).
    pub nominal: Option<f64>,
}

/// Units used by the variables, with their SI base-unit exponents (kg, m, s, rad) for the XML.
pub const UNITS: &[(&str, [i32; 4])] = &[
    ("m", [0, 1, 0, 0]),
    ("m/s", [0, 1, -1, 0]),
    ("m/s2", [0, 1, -2, 0]),
    ("rad", [0, 0, 0, 1]),
    ("rad/s", [0, 0, -1, 1]),
    ("rad/s2", [0, 0, -2, 1]),
    ("N", [1, 1, -2, 0]),
    ("N.m", [1, 2, -2, 0]),
    ("1/s", [0, 0, -1, 0]),
    ("1/s2", [0, 0, -2, 0]),
    ("s", [0, 0, 1, 0]),
    ("J", [1, 2, -2, 0]),
    ("N.s", [1, 1, -1, 0]),
    ("J.s", [1, 2, -1, 0]),
    ("Pa", [1, -1, -2, 0]),
];

/// Names of the stress outputs of a recovery point, in `Quantity::Stress` component order.
pub const STRESS_COMPONENTS: [&str; 7] = ["sxx", "syy", "szz", "sxy", "syz", "szx", "mises"];

const AXES: [&str; 3] = ["x", "y", "z"];

/// The variable table of a body, value references 1.. in table order.
#[derive(Debug, Clone)]
pub struct VariableTable {
    pub variables: Vec<Variable>,
    /// Modes 1..=n_dynamic are states; the rest are quasi-static (Model Exchange solves them from
    /// the inputs and the states at every evaluation).
    pub n_dynamic: usize,
    /// Modes n_dynamic+1..=n_dynamic+n_relaxing are relaxing: their q is a state whose rate
    /// q' is solved from their damping without inertia.
    pub n_relaxing: usize,
    /// The body has rotating-frame terms, through which q'_d loads the quasi-static modes.
    rotates: bool,
}

struct Builder {
    variables: Vec<Variable>,
}

impl Builder {
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        name: String,
        description: String,
        causality: Causality,
        variability: Variability,
        initial: Option<Initial>,
        start: Option<Start>,
        unit: Option<&'static str>,
        quantity: Quantity,
    ) -> u32 {
        let vr = self.variables.len() as u32 + 1;
        let var_type = match start {
            Some(Start::Boolean(_)) => VarType::Boolean,
            _ => VarType::Real,
        };
        self.variables.push(Variable {
            vr,
            name,
            description,
            var_type,
            causality,
            variability,
            initial,
            start,
            unit,
            quantity,
            derivative_of: None,
            nominal: None,
        });
        vr
    }

    fn input3(&mut self, prefix: &str, what: &str, unit: &'static str, q: impl Fn(usize) -> Quantity) {
        for (i, axis) in AXES.iter().enumerate() {
            self.push(
                format!("{prefix}[{}]", i + 1),
                format!("{what}, {axis} component, world frame"),
                Causality::Input,
                Variability::Continuous,
                None,
                Some(Start::Real(0.0)),
                Some(unit),
                q(i),
            );
        }
    }

    fn output3(&mut self, prefix: &str, what: &str, frame: &str, unit: &'static str, q: impl Fn(usize) -> Quantity) {
        for (i, axis) in AXES.iter().enumerate() {
            self.push(
                format!("{prefix}[{}]", i + 1),
                format!("{what}, {axis} component, {frame}"),
                Causality::Output,
                Variability::Continuous,
                None,
                None,
                Some(unit),
                q(i),
            );
        }
    }

    fn matrix(&mut self, prefix: &str, what: &str, causality: Causality, q: impl Fn(usize, usize) -> Quantity) {
        for i in 0..3 {
            for j in 0..3 {
                let start = (causality == Causality::Input).then_some(Start::Real(if i == j { 1.0 } else { 0.0 }));
                self.push(
                    format!("{prefix}[{},{}]", i + 1, j + 1),
                    format!("{what}, row {} column {} (columns: frame axes in world)", i + 1, j + 1),
                    causality,
                    Variability::Continuous,
                    None,
                    start,
                    Some("1"),
                    q(i, j),
                );
            }
        }
    }
}

impl VariableTable {
    pub fn new(body: &ReducedBody) -> Self {
        let mut b = Builder { variables: Vec::new() };
        let m = body.mount.as_str();
        if !body.free_floating {
            b.input3(&format!("{m}.r"), "Mount position", "m", Quantity::MountPosition);
            b.matrix(&format!("{m}.R"), "Mount orientation", Causality::Input, Quantity::MountRotation);
            b.input3(&format!("{m}.v"), "Mount velocity", "m/s", Quantity::MountVelocity);
            b.input3(&format!("{m}.w"), "Mount angular velocity", "rad/s", Quantity::MountAngularVelocity);
            b.input3(&format!("{m}.a"), "Mount acceleration", "m/s2", Quantity::MountAcceleration);
            b.input3(&format!("{m}.z"), "Mount angular acceleration", "rad/s2", Quantity::MountAngularAcceleration);
            b.output3(
                &format!("{m}.f"),
                "Force the mount applies to the body",
                "world frame",
                "N",
                Quantity::MountForce,
            );
            b.output3(
                &format!("{m}.t"),
                "Torque the mount applies to the body about the mount point",
                "world frame",
                "N.m",
                Quantity::MountTorque,
            );
        }
        for (k, flange) in body.flanges.iter().enumerate() {
            let n = flange.name.as_str();
            b.input3(&format!("{n}.f"), "Force applied to the flange", "N", |i| Quantity::FlangeForce(k, i));
            b.input3(&format!("{n}.t"), "Torque applied to the flange about its reference point", "N.m", |i| {
                Quantity::FlangeTorque(k, i)
            });
            let out = |o: FlangeOutput| Quantity::Flange(k, o);
            b.output3(&format!("{n}.r"), "Flange position", "world frame", "m", |i| out(FlangeOutput::Position(i)));
            b.matrix(&format!("{n}.R"), "Flange orientation", Causality::Output, |i, j| {
                out(FlangeOutput::Rotation(i, j))
            });
            b.output3(&format!("{n}.v"), "Flange velocity", "world frame", "m/s", |i| out(FlangeOutput::Velocity(i)));
            b.output3(&format!("{n}.w"), "Flange angular velocity", "world frame", "rad/s", |i| {
                out(FlangeOutput::AngularVelocity(i))
            });
            b.output3(&format!("{n}.a"), "Flange acceleration", "world frame", "m/s2", |i| {
                out(FlangeOutput::Acceleration(i))
            });
            b.output3(&format!("{n}.z"), "Flange angular acceleration", "world frame", "rad/s2", |i| {
                out(FlangeOutput::AngularAcceleration(i))
            });
            b.output3(&format!("{n}.u"), "Flange displacement relative to the mount", "body frame", "m", |i| {
                out(FlangeOutput::Displacement(i))
            });
            b.output3(
                &format!("{n}.phi"),
                "Flange rotation relative to the mount (rotation vector)",
                "body frame",
                "rad",
                |i| out(FlangeOutput::RotationVector(i)),
            );
        }
        for (k, point) in body.stress_points.iter().enumerate() {
            for (i, component) in STRESS_COMPONENTS.iter().enumerate() {
                let what = match i {
                    0..3 => format!("Normal stress {component}, body frame"),
                    3..6 => format!("Shear stress {component}, body frame"),
                    _ => "Von Mises equivalent stress".to_string(),
                };
                b.push(
                    format!("{}.{component}", point.name),
                    format!("{what}, at {}", point.description),
                    Causality::Output,
                    Variability::Continuous,
                    None,
                    None,
                    Some("Pa"),
                    Quantity::Stress(k, i),
                );
            }
        }
        for (i, axis) in AXES.iter().enumerate() {
            b.push(
                format!("g[{}]", i + 1),
                format!("Gravitational acceleration, {axis} component, world frame"),
                Causality::Parameter,
                Variability::Fixed,
                None,
                Some(Start::Real(0.0)),
                Some("m/s2"),
                Quantity::Gravity(i),
            );
        }
        b.push(
            "damping.alpha".into(),
            "Rayleigh damping: mass-proportional coefficient (D = alpha M + beta K)".into(),
            Causality::Parameter,
            Variability::Fixed,
            None,
            Some(Start::Real(body.alpha)),
            Some("1/s"),
            Quantity::RayleighAlpha,
        );
        b.push(
            "damping.beta".into(),
            "Rayleigh damping: stiffness-proportional coefficient".into(),
            Causality::Parameter,
            Variability::Fixed,
            None,
            Some(Start::Real(body.beta)),
            Some("s"),
            Quantity::RayleighBeta,
        );
        if !body.free_floating {
            b.push(
            "static_start".into(),
            "Start in static equilibrium under the initial inputs (q' = 0, q = K^-1 p) instead of at the start values of q, qd".into(),
            Causality::Parameter,
            Variability::Fixed,
            None,
            Some(Start::Boolean(false)),
            None,
            Quantity::StaticStart,
        );
        }
        if body.free_floating {
            Self::free_body_parameters(&mut b);
        }
        let n = body.n_modes();
        let nd = body.n_dynamic();
        let nr = body.n_relaxing();
        let nominal = modal_nominals(body);
        // a dynamic mode's q, q' are states with start values; a quasi-static mode's are
        // calculated (its equilibrium with the inputs and the dynamic modes, at rest), a
        // relaxing mode's q a state that starts there
        let initial = |j: usize| Some(if j < nd { Initial::Approx } else { Initial::Calculated });
        let start = |j: usize| (j < nd).then_some(Start::Real(0.0));
        let kind = |j: usize| {
            if j < nd {
                ""
            } else if j < nd + nr {
                ", relaxing in Model Exchange: damped without inertia"
            } else {
                ", quasi-static in Model Exchange"
            }
        };
        let mut q_vr = Vec::with_capacity(n);
        for j in 0..n {
            q_vr.push(b.push(
                format!("q[{}]", j + 1),
                format!(
                    "Modal coordinate {} ({:.4} Hz{})",
                    j + 1,
                    body.omega[j] / (2.0 * std::f64::consts::PI),
                    kind(j)
                ),
                Causality::Local,
                Variability::Continuous,
                initial(j),
                start(j),
                None,
                Quantity::ModalCoordinate(j),
            ));
            if j < nd + nr {
                b.variables[q_vr[j] as usize - 1].nominal = Some(nominal[j]);
            }
        }
        let mut qd_vr = Vec::with_capacity(n);
        for (j, &q_vr_j) in q_vr.iter().enumerate() {
            let vr = b.push(
                format!("qd[{}]", j + 1),
                format!("Modal velocity {}{}", j + 1, kind(j)),
                Causality::Local,
                Variability::Continuous,
                initial(j),
                start(j),
                Some("1/s"),
                Quantity::ModalVelocity(j),
            );
            if j < nd + nr {
                b.variables[vr as usize - 1].derivative_of = Some(q_vr_j);
            }
            if j < nd {
                b.variables[vr as usize - 1].nominal = Some(body.omega[j] * nominal[j]);
            }
            qd_vr.push(vr);
        }
        for (j, &qd_vr_j) in qd_vr.iter().enumerate() {
            let vr = b.push(
                format!("der(qd[{}])", j + 1),
                format!("Modal acceleration {}{}", j + 1, kind(j)),
                Causality::Local,
                Variability::Continuous,
                None,
                None,
                Some("1/s2"),
                Quantity::ModalAcceleration(j),
            );
            if j < nd {
                b.variables[vr as usize - 1].derivative_of = Some(qd_vr_j);
            }
        }
        if body.free_floating {
            Self::free_body_states_and_outputs(&mut b);
        }
        // modal coordinates carry sqrt(kg) m, left unitless in the XML; their rates are then
        // 1/s and 1/s2
        Self { variables: b.variables, n_dynamic: nd, n_relaxing: nr, rotates: body.rotation.is_some() }
    }

    fn free_body_parameters(b: &mut Builder) {
        /// Name, description, unit and quantity of a vector parameter.
        type VectorParameter = (&'static str, &'static str, &'static str, fn(usize) -> Quantity);
        let params: [VectorParameter; 4] = [
            ("initial.r", "Initial position of the centre of mass", "m", Quantity::InitialPosition),
            (
                "initial.phi",
                "Initial orientation as a rotation vector (from the axes as meshed)",
                "rad",
                Quantity::InitialRotation,
            ),
            ("initial.v", "Initial velocity of the centre of mass", "m/s", Quantity::InitialVelocity),
            ("initial.w", "Initial angular velocity", "rad/s", Quantity::InitialAngularVelocity),
        ];
        for (name, what, unit, q) in params {
            for (i, axis) in AXES.iter().enumerate() {
                b.push(
                    format!("{name}[{}]", i + 1),
                    format!("{what}, {axis} component, world frame"),
                    Causality::Parameter,
                    Variability::Fixed,
                    None,
                    Some(Start::Real(0.0)),
                    Some(unit),
                    q(i),
                );
            }
        }
    }

    /// States (centre-of-mass position and velocity, quaternion, body-frame angular velocity),
    /// their derivatives, and the body's outputs.
    fn free_body_states_and_outputs(b: &mut Builder) {
        let state = |b: &mut Builder, name: String, what: String, unit: Option<&'static str>, q: Quantity| {
            b.push(name, what, Causality::Local, Variability::Continuous, Some(Initial::Calculated), None, unit, q)
        };
        let mut r_vr = [0; 3];
        let mut v_vr = [0; 3];
        let mut quat_vr = [0; 4];
        let mut w_vr = [0; 3];
        for i in 0..3 {
            r_vr[i] = state(
                b,
                format!("frame.r[{}]", i + 1),
                format!("Centre-of-mass position, {}, world (state)", AXES[i]),
                Some("m"),
                Quantity::FramePosition(i),
            );
        }
        for (i, vr) in quat_vr.iter_mut().enumerate() {
            *vr = state(
                b,
                format!("frame.Q[{}]", i + 1),
                format!("Orientation quaternion component {} (w, x, y, z; state)", i + 1),
                Some("1"),
                Quantity::FrameQuaternion(i),
            );
        }
        for i in 0..3 {
            v_vr[i] = state(
                b,
                format!("frame.v[{}]", i + 1),
                format!("Centre-of-mass velocity, {}, world (state)", AXES[i]),
                Some("m/s"),
                Quantity::FrameVelocity(i),
            );
            b.variables[v_vr[i] as usize - 1].derivative_of = Some(r_vr[i]);
        }
        for i in 0..3 {
            w_vr[i] = state(
                b,
                format!("frame.W[{}]", i + 1),
                format!("Angular velocity, {}, body frame (state)", AXES[i]),
                Some("rad/s"),
                Quantity::FrameAngularVelocity(i),
            );
        }
        let derivative =
            |b: &mut Builder, name: String, what: String, unit: Option<&'static str>, q: Quantity, of: u32| {
                let vr = b.push(name, what, Causality::Local, Variability::Continuous, None, None, unit, q);
                b.variables[vr as usize - 1].derivative_of = Some(of);
            };
        for (i, &of) in quat_vr.iter().enumerate() {
            derivative(
                b,
                format!("der(frame.Q[{}])", i + 1),
                format!("Quaternion rate {}", i + 1),
                Some("1/s"),
                Quantity::FrameQuaternionRate(i),
                of,
            );
        }
        for i in 0..3 {
            derivative(
                b,
                format!("der(frame.v[{}])", i + 1),
                format!("Centre-of-mass acceleration, {}, world", AXES[i]),
                Some("m/s2"),
                Quantity::FrameAcceleration(i),
                v_vr[i],
            );
        }
        for i in 0..3 {
            derivative(
                b,
                format!("der(frame.W[{}])", i + 1),
                format!("Angular acceleration, {}, body frame", AXES[i]),
                Some("rad/s2"),
                Quantity::FrameAngularAcceleration(i),
                w_vr[i],
            );
        }
        let out = |b: &mut Builder, name: String, what: String, unit: &'static str, q: Quantity| {
            b.push(name, what, Causality::Output, Variability::Continuous, None, None, Some(unit), q);
        };
        for i in 0..3 {
            for j in 0..3 {
                out(
                    b,
                    format!("body.R[{},{}]", i + 1, j + 1),
                    format!("Body orientation, row {} column {} (columns: body axes in world)", i + 1, j + 1),
                    "1",
                    Quantity::BodyRotation(i, j),
                );
            }
        }
        for (i, axis) in AXES.iter().enumerate() {
            out(
                b,
                format!("body.w[{}]", i + 1),
                format!("Body angular velocity, {axis}, world frame"),
                "rad/s",
                Quantity::BodyAngularVelocity(i),
            );
        }
        for (i, axis) in AXES.iter().enumerate() {
            out(
                b,
                format!("body.z[{}]", i + 1),
                format!("Body angular acceleration, {axis}, world frame"),
                "rad/s2",
                Quantity::BodyAngularAcceleration(i),
            );
        }
        out(
            b,
            "body.energy".into(),
            "Total energy: kinetic, elastic and gravitational".into(),
            "J",
            Quantity::BodyEnergy,
        );
        for (i, axis) in AXES.iter().enumerate() {
            out(
                b,
                format!("body.p[{}]", i + 1),
                format!("Linear momentum, {axis}, world frame"),
                "N.s",
                Quantity::BodyMomentum(i),
            );
        }
        for (i, axis) in AXES.iter().enumerate() {
            out(
                b,
                format!("body.h[{}]", i + 1),
                format!("Angular momentum about the world origin, {axis}, world frame"),
                "J.s",
                Quantity::BodyAngularMomentum(i),
            );
        }
    }

    pub fn get(&self, vr: u32) -> Option<&Variable> {
        (vr as usize).checked_sub(1).and_then(|i| self.variables.get(i))
    }

    /// The variable of this name (a linear search: for setting up, not for every get/set).
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The value reference of the variable of this name.
    pub fn value_reference(&self, name: &str) -> Option<u32> {
        self.variable(name).map(|v| v.vr)
    }

    /// State value references in state order (`state_variables`).
    pub fn states(&self) -> Vec<u32> {
        self.state_variables().map(|v| v.vr).collect()
    }

    /// The state variables in state order (q, qd of the dynamic modes, q of the relaxing ones,
    /// then a free body's frame), without allocating.
    pub fn state_variables(&self) -> impl Iterator<Item = &Variable> {
        let (nd, ns) = (self.n_dynamic, self.n_dynamic + self.n_relaxing);
        let of =
            move |f: fn(&Quantity, usize, usize) -> bool| self.variables.iter().filter(move |v| f(&v.quantity, nd, ns));
        of(|q, nd, _| matches!(q, Quantity::ModalCoordinate(j) if *j < nd))
            .chain(of(|q, nd, _| matches!(q, Quantity::ModalVelocity(j) if *j < nd)))
            .chain(of(|q, nd, ns| matches!(q, Quantity::ModalCoordinate(j) if *j >= nd && *j < ns)))
            .chain(of(|q, _, _| Self::is_frame_state(q)))
    }

    /// Whether the quantity is a continuous state: q, q' of a dynamic mode, q of a relaxing
    /// one or a frame state.
    pub fn is_state(&self, q: Quantity) -> bool {
        match q {
            Quantity::ModalCoordinate(j) => j < self.n_dynamic + self.n_relaxing,
            Quantity::ModalVelocity(j) => j < self.n_dynamic,
            _ => Self::is_frame_state(&q),
        }
    }

    fn is_frame_state(q: &Quantity) -> bool {
        matches!(
            q,
            Quantity::FramePosition(_)
                | Quantity::FrameQuaternion(_)
                | Quantity::FrameVelocity(_)
                | Quantity::FrameAngularVelocity(_)
        )
    }

    /// Derivative value references in state order: qd (= der(q)) then der(qd) of the dynamic
    /// modes, qd of the relaxing ones, then a free body's frame rates.
    pub fn derivatives(&self) -> Vec<u32> {
        let (nd, ns) = (self.n_dynamic, self.n_dynamic + self.n_relaxing);
        let mut d = self.select(|q| matches!(q, Quantity::ModalVelocity(j) if *j < nd));
        d.extend(self.select(|q| matches!(q, Quantity::ModalAcceleration(j) if *j < nd)));
        d.extend(self.select(|q| matches!(q, Quantity::ModalVelocity(j) if *j >= nd && *j < ns)));
        // frame: d/dt r = v (the state frame.v), then the quaternion, velocity and spin rates
        d.extend(self.variables.iter().filter(|v| matches!(v.quantity, Quantity::FrameVelocity(_))).map(|v| v.vr));
        d.extend(
            self.variables.iter().filter(|v| matches!(v.quantity, Quantity::FrameQuaternionRate(_))).map(|v| v.vr),
        );
        d.extend(self.variables.iter().filter(|v| matches!(v.quantity, Quantity::FrameAcceleration(_))).map(|v| v.vr));
        d.extend(
            self.variables.iter().filter(|v| matches!(v.quantity, Quantity::FrameAngularAcceleration(_))).map(|v| v.vr),
        );
        d
    }

    fn select(&self, f: impl Fn(&Quantity) -> bool) -> Vec<u32> {
        self.variables.iter().filter(|v| f(&v.quantity)).map(|v| v.vr).collect()
    }

    /// Inputs and states a variable depends on (for ModelStructure), ascending.
    pub fn dependencies(&self, var: &Variable) -> Vec<u32> {
        use Quantity as Q;
        let mount_r = |q: &Q| matches!(q, Q::MountPosition(_));
        let mount_rot = |q: &Q| matches!(q, Q::MountRotation(..));
        let mount_v = |q: &Q| matches!(q, Q::MountVelocity(_));
        let mount_w = |q: &Q| matches!(q, Q::MountAngularVelocity(_));
        let mount_a = |q: &Q| matches!(q, Q::MountAcceleration(_));
        let mount_z = |q: &Q| matches!(q, Q::MountAngularAcceleration(_));
        let loads = |q: &Q| matches!(q, Q::FlangeForce(..) | Q::FlangeTorque(..));
        let nd = self.n_dynamic;
        let ns = nd + self.n_relaxing;
        let quasi_static = self.variables.iter().any(|v| matches!(v.quantity, Q::ModalCoordinate(j) if j >= nd));
        let qd_all = |q: &Q| matches!(q, Q::ModalVelocity(j) if *j < nd);
        // q: the dynamic modes' states, and what the quasi-static modes are solved from (the
        // modal load of the mount's motion and the flange loads, the coupling of the spin, and
        // through the gyroscopic terms the dynamic modes' velocities)
        let rotates = self.rotates;
        let q_all = move |q: &Q| {
            matches!(q, Q::ModalCoordinate(j) if *j < ns)
                || quasi_static
                    && (mount_a(q)
                        || mount_rot(q)
                        || loads(q)
                        || rotates && (mount_w(q) || mount_z(q) || matches!(q, Q::ModalVelocity(j) if *j < nd)))
        };
        // q'' = p(a, R, loads) - d q' - w^2 q
        let accel = |q: &Q| mount_a(q) || mount_rot(q) || loads(q) || q_all(q) || qd_all(q);
        // d_r q'_r = p_r - w_r^2 q_r - (C_k q + C_d q'_d)_r
        let relaxing = self.n_relaxing > 0;
        let relaxing_rate = |q: &Q| accel(q) || mount_w(q) || mount_z(q);
        if self.variables.iter().any(|v| Self::is_frame_state(&v.quantity)) {
            // free-floating: every output and derivative may depend on every state and load
            let mut deps = self.select(|q| self.is_state(*q) || loads(q));
            deps.sort_unstable();
            return deps;
        }
        let mut deps = match var.quantity {
            Q::Flange(_, o) => match o {
                FlangeOutput::Position(_) => self.select(|q| mount_r(q) || mount_rot(q) || q_all(q)),
                FlangeOutput::Rotation(..) => self.select(|q| mount_rot(q) || q_all(q)),
                FlangeOutput::Displacement(_) | FlangeOutput::RotationVector(_) => self.select(q_all),
                // the relaxing modes' rates follow the loads and motion as their accelerations do
                FlangeOutput::Velocity(_) => self.select(|q| {
                    mount_v(q) || mount_w(q) || mount_rot(q) || q_all(q) || qd_all(q) || relaxing && relaxing_rate(q)
                }),
                FlangeOutput::AngularVelocity(_) => {
                    self.select(|q| mount_w(q) || mount_rot(q) || qd_all(q) || relaxing && relaxing_rate(q))
                }
                FlangeOutput::Acceleration(_) | FlangeOutput::AngularAcceleration(_) => {
                    self.select(|q| accel(q) || mount_w(q) || mount_z(q))
                }
            },
            // stresses follow the deformation as the flange displacements do
            Q::Stress(..) => self.select(q_all),
            // the rotating-frame terms couple all modes and bring in the spin
            Q::MountForce(_) | Q::MountTorque(_) => self.select(|q| accel(q) || mount_w(q) || mount_z(q)),
            Q::ModalVelocity(j) if j >= nd && j < ns => self.select(relaxing_rate),
            Q::ModalVelocity(j) => self.select(|q| *q == Q::ModalVelocity(j)),
            Q::ModalAcceleration(_) => self.select(|q| accel(q) || mount_w(q) || mount_z(q)),
            _ => Vec::new(),
        };
        deps.sort_unstable();
        deps
    }

    /// Inputs a variable depends on during initialisation (InitialUnknowns): the states are
    /// unknowns then, so a dependence on q stands for what q depends on - with `static_start`,
    /// the loads that set the static equilibrium; q' starts at rest or its start value.
    pub fn initial_dependencies(&self, var: &Variable) -> Vec<u32> {
        use Quantity as Q;
        // parameters are knowns of the initialization too (FMI 2.0, ModelStructure): the
        // initial frame of a free body, gravity and damping in the loads and accelerations,
        // and static_start, which switches the initial state between its start values and the
        // static solution
        let initial_frame = |q: &Q| {
            matches!(
                q,
                Q::InitialPosition(_) | Q::InitialRotation(_) | Q::InitialVelocity(_) | Q::InitialAngularVelocity(_)
            )
        };
        let load_parameters = |q: &Q| matches!(q, Q::Gravity(_) | Q::RayleighAlpha | Q::RayleighBeta);
        if self.variables.iter().any(|v| Self::is_frame_state(&v.quantity)) {
            // free-floating: the frame starts from its parameters, the modes at their start
            // values; everything else follows the loads, gravity and damping as well
            if Self::is_frame_state(&var.quantity) {
                return self.select(initial_frame);
            }
            if matches!(var.quantity, Q::ModalCoordinate(_) | Q::ModalVelocity(_)) {
                return Vec::new();
            }
            return self.select(|q| {
                matches!(q, Q::FlangeForce(..) | Q::FlangeTorque(..)) || initial_frame(q) || load_parameters(q)
            });
        }
        let static_loads = |q: &Q| {
            matches!(
                q,
                Q::MountAcceleration(_)
                    | Q::MountRotation(..)
                    | Q::MountAngularVelocity(_)
                    | Q::MountAngularAcceleration(_)
                    | Q::FlangeForce(..)
                    | Q::FlangeTorque(..)
                    | Q::Gravity(_)
                    | Q::StaticStart
            )
        };
        let direct = match var.quantity {
            Q::ModalCoordinate(_) => return self.select(static_loads),
            Q::ModalVelocity(_) => return self.select(|q| *q == Q::StaticStart),
            _ => self.dependencies(var),
        };
        let mut deps = Vec::new();
        for vr in direct {
            let Some(v) = self.get(vr) else { continue };
            match v.quantity {
                Q::ModalCoordinate(_) => deps.extend(self.select(static_loads)),
                Q::ModalVelocity(_) => deps.extend(self.select(|q| *q == Q::StaticStart)),
                _ => deps.push(vr),
            }
        }
        // what the modal acceleration enters (der(qd), accelerations, reactions) also sees
        // gravity and damping directly
        let accelerated = matches!(
            var.quantity,
            Q::ModalAcceleration(_)
                | Q::MountForce(_)
                | Q::MountTorque(_)
                | Q::Flange(_, FlangeOutput::Acceleration(_) | FlangeOutput::AngularAcceleration(_))
        );
        if accelerated {
            deps.extend(self.select(load_parameters));
        }
        deps.sort_unstable();
        deps.dedup();
        deps
    }
}

/// The fraction of a mode's unit static response that its nominal is. Hosts take
/// atol = rtol x nominal. Once a lightly damped mode has settled on a static load, the relative
/// part rtol |q| of the error test is as large as the deflection, and only atol keeps the host
/// from stepping over the mode's ringing: with the unit response itself as nominal, FMPy's CVode
/// at rtol 1e-4 left the bracket ringing at 16 % of the swing of its mount force a second after a
/// gravity step (steps longer than the period alias the oscillation, and the error test does not
/// see it); at 1e-2 of it 5e-3, at 1e-3 2.3e-3, smaller fractions gain nothing (the relative
/// part takes over) at the same cost (`tests/test_me_host_defaults.py`, the benchmark
/// `bench/me_host_defaults.py`).
pub const NOMINAL_FRACTION: f64 = 1e-3;

/// The nominal of each modal coordinate: NOMINAL_FRACTION of its largest static response to a
/// unit force or torque (1 N, 1 N m) at a force flange and to 1 g of the mount's acceleration or
/// gravity along any axis, |p_k| / omega_k^2. A mode no such load excites gets 1e-6 of the
/// largest (a nominal must be positive).
pub fn modal_nominals(body: &ReducedBody) -> Vec<f64> {
    const G: f64 = 9.81;
    let n = body.n_modes();
    let mut out: Vec<f64> = (0..n)
        .map(|k| {
            let mut load = 0.0f64;
            for flange in &body.flanges {
                for row in 0..6 {
                    load = load.max(flange.shapes[row * n + k].abs());
                }
            }
            for a in 0..3 {
                load = load.max(G * body.c_t[a * n + k].abs());
            }
            let w2 = body.omega[k] * body.omega[k];
            if w2 > 0.0 && load.is_finite() { load / w2 } else { 0.0 }
        })
        .collect();
    let largest = out.iter().fold(0.0f64, |m, v| m.max(*v));
    let floor = if largest > 0.0 { 1e-6 * largest } else { 1.0 };
    for v in out.iter_mut() {
        *v = NOMINAL_FRACTION * v.max(floor);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduced::two_mode_body;

    #[test]
    fn every_name_finds_its_value_reference() {
        let table = VariableTable::new(&two_mode_body());
        for v in &table.variables {
            assert_eq!(table.value_reference(&v.name), Some(v.vr), "{}", v.name);
            assert_eq!(table.get(v.vr).map(|w| &w.name), Some(&v.name));
        }
        assert_eq!(table.value_reference("tip.f[1]"), table.variable("tip.f[1]").map(|v| v.vr));
        assert!(table.value_reference("tip.f[1]").is_some());
        assert_eq!(table.value_reference("no.such[1]"), None);
    }
}
