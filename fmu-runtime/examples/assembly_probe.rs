use fmu_runtime::assembly::description::AssemblyDescription;
use fmu_runtime::assembly::model::Assembly;
fn main() {
    let bytes = std::fs::read(std::env::args().nth(1).unwrap()).unwrap();
    let d = AssemblyDescription::from_sealed_bytes(&bytes).unwrap();
    let mut a = Assembly::new(&d).unwrap();
    a.start_run(0.0).unwrap();
    let n = 2000;
    let mut times = Vec::new();
    let mut iters = 0;
    for _ in 0..n {
        let t = std::time::Instant::now();
        a.do_step(1e-3).unwrap();
        times.push(t.elapsed().as_secs_f64() * 1e6);
        iters += a.solver.last_iterations;
    }
    times.sort_by(|a, b| a.partial_cmp(b).unwrap());
    println!(
        "p50 {:.1} us p99 {:.1} max {:.1}; iterations/step {:.2}, matrices {}",
        times[n / 2],
        times[n * 99 / 100],
        times[n - 1],
        iters as f64 / n as f64,
        a.solver.matrices_formed
    );
}
