//! The sparse eigensolver and the Craig-Bampton reduction against dense linear algebra on a model
//! small enough to solve densely (the reference: faer's dense Cholesky and symmetric eigensolver,
//! independent of our Lanczos and of the reduction).

use faer::{Mat, Side};
use fmu_builder::input::spec::Spec;
use fmu_builder::linalg::eigen;
use fmu_builder::linalg::sparse::{Sparse, SpdSolve, SpdSolver, block};
use fmu_builder::pipeline::reduce_spec;
use fmu_builder::reduce::basis::EIGEN_TOL;
use std::path::Path;

fn spec(reduction: &str) -> Spec {
    let text = format!(
        r#"{{
      "name": "Small",
      "geometry": {{ "element": "hex8", "boxes": [ {{ "min": [0,0,0], "max": [0.5,0.04,0.06], "elements": [12,2,2] }} ] }},
      "material": {{ "E": 7e10, "nu": 0.33, "rho": 2700 }},
      "flanges": [
        {{ "name": "base", "role": "motion", "nodes": {{ "box_face": {{ "box": 0, "face": "-x" }} }} }},
        {{ "name": "tip", "role": "force", "nodes": {{ "box_face": {{ "box": 0, "face": "+x" }} }} }}
      ],
      "reduction": {reduction}
    }}"#
    );
    Spec::from_str(Path::new("small.json"), &text).unwrap()
}

fn dense(a: &Sparse) -> Mat<f64> {
    let mut d = Mat::<f64>::zeros(a.nrows(), a.ncols());
    for j in 0..a.ncols() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            d[(i, j)] += v;
        }
    }
    d
}

/// Eigenvalues of K x = lambda M x, ascending, densely: L^-1 K L^-T with M = L L^T.
fn dense_eigenvalues(k: &Sparse, m: &Sparse) -> Vec<f64> {
    let (k, m) = (dense(k), dense(m));
    let l = m.llt(Side::Lower).unwrap().L().to_owned();
    let mut c = k.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let sym = Mat::<f64>::from_fn(ct.nrows(), ct.ncols(), |i, j| 0.5 * (ct[(i, j)] + ct[(j, i)]));
    sym.self_adjoint_eigenvalues(Side::Lower).unwrap()
}

