//! Choosing the reduced order from the scene: from a rich reduced model (orthonormal modes
//! Lambda, Phi) keep the modes that dominate the flange transfer functions, |phi_b,k|^2 /
//! (2 zeta_k w_k^2) for the connected flanges (docs/REFERENCES.md section 4: dominance beats keeping
//! the lowest), plus the residual flexibility of the rest (the static response of the dropped
//! modes to flange and inertial loads, Rayleigh-Ritz'ed among themselves), so statics stay exact.
//! The smallest selection whose flange FRF error against the full model stays under the
//! tolerance over the band wins. All of it happens in the rich model's coordinates: no sparse
//! work beyond the full-model responses computed once.

use crate::linalg::symmetric_eigen::symmetric_eigen;
use crate::reduce::frf::ComparisonDamping;
use faer::{Mat, c64};

/// A selection in the rich model's coordinates: columns Y (r_rich x r_sel, orthonormal) and the
/// selected model's frequencies (Y^T Lambda Y = diag(omega^2)).
pub struct Selection {
    pub y: Mat<f64>,
    pub omega: Vec<f64>,
    pub kept_modes: usize,
}

/// Order the rich modes by dominance over the band (largest first): the mode's largest dynamic
/// contribution to the flange transfer functions beyond its static part, which the residual
/// flexibility keeps anyway: |phi_b,k|^2 max_w |1/(w_k^2 - w^2 + i w d_k) - 1/w_k^2|. For a mode
/// in the band this is the classic |c_k||b_k|/(2 zeta_k w_k^2); far above it, nearly nothing.
pub fn dominance_order(omega: &[f64], phi_b: &Mat<f64>, damping: ComparisonDamping, freqs_hz: &[f64]) -> Vec<usize> {
    let score = |k: usize| -> f64 {
        let w = omega[k];
        let l = w * w;
        let d = damping.alpha + damping.beta * l;
        let gain: f64 = (0..phi_b.nrows()).map(|i| phi_b[(i, k)] * phi_b[(i, k)]).sum();
        let dynamic = freqs_hz
            .iter()
            .map(|f| {
                let x = 2.0 * std::f64::consts::PI * f;
                let g = c64::new(1.0, 0.0) / c64::new(l - x * x, l * damping.loss_factor + x * d);
                (g - c64::new(1.0 / l, 0.0)).norm()
            })
            .fold(0.0f64, f64::max);
        gain * dynamic
    };
    let mut idx: Vec<usize> = (0..omega.len()).collect();
    idx.sort_by(|&a, &b| score(b).total_cmp(&score(a)));
    idx
}

/// The selection keeping `kept` (indices into the rich modes) plus the residual static response
/// of the others to the loads `loads` (r_rich x l: generalized loads Phi^T f in rich coordinates).
pub fn select(omega: &[f64], kept: &[usize], loads: &Mat<f64>) -> Selection {
    let r = omega.len();
    let dropped: Vec<usize> = (0..r).filter(|k| !kept.contains(k)).collect();
    // residual static shapes: Lambda^-1 p on the dropped modes only
    let mut residual = Mat::<f64>::zeros(r, loads.ncols());
    for &k in &dropped {
        for j in 0..loads.ncols() {
            residual[(k, j)] = loads[(k, j)] / (omega[k] * omega[k]);
        }
    }
    // orthonormal basis of the residual span (identity mass), dropping dependent directions
    let gram = residual.transpose() * &residual;
    let mut extra: Vec<(Vec<f64>, f64)> = Vec::new();
    if gram.nrows() > 0 {
        let evd = symmetric_eigen(&gram, "the residual static shapes").ok();
        if let Some(evd) = evd {
            let s = &evd.values;
            let u = &evd.vectors;
            let largest = (0..gram.nrows()).map(|i| s[i]).fold(0.0f64, f64::max);
            let mut w = Vec::new();
            for i in 0..gram.nrows() {
                if s[i] > 1e-12 * largest {
                    let col = &residual * u.col(i).as_mat();
                    let norm = s[i].sqrt();
                    w.push((0..r).map(|k| col[(k, 0)] / norm).collect::<Vec<f64>>());
                }
            }
            // Rayleigh-Ritz of the residual block with K = Lambda
            let nw = w.len();
            let kw = Mat::<f64>::from_fn(nw, nw, |a, b| (0..r).map(|k| w[a][k] * omega[k] * omega[k] * w[b][k]).sum());
            if nw > 0
                && let Ok(e) = symmetric_eigen(&kw, "the residual stiffness")
            {
                let (ks, ku) = (&e.values, &e.vectors);
                for c in 0..nw {
                    let v: Vec<f64> = (0..r).map(|k| (0..nw).map(|a| w[a][k] * ku[(a, c)]).sum()).collect();
                    extra.push((v, ks[c].max(0.0).sqrt()));
                }
            }
        }
    }
    let n = kept.len() + extra.len();
    let mut y = Mat::<f64>::zeros(r, n);
    let mut sel: Vec<(usize, f64)> = Vec::with_capacity(n);
    for (c, &k) in kept.iter().enumerate() {
        y[(k, c)] = 1.0;
        sel.push((c, omega[k]));
    }
    for (e, (v, w)) in extra.iter().enumerate() {
        let c = kept.len() + e;
        for k in 0..r {
            y[(k, c)] = v[k];
        }
        sel.push((c, *w));
    }
    // ascending frequency
    sel.sort_by(|a, b| a.1.total_cmp(&b.1));
    let y_sorted = Mat::from_fn(r, n, |k, c| y[(k, sel[c].0)]);
    Selection { y: y_sorted, omega: sel.iter().map(|s| s.1).collect(), kept_modes: kept.len() }
}

/// Flange FRF error of a selection against full-model responses `full` at `freqs_hz`
/// (same unit-free scaling as the report).
pub fn frf_error(
    sel: &Selection,
    phi_b: &Mat<f64>,
    damping: ComparisonDamping,
    freqs_hz: &[f64],
    full: &[Mat<c64>],
    scale: &[f64],
) -> f64 {
    let shapes = phi_b * &sel.y; // nb x r_sel
    let mut worst = 0.0f64;
    for (f, h) in freqs_hz.iter().zip(full) {
        let w = 2.0 * std::f64::consts::PI * f;
        let g: Vec<c64> = sel
            .omega
            .iter()
            .map(|&om| {
                let l = om * om;
                let d = damping.alpha + damping.beta * l;
                c64::new(1.0, 0.0) / c64::new(l - w * w, l * damping.loss_factor + w * d)
            })
            .collect();
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..h.nrows() {
            for j in 0..h.ncols() {
                let mut red = c64::new(0.0, 0.0);
                for k in 0..g.len() {
                    red += g[k] * (shapes[(i, k)] * shapes[(j, k)]);
                }
                let s = scale[i] * scale[j];
                num += ((h[(i, j)] - red) * s).norm_sqr();
                den += (h[(i, j)] * s).norm_sqr();
            }
        }
        if den > 0.0 {
            worst = worst.max((num / den).sqrt());
        }
    }
    worst
}
