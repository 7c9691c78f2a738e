//! No heap allocation in a step: a counting global allocator (per thread, so the test harness's
//! other threads do not count) around 1000 steps, derivative evaluations and output reads, for a
//! fixed mount, a spinning one with every coupling and stiffening term present, and a
//! free-floating body; through the body, through the FMI model trait and through the exported
//! C functions (the code the FMU's binary runs); and the coupled propagator on its own, with the
//! workspace its caller lends it, which refuses a workspace too small without allocating.
//!
//! The bodies are synthetic (consistent shapes, small invariants), sized like a 20-mode model:
//! allocation does not depend on the numbers. fmu-builder's tests/no_alloc.rs does the same with
//! a beam built by the builder.

use fmi2::Model;
use fmi2::types::*;
use fmu_runtime::body::FlexibleBody;
use fmu_runtime::coupled_propagator::CoupledPropagator;
use fmu_runtime::fmu::BodyFmu;
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::{FlangeShapes, ReducedBody, RotationTerms, Stiffening, StressPoint, two_mode_body};
use fmu_runtime::workspace::{Workspace, WorkspaceReq};
use std::ffi::CString;
use std::sync::Arc;
use test_support::alloc::{Counting, assert_no_allocation};
use test_support::logger;
use test_support::scratch::{Scratch, file_uri};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Deterministic numbers in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn vec(&mut self, len: usize, scale: f64) -> Vec<f64> {
        (0..len).map(|_| scale * self.next()).collect()
    }
}

/// A body of order n with two force flanges, rotation invariants (G_a skew) and every
/// stiffening block (the second flange without any, as the builder writes for a flange whose
/// prestress is not modelled).
fn synthetic_body(n: usize, free_floating: bool) -> ReducedBody {
    let mut r = Lcg(7);
    let nn = n * n;
    let mut g = vec![0.0; 3 * nn];
    for a in 0..3 {
        for i in 0..n {
            for j in 0..i {
                let v = 0.05 * r.next();
                g[a * nn + i * n + j] = v;
                g[a * nn + j * n + i] = -v;
            }
        }
    }
    let mut o_mat = r.vec(9 * nn, 1e-3);
    for k in 0..9 {
        for i in 0..n {
            o_mat[k * nn + i * n + i] += 0.01;
        }
    }
    let moments = if free_floating { vec![0.0; 3 * n] } else { r.vec(3 * n, 0.05) };
    ReducedBody {
        guid: format!("{{synthetic-{n}-{free_floating}}}"),
        model_name: "Synthetic".into(),
        mount: if free_floating { String::new() } else { "base".into() },
        omega: (0..n).map(|k| 30.0 * (k + 1) as f64 * (1.0 + 0.1 * k as f64)).collect(),
        alpha: 0.5,
        beta: 1e-4,
        modal_damping: vec![0.0; n],
        mass: 2.0,
        first_moment: if free_floating { [0.0; 3] } else { [1.0, 0.0, 0.0] },
        inertia: [0.1, 0.0, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 0.7],
        c_t: moments.clone(),
        c_r: if free_floating { vec![0.0; 3 * n] } else { r.vec(3 * n, 0.05) },
        flanges: vec![
            FlangeShapes { name: "tip".into(), position: [1.0, 0.0, 0.0], shapes: r.vec(6 * n, 0.1) },
            FlangeShapes { name: "mid".into(), position: [0.5, 0.0, 0.0], shapes: r.vec(6 * n, 0.1) },
        ],
        stress_points: (0..2)
            .map(|k| StressPoint {
                name: format!("stress.n{}", k + 1),
                description: format!("synthetic point {k}"),
                position: [0.2 * k as f64, 0.0, 0.0],
                modes: r.vec(6 * n, 1e6),
            })
            .collect(),
        rotation: Some(RotationTerms { g, o_mat, o_vec: r.vec(9 * n, 1e-3) }),
        stiffening: Some(Stiffening {
            centrifugal: Some(r.vec(9 * nn, 1e-3)),
            euler: Some(r.vec(3 * nn, 1e-3)),
            translation: Some(r.vec(3 * nn, 1e-3)),
            flanges: vec![r.vec(6 * nn, 1e-3), Vec::new()],
        }),
        free_floating,
        // half the modes quasi-static in Model Exchange: the algebraic solve runs in every test
        dynamic_cutoff: 30.0 * (n / 2) as f64 * (1.0 + 0.1 * (n / 2 - 1) as f64),
    }
}

