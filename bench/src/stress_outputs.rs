//! What stress outputs cost per step: the 20-mode beam (no rotation declared) with 0, 10 and
//! 100 recovery points (hot spots), a master loop of fmi2SetReal(tip.f) + fmi2DoStep +
//! fmi2GetReal of every stress output (seven per point), against the same loop with no stress
//! output.

use crate::fmi::Fmu;
use crate::{H, Stats, measure, ns};
use fmi2::types::{fmi2CoSimulation, fmi2Status};
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

/// Recovery point counts measured.
const POINTS: [usize; 3] = [0, 10, 100];
/// Target: reading one more point's seven outputs per step costs at most 1.5 plain steps (set,
/// step, no output). A point's six rows of 26 are summed once per evaluation (six independent
/// sums, then von Mises), and each output read costs what any output read costs (~25 ns):
/// measured 0.57 of a plain step on the README's machine at rest (154-220 ns per point against
/// 272-400 ns per step), 0.88 with both its cores busy elsewhere.
pub const PER_POINT_LIMIT: f64 = 1.5;

fn spec(points: usize) -> String {
    let outputs =
        if points == 0 { String::new() } else { format!(r#""outputs": {{ "stress": {{ "hot_spots": {points} }} }},"#) };
    format!(
        r#"{{
  "name": "BenchStress{points}",
  "scene": {{ "loads": [] }},
  {outputs}
  "geometry": {{ "element": "hex20", "boxes": [ {{ "min": [0.0, -0.005, -0.01], "max": [1.0, 0.005, 0.01], "elements": [50, 2, 2] }} ] }},
  "material": {{ "E": 2.0e11, "nu": 0.3, "rho": 7850.0 }},
  "damping": {{ "alpha": 1.0, "beta": 0.001 }},
  "flanges": [
    {{ "name": "base", "role": "motion", "nodes": {{ "box_face": {{ "box": 0, "face": "-x" }} }} }},
    {{ "name": "tip", "role": "force", "nodes": {{ "box_face": {{ "box": 0, "face": "+x" }} }} }}
  ],
  "reduction": {{ "method": "craig_bampton", "modes": 20 }}
}}
"#
    )
}

/// The table and the per-point target: (what, measured, ok).
pub fn run(work: &Path, repeats: usize) -> Result<(String, String, bool), String> {
    let mut rows: Vec<(usize, Stats)> = Vec::new();
    for points in POINTS {
        let input = work.join(format!("stress{points}.json"));
        let output = work.join(format!("BenchStress{points}.fmu"));
        std::fs::write(&input, spec(points)).map_err(|e| e.to_string())?;
        let built = fmu_builder::pipeline::build(&input, &output).map_err(|e| format!("{}: {e}", input.display()))?;
        let names: Vec<String> = built
            .reduced
            .stress_points
            .iter()
            .flat_map(|p| fmu_runtime::interface::STRESS_COMPONENTS.iter().map(move |c| format!("{}.{c}", p.name)))
            .collect();
        assert_eq!(names.len(), 7 * points);
        let fmu = Fmu::open(&output, &work.join(format!("BenchStress{points}")))?;
        let vrs: Vec<u32> = names.iter().map(|n| fmu.description.vr(n)).collect();
        let force = fmu.description.vr("tip.f[3]");
        let inst = fmu.instantiate(fmi2CoSimulation, "stress")?;
        inst.initialize()?;
        let api = &inst.fmu.api;
        let c = inst.c;
        let mut out = vec![0.0; vrs.len()];
        let mut t = 0.0;
        let stats = measure(repeats, Duration::from_millis(200), 2_000_000, |n| {
            let mut bad = 0;
            let mut sink = 0.0;
            let start = Instant::now();
            for k in 0..n {
                let f = [100.0 * ((k % 97) as f64 / 97.0)];
                unsafe {
                    bad += ((api.set_real)(c, &force, 1, f.as_ptr()) != fmi2Status::fmi2OK) as usize;
                    bad += ((api.do_step)(c, t, H, 1) != fmi2Status::fmi2OK) as usize;
                    if !vrs.is_empty() {
                        bad += ((api.get_real)(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) != fmi2Status::fmi2OK)
                            as usize;
                    }
                }
                sink += out.first().copied().unwrap_or(0.0);
                t += H;
            }
            let elapsed = start.elapsed();
            black_box(sink);
            assert_eq!(bad, 0, "an FMI call failed");
            elapsed
        });
        rows.push((points, stats));
    }
    println!("## Stress outputs: ns per step with 0, 10 and 100 recovery points\n");
    println!(
        "The 20-mode beam without rotation terms, hot spots as recovery points: fmi2SetReal(tip.f[3]) + fmi2DoStep + fmi2GetReal of the seven stress outputs of every point (six components and von Mises).\n"
    );
    println!("| points | outputs read | ns per step (median) | min | per point above 0 points [ns] |");
    println!("|---:|---:|---:|---:|---:|");
    let base = rows[0].1.median;
    for (points, s) in &rows {
        let per = if *points > 0 { format!("{:.1}", (s.median - base) / *points as f64) } else { "-".into() };
        println!("| {points} | {} | {} | {} | {per} |", 7 * points, ns(s.median), ns(s.min));
    }
    println!();
    let (points, s) = rows[rows.len() - 1];
    let per_point = (s.median - base) / points as f64 / base;
    Ok((
        format!("one stress recovery point's seven outputs per step / a step without ({points} points)"),
        format!("{per_point:.3}"),
        per_point <= PER_POINT_LIMIT,
    ))
}
