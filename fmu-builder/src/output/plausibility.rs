//! What the build finished but a user probably did not mean, said as warnings (the build stands):
//! inputs that look like a unit slip (E in MPa, rho in g/cm^3, a mesh in millimetres) and a body
//! whose lowest frequency no engineering part has; and, stated plainly, what the scene lets the
//! FMU do and which inputs it will refuse.

use crate::input::spec::{SceneLoad, Spec};
use crate::model::flange::model_size;
use crate::model::part::Part;
use serde::Serialize;

/// Young's moduli of engineering solids [Pa]: soft elastomers ~1e6, diamond ~1.2e12.
const E_RANGE: [f64; 2] = [1e6, 1.5e12];
/// Densities of engineering solids [kg/m^3]: foams ~30, osmium 22 600.
const RHO_RANGE: [f64; 2] = [20.0, 25_000.0];
/// Sizes of parts a system model holds [m]: a watch spring to a crane boom.
const SIZE_RANGE: [f64; 2] = [1e-4, 100.0];
/// The heaviest part a system model holds [kg]: a crane boom. A part in millimetres read as
/// metres weighs 1e9 times its mass: a 50 x 20 x 2 mm steel plate, 50 m across, is within
/// SIZE_RANGE but weighs 1.6e7 kg.
const MASS_LIMIT: f64 = 1e5;
/// Sizes of solid elements in engineering meshes [m] (the median of their bounding boxes'
/// diagonals): a 10 um feature to a 2 m block of a coarse mesh. A millimetre mesh read as metres
/// has elements of metres even where the part's own size and mass are plausible (a 10 x 0.1 x
/// 0.2 mm bar in two elements: 10 m long, 1 570 kg, 5 m elements).
const ELEMENT_RANGE: [f64; 2] = [1e-5, 2.0];
/// The most modes a reduction band holds before the build says so ahead of the eigen-solve: a
/// few thousand modes take minutes on this machine's cores; a part in millimetres read as
/// metres puts a billion times as many below the same frequency.
const BAND_MODES: f64 = 5000.0;
/// Lowest frequencies of elastic parts [Hz]: a slender boom ~0.1, a micro-part ~1e6.
const FREQUENCY_RANGE: [f64; 2] = [0.1, 1e6];

/// `SceneReport::body` of a body without any flange: a valid FMU (a free flexible body whose
/// motion starts from its initial conditions), but nothing in it is "the mount".
pub const FREE_WITHOUT_FLANGES: &str = "free-floating body without flanges";

/// What the scene lets the FMU model, and what it refuses.
#[derive(Debug, Clone, Serialize, Default)]
pub struct SceneReport {
    /// What holds the body, in words: "mounted at flange base", "free-floating, driven by its
    /// force flanges" or "free-floating body without flanges" (no inputs at all: it moves by
    /// its initial conditions alone, and its frame is its centre of mass, not a mount).
    pub body: String,
    /// Rotating-frame terms (Coriolis, centrifugal, Euler): a rotating mount is accepted.
    pub rotation: bool,
    /// Static shapes of gravity / mount acceleration in the basis (their statics exact).
    pub gravity: bool,
    pub acceleration: bool,
    /// Stress stiffening by the prestress of the declared loads and the flange loads.
    pub geometric_stiffening: bool,
    /// Inputs the FMU refuses with this scene, in words.
    pub refuses: Vec<String>,
}

pub fn scene(spec: &Spec, mount: Option<&str>) -> SceneReport {
    let rotation = spec.rotates();
    let mut refuses = Vec::new();
    if let (false, Some(m)) = (rotation, mount) {
        refuses.push(format!(
            "a rotating mount: {m}.w and {m}.z must stay zero (the scene does not declare \"rotation\")"
        ));
    }
    if let Some(m) = mount {
        refuses.push(format!("a {m}.R that is not a rotation matrix"));
    }
    let body = match mount {
        Some(m) => format!("mounted at flange {m}"),
        None if spec.flanges.is_empty() => FREE_WITHOUT_FLANGES.to_string(),
        None => "free-floating, driven by its force flanges".to_string(),
    };
    SceneReport {
        body,
        rotation,
        gravity: spec.declares(SceneLoad::Gravity),
        acceleration: spec.declares(SceneLoad::Acceleration),
        geometric_stiffening: spec.stiffening(),
        refuses,
    }
}