#[derive(Clone, Copy, Debug)]
enum Motion {
    Fixed,
    /// Spinning about an off-axis mount: every inertial term active.
    Rotating,
}

fn drive(b: &mut FlexibleBody, motion: Motion) {
    if let Motion::Rotating = motion {
        let m = b.mount_mut();
        let (s, c) = 0.3f64.sin_cos();
        m.rot = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
        m.r = [0.2, 0.0, 0.0];
        m.w = [0.0, 1.0, 10.0];
        m.v = [0.0, 2.0, 0.0];
        m.a = [-20.0, 0.0, 0.0];
        m.z = [0.0, 0.0, 0.5];
    }
    b.parameters_mut().g = [0.0, 0.0, -9.81];
}

/// 1000 steps with the tip force changing every step, reading every output; then 1000
/// derivative evaluations at changing states.
fn exercise_body(name: &str, reduced: ReducedBody, motion: Motion) {
    // a copy, as an FMU state restored before the first step is: the copy must not allocate either
    let mut b = FlexibleBody::new(Arc::new(reduced)).clone();
    drive(&mut b, motion);
    let n = b.n_modes();
    let nf = b.reduced().flanges.len();
    let mut q = vec![0.0; n];
    let mut qd = vec![0.0; n];
    let mut dq = vec![0.0; n];
    let mut dqd = vec![0.0; n];
    let mut sink = 0.0;
    assert_no_allocation(&format!("{name} {motion:?}: steps"), || {
        for k in 0..1000 {
            b.load_mut(0).f = [1.0, 0.5, (k % 17) as f64];
            b.load_mut(0).t = [0.0, 0.1, 0.0];
            if k % 2 == 1 {
                // every other step with interpolated inputs: the ramp and its coupling at the end
                b.load_rate_mut(0).f = [0.0, 3.0, -5.0];
                let r = b.mount_rate_mut();
                r.a = [1.0, 0.0, 0.0];
                if let Motion::Rotating = motion {
                    r.w = [0.0, 0.0, 2.0];
                    r.rot = [0.0, -0.01, 0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0];
                }
            }
            b.step(1e-3).unwrap();
            for f in 0..nf {
                let m = b.flange_motion(f).unwrap();
                sink += m.r[0] + m.rot[4] + m.v[2] + m.w[1] + m.a[0] + m.z[2] + m.u[2] + m.phi[1];
            }
            if b.frame().is_none() {
                let (f, t) = b.mount_reaction().unwrap();
                sink += f[2] + t[1];
            } else {
                sink += b.invariants().unwrap().energy + b.frame_rate().unwrap().v[0];
            }
            sink += b.qdd().unwrap()[0];
        }
        // a host changing its step size now and then
        for k in 0..100 {
            b.step(if k % 2 == 0 { 1e-3 } else { 5e-4 }).unwrap();
        }
    });
    assert_no_allocation(&format!("{name} {motion:?}: derivatives"), || {
        for k in 0..1000 {
            for j in 0..n {
                q[j] = 1e-4 * ((j + k) % 5) as f64;
                qd[j] = 1e-3 * ((j * k) % 3) as f64;
            }
            b.set_state(&q, &qd);
            b.derivatives(&mut dq, &mut dqd).unwrap();
            sink += dqd[0];
        }
    });
    // Model Exchange: the modes above the cutoff solved at every evaluation
    b.set_quasi_static(true);
    let nd = b.n_dynamic();
    assert!(nd < n || n == 2, "{name}: the quasi-static solve must be exercised");
    assert_no_allocation(&format!("{name} {motion:?}: quasi-static derivatives"), || {
        for k in 0..1000 {
            for j in 0..nd {
                q[j] = 1e-4 * ((j + k) % 5) as f64;
                qd[j] = 1e-3 * ((j * k) % 3) as f64;
            }
            b.set_state(&q[..nd], &qd[..nd]);
            b.derivatives(&mut dq[..nd], &mut dqd[..nd]).unwrap();
            sink += dqd[0] + b.flange_motion(0).unwrap().u[2];
        }
    });
    assert!(sink.is_finite(), "{name} {motion:?}: the body blew up ({sink})");
}

