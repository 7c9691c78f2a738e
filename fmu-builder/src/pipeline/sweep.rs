//! Speed against error: the same body reduced by each method at growing orders, each reduced
//! model's flange transfer-function error over the band (against the full model), its cost per
//! co-simulation step (the runtime stepped in process), and its build time, side by side in one
//! run so the ratios mean something on a noisy machine.

use super::{Built, reduce_spec};
use crate::error::Result;
use crate::input::spec::{Method, Reduction, Scene, Spec};
use fmu_runtime::body::FlexibleBody;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

#[derive(Debug, Clone)]
pub struct SweepRow {
    pub method: &'static str,
    pub setting: String,
    pub order: usize,
    pub frf_error: f64,
    /// Mean wall time of one fmi2DoStep-equivalent (FlexibleBody::step, h = 1 ms) [ns], mount fixed.
    pub step_ns: f64,
    /// Same with the mount spinning at 10 rad/s (rotating-frame terms active); None without them.
    pub step_ns_rotating: Option<f64>,
    pub build_s: f64,
}

/// Nanoseconds per step of the reduced body with a tip load, mount fixed or spinning.
pub fn step_cost(built: &Built, spin: f64) -> f64 {
    let mut body = FlexibleBody::new(Arc::new(built.reduced.clone()));
    if !built.reduced.flanges.is_empty() {
        body.load_mut(0).f = [0.0, 0.0, 1.0];
    }
    body.mount_mut().w = [0.0, 0.0, spin];
    let h = 1e-3;
    for _ in 0..200 {
        let _ = body.step(h);
    }
    // enough steps for ~50 ms of work, at least 2000
    let probe = Instant::now();
    for _ in 0..200 {
        let _ = body.step(h);
    }
    let per = probe.elapsed().as_secs_f64() / 200.0;
    let n = ((0.05 / per.max(1e-9)) as usize).clamp(2000, 2_000_000);
    let start = Instant::now();
    for _ in 0..n {
        let _ = body.step(h);
    }
    start.elapsed().as_secs_f64() * 1e9 / n as f64
}

fn variant(spec: &Spec, reduction: Reduction, band: [f64; 2]) -> Spec {
    let mut s = spec.clone();
    s.reduction = reduction;
    let mut scene = s.scene.clone().unwrap_or(Scene { loads: Vec::new(), ..Scene::default() });
    scene.band = Some(band);
    scene.tolerance = None;
    s.scene = Some(scene);
    s
}

