//! Flange-to-flange frequency response of the full FE model and of the reduced model over the
//! scene's band, and the error between them: H(w) = B^T (K (1 + i eta) + i w D - w^2 M)^-1 B with
//! B the unit loads at the force flanges, by a complex sparse LU of the full model per sampled
//! frequency, and in closed form for the reduced model (its matrices are diagonal).

use crate::error::{BuildError, Result};
use crate::linalg::faer_error;
use crate::linalg::sparse::{block, mul_compensated};
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::{Basis, flange_unit_load_rows, flange_unit_loads};
use faer::Mat;
use faer::c64;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use serde::Serialize;

pub use crate::reduce::damping::ComparisonDamping;

#[derive(Debug, Clone, Serialize)]
pub struct FrequencyResponse {
    pub band_hz: [f64; 2],
    pub damping: ComparisonDamping,
    pub frequencies_hz: Vec<f64>,
    /// Per frequency: |S (H_full - H_red) S|_F / |S H_full S|_F, S = diag(C_static)^-1/2 (unit-free).
    pub relative_error: Vec<f64>,
    pub max_relative_error: f64,
    /// Per frequency, the driving-point magnitudes |H_ii| of each flange DoF (6 per flange), full
    /// and reduced: the curves of the report's plots.
    pub driving_point_full: Vec<Vec<f64>>,
    pub driving_point_reduced: Vec<Vec<f64>>,
    /// The full model's complete flange FRF at every sampled frequency, row-major nb x nb, as
    /// [re, im] pairs: for independent checks (e.g. a SciPy solve on the exported matrices).
    pub full_matrices: Vec<Vec<[f64; 2]>>,
    /// With stress recovery points: per frequency, |S_full - S_red|_F / |S_full|_F of the stress
    /// responses (every point, component and unit flange load).
    pub stress_relative_error: Vec<f64>,
    /// The full model's stress responses at the first `STRESS_FRF_POINTS` recovery points: per
    /// frequency, point-major (point, component xx..zx, unit load) as [re, im] [Pa per N or N m].
    pub stress_full: Vec<Vec<[f64; 2]>>,
    /// How the full model's responses were computed.
    pub method: String,
}

/// Recovery points whose full-model stress responses the report keeps (the error covers all).
pub const STRESS_FRF_POINTS: usize = 20;

/// Stresses (points x k, point-major) of responses of the constrained model (n_clamped x k).
pub type StressesOf<'a> = dyn Fn(faer::MatRef<'_, f64>) -> Result<Vec<[f64; 6]>> + 'a;

/// Stresses at the recovery points, for the comparison of their responses: `full` maps
/// responses of the constrained model (n_clamped x k) to the points' stresses (points x k,
/// point-major); `modes` are the reduced body's stress modes (6 x r per point, row-major).
pub struct StressProbe<'a> {
    pub full: &'a StressesOf<'a>,
    pub modes: Vec<&'a [f64]>,
}

/// Sample frequencies: an even grid over the band plus every full-model eigenfrequency in it and
/// its close neighbours, where responses peak and errors hide.
pub fn grid(band: [f64; 2], eigen_hz: &[f64], points: usize) -> Vec<f64> {
    let mut f: Vec<f64> =
        (0..points).map(|i| band[0] + (band[1] - band[0]) * (i as f64 + 0.5) / points as f64).collect();
    for &e in eigen_hz {
        for x in [0.995 * e, e, 1.005 * e] {
            if x >= band[0] && x <= band[1] {
                f.push(x);
            }
        }
    }
    f.sort_by(|a, b| a.total_cmp(b));
    f.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs().max(1e-9));
    f
}

/// The full model's flange FRF, factor by factor: K + M pattern and the symbolic LU analysed
/// once, a numeric complex LU per frequency.
pub struct FullResponse {
    k: crate::linalg::sparse::Sparse,
    m: crate::linalg::sparse::Sparse,
    b: Mat<f64>,
    rows: Vec<usize>,
    /// Pattern of K + M, and where each stored entry of K and of M lands in it.
    pattern: faer::sparse::SymbolicSparseColMat<usize>,
    k_slot: Vec<usize>,
    m_slot: Vec<usize>,
    /// Symmetric equilibration 1/sqrt|K_ii|: flange rotation DoFs (N m/rad) and translations
    /// (N/m) differ by orders of magnitude, and the unscaled LU pays that in digits.
    scale: Vec<f64>,
    symbolic: Option<faer::sparse::linalg::solvers::SymbolicLu<usize>>,
}

