//! No heap allocation in a step of a body the builder reduced: the paper's steel beam with
//! 20 Craig-Bampton modes, gravity, rotation and geometric stiffening declared (so every
//! coupling and stiffening term of the runtime is present), stepped 1000 times with the tip
//! force changing every step and every output read, mount fixed and spinning, plus 1000
//! Model-Exchange derivative evaluations. Counted per thread by a counting global allocator.
//! fmu-runtime's tests/no_alloc.rs covers the exported C functions and free-floating bodies.

use fmi2::Model;
use fmu_builder::input::spec::Spec;
use fmu_builder::pipeline::reduce_spec;
use fmu_runtime::fmu::BodyFmu;
use fmu_runtime::interface::VariableTable;
use std::path::Path;

use test_support::alloc::{Counting, assert_no_allocation};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn a_built_beam_steps_without_allocating() {
    let text = r#"{
      "name": "Beam",
      "geometry": { "element": "hex20", "boxes": [ { "min": [0.0, -0.005, -0.01], "max": [1.0, 0.005, 0.01], "elements": [50, 2, 2] } ] },
      "material": { "E": 2.0e11, "nu": 0.3, "rho": 7850.0 },
      "damping": { "alpha": 1.0, "beta": 0.001 },
      "flanges": [
        { "name": "base", "role": "motion", "nodes": { "box_face": { "box": 0, "face": "-x" } } },
        { "name": "tip", "role": "force", "nodes": { "box_face": { "box": 0, "face": "+x" } } }
      ],
      "scene": { "loads": ["gravity", "rotation"], "geometric_stiffening": true },
      "reduction": { "method": "craig_bampton", "modes": 20 }
    }"#;
    let spec = Spec::from_str(Path::new("beam.json"), text).unwrap();
    let built = reduce_spec(spec, Path::new("beam.json")).unwrap();
    let reduced = built.reduced;
    let st = reduced.stiffening.as_ref().expect("stiffening terms");
    assert!(
        reduced.rotation.is_some() && st.centrifugal.is_some() && st.translation.is_some() && !st.flanges[0].is_empty()
    );
    let table = VariableTable::new(&reduced);
    let force: Vec<u32> = (1..=3).map(|i| table.value_reference(&format!("tip.f[{i}]")).unwrap()).collect();
    let torque = table.value_reference("tip.t[1]").unwrap();
    let mut outputs = Vec::new();
    for q in ["r", "v", "w", "a", "z", "u", "phi"] {
        for i in 1..=3 {
            outputs.push(table.value_reference(&format!("tip.{q}[{i}]")).unwrap());
        }
    }
    for i in 1..=3 {
        for j in 1..=3 {
            outputs.push(table.value_reference(&format!("tip.R[{i},{j}]")).unwrap());
        }
        outputs.push(table.value_reference(&format!("base.f[{i}]")).unwrap());
        outputs.push(table.value_reference(&format!("base.t[{i}]")).unwrap());
    }
    for spinning in [false, true] {
        let what = if spinning { "spinning mount" } else { "fixed mount" };
        let mut fmu = BodyFmu::from_reduced(reduced.clone());
        fmu.set_real(table.value_reference("g[3]").unwrap(), -9.81).unwrap();
        if spinning {
            // spinning at 10 rad/s about world z through the mount point, at the orientation Rz(0.3)
            let (s, c) = 0.3f64.sin_cos();
            let rot = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
            for i in 0..3 {
                for j in 0..3 {
                    fmu.set_real(
                        table.value_reference(&format!("base.R[{},{}]", i + 1, j + 1)).unwrap(),
                        rot[3 * i + j],
                    )
                    .unwrap();
                }
            }
            fmu.set_real(table.value_reference("base.w[3]").unwrap(), 10.0).unwrap();
        }
        fmu.enter_initialization(0.0).unwrap();
        fmu.exit_initialization().unwrap();
        let mut sink = 0.0;
        assert_no_allocation(&format!("{what}: set tip load, do_step, get outputs"), || {
            for k in 0..1000 {
                fmu.set_real(force[2], 10.0 * (k % 7) as f64).unwrap();
                fmu.set_real(force[1], 1.0).unwrap();
                fmu.set_real(torque, 0.1).unwrap();
                fmu.do_step(k as f64 * 1e-3, 1e-3).unwrap();
                for &r in &outputs {
                    sink += fmu.get_real(r).unwrap();
                }
            }
        });
        let nx = fmu.n_states();
        let mut x = vec![0.0; nx];
        let mut dx = vec![0.0; nx];
        assert_no_allocation(&format!("{what}: set_continuous_states, get_derivatives"), || {
            for k in 0..1000 {
                fmu.get_continuous_states(&mut x);
                x[k % nx] += 1e-9;
                fmu.set_continuous_states(&x);
                fmu.get_derivatives(&mut dx).unwrap();
                sink += dx[nx - 1];
            }
        });
        assert!(sink.is_finite(), "{what}: {sink}");
    }
}
