//! Saddle-point systems of an assembly solved with the bodies' modes condensed out first.
//!
//! In the iteration matrix and the index-1 matrix a flexible body's modal rows are
//! `C_t^T R^T a + C_r^T w' + d_k q''_k`: each mode meets the other unknowns only through its own
//! frame and the joints at its flanges, never another mode (mass-normalised modes; the
//! gyroscopic terms are not in these matrices). With the modes E and the rest R (the frames'
//! slots and the joints' multipliers), K_EE is diagonal, so
//!
//! ```text
//! S = K_RR - K_RE D^-1 K_ER,   S x_R = b_R - K_RE D^-1 b_E,   x_E = D^-1 (b_E - K_ER x_R)
//! ```
//!
//! is exact: two links of 18 modes leave 22 unknowns of 58 (LU work ~ r^3: a twentieth), and
//! each solve touches only the non-zeros of the modes' rows and columns. A matrix whose
//! eliminated block is not diagonal (the finite-difference one) takes the dense LU of the whole.
//! Every buffer is allocated when the condensation is made.

use crate::body::dense::{lu_factor, lu_solve};

#[derive(Debug, Clone)]
pub struct Condensation {
    dim: usize,
    /// The slots condensed out (E) and the rest (R), in the full system's numbering; slots in
    /// neither are left out (their rows and columns are not read, their solution is 0).
    eliminated: Vec<usize>,
    kept: Vec<usize>,
    /// Every slot not left out, in order.
    taken: Vec<usize>,
    left_out: Vec<usize>,
    /// 1 / K_ee per eliminated slot.
    inv_d: Vec<f64>,
    /// Per eliminated slot, K_Re (column) and K_eR (row) over R: |E| x |R| each.
    column: Vec<f64>,
    row: Vec<f64>,
    /// S's factors (|R| x |R|) or, where the block is not diagonal, the whole matrix's.
    factors: Vec<f64>,
    pivots: Vec<usize>,
    dense: bool,
    scratch: Vec<f64>,
}

impl Condensation {
    /// A condensation of a `dim` x `dim` system that eliminates `eliminated` where it can.
    pub fn new(dim: usize, eliminated: Vec<usize>) -> Self {
        Self::without(dim, eliminated, &[])
    }

    /// [`Self::new`] of the system without the slots `left_out` (a mode without inertia in the
    /// index-1 system: no row, no column, no acceleration).
    pub fn without(dim: usize, eliminated: Vec<usize>, left_out: &[usize]) -> Self {
        let kept: Vec<usize> = (0..dim).filter(|i| !eliminated.contains(i) && !left_out.contains(i)).collect();
        let taken: Vec<usize> = (0..dim).filter(|i| !left_out.contains(i)).collect();
        let (e, r) = (eliminated.len(), kept.len());
        Self {
            dim,
            inv_d: vec![0.0; e],
            column: vec![0.0; e * r],
            row: vec![0.0; e * r],
            factors: vec![0.0; dim * dim],
            pivots: vec![0; dim],
            dense: false,
            scratch: vec![0.0; dim],
            eliminated,
            kept,
            taken,
            left_out: left_out.to_vec(),
        }
    }

    /// Factor `matrix` (row-major `dim` x `dim`, left as it is); Err on a singular one.
    pub fn factor(&mut self, matrix: &[f64]) -> Result<(), ()> {
        let n = self.dim;
        self.dense = !self.eliminated.iter().all(|&i| {
            let d = matrix[i * n + i];
            d.is_finite() && d != 0.0 && self.eliminated.iter().all(|&j| j == i || matrix[i * n + j] == 0.0)
        });
        if self.dense {
            // the rows and columns of the slots not left out
            let m = self.taken.len();
            for (a, &i) in self.taken.iter().enumerate() {
                for (b, &j) in self.taken.iter().enumerate() {
                    self.factors[a * m + b] = matrix[i * n + j];
                }
            }
            return lu_factor(&mut self.factors[..m * m], m, &mut self.pivots[..m]);
        }
        let r = self.kept.len();
        for (a, &i) in self.kept.iter().enumerate() {
            for (b, &j) in self.kept.iter().enumerate() {
                self.factors[a * r + b] = matrix[i * n + j];
            }
        }
        for (e, &k) in self.eliminated.iter().enumerate() {
            let inv = 1.0 / matrix[k * n + k];
            self.inv_d[e] = inv;
            let (column, row) = (&mut self.column[e * r..(e + 1) * r], &mut self.row[e * r..(e + 1) * r]);
            for (a, &i) in self.kept.iter().enumerate() {
                column[a] = matrix[i * n + k];
                row[a] = matrix[k * n + i];
            }
            // S -= K_Re K_eR / d over the non-zeros
            for (a, &c) in column.iter().enumerate() {
                if c != 0.0 {
                    let f = c * inv;
                    let s = &mut self.factors[a * r..(a + 1) * r];
                    for (x, &y) in s.iter_mut().zip(row.iter()) {
                        *x -= f * y;
                    }
                }
            }
        }
        lu_factor(&mut self.factors[..r * r], r, &mut self.pivots[..r])
    }

