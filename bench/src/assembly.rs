//! Assembly FMUs (several bodies and joints solved inside one FMU by generalised alpha with
//! Newton): examples/assemblies/double_pendulum.json and two_link_weld.json, built by the
//! builder library as `fmu-builder` builds them, each FMU's binary dlopen'ed and stepped through
//! the FMI 2.0 C API at h = 1 ms from its start, N steps (`STEPS`, `--short`: `SHORT_STEPS`),
//! every fmi2DoStep timed on its own: p50, p99 and max per step and the loop's wall time per
//! simulated second; then a fresh instance the same way with what a user reads after each step
//! (fmi2GetReal of four positions and one joint reaction: the reaction makes the FMU solve its
//! index-1 system at the communication point), timed step and read apart. Every call's time is
//! written to `<case>_step_times.csv` in the work folder (`--keep DIR` keeps it).
//!
//! Heap allocations per step (a target, 0): the same FMU through the runtime's C functions
//! linked into this binary (`Fmu::open_in_process`, as for the bodies), stepped with the same
//! reads, counted by the bench's global allocator.
//!
//! Against the repository's other ways of running the double pendulum (bench/assembly_masters.py,
//! run by the tests' Python when found, else skipped with a message): examples/chain/chain_master.py,
//! the Python master that co-simulates two separate body FMUs of examples/chain/link.json (built
//! here too, by the same builder) and iterates on the joints; and Exudyn's flexible double
//! pendulum of the same mesh (tests/exudyn_reference.py). The issue asks the assembly FMU to be
//! at least `CHAIN_MASTER_RATIO` times faster per simulated second than chain_master at equal or
//! better accuracy (both against the rigid double pendulum): the ratio is printed and reported,
//! not checked (the step is being optimised).

use crate::assembly_steps::{self, StepRow};
use crate::fmi::Fmu;
use crate::{H, Target, ns};
use fmi2::types::{fmi2CoSimulation, fmi2Status};
use std::path::{Path, PathBuf};
use std::time::Instant;
use test_support::alloc;

/// Steps timed per case (full run) and in `--short`.
pub const STEPS: usize = 5000;
pub const SHORT_STEPS: usize = 1000;
/// Steps counted for heap allocations (after the first).
const COUNTED_STEPS: usize = 1000;
/// chain_master's and Exudyn's simulated time [s] (full run; `--short`: half a second each).
const CHAIN_SECONDS: f64 = 1.0;
const EXUDYN_SECONDS: f64 = 2.0;
const SHORT_SECONDS: f64 = 0.5;
/// The figure: the assembly FMU / chain_master per simulated second. Reported only.
const CHAIN_MASTER_RATIO: f64 = 100.0;

