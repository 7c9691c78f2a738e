//! `documentation/index.html` of the FMU: the body's mass, flanges, reduction and its accuracy
//! against the full FE model, readable without any tool. The plots are inline SVG (no JavaScript, no
//! external files) drawn by `output::plot`: [`frequency_response_plot`] and
//! [`relative_error_plot`].

use crate::output::numbers::{fixed, scientific};
use crate::output::plot::{Annotation, PALETTE, PlotSpec, Series, Stroke, esc, line_plot};
use crate::output::report::{Report, StressPointReport};
use crate::reduce::accuracy::{Accuracy, MAC_PAIRED, ModePair};
use crate::reduce::frf::{ComparisonDamping, FrequencyResponse};
use fmu_runtime::interface::VariableTable;
use std::fmt::Write;

pub fn index_html(r: &Report, table: &VariableTable, input: &str) -> String {
    let mut h = String::new();
    rigid_body_html(&mut h, r);
    flanges_html(&mut h, r);
    h.push_str(&pictures_html(&r.pictures));
    h.push_str(&scene_html(r));
    h.push_str(&stress_points_html(&r.stress_points));
    reduction_html(&mut h, r);
    let a = &r.accuracy;
    let tolerance = frequency_tolerance(input);
    let (marked, across) = if a.pairs.is_empty() {
        (mode_table(&mut h, a, tolerance), Vec::new())
    } else {
        paired_table(&mut h, a, tolerance)
    };
    h.push_str("</table>\n");
    h.push_str(&eigenfrequency_legend(a.pairs.is_empty(), tolerance, input, marked, &across));
    if let Some(plot) = frequency_error_plot(a) {
        let _ = write!(h, "<div class=\"plot\">\n{plot}</div>\n");
    }
    let _ = write!(
        h,
        "<h3>Static compliance of the force flanges</h3>\n<p>Largest deviation of the reduced from the full-model \
compliance (relative to its largest entry): {:.2e}. Constraint modes make it exact up to round-off.</p>\n",
        a.compliance_max_relative_error
    );
    h.push_str(&crate::output::verdict::html(&r.verdict));
    if let Some(fr) = &a.frequency_response {
        h.push_str(&accuracy_over_band_html(fr, &a.compliance_flanges));
    }
    h.push_str(&variables_html(table));
    let _ = write!(
        h,
        "<h2>Input</h2>\n<p>The input as the builder read it (defaults filled in, unset fields left out), also <code>input.json</code> beside this \
file:</p>\n<pre>{}</pre>\n",
        esc(input)
    );
    h.push_str("<p>The machine-readable report, with the full compliance matrices, is <code>report.json</code> beside this file.</p>\n</body></html>\n");
    h
}

/// The page's head, its title and the rigid body's properties.
fn rigid_body_html(h: &mut String, r: &Report) {
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{name}</title>\
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #bbb;padding:0.2em 0.6em;text-align:right}}th{{background:#eee}}tr.outside td{{background:#fde4e4}}\
.legend{{font-size:90%}}</style></head><body>\n\
<h1>{name}: reduced flexible body</h1>\n<p>Built by {tool} from a {el} mesh of {nodes} nodes and {els} elements \
({dofs} DoFs after flange coupling). GUID {guid}.</p>\n",
        tool = esc(&r.tool),
        name = esc(&r.model_name),
        el = esc(&r.element),
        nodes = r.nodes,
        els = r.elements,
        dofs = r.dofs_constrained,
        guid = esc(&r.guid),
    );
    let c = r.center_of_mass;
    let _ = write!(
        h,
        "<h2>Rigid body</h2>\n<table><tr><th>mass [kg]</th><td>{:.6e}</td></tr><tr><th>volume [m^3]</th><td>{}</td></tr>\
<tr><th>centre of mass [m] (body frame)</th><td>{}</td></tr>\
<tr><th>inertia tensor about the body frame's origin [kg m^2] (rows)</th><td>{}</td></tr>\
<tr><th>damping applied</th><td>{}</td></tr></table>\n\
<p>Body frame: origin at the mount flange's reference point (for a free body: the centre of mass), axes those of \
the undeformed part as meshed. World frame: the host's; the mount's inputs place the body frame in it.</p>\n",
        r.mass,
        r.volume.map_or("(matrix input)".to_string(), |v| format!("{v:.6e}")),
        scientific(&c).join(", "),
        scientific(&r.inertia_about_origin).chunks(3).map(|row| row.join(", ")).collect::<Vec<_>>().join("<br>"),
        esc(&r.damping)
    );
}

/// The flanges' table.
fn flanges_html(h: &mut String, r: &Report) {
    h.push_str("<h2>Flanges</h2>\n<table><tr><th>name</th><th>role</th><th>reference point [m]</th><th>slave nodes</th><th>coupling</th></tr>\n");
    for f in &r.flanges {
        let p = f.reference_point;
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}, {}, {}</td><td>{}</td><td>{}</td></tr>",
            esc(&f.name),
            esc(&f.role),
            fixed(p[0], 6),
            fixed(p[1], 6),
            fixed(p[2], 6),
            f.slave_nodes,
            esc(&f.coupling)
        );
    }
    h.push_str("</table>\n");
}

/// The reduction's method and order, and what the model exchange does.
fn reduction_html(h: &mut String, r: &Report) {
    let _ = write!(
        h,
        "<h2>Reduction</h2>\n<p>{} with {} fixed-interface normal modes and {} constraint modes: reduced order {}.</p>\n",
        esc(&r.method),
        r.fixed_interface_modes,
        r.constraint_modes,
        r.order,
    );
    for sentence in crate::output::model_exchange::sentences(r) {
        let _ = writeln!(h, "<p>{}</p>", esc(&sentence));
    }
}

