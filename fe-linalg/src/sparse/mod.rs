//! Sparse helpers over faer: leading blocks, symmetric products and a factor-once solver.

mod blocks;
mod compensated_product;
mod lu;
mod products;
mod spd_solve;
mod spd_solver;

pub use blocks::{add_scaled, block};
pub use compensated_product::mul_compensated;
pub use lu::LuSolver;
pub use products::{mul, mul_leading, mul_new};
pub use spd_solve::SpdSolve;
pub use spd_solver::SpdSolver;

use faer::sparse::SparseColMat;

pub type Sparse = SparseColMat<usize, f64>;

#[cfg(test)]
mod tests {
    /// A chain of 50 rows, row 37 indefinite: whatever order the factorisation chooses, every
    /// other pivot stays positive, so the failure maps back to row 37.
    #[test]
    fn the_failing_pivot_is_found_in_the_matrix_order() {
        use faer::sparse::{SparseColMat, Triplet};
        let chain = |bad: Option<usize>| {
            let mut t = Vec::new();
            for i in 0..50 {
                t.push(Triplet::new(i, i, if Some(i) == bad { -1.0 } else { 4.0 }));
                if i + 1 < 50 {
                    t.push(Triplet::new(i, i + 1, 1.0));
                    t.push(Triplet::new(i + 1, i, 1.0));
                }
            }
            SparseColMat::try_new_from_triplets(50, 50, &t).unwrap()
        };
        let failure = |a| match super::SpdSolver::new(std::borrow::Cow::Owned(a), "test", &|d| format!("row {d}.")) {
            Ok(_) => "factored".to_string(),
            Err(e) => e.to_string(),
        };
        assert!(failure(chain(Some(37))).contains("fails at row 37."), "{}", failure(chain(Some(37))));
        assert_eq!(failure(chain(None)), "factored");
        // a 3D grid (supernodal factor, reordered): every principal block without the bad row is
        // diagonally dominant, so the failure is that row whatever the order
        let grid = crate::test_grids::laplacian(12, |i| if i == 1000 { -100.0 } else { 7.0 });
        assert!(failure(grid.clone()).contains("fails at row 1000."), "{}", failure(grid));
    }

