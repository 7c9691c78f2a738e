use fmu_builder::spec::Spec;
use std::path::Path;
fn main() {
    let arg = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&arg).unwrap();
    let t = std::time::Instant::now();
    let spec = Spec::from_str(Path::new(&arg), &text).unwrap();
    let b = fmu_builder::pipeline::reduce_spec(spec, Path::new(&arg)).unwrap_or_else(|e| panic!("{e}"));
    println!("{}", fmu_builder::summary::text(&b.report));
    println!("full: {:?}", b.report.accuracy.full_hz);
    println!("red: {:?}", b.report.accuracy.reduced_hz);
    println!("rel: {:?}", b.report.accuracy.relative_error);
    let c = &b.report.accuracy.compliance_full;
    // tip load F_z=1e-4, M_x=M_y=1e-4
    let load = [0.0, 0.0, 1e-4, 1e-4, 1e-4, 0.0];
    let u: Vec<f64> = (0..6).map(|i| (0..6).map(|j| c[i][j] * load[j]).sum()).collect();
    println!("static tip u,phi = {:?}", u);
    let cr = &b.report.accuracy.compliance_reduced;
    let ur: Vec<f64> = (0..6).map(|i| (0..6).map(|j| cr[i][j] * load[j]).sum()).collect();
    println!("reduced tip u,phi = {:?}", ur);
    for i in 0..6 { println!("rel {i}: {:e}", (ur[i]-u[i])/u[i]); }
    for i in 0..6 { println!("diag rel {i}: {:e}", (cr[i][i]-c[i][i])/c[i][i]); }
    println!("elapsed {:?}", t.elapsed());
}