pub fn sweep(spec: &Spec, file: &Path, on_row: &mut dyn FnMut(&SweepRow)) -> Result<Vec<SweepRow>> {
    // the band: the scene's, or 0 to the tenth eigenfrequency of the mounted body
    let band = match spec.scene.as_ref().and_then(|s| s.band) {
        Some(b) => b,
        None => {
            let probe = reduce_spec(variant(spec, cb(10), [0.0, 1.0]), file)?;
            let f = &probe.report.accuracy.full_hz;
            [0.0, f.get(9).or(f.last()).copied().unwrap_or(1.0)]
        }
    };
    let rotating = with_rotation(spec, band);
    let mut rows = Vec::new();
    for (method, setting, reduction) in runs(spec, band) {
        let base = if setting.ends_with("rotation declared") { &rotating } else { spec };
        let mut v = variant(base, reduction, band);
        if let Some(sc) = v.scene.as_mut() {
            sc.loads = base.scene.as_ref().map(|s| s.loads.clone()).unwrap_or_default();
        }
        let start = Instant::now();
        let built = match reduce_spec(v, file) {
            Ok(b) => b,
            Err(_) => continue, // e.g. more modes than the mesh has
        };
        let build_s = start.elapsed().as_secs_f64();
        let frf_error = built.report.accuracy.frequency_response.as_ref().map_or(f64::NAN, |f| f.max_relative_error);
        let step_ns = step_cost(&built, 0.0);
        let step_ns_rotating = built.reduced.rotation.is_some().then(|| step_cost(&built, 10.0));
        let row =
            SweepRow { method, setting, order: built.reduced.n_modes(), frf_error, step_ns, step_ns_rotating, build_s };
        on_row(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// The reductions compared: each method at growing orders, and Craig-Bampton with rotation
/// declared (what modelling rotation costs per step).
fn runs(spec: &Spec, band: [f64; 2]) -> Vec<(&'static str, String, Reduction)> {
    let points = spec.reduction.expansion_points.clone().unwrap_or_else(|| vec![0.5 * band[1], band[1]]);
    let mut runs: Vec<(&'static str, String, Reduction)> = Vec::new();
    for m in [2, 4, 8, 16, 32, 64] {
        runs.push(("craig_bampton", format!("{m} modes"), cb(m)));
    }
    for m in [2, 4, 8, 16, 32] {
        runs.push(("modal", format!("{m} modes"), Reduction { method: Method::Modal, ..cb(m) }));
    }
    for k in 1..=4 {
        runs.push((
            "krylov",
            format!("{k} moments at {points:?} Hz"),
            Reduction {
                method: Method::Krylov,
                modes: None,
                max_frequency: None,
                expansion_points: Some(points.clone()),
                moments: Some(k),
                real_expansion_points: spec.reduction.real_expansion_points.clone(),
                dynamic_cutoff: spec.reduction.dynamic_cutoff,
                // the sweep compares methods in process
                backend: Default::default(),
            },
        ));
    }
    runs.push(("craig_bampton", "16 modes, rotation declared".to_string(), cb(16)));
    runs
}

/// The same body with rotation declared in the scene.
fn with_rotation(spec: &Spec, band: [f64; 2]) -> Spec {
    let mut rotating = spec.clone();
    let mut scene = rotating.scene.clone().unwrap_or_default();
    if !scene.loads.contains(&crate::input::spec::SceneLoad::Rotation) {
        scene.loads.push(crate::input::spec::SceneLoad::Rotation);
    }
    scene.band = Some(band);
    scene.tolerance = None;
    rotating.scene = Some(scene);
    rotating
}

fn cb(modes: usize) -> Reduction {
    Reduction {
        method: Method::CraigBampton,
        modes: Some(modes),
        max_frequency: None,
        expansion_points: None,
        moments: None,
        real_expansion_points: None,
        dynamic_cutoff: None,
        backend: Default::default(),
    }
}

/// The table as printed and put in the README.
pub fn table(rows: &[SweepRow], band: Option<[f64; 2]>) -> String {
    let mut s = table_header(band);
    for r in rows {
        s.push_str(&table_row(r));
    }
    s
}

/// The table's head: what is compared, and the column names.
pub fn table_header(band: Option<[f64; 2]>) -> String {
    let mut s = String::new();
    if let Some(b) = band {
        s.push_str(&format!(
            "flange transfer-function error over {:.4}..{:.4} Hz; step cost: h = 1 ms, in process\n",
            b[0], b[1]
        ));
    }
    s.push_str("| method | setting | order | FRF error in band | ns/step (fixed mount) | ns/step (spinning 10 rad/s) | build [s] |\n");
    s.push_str("|---|---|---:|---:|---:|---:|---:|\n");
    s
}

/// One line of the table.
pub fn table_row(r: &SweepRow) -> String {
    let rot = r.step_ns_rotating.map_or("-".to_string(), |v| format!("{v:.0}"));
    format!(
        "| {} | {} | {} | {:.2e} | {:.0} | {} | {:.2} |\n",
        r.method, r.setting, r.order, r.frf_error, r.step_ns, rot, r.build_s
    )
}

/// Error in band against cost per step, one line per method (log-log), as a standalone SVG.
pub fn plot(rows: &[SweepRow]) -> String {
    use crate::output::plot::{Annotation, PALETTE, PlotSpec, Series, Stroke, line_plot};
    let mut spec = PlotSpec::new(
        "Speed against error",
        "cost per step [ns] (fixed mount, h = 1 ms)",
        "flange FRF error in band",
        true,
    );
    spec.log_x = true;
    let mut series = Vec::new();
    let mut labels = Vec::new();
    for (i, method) in ["craig_bampton", "modal", "krylov"].iter().enumerate() {
        let pts: Vec<&SweepRow> =
            rows.iter().filter(|r| r.method == *method && !r.setting.ends_with("declared")).collect();
        if pts.is_empty() {
            continue;
        }
        let (x, y): (Vec<f64>, Vec<f64>) = pts.iter().map(|r| (r.step_ns, r.frf_error)).unzip();
        let color = PALETTE[i % PALETTE.len()].to_string();
        series.push(Series {
            label: Some(method.replace('_', "-")),
            x: x.clone(),
            y: y.clone(),
            color: color.clone(),
            stroke: Stroke::Line,
        });
        // each run a marker, labelled with its order
        series.push(Series { label: None, x, y, color, stroke: Stroke::Markers });
        labels.extend(pts.iter().map(|r| Annotation { x: r.step_ns, y: r.frf_error, text: format!("r={}", r.order) }));
    }
    let svg = line_plot(&spec, &series, &labels);
    format!("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n{svg}\n")
}