impl FullResponse {
    pub fn new(model: &Assembled) -> Result<Self> {
        let nc = model.dofs.n_clamped();
        let k = block(&model.stiffness, 0..nc, 0..nc)?;
        let m = block(&model.mass, 0..nc, 0..nc)?;
        let b = flange_unit_loads(model);
        let rows = flange_unit_load_rows(model);
        let mut trip = Vec::new();
        for a in [&k, &m] {
            for j in 0..nc {
                for &i in a.row_idx_of_col_raw(j) {
                    trip.push(Triplet::new(i, j, 0.0f64));
                }
            }
        }
        let union = SparseColMat::<usize, f64>::try_new_from_triplets(nc, nc, &trip).map_err(|e| {
            BuildError::numerical(format!("pattern of K + M: {}", faer_error::creation(&e))).caused_by(e)
        })?;
        let pattern = union.symbolic().to_owned().map_err(|e| {
            BuildError::numerical(format!("pattern of K + M: {}", faer_error::generic(&e))).caused_by(e)
        })?;
        let slots = |a: &crate::linalg::sparse::Sparse| -> Vec<usize> {
            let mut out = Vec::with_capacity(a.val().len());
            for j in 0..nc {
                let start = union.symbolic().col_ptr()[j];
                let col = union.row_idx_of_col_raw(j);
                for &i in a.row_idx_of_col_raw(j) {
                    out.push(start + col.binary_search(&i).unwrap_or(0));
                }
            }
            out
        };
        let (k_slot, m_slot) = (slots(&k), slots(&m));
        let scale = (0..nc)
            .map(|j| {
                let d: f64 = k
                    .row_idx_of_col_raw(j)
                    .iter()
                    .zip(k.val_of_col(j))
                    .filter(|(i, _)| **i == j)
                    .map(|(_, v)| *v)
                    .sum();
                1.0 / d.abs().sqrt().max(1e-300)
            })
            .collect();
        Ok(Self { k, m, b, rows, pattern, k_slot, m_slot, scale, symbolic: None })
    }

    /// Flange FRF at `hz` (nb x nb).
    pub fn at(&mut self, damping: ComparisonDamping, hz: f64) -> Result<Mat<c64>> {
        let x = self.response(damping, hz)?;
        let rows = &self.rows;
        Ok(Mat::from_fn(rows.len(), rows.len(), |i, j| x[(rows[i], j)]))
    }

