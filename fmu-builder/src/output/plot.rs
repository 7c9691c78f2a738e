//! Line plots as inline SVG: any set of series on linear or logarithmic axes, with legend and
//! annotations; non-finite points break a line, and log axes clamp zeros to their floor. Written
//! here rather than with a plotting crate because plotters 0.3 (measured) draws a NaN point to the
//! axis instead of leaving a gap and labels log axes with raw floats (`9.999999999999999e-6`).

use std::fmt::Write;

/// Distinguishable colours (Tableau 10), cycled.
pub const PALETTE: [&str; 10] =
    ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];
/// Log axes span at most this many decades below the largest value; smaller values and zeros are
/// drawn at the floor.
pub const LOG_AXIS_DECADES: f64 = 12.0;
/// Text and attribute values escaped for XML (HTML and SVG).
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
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
        let pad = if span > 0.0 {
            0.05 * span
        } else if min != 0.0 {
            0.1 * min.abs()
        } else {
            1.0
        };
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
        Stroke::Solid => {
            format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"3\" stroke-opacity=\"0.45\" stroke-linejoin=\"round\"")
        }
        Stroke::Dashed => format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.4\" stroke-dasharray=\"5 3\""),
        Stroke::Line => format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.6\" stroke-linejoin=\"round\""),
        Stroke::Markers => format!("fill=\"{c}\" stroke=\"none\""),
    }
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        s.chars().take(n - 1).chain(std::iter::once('\u{2026}')).collect()
    }
}

/// An SVG line plot: `series` on linear or log axes (decades on log axes, 5-8 nice ticks on linear
/// ones), a grid, axis labels, a title, a legend of the labelled series at the right and
/// `annotations` as circled points with their text. Log axes draw zeros and negatives at the
/// floor; NaN/inf points break the line. Every coordinate written is finite.
pub fn line_plot(spec: &PlotSpec, series: &[Series], annotations: &[Annotation]) -> String {
    let legend: Vec<&Series> = series.iter().filter(|s| s.label.is_some()).collect();
    let frame = Frame::new(spec, legend.len());
    let Frame { left, top, right, bottom, .. } = frame;
    let xs: Vec<f64> = series
        .iter()
        .flat_map(|s| s.x.iter().take(s.y.len()).copied())
        .chain(annotations.iter().map(|a| a.x))
        .collect();
    let ys: Vec<f64> = series
        .iter()
        .flat_map(|s| s.y.iter().take(s.x.len()).copied())
        .chain(annotations.iter().map(|a| a.y))
        .collect();
    let (xlo, xhi) = axis_range(&xs, spec.log_x, spec.x_range);
    let (ylo, yhi) = axis_range(&ys, spec.log_y, spec.y_range);
    let sx = Scale { lo: xlo, hi: xhi, log: spec.log_x, p0: left, p1: right };
    let sy = Scale { lo: ylo, hi: yhi, log: spec.log_y, p0: bottom, p1: top };

    let mut s = String::new();
    write_title(&mut s, spec, &frame);
    // grid and ticks
    write_x_ticks(&mut s, &sx, &frame);
    write_y_ticks(&mut s, &sy, &frame);
    write_box(&mut s, spec, &frame);
    // curves
    for se in series {
        write_curve(&mut s, se, &sx, &sy);
    }
    write_annotations(&mut s, annotations, &sx, &sy, &frame);
    write_legend(&mut s, &legend, &frame);
    s.push_str("</svg>\n");
    s
}

/// Legend rows' height.
const ROW: f64 = 15.0;

/// The picture's size and the plot area's edges in it.
#[derive(Clone, Copy)]
struct Frame {
    width: f64,
    height: f64,
    left: f64,
    top: f64,
    right: f64,
    bottom: f64,
}

