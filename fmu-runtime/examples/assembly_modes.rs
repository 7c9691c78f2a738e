use fmu_runtime::assembly::description::{AssemblyDescription, BodyModel};
fn main() {
    let bytes = std::fs::read(std::env::args().nth(1).unwrap()).unwrap();
    let d = AssemblyDescription::from_sealed_bytes(&bytes).unwrap();
    for b in &d.bodies {
        if let BodyModel::Flexible(r) = &b.model {
            println!(
                "{}: n {} n_dynamic {} cutoff {:.1} Hz, f = {:?}",
                b.name,
                r.n_modes(),
                r.n_dynamic(),
                r.dynamic_cutoff / 6.283,
                r.omega.iter().map(|w| (w / 6.283185 * 10.0).round() / 10.0).collect::<Vec<_>>()
            );
        }
    }
}