/// Warnings for values far outside what engineering parts in SI units have: the part's
/// materials, extent and mass (`early`, [`part_warnings`]: said as soon as the part is
/// assembled), its notes, and the lowest frequency of the full model (`lowest_hz`; `mounted`: of
/// the mounted body, else of the free one).
pub fn warnings(early: Vec<String>, part: &Part, lowest_hz: Option<f64>, mounted: bool) -> Vec<String> {
    let mut out = early;
    out.extend(part.notes.iter().cloned());
    if let Some(f) = lowest_hz
        && outside(f, FREQUENCY_RANGE)
    {
        out.push(format!(
            "the lowest frequency of the {} body is {f:.4e} Hz, outside the {} .. {:e} Hz of elastic parts: check the units of E, rho and the mesh",
            if mounted { "mounted" } else { "free" },
            FREQUENCY_RANGE[0],
            FREQUENCY_RANGE[1]
        ));
    }
    out
}

fn outside(v: f64, r: [f64; 2]) -> bool {
    v < r[0] || v > r[1]
}

/// The warnings of [`warnings`] that need only the part and its `mass` [kg] (the assembled
/// nodal mass; None for a part given by its matrices): its materials, extent and mass. The
/// builder says them before anything costly, where a unit slip would otherwise run a reduction
/// of the wrong part first.
/// The modes of `part` (mass `mass`) below `max_frequency` [Hz], by Weyl's count for an
/// isotropic solid, V omega^3 / (6 pi^2) (1 / c_L^3 + 2 / c_T^3), with the fastest waves and
/// the smallest volume among its materials: an estimate from below (slender and thin parts
/// have more low modes than a solid of their volume), so a warning from it is no false alarm.
pub fn band_warning(part: &Part, mass: Option<f64>, max_frequency: f64) -> Option<String> {
    let mass = mass?;
    let rho = part.materials.iter().map(|m| m.rho).fold(0.0, f64::max);
    let speeds = |m: &crate::model::assembly::SolidMaterial| {
        let (e, nu) = (m.elasticity.e, m.elasticity.nu);
        let shear = (e / (2.0 * m.rho * (1.0 + nu))).sqrt();
        let pressure = (e * (1.0 - nu) / (m.rho * (1.0 + nu) * (1.0 - 2.0 * nu))).sqrt();
        (pressure, shear)
    };
    let (c_l, c_t) =
        part.materials.iter().map(speeds).fold((0.0, 0.0), |(a, b), (p, s)| (f64::max(a, p), f64::max(b, s)));
    if !(rho > 0.0 && c_l > 0.0 && c_t > 0.0 && max_frequency > 0.0) {
        return None;
    }
    let volume = mass / rho;
    let omega = 2.0 * std::f64::consts::PI * max_frequency;
    let modes = volume * omega.powi(3) / (6.0 * std::f64::consts::PI.powi(2)) * (1.0 / c_l.powi(3) + 2.0 / c_t.powi(3));
    (modes.is_finite() && modes > BAND_MODES).then(|| {
        format!(
            "the band up to reduction.max_frequency = {max_frequency} Hz holds about {modes:.1e} modes of this part (Weyl's count for a solid of its {volume:.3e} m^3), more than the {BAND_MODES} an eigen-solve takes in minutes: a mesh in millimetres? give its unit (\"geometry\": {{\"length_unit\": \"mm\"}}); or lower max_frequency"
        )
    })
}

/// Elements outside ELEMENT_RANGE, said with the probable slip.
fn element_warning(part: &Part) -> Option<String> {
    let e = element_size(&part.mesh).filter(|e| outside(*e, ELEMENT_RANGE))?;
    let hint = if e > ELEMENT_RANGE[1] {
        " (a mesh in millimetres? give its unit: \"geometry\": {\"length_unit\": \"mm\"})"
    } else {
        " (a mesh in metres given a smaller geometry.length_unit?)"
    };
    Some(format!(
        "the part's elements are {e:.3e} m across (the median of their bounding boxes' diagonals), outside the {:e} .. {} m of engineering meshes{hint}; lengths are in metres unless geometry.length_unit says otherwise",
        ELEMENT_RANGE[0], ELEMENT_RANGE[1]
    ))
}