    /// A symmetric matrix with an irregular pattern: entry (i, j) where (i * j + i + j) % 7 < 2.
    fn symmetric(n: usize) -> super::Sparse {
        use faer::sparse::{SparseColMat, Triplet};
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..=i {
                if i == j || (i * j + i + j) % 7 < 2 {
                    let v = ((i * 13 + j * 31) % 17) as f64 / 7.0 - 1.1 + if i == j { 5.0 } else { 0.0 };
                    t.push(Triplet::new(i, j, v));
                    if i != j {
                        t.push(Triplet::new(j, i, v));
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// `symmetric_product`'s gather form against the general scatter products on every group width (1 to 37 columns,
    /// with and without C, both signs): the plain sums differ only in their order (round-off of
    /// 1e-15 relative), the compensated ones are exact to the last bit in both (double-double
    /// sums rounded once).
    #[test]
    fn gather_products_equal_the_general_ones() {
        use crate::symmetric_product;
        use faer::Mat;
        let n = 90;
        let a = symmetric(n);
        for k in [1, 2, 3, 5, 8, 9, 16, 17, 26, 37] {
            let x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 3 + j * 11) % 23) as f64 / 3.0 - 3.3);
            let c = Mat::<f64>::from_fn(n, k, |i, j| (i as f64 - j as f64) / 9.0);
            let plain = symmetric_product::mul_new(&a, x.as_ref());
            let general = super::mul_new(&a, x.as_ref());
            assert_eq!((plain.nrows(), plain.ncols()), (general.nrows(), general.ncols()));
            let scale = general.norm_max();
            assert!((&plain - &general).norm_max() <= 1e-14 * scale, "{k} columns");
            for (sign, cc) in [(1.0, None), (-1.0, Some(c.as_ref()))] {
                let fast = symmetric_product::mul_compensated(cc, sign, &a, x.as_ref());
                let general = super::mul_compensated(cc, sign, &a, x.as_ref());
                assert_eq!((fast.nrows(), fast.ncols()), (general.nrows(), general.ncols()));
                for j in 0..k {
                    for i in 0..n {
                        // both exact to double-double before one rounding: equal unless the exact
                        // sum lies within 1e-32 of a rounding boundary (none does here)
                        assert_eq!(fast[(i, j)].to_bits(), general[(i, j)].to_bits(), "({i}, {j}) of {k}");
                    }
                }
            }
        }
    }

    /// On a 3D grid (a supernodal factor in nested-dissection order) the split solve equals
    /// faer's own solve through the same factor to round-off, for one and for many right-hand
    /// sides, and its solution satisfies A x = b (consistency with faer's solve and with the
    /// matrix itself; the physics of the solves is checked against CalculiX in the Python tests).
    #[test]
    fn split_solves_equal_the_whole_tree_solve() {
        use super::SpdSolver;
        use crate::tree_solve::TreeSolve;
        use faer::Mat;
        let a = crate::test_grids::laplacian(16, |i| 6.0 + 1e-3 * (i % 7) as f64);
        let n = a.nrows();
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Borrowed(&a), "grid", &name).unwrap();
        let (symbolic, values) = solver.factor().unwrap();
        let tree = TreeSolve::new(symbolic, 2).expect("a grid's tree splits between two threads");
        let parts = tree.subtrees_per_thread();
        assert_eq!(parts.len(), 2);
        assert!(parts.iter().all(|&p| p > 0), "both threads get subtrees");
        for k in [1, 9, 46] {
            let b = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + 3 * j) % 11) as f64 - 5.0);
            let mut split = b.clone();
            tree.solve(symbolic, values, split.as_mut());
            let mut whole = b.clone();
            solver.solve_whole_tree(whole.as_mut());
            assert_eq!((split.nrows(), split.ncols()), (whole.nrows(), whole.ncols()));
            let scale = whole.norm_max();
            // the same arithmetic in another order: round-off (measured 1e-16 of the solution)
            assert!((&split - &whole).norm_max() <= 1e-13 * scale, "{k} right-hand sides");
            let residual = &b - crate::symmetric_product::mul_new(&a, split.as_ref());
            assert!(residual.norm_max() <= 1e-12 * b.norm_max(), "A x = b for {k} right-hand sides");
        }
    }

    /// The compensated product in groups, on threads and with FMA equals the plain Dekker route
    /// bit for bit (both form the exact product errors), and recovers a sum that cancels to 1
    /// out of terms of 1e16, which plain double sums lose entirely.
    #[test]
    fn compensated_product_is_exact_in_every_route() {
        use faer::Mat;
        use faer::sparse::{SparseColMat, Triplet};
        let n = 40;
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..n {
                if (i * 7 + j * 3) % 5 == 0 {
                    t.push(Triplet::new(i, j, ((i * 13 + j * 31) % 17) as f64 / 7.0 - 1.1));
                }
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap();
        let x = Mat::<f64>::from_fn(n, 19, |i, j| ((i * 3 + j * 11) % 23) as f64 / 3.0 - 3.3);
        let c = Mat::<f64>::from_fn(n, 19, |i, j| (i as f64 - j as f64) / 9.0);
        let fast = super::mul_compensated(Some(c.as_ref()), -1.0, &a, x.as_ref());
        assert_eq!((fast.nrows(), fast.ncols()), (n, 19));
        // every column on its own, width 1 without FMA: the grouping and the vector width change
        // nothing
        for first in 0..19 {
            let w = 1;
            let plain = super::compensated_product::compensated_generic::<false, 1>(
                Some(c.as_ref().subcols(first, w)),
                -1.0,
                &a,
                x.as_ref().subcols(first, w),
            );
            for j in 0..w {
                for i in 0..n {
                    assert_eq!(fast[(i, first + j)].to_bits(), plain[(i, j)].to_bits());
                }
            }
        }
        let row = SparseColMat::<usize, f64>::try_new_from_triplets(
            1,
            3,
            &[Triplet::new(0, 0, 1e16), Triplet::new(0, 1, 1.0), Triplet::new(0, 2, -1e16)],
        )
        .unwrap();
        let ones = Mat::<f64>::from_fn(3, 1, |_, _| 1.0);
        assert_eq!(super::mul_compensated(None, 1.0, &row, ones.as_ref())[(0, 0)], 1.0);
    }
}