/// The eigenfrequency table row by row (no pairs of reduced and full modes): the rows marked
/// outside the tolerance.
fn mode_table(h: &mut String, a: &Accuracy, tolerance: f64) -> usize {
    let mut marked = 0usize;
    h.push_str("<h3>Eigenfrequencies of the mounted body</h3>\n<table><tr><th>mode</th><th>reduced [Hz]</th><th>full FE [Hz]</th><th>relative error</th></tr>\n");
    for i in 0..a.reduced_hz.len() {
        let full = a.full_hz.get(i).map(|f| format!("{f:.6}")).unwrap_or_default();
        let e = a.relative_error.get(i).copied();
        let out = e.is_some_and(|e| !(e.abs() <= tolerance));
        marked += usize::from(out);
        let err = e.map(|e| format!("{e:.2e}")).unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr{}><td>{}</td><td>{:.6}</td><td>{full}</td><td>{err}{}</td></tr>",
            row_class(out),
            i + 1,
            a.reduced_hz[i],
            mark(out)
        );
    }
    marked
}

/// The eigenfrequency table of paired modes: the rows marked outside the valid range, and the
/// pairs across indices (reduced, full).
fn paired_table(h: &mut String, a: &Accuracy, tolerance: f64) -> (usize, Vec<(usize, usize)>) {
    let mut marked = 0usize;
    let mut across = Vec::new();
    h.push_str(
        "<h3>Eigenfrequencies: reduced modes and the full modes of the same shape</h3>\n<p>Each reduced mode is paired \
with the computed full-model mode whose shape it resembles most (modal assurance criterion, MAC, in the mass inner \
product); a reduced mode that resembles none (MAC below 0.9) lies beyond what the model represents: a constraint or \
residual-flexibility mode, there to make statics exact, not a vibration mode of the part.</p>\n\
<table><tr><th>reduced mode</th><th>reduced [Hz]</th><th>full mode</th><th>full FE [Hz]</th><th>MAC</th>\
<th>relative error</th></tr>\n",
    );
    for p in &a.pairs {
        let out = outside_valid_range(p, tolerance);
        marked += usize::from(out);
        let (full, full_hz, err) = match (p.full, p.full_hz, p.relative_error) {
            (Some(j), Some(f), Some(e)) => {
                // a pair across indices is the one place a negative error is no sign of a
                // broken projection: it gets its note below the table
                let note = if j == p.reduced {
                    String::new()
                } else {
                    across.push((p.reduced, j));
                    format!(" <sup>{ACROSS_MARK}</sup>")
                };
                (format!("{j}{note}"), format!("{f:.6}"), format!("{e:.2e}"))
            }
            _ => ("-".to_string(), "-".to_string(), "outside the valid range".to_string()),
        };
        let _ = writeln!(
            h,
            "<tr{}><td>{}</td><td>{:.6}</td><td>{full}</td><td>{full_hz}</td><td>{:.4}</td><td>{err}{}</td></tr>",
            row_class(out),
            p.reduced,
            p.reduced_hz,
            p.mac,
            mark(out)
        );
    }
    (marked, across)
}

/// Largest relative eigenfrequency error of a mode still counted as represented where the scene
/// names no tolerance of its own.
pub const DEFAULT_FREQUENCY_TOLERANCE: f64 = 0.01;
/// Marks a pair of a reduced and a full mode of different indices.
const ACROSS_MARK: &str = "&Dagger;";

/// The scene's tolerance (`scene.tolerance` of the input listing) or [`DEFAULT_FREQUENCY_TOLERANCE`]:
/// read from the listing as the page shows it, so that the limit the marks use is the one printed.
fn frequency_tolerance(input: &str) -> f64 {
    scene_tolerance(input).unwrap_or(DEFAULT_FREQUENCY_TOLERANCE)
}

fn scene_tolerance(input: &str) -> Option<f64> {
    let v: serde_json::Value = serde_json::from_str(input).ok()?;
    v.get("scene")?.get("tolerance")?.as_f64().filter(|t| t.is_finite() && *t > 0.0)
}

/// A mode the reduced model does not represent: no full mode resembles it (MAC below
/// [`MAC_PAIRED`]) or its frequency misses the full mode's by more than `tolerance`. The MAC alone
/// lets through modes of the right shape at the wrong frequency (MAC 0.914 at 26 % error).
fn outside_valid_range(p: &ModePair, tolerance: f64) -> bool {
    p.full.is_none() || !(p.mac >= MAC_PAIRED) || p.relative_error.is_none_or(|e| !(e.abs() <= tolerance))
}

fn row_class(outside: bool) -> &'static str {
    if outside { " class=\"outside\"" } else { "" }
}

fn mark(outside: bool) -> &'static str {
    if outside { " <sup title=\"outside the valid range\">&dagger;</sup>" } else { "" }
}

/// What the marks of the eigenfrequency table mean, and why a pair across indices may show a
/// negative error.
fn eigenfrequency_legend(
    by_index: bool,
    tolerance: f64,
    input: &str,
    marked: usize,
    across: &[(usize, usize)],
) -> String {
    let source = if scene_tolerance(input).is_some() {
        "the scene's tolerance, scene.tolerance".to_string()
    } else {
        "the scene names no tolerance".to_string()
    };
    let mac = if by_index { String::new() } else { format!(" or a MAC below {MAC_PAIRED}") };
    let mut h = format!(
        "<p class=\"legend\"><sup>&dagger;</sup> (shaded row): outside the valid range, a relative frequency error \
above {} ({source}){mac}. {marked} mode{} marked.</p>\n",
        fmt_percent(tolerance),
        if marked == 1 { "" } else { "s" },
    );
    if !across.is_empty() {
        let pairs = across.iter().map(|(r, f)| format!("reduced mode {r} with full mode {f}")).collect::<Vec<_>>();
        let _ = writeln!(
            h,
            "<p class=\"legend\"><sup>{ACROSS_MARK}</sup> Paired by MAC across indices: {}. Reduction bounds each \
reduced frequency from below by the full model's frequency of the same index, not by that of the full mode of the \
same shape: where two full modes lie close, a pair across indices may show a negative error.</p>",
            pairs.join(", ")
        );
    }
    h
}

