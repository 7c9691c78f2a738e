//! Fields stored row by row (a node's or a DoF's values side by side) and the two products the
//! floating-frame terms are made of: a symmetric sparse mass times many columns, and the
//! reduction `A^T B` over the mesh.
//!
//! Both run on rayon's threads in fixed chunks of rows. The chunks do not depend on the thread
//! count, so neither do the results' bits. faer's parallel dense product is avoided for `A^T B`:
//! with a few dozen columns and hundreds of thousands of rows its threads meet at a barrier per
//! block and spin there, which cost 10-17 s instead of 1 s on a loaded two-core machine.

use crate::linalg::sparse::Sparse;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;

/// Rows per task of the sparse product and of the regrouping: enough work to outweigh rayon's
/// hand-off, small enough to balance two cores.
const ROWS_PER_TASK: usize = 1024;

/// Rows per partial sum of `transpose_times`: each partial is one cache-friendly sequential dense
/// product, and the few partials are summed in order.
const ROWS_PER_PARTIAL: usize = 8192;

/// Which row holds which index (a node, a DoF). Fields combined with each other share one.
///
/// A mesh's own numbering can scatter neighbours (Gmsh numbers the mid-side nodes after all
/// corners: a node's mass couplings sit 20 000 rows away on average in a 85 000-node bracket),
/// and then every term of the sparse product fetches a row from far away in memory. In the
/// spatial layout neighbours share cache lines, which makes the product twice as fast there.
pub struct Layout {
    index_at: Vec<usize>,
    slot_of: Vec<usize>,
}

impl Layout {
    /// Index i in row i.
    pub fn natural(n: usize) -> Self {
        Self { index_at: (0..n).collect(), slot_of: (0..n).collect() }
    }

    /// Points in Morton (Z-curve) order of their position in the bounding box, ties by index.
    pub fn spatial(points: &[[f64; 3]]) -> Self {
        let key = morton_key(points);
        let mut index_at: Vec<usize> = (0..points.len()).collect();
        index_at.sort_unstable_by_key(|&i| (key(points[i]), i));
        let mut slot_of = vec![0; points.len()];
        for (slot, &i) in index_at.iter().enumerate() {
            slot_of[i] = slot;
        }
        Self { index_at, slot_of }
    }

    pub fn len(&self) -> usize {
        self.index_at.len()
    }

    pub fn is_empty(&self) -> bool {
        self.index_at.is_empty()
    }
}

/// Bits per axis of the Morton key: 3 x 21 fill a u64.
const MORTON_BITS: u32 = 21;

/// The Morton key of a point: its coordinates scaled to the bounding box's longest side,
/// quantised to `MORTON_BITS` and interleaved bit by bit.
fn morton_key(points: &[[f64; 3]]) -> impl Fn([f64; 3]) -> u64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            (lo[c], hi[c]) = (lo[c].min(p[c]), hi[c].max(p[c]));
        }
    }
    let span = (0..3).map(|c| hi[c] - lo[c]).fold(0.0f64, f64::max);
    let scale = if span > 0.0 { f64::from((1u32 << MORTON_BITS) - 1) / span } else { 0.0 };
    move |p| (0..3).map(|c| spread_bits(((p[c] - lo[c]) * scale) as u64) << c).fold(0, |key, bits| key | bits)
}

/// The low `MORTON_BITS` bits of `v` moved to every third bit (bit k to bit 3k).
fn spread_bits(v: u64) -> u64 {
    let mut x = v & ((1 << MORTON_BITS) - 1);
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// One row of `width` values per index of a `Layout`, the row of slot s at
/// `data[s * width..(s + 1) * width]`.
pub struct Rows<'a> {
    layout: &'a Layout,
    width: usize,
    data: Vec<f64>,
}

impl<'a> Rows<'a> {
    /// The row of index i filled by `fill(i, row)` from zeros.
    pub fn from_fn(layout: &'a Layout, width: usize, mut fill: impl FnMut(usize, &mut [f64])) -> Self {
        let mut data = vec![0.0; layout.len() * width];
        if width > 0 {
            for (row, &i) in data.chunks_exact_mut(width).zip(&layout.index_at) {
                fill(i, row);
            }
        }
        Self { layout, width, data }
    }

