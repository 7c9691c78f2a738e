//! The congruence T^T A T of a sparse matrix under a DoF map T whose rows have few terms (the
//! rigid coupling's: a free DoF keeps one image, a slave DoF becomes u + theta x d; a
//! distributing coupling's six dependent DoFs have many),
//! computed column by column of the result on all cores, then made exactly symmetric in place.
//! Nothing proportional to the sum of all products is held: the result's pattern is counted
//! first, then filled.

use crate::error::{BuildError, Result};
use crate::linalg::faer_error;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use std::ops::Range;

/// Where each DoF of A goes: its (DoF of the result, coefficient) terms, row by row of the map
/// T (compressed): one for a free DoF, up to three for a rigid flange's node (u + theta x d),
/// a distributing flange's whole node set for its six dependent DoFs.
#[derive(Debug, Clone)]
pub(crate) struct Images {
    first: Vec<usize>,
    terms: Vec<(usize, f64)>,
}

impl Images {
    pub(crate) fn with_capacity(dofs: usize) -> Self {
        let mut first = Vec::with_capacity(dofs + 1);
        first.push(0);
        Self { first, terms: Vec::with_capacity(dofs) }
    }

    /// Appends the next DoF's image.
    pub(crate) fn push(&mut self, terms: impl IntoIterator<Item = (usize, f64)>) {
        self.terms.extend(terms);
        self.first.push(self.terms.len());
    }

    pub(crate) fn len(&self) -> usize {
        self.first.len() - 1
    }

    pub(crate) fn of(&self, i: usize) -> &[(usize, f64)] {
        &self.terms[self.first[i]..self.first[i + 1]]
    }

    fn all_terms(&self) -> &[(usize, f64)] {
        &self.terms
    }
}

/// Columns of the result per parallel task: enough to amortise the task, few enough to balance
/// the heavy master columns against the rest.
const COLUMNS_PER_TASK: usize = 512;

/// T^T A T (n x n) for the map with rows `images`, with mirrored entries equal to the bit:
/// (B + B^T) / 2 of the product B. Summation order leaves B with round-off asymmetry, and an
/// exported matrix read back by another solver (mirrored from one triangle) must be the very
/// matrix we factor. `what` names the matrix in errors.
pub(crate) fn symmetric_congruence(
    a: &SparseColMat<usize, f64>,
    images: &Images,
    n: usize,
    what: &str,
) -> Result<SparseColMat<usize, f64>> {
    if a.nrows() != images.len() || a.ncols() != images.len() {
        return Err(BuildError::internal(format!(
            "coupling the {what}: the matrix is {} x {} but the coupling maps {} DoFs",
            a.nrows(),
            a.ncols(),
            images.len()
        )));
    }
    if let Some(&(g, _)) = images.all_terms().iter().find(|(g, _)| *g >= n) {
        return Err(BuildError::internal(format!("coupling the {what}: DoF {g} beyond the {n} coupled DoFs")));
    }
    let preimages = Preimages::of(images, n);
    let product = Product { a, images, sole: sole_images(images, &preimages), preimages: &preimages };
    symmetric_product(&product, what)
}

/// The transpose of the map: for each DoF of the result, the DoFs of A mapped onto it with their
/// coefficients, ascending (the order the products are summed in).
struct Preimages {
    first: Vec<usize>,
    terms: Vec<(usize, f64)>,
}

impl Preimages {
    fn of(images: &Images, n: usize) -> Self {
        let mut first = vec![0; n + 1];
        for &(g, _) in images.all_terms() {
            first[g + 1] += 1;
        }
        for g in 0..n {
            first[g + 1] += first[g];
        }
        let mut next = first.clone();
        let mut terms = vec![(0, 0.0); first[n]];
        for i in 0..images.len() {
            for &(g, c) in images.of(i) {
                terms[next[g]] = (i, c);
                next[g] += 1;
            }
        }
        Self { first, terms }
    }

    fn of_dof(&self, g: usize) -> &[(usize, f64)] {
        &self.terms[self.first[g]..self.first[g + 1]]
    }
}

/// A DoF of A whose image is one term onto a DoF of the result that nothing else maps to (a
/// free node's DoF under the rigid coupling): its products land in distinct rows and need no
/// accumulation.
#[derive(Clone, Copy)]
struct SoleImage {
    dof: usize,
    coefficient: f64,
}

const SHARED: SoleImage = SoleImage { dof: usize::MAX, coefficient: 0.0 };