/// "1 %", "0.1 %", "2.5e-4 %".
fn fmt_percent(fraction: f64) -> String {
    format!("{} %", fmt_num(100.0 * fraction))
}

/// A stress [Pa] in MPa to 4 significant digits: a column of mixed magnitudes reads alike
/// (1.521 and 0.6314, not 1.521e6 and 631357.8008).
fn fmt_mpa(pa: f64) -> String {
    let v = pa / 1e6;
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_string();
    }
    // fixed point down to 1 Pa: the stresses per unit load of a small part are thousandths of a
    // MPa, and a column of them reads alike without exponents
    let magnitude = v.abs().log10().floor();
    if !(-6.0..4.0).contains(&magnitude) {
        return format!("{v:.3e}");
    }
    let s = format!("{v:.*}", (3.0 - magnitude) as usize);
    // rounding may carry into a new digit (9.9996 -> 10.000): one decimal too many then
    let digits = s.chars().filter(char::is_ascii_digit).skip_while(|c| *c == '0').count();
    if digits > 4 && s.contains('.') { s[..s.len() - 1].trim_end_matches('.').to_string() } else { s }
}

/// The input as the page and `documentation/input.json` list it: the builder's reading of it
/// (defaults filled in) without the fields left unset, which serialise as `null` and would bury
/// what the user wrote; fields keep their order.
pub fn input_listing<T: serde::Serialize>(spec: &T) -> serde_json::Result<String> {
    let text = serde_json::to_string(spec)?;
    let tree: Ordered = serde_json::from_str(&text)?;
    serde_json::to_string_pretty(&tree)
}

/// JSON in the order written (serde_json's `Value` sorts object keys), objects without their
/// `null` members.
enum Ordered {
    Leaf(serde_json::Value),
    Array(Vec<Ordered>),
    Object(Vec<(String, Ordered)>),
}

impl<'de> serde::Deserialize<'de> for Ordered {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Ordered;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("JSON")
            }
            fn visit_unit<E>(self) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(serde_json::Value::Null))
            }
            fn visit_bool<E>(self, v: bool) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_i64<E>(self, v: i64) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_str<E>(self, v: &str) -> Result<Ordered, E> {
                Ok(Ordered::Leaf(v.into()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Ordered, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = a.next_element()? {
                    out.push(x);
                }
                Ok(Ordered::Array(out))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<Ordered, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = a.next_entry::<String, Ordered>()? {
                    if !matches!(v, Ordered::Leaf(serde_json::Value::Null)) {
                        out.push((k, v));
                    }
                }
                Ok(Ordered::Object(out))
            }
        }
        d.deserialize_any(V)
    }
}

impl serde::Serialize for Ordered {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{SerializeMap, SerializeSeq};
        match self {
            Ordered::Leaf(v) => v.serialize(s),
            Ordered::Array(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for x in items {
                    seq.serialize_element(x)?;
                }
                seq.end()
            }
            Ordered::Object(members) => {
                let mut map = s.serialize_map(Some(members.len()))?;
                for (k, v) in members {
                    map.serialize_entry(k, v)?;
                }
                map.end()
            }
        }
    }
}

/// The mesh with its flanges and the first mode shapes.
fn pictures_html(pictures: &[(String, String)]) -> String {
    if pictures.is_empty() {
        return String::new();
    }
    let mut h = String::from("<h2>Pictures</h2>\n");
    for (caption, svg) in pictures {
        let _ = write!(h, "<figure>\n{svg}<figcaption>{}</figcaption></figure>\n", esc(caption));
    }
    h
}

/// Every variable of the FMU: name, causality, unit and what it means (frames and signs are in
/// the descriptions).
fn variables_html(table: &VariableTable) -> String {
    let mut h = String::from(
        "<h2>Variables</h2>\n<p>Loads act on the body; torques are about the flange's reference point; \
\"world frame\" is the host's, \"body frame\" the part's axes at the mount.</p>\n\
<table><tr><th>name</th><th>causality</th><th>unit</th><th>meaning</th></tr>\n",
    );
    for v in &table.variables {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:?}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
            esc(&v.name),
            v.causality,
            v.unit.unwrap_or(""),
            esc(&v.description)
        );
    }
    h.push_str("</table>\n");
    h
}

/// What the scene lets the FMU model, what it refuses, and the build's warnings.
fn scene_html(r: &Report) -> String {
    let sc = &r.scene;
    let yes = |b: bool| if b { "yes" } else { "no" };
    let mut h = format!(
        "<h2>Scene</h2>\n<table><tr><th>rotating-frame terms (a rotating mount)</th><td>{}</td></tr>\
<tr><th>static shapes of gravity</th><td>{}</td></tr><tr><th>static shapes of mount acceleration</th><td>{}</td></tr>\
<tr><th>geometric stiffening</th><td>{}</td></tr></table>\n",
        yes(sc.rotation),
        yes(sc.gravity),
        yes(sc.acceleration),
        yes(sc.geometric_stiffening)
    );
    if !sc.refuses.is_empty() {
        h.push_str("<p>The FMU refuses (fmi2Error with the reason logged):</p>\n<ul>\n");
        for refusal in &sc.refuses {
            let _ = writeln!(h, "<li>{}</li>", esc(refusal));
        }
        h.push_str("</ul>\n");
    }
    if !r.warnings.is_empty() {
        h.push_str("<h2>Warnings</h2>\n<ul>\n");
        for w in &r.warnings {
            let _ = writeln!(h, "<li>{}</li>", esc(w));
        }
        h.push_str("</ul>\n");
    }
    h
}