    /// b = K^-1 b in place, from [`Self::factor`]'s factors.
    pub fn solve(&mut self, b: &mut [f64]) {
        for &i in &self.left_out {
            b[i] = 0.0;
        }
        if self.dense {
            let m = self.taken.len();
            let x = &mut self.scratch[..m];
            for (a, &i) in self.taken.iter().enumerate() {
                x[a] = b[i];
            }
            lu_solve(&self.factors[..m * m], m, &self.pivots[..m], x);
            for (a, &i) in self.taken.iter().enumerate() {
                b[i] = x[a];
            }
            return;
        }
        let r = self.kept.len();
        let x = &mut self.scratch[..r];
        for (a, &i) in self.kept.iter().enumerate() {
            x[a] = b[i];
        }
        for (e, &k) in self.eliminated.iter().enumerate() {
            let f = b[k] * self.inv_d[e];
            if f != 0.0 {
                for (xa, &c) in x.iter_mut().zip(&self.column[e * r..(e + 1) * r]) {
                    *xa -= c * f;
                }
            }
        }
        lu_solve(&self.factors[..r * r], r, &self.pivots[..r], x);
        for (a, &i) in self.kept.iter().enumerate() {
            b[i] = x[a];
        }
        for (e, &k) in self.eliminated.iter().enumerate() {
            let row = &self.row[e * r..(e + 1) * r];
            let s: f64 = row.iter().zip(x.iter()).map(|(p, q)| p * q).sum();
            b[k] = (b[k] - s) * self.inv_d[e];
        }
    }

    /// Whether the last factorisation condensed (false: it took the dense LU).
    #[cfg(test)]
    pub fn condensed(&self) -> bool {
        !self.dense
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A saddle-point matrix of two arrow blocks (frames 0..2 and 4..6, modes 2..4 and 6..8)
    /// and two constraint rows; against the dense LU of the same.
    fn example() -> Vec<f64> {
        let n = 10;
        let mut k = vec![0.0; n * n];
        let mut put = |i: usize, j: usize, v: f64| k[i * n + j] = v;
        for (f, m) in [(0, 2), (4, 6)] {
            put(f, f, 4.0);
            put(f + 1, f + 1, 5.0);
            put(f, f + 1, 0.5);
            put(f + 1, f, 0.5);
            for k in 0..2 {
                put(m + k, m + k, 1.5 + k as f64);
                put(f, m + k, 0.3 + 0.1 * k as f64);
                put(m + k, f, 0.2 - 0.1 * k as f64);
                put(f + 1, m + k, -0.4);
                put(m + k, f + 1, 0.25);
            }
        }
        // joints: frame 0 to frame 1, mode 3 to mode 6
        for (row, cols) in [(8, [(0, 1.0), (4, -1.0), (3, 0.2)]), (9, [(1, 1.0), (5, -1.0), (6, 0.3)])] {
            for (j, b) in cols {
                put(row, j, b);
                put(j, row, -b);
            }
        }
        k
    }

    #[test]
    fn condensing_the_modes_solves_as_the_dense_lu_does() {
        let n = 10;
        let k = example();
        let mut c = Condensation::new(n, vec![2, 3, 6, 7]);
        c.factor(&k).unwrap();
        assert!(c.condensed());
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.1).collect();
        let mut x = b.clone();
        c.solve(&mut x);
        let (mut dense, mut pivots, mut y) = (k.clone(), vec![0; n], b.clone());
        lu_factor(&mut dense, n, &mut pivots).unwrap();
        lu_solve(&dense, n, &pivots, &mut y);
        for i in 0..n {
            assert!((x[i] - y[i]).abs() <= 1e-13, "{i}: {} against {}", x[i], y[i]);
        }
        // and K x = b
        for i in 0..n {
            let s: f64 = (0..n).map(|j| k[i * n + j] * x[j]).sum();
            assert!((s - b[i]).abs() <= 1e-13);
        }
    }

    #[test]
    fn a_slot_left_out_is_neither_read_nor_solved_for() {
        let n = 10;
        let k = example();
        // slot 7 left out: its row and column replaced by garbage the condensation must not read
        let mut garbage = k.clone();
        for i in 0..n {
            garbage[7 * n + i] = f64::NAN;
            garbage[i * n + 7] = f64::NAN;
        }
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        // the reference: the dense LU of the system without slot 7
        let taken: Vec<usize> = (0..n).filter(|&i| i != 7).collect();
        let m = taken.len();
        let mut dense: Vec<f64> =
            taken.iter().flat_map(|&i| taken.iter().map(move |&j| (i, j))).map(|(i, j)| k[i * n + j]).collect();
        let mut y: Vec<f64> = taken.iter().map(|&i| b[i]).collect();
        let mut pivots = vec![0; m];
        lu_factor(&mut dense, m, &mut pivots).unwrap();
        lu_solve(&dense, m, &pivots, &mut y);
        for eliminated in [vec![2, 3, 6], vec![]] {
            let mut c = Condensation::without(n, eliminated.clone(), &[7]);
            c.factor(&garbage).unwrap();
            assert!(c.condensed());
            let mut x = b.clone();
            c.solve(&mut x);
            assert_eq!(x[7], 0.0);
            for (a, &i) in taken.iter().enumerate() {
                assert!((x[i] - y[a]).abs() <= 1e-13, "{eliminated:?}: slot {i}");
            }
        }
    }

    #[test]
    fn a_coupled_modal_block_takes_the_dense_lu() {
        let n = 10;
        let mut k = example();
        k[2 * n + 3] = 0.1;
        let mut c = Condensation::new(n, vec![2, 3, 6, 7]);
        c.factor(&k).unwrap();
        assert!(!c.condensed());
        let b = vec![1.0; n];
        let mut x = b.clone();
        c.solve(&mut x);
        for i in 0..n {
            let s: f64 = (0..n).map(|j| k[i * n + j] * x[j]).sum();
            assert!((s - b[i]).abs() <= 1e-13);
        }
    }
}
