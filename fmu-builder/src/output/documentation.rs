//! `documentation/index.html` of the FMU: the body's mass, flanges, reduction and its accuracy
//! against the full FE model, readable without any tool. The plots are inline SVG written by hand
//! (no JavaScript, no external files): [`line_plot`] draws any set of series on linear or
//! logarithmic axes; [`frequency_response_plot`] and [`relative_error_plot`] build on it.

use crate::reduce::frf::{ComparisonDamping, FrequencyResponse};
use crate::output::report::Report;
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

pub fn index_html(r: &Report) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{name}</title>\
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #bbb;padding:0.2em 0.6em;text-align:right}}th{{background:#eee}}</style></head><body>\n\
<h1>{name}: reduced flexible body</h1>\n<p>Built by fmu-builder from a {el} mesh of {nodes} nodes and {els} elements \
({dofs} DoFs after flange coupling). GUID {guid}.</p>\n",
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
<tr><th>centre of mass [m] (body frame)</th><td>{:.6e}, {:.6e}, {:.6e}</td></tr></table>\n\
<p>Body frame: origin at the mount flange's reference point, axes of the undeformed part.</p>\n",
        r.mass, r.volume.map_or("(matrix input)".to_string(), |v| format!("{v:.6e}")), c[0], c[1], c[2]
    );
    h.push_str("<h2>Flanges</h2>\n<table><tr><th>name</th><th>role</th><th>reference point [m]</th><th>slave nodes</th></tr>\n");
    for f in &r.flanges {
        let p = f.reference_point;
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{:.6}, {:.6}, {:.6}</td><td>{}</td></tr>",
            esc(&f.name),
            esc(&f.role),
            p[0],
            p[1],
            p[2],
            f.slave_nodes
        );
    }
    h.push_str("</table>\n");
    let _ = write!(
        h,
        "<h2>Reduction</h2>\n<p>{} with {} fixed-interface normal modes and {} constraint modes: reduced order {} \
(states q, qd: {}).</p>\n",
        esc(&r.method),
        r.fixed_interface_modes,
        r.constraint_modes,
        r.order,
        2 * r.order
    );
    h.push_str("<h3>Eigenfrequencies of the mounted body</h3>\n<table><tr><th>mode</th><th>reduced [Hz]</th><th>full FE [Hz]</th><th>relative error</th></tr>\n");
    let a = &r.accuracy;
    for i in 0..a.reduced_hz.len() {
        let full = a.full_hz.get(i).map(|f| format!("{f:.6}")).unwrap_or_default();
        let err = a.relative_error.get(i).map(|e| format!("{e:.2e}")).unwrap_or_default();
        let _ = writeln!(h, "<tr><td>{}</td><td>{:.6}</td><td>{full}</td><td>{err}</td></tr>", i + 1, a.reduced_hz[i]);
    }
    h.push_str("</table>\n");
    let _ = write!(
        h,
        "<h3>Static compliance of the force flanges</h3>\n<p>Largest deviation of the reduced from the full-model \
compliance (relative to its largest entry): {:.2e}. Constraint modes make it exact up to round-off.</p>\n",
        a.compliance_max_relative_error
    );
    if let Some(fr) = &a.frequency_response {
        h.push_str(&accuracy_over_band_html(fr, &a.compliance_flanges));
    }
    h.push_str("<p>The machine-readable report, with the full compliance matrices, is <code>report.json</code> beside this file.</p>\n</body></html>\n");
    h
}