/// The stress recovery points (outputs.stress) and, per point, its static stresses under every
/// unit load case: what the FMU's stress outputs read for that load held steady.
fn stress_points_html(points: &[StressPointReport]) -> String {
    if points.is_empty() {
        return String::new();
    }
    let mut h = String::from(
        "<h2>Stress recovery points</h2>\n<p>Outputs <code>&lt;point&gt;.sxx</code> .. <code>.szx</code> (body frame) and \
<code>.mises</code> [Pa] at each node below: nodal stresses as CalculiX computes them (integration-point stresses \
extrapolated to the element's nodes, averaged over the elements sharing the node), linear in the modal coordinates. \
Hot spots are the nodes with the highest von Mises stress under the unit load cases, each case relative to its own \
peak; nodes tied to a flange are not candidates. The static stresses per unit load follow each point, in MPa \
(4 significant digits).</p>\n",
    );
    for p in points {
        let _ = write!(
            h,
            "<h3>{}</h3>\n<p>{}</p>\n<table><tr><th>unit load case</th><th>sxx [MPa]</th><th>syy [MPa]</th><th>szz [MPa]</th>\
<th>sxy [MPa]</th><th>syz [MPa]</th><th>szx [MPa]</th><th>von Mises [MPa]</th></tr>\n",
            esc(&p.name),
            esc(&p.description)
        );
        for c in &p.unit_cases {
            let _ = write!(h, "<tr><td>{}</td>", esc(&c.case));
            for v in c.stress.iter().chain(std::iter::once(&c.von_mises)) {
                let _ = write!(h, "<td>{}</td>", fmt_mpa(*v));
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table>\n");
    }
    h
}

/// The "Accuracy over the band" section: a table of the comparison's settings and result, the
/// driving-point magnitudes full vs reduced and the relative error per frequency.
fn accuracy_over_band_html(fr: &FrequencyResponse, flanges: &[String]) -> String {
    let mut h = String::new();
    let (argmax, _) = arg_max(&fr.relative_error);
    let at = argmax.and_then(|i| fr.frequencies_hz.get(i)).map(|f| format!(" (at {})", fmt_hz(*f))).unwrap_or_default();
    let _ = write!(
        h,
        "<h2>Accuracy over the band</h2>\n<p>Flange-to-flange transfer functions H(&omega;) (unit loads at the force \
flanges, response at the same DoFs) of the full FE model and of the reduced model, both with the damping below, at {n} \
frequencies: an even grid over the band plus every full-model eigenfrequency in it and its close neighbours. The relative \
error is |S (H<sub>full</sub> &minus; H<sub>red</sub>) S|<sub>F</sub> / |S H<sub>full</sub> S|<sub>F</sub> with \
S = diag(C<sub>static</sub>)<sup>&minus;1/2</sup>, unit-free.</p>\n\
<table><tr><th>band [Hz]</th><td>{lo} &ndash; {hi}</td></tr><tr><th>comparison damping</th><td>{damping}</td></tr>\
<tr><th>sampled frequencies</th><td>{n}</td></tr><tr><th>max relative error</th><td>{max:.3e}{at}</td></tr>\
<tr><th>full model's responses</th><td>{method}</td></tr></table>\n",
        method = esc(&fr.method),
        n = fr.frequencies_hz.len(),
        lo = fmt_num(fr.band_hz[0]),
        hi = fmt_num(fr.band_hz[1]),
        damping = damping_html(&fr.damping),
        max = fr.max_relative_error,
    );
    let (stress_at, stress_max) = arg_max(&fr.stress_relative_error);
    if let Some(i) = stress_at {
        let _ = writeln!(
            h,
            "<p>Stress responses at the recovery points (every point, component and unit flange load), full against \
reduced: largest relative error {stress_max:.3e} (at {}).</p>",
            fmt_hz(fr.frequencies_hz[i])
        );
    }
    h.push_str("<div class=\"plot\">\n");
    h.push_str(&frequency_response_plot(fr, flanges));
    h.push_str("</div>\n<div class=\"plot\">\n");
    h.push_str(&relative_error_plot(fr));
    h.push_str("</div>\n");
    h
}

fn damping_html(d: &ComparisonDamping) -> String {
    let mut parts = Vec::new();
    if d.alpha != 0.0 || d.beta != 0.0 {
        parts.push(format!("Rayleigh &alpha; = {:.4e} 1/s, &beta; = {:.4e} s (the input's)", d.alpha, d.beta));
    }
    if d.loss_factor != 0.0 {
        let why = if parts.is_empty() {
            " (no Rayleigh damping in the input, and modal damping has no full-model counterpart: a loss factor keeps \
both models' responses finite at the eigenfrequencies)"
        } else {
            ""
        };
        parts.push(format!("structural loss factor &eta; = {}{why}", fmt_num(d.loss_factor)));
    }
    if parts.is_empty() { "none".to_string() } else { parts.join("; ") }
}

/// Short decimal text of a finite number, "NaN"/"inf" otherwise.
fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        format!("{v}")
    } else if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-3) {
        format!("{v:.3e}")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" { "0".to_string() } else { s.to_string() }
    }
}

fn fmt_hz(v: f64) -> String {
    format!("{} Hz", fmt_num(v))
}

/// Index and value of the largest finite entry.
fn arg_max(v: &[f64]) -> (Option<usize>, f64) {
    let mut best = (None, f64::NEG_INFINITY);
    for (i, &x) in v.iter().enumerate() {
        if x.is_finite() && x > best.1 {
            best = (Some(i), x);
        }
    }
    best
}

/// Flange DoF names in the order of the compliance rows.
pub const DOF_NAMES: [&str; 6] = ["u_x", "u_y", "u_z", "phi_x", "phi_y", "phi_z"];
/// A flange DoF is plotted when its peak |H_ii| over the band reaches this fraction of the
/// largest peak of its kind (translations m/N, rotations rad/(N m)).
pub const NEGLIGIBLE_RESPONSE: f64 = 1e-3;