    /// A mesh field (3N x k, node-major rows 3n + c) with one row per node: the node's x values of
    /// the k columns, then its y values, then its z values (width 3k).
    pub fn by_node(layout: &'a Layout, field: MatRef<'_, f64>) -> Self {
        assert_eq!(field.nrows(), 3 * layout.len(), "a mesh field has three rows per node");
        let k = field.ncols();
        let mut data = vec![0.0; field.nrows() * k];
        if k > 0 {
            data.par_chunks_mut(3 * k * ROWS_PER_TASK).enumerate().for_each(|(task, chunk)| {
                for (row, &n) in chunk.chunks_exact_mut(3 * k).zip(&layout.index_at[task * ROWS_PER_TASK..]) {
                    for (c, component) in row.chunks_exact_mut(k).enumerate() {
                        for (j, v) in component.iter_mut().enumerate() {
                            *v = field[(3 * n + c, j)];
                        }
                    }
                }
            });
        }
        Self { layout, width: 3 * k, data }
    }

    pub fn n_rows(&self) -> usize {
        self.layout.len()
    }

    pub fn width(&self) -> usize {
        self.width
    }

    /// The row of index i.
    pub fn row(&self, i: usize) -> &[f64] {
        let s = self.layout.slot_of[i];
        &self.data[s * self.width..(s + 1) * self.width]
    }

    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        let s = self.layout.slot_of[i];
        &mut self.data[s * self.width..(s + 1) * self.width]
    }

    /// The rows as an n_rows x width matrix, in the layout's order (index order for a natural
    /// layout): for sums over the rows, or a natural layout's leading rows.
    pub fn as_mat(&self) -> MatRef<'_, f64> {
        MatRef::from_row_major_slice(&self.data, self.n_rows(), self.width)
    }

    /// A x for a symmetric sparse A (n_rows x n_rows), in x's layout. Symmetry lets column i of A
    /// stand for its row i, so every output row is a sum of whole input rows (vectorised, no
    /// scatter) and the output rows are independent (parallel without locks). The terms add in
    /// A's row order, as in faer's column-by-column product of the same matrix.
    pub fn symmetric_times(a: &Sparse, x: &Rows<'a>) -> Rows<'a> {
        assert_eq!(a.ncols(), x.n_rows(), "the matrix and the rows differ in size");
        let (layout, width) = (x.layout, x.width);
        let mut data = vec![0.0; x.data.len()];
        if width > 0 {
            data.par_chunks_mut(width * ROWS_PER_TASK).enumerate().for_each(|(task, chunk)| {
                for (row, &i) in chunk.chunks_exact_mut(width).zip(&layout.index_at[task * ROWS_PER_TASK..]) {
                    for (&m, &a_mi) in a.row_idx_of_col_raw(i).iter().zip(a.val_of_col(i)) {
                        for (o, &x_m) in row.iter_mut().zip(x.row(m)) {
                            *o += a_mi * x_m;
                        }
                    }
                }
            });
        }
        Rows { layout, width, data }
    }

    /// A^T B over the indices (self.width x b.width), for rows of one layout.
    pub fn inner(&self, b: &Rows<'_>) -> Mat<f64> {
        assert!(std::ptr::eq(self.layout, b.layout), "A^T B needs rows of one layout");
        transpose_times(self.as_mat(), b.as_mat())
    }
}

/// A^T B (a.ncols() x b.ncols()) for tall A and B with the same rows, summed over fixed chunks of
/// rows on rayon's threads.
pub fn transpose_times(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    transpose_times_in_chunks(a, b, ROWS_PER_PARTIAL)
}

