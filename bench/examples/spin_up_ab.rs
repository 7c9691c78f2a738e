//! Two builds of the same FMU timed side by side in one run: a steady spin and a spin-up, in
//! alternating batches of 1000 `fmi2DoStep` each (this VM's neighbours move runs minutes apart
//! by more than most changes are worth; batches seconds apart see the same machine).
//!
//! `cargo run --release -p bench -- --modes 20,50,100 --fixed-modes "" --skip-full --repeats 1
//! --keep DIR` builds the bench's FMUs and keeps them; do it once per build of the runtime, then
//! `cargo run --release -p bench --example spin_up_ab -- A/BenchBeam100.fmu B/BenchBeam100.fmu 15`.
//!
//! The mount as the bench's rotating one (base.R = Rz(0.3), 10 rad/s about z, 100 N tip
//! force), 50 steps in, its state saved; every batch restores it. Spin-up: fmi2SetReal(base.w[3])
//! before each step, the spin growing by 30 rad/s^2 from 10 rad/s (the bench's spin-up).
//! Printed per FMU: medians and minima over the batches, ns per step, and the spin-up's cost
//! above the steady step.

#[path = "../src/fmi.rs"]
#[allow(dead_code)]
mod fmi;
#[path = "../src/rotating_mount.rs"]
mod rotating_mount;

use fmi2::types::*;
use rotating_mount::rotating_mount;
use std::path::Path;
use std::time::Instant;

const H: f64 = 1e-3;
const SPIN: f64 = 10.0;
const SPIN_UP_RATE: f64 = 30.0;
const STEPS: usize = 1000;

/// The bench's rotating mount at 10 rad/s, the bench's 100 N tip force, initialised.
fn start(inst: &fmi::Instance) -> Result<(), String> {
    rotating_mount(inst, SPIN)?;
    inst.set(&["tip.f[3]"], &[100.0])?;
    inst.initialize()
}

/// ns per step of one batch from the saved state, the spin growing every step or held.
fn batch(inst: &fmi::Instance, saved: fmi2FMUstate, spin_up: bool) -> Result<f64, String> {
    inst.set_state(saved)?;
    let w_vr = inst.fmu.description.vr("base.w[3]");
    let mut t = 50.0 * H;
    let start = Instant::now();
    for k in 0..STEPS {
        if spin_up {
            let w = [SPIN + SPIN_UP_RATE * H * k as f64];
            // SAFETY: FMI 2.0 contract, one value behind one reference
            inst.check("fmi2SetReal", unsafe { (inst.fmu.api.set_real)(inst.c, &w_vr, 1, w.as_ptr()) })?;
        }
        inst.check("fmi2DoStep", inst.do_step(t, H))?;
        t += H;
    }
    Ok(start.elapsed().as_nanos() as f64 / STEPS as f64)
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b, rounds] = &args[..] else {
        return Err("usage: spin_up_ab A.fmu B.fmu ROUNDS".into());
    };
    let rounds: usize = rounds.parse().map_err(|e| format!("ROUNDS {rounds:?}: {e}"))?;
    let tmp = std::env::temp_dir().join(format!("spin-up-ab-{}", std::process::id()));
    let fmus = [a, b]
        .iter()
        .enumerate()
        .map(|(k, p)| fmi::Fmu::open(Path::new(p), &tmp.join(k.to_string())))
        .collect::<Result<Vec<_>, _>>();
    let timed = fmus.and_then(|fmus| time(&fmus, [a, b], rounds));
    let _ = std::fs::remove_dir_all(&tmp);
    timed
}

fn time(fmus: &[fmi::Fmu], paths: [&String; 2], rounds: usize) -> Result<(), String> {
    let mut runs = Vec::new();
    for fmu in fmus {
        let inst = fmu.instantiate(fmi2CoSimulation, "spin_up_ab")?;
        start(&inst)?;
        for k in 0..50 {
            inst.check("fmi2DoStep", inst.do_step(k as f64 * H, H))?;
        }
        let saved = inst.get_state()?;
        runs.push((inst, saved, Vec::new(), Vec::new()));
    }
    for _ in 0..rounds.max(1) {
        for (inst, saved, steady, up) in &mut runs {
            steady.push(batch(inst, *saved, false)?);
            up.push(batch(inst, *saved, true)?);
        }
    }
    println!("| FMU | steady spin, median (min) | spin-up, median (min) | spin-up above steady, medians (minima) |");
    println!("|---|---:|---:|---:|");
    for (path, (_, _, steady, up)) in paths.iter().zip(&mut runs) {
        steady.sort_by(f64::total_cmp);
        up.sort_by(f64::total_cmp);
        let (s, u) = (steady[steady.len() / 2], up[up.len() / 2]);
        println!(
            "| {path} | {s:.0} ({:.0}) | {u:.0} ({:.0}) | {:.0} ({:.0}) |",
            steady[0],
            up[0],
            u - s,
            up[0] - steady[0]
        );
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("spin_up_ab: {e}");
        std::process::exit(1);
    }
}