impl Frame {
    /// Room for the axes' labels, and for a legend of `legend` rows at the right.
    fn new(spec: &PlotSpec, legend: usize) -> Self {
        let width = if spec.width.is_finite() { spec.width.clamp(200.0, 4000.0) } else { 700.0 };
        let (left, top) = (72.0, 34.0);
        let right = width - if legend == 0 { 24.0 } else { 170.0 };
        let min_height = if spec.height.is_finite() { spec.height.clamp(150.0, 4000.0) } else { 350.0 };
        let height = min_height.max(top + 10.0 + ROW * legend as f64 + 20.0);
        let bottom = height - 48.0;
        Self { width, height, left, top, right, bottom }
    }
}

/// The SVG element, its title and its white background.
fn write_title(s: &mut String, spec: &PlotSpec, frame: &Frame) {
    let Frame { width, height, left, right, .. } = *frame;
    let _ = write!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" viewBox=\"0 0 {width:.0} {height:.0}\" \
font-family=\"sans-serif\" font-size=\"11\" role=\"img\" aria-label=\"{t}\">\n<title>{t}</title>\n\
<rect x=\"0\" y=\"0\" width=\"{width:.0}\" height=\"{height:.0}\" fill=\"white\"/>\n\
<text x=\"{tx:.1}\" y=\"20\" text-anchor=\"middle\" font-size=\"13\" font-weight=\"bold\">{t}</text>\n",
        t = esc(&spec.title),
        tx = (left + right) / 2.0,
    );
}

/// The x axis's ticks and labels, grid lines at the labelled ones.
fn write_x_ticks(s: &mut String, sx: &Scale, frame: &Frame) {
    let Frame { top, bottom, .. } = *frame;
    for (t, label) in axis_ticks(sx.lo, sx.hi, sx.log) {
        let x = sx.at(t);
        let len = if label.is_some() { 5.0 } else { 3.0 };
        if label.is_some() {
            let _ = writeln!(
                s,
                "<line x1=\"{x:.1}\" y1=\"{top:.1}\" x2=\"{x:.1}\" y2=\"{bottom:.1}\" stroke=\"#e4e4e4\"/>"
            );
        }
        let _ = writeln!(
            s,
            "<line x1=\"{x:.1}\" y1=\"{bottom:.1}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#444\"/>",
            bottom + len
        );
        if let Some(l) = label {
            let _ = writeln!(s, "<text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{l}</text>", bottom + 18.0);
        }
    }
}

/// The y axis's ticks and labels, grid lines at the labelled ones.
fn write_y_ticks(s: &mut String, sy: &Scale, frame: &Frame) {
    let Frame { left, right, .. } = *frame;
    for (t, label) in axis_ticks(sy.lo, sy.hi, sy.log) {
        let y = sy.at(t);
        let len = if label.is_some() { 5.0 } else { 3.0 };
        if label.is_some() {
            let _ = writeln!(
                s,
                "<line x1=\"{left:.1}\" y1=\"{y:.1}\" x2=\"{right:.1}\" y2=\"{y:.1}\" stroke=\"#e4e4e4\"/>"
            );
        }
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{left:.1}\" y2=\"{y:.1}\" stroke=\"#444\"/>",
            left - len
        );
        if let Some(l) = label {
            let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{l}</text>", left - 8.0, y + 4.0);
        }
    }
}

/// The plot area's border and the axes' labels.
fn write_box(s: &mut String, spec: &PlotSpec, frame: &Frame) {
    let Frame { height, left, top, right, bottom, .. } = *frame;
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
}