#[test]
fn body_steps_and_derivatives_allocate_nothing() {
    exercise_body("two-mode body", two_mode_body(), Motion::Fixed);
    for motion in [Motion::Fixed, Motion::Rotating] {
        exercise_body("synthetic body (26 modes)", synthetic_body(26, false), motion);
    }
    exercise_body("free-floating body (26 modes)", synthetic_body(26, true), Motion::Fixed);
}

/// The coupled propagator with a lent workspace: new exponentials (the step size changes every
/// call) and advances allocate nothing, and a workspace smaller than
/// `CoupledPropagator::workspace_req` is refused by both, without allocating or panicking.
#[test]
fn the_coupled_propagator_works_in_the_lent_workspace_and_refuses_a_small_one() {
    let n = 26;
    let mut r = Lcg(3);
    let omega: Vec<f64> = (0..n).map(|k| 30.0 * (k + 1) as f64).collect();
    let (c_d, c_k, extra) = (r.vec(n * n, 1.0), r.vec(n * n, 10.0), vec![0.0; n]);
    let (p0, p1) = (r.vec(n, 1.0), r.vec(n, 0.5));
    let (mut q, mut qd) = (r.vec(n, 1e-3), r.vec(n, 1e-2));
    let mut p = CoupledPropagator::with_modes(n);
    let mut ws = Workspace::new(CoupledPropagator::workspace_req(n));
    // one value short of what advance needs, far short of the exponential's
    let mut tiny = Workspace::new(WorkspaceReq::slices(&[4 * n - 1]));
    let mut refused = 0;
    assert_no_allocation("coupled propagator: prepare and advance", || {
        for k in 0..20 {
            let h = 1e-3 * (1 + k % 3) as f64;
            p.prepare(&omega, 0.5, 1e-4, &extra, &c_d, &c_k, h, &mut ws).unwrap();
            p.advance(&omega, &p0, &p1, &mut q, &mut qd, &mut ws).unwrap();
            refused += p.prepare(&omega, 0.5, 1e-4, &extra, &c_d, &c_k, 2.0 * h, &mut tiny).is_err() as usize;
            refused += p.advance(&omega, &p0, &p1, &mut q, &mut qd, &mut tiny).is_err() as usize;
        }
    });
    assert_eq!(refused, 40);
    assert!(q.iter().chain(&qd).all(|v| v.is_finite()));
}

fn outputs(table: &VariableTable, reduced: &ReducedBody) -> Vec<u32> {
    let mut names = Vec::new();
    for f in &reduced.flanges {
        for q in ["r", "v", "w", "a", "z", "u", "phi"] {
            for i in 1..=3 {
                names.push(format!("{}.{q}[{i}]", f.name));
            }
        }
        for i in 1..=3 {
            for j in 1..=3 {
                names.push(format!("{}.R[{i},{j}]", f.name));
            }
        }
    }
    for p in &reduced.stress_points {
        names.extend(fmu_runtime::interface::STRESS_COMPONENTS.iter().map(|c| format!("{}.{c}", p.name)));
    }
    let extra: &[&str] =
        if reduced.free_floating { &["body.energy", "body.h[3]", "frame.r[1]"] } else { &["base.f[3]", "base.t[2]"] };
    names.extend(extra.iter().map(|s| s.to_string()));
    names.iter().map(|n| table.value_reference(n).unwrap()).collect()
}