/// The median over the elements of their bounding boxes' diagonals [m]; None without elements.
fn element_size(mesh: &crate::input::mesh::Mesh) -> Option<f64> {
    let mut sizes: Vec<f64> = mesh
        .offsets
        .windows(2)
        .map(|w| {
            let nodes = &mesh.elements[w[0]..w[1]];
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &n in nodes {
                for a in 0..3 {
                    lo[a] = lo[a].min(mesh.nodes[n][a]);
                    hi[a] = hi[a].max(mesh.nodes[n][a]);
                }
            }
            (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt()
        })
        .filter(|d| d.is_finite())
        .collect();
    if sizes.is_empty() {
        return None;
    }
    let middle = sizes.len() / 2;
    Some(*sizes.select_nth_unstable_by(middle, f64::total_cmp).1)
}

/// What the build says as soon as the part is read: [`part_warnings`] and [`band_warning`] of
/// the input's `reduction.max_frequency`.
pub fn early_warnings(part: &Part, mass: Option<f64>, max_frequency: Option<f64>) -> Vec<String> {
    let mut out = part_warnings(part, mass);
    out.extend(max_frequency.and_then(|f| band_warning(part, mass, f)));
    out
}

pub fn part_warnings(part: &Part, mass: Option<f64>) -> Vec<String> {
    let mut out = Vec::new();
    for m in &part.materials {
        let (e, rho) = (m.elasticity.e, m.rho);
        let name = if m.name.is_empty() { "the material".to_string() } else { format!("material {}", m.name) };
        if outside(e, E_RANGE) {
            let hint = if e < E_RANGE[0] && e * 1e6 >= E_RANGE[0] && e * 1e6 <= E_RANGE[1] {
                format!(" (given in MPa? {e:e} MPa is {:e} Pa)", e * 1e6)
            } else {
                String::new()
            };
            out.push(format!(
                "{name}: E = {e:e} Pa lies outside the {:e} .. {:e} Pa of engineering solids{hint}; the input is in SI units",
                E_RANGE[0], E_RANGE[1]
            ));
        }
        if !part.from_matrices && outside(rho, RHO_RANGE) {
            let hint = if rho < RHO_RANGE[0] && rho * 1e3 >= RHO_RANGE[0] {
                format!(" (given in g/cm^3? {rho} g/cm^3 is {} kg/m^3)", rho * 1e3)
            } else {
                String::new()
            };
            out.push(format!(
                "{name}: rho = {rho:e} kg/m^3 lies outside the {} .. {} kg/m^3 of engineering solids{hint}",
                RHO_RANGE[0], RHO_RANGE[1]
            ));
        }
    }
    let said_before = out.len();
    let size = (!part.mesh.nodes.is_empty()).then(|| model_size(&part.mesh));
    // the mass checked only where a slip could hide in a plausible size: a part across more
    // than a metre (a millimetre mesh read as metres is a thousand times its size)
    let large = size.is_some_and(|s| s > 1.0);
    let mm = " (a mesh in millimetres? give its unit: \"geometry\": {\"length_unit\": \"mm\"})";
    if let Some(size) = size
        && outside(size, SIZE_RANGE)
    {
        // a mesh in millimetres read as metres is a billion times too heavy: the mass says so
        // in a number the user recognises at once
        let weighs = match mass {
            Some(m) => format!(" and would weigh {m:.3e} kg"),
            None => String::new(),
        };
        let hint = if size > SIZE_RANGE[1] {
            mm
        } else {
            " (a mesh in kilometres, or scaled twice? check geometry.length_unit)"
        };
        out.push(format!(
            "the part is {size:.4e} m across (its bounding box's diagonal){weighs}, outside the {:e} .. {} m of parts a system model holds{hint}; lengths are in metres unless geometry.length_unit says otherwise",
            SIZE_RANGE[0], SIZE_RANGE[1]
        ));
    } else if let Some(m) = mass
        && large
        && m > MASS_LIMIT
    {
        let across = size.map(|s| format!(", {s:.4e} m across")).unwrap_or_default();
        out.push(format!(
            "the part would weigh {m:.3e} kg{across}, more than the {:e} kg of parts a system model holds{mm}; lengths are in metres unless geometry.length_unit says otherwise",
            MASS_LIMIT
        ));
    }
    // one slip, one warning: the elements only where the size and the mass looked plausible
    if out.len() == said_before {
        out.extend(element_warning(part));
    }
    out
}