/// The "Accuracy over the band" section: a table of the comparison's settings and result, the
/// driving-point magnitudes full vs reduced and the relative error per frequency.
fn accuracy_over_band_html(fr: &FrequencyResponse, flanges: &[String]) -> String {
    let mut h = String::new();
    let (argmax, _) = arg_max(&fr.relative_error);
    let at = argmax
        .and_then(|i| fr.frequencies_hz.get(i))
        .map(|f| format!(" (at {})", fmt_hz(*f)))
        .unwrap_or_default();
    let _ = write!(
        h,
        "<h2>Accuracy over the band</h2>\n<p>Flange-to-flange transfer functions H(&omega;) (unit loads at the force \
flanges, response at the same DoFs) of the full FE model and of the reduced model, both with the damping below, at {n} \
frequencies: an even grid over the band plus every full-model eigenfrequency in it and its close neighbours. The relative \
error is |S (H<sub>full</sub> &minus; H<sub>red</sub>) S|<sub>F</sub> / |S H<sub>full</sub> S|<sub>F</sub> with \
S = diag(C<sub>static</sub>)<sup>&minus;1/2</sup>, unit-free.</p>\n\
<table><tr><th>band [Hz]</th><td>{lo} &ndash; {hi}</td></tr><tr><th>comparison damping</th><td>{damping}</td></tr>\
<tr><th>sampled frequencies</th><td>{n}</td></tr><tr><th>max relative error</th><td>{max:.3e}{at}</td></tr></table>\n",
        n = fr.frequencies_hz.len(),
        lo = fmt_num(fr.band_hz[0]),
        hi = fmt_num(fr.band_hz[1]),
        damping = damping_html(&fr.damping),
        max = fr.max_relative_error,
    );
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
        let why = if parts.is_empty() { " (the input has no damping; undamped responses are infinite at the eigenfrequencies)" } else { "" };
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
/// Distinguishable colours (Tableau 10), cycled.
pub const PALETTE: [&str; 10] =
    ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];
/// A flange DoF is plotted when its peak |H_ii| over the band reaches this fraction of the
/// largest peak of its kind (translations m/N, rotations rad/(N m)).
pub const NEGLIGIBLE_RESPONSE: f64 = 1e-3;
/// Log axes span at most this many decades below the largest value; smaller values and zeros are
/// drawn at the floor.
pub const LOG_AXIS_DECADES: f64 = 12.0;

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
        .map(|d| per_frequency.iter().filter_map(|r| r.get(d)).filter(|v| v.is_finite()).fold(0.0f64, |a, v| a.max(v.abs())))
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
    let mut series = vec![
        Series::key("full FE model", "#555", Stroke::Solid),
        Series::key("reduced model", "#555", Stroke::Dashed),
    ];
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
    let mut spec = PlotSpec::new("Driving-point response |H_ii|: full FE vs reduced", "frequency [Hz]", "|H_ii|  [m/N, rad/(N m)]", true);
    spec.x_range = Some(fr.band_hz);
    line_plot(&spec, &series, &[])
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
        annotations.push(Annotation { x: *f, y: max, text: format!("max {:.2e} at {}", fr.max_relative_error, fmt_hz(*f)) });
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

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stroke {
    /// Broad, half-transparent line (a reference curve others are drawn over).
    Solid,
    /// Thin dashed line.
    Dashed,
    /// Thin solid line.
    Line,
    /// A dot per point, no line.
    Markers,
}

/// One curve: points (x[i], y[i]) up to the shorter of the two; non-finite points break the line.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text; `None` keeps the series out of the legend. A labelled series without points is
    /// a pure legend entry (e.g. the key of a line style).
    pub label: Option<String>,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    /// Any SVG colour, e.g. "#1f77b4".
    pub color: String,
    pub stroke: Stroke,
}

impl Series {
    /// A legend-only entry.
    pub fn key(label: &str, color: &str, stroke: Stroke) -> Self {
        Self { label: Some(label.to_string()), x: Vec::new(), y: Vec::new(), color: color.to_string(), stroke }
    }
}

/// A marked point with a text beside it (e.g. the maximum).
#[derive(Debug, Clone)]
pub struct Annotation {
    pub x: f64,
    pub y: f64,
    pub text: String,
}

/// Title, axes and size of a [`line_plot`].
#[derive(Debug, Clone)]
pub struct PlotSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// Axis ranges; `None` (or an unusable range) fits the data.
    pub x_range: Option<[f64; 2]>,
    pub y_range: Option<[f64; 2]>,
    /// Minimum size [px]; the height grows when the legend needs it.
    pub width: f64,
    pub height: f64,
}

impl PlotSpec {
    /// 700 x 350 px, linear x, ranges from the data.
    pub fn new(title: &str, x_label: &str, y_label: &str, log_y: bool) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            log_x: false,
            log_y,
            x_range: None,
            y_range: None,
            width: 700.0,
            height: 350.0,
        }
    }
}