    /// The full model's response to each unit flange load at `hz` (n_clamped x nb).
    pub fn response(&mut self, damping: ComparisonDamping, hz: f64) -> Result<Mat<c64>> {
        let nc = self.k.nrows();
        let w = 2.0 * std::f64::consts::PI * hz;
        // K (1 + i eta) + i w (alpha M + beta K) - w^2 M, always with the same triplet order
        let k_coef = c64::new(1.0, damping.loss_factor + w * damping.beta);
        let m_coef = c64::new(-w * w, w * damping.alpha);
        let mut values = vec![c64::new(0.0, 0.0); self.pattern.row_idx().len()];
        for (a, coef, slots) in [(&self.k, k_coef, &self.k_slot), (&self.m, m_coef, &self.m_slot)] {
            // stored entries, column by column, in the order `slots` was built
            let mut e = 0;
            for j in 0..nc {
                for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                    values[slots[e]] += coef * (v * self.scale[i] * self.scale[j]);
                    e += 1;
                }
            }
        }
        let z = SparseColMat::<usize, c64>::new(self.pattern.clone(), values);
        if self.symbolic.is_none() {
            self.symbolic = Some(faer::sparse::linalg::solvers::SymbolicLu::try_new(z.symbolic()).map_err(|e| {
                BuildError::numerical(format!("symbolic LU: {}", faer_error::generic(&e))).caused_by(e)
            })?);
        }
        let symbolic = self.symbolic.clone().ok_or_else(|| BuildError::internal("symbolic LU missing"))?;
        let lu = faer::sparse::linalg::solvers::Lu::try_new_with_symbolic(symbolic, z.as_ref()).map_err(|e| {
            BuildError::numerical(format!("dynamic stiffness at {hz} Hz is {}", faer_error::lu(&e))).caused_by(e)
        })?;
        // Z = S^-1 Zs S^-1: x = S Zs^-1 S b
        let sc = &self.scale;
        let mut x = Mat::<c64>::from_fn(nc, self.b.ncols(), |i, j| c64::new(self.b[(i, j)] * sc[i], 0.0));
        lu.solve_in_place(x.as_mut());
        for j in 0..x.ncols() {
            for i in 0..nc {
                x[(i, j)] *= sc[i];
            }
        }
        // refinement on residuals with compensated K x and M x (the low-frequency dynamic
        // stiffness is as ill-conditioned as K): b - (k_coef K + m_coef M) x
        for _ in 0..2 {
            let re = Mat::<f64>::from_fn(nc, x.ncols(), |i, j| x[(i, j)].re);
            let im = Mat::<f64>::from_fn(nc, x.ncols(), |i, j| x[(i, j)].im);
            let (kr, ki) =
                (mul_compensated(None, 1.0, &self.k, re.as_ref()), mul_compensated(None, 1.0, &self.k, im.as_ref()));
            let (mr, mi) =
                (mul_compensated(None, 1.0, &self.m, re.as_ref()), mul_compensated(None, 1.0, &self.m, im.as_ref()));
            let mut r = Mat::<c64>::from_fn(nc, x.ncols(), |i, j| {
                let kx = c64::new(kr[(i, j)], ki[(i, j)]);
                let mx = c64::new(mr[(i, j)], mi[(i, j)]);
                c64::new(self.b[(i, j)], 0.0) - (k_coef * kx + m_coef * mx)
            });
            for j in 0..r.ncols() {
                for i in 0..nc {
                    r[(i, j)] *= sc[i];
                }
            }
            lu.solve_in_place(r.as_mut());
            for j in 0..r.ncols() {
                for i in 0..nc {
                    r[(i, j)] *= sc[i];
                }
            }
            x += &r;
        }
        Ok(x)
    }
}

/// The full model's flange FRF (nb x nb) at each of `freqs` in the band up to `top_hz`: the band
/// method where it applies (`band_response`), else a complex LU per frequency.
pub fn full_responses(
    model: &Assembled,
    solver: &dyn crate::linalg::sparse::SpdSolve,
    damping: ComparisonDamping,
    top_hz: f64,
    freqs: &[f64],
) -> Result<Vec<Mat<c64>>> {
    let rows = flange_unit_load_rows(model);
    match crate::reduce::band_response::BandResponse::new(
        model,
        solver,
        top_hz,
        damping,
        crate::reduce::band_response::Known::default(),
        crate::reduce::band_response::CUT,
    )? {
        Some(band) => Ok(freqs
            .iter()
            .map(|&f| {
                let (y, w) = band.coefficients(damping, f);
                band.rows_of(&rows, &y, &w)
            })
            .collect()),
        None => {
            let mut direct = FullResponse::new(model)?;
            freqs.iter().map(|&f| direct.at(damping, f)).collect()
        }
    }
}

/// The reduced model's modal receptances at `hz`: 1 / (lambda (1 + i eta) + i w d - w^2) per
/// mode, with the same Rayleigh damping projected (diagonal: Phi is M- and K-orthogonal).
fn modal_receptances(basis: &Basis, damping: ComparisonDamping, hz: f64) -> Vec<c64> {
    let w = 2.0 * std::f64::consts::PI * hz;
    (0..basis.omega.len())
        .map(|k| {
            let lambda = basis.omega[k] * basis.omega[k];
            let d = damping.alpha + damping.beta * lambda;
            c64::new(1.0, 0.0) / c64::new(lambda - w * w, lambda * damping.loss_factor + w * d)
        })
        .collect()
}

/// Reduced-model flange FRF at `hz`: Phi_b diag(receptances) Phi_b^T.
/// `rows`: the flange master DoFs (`flange_unit_load_rows`).
pub fn reduced_response(rows: &[usize], basis: &Basis, damping: ComparisonDamping, hz: f64) -> Mat<c64> {
    let r = basis.omega.len();
    let g = modal_receptances(basis, damping, hz);
    Mat::from_fn(rows.len(), rows.len(), |i, j| {
        let mut s = c64::new(0.0, 0.0);
        for k in 0..r {
            s += g[k] * (basis.phi[(rows[i], k)] * basis.phi[(rows[j], k)]);
        }
        s
    })
}

