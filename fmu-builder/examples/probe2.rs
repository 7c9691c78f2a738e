use fmu_builder::spec::Spec;
use fmu_builder::sparse::{block, SpdSolver, mul_compensated, mul_new};
use std::path::Path;
fn main() {
    let arg = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&arg).unwrap();
    let spec = Spec::from_str(Path::new(&arg), &text).unwrap();
    let b = fmu_builder::pipeline::reduce_spec(spec, Path::new(&arg)).unwrap();
    let nc = b.model.dofs.n_clamped();
    let k = block(&b.model.stiffness, 0..nc, 0..nc).unwrap();
    let m = block(&b.model.mass, 0..nc, 0..nc).unwrap();
    let s = SpdSolver::new(&k, "k").unwrap();
    let e = fmu_builder::eigen::lowest(&s, &m, 10, 1e-10).unwrap();
    let hz = |l: f64| l.sqrt()/(2.0*std::f64::consts::PI);
    let rq = |v: faer::MatRef<f64>| {
        let kv = mul_compensated(None, 1.0, &k, v);
        let mv = mul_new(&m, v);
        let a: f64 = (0..nc).map(|i| v[(i,0)]*kv[(i,0)]).sum();
        let bb: f64 = (0..nc).map(|i| v[(i,0)]*mv[(i,0)]).sum();
        a/bb
    };
    for j in 0..3 {
        println!("full lanczos {:.12} rq {:.12}", hz(e.values[j]), hz(rq(e.vectors.subcols(j,1))));
        println!("reduced      {:.12} rq {:.12}", b.report.accuracy.reduced_hz[j], hz(rq(b.basis.phi.subcols(j,1))));
    }
}