/// Maps data to pixels along one axis; for a log axis `lo`/`hi` are decades (exponents).
#[derive(Debug, Clone, Copy)]
struct Scale {
    lo: f64,
    hi: f64,
    log: bool,
    p0: f64,
    p1: f64,
}

impl Scale {
    /// Pixel of `v`, clamped to the axis; `None` for NaN/inf. On a log axis, values below the
    /// floor (zeros, negatives) land on the floor.
    fn px(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        let t = if self.log { if v > 0.0 { v.log10().max(self.lo) } else { self.lo } } else { v };
        let frac = ((t - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0);
        let p = self.p0 + frac * (self.p1 - self.p0);
        p.is_finite().then_some(p)
    }

    /// Pixel of an axis coordinate (decade exponent on a log axis).
    fn at(&self, t: f64) -> f64 {
        let p = self.p0 + (t - self.lo) / (self.hi - self.lo) * (self.p1 - self.p0);
        if p.is_finite() { p } else { self.p0 }
    }
}

/// Axis range: the explicit one when usable, else fitted to `values`. Linear: (min, max) with 5 %
/// margins; log: whole decades (exponents) covering at most [`LOG_AXIS_DECADES`] below the max.
fn axis_range(values: &[f64], log: bool, explicit: Option<[f64; 2]>) -> (f64, f64) {
    if let Some([a, b]) = explicit
        && a.is_finite()
        && b.is_finite()
        && a < b
        && (!log || a > 0.0)
    {
        return if log { (a.log10(), b.log10()) } else { (a, b) };
    }
    if log {
        let pos = values.iter().copied().filter(|v| v.is_finite() && *v > 0.0);
        let (min, max) = pos.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if max <= 0.0 {
            return (-1.0, 0.0);
        }
        let hi = max.log10().ceil();
        let lo = min.log10().max(max.log10() - LOG_AXIS_DECADES).floor();
        if lo < hi { (lo, hi) } else { (hi - 1.0, hi) }
    } else {
        let fin = values.iter().copied().filter(|v| v.is_finite());
        let (min, max) = fin.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if !(min.is_finite() && max.is_finite()) {
            return (0.0, 1.0);
        }
        let span = max - min;
        let pad = if span > 0.0 { 0.05 * span } else if min != 0.0 { 0.1 * min.abs() } else { 1.0 };
        let (lo, hi) = (min - pad, max + pad);
        if lo < hi && lo.is_finite() && hi.is_finite() { (lo, hi) } else { (0.0, 1.0) }
    }
}

/// 5-8 "nice" tick positions (steps 1, 2, 2.5, 5 x 10^k) inside [lo, hi], and the step.
fn linear_ticks(lo: f64, hi: f64) -> (Vec<f64>, f64) {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return (vec![lo], 1.0);
    }
    let e = (span / 6.0).log10().floor();
    let count = |step: f64| ((hi / step + 1e-9).floor() - (lo / step - 1e-9).ceil()) as i64 + 1;
    let mut best: Option<(i64, f64)> = None;
    for k in [e - 1.0, e, e + 1.0] {
        for m in [1.0, 2.0, 2.5, 5.0] {
            let step = m * 10f64.powf(k);
            let n = count(step);
            let score = if (5..=8).contains(&n) { (n - 6).abs() } else { 10 + (n - 6).abs() } * 2 + i64::from(m == 2.5);
            if best.is_none_or(|(s, _)| score < s) {
                best = Some((score, step));
            }
        }
    }
    let step = best.map_or(span / 5.0, |(_, s)| s);
    let first = (lo / step - 1e-9).ceil();
    let n = count(step).clamp(0, 50);
    let ticks = (0..n)
        .map(|i| {
            let v = (first + i as f64) * step;
            if v.abs() < 1e-9 * step { 0.0 } else { v }
        })
        .collect();
    (ticks, step)
}

/// Tick text with as many decimals as the step needs.
fn tick_text(v: f64, step: f64) -> String {
    let m = v.abs().max(step.abs());
    if m >= 1e6 || step < 1e-4 {
        return format!("{v:.2e}");
    }
    let decimals = (0..=6).find(|&d| {
        let s = step * 10f64.powi(d);
        (s - s.round()).abs() < 1e-6 * s.max(1.0)
    });
    format!("{v:.*}", decimals.unwrap_or(6) as usize)
}

