//! Test matrices of the linear algebra's unit tests: the 7-point Laplacian of a k^3 grid, whose
//! fill, definiteness and spectrum are known.

use faer::sparse::{SparseColMat, Triplet};

/// `linalg::sparse::Sparse`, named here without importing it: `sparse` and `ordering` use these
/// grids in their tests, and the import would close a circle.
type Sparse = SparseColMat<usize, f64>;

/// -1 between grid neighbours, `diagonal(i)` on row i.
pub fn laplacian(k: usize, diagonal: impl Fn(usize) -> f64) -> Sparse {
    let id = |x: usize, y: usize, z: usize| x + k * (y + k * z);
    let mut t = Vec::new();
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                let i = id(x, y, z);
                t.push(Triplet::new(i, i, diagonal(i)));
                for (dx, dy, dz) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    if x + dx < k && y + dy < k && z + dz < k {
                        let j = id(x + dx, y + dy, z + dz);
                        t.push(Triplet::new(i, j, -1.0));
                        t.push(Triplet::new(j, i, -1.0));
                    }
                }
            }
        }
    }
    let n = k * k * k;
    Sparse::try_new_from_triplets(n, n, &t).expect("a grid's entries lie inside it")
}

/// The k^3 diagonal matrix of `diagonal(i)`.
pub fn diagonal(k: usize, diagonal: impl Fn(usize) -> f64) -> Sparse {
    let n = k * k * k;
    let t: Vec<_> = (0..n).map(|i| Triplet::new(i, i, diagonal(i))).collect();
    Sparse::try_new_from_triplets(n, n, &t).expect("a diagonal's entries lie inside it")
}