fn transpose_times_in_chunks(a: MatRef<'_, f64>, b: MatRef<'_, f64>, rows_per_partial: usize) -> Mat<f64> {
    assert_eq!(a.nrows(), b.nrows(), "A^T B needs A and B with the same rows");
    let starts: Vec<usize> = (0..a.nrows()).step_by(rows_per_partial).collect();
    let partials: Vec<Mat<f64>> = starts
        .par_iter()
        .map(|&start| {
            let len = rows_per_partial.min(a.nrows() - start);
            let mut p = Mat::<f64>::zeros(a.ncols(), b.ncols());
            let (a_c, b_c) = (a.subrows(start, len), b.subrows(start, len));
            faer::linalg::matmul::matmul(p.as_mut(), Accum::Replace, a_c.transpose(), b_c, 1.0, Par::Seq);
            p
        })
        .collect();
    let mut sum = Mat::<f64>::zeros(a.ncols(), b.ncols());
    for p in &partials {
        sum += p;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// A symmetric 5 x 5 pattern with a full diagonal and a few couplings.
    fn symmetric() -> Sparse {
        let mut t = Vec::new();
        for i in 0..5 {
            t.push(Triplet::new(i, i, 2.0 + i as f64));
        }
        for &(i, j, v) in &[(0, 3, -0.5), (1, 2, 0.25), (2, 4, 1.5), (0, 4, -0.125)] {
            t.push(Triplet::new(i, j, v));
            t.push(Triplet::new(j, i, v));
        }
        SparseColMat::try_new_from_triplets(5, 5, &t).expect("valid triplets")
    }

    #[test]
    fn symmetric_times_equals_faer_bit_for_bit() {
        let a = symmetric();
        let layout = Layout::spatial(&[[0.5, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3], [1.0, 1.0, 1.0], [0.1, 0.2, 0.9]]);
        assert_ne!(layout.index_at, vec![0, 1, 2, 3, 4], "a layout that differs from the numbering");
        let x = Rows::from_fn(&layout, 4, |i, row| {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (i as f64 + 1.0) * 0.3 - j as f64 * 0.7;
            }
        });
        let y = Rows::symmetric_times(&a, &x);
        let x_natural = Mat::<f64>::from_fn(5, 4, |i, j| x.row(i)[j]);
        let expected = crate::linalg::sparse::mul_new(&a, x_natural.as_ref());
        assert_eq!((y.n_rows(), y.width()), (5, 4));
        for i in 0..5 {
            for j in 0..4 {
                assert_eq!(y.row(i)[j].to_bits(), expected[(i, j)].to_bits(), "({i}, {j})");
            }
        }
    }

    #[test]
    fn chunked_transpose_times_equals_the_plain_product() {
        let a = Mat::<f64>::from_fn(11, 3, |i, j| (i * 3 + j) as f64 * 0.1 - 1.0);
        let b = Mat::<f64>::from_fn(11, 2, |i, j| 1.0 / (1.0 + i as f64 + j as f64));
        let expected = a.transpose() * &b;
        for rows_per_partial in [1, 3, 11, 64] {
            let p = transpose_times_in_chunks(a.as_ref(), b.as_ref(), rows_per_partial);
            assert_eq!((p.nrows(), p.ncols()), (3, 2));
            // a few sums of eleven terms of size 1: round-off of 1e-15 at most
            assert!((&p - &expected).norm_max() <= 1e-14, "{rows_per_partial} rows per partial");
        }
    }

    #[test]
    fn spatial_layout_follows_the_z_curve() {
        assert_eq!(spread_bits(0b1011), 0b001_000_001_001);
        // the eight corners of a cube: x is the lowest bit of the key, z the highest
        let corners: Vec<[f64; 3]> =
            (0..8).map(|k| [f64::from(k & 1), f64::from((k >> 1) & 1), f64::from(k >> 2)]).rev().collect();
        let layout = Layout::spatial(&corners);
        assert_eq!(layout.index_at, vec![7, 6, 5, 4, 3, 2, 1, 0]);
        assert!((0..8).all(|i| layout.index_at[layout.slot_of[i]] == i));
        assert_eq!(Layout::spatial(&[[2.0; 3]; 3]).index_at, vec![0, 1, 2], "one point: ties by index");
        assert!(Layout::spatial(&[]).is_empty());
    }

    #[test]
    fn by_node_groups_a_nodes_components() {
        // two nodes, two columns: entry (3n + c, j) = 10 n + c + 0.5 j
        let f = Mat::<f64>::from_fn(6, 2, |i, j| (10 * (i / 3) + i % 3) as f64 + 0.5 * j as f64);
        let layout = Layout::spatial(&[[1.0; 3], [0.0; 3]]);
        assert_eq!(layout.index_at, vec![1, 0]);
        let rows = Rows::by_node(&layout, f.as_ref());
        assert_eq!((rows.n_rows(), rows.width()), (2, 6));
        assert_eq!(rows.row(1), &[10.0, 10.5, 11.0, 11.5, 12.0, 12.5]);
        assert_eq!(rows.as_mat().row(0).iter().copied().collect::<Vec<_>>(), rows.row(1));
    }
}
