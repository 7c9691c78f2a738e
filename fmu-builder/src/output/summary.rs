//! The short terminal summary printed after a build.

use crate::output::numbers::fixed;
use crate::output::report::Report;
use crate::output::verdict;
use std::fmt::Write;

/// A point or vector [m] as "(x, y, z)", six places each.
fn point(p: [f64; 3]) -> String {
    format!("({}, {}, {})", fixed(p[0], 6), fixed(p[1], 6), fixed(p[2], 6))
}

pub fn text(r: &Report) -> String {
    let mut s = String::new();
    body(&mut s, r);
    scene(&mut s, r);
    accuracy(&mut s, r);
    if !r.stress_points.is_empty() {
        let hot = r.stress_points.iter().filter(|p| p.description.contains("hot spot")).count();
        let _ = writeln!(
            s,
            "  stress outputs at {} points ({hot} hot spots): <point>.sxx .. .szx, .mises [Pa], listed in the documentation",
            r.stress_points.len()
        );
        for p in r.stress_points.iter().filter(|p| p.description.contains("hot spot")) {
            let _ = writeln!(s, "    {}: {}", p.name, p.description);
        }
    }
    if let (Some(band), Some(frf)) = (verdict::band_sentence(&r.verdict), &r.accuracy.frequency_response) {
        let _ = writeln!(s, "  {band}; {} frequencies", frf.frequencies_hz.len());
    }
    let _ = writeln!(s, "  verdict: {}", verdict::sentence(&r.verdict));
    s
}

/// The model, its mass, flanges, reduction and back-end.
fn body(s: &mut String, r: &Report) {
    let _ = writeln!(
        s,
        "{}: {} mesh, {} nodes, {} elements, {} DoFs after flange coupling",
        r.model_name, r.element, r.nodes, r.elements, r.dofs_constrained
    );
    // a free body's frame is not a mount: say what holds it (or that nothing does)
    let frame = if r.scene.body.starts_with("mounted") {
        "from the mount".to_string()
    } else {
        format!("at the body frame's origin: {}", r.scene.body)
    };
    let _ = writeln!(s, "  mass {:.6e} kg, centre of mass {} m {frame}", r.mass, point(r.center_of_mass));
    for f in &r.flanges {
        let _ = writeln!(
            s,
            "  flange {:<12} {:<6} at {} m, {} slave nodes, {}",
            f.name,
            f.role,
            point(f.reference_point),
            f.slave_nodes,
            f.coupling
        );
    }
    let _ = writeln!(
        s,
        "  {}: {} normal modes + {} static/Krylov shapes = order {}",
        r.method, r.fixed_interface_modes, r.constraint_modes, r.order
    );
    if r.fixed_interface_modes == 0 && !r.method.to_lowercase().contains("krylov") {
        // without a normal mode the basis holds static shapes only: say what that model answers
        let _ = writeln!(
            s,
            "  static-only model (no normal modes, static shapes only): exact for static flange loads, with no resonance \
             of its own; valid well below the body's lowest mode only (request modes for its dynamics)"
        );
    }
    if r.backend.kind == "petsc" {
        let b = &r.backend;
        let rows: Vec<String> = b.rows_per_rank.iter().map(usize::to_string).collect();
        let peaks: Vec<String> = b.peak_mib_per_rank.iter().map(|p| format!("{p:.0}")).collect();
        let _ = writeln!(
            s,
            "  back-end: PETSc/MUMPS on {} MPI ranks, rows {}, factor {:.3e} entries in all, peak {} MiB per rank",
            b.ranks,
            rows.join(" / "),
            b.factor_entries,
            peaks.join(" / ")
        );
    }
}

/// What the scene includes and what the FMU refuses.
fn scene(s: &mut String, r: &Report) {
    let yes = |b: bool| if b { "yes" } else { "no" };
    let sc = &r.scene;
    let _ = writeln!(
        s,
        "  scene: rotation terms {}, gravity shapes {}, acceleration shapes {}, geometric stiffening {}",
        yes(sc.rotation),
        yes(sc.gravity),
        yes(sc.acceleration),
        yes(sc.geometric_stiffening)
    );
    for refusal in &sc.refuses {
        let _ = writeln!(s, "  the FMU refuses {refusal}");
    }
    for sentence in crate::output::model_exchange::sentences(r) {
        let _ = writeln!(s, "  {sentence}");
    }
}

/// The lowest frequencies and how far up the spectrum, and in statics, the reduction is exact.
fn accuracy(s: &mut String, r: &Report) {
    let a = &r.accuracy;
    let shown = a.reduced_hz.len().min(8);
    let freqs: Vec<String> = a.reduced_hz[..shown].iter().map(|f| format!("{f:.4}")).collect();
    let _ = writeln!(
        s,
        "  lowest frequencies [Hz]: {}{}",
        freqs.join(", "),
        if a.reduced_hz.len() > shown { ", ..." } else { "" }
    );
    // how far up the spectrum the reduced model is good to a given accuracy
    let good_up_to = |tol: f64| -> Option<(usize, f64)> {
        let n = a.relative_error.iter().take_while(|e| e.abs() <= tol).count();
        (n > 0).then(|| (n, a.full_hz[n - 1]))
    };
    for tol in [1e-5, 1e-3] {
        match good_up_to(tol) {
            Some((n, f)) => {
                let _ = writeln!(s, "  vs full FE: the lowest {n} frequencies (to {f:.4} Hz) within {tol:.0e}");
            }
            None => {
                let off = a.relative_error.first().map_or(String::new(), |e| format!(" ({:.1e})", e.abs()));
                let _ = writeln!(s, "  vs full FE: even the lowest frequency is off by more than {tol:.0e}{off}");
            }
        }
    }
    let beyond = a.pairs.iter().filter(|p| p.full.is_none()).count();
    if beyond > 0 {
        let _ = writeln!(
            s,
            "  {beyond} reduced modes resemble no full mode (MAC < {}): constraint or residual-flexibility modes, beyond \
             the frequencies the model represents",
            crate::reduce::accuracy::MAC_PAIRED
        );
    }
    let _ = writeln!(s, "  vs full FE: static flange compliance within {:.1e}", a.compliance_max_relative_error);
}

/// What an assembly's build printed: its bodies, joints and the FMU's variables.
pub fn assembly_text(d: &fmu_runtime::assembly::description::AssemblyDescription, (stop, step): (f64, f64)) -> String {
    use fmu_runtime::assembly::description::BodyModel;
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "assembly {}: {} bodies, {} joints", d.model_name, d.bodies.len(), d.joints.len());
    for body in &d.bodies {
        match &body.model {
            BodyModel::Flexible(r) => {
                let _ = writeln!(s, "  body {}: flexible, {:.4} kg, {} modes", body.name, r.mass, r.n_modes());
            }
            BodyModel::Rigid { mass, .. } => {
                let _ = writeln!(s, "  body {}: rigid, {mass:.4} kg", body.name);
            }
        }
    }
    for j in &d.joints {
        let _ = writeln!(s, "  joint {}: {}{}", j.name, j.kind.name(), if j.drive.is_some() { ", driven" } else { "" });
    }
    let _ = writeln!(
        s,
        "Co-Simulation: generalised-alpha (spectral radius {}), steps of at most {} s; DefaultExperiment stop {} s, step {} s",
        d.solver.spectral_radius, d.solver.max_step, stop, step
    );
    s
}
