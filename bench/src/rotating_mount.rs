//! The bench's rotating mount (shared with `examples/spin_up_ab.rs`).

use crate::fmi::Instance;

/// Inputs of the rotating mount, set once: spinning at `spin` rad/s about world z through the
/// mount point, which stays at the origin (r = 0, so v = w x r = 0 and a = w x (w x r) = 0), at
/// the orientation Rz(0.3).
pub fn rotating_mount(inst: &Instance, spin: f64) -> Result<(), String> {
    let (s, c) = 0.3f64.sin_cos();
    let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
    let mut names = Vec::new();
    let mut values = Vec::new();
    for (i, row) in rot.iter().enumerate() {
        for (j, value) in row.iter().enumerate() {
            names.push(format!("base.R[{},{}]", i + 1, j + 1));
            values.push(*value);
        }
    }
    for (i, w) in [0.0, 0.0, spin].iter().enumerate() {
        names.push(format!("base.w[{}]", i + 1));
        values.push(*w);
        names.push(format!("base.r[{}]", i + 1));
        values.push(0.0);
        names.push(format!("base.v[{}]", i + 1));
        values.push(0.0);
        names.push(format!("base.a[{}]", i + 1));
        values.push(0.0);
    }
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    inst.set(&names, &values)
}