/// Full vs reduced over the band.
#[allow(clippy::too_many_arguments)]
pub fn compare(
    model: &Assembled,
    solver: &dyn crate::linalg::sparse::SpdSolve,
    basis: &Basis,
    damping: ComparisonDamping,
    band: [f64; 2],
    eigen_hz: &[f64],
    static_compliance: &[Vec<f64>],
    stress: Option<&StressProbe<'_>>,
    known: crate::reduce::band_response::Known<'_>,
    cut: f64,
) -> Result<FrequencyResponse> {
    let frequencies = grid(band, eigen_hz, 60);
    let scale: Vec<f64> =
        (0..static_compliance.len()).map(|i| 1.0 / static_compliance[i][i].abs().sqrt().max(1e-300)).collect();
    let mut relative_error = Vec::with_capacity(frequencies.len());
    let mut driving_point_full = Vec::new();
    let mut driving_point_reduced = Vec::new();
    let mut full_matrices = Vec::new();
    let mut stress_relative_error = Vec::new();
    let mut stress_full = Vec::new();
    let rows = flange_unit_load_rows(model);
    // the full model over the band: modes below twice its top exactly plus a Krylov projection
    // of the rest (one eigen-solve for the band), or, where too many modes lie below that, a
    // complex LU per frequency
    let fast = crate::reduce::band_response::BandResponse::new(model, solver, band[1], damping, known, cut)?;
    let mut direct = if fast.is_none() { Some(FullResponse::new(model)?) } else { None };
    // stresses are linear in the response: those of the fast path's columns, once
    let column_stresses = match (&fast, stress) {
        (Some(f), Some(probe)) => Some((probe.full)(f.columns().as_ref())?),
        _ => None,
    };
    let method = method(fast.as_ref(), cut, band);
    for (i, &f) in frequencies.iter().enumerate() {
        phases::step(|| format!("{} of {} frequencies ({f:.4} Hz)", i + 1, frequencies.len()));
        let (full, full_stress) =
            full_response(fast.as_ref(), direct.as_mut(), column_stresses.as_deref(), stress, &rows, damping, f)?;
        if let (Some(probe), Some(fs)) = (stress, &full_stress) {
            let (error, kept) = stress_responses(probe, fs, &rows, basis, damping, f);
            stress_relative_error.push(error);
            stress_full.push(kept);
        }
        let red = reduced_response(&rows, basis, damping, f);
        relative_error.push(scaled_relative_error(&full, &red, &scale));
        driving_point_full.push((0..full.nrows()).map(|i| full[(i, i)].norm()).collect());
        driving_point_reduced.push((0..red.nrows()).map(|i| red[(i, i)].norm()).collect());
        full_matrices.push(re_im_entries(&full));
    }
    let max_relative_error = relative_error.iter().copied().fold(0.0, f64::max);
    Ok(FrequencyResponse {
        band_hz: band,
        damping,
        frequencies_hz: frequencies,
        relative_error,
        max_relative_error,
        driving_point_full,
        driving_point_reduced,
        full_matrices,
        stress_relative_error,
        stress_full,
        method,
    })
}

/// How the full model's responses were computed, for the report.
fn method(fast: Option<&crate::reduce::band_response::BandResponse<'_>>, cut: f64, band: [f64; 2]) -> String {
    match fast {
        Some(f) => format!(
            "{} full modes below {:.4} Hz exactly, the rest by {} Krylov blocks of the complement",
            f.modes,
            cut * band[1],
            f.blocks
        ),
        None => "a complex sparse LU of the full model per frequency".to_string(),
    }
}

/// Complex stresses at the probe's points, point-major (point, load).
type PointStresses = Vec<[c64; 6]>;

/// The full model's flange responses at `f` Hz and their stresses at the probe's points: from
/// the band's modes and Krylov blocks (`fast`) where they were computed, else a complex LU.
fn full_response(
    fast: Option<&crate::reduce::band_response::BandResponse<'_>>,
    direct: Option<&mut FullResponse>,
    column_stresses: Option<&[[f64; 6]]>,
    stress: Option<&StressProbe<'_>>,
    rows: &[usize],
    damping: ComparisonDamping,
    f: f64,
) -> Result<(Mat<c64>, Option<PointStresses>)> {
    Ok(match (fast, direct) {
        (Some(fr), _) => {
            let (y, w) = fr.coefficients(damping, f);
            let full = fr.rows_of(rows, &y, &w);
            let s = column_stresses.map(|cs| combine_stresses(cs, &y, &w));
            (full, s)
        }
        (None, Some(d)) => {
            let x = d.response(damping, f)?;
            let full = Mat::from_fn(rows.len(), rows.len(), |i, j| x[(rows[i], j)]);
            let s = match stress {
                Some(probe) => Some(stresses_of_complex(probe, &x)?),
                None => None,
            };
            (full, s)
        }
        (None, None) => unreachable!("one of the two is built"),
    })
}