#[test]
fn lanczos_matches_dense_eigenvalues() {
    let built = reduce_spec(spec(r#"{ "modes": 4 }"#), Path::new("small.json")).unwrap();
    let nc = built.model.dofs.n_clamped();
    let k = block(&built.model.stiffness, 0..nc, 0..nc).unwrap();
    let m = block(&built.model.mass, 0..nc, 0..nc).unwrap();
    let reference = dense_eigenvalues(&k, &m);
    let lanczos = eigen::lowest(
        &SpdSolver::new(std::borrow::Cow::Borrowed(&k), "K", &|d| format!("DoF {d}")).unwrap(),
        &m,
        15,
        EIGEN_TOL,
    )
    .unwrap();
    assert_eq!(lanczos.values.len(), 15);
    assert!(reference.len() >= 15);
    let worst = lanczos.values.iter().zip(&reference).map(|(l, r)| (l - r).abs() / r).fold(0.0, f64::max);
    eprintln!("Lanczos vs dense: worst relative deviation {worst:.1e}");
    // measured 9.4e-11: the Lanczos residual tolerance (EIGEN_TOL) bounds it
    for (i, (l, r)) in lanczos.values.iter().zip(&reference).enumerate() {
        assert!((l - r).abs() <= 1e-9 * r, "mode {i}: {l} vs {r}");
    }
    // and the report's full-model frequencies are these
    assert!(built.report.accuracy.full_hz.len() >= 10 && reference.len() >= built.report.accuracy.full_hz.len());
    let worst = built
        .report
        .accuracy
        .full_hz
        .iter()
        .zip(&reference)
        .map(|(f, r)| (f - r.sqrt() / (2.0 * std::f64::consts::PI)).abs() / f)
        .fold(0.0, f64::max);
    eprintln!("report vs dense: worst relative deviation {worst:.1e}");
    // measured 4.7e-11 (frequencies: half the eigenvalues' relative deviation)
    for (f, r) in built.report.accuracy.full_hz.iter().zip(&reference) {
        assert!((f - r.sqrt() / (2.0 * std::f64::consts::PI)).abs() <= 5e-10 * f);
    }
}

#[test]
fn max_frequency_keeps_every_fixed_interface_mode_below_it() {
    let f_max = 3000.0;
    let built = reduce_spec(spec(&format!(r#"{{ "max_frequency": {f_max} }}"#)), Path::new("small.json")).unwrap();
    let d = &built.model.dofs;
    let ni = d.n_interior;
    let k = block(&built.model.stiffness, 0..ni, 0..ni).unwrap();
    let m = block(&built.model.mass, 0..ni, 0..ni).unwrap();
    let omega_max = 2.0 * std::f64::consts::PI * f_max;
    let below = dense_eigenvalues(&k, &m).iter().filter(|l| l.sqrt() < omega_max).count();
    assert!(below > 3, "the test needs a few modes below the limit");
    assert_eq!(built.basis.n_normal, below);
    assert!(built.basis.fixed_interface_omega.iter().all(|w| *w < omega_max));
}

#[test]
fn mass_properties_are_those_of_the_box() {
    let built = reduce_spec(spec(r#"{ "modes": 2 }"#), Path::new("small.json")).unwrap();
    let (a, b, c) = (0.5, 0.04, 0.06);
    let m = 2700.0 * a * b * c;
    let r = &built.report;
    // round-off of sums over the elements: measured 2.3e-15 (mass), 1.1e-16 m (centre of mass),
    // 8.3e-15 (inertia)
    assert!((r.mass - m).abs() <= 3e-14 * m);
    // body origin: centre of the -x face; centre of mass at (a/2, 0, 0)
    assert!((r.center_of_mass[0] - a / 2.0).abs() < 2e-15 && r.center_of_mass[1].abs() < 2e-15);
    // inertia about the origin: J_xx = m (b^2 + c^2)/12, J_yy = m (a^2/3 + c^2/12)
    let j = r.inertia_about_origin;
    eprintln!(
        "mass {:.1e}, centre of mass {:.1e} {:.1e}, inertia {:.1e} {:.1e} {:.1e}",
        (r.mass - m).abs() / m,
        (r.center_of_mass[0] - a / 2.0).abs(),
        r.center_of_mass[1].abs(),
        (j[0] - m * (b * b + c * c) / 12.0).abs() / j[0],
        (j[4] - m * (a * a / 3.0 + c * c / 12.0)).abs() / j[4],
        (j[8] - m * (a * a / 3.0 + b * b / 12.0)).abs() / j[8]
    );
    assert!((j[0] - m * (b * b + c * c) / 12.0).abs() <= 1e-13 * j[0]);
    assert!((j[4] - m * (a * a / 3.0 + c * c / 12.0)).abs() <= 1e-13 * j[4]);
    assert!((j[8] - m * (a * a / 3.0 + b * b / 12.0)).abs() <= 1e-13 * j[8]);
}

/// The band response (modes below twice the band's top plus a Krylov projection of the rest)
/// against the direct complex LU of the full model, at frequencies across the band including its
/// eigenfrequencies, damped by Rayleigh and by a loss factor (a consistency check of the fast
/// method; the LU's own accuracy is checked against SciPy in the Python tests). Measured 1e-12
/// off resonance and 4.4e-10 exactly at the first eigenfrequency, where the response is the
/// mode's alone over its damping (zeta 6e-3): the eigenvalue's relative error (~5e-12, the
/// Lanczos check's) divided by 2 zeta; 5e-9 is ten times that.
#[test]
fn band_response_equals_the_direct_solve() {
    use fmu_builder::reduce::band_response::{BandResponse, Known};
    use fmu_builder::reduce::frf::{ComparisonDamping, FullResponse};
    let built = reduce_spec(spec(r#"{ "modes": 4 }"#), Path::new("small.json")).unwrap();
    let model = &built.model;
    let nc = model.dofs.n_clamped();
    let k = block(&model.stiffness, 0..nc, 0..nc).unwrap();
    let solver = SpdSolver::new(std::borrow::Cow::Borrowed(&k), "K", &|d| format!("DoF {d}")).unwrap();
    let f1 = built.report.accuracy.full_hz[0];
    let top = 6.0 * f1;
    // the Krylov space's first block solved here, or given as the build has it (its refined
    // static shapes)
    let mut static_response = fmu_builder::reduce::basis::flange_unit_loads(model);
    solver.solve_refined(static_response.as_mut());
    let given = Known { modes: None, static_response: Some(&static_response) };
    for (damping, known) in [
        (ComparisonDamping::new(2.0, 1e-5), Known::default()),
        (ComparisonDamping::new(0.0, 0.0), Known::default()),
        (ComparisonDamping::new(0.0, 0.0), given),
    ] {
        let band =
            BandResponse::new(model, &solver, top, damping, known, 2.0).unwrap().expect("few modes below the cut");
        let mut direct = FullResponse::new(model).unwrap();
        let rows: Vec<usize> = {
            let b = fmu_builder::reduce::basis::flange_unit_loads(model);
            (0..b.ncols()).map(|j| (0..b.nrows()).find(|&i| b[(i, j)] != 0.0).unwrap()).collect()
        };
        let mut worst = 0.0f64;
        let freqs: Vec<f64> = (0..=12)
            .map(|i| top * i as f64 / 12.0)
            .chain(built.report.accuracy.full_hz.iter().copied().filter(|&f| f <= top))
            .collect();
        assert!(freqs.len() > 13);
        for f in freqs {
            let reference = direct.at(damping, f).unwrap();
            let (y, w) = band.coefficients(damping, f);
            let fast = band.rows_of(&rows, &y, &w);
            assert_eq!((fast.nrows(), fast.ncols()), (reference.nrows(), reference.ncols()));
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..fast.nrows() {
                for j in 0..fast.ncols() {
                    num += (fast[(i, j)] - reference[(i, j)]).norm_sqr();
                    den += reference[(i, j)].norm_sqr();
                }
            }
            worst = worst.max((num / den).sqrt());
        }
        println!(
            "band response vs direct LU: {} modes, {} blocks, worst relative difference {worst:.1e}",
            band.modes, band.blocks
        );
        assert!(worst <= 5e-9, "{worst:e}");
    }
}