/// "tip u_z" for DoF `d` (6 per flange, in the order of `flanges`), "DoF 13" past their end.
pub fn dof_label(flanges: &[String], d: usize) -> String {
    match flanges.get(d / 6) {
        Some(f) => format!("{f} {}", DOF_NAMES[d % 6]),
        None => format!("DoF {}", d + 1),
    }
}

/// The flange DoFs with a non-negligible driving-point response (see [`NEGLIGIBLE_RESPONSE`]);
/// `per_frequency[k][d]` is |H_dd| at the k-th frequency.
pub fn significant_dofs(per_frequency: &[Vec<f64>]) -> Vec<usize> {
    let n = per_frequency.iter().map(Vec::len).max().unwrap_or(0);
    let peak: Vec<f64> = (0..n)
        .map(|d| {
            per_frequency.iter().filter_map(|r| r.get(d)).filter(|v| v.is_finite()).fold(0.0f64, |a, v| a.max(v.abs()))
        })
        .collect();
    let kind_max = |translation: bool| {
        peak.iter().enumerate().filter(|(d, _)| (d % 6 < 3) == translation).fold(0.0f64, |a, (_, p)| a.max(*p))
    };
    let (t, r) = (kind_max(true), kind_max(false));
    (0..n).filter(|&d| peak[d] > 0.0 && peak[d] >= NEGLIGIBLE_RESPONSE * if d % 6 < 3 { t } else { r }).collect()
}

fn column(per_frequency: &[Vec<f64>], d: usize) -> Vec<f64> {
    per_frequency.iter().map(|r| r.get(d).copied().unwrap_or(f64::NAN)).collect()
}

/// Plot (a): driving-point magnitudes |H_ii| of the significant flange DoFs over the band, full
/// model as a broad light line, reduced model dashed on top in the same colour.
pub fn frequency_response_plot(fr: &FrequencyResponse, flanges: &[String]) -> String {
    let mut series =
        vec![Series::key("full FE model", "#555", Stroke::Solid), Series::key("reduced model", "#555", Stroke::Dashed)];
    for (k, d) in significant_dofs(&fr.driving_point_full).into_iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        series.push(Series {
            label: Some(dof_label(flanges, d)),
            x: fr.frequencies_hz.clone(),
            y: column(&fr.driving_point_full, d),
            color: color.to_string(),
            stroke: Stroke::Solid,
        });
        series.push(Series {
            label: None,
            x: fr.frequencies_hz.clone(),
            y: column(&fr.driving_point_reduced, d),
            color: color.to_string(),
            stroke: Stroke::Dashed,
        });
    }
    let mut spec = PlotSpec::new(
        "Driving-point response |H_ii|: full FE vs reduced",
        "frequency [Hz]",
        "|H_ii|  [m/N, rad/(N m)]",
        true,
    );
    spec.x_range = Some(fr.band_hz);
    line_plot(&spec, &series, &[])
}

/// The eigenfrequency error of every reduced mode paired with a full mode (by MAC, or by index
/// where no pairing was made), over the full mode's frequency on a log axis: the accuracy plot
/// every body has, with or without force flanges and a band. None without a pair.
pub fn frequency_error_plot(a: &Accuracy) -> Option<String> {
    let points: Vec<(f64, f64)> = if a.pairs.is_empty() {
        a.full_hz.iter().zip(&a.relative_error).map(|(&f, &e)| (f, e)).collect()
    } else {
        a.pairs.iter().filter_map(|p| Some((p.full_hz?, p.relative_error?))).collect()
    };
    // an exact frequency has no place on a log axis: shown at the floor of double precision
    if points.is_empty() {
        return None;
    }
    let (x, y): (Vec<f64>, Vec<f64>) = points.into_iter().map(|(f, e)| (f, e.abs().max(1e-16))).unzip();
    let worst = y.iter().copied().fold(0.0, f64::max);
    let series = [
        Series { label: None, x: x.clone(), y: y.clone(), color: PALETTE[0].to_string(), stroke: Stroke::Line },
        Series { label: None, x, y, color: PALETTE[0].to_string(), stroke: Stroke::Markers },
    ];
    let spec = PlotSpec::new(
        &format!("Eigenfrequency error of the reduced modes, against the full FE model (max {worst:.2e})"),
        "full-model frequency [Hz]",
        "relative error [-]",
        true,
    );
    Some(line_plot(&spec, &series, &[]))
}

/// Plot (b): relative error of the flange FRF per frequency on a log axis, its maximum marked.
pub fn relative_error_plot(fr: &FrequencyResponse) -> String {
    let series = [Series {
        label: None,
        x: fr.frequencies_hz.clone(),
        y: fr.relative_error.clone(),
        color: PALETTE[0].to_string(),
        stroke: Stroke::Line,
    }];
    let mut annotations = Vec::new();
    let (argmax, max) = arg_max(&fr.relative_error);
    if let Some(f) = argmax.and_then(|i| fr.frequencies_hz.get(i)) {
        annotations.push(Annotation {
            x: *f,
            y: max,
            text: format!("max {:.2e} at {}", fr.max_relative_error, fmt_hz(*f)),
        });
    }
    let mut spec = PlotSpec::new(
        &format!("Relative error of the flange FRF, reduced vs full (max {:.2e})", fr.max_relative_error),
        "frequency [Hz]",
        "relative error [-]",
        true,
    );
    spec.x_range = Some(fr.band_hz);
    line_plot(&spec, &series, &annotations)
}