/// |full - reduced| / |full| in the Frobenius norm, each entry scaled by the static compliances
/// of its row and column (so every flange direction weighs alike).
fn scaled_relative_error(full: &Mat<c64>, red: &Mat<c64>, scale: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..full.nrows() {
        for j in 0..full.ncols() {
            let s = scale[i] * scale[j];
            num += ((full[(i, j)] - red[(i, j)]) * s).norm_sqr();
            den += (full[(i, j)] * s).norm_sqr();
        }
    }
    if den > 0.0 { (num / den).sqrt() } else { 0.0 }
}

/// The matrix's entries row by row as [re, im].
fn re_im_entries(full: &Mat<c64>) -> Vec<[f64; 2]> {
    (0..full.nrows() * full.ncols())
        .map(|e| {
            let z = full[(e / full.ncols(), e % full.ncols())];
            [z.re, z.im]
        })
        .collect()
}

/// Stresses at the probe's points of a complex response x (n x nb): point-major (point, load).
fn stresses_of_complex(probe: &StressProbe<'_>, x: &Mat<c64>) -> Result<Vec<[c64; 6]>> {
    let nb = x.ncols();
    let re = Mat::<f64>::from_fn(x.nrows(), nb, |i, j| x[(i, j)].re);
    let im = Mat::<f64>::from_fn(x.nrows(), nb, |i, j| x[(i, j)].im);
    let (s_re, s_im) = ((probe.full)(re.as_ref())?, (probe.full)(im.as_ref())?);
    Ok(s_re.iter().zip(&s_im).map(|(r, i)| std::array::from_fn(|c| c64::new(r[c], i[c]))).collect())
}

/// Stresses of x = [Phi Q] [y; w] from those of the columns (points x (k + m), point-major).
fn combine_stresses(columns: &[[f64; 6]], y: &Mat<c64>, w: &Mat<c64>) -> Vec<[c64; 6]> {
    let (k, m, nb) = (y.nrows(), w.nrows(), y.ncols());
    let per_point = k + m;
    let points = columns.len().checked_div(per_point).unwrap_or(0);
    let mut out = vec![[c64::new(0.0, 0.0); 6]; points * nb];
    for p in 0..points {
        for j in 0..nb {
            let o = &mut out[p * nb + j];
            for col in 0..per_point {
                let coef = if col < k { y[(col, j)] } else { w[(col - k, j)] };
                let s = &columns[p * per_point + col];
                for c in 0..6 {
                    o[c] += coef * s[c];
                }
            }
        }
    }
    out
}

/// The stress responses at the probe's points, full (from the full response `x`) against
/// reduced (stress modes times modal receptances times Phi_b^T): the relative error over all,
/// and the full responses of the first `STRESS_FRF_POINTS` points as [re, im].
fn stress_responses(
    probe: &StressProbe<'_>,
    full_stress: &[[c64; 6]],
    rows: &[usize],
    basis: &Basis,
    damping: ComparisonDamping,
    hz: f64,
) -> (f64, Vec<[f64; 2]>) {
    let nb = rows.len();
    let g = modal_receptances(basis, damping, hz);
    let r = g.len();
    let (mut num, mut den) = (0.0, 0.0);
    let mut kept = Vec::new();
    for (p, modes) in probe.modes.iter().enumerate() {
        for c in 0..6 {
            for j in 0..nb {
                let mut red = c64::new(0.0, 0.0);
                for k in 0..r {
                    red += g[k] * (modes[c * r + k] * basis.phi[(rows[j], k)]);
                }
                let full = full_stress[p * nb + j][c];
                num += (full - red).norm_sqr();
                den += full.norm_sqr();
                if p < STRESS_FRF_POINTS {
                    kept.push([full.re, full.im]);
                }
            }
        }
    }
    (if den > 0.0 { (num / den).sqrt() } else { 0.0 }, kept)
}