/// One series: a path through its finite points (broken where one is not), dots for markers and
/// for points standing alone.
fn write_curve(s: &mut String, se: &Series, sx: &Scale, sy: &Scale) {
    let pts: Vec<Option<(f64, f64)>> = se.x.iter().zip(&se.y).map(|(&x, &y)| Some((sx.px(x)?, sy.px(y)?))).collect();
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

/// Circled points with their text, on the side of the point towards the plot's middle.
fn write_annotations(s: &mut String, annotations: &[Annotation], sx: &Scale, sy: &Scale, frame: &Frame) {
    let Frame { left, top, right, .. } = *frame;
    for a in annotations {
        let (Some(x), Some(y)) = (sx.px(a.x), sy.px(a.y)) else { continue };
        let _ = writeln!(
            s,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"none\" stroke=\"#c00\" stroke-width=\"1.5\"/>"
        );
        let (tx, anchor) = if x < (left + right) / 2.0 { (x + 8.0, "start") } else { (x - 8.0, "end") };
        let ty = if y - 8.0 < top + 12.0 { y + 16.0 } else { y - 8.0 };
        let _ = writeln!(
            s,
            "<text x=\"{tx:.1}\" y=\"{ty:.1}\" text-anchor=\"{anchor}\" fill=\"#c00\">{}</text>",
            esc(&a.text)
        );
    }
}

/// The labelled series' strokes and labels at the right.
fn write_legend(s: &mut String, legend: &[&Series], frame: &Frame) {
    let Frame { top, right, .. } = *frame;
    for (i, se) in legend.iter().enumerate() {
        let y = top + 10.0 + ROW * i as f64;
        let x = right + 12.0;
        if se.stroke == Stroke::Markers {
            let _ = writeln!(s, "<circle cx=\"{:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{}\"/>", x + 11.0, esc(&se.color));
        } else {
            let _ = writeln!(
                s,
                "<line x1=\"{x:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" {}/>",
                x + 22.0,
                stroke_attrs(&se.color, se.stroke)
            );
        }
        let label = se.label.as_deref().unwrap_or_default();
        let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\">{}</text>", x + 28.0, y + 4.0, esc(&truncate(label, 20)));
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use quick_xml::Reader;
    use quick_xml::events::Event;

    /// Reads the SVG through quick_xml (matching end tags, attributes) and checks that every
    /// numeric attribute and path coordinate is finite. Returns the element count.
    pub(crate) fn check_svg(svg: &str) -> usize {
        let numeric =
            ["x", "y", "x1", "y1", "x2", "y2", "cx", "cy", "r", "width", "height", "dy", "stroke-width", "font-size"];
        let mut reader = Reader::from_str(svg);
        let (mut depth, mut elements) = (0i64, 0usize);
        loop {
            let ev = reader
                .read_event()
                .unwrap_or_else(|e| panic!("SVG is not well-formed at {}: {e}", reader.buffer_position()));
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
                    for tok in val
                        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
                        .filter(|t| t.contains(|c: char| c.is_ascii_digit()))
                    {
                        assert!(tok.parse::<f64>().is_ok_and(f64::is_finite), "{key}: {tok}");
                    }
                }
            }
        }
        assert_eq!(depth, 0, "unbalanced elements");
        elements
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
        for (lo, hi) in [
            (0.0, 2000.0),
            (10.0, 1234.0),
            (0.0, 1.0),
            (0.3, 0.7),
            (-5.0, 5.0),
            (95.0, 105.0),
            (0.0, 3e7),
            (1e-6, 3e-6),
        ] {
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
            Series {
                label: Some("Craig-Bampton".into()),
                x: vec![6.0, 10.0, 20.0, 40.0],
                y: vec![1e-1, 1e-2, 1e-4, 1e-7],
                color: PALETTE[0].into(),
                stroke: Stroke::Dashed,
            },
            Series {
                label: Some("modal \"x\" <y>".into()),
                x: vec![6.0, 12.0],
                y: vec![3e-2, 2e-3],
                color: PALETTE[1].into(),
                stroke: Stroke::Markers,
            },
        ];
        let svg = line_plot(&spec, &series, &[Annotation { x: 40.0, y: 1e-7, text: "chosen".into() }]);
        check_svg(&svg);
        assert!(svg.contains("modal &quot;x&quot; &lt;y&gt;") && svg.contains("chosen"));
    }
}