fn sole_images(images: &Images, preimages: &Preimages) -> Vec<SoleImage> {
    let sole = |i: usize| match images.of(i) {
        &[(dof, coefficient)] if preimages.of_dof(dof).len() == 1 => SoleImage { dof, coefficient },
        _ => SHARED,
    };
    (0..images.len()).map(sole).collect()
}

/// One thread's work space for a column of the result: its rows and values, and dense sums
/// for rows that several products reach, with the column that last touched each row, so no
/// array is cleared between columns.
struct ColumnScratch {
    rows: Vec<usize>,
    vals: Vec<f64>,
    touched_by: Vec<usize>,
    sum: Vec<f64>,
    shared_rows: Vec<usize>,
}

impl ColumnScratch {
    fn new(n: usize) -> Self {
        Self {
            rows: Vec::new(),
            vals: Vec::new(),
            touched_by: vec![usize::MAX; n],
            sum: vec![0.0; n],
            shared_rows: Vec::new(),
        }
    }

    /// Adds the product `value` to row `r` of column g.
    fn accumulate(&mut self, g: usize, r: usize, value: f64) {
        if self.touched_by[r] != g {
            self.touched_by[r] = g;
            self.sum[r] = 0.0;
            self.shared_rows.push(r);
        }
        self.sum[r] += value;
    }

    /// Clears the column listed, its rows no longer marked as touched by it.
    fn forget_column(&mut self) {
        for &r in &self.rows {
            self.touched_by[r] = usize::MAX;
        }
        self.rows.clear();
        self.vals.clear();
    }

    /// Appends the accumulated rows, ascending, after the rows already listed.
    fn append_shared(&mut self) {
        self.shared_rows.sort_unstable();
        for &r in &self.shared_rows {
            self.rows.push(r);
            self.vals.push(self.sum[r]);
        }
        self.shared_rows.clear();
    }
}

struct Product<'a> {
    a: &'a SparseColMat<usize, f64>,
    images: &'a Images,
    sole: Vec<SoleImage>,
    preimages: &'a Preimages,
}

impl Product<'_> {
    fn n(&self) -> usize {
        self.preimages.first.len() - 1
    }

    /// Column g of T^T A T into `s.rows` (ascending) and `s.vals`.
    fn column(&self, g: usize, s: &mut ColumnScratch) {
        s.rows.clear();
        s.vals.clear();
        if let &[(j, cj)] = self.preimages.of_dof(g) {
            if self.column_of_one_preimage(g, j, cj, s) {
                return;
            }
            s.forget_column();
        }
        for &(j, cj) in self.preimages.of_dof(g) {
            for (&i, &v) in self.a.row_idx_of_col_raw(j).iter().zip(self.a.val_of_col(j)) {
                for &(gi, ci) in self.images.of(i) {
                    s.accumulate(g, gi, ci * v * cj);
                }
            }
        }
        s.append_shared();
    }

    /// The common column (a free DoF's): A's column j mapped row by row, sole images written
    /// straight in A's row order, only the shared ones (flange masters) summed. False if the
    /// rows do not come out ascending (not under the rigid coupling, whose free DoFs keep their
    /// order and whose masters come last), for the general route to redo.
    fn column_of_one_preimage(&self, g: usize, j: usize, cj: f64, s: &mut ColumnScratch) -> bool {
        for (&i, &v) in self.a.row_idx_of_col_raw(j).iter().zip(self.a.val_of_col(j)) {
            let sole = self.sole[i];
            if sole.dof != SHARED.dof {
                s.rows.push(sole.dof);
                s.vals.push(sole.coefficient * v * cj);
            } else {
                for &(gi, ci) in self.images.of(i) {
                    s.accumulate(g, gi, ci * v * cj);
                }
            }
        }
        s.append_shared();
        s.rows.is_sorted_by(|a, b| a < b)
    }

    /// Column pointers of the result: each column's entry count, summed up.
    fn column_starts(&self) -> Vec<usize> {
        let n = self.n();
        let mut col_ptr = vec![0; n + 1];
        col_ptr[1..].par_chunks_mut(COLUMNS_PER_TASK).enumerate().for_each_init(
            || ColumnScratch::new(n),
            |s, (task, counts)| {
                for (k, count) in counts.iter_mut().enumerate() {
                    self.column(task * COLUMNS_PER_TASK + k, s);
                    *count = s.rows.len();
                }
            },
        );
        for g in 0..n {
            col_ptr[g + 1] += col_ptr[g];
        }
        col_ptr
    }

    /// The product on the counted pattern.
    fn fill(&self, col_ptr: Vec<usize>) -> SparseColMat<usize, f64> {
        let n = self.n();
        let mut row_idx = vec![0; col_ptr[n]];
        let mut val = vec![0.0; col_ptr[n]];
        column_tasks(&col_ptr, &mut row_idx, &mut val).into_par_iter().for_each_init(
            || ColumnScratch::new(n),
            |s, (columns, rows_out, val_out)| {
                let base = col_ptr[columns.start];
                for g in columns {
                    self.column(g, s);
                    let at = col_ptr[g] - base;
                    rows_out[at..at + s.rows.len()].copy_from_slice(&s.rows);
                    val_out[at..at + s.vals.len()].copy_from_slice(&s.vals);
                }
            },
        );
        SparseColMat::new(SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx), val)
    }
}

