//! The double pendulum's cost at equal accuracy: the issue compares the assembly FMU with
//! chain_master per simulated second *at equal or better accuracy*, and the FMU is more accurate
//! than chain_master at the same step, so the fair comparison lets it take a longer one.
//!
//! examples/assemblies/double_pendulum.json is built with `solver.max_step` (and the experiment's
//! step) set to each of `STEPS` and to `REFERENCE_STEP`, each FMU stepped for `SECONDS` at its
//! own step, timed `REPEATS` times (the median counts) with two sets of outputs read after every
//! step: the four positions chain_master's run reads (the elbow's and the tip's x, z), and those
//! with a joint reaction (the main table's loop: a reaction takes the index-1 solve of
//! [`fmu_runtime`]'s outputs, about as much work again as a step). Accuracy: the elbow's and the
//! tip's (x, z) against the run at `REFERENCE_STEP` (a converged solution of the same model: a
//! consistency check of the time integration, not of the physics), after every step of the run
//! (the reference's step divides each), max over the window / the reference's swing per column,
//! worst column. chain_master's trajectory is measured against the same reference by
//! bench/assembly_masters.py (`--reference`).

use crate::fmi::Fmu;
use fmi2::types::{fmi2CoSimulation, fmi2Status};
use std::path::Path;
use std::time::Instant;

/// The converged reference's step [s].
pub const REFERENCE_STEP: f64 = 0.25e-3;
/// The steps timed [s], whole multiples of the reference's.
pub const STEPS: [f64; 4] = [1.0e-3, 1.5e-3, 1.75e-3, 2.0e-3];
/// Simulated time [s]: chain_master's window.
pub const SECONDS: f64 = 1.0;
/// Timed runs per step and set of outputs, of which the median counts (a run is 10 to 40 ms:
/// one alone varies by a fifth on a busy machine).
pub const REPEATS: usize = 5;

/// The elbow and the tip (x, z) after every step, from t = 0.
pub type Positions = Vec<[f64; 4]>;

pub struct StepRow {
    pub step: f64,
    /// the loop's wall time with the positions read / simulated time [s/s]
    pub positions_per_second: f64,
    /// the same with the positions and a joint reaction read
    pub per_simulated_second: f64,
    pub error: f64,
}

/// The double pendulum built with solver steps of `h`, in `work`.
fn build(h: f64, work: &Path) -> Result<std::path::PathBuf, String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/assemblies");
    let source = dir.join("double_pendulum.json");
    let text = std::fs::read_to_string(&source).map_err(|e| format!("{}: {e}", source.display()))?;
    let mut doc: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", source.display()))?;
    doc["assembly"]["solver"] = serde_json::json!({ "max_step": h });
    doc["experiment"]["step_size"] = serde_json::json!(h);
    let input = work.join(format!("double_pendulum_{:.0}us.json", h * 1e6));
    let output = input.with_extension("fmu");
    // the bodies' paths are relative to the example's folder: the input stays beside it in name
    let text = serde_json::to_string(&doc).map_err(|e| e.to_string())?;
    let spec = fmu_builder::input::assembly::AssemblySpec::from_str(&source, &text)
        .map_err(|e| format!("{} with max_step {h}: {e}", source.display()))?;
    fmu_builder::pipeline::assembly::build_assembly(spec, &output, &[])
        .map_err(|e| format!("building {} with max_step {h}: {e}", source.display()))?;
    Ok(output)
}

/// Step the FMU at `h` for SECONDS with `outputs` read after every step (the first four: the
/// positions); the loop's wall time and the positions after every step.
fn run(fmu: &Fmu, h: f64, outputs: &[&str]) -> Result<(f64, Positions), String> {
    let vrs = fmu.description.vrs(outputs);
    let api = &fmu.api;
    let inst = fmu.instantiate(fmi2CoSimulation, "assembly-step-sweep")?;
    inst.initialize()?;
    let steps = (SECONDS / h).round() as usize;
    let mut out = vec![0.0; vrs.len()];
    inst.get(&vrs, &mut out)?;
    let mut positions = Vec::with_capacity(steps + 1);
    positions.push([out[0], out[1], out[2], out[3]]);
    let mut bad = 0;
    let start = Instant::now();
    for k in 1..=steps {
        let t = (k - 1) as f64 * h;
        unsafe {
            bad += ((api.do_step)(inst.c, t, h, 1) != fmi2Status::fmi2OK) as usize;
            bad += ((api.get_real)(inst.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) != fmi2Status::fmi2OK) as usize;
        }
        positions.push([out[0], out[1], out[2], out[3]]);
    }
    let wall = start.elapsed().as_secs_f64();
    if bad > 0 {
        return Err(format!("{bad} FMI calls failed at h = {h}"));
    }
    Ok((wall, positions))
}

/// The median wall time of REPEATS runs with `outputs`, and the positions (the same in every
/// run: the FMU is deterministic).
fn timed(fmu: &Fmu, h: f64, outputs: &[&str]) -> Result<(f64, Positions), String> {
    let mut walls = Vec::with_capacity(REPEATS);
    let mut positions = Vec::new();
    for _ in 0..REPEATS {
        let (wall, p) = run(fmu, h, outputs)?;
        walls.push(wall);
        positions = p;
    }
    walls.sort_by(f64::total_cmp);
    Ok((walls[REPEATS / 2], positions))
}

/// max |a - reference| at a's times (every `every`-th of the reference's) / the reference's
/// swing, worst column.
pub fn error(a: &Positions, reference: &Positions, every: usize) -> f64 {
    (0..4)
        .map(|c| {
            let (lo, hi) =
                reference.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| (l.min(r[c]), h.max(r[c])));
            let at = reference.iter().step_by(every);
            let worst = a.iter().zip(at).fold(0.0f64, |m, (x, r)| m.max((x[c] - r[c]).abs()));
            worst / (hi - lo)
        })
        .fold(0.0, f64::max)
}

/// The reference's positions (written to `csv` for the masters' script: t, elbow x, z, tip x, z
/// after every reference step) and one row per step of `STEPS`.
pub fn sweep(work: &Path, outputs: &[&str], csv: &Path) -> Result<Vec<StepRow>, String> {
    let open = |path: &Path| Fmu::open(path, &path.with_extension(""));
    let reference_fmu = open(&build(REFERENCE_STEP, work)?)?;
    let (_, reference) = run(&reference_fmu, REFERENCE_STEP, outputs)?;
    let text: String = reference
        .iter()
        .enumerate()
        .map(|(k, r)| {
            format!("{:.6},{:.17e},{:.17e},{:.17e},{:.17e}\n", k as f64 * REFERENCE_STEP, r[0], r[1], r[2], r[3])
        })
        .collect();
    std::fs::write(csv, text).map_err(|e| format!("{}: {e}", csv.display()))?;
    STEPS
        .iter()
        .map(|&h| {
            let fmu = open(&build(h, work)?)?;
            let (wall, positions) = timed(&fmu, h, outputs)?;
            let (positions_wall, _) = timed(&fmu, h, &outputs[..4])?;
            eprintln!(
                "step sweep: h = {} ms, {:.1} ms per simulated second ({:.1} with the positions alone)",
                h * 1e3,
                wall / SECONDS * 1e3,
                positions_wall / SECONDS * 1e3
            );
            let every = (h / REFERENCE_STEP).round() as usize;
            Ok(StepRow {
                step: h,
                positions_per_second: positions_wall / SECONDS,
                per_simulated_second: wall / SECONDS,
                error: error(&positions, &reference, every),
            })
        })
        .collect()
}
