#[path = "../src/fmi.rs"]
#[allow(dead_code)]
mod fmi;
#[path = "../src/rotating_mount.rs"]
mod rotating_mount;
use fmi2::types::*;
use std::path::Path;
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let tmp = std::env::temp_dir().join(format!("spin-up-ab-{}", std::process::id()));
    let fmu = fmi::Fmu::open(Path::new(&args[0]), &tmp.join("0")).unwrap();
    let mode: usize = args[1].parse().unwrap();
    let inst = fmu.instantiate(fmi2CoSimulation, "probe").unwrap();
    rotating_mount::rotating_mount(&inst, 10.0).unwrap();
    inst.initialize().unwrap();
    let d = &fmu.description;
    let fv = [d.vr("tip.f[1]"), d.vr("tip.f[2]"), d.vr("tip.f[3]")];
    let mut names = vec![];
    for v in ["r", "v", "w"] {
        for i in 1..=3 {
            names.push(format!("tip.{v}[{i}]"));
        }
    }
    for i in 1..=3 {
        for j in 1..=3 {
            names.push(format!("tip.R[{i},{j}]"));
        }
    }
    let ov: Vec<u32> = names.iter().map(|n| d.vr(n)).collect();
    let mut out = [0.0; 18];
    let mut t = 0.0;
    let rounds = if mode >= 4 { 200 } else { 5 };
    for round in 0..rounds {
        let start = Instant::now();
        for k in 0..2000 {
            let f = [0.0, 30.0 * ((k % 7) as f64), 100.0 * ((k % 5) as f64)];
            unsafe {
                if mode & 1 != 0 {
                    (fmu.api.set_real)(inst.c, fv.as_ptr(), 3, f.as_ptr());
                }
                (fmu.api.do_step)(inst.c, t, 1e-3, 1);
                if mode & 2 != 0 {
                    (fmu.api.get_real)(inst.c, ov.as_ptr(), 18, out.as_mut_ptr());
                }
            }
            t += 1e-3;
        }
        if round + 1 == rounds {
            println!("mode {mode}: {:.0} ns per loop", start.elapsed().as_nanos() as f64 / 2000.0);
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