/// The output split into disjoint runs of `COLUMNS_PER_TASK` columns, one per task.
type ColumnTask<'a> = (Range<usize>, &'a mut [usize], &'a mut [f64]);

fn column_tasks<'a>(col_ptr: &[usize], mut rows: &'a mut [usize], mut val: &'a mut [f64]) -> Vec<ColumnTask<'a>> {
    let n = col_ptr.len() - 1;
    let mut tasks = Vec::with_capacity(n.div_ceil(COLUMNS_PER_TASK));
    for start in (0..n).step_by(COLUMNS_PER_TASK) {
        let end = n.min(start + COLUMNS_PER_TASK);
        let len = col_ptr[end] - col_ptr[start];
        let (task_rows, rest_rows) = std::mem::take(&mut rows).split_at_mut(len);
        let (task_val, rest_val) = std::mem::take(&mut val).split_at_mut(len);
        tasks.push((start..end, task_rows, task_val));
        (rows, val) = (rest_rows, rest_val);
    }
    tasks
}

/// (B + B^T) / 2 of the product B, each mirrored pair given one value (0.5 b_ij + 0.5 b_ji,
/// halves first so that two large values cannot overflow). In place when B's pattern is
/// symmetric, as the product of every matrix with a symmetric pattern is; otherwise B is formed
/// again and averaged on the union of both patterns.
fn symmetric_product(product: &Product<'_>, what: &str) -> Result<SparseColMat<usize, f64>> {
    let mut b = product.fill(product.column_starts());
    if average_with_transpose(&mut b) {
        return Ok(b);
    }
    drop(b);
    let b = product.fill(product.column_starts());
    let failed = |e: faer::sparse::FaerError| {
        BuildError::numerical(format!("symmetrising the coupled {what}: {}", faer_error::generic(&e))).caused_by(e)
    };
    let bt = b.as_ref().transpose().to_col_major().map_err(failed)?;
    faer::sparse::ops::binary_op(b.as_ref(), bt.as_ref(), |x, y| {
        0.5 * x.copied().unwrap_or(0.0) + 0.5 * y.copied().unwrap_or(0.0)
    })
    .map_err(failed)
}