/// The documentation page of an assembly: its bodies (each flexible one's reduction in figures),
/// joints, external flanges and variables.
pub fn assembly_html(
    spec: &crate::input::assembly::AssemblySpec,
    d: &fmu_runtime::assembly::description::AssemblyDescription,
    table: &fmu_runtime::interface::assembly::AssemblyTable,
    reports: &[(String, Report)],
) -> String {
    use fmu_runtime::assembly::description::{BodyModel, Side};
    let esc = |s: &str| s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;");
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title></head><body>\n<h1>{0}</h1>\n\
<p>An assembly of {1} bodies and {2} joints, solved together inside the FMU (Co-Simulation): generalised-alpha \
with spectral radius {3} on the bodies' poses, the joints' equations at position level in every step of at most \
{4} s, Newton's method to {5:e}.</p>\n",
        esc(&spec.name),
        d.bodies.len(),
        d.joints.len(),
        d.solver.spectral_radius,
        d.solver.max_step,
        d.solver.tolerance
    );
    h.push_str("<h2>Bodies</h2>\n<table>\n<tr><th>body</th><th>kind</th><th>mass [kg]</th><th>modes</th><th>flange compliance error</th></tr>\n");
    for b in &d.bodies {
        let (kind, mass, modes) = match &b.model {
            BodyModel::Flexible(r) => ("flexible", r.mass, r.n_modes().to_string()),
            BodyModel::Rigid { mass, .. } => ("rigid", *mass, "-".to_string()),
        };
        let compliance = reports
            .iter()
            .find(|(n, _)| *n == b.name)
            .map_or("-".to_string(), |(_, r)| format!("{:.2e}", r.accuracy.compliance_max_relative_error));
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{kind}</td><td>{mass:.6}</td><td>{modes}</td><td>{compliance}</td></tr>",
            esc(&b.name)
        );
    }
    h.push_str(
        "</table>\n<h2>Joints</h2>\n<table>\n<tr><th>joint</th><th>type</th><th>between</th><th>drive</th></tr>\n",
    );
    let side = |s: &Side| match s {
        Side::Ground => "ground".to_string(),
        Side::Body { body, marker } => {
            format!("{}.{}", d.bodies[*body].name, d.bodies[*body].flange_names()[*marker])
        }
    };
    for j in &d.joints {
        let drive = j.drive.map_or("-".to_string(), |dr| format!("{:?} by {:?}", dr.quantity, dr.function));
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{} - {}</td><td>{}</td></tr>",
            esc(&j.name),
            j.kind.name(),
            esc(&side(&j.first)),
            esc(&side(&j.second)),
            esc(&drive)
        );
    }
    h.push_str("</table>\n<h2>Variables</h2>\n<table>\n<tr><th>name</th><th>causality</th><th>unit</th><th>description</th></tr>\n");
    for v in &table.variables {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:?}</td><td>{}</td><td>{}</td></tr>",
            esc(&v.name),
            v.causality,
            v.unit.unwrap_or(""),
            esc(&v.description)
        );
    }
    h.push_str("</table>\n</body></html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::plot::tests::check_svg;
    use crate::output::report::FlangeReport;
    use crate::reduce::accuracy::Accuracy;

    fn frf(freqs: Vec<f64>, err: Vec<f64>, full: Vec<Vec<f64>>, red: Vec<Vec<f64>>) -> FrequencyResponse {
        let max = err.iter().copied().fold(0.0, f64::max);
        FrequencyResponse {
            band_hz: [0.0, 2000.0],
            damping: ComparisonDamping::new(0.0, 0.0),
            frequencies_hz: freqs,
            relative_error: err,
            max_relative_error: max,
            driving_point_full: full,
            driving_point_reduced: red,
            full_matrices: Vec::new(),
            stress_relative_error: Vec::new(),
            stress_full: Vec::new(),
            method: "test".into(),
        }
    }

    /// A cantilever-like response: two modes in the band, u_x and phi_x negligible.
    fn sample_frf() -> FrequencyResponse {
        let freqs: Vec<f64> = (0..80).map(|i| 12.5 + 25.0 * i as f64).collect();
        let resp = |f: f64, scale: f64| {
            let h = |fn_: f64| 1.0 / ((fn_ * fn_ - f * f).powi(2) + (0.02 * fn_ * f).powi(2)).sqrt();
            scale * (h(300.0) + 0.3 * h(1500.0))
        };
        let full: Vec<Vec<f64>> =
            freqs.iter().map(|&f| vec![1e-12, resp(f, 1e2), resp(f, 3e2), 0.0, resp(f, 5e2), resp(f, 2e2)]).collect();
        let red: Vec<Vec<f64>> = full.iter().map(|r| r.iter().map(|v| v * 1.01).collect()).collect();
        let err = freqs.iter().map(|f| 1e-6 * (1.0 + f / 100.0)).collect();
        frf(freqs, err, full, red)
    }

    /// The page of `r` with a two-mode body's variables and a small input.
    fn html_of(r: &Report) -> String {
        let table = VariableTable::new(&fmu_runtime::reduced::two_mode_body());
        index_html(r, &table, "{\"name\": \"Beam <test>\"}")
    }

    fn report(fr: Option<FrequencyResponse>) -> Report {
        Report {
            model_name: "Beam <test> & co".into(),
            tool: "fmu-builder test".into(),
            damping: "none".into(),
            guid: "{0000}".into(),
            element: "C3D10".into(),
            nodes: 100,
            elements: 50,
            dofs_constrained: 294,
            mass: 1.5,
            volume: Some(2e-4),
            source: "1 boxes".into(),
            rigid_body_residual: None,
            center_of_mass: [0.1, 0.0, 0.0],
            inertia_about_origin: [0.0; 9],
            method: "Craig-Bampton".into(),
            fixed_interface_modes: 4,
            constraint_modes: 6,
            order: 10,
            dynamic_modes: 4,
            relaxing_modes: 0,
            dynamic_cutoff_hz: Some(500.0),
            dynamic_cutoff_rule: "the highest fixed-interface mode".into(),
            scene_cutoff_hz: Some(1e4),
            host_cutoff_hz: 500.0,
            default_experiment: crate::output::report::ExperimentReport {
                stop_time: 2.0,
                step_size: 2e-3,
                tolerance: 1e-6,
            },
            default_step_rule: "a thousandth of the run".into(),
            explicit_euler_step: 0.0,
            explicit_euler_mode_hz: Some(300.0),
            undamped_dynamic_modes: 2,
            flanges: vec![FlangeReport {
                name: "tip".into(),
                role: "force".into(),
                reference_point: [1.0, 0.0, 0.0],
                slave_nodes: 9,
                coupling: "rigid".into(),
            }],
            stress_points: Vec::new(),
            backend: Default::default(),
            scene: Default::default(),
            warnings: Vec::new(),
            said_early: 0,
            pictures: Vec::new(),
            verdict: Default::default(),
            accuracy: Accuracy {
                reduced_hz: vec![300.0, 1500.0],
                full_hz: vec![299.0, 1490.0],
                relative_error: vec![3e-3, 6e-3],
                compliance_flanges: vec!["tip".into()],
                compliance_full: vec![vec![1.0; 6]; 6],
                compliance_reduced: vec![vec![1.0; 6]; 6],
                compliance_max_relative_error: 1e-14,
                inertial_cases: Vec::new(),
                inertial_flange_response_full: Vec::new(),
                frequency_response: fr,
                pairs: Vec::new(),
            },
        }
    }

    fn svgs(html: &str) -> Vec<&str> {
        let mut out = Vec::new();
        let mut rest = html;
        while let Some(a) = rest.find("<svg") {
            let b = rest[a..].find("</svg>").expect("unterminated svg") + a + "</svg>".len();
            out.push(&rest[a..b]);
            rest = &rest[b..];
        }
        out
    }

    fn pair(reduced: usize, full: Option<usize>, mac: f64, err: f64) -> ModePair {
        ModePair {
            reduced,
            full,
            mac,
            reduced_hz: 100.0 * reduced as f64,
            full_hz: full.map(|_| 100.0 * reduced as f64 / (1.0 + err)),
            relative_error: full.map(|_| err),
        }
    }

    /// The rows of the eigenfrequency table that carry the outside-the-valid-range mark.
    fn marked_rows(html: &str) -> Vec<String> {
        html.lines()
            .filter(|l| l.starts_with("<tr class=\"outside\">"))
            .map(|l| l.split("<td>").nth(1).unwrap_or("").trim_end_matches("</td>").to_string())
            .collect()
    }

    #[test]
    fn modes_are_marked_by_frequency_error_or_mac() {
        let mut r = report(None);
        r.accuracy.pairs = vec![
            pair(1, Some(1), 0.999, 2e-3),
            // the right shape at the wrong frequency: the MAC alone let it through
            pair(2, Some(2), 0.914, 0.26),
            pair(3, None, 0.4, 0.0),
            pair(4, Some(4), 0.95, -0.012),
        ];
        let html = html_of(&r);
        assert_eq!(marked_rows(&html), ["2", "3", "4"], "{html}");
        assert!(
            html.contains("above 1 % (the scene names no tolerance) or a MAC below 0.9. 3 modes marked."),
            "{html}"
        );
        // the scene's tolerance replaces the 1 %
        let table = VariableTable::new(&fmu_runtime::reduced::two_mode_body());
        let html = index_html(&r, &table, "{\"name\": \"b\", \"scene\": {\"tolerance\": 0.5}}");
        assert_eq!(marked_rows(&html), ["3"]);
        assert!(html.contains("above 50 % (the scene's tolerance, scene.tolerance)"), "{html}");
        // without pairs, by index: the frequency error alone
        r.accuracy.pairs.clear();
        r.accuracy.relative_error = vec![3e-3, 0.02];
        let html = html_of(&r);
        assert_eq!(marked_rows(&html), ["2"]);
        assert!(!html.contains("MAC below") && html.contains("1 mode marked."));
    }

    #[test]
    fn a_pair_across_indices_is_noted() {
        let mut r = report(None);
        r.accuracy.pairs =
            vec![pair(16, Some(16), 0.99, 1e-4), pair(17, Some(18), 0.97, -3e-3), pair(18, Some(17), 0.97, 4e-3)];
        let html = html_of(&r);
        assert!(html.contains("<td>18 <sup>&Dagger;</sup></td>") && html.contains("<td>17 <sup>&Dagger;</sup></td>"));
        assert_eq!(html.matches("<sup>&Dagger;</sup>").count(), 3, "two cells and the note");
        assert!(html.contains(
            "Paired by MAC across indices: reduced mode 17 with full mode 18, reduced mode 18 with full mode 17."
        ));
        assert!(html.contains("negative error"));
        r.accuracy.pairs.remove(1);
        r.accuracy.pairs.remove(1);
        assert!(!html_of(&r).contains("&Dagger;"));
    }

    #[test]
    fn stresses_in_mpa_to_four_digits() {
        for (pa, text) in [
            (1.521e6, "1.521"),
            (631357.8008, "0.6314"),
            (-1.5214e8, "-152.1"),
            (2.0e9, "2000"),
            (9.99996e6, "10.00"),
            (0.0, "0"),
            (12.0, "0.00001200"),
            (0.5, "5.000e-7"),
            (3.2e10, "3.200e4"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(fmt_mpa(pa), text, "{pa}");
        }
        let mut r = report(None);
        r.stress_points = vec![StressPointReport {
            name: "hot1".into(),
            description: "node 7".into(),
            position: [0.0; 3],
            unit_cases: vec![crate::output::report::UnitCaseStress {
                case: "tip f_z".into(),
                stress: [1.521e6, 631357.8008, 0.0, -2.5e5, 1.0, 7.0e7],
                von_mises: 1.9e6,
            }],
        }];
        let html = html_of(&r);
        assert!(html.contains("<th>von Mises [MPa]</th>") && !html.contains("[Pa]</th>"), "{html}");
        assert!(html.contains("<td>1.521</td><td>0.6314</td><td>0</td><td>-0.2500</td><td>0.000001000</td><td>70.00</td><td>1.900</td>"), "{html}");
    }

    #[test]
    fn the_input_listing_leaves_out_unset_fields_in_order() {
        #[derive(serde::Serialize)]
        struct Inner {
            b: Option<f64>,
            a: Vec<Option<u32>>,
        }
        #[derive(serde::Serialize)]
        struct Outer {
            name: &'static str,
            unset: Option<u32>,
            inner: Inner,
            e: f64,
        }
        let text = input_listing(&Outer {
            name: "x",
            unset: None,
            inner: Inner { b: None, a: vec![Some(1), None] },
            e: 2.1e11,
        })
        .unwrap();
        // an array keeps its nulls: their positions carry meaning
        assert_eq!(
            text,
            "{\n  \"name\": \"x\",\n  \"inner\": {\n    \"a\": [\n      1,\n      null\n    ]\n  },\n  \"e\": 210000000000.0\n}"
        );
    }

    #[test]
    fn three_svgs_with_frequency_response() {
        let html = html_of(&report(Some(sample_frf())));
        // the eigenfrequency errors, the driving points, the FRF error
        assert_eq!(html.matches("<svg").count(), 3);
        assert!(html.contains("Accuracy over the band"));
        assert!(html.contains("loss factor"));
        assert!(html.contains("tip u_z") && html.contains("tip phi_y"));
        // u_x (1e-12) and phi_x (0) are negligible
        assert!(!html.contains("tip u_x") && !html.contains("tip phi_x"));
        for svg in svgs(&html) {
            assert!(check_svg(svg) > 20);
        }
        // the existing content stays
        for s in [
            "Rigid body",
            "Flanges",
            "Reduction",
            "Eigenfrequencies",
            "Static compliance",
            "Beam &lt;test&gt; &amp; co",
        ] {
            assert!(html.contains(s), "{s}");
        }
    }

    #[test]
    fn the_frequency_errors_alone_without_frequency_response() {
        let html = html_of(&report(None));
        let plots = svgs(&html);
        assert_eq!(plots.len(), 1);
        assert!(plots[0].contains("Eigenfrequency error of the reduced modes"));
        // both modes' points, a marker each
        assert!(check_svg(plots[0]) > 10);
        assert_eq!(plots[0].matches("<circle").count(), 2);
        assert!(plots[0].contains("max 6.00e-3"), "{}", plots[0]);
        assert!(!html.contains("Accuracy over the band"));
        assert!(html.contains("Static compliance"));
    }

    #[test]
    fn the_model_exchange_split_and_its_reason_are_stated() {
        let mut r = report(None);
        let html = html_of(&r);
        // the host's limit chose the cutoff: its reason and the remedy are named
        assert!(html.contains("500 solver steps"), "{html}");
        assert!(html.contains("reduction.dynamic_cutoff"));
        assert!(html.contains("stop 2e0 s, tolerance 1e-6, step 2e-3 s: a thousandth of the run"), "{html}");
        // an undamped dynamic mode: no explicit step is stable, and the page says so
        assert!(html.contains("cannot carry it: the dynamic mode at 300.0000 Hz is undamped"));
        // undamped dynamic modes: the tolerance advice and its field
        assert!(html.contains("2 dynamic modes are undamped") && html.contains("experiment.tolerance"), "{html}");
        // the scene's own cutoff below the host's: no excuse is printed
        r.scene_cutoff_hz = Some(400.0);
        r.host_cutoff_hz = 2000.0;
        assert!(!html_of(&r).contains("500 solver steps"));
    }

    #[test]
    fn rayleigh_damping_and_max_in_table() {
        let mut fr = sample_frf();
        fr.damping = ComparisonDamping::new(2.0, 1e-5);
        let html = html_of(&report(Some(fr.clone())));
        assert!(html.contains("Rayleigh") && html.contains("2.0000e0") && html.contains("1.0000e-5"));
        assert!(html.contains(&format!("{:.3e}", fr.max_relative_error)));
        assert!(html.contains(&format!("max {:.2e}", fr.max_relative_error)));
    }

    #[test]
    fn degenerate_data_does_not_panic() {
        let cases = vec![
            // zeros everywhere on log axes
            frf(vec![10.0, 20.0, 30.0], vec![0.0; 3], vec![vec![0.0; 6]; 3], vec![vec![0.0; 6]; 3]),
            // one frequency
            frf(vec![100.0], vec![1e-3], vec![vec![1e-4; 6]], vec![vec![1e-4; 6]]),
            // NaN, inf, negative and ragged rows
            frf(
                vec![1.0, f64::NAN, 3.0, 4.0],
                vec![f64::NAN, 1e-2, f64::INFINITY, -1.0],
                vec![vec![1e-3, f64::NAN], vec![f64::INFINITY; 12], vec![], vec![0.0, 1e-5, 2e-5]],
                vec![vec![1e-3]],
            ),
            // nothing at all
            frf(Vec::new(), Vec::new(), Vec::new(), Vec::new()),
        ];
        for mut fr in cases {
            for band in [[0.0, 2000.0], [100.0, 100.0], [f64::NAN, 5.0], [50.0, 10.0]] {
                fr.band_hz = band;
                let html = html_of(&report(Some(fr.clone())));
                let svgs = svgs(&html);
                // the eigenfrequency errors and the band's two plots
                assert_eq!(svgs.len(), 3);
                for svg in svgs {
                    check_svg(svg);
                }
            }
        }
    }
}