fn mount_inputs(table: &VariableTable) -> (Vec<u32>, Vec<f64>) {
    let (s, c) = 0.3f64.sin_cos();
    let mut vrs = Vec::new();
    let mut values = Vec::new();
    let rot = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
    for i in 0..3 {
        for j in 0..3 {
            vrs.push(table.value_reference(&format!("base.R[{},{}]", i + 1, j + 1)).unwrap());
            values.push(rot[3 * i + j]);
        }
    }
    for (name, v) in [
        ("base.w", [0.0, 1.0, 10.0]),
        ("base.r", [0.2, 0.0, 0.0]),
        ("base.v", [0.0, 2.0, 0.0]),
        ("base.a", [-20.0, 0.0, 0.0]),
    ] {
        for (i, x) in v.into_iter().enumerate() {
            vrs.push(table.value_reference(&format!("{name}[{}]", i + 1)).unwrap());
            values.push(x);
        }
    }
    (vrs, values)
}

#[test]
fn fmi_model_calls_allocate_nothing() {
    for (reduced, motion) in [
        (two_mode_body(), Motion::Fixed),
        (synthetic_body(26, false), Motion::Fixed),
        (synthetic_body(26, false), Motion::Rotating),
        (synthetic_body(26, true), Motion::Fixed),
    ] {
        let name = format!("{} {motion:?}", reduced.guid);
        let table = VariableTable::new(&reduced);
        let out = outputs(&table, &reduced);
        let force = ["tip.f[1]", "tip.f[2]", "tip.f[3]"].map(|n| table.value_reference(n).unwrap());
        let mut fmu = BodyFmu::from_reduced(reduced.clone());
        if let Motion::Rotating = motion {
            let (vrs, values) = mount_inputs(&table);
            for (r, v) in vrs.iter().zip(&values) {
                fmu.set_real(*r, *v).unwrap();
            }
        }
        fmu.enter_initialization(0.0).unwrap();
        fmu.exit_initialization().unwrap();
        // fmi2SetFMUstate with a state taken before the first step: the model is a copy
        let mut fmu = fmu.clone();
        let nx = fmu.n_states();
        let mut x = vec![0.0; nx];
        let mut dx = vec![0.0; nx];
        let mut sink = 0.0;
        assert_no_allocation(&format!("{name}: set_real, do_step, get_real"), || {
            for k in 0..1000 {
                fmu.set_real(force[2], (k % 13) as f64).unwrap();
                fmu.set_real(force[0], 0.5).unwrap();
                fmu.do_step(k as f64 * 1e-3, 1e-3).unwrap();
                for &r in &out {
                    sink += fmu.get_real(r).unwrap();
                }
            }
        });
        assert_no_allocation(&format!("{name}: set_continuous_states, get_derivatives"), || {
            for k in 0..1000 {
                fmu.get_continuous_states(&mut x);
                x[k % nx] += 1e-6;
                fmu.set_continuous_states(&x);
                fmu.get_derivatives(&mut dx).unwrap();
                sink += dx[nx - 1];
            }
        });
        assert!(sink.is_finite(), "{name}: {sink}");
    }
}

// --- the exported C functions, as the FMU's binary runs them ---------------------------------

fn callbacks() -> fmi2CallbackFunctions {
    logger::callbacks_with(logger::quiet, std::ptr::null_mut())
}

fn resources(reduced: &ReducedBody, tag: &str) -> (Scratch, CString) {
    let dir = Scratch::new(&format!("fmu-runtime-no-alloc-{tag}"));
    let res = dir.folder("resources");
    std::fs::write(res.join(fmu_runtime::format::RESOURCE_FILE), reduced.to_bytes()).unwrap();
    (dir, file_uri(&res))
}

fn ok(what: &str, s: fmi2Status) {
    assert_eq!(s, fmi2Status::fmi2OK, "{what}");
}