/// Decade tick text: 10 with a superscript exponent.
fn decade_text(k: i64) -> String {
    format!("10<tspan dy=\"-5\" font-size=\"8\">{k}</tspan>")
}

/// Ticks of one axis: (axis coordinate, label if labelled); minor ticks without label.
fn axis_ticks(lo: f64, hi: f64, log: bool) -> Vec<(f64, Option<String>)> {
    if log {
        let (a, b) = (lo.ceil() as i64, hi.floor() as i64);
        let n = (b - a).max(0);
        let every = ((n + 7) / 8).max(1);
        let mut t = Vec::new();
        for k in a..=b {
            t.push((k as f64, ((k - a) % every == 0).then(|| decade_text(k))));
        }
        if n <= 6 {
            for k in (lo.floor() as i64)..=(hi.ceil() as i64) {
                for m in 2..=9 {
                    let c = k as f64 + (m as f64).log10();
                    if c > lo && c < hi {
                        t.push((c, None));
                    }
                }
            }
        }
        t
    } else {
        let (ticks, step) = linear_ticks(lo, hi);
        ticks.into_iter().map(|v| (v, Some(tick_text(v, step)))).collect()
    }
}

fn stroke_attrs(color: &str, stroke: Stroke) -> String {
    let c = esc(color);
    match stroke {
        Stroke::Solid => format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"3\" stroke-opacity=\"0.45\" stroke-linejoin=\"round\""),
        Stroke::Dashed => format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.4\" stroke-dasharray=\"5 3\""),
        Stroke::Line => format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.6\" stroke-linejoin=\"round\""),
        Stroke::Markers => format!("fill=\"{c}\" stroke=\"none\""),
    }
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n { s.to_string() } else { s.chars().take(n - 1).chain(std::iter::once('\u{2026}')).collect() }
}