/// One example assembly and what a user reads from it after each step.
struct Case {
    /// examples/assemblies/<file>.json
    file: &'static str,
    /// four positions (world) and one joint reaction
    outputs: [&'static str; 5],
    what: &'static str,
}

const CASES: [Case; 2] = [
    Case {
        file: "double_pendulum",
        outputs: ["upper.tip.r[1]", "upper.tip.r[3]", "lower.tip.r[1]", "lower.tip.r[3]", "pivot.f[3]"],
        what: "two 1 m flexible links on revolute joints, released at 45 degrees under gravity",
    },
    Case {
        file: "two_link_weld",
        outputs: ["upper.tip.r[2]", "upper.tip.r[3]", "lower.tip.r[2]", "lower.tip.r[3]", "clamp.t[2]"],
        what: "two 1 m flexible links welded end to end, clamped, from rest under gravity",
    },
];

/// Per-call times [ns] of one loop, in call order and sorted, and the loop's wall time [s].
struct Timed {
    in_order: Vec<f64>,
    sorted: Vec<f64>,
    wall_s: f64,
}

/// A step slower than this many times the median counts as slow (the tail's size).
const SLOW: f64 = 4.0;

impl Timed {
    fn new(in_order: Vec<f64>, wall_s: f64) -> Self {
        let mut sorted = in_order.clone();
        sorted.sort_by(f64::total_cmp);
        Self { in_order, sorted, wall_s }
    }
    fn quantile(&self, q: f64) -> f64 {
        let n = self.sorted.len();
        self.sorted[((q * n as f64).ceil() as usize).clamp(1, n) - 1]
    }
    fn mean(&self) -> f64 {
        self.sorted.iter().sum::<f64>() / self.sorted.len() as f64
    }
    /// Calls slower than SLOW times the median.
    fn slow(&self) -> usize {
        let limit = SLOW * self.quantile(0.5);
        self.sorted.iter().filter(|&&x| x > limit).count()
    }
    /// p50 | p99 | max | mean [us] | slow calls
    fn cells(&self) -> String {
        let us = |x: f64| format!("{:.1}", x * 1e-3);
        format!(
            "{} | {} | {} | {} | {}",
            us(self.quantile(0.5)),
            us(self.quantile(0.99)),
            us(self.sorted[self.sorted.len() - 1]),
            us(self.mean()),
            self.slow()
        )
    }
}

struct Row {
    name: String,
    what: &'static str,
    build_s: f64,
    steps: usize,
    /// fmi2DoStep alone
    step: Timed,
    /// fmi2DoStep + fmi2GetReal of the outputs, per step (and the loop's wall time)
    step_and_read: Timed,
    /// the fmi2GetReal alone, from the same loop
    read: Timed,
    outputs: [&'static str; 5],
    allocations: usize,
    /// t, the four positions, every step from t = 0 (from the loop with reads)
    positions: Vec<[f64; 5]>,
}

/// examples/ of this workspace.
fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

fn build(case: &Case, work: &Path) -> Result<(PathBuf, f64), String> {
    let input = examples().join("assemblies").join(format!("{}.json", case.file));
    let output = work.join(format!("{}.fmu", case.file));
    let start = Instant::now();
    let text = std::fs::read_to_string(&input).map_err(|e| format!("{}: {e}", input.display()))?;
    let spec = fmu_builder::input::assembly::AssemblySpec::from_str(&input, &text)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    fmu_builder::pipeline::assembly::build_assembly(spec, &output, &[])
        .map_err(|e| format!("building {}: {e}", input.display()))?;
    Ok((output, start.elapsed().as_secs_f64()))
}

fn bench_case(case: &Case, work: &Path, steps: usize) -> Result<Row, String> {
    let (fmu_path, build_s) = build(case, work)?;
    eprintln!("built {} in {build_s:.1} s", fmu_path.display());
    let dir = work.join(case.file);
    let fmu = Fmu::open(&fmu_path, &dir)?;
    let vrs = fmu.description.vrs(&case.outputs);
    let api = &fmu.api;

    // fmi2DoStep alone, every call timed
    let step = {
        let inst = fmu.instantiate(fmi2CoSimulation, "assembly-steps")?;
        inst.initialize()?;
        let mut per_call = Vec::with_capacity(steps);
        let mut bad = 0;
        let mut t = 0.0;
        let loop_start = Instant::now();
        for _ in 0..steps {
            let start = Instant::now();
            bad += (unsafe { (api.do_step)(inst.c, t, H, 1) } != fmi2Status::fmi2OK) as usize;
            per_call.push(start.elapsed().as_nanos() as f64);
            t += H;
        }
        let wall_s = loop_start.elapsed().as_secs_f64();
        if bad > 0 {
            return Err(format!("{}: {bad} of {steps} fmi2DoStep calls failed", case.file));
        }
        Timed::new(per_call, wall_s)
    };

    // a fresh instance: step, then read the outputs, both timed
    let (step_and_read, read, positions) = {
        let inst = fmu.instantiate(fmi2CoSimulation, "assembly-reads")?;
        inst.initialize()?;
        let mut out = [0.0; 5];
        inst.get(&vrs, &mut out)?;
        let mut positions = Vec::with_capacity(steps + 1);
        positions.push([0.0, out[0], out[1], out[2], out[3]]);
        let (mut both, mut reads) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
        let mut bad = 0;
        let mut t = 0.0;
        let loop_start = Instant::now();
        for _ in 0..steps {
            let start = Instant::now();
            bad += (unsafe { (api.do_step)(inst.c, t, H, 1) } != fmi2Status::fmi2OK) as usize;
            let stepped = Instant::now();
            bad += (unsafe { (api.get_real)(inst.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) } != fmi2Status::fmi2OK)
                as usize;
            let end = Instant::now();
            both.push((end - start).as_nanos() as f64);
            reads.push((end - stepped).as_nanos() as f64);
            t += H;
            positions.push([t, out[0], out[1], out[2], out[3]]);
        }
        let wall_s = loop_start.elapsed().as_secs_f64();
        if bad > 0 {
            return Err(format!("{}: {bad} FMI calls failed in the loop with outputs", case.file));
        }
        if !out.iter().all(|v| v.is_finite()) {
            return Err(format!("{}: outputs not finite after {steps} steps: {out:?}", case.file));
        }
        (Timed::new(both, wall_s), Timed::new(reads, wall_s), positions)
    };
    // every call's time, for a look at the tail (kept with --keep)
    let times = work.join(format!("{}_step_times.csv", case.file));
    let mut text = String::from("step,do_step_ns,do_step_and_read_ns,read_ns\n");
    for k in 0..steps {
        text += &format!("{},{},{},{}\n", k + 1, step.in_order[k], step_and_read.in_order[k], read.in_order[k]);
    }
    std::fs::write(&times, text).map_err(|e| format!("{}: {e}", times.display()))?;
    let allocations = count_allocations(&dir, &vrs)?;
    eprintln!(
        "timed {}: fmi2DoStep p50 {:.1} us, with outputs {:.1} us, {allocations} allocations in {COUNTED_STEPS} steps",
        case.file,
        step.quantile(0.5) * 1e-3,
        step_and_read.quantile(0.5) * 1e-3
    );
    Ok(Row {
        name: case.file.to_string(),
        what: case.what,
        build_s,
        steps,
        step,
        step_and_read,
        read,
        outputs: case.outputs,
        allocations,
        positions,
    })
}

/// Heap allocations in COUNTED_STEPS steps with the outputs read, after a first step, through
/// the runtime's C functions linked into this binary driving the unzipped FMU in `dir`.
fn count_allocations(dir: &Path, vrs: &[u32]) -> Result<usize, String> {
    let fmu = Fmu::open_in_process(dir)?;
    let api = &fmu.api;
    let before = alloc::total();
    let inst = fmu.instantiate(fmi2CoSimulation, "assembly-count")?;
    inst.initialize()?;
    if alloc::total() == before {
        return Err("the allocation counter saw no allocation in the assembly's fmi2Instantiate".into());
    }
    let mut out = [0.0; 5];
    let mut t = 0.0;
    let mut bad = (inst.do_step(t, H) != fmi2Status::fmi2OK) as usize;
    bad +=
        (unsafe { (api.get_real)(inst.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) } != fmi2Status::fmi2OK) as usize;
    t += H;
    let before = alloc::total();
    for _ in 0..COUNTED_STEPS {
        unsafe {
            bad += ((api.do_step)(inst.c, t, H, 1) != fmi2Status::fmi2OK) as usize;
            bad += ((api.get_real)(inst.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) != fmi2Status::fmi2OK) as usize;
        }
        t += H;
    }
    let n = alloc::total() - before;
    if bad > 0 {
        return Err(format!("{bad} FMI calls failed while counting the assembly's allocations"));
    }
    Ok(n)
}

/// The Python the masters run under: `--python`, else the tests' virtual environment.
fn python(given: Option<&Path>) -> Option<PathBuf> {
    match given {
        Some(p) => Some(p.to_path_buf()),
        None => {
            let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/.venv/bin/python");
            venv.exists().then_some(venv)
        }
    }
}

/// chain_master's and Exudyn's double pendulum (bench/assembly_masters.py), with the assembly's
/// own trajectory for the accuracy comparison. None (and a message) without the tests' Python.
fn masters(
    work: &Path,
    python: Option<&Path>,
    pendulum: &Row,
    short: bool,
    reference: Option<&Path>,
) -> Result<Option<serde_json::Value>, String> {
    let Some(python) = self::python(python) else {
        println!(
            "(chain_master and Exudyn skipped: no tests/.venv/bin/python in this workspace; make it with `bash tests/run.sh --setup-only` or pass `--python PATH`.)\n"
        );
        return Ok(None);
    };
    // the link's body FMU (chain_master's bodies) and its CalculiX deck (Exudyn's mesh)
    let link = work.join("Link.fmu");
    let deck = work.join("link.inp");
    let job = fmu_builder::job::Job {
        input: examples().join("chain/link.json"),
        output: Some(link.clone()),
        force: true,
        exports: fmu_builder::job::Exports { inp: Some(deck.clone()), ..Default::default() },
        quiet: true,
        ..Default::default()
    };
    fmu_builder::job::run(&job).map_err(|e| format!("building examples/chain/link.json: {e}"))?;
    let csv = work.join("double_pendulum_positions.csv");
    let text: String = pendulum
        .positions
        .iter()
        .map(|r| format!("{:.6},{:.17e},{:.17e},{:.17e},{:.17e}\n", r[0], r[1], r[2], r[3], r[4]))
        .collect();
    std::fs::write(&csv, text).map_err(|e| format!("{}: {e}", csv.display()))?;
    let (chain_s, exudyn_s) = if short { (SHORT_SECONDS, SHORT_SECONDS) } else { (CHAIN_SECONDS, EXUDYN_SECONDS) };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("assembly_masters.py");
    eprintln!("running {} under {} ...", script.display(), python.display());
    let output = std::process::Command::new(&python)
        .arg(&script)
        .arg("--link")
        .arg(&link)
        .args(["--seconds", &chain_s.to_string()])
        .arg("--deck")
        .arg(&deck)
        .args(["--exudyn-seconds", &exudyn_s.to_string()])
        .arg("--assembly")
        .arg(&csv)
        .args(reference.iter().flat_map(|r| [std::ffi::OsStr::new("--reference"), r.as_os_str()]))
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !output.status.success() {
        println!(
            "(chain_master and Exudyn: {} {} failed ({}); skipped.)\n",
            python.display(),
            script.display(),
            output.status
        );
        return Ok(None);
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout.lines().last().unwrap_or("");
    serde_json::from_str(line).map(Some).map_err(|e| format!("{}: its output {line:?}: {e}", script.display()))
}

fn max_of(v: &serde_json::Value) -> f64 {
    v.as_array().map_or(f64::NAN, |a| a.iter().filter_map(|x| x.as_f64()).fold(f64::NEG_INFINITY, f64::max))
}

/// The assembly section: tables printed, the allocation target returned.
pub fn run(work: &Path, short: bool, python: Option<&Path>) -> Result<Vec<Target>, String> {
    let steps = if short { SHORT_STEPS } else { STEPS };
    let rows: Vec<Row> = CASES.iter().map(|c| bench_case(c, work, steps)).collect::<Result<_, _>>()?;

    println!("## Assemblies: per step through the C API (h = {} ms, {steps} steps from t = 0)\n", H * 1e3);
    println!(
        "Each example of examples/assemblies built by the builder library, its binary dlopen'ed; every fmi2DoStep timed on its own (Instant around the call), in a first instance; then a fresh instance from t = 0 again, each step followed by fmi2GetReal of the outputs a user reads (four positions and one joint reaction: the reaction makes the FMU solve its index-1 system at the communication point), step and read timed apart. Per simulated second: the loop's wall time / {} s. Heap allocations: {COUNTED_STEPS} steps with the reads, through the runtime's C functions linked into this binary (`Fmu::open_in_process`), counted by the bench's allocator.\n",
        steps as f64 * H
    );
    println!(
        "| assembly | calls per step | p50 [us] | p99 [us] | max [us] | mean [us] | calls > {SLOW} x p50 | ms per simulated second | allocations |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        println!(
            "| {} | fmi2DoStep | {} | {:.1} | - |",
            r.name,
            r.step.cells(),
            r.step.wall_s / (r.steps as f64 * H) * 1e3
        );
        println!(
            "| {} | fmi2DoStep + fmi2GetReal({}) | {} | {:.1} | {} |",
            r.name,
            r.outputs.join(", "),
            r.step_and_read.cells(),
            r.step_and_read.wall_s / (r.steps as f64 * H) * 1e3,
            r.allocations
        );
        println!("| {} | of which fmi2GetReal | {} | - | - |", r.name, r.read.cells());
    }
    println!();
    for r in &rows {
        println!("- {}: {}; built in {:.1} s.", r.name, r.what, r.build_s);
    }
    println!();

    let pendulum = &rows[0];
    // the step sweep only where chain_master runs (its accuracy is what it is measured against)
    let reference_csv = work.join("double_pendulum_reference.csv");
    let sweep = match self::python(python) {
        Some(_) if !short => Some(assembly_steps::sweep(work, &CASES[0].outputs, &reference_csv)?),
        _ => None,
    };
    if let Some(m) = masters(work, python, pendulum, short, sweep.as_ref().map(|_| reference_csv.as_path()))? {
        let c = &m["chain_master"];
        let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        let fmu_per_s = pendulum.step_and_read.wall_s / (pendulum.steps as f64 * H);
        let fmu_step_only = pendulum.step.wall_s / (pendulum.steps as f64 * H);
        let chain_per_s = f(c, "loop_s_per_sim_s");
        let ratio = chain_per_s / fmu_per_s;
        let chain_error = max_of(&c["error_vs_rigid"]);
        let fmu_error = max_of(&m["assembly"]["error_vs_rigid_chain_window"]);
        println!("### The double pendulum against chain_master and Exudyn\n");
        println!(
            "The same scene (examples/assemblies/double_pendulum.json; chain_master as tests/test_chain.py `double_pendulum` drives it: two body FMUs of examples/chain/link.json, revolute joints, the master retaking every step; Exudyn: tests/exudyn_reference.py, the same mesh's CalculiX matrices, 12 Craig-Bampton modes per link, generalised alpha, only SolveDynamic timed, so only its mean per step), h = 1 ms from rest. Error: elbow and tip (x, z) against the rigid double pendulum, max over the window / the rigid swing, worst column (bench/assembly_masters.py).\n"
        );
        let e = &m["exudyn"];
        let exudyn_ok = e.get("steps").is_some();
        let (chain_s, exudyn_s) = (f(c, "seconds"), f(e, "seconds"));
        let exudyn_window_error =
            if exudyn_ok { max_of(&m["assembly"]["error_vs_rigid_exudyn_window"]) } else { f64::NAN };
        println!(
            "| solver | simulated [s] | p50 [us] | p99 [us] | max [us] | mean [us] | steps > {SLOW} x p50 | ms per simulated second | error vs rigid, first {chain_s} s | error vs rigid, first {exudyn_s} s |"
        );
        println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        println!(
            "| assembly FMU, fmi2DoStep + outputs | {:.1} | {} | {:.1} | {:.2e} | {:.2e} |",
            pendulum.steps as f64 * H,
            pendulum.step_and_read.cells(),
            fmu_per_s * 1e3,
            fmu_error,
            exudyn_window_error
        );
        println!(
            "| assembly FMU, fmi2DoStep alone | {:.1} | {} | {:.1} | | |",
            pendulum.steps as f64 * H,
            pendulum.step.cells(),
            fmu_step_only * 1e3
        );
        println!(
            "| chain_master (Python, 2 body FMUs, {:.2} FMU steps per step) | {chain_s} | {:.0} | {:.0} | {:.0} | {:.0} | {} | {:.0} | {:.2e} | |",
            f(c, "evaluations_per_step"),
            f(c, "p50_us"),
            f(c, "p99_us"),
            f(c, "max_us"),
            f(c, "mean_us"),
            c["slow"],
            chain_per_s * 1e3,
            chain_error
        );
        if exudyn_ok {
            println!(
                "| Exudyn (SolveDynamic) | {exudyn_s} | - | - | - | {:.0} | - | {:.0} | | {:.2e} |",
                f(e, "mean_us"),
                f(e, "solve_s_per_sim_s") * 1e3,
                max_of(&e["error_vs_rigid"]),
            );
        } else {
            println!(
                "| Exudyn | - | - | - | - | - | - | - | | {} |",
                e.get("error").and_then(|x| x.as_str()).unwrap_or("not run")
            );
        }
        println!();
        let equal_or_better = fmu_error <= chain_error;
        println!(
            "chain_master / assembly FMU per simulated second at the same 1 ms step, with the positions and a joint reaction read: **{ratio:.0}x** (step alone: {:.0}x); the target of at least {CHAIN_MASTER_RATIO:.0}x is at equal or better accuracy, where the FMU takes a longer step{}. Accuracy: the FMU's error {fmu_error:.2e} against chain_master's {chain_error:.2e}: {}. Over the FMU's whole {:.1} s the FMU's error is {:.2e}.\n",
            chain_per_s / fmu_step_only,
            if sweep.is_some() { " (the step sweep below)" } else { " (the step sweep runs in a full run only)" },
            if equal_or_better { "equal or better" } else { "worse" },
            pendulum.steps as f64 * H,
            max_of(&m["assembly"]["error_vs_rigid"])
        );
        if let Some(sweep) = &sweep {
            print_sweep(sweep, chain_per_s, f(c, "error_vs_reference"));
        }
        eprintln!(
            "assembly vs chain_master: {ratio:.0}x per simulated second ({} us per step for the FMU)",
            ns(pendulum.step_and_read.quantile(0.5) * 1e-3)
        );
    }

    let total: usize = rows.iter().map(|r| r.allocations).sum();
    Ok(vec![Target {
        what: format!(
            "assembly FMU heap allocations in {COUNTED_STEPS} steps with outputs ({} assemblies)",
            rows.len()
        ),
        measured: format!("{total}"),
        limit: "0".into(),
        ok: total == 0,
    }])
}

/// The step sweep's table and the ratio to chain_master at equal or better accuracy.
fn print_sweep(sweep: &[StepRow], chain_per_s: f64, chain_error: f64) {
    println!(
        "### At equal accuracy\n\nThe double pendulum built with `solver.max_step` of each step below and stepped at it for {} s, timed {} times (the median counts) with the outputs read after each step: the elbow's and the tip's (x, z), which chain_master's run reads, and those with the pivot's reaction (an index-1 solve at each communication point); error: elbow and tip (x, z) against the same FMU at a {} ms step (a converged solution of the same model: the time integration's error, a consistency check), after every step of each run, max / the swing, worst column; chain_master's run above the same way (bench/src/assembly_steps.rs).\n",
        assembly_steps::SECONDS,
        assembly_steps::REPEATS,
        assembly_steps::REFERENCE_STEP * 1e3,
    );
    println!(
        "| solver | step [ms] | ms per simulated second, positions | with a reaction | error vs converged | chain_master / this, positions | with a reaction |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    println!("| chain_master | 1 | {:.0} | | {chain_error:.2e} | 1 | |", chain_per_s * 1e3);
    for r in sweep {
        println!(
            "| assembly FMU | {} | {:.1} | {:.1} | {:.2e} | {:.0}x | {:.0}x |",
            r.step * 1e3,
            r.positions_per_second * 1e3,
            r.per_simulated_second * 1e3,
            r.error,
            chain_per_s / r.positions_per_second,
            chain_per_s / r.per_simulated_second
        );
    }
    let best = sweep
        .iter()
        .filter(|r| r.error <= chain_error)
        .min_by(|a, b| a.per_simulated_second.total_cmp(&b.per_simulated_second));
    match best {
        Some(r) => {
            let (positions, reaction) = (chain_per_s / r.positions_per_second, chain_per_s / r.per_simulated_second);
            println!(
                "\nAt equal or better accuracy (the longest step here whose error is at most chain_master's, {} ms): **{positions:.0}x** per simulated second with the outputs chain_master's run reads, {reaction:.0}x with a joint reaction too; the target is at least {CHAIN_MASTER_RATIO:.0}x: {} (reported, not checked).\n",
                r.step * 1e3,
                if positions >= CHAIN_MASTER_RATIO { "met" } else { "NOT met" }
            )
        }
        None => println!("\nNo step here is as accurate as chain_master ({chain_error:.2e}).\n"),
    }
}