#[test]
fn exported_c_functions_allocate_nothing() {
    for (tag, reduced, motion) in [
        ("fixed", synthetic_body(26, false), Motion::Fixed),
        ("rotating", synthetic_body(26, false), Motion::Rotating),
        ("free", synthetic_body(26, true), Motion::Fixed),
    ] {
        let mut reduced = reduced;
        reduced.seal(); // the runtime checks the file's content against its GUID
        let table = VariableTable::new(&reduced);
        let out = outputs(&table, &reduced);
        let force = ["tip.f[1]", "tip.f[2]", "tip.f[3]"].map(|n| table.value_reference(n).unwrap());
        let (_dir, uri) = resources(&reduced, tag);
        let guid = CString::new(reduced.guid.clone()).unwrap();
        let cb = callbacks();
        for kind in [fmi2CoSimulation, fmi2ModelExchange] {
            let name = format!("{tag} {}", if kind == fmi2CoSimulation { "CS" } else { "ME" });
            unsafe {
                let c = fmu_runtime::fmi2Instantiate(
                    c"no-alloc".as_ptr(),
                    kind,
                    guid.as_ptr(),
                    uri.as_ptr(),
                    &cb,
                    fmi2False,
                    fmi2False,
                );
                assert!(!c.is_null(), "{name}: fmi2Instantiate");
                ok("fmi2SetupExperiment", fmu_runtime::fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
                if let Motion::Rotating = motion {
                    let (vrs, values) = mount_inputs(&table);
                    ok("fmi2SetReal", fmu_runtime::fmi2SetReal(c, vrs.as_ptr(), vrs.len(), values.as_ptr()));
                }
                ok("fmi2EnterInitializationMode", fmu_runtime::fmi2EnterInitializationMode(c));
                ok("fmi2ExitInitializationMode", fmu_runtime::fmi2ExitInitializationMode(c));
                let mut values = vec![0.0; out.len()];
                let mut sink = 0.0;
                if kind == fmi2CoSimulation {
                    assert_no_allocation(&format!("{name}: fmi2SetReal, fmi2DoStep, fmi2GetReal"), || {
                        let mut t = 0.0;
                        for k in 0..1000 {
                            let f = [0.5, 0.0, (k % 13) as f64];
                            ok("fmi2SetReal", fmu_runtime::fmi2SetReal(c, force.as_ptr(), 3, f.as_ptr()));
                            ok("fmi2DoStep", fmu_runtime::fmi2DoStep(c, t, 1e-3, fmi2True));
                            t += 1e-3;
                            ok(
                                "fmi2GetReal",
                                fmu_runtime::fmi2GetReal(c, out.as_ptr(), out.len(), values.as_mut_ptr()),
                            );
                            sink += values[2];
                        }
                    });
                } else {
                    let mut info = fmi2EventInfo::default();
                    ok("fmi2NewDiscreteStates", fmu_runtime::fmi2NewDiscreteStates(c, &mut info));
                    ok("fmi2EnterContinuousTimeMode", fmu_runtime::fmi2EnterContinuousTimeMode(c));
                    let nx = table.states().len();
                    let mut x = vec![0.0; nx];
                    let mut dx = vec![0.0; nx];
                    ok("fmi2GetContinuousStates", fmu_runtime::fmi2GetContinuousStates(c, x.as_mut_ptr(), nx));
                    assert_no_allocation(
                        &format!("{name}: fmi2SetTime, fmi2SetContinuousStates, fmi2GetDerivatives, fmi2GetReal"),
                        || {
                            for k in 0..1000 {
                                x[k % nx] += 1e-7;
                                ok("fmi2SetTime", fmu_runtime::fmi2SetTime(c, k as f64 * 1e-4));
                                ok("fmi2SetContinuousStates", fmu_runtime::fmi2SetContinuousStates(c, x.as_ptr(), nx));
                                ok("fmi2GetDerivatives", fmu_runtime::fmi2GetDerivatives(c, dx.as_mut_ptr(), nx));
                                ok(
                                    "fmi2GetReal",
                                    fmu_runtime::fmi2GetReal(c, out.as_ptr(), out.len(), values.as_mut_ptr()),
                                );
                                sink += dx[nx - 1] + values[0];
                            }
                        },
                    );
                }
                assert!(sink.is_finite(), "{name}: {sink}");
                fmu_runtime::fmi2FreeInstance(c);
            }
        }
    }
}