/// B := (B + B^T) / 2 for B with rows ascending, walking the columns in order with one cursor
/// per column: the strictly upper entries of column i are met, ascending, as the strictly lower
/// entries (i, j) of the columns j < i. False, with B's values half averaged, if some entry has
/// no mirror.
fn average_with_transpose(b: &mut SparseColMat<usize, f64>) -> bool {
    let (pattern, val) = b.parts_mut();
    let (n, col_ptr, row_idx) = (pattern.ncols(), pattern.col_ptr(), pattern.row_idx());
    let mut cursor = col_ptr[..n].to_vec();
    for j in 0..n {
        for p in col_ptr[j]..col_ptr[j + 1] {
            let i = row_idx[p];
            if i <= j {
                continue;
            }
            let q = cursor[i];
            if q == col_ptr[i + 1] || row_idx[q] != j {
                return false;
            }
            cursor[i] += 1;
            let s = 0.5 * val[p] + 0.5 * val[q];
            val[p] = s;
            val[q] = s;
        }
    }
    // every strictly upper entry of each column was met as a mirror
    (0..n).all(|i| cursor[i] == col_ptr[i + 1] || row_idx[cursor[i]] >= i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;
    use faer::sparse::Triplet;

    fn sparse(n: usize, entries: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let trip: Vec<_> = entries.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        SparseColMat::try_new_from_triplets(n, n, &trip).unwrap()
    }

    /// (B + B^T) / 2 of B = T^T A T, formed densely.
    fn images_of(rows: &[Vec<(usize, f64)>]) -> Images {
        let mut images = Images::with_capacity(rows.len());
        for r in rows {
            images.push(r.iter().copied());
        }
        images
    }

    fn dense_reference(a: &SparseColMat<usize, f64>, images: &Images, n: usize) -> Mat<f64> {
        let t =
            Mat::from_fn(images.len(), n, |i, g| images.of(i).iter().filter(|t| t.0 == g).map(|t| t.1).sum::<f64>());
        let b = t.transpose() * a.to_dense() * &t;
        Mat::from_fn(n, n, |i, j| 0.5 * b[(i, j)] + 0.5 * b[(j, i)])
    }

    fn assert_exactly_symmetric(s: &SparseColMat<usize, f64>) {
        for j in 0..s.ncols() {
            for (&i, &v) in s.row_idx_of_col_raw(j).iter().zip(s.val_of_col(j)) {
                let p = s.row_idx_of_col_raw(i).binary_search(&j).expect("mirror in the pattern");
                assert_eq!(s.val_of_col(i)[p].to_bits(), v.to_bits(), "({i}, {j})");
            }
        }
    }

    /// Equal to the dense reference to round-off: every entry is a sum of a few products of
    /// order one, summed in another order.
    fn assert_matches(s: &SparseColMat<usize, f64>, reference: &Mat<f64>) {
        let dense = s.to_dense();
        for (i, j) in (0..s.nrows()).flat_map(|i| (0..s.ncols()).map(move |j| (i, j))) {
            assert!(
                (dense[(i, j)] - reference[(i, j)]).abs() <= 1e-14,
                "({i}, {j}): {} vs {}",
                dense[(i, j)],
                reference[(i, j)]
            );
        }
    }

    #[test]
    fn a_pattern_that_is_not_symmetric_is_averaged_on_the_union() {
        // A(0, 2) has no mirror; DoF 3 is tied to 1 and 2 as a slave is to its master's DoFs
        let a = sparse(
            4,
            &[
                (0, 0, 4.0),
                (0, 2, 1.5),
                (1, 1, 3.0),
                (2, 1, -1.0),
                (1, 2, -1.0),
                (2, 2, 5.0),
                (3, 3, 2.0),
                (3, 0, 0.25),
            ],
        );
        let images = images_of(&[vec![(0, 1.0)], vec![(1, 1.0)], vec![(2, 1.0)], vec![(1, 0.5), (2, -2.0)]]);
        let s = symmetric_congruence(&a, &images, 3, "test").unwrap();
        assert_exactly_symmetric(&s);
        assert_matches(&s, &dense_reference(&a, &images, 3));
        // B(1, 0) = 0.5 A(3, 0) has no mirror in B: S holds both
        assert!(s.row_idx_of_col_raw(0).contains(&1) && s.row_idx_of_col_raw(1).contains(&0));
    }

    #[test]
    fn images_out_of_order_take_the_general_route() {
        // a permutation with a scale, and two DoFs onto one: no column comes out ascending by itself
        let a = sparse(
            4,
            &[
                (0, 0, 2.0),
                (1, 1, 3.0),
                (2, 2, 4.0),
                (3, 3, 5.0),
                (0, 1, 0.5),
                (1, 0, 0.5),
                (2, 3, -0.75),
                (3, 2, -0.75),
                (0, 3, 0.1),
                (3, 0, 0.1),
            ],
        );
        let images = images_of(&[vec![(2, 1.0)], vec![(0, -2.0)], vec![(1, 1.0)], vec![(1, 0.5), (0, 3.0)]]);
        let s = symmetric_congruence(&a, &images, 3, "test").unwrap();
        assert_exactly_symmetric(&s);
        assert_matches(&s, &dense_reference(&a, &images, 3));
        for j in 0..3 {
            assert!(s.row_idx_of_col_raw(j).is_sorted_by(|x, y| x < y));
        }
    }

    #[test]
    fn a_map_that_does_not_fit_is_an_error() {
        let a = sparse(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        assert!(symmetric_congruence(&a, &images_of(&[vec![(0, 1.0)]]), 1, "test").is_err());
        let images = images_of(&[vec![(0, 1.0)], vec![(5, 1.0)]]);
        assert!(symmetric_congruence(&a, &images, 2, "test").is_err());
    }
}