/// An SVG line plot: `series` on linear or log axes (decades on log axes, 5-8 nice ticks on linear
/// ones), a grid, axis labels, a title, a legend of the labelled series at the right and
/// `annotations` as circled points with their text. Log axes draw zeros and negatives at the
/// floor; NaN/inf points break the line. Every coordinate written is finite.
pub fn line_plot(spec: &PlotSpec, series: &[Series], annotations: &[Annotation]) -> String {
    const ROW: f64 = 15.0;
    let legend: Vec<&Series> = series.iter().filter(|s| s.label.is_some()).collect();
    let width = if spec.width.is_finite() { spec.width.clamp(200.0, 4000.0) } else { 700.0 };
    let (left, top) = (72.0, 34.0);
    let right = width - if legend.is_empty() { 24.0 } else { 170.0 };
    let min_height = if spec.height.is_finite() { spec.height.clamp(150.0, 4000.0) } else { 350.0 };
    let height = min_height.max(top + 10.0 + ROW * legend.len() as f64 + 20.0);
    let bottom = height - 48.0;

    let xs: Vec<f64> = series.iter().flat_map(|s| s.x.iter().take(s.y.len()).copied()).chain(annotations.iter().map(|a| a.x)).collect();
    let ys: Vec<f64> = series.iter().flat_map(|s| s.y.iter().take(s.x.len()).copied()).chain(annotations.iter().map(|a| a.y)).collect();
    let (xlo, xhi) = axis_range(&xs, spec.log_x, spec.x_range);
    let (ylo, yhi) = axis_range(&ys, spec.log_y, spec.y_range);
    let sx = Scale { lo: xlo, hi: xhi, log: spec.log_x, p0: left, p1: right };
    let sy = Scale { lo: ylo, hi: yhi, log: spec.log_y, p0: bottom, p1: top };

    let mut s = String::new();
    let _ = write!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" viewBox=\"0 0 {width:.0} {height:.0}\" \
font-family=\"sans-serif\" font-size=\"11\" role=\"img\" aria-label=\"{t}\">\n<title>{t}</title>\n\
<rect x=\"0\" y=\"0\" width=\"{width:.0}\" height=\"{height:.0}\" fill=\"white\"/>\n\
<text x=\"{tx:.1}\" y=\"20\" text-anchor=\"middle\" font-size=\"13\" font-weight=\"bold\">{t}</text>\n",
        t = esc(&spec.title),
        tx = (left + right) / 2.0,
    );
    // grid and ticks
    for (t, label) in axis_ticks(xlo, xhi, spec.log_x) {
        let x = sx.at(t);
        let len = if label.is_some() { 5.0 } else { 3.0 };
        if label.is_some() {
            let _ = writeln!(s, "<line x1=\"{x:.1}\" y1=\"{top:.1}\" x2=\"{x:.1}\" y2=\"{bottom:.1}\" stroke=\"#e4e4e4\"/>");
        }
        let _ = writeln!(s, "<line x1=\"{x:.1}\" y1=\"{bottom:.1}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#444\"/>", bottom + len);
        if let Some(l) = label {
            let _ = writeln!(s, "<text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{l}</text>", bottom + 18.0);
        }
    }
    for (t, label) in axis_ticks(ylo, yhi, spec.log_y) {
        let y = sy.at(t);
        let len = if label.is_some() { 5.0 } else { 3.0 };
        if label.is_some() {
            let _ = writeln!(s, "<line x1=\"{left:.1}\" y1=\"{y:.1}\" x2=\"{right:.1}\" y2=\"{y:.1}\" stroke=\"#e4e4e4\"/>");
        }
        let _ = writeln!(s, "<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{left:.1}\" y2=\"{y:.1}\" stroke=\"#444\"/>", left - len);
        if let Some(l) = label {
            let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{l}</text>", left - 8.0, y + 4.0);
        }
    }
    let _ = write!(
        s,
        "<rect x=\"{left:.1}\" y=\"{top:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" stroke=\"#444\"/>\n\
<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n\
<text x=\"16\" y=\"{yc:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 16 {yc:.1})\">{}</text>\n",
        right - left,
        bottom - top,
        (left + right) / 2.0,
        height - 10.0,
        esc(&spec.x_label),
        esc(&spec.y_label),
        yc = (top + bottom) / 2.0,
    );
    // curves
    for se in series {
        let pts: Vec<Option<(f64, f64)>> =
            se.x.iter().zip(&se.y).map(|(&x, &y)| Some((sx.px(x)?, sy.px(y)?))).collect();
        let segments: Vec<&[Option<(f64, f64)>]> = pts.split(|p| p.is_none()).filter(|g| !g.is_empty()).collect();
        let mut dots = Vec::new();
        let mut d = String::new();
        for g in segments {
            let g: Vec<(f64, f64)> = g.iter().flatten().copied().collect();
            if se.stroke == Stroke::Markers || g.len() == 1 {
                dots.extend(g);
                continue;
            }
            for (i, (x, y)) in g.iter().enumerate() {
                let _ = write!(d, "{}{x:.1} {y:.1}", if i == 0 { if d.is_empty() { "M" } else { " M" } } else { " L" });
            }
        }
        if !d.is_empty() {
            let _ = writeln!(s, "<path d=\"{d}\" {}/>", stroke_attrs(&se.color, se.stroke));
        }
        for (x, y) in dots {
            let _ = writeln!(s, "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{}\"/>", esc(&se.color));
        }
    }
    // annotations
    for a in annotations {
        let (Some(x), Some(y)) = (sx.px(a.x), sy.px(a.y)) else { continue };
        let _ = writeln!(s, "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"none\" stroke=\"#c00\" stroke-width=\"1.5\"/>");
        let (tx, anchor) = if x < (left + right) / 2.0 { (x + 8.0, "start") } else { (x - 8.0, "end") };
        let ty = if y - 8.0 < top + 12.0 { y + 16.0 } else { y - 8.0 };
        let _ = writeln!(s, "<text x=\"{tx:.1}\" y=\"{ty:.1}\" text-anchor=\"{anchor}\" fill=\"#c00\">{}</text>", esc(&a.text));
    }
    // legend
    for (i, se) in legend.iter().enumerate() {
        let y = top + 10.0 + ROW * i as f64;
        let x = right + 12.0;
        if se.stroke == Stroke::Markers {
            let _ = writeln!(s, "<circle cx=\"{:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{}\"/>", x + 11.0, esc(&se.color));
        } else {
            let _ = writeln!(s, "<line x1=\"{x:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" {}/>", x + 22.0, stroke_attrs(&se.color, se.stroke));
        }
        let label = se.label.as_deref().unwrap_or_default();
        let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\">{}</text>", x + 28.0, y + 4.0, esc(&truncate(label, 20)));
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::report::FlangeReport;
    use crate::reduce::accuracy::Accuracy;
    use quick_xml::Reader;
    use quick_xml::events::Event;

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
        }
    }

    /// A cantilever-like response: two modes in the band, u_x and phi_x negligible.
    fn sample_frf() -> FrequencyResponse {
        let freqs: Vec<f64> = (0..80).map(|i| 12.5 + 25.0 * i as f64).collect();
        let resp = |f: f64, scale: f64| {
            let h = |fn_: f64| 1.0 / ((fn_ * fn_ - f * f).powi(2) + (0.02 * fn_ * f).powi(2)).sqrt();
            scale * (h(300.0) + 0.3 * h(1500.0))
        };
        let full: Vec<Vec<f64>> = freqs
            .iter()
            .map(|&f| vec![1e-12, resp(f, 1e2), resp(f, 3e2), 0.0, resp(f, 5e2), resp(f, 2e2)])
            .collect();
        let red: Vec<Vec<f64>> = full.iter().map(|r| r.iter().map(|v| v * 1.01).collect()).collect();
        let err = freqs.iter().map(|f| 1e-6 * (1.0 + f / 100.0)).collect();
        frf(freqs, err, full, red)
    }

    fn report(fr: Option<FrequencyResponse>) -> Report {
        Report {
            model_name: "Beam <test> & co".into(),
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
            flanges: vec![FlangeReport { name: "tip".into(), role: "force".into(), reference_point: [1.0, 0.0, 0.0], slave_nodes: 9 }],
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

    /// Reads the SVG through quick_xml (matching end tags, attributes) and checks that every
    /// numeric attribute and path coordinate is finite. Returns the element count.
    fn check_svg(svg: &str) -> usize {
        let numeric = ["x", "y", "x1", "y1", "x2", "y2", "cx", "cy", "r", "width", "height", "dy", "stroke-width", "font-size"];
        let mut reader = Reader::from_str(svg);
        let (mut depth, mut elements) = (0i64, 0usize);
        loop {
            let ev = reader.read_event().unwrap_or_else(|e| panic!("SVG is not well-formed at {}: {e}", reader.buffer_position()));
            let attrs = match &ev {
                Event::Start(e) => {
                    depth += 1;
                    Some(e.attributes())
                }
                Event::Empty(e) => Some(e.attributes()),
                Event::End(_) => {
                    depth -= 1;
                    None
                }
                Event::Eof => break,
                _ => None,
            };
            let Some(attrs) = attrs else { continue };
            elements += 1;
            for a in attrs {
                let a = a.expect("bad attribute");
                let key = a.key.as_ref().to_string();
                let val = a.value.to_string();
                let lower = val.to_lowercase();
                assert!(key == "aria-label" || !(lower.contains("nan") || lower.contains("inf")), "{key}=\"{val}\"");
                if numeric.contains(&key.as_str()) {
                    assert!(val.parse::<f64>().is_ok_and(f64::is_finite), "{key}=\"{val}\"");
                }
                if key == "d" || key == "viewBox" || key == "transform" || key == "stroke-dasharray" {
                    for tok in val.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e')).filter(|t| t.contains(|c: char| c.is_ascii_digit())) {
                        assert!(tok.parse::<f64>().is_ok_and(f64::is_finite), "{key}: {tok}");
                    }
                }
            }
        }
        assert_eq!(depth, 0, "unbalanced elements");
        elements
    }

    #[test]
    fn two_svgs_with_frequency_response() {
        let html = index_html(&report(Some(sample_frf())));
        assert_eq!(html.matches("<svg").count(), 2);
        assert!(html.contains("Accuracy over the band"));
        assert!(html.contains("loss factor"));
        assert!(html.contains("tip u_z") && html.contains("tip phi_y"));
        // u_x (1e-12) and phi_x (0) are negligible
        assert!(!html.contains("tip u_x") && !html.contains("tip phi_x"));
        for svg in svgs(&html) {
            assert!(check_svg(svg) > 20);
        }
        // the existing content stays
        for s in ["Rigid body", "Flanges", "Reduction", "Eigenfrequencies", "Static compliance", "Beam &lt;test&gt; &amp; co"] {
            assert!(html.contains(s), "{s}");
        }
    }

    #[test]
    fn no_svg_without_frequency_response() {
        let html = index_html(&report(None));
        assert_eq!(html.matches("<svg").count(), 0);
        assert!(!html.contains("Accuracy over the band"));
        assert!(html.contains("Static compliance"));
    }

    #[test]
    fn rayleigh_damping_and_max_in_table() {
        let mut fr = sample_frf();
        fr.damping = ComparisonDamping::new(2.0, 1e-5);
        let html = index_html(&report(Some(fr.clone())));
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
                let html = index_html(&report(Some(fr.clone())));
                let svgs = svgs(&html);
                assert_eq!(svgs.len(), 2);
                for svg in svgs {
                    check_svg(svg);
                }
            }
        }
    }

    #[test]
    fn log_axis_clamps_zeros_to_the_floor() {
        let series = [Series {
            label: Some("a".into()),
            x: vec![0.0, 1.0, 2.0, 3.0],
            y: vec![0.0, 1e-3, 1.0, -5.0],
            color: "#000".into(),
            stroke: Stroke::Markers,
        }];
        let svg = line_plot(&PlotSpec::new("t", "x", "y", true), &series, &[]);
        check_svg(&svg);
        // all four points drawn, the zero and the negative at the floor (bottom of the plot, 10^-3)
        assert_eq!(svg.matches("r=\"2.5\"").count(), 4 + 1);
        let (lo, hi) = axis_range(&series[0].y, true, None);
        assert_eq!((lo, hi), (-3.0, 0.0));
        let s = Scale { lo, hi, log: true, p0: 300.0, p1: 30.0 };
        assert_eq!(s.px(0.0), Some(300.0));
        assert_eq!(s.px(-1.0), Some(300.0));
        assert_eq!(s.px(1e-9), Some(300.0));
        assert_eq!(s.px(f64::NAN), None);
        // a tiny value among large ones does not stretch the axis beyond LOG_AXIS_DECADES
        let (lo, hi) = axis_range(&[1e-300, 1.0, 0.0], true, None);
        assert!(hi - lo <= LOG_AXIS_DECADES + 1.0);
        assert_eq!(axis_range(&[0.0, f64::NAN], true, None), (-1.0, 0.0));
    }

    #[test]
    fn linear_ticks_are_nice() {
        for (lo, hi) in [(0.0, 2000.0), (10.0, 1234.0), (0.0, 1.0), (0.3, 0.7), (-5.0, 5.0), (95.0, 105.0), (0.0, 3e7), (1e-6, 3e-6)] {
            let (t, step) = linear_ticks(lo, hi);
            assert!((5..=8).contains(&t.len()), "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|v| *v >= lo - 1e-9 * step && *v <= hi + 1e-9 * step), "{t:?}");
            let m = step / 10f64.powf(step.log10().floor());
            assert!([1.0, 2.0, 2.5, 5.0].iter().any(|n| (m - n).abs() < 1e-9), "{step}");
        }
        assert_eq!(tick_text(250.0, 250.0), "250");
        assert_eq!(tick_text(7.5, 2.5), "7.5");
        assert_eq!(tick_text(0.2, 0.1), "0.2");
    }

    #[test]
    fn line_plot_is_reusable_for_log_log_sweeps() {
        let mut spec = PlotSpec::new("error vs cost", "reduced order", "max relative error", true);
        spec.log_x = true;
        let series = [
            Series { label: Some("Craig-Bampton".into()), x: vec![6.0, 10.0, 20.0, 40.0], y: vec![1e-1, 1e-2, 1e-4, 1e-7], color: PALETTE[0].into(), stroke: Stroke::Dashed },
            Series { label: Some("modal \"x\" <y>".into()), x: vec![6.0, 12.0], y: vec![3e-2, 2e-3], color: PALETTE[1].into(), stroke: Stroke::Markers },
        ];
        let svg = line_plot(&spec, &series, &[Annotation { x: 40.0, y: 1e-7, text: "chosen".into() }]);
        check_svg(&svg);
        assert!(svg.contains("modal &quot;x&quot; &lt;y&gt;") && svg.contains("chosen"));
    }
}
