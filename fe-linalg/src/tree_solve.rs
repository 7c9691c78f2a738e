//! Solves with a supernodal Cholesky factor (faer's) whose elimination tree is split between the
//! threads: every thread walks its own subtrees, the supernodes above them (the top separators
//! of the nested dissection) follow on all threads together. A solve reads each entry of the
//! factor once in all, where splitting the right-hand sides between the threads (each thread
//! through the whole factor) reads it once per thread: solves with few right-hand sides stream
//! the factor from memory and do little arithmetic on it, so that was half the memory bandwidth
//! spent twice.
//!
//! It needs the supernodes in a postorder of their tree (every subtree a contiguous range of
//! supernodes and of rows), which faer's symbolic factorisation gives; `TreeSolve::new` checks
//! it and declines otherwise, and the caller solves as before.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use std::ops::Range;

/// A split of a supernodal factor's elimination tree between threads.
pub struct TreeSolve {
    /// Per thread, its subtrees as ranges of supernodes (each ending at the subtree's root).
    parts: Vec<Vec<Range<usize>>>,
    /// The supernodes above every part, ascending.
    top: Vec<usize>,
    /// Each row's position among the rows of the top supernodes (`NOT_TOP` for the others).
    top_index: Vec<usize>,
    top_rows: Vec<usize>,
    /// One element of every cycle of the fill-reducing permutation, for permuting in place.
    cycle_leaders: Vec<usize>,
}

const NOT_TOP: usize = usize::MAX;

/// Largest share of the factor the top supernodes may hold before the split is not worth it.
const MAX_TOP_SHARE: f64 = 0.5;

impl TreeSolve {
    /// The split of `symbolic`'s tree between `threads`, or None where there is nothing to
    /// split (one thread, a simplicial factor, supernodes not in postorder, no balance found).
    pub fn new(symbolic: &SymbolicCholesky<usize>, threads: usize) -> Option<Self> {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else { return None };
        if threads < 2 {
            return None;
        }
        let tree = Tree::of(sn)?;
        let (parts, mut top) = tree.split(threads)?;
        top.sort_unstable();
        let (top_index, top_rows) = rows_of(&top, sn);
        // each subtree ends at its root: work within it in increasing supernode order (children
        // before parents) and in decreasing order for the transposed solve
        let mut parts = parts;
        for p in &mut parts {
            p.sort_by_key(|r| r.start);
        }
        let cycle_leaders = match symbolic.perm() {
            Some(perm) => cycle_leaders(perm.arrays().0),
            None => Vec::new(),
        };
        Some(Self { parts, top, top_index, top_rows, cycle_leaders })
    }
}

/// Per thread, its subtrees as ranges of supernodes.
type Subtrees = Vec<Vec<Range<usize>>>;

/// The tree of a factor's supernodes, in postorder.
struct Tree {
    /// Factor entries per supernode.
    work: Vec<usize>,
    parent: Vec<Option<usize>>,
    /// The first supernode of each one's subtree (which ends at the supernode itself).
    first: Vec<usize>,
    subtree_work: Vec<usize>,
    children: Vec<Vec<usize>>,
}

impl Tree {
    /// The supernodal tree of `sn`, or None where its supernodes do not tile the columns in a
    /// postorder of the tree.
    fn of(sn: &SymbolicSupernodalCholesky<usize>) -> Option<Self> {
        let ns = sn.n_supernodes();
        let n = sn.nrows();
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        // supernodes tile the columns in order
        if ns == 0 || begin[0] != 0 || end[ns - 1] != n || (1..ns).any(|s| begin[s] != end[s - 1]) {
            return None;
        }
        let mut owner = vec![0usize; n];
        for s in 0..ns {
            owner[begin[s]..end[s]].fill(s);
        }
        // the supernodal tree: a supernode's parent holds the first row below its diagonal block
        let mut parent = vec![None; ns];
        for (s, p) in parent.iter_mut().enumerate() {
            if let Some(&row) = sn.supernode(s).pattern().iter().min() {
                if row < end[s] {
                    return None;
                }
                *p = Some(owner[row]);
            }
        }
        let work: Vec<usize> = (0..ns).map(|s| sn.col_ptr_for_val()[s + 1] - sn.col_ptr_for_val()[s]).collect();
        let mut first = (0..ns).collect::<Vec<_>>();
        let mut size = vec![1usize; ns];
        let mut subtree_work = work.clone();
        let mut children = vec![Vec::new(); ns];
        for s in 0..ns {
            if let Some(p) = parent[s] {
                first[p] = first[p].min(first[s]);
                size[p] += size[s];
                subtree_work[p] += subtree_work[s];
                children[p].push(s);
            }
        }
        // postorder: every subtree is the range of supernodes ending at its root
        if (0..ns).any(|s| s + 1 - first[s] != size[s]) {
            return None;
        }
        Some(Self { work, parent, first, subtree_work, children })
    }

    /// Subtrees for each of `threads` threads, of loads within 10 % of each other, and the
    /// supernodes above them (the roots split to get there); None where no such split keeps the
    /// top within `MAX_TOP_SHARE` of the factor.
    fn split(&self, threads: usize) -> Option<(Subtrees, Vec<usize>)> {
        let Self { work, parent, first, subtree_work, children } = self;
        let ns = work.len();
        let total: usize = work.iter().sum();
        let mut pool: Vec<usize> = (0..ns).filter(|&s| parent[s].is_none()).collect();
        let mut top = Vec::new();
        let mut top_work = 0usize;
        let parts = loop {
            // largest subtrees first, each to the least loaded thread
            pool.sort_by_key(|&s| std::cmp::Reverse(subtree_work[s]));
            let mut loads = vec![0usize; threads];
            let mut parts: Vec<Vec<Range<usize>>> = vec![Vec::new(); threads];
            for &s in &pool {
                let t = (0..threads).min_by_key(|&t| loads[t]).unwrap_or(0);
                loads[t] += subtree_work[s];
                parts[t].push(first[s]..s + 1);
            }
            let max = loads.iter().copied().max().unwrap_or(0) as f64;
            let mean = loads.iter().sum::<usize>() as f64 / threads as f64;
            if max <= 1.1 * mean {
                break parts;
            }
            // the largest subtree is split: its root joins the top, its children the pool
            let big = pool[0];
            if children[big].is_empty() || (top_work + work[big]) as f64 > MAX_TOP_SHARE * total as f64 {
                return None;
            }
            pool.remove(0);
            top.push(big);
            top_work += work[big];
            pool.extend(children[big].iter().copied());
        };
        Some((parts, top))
    }
}

/// Each row's position among the rows of the `top` supernodes (`NOT_TOP` for the others), and
/// those rows.
fn rows_of(top: &[usize], sn: &SymbolicSupernodalCholesky<usize>) -> (Vec<usize>, Vec<usize>) {
    let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
    let n = sn.nrows();
    let mut top_index = vec![NOT_TOP; n];
    let mut top_rows = Vec::new();
    for &s in top {
        for row in begin[s]..end[s] {
            top_index[row] = top_rows.len();
            top_rows.push(row);
        }
    }
    (top_index, top_rows)
}

impl TreeSolve {
    /// How many subtrees each thread walks.
    pub fn subtrees_per_thread(&self) -> Vec<usize> {
        self.parts.iter().map(Vec::len).collect()
    }

    /// Solves L L^T x = rhs in place (the factor `values` of `symbolic`, the one `new` split).
    pub fn solve(&self, symbolic: &SymbolicCholesky<usize>, values: &[f64], mut rhs: MatMut<'_, f64>) {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else { return };
        let llt = SupernodalLltRef::<'_, usize, f64>::new(sn, values);
        let perm = symbolic.perm().map(|p| p.arrays());
        if let Some((forward, _)) = perm {
            permute_columns(rhs.rb_mut(), forward, &self.cycle_leaders);
        }
        self.forward(sn, llt, rhs.rb_mut());
        self.backward(sn, llt, rhs.rb_mut());
        if let Some((_, inverse)) = perm {
            permute_columns(rhs.rb_mut(), inverse, &self.cycle_leaders);
        }
    }

    /// The subtrees' rows as disjoint pieces of x, per thread: (first row, end row, piece).
    fn pieces<'x>(
        &self,
        sn: &SymbolicSupernodalCholesky<usize>,
        x: MatMut<'x, f64>,
    ) -> Vec<Vec<(usize, usize, MatMut<'x, f64>)>> {
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        let mut ranges: Vec<(usize, usize, usize)> = Vec::new();
        for (t, part) in self.parts.iter().enumerate() {
            for r in part {
                ranges.push((begin[r.start], end[r.end - 1], t));
            }
        }
        ranges.sort_unstable();
        let mut out: Vec<Vec<(usize, usize, MatMut<'x, f64>)>> = (0..self.parts.len()).map(|_| Vec::new()).collect();
        let mut rest = x;
        let mut at = 0;
        for (r0, r1, t) in ranges {
            let (_, tail) = rest.split_at_row_mut(r0 - at);
            let (piece, tail) = tail.split_at_row_mut(r1 - r0);
            out[t].push((r0, r1, piece));
            rest = tail;
            at = r1;
        }
        for list in &mut out {
            list.sort_by_key(|p| p.0);
        }
        out
    }

    fn forward(
        &self,
        sn: &SymbolicSupernodalCholesky<usize>,
        llt: SupernodalLltRef<'_, usize, f64>,
        mut x: MatMut<'_, f64>,
    ) {
        use rayon::prelude::*;
        let k = x.ncols();
        let n_top = self.top_rows.len();
        let parts = self.pieces(sn, x.rb_mut());
        // each thread's updates of the top rows in a matrix of its own, summed after
        let updates: Vec<Mat<f64>> = parts
            .into_par_iter()
            .zip(self.parts.par_iter())
            .map(|(pieces, ranges)| {
                let mut update = Mat::<f64>::zeros(n_top, k);
                let mut tmp = Mat::<f64>::zeros(0, 0);
                for ((r0, r1, mut piece), supernodes) in pieces.into_iter().zip(ranges) {
                    for s in supernodes.clone() {
                        let node = llt.supernode(s);
                        let x_top = piece.rb_mut().subrows_mut(node.start() - r0, node.val().ncols());
                        let tmp = forward_node(node.val(), x_top, &mut tmp, Par::Seq);
                        let pattern = node.pattern();
                        for j in 0..k {
                            for (idx, &i) in pattern.iter().enumerate() {
                                if i < r1 {
                                    piece[(i - r0, j)] -= tmp[(idx, j)];
                                } else {
                                    update[(self.top_index[i], j)] -= tmp[(idx, j)];
                                }
                            }
                        }
                    }
                }
                update
            })
            .collect();
        for update in &updates {
            for j in 0..k {
                for (t, &row) in self.top_rows.iter().enumerate() {
                    x[(row, j)] += update[(t, j)];
                }
            }
        }
        drop(updates);
        let par = faer::get_global_parallelism();
        let mut tmp = Mat::<f64>::zeros(0, 0);
        for &s in &self.top {
            let node = llt.supernode(s);
            let x_top = x.rb_mut().subrows_mut(node.start(), node.val().ncols());
            let tmp = forward_node(node.val(), x_top, &mut tmp, par);
            for j in 0..k {
                for (idx, &i) in node.pattern().iter().enumerate() {
                    x[(i, j)] -= tmp[(idx, j)];
                }
            }
        }
    }

    fn backward(
        &self,
        sn: &SymbolicSupernodalCholesky<usize>,
        llt: SupernodalLltRef<'_, usize, f64>,
        mut x: MatMut<'_, f64>,
    ) {
        use rayon::prelude::*;
        let k = x.ncols();
        let par = faer::get_global_parallelism();
        let mut tmp = Mat::<f64>::zeros(0, 0);
        for &s in self.top.iter().rev() {
            let node = llt.supernode(s);
            let pattern = node.pattern();
            let mut below = workspace(&mut tmp, pattern.len(), k);
            for j in 0..k {
                for (idx, &i) in pattern.iter().enumerate() {
                    below[(idx, j)] = x[(i, j)];
                }
            }
            let x_top = x.rb_mut().subrows_mut(node.start(), node.val().ncols());
            backward_node(node.val(), below.rb(), x_top, par);
        }
        // the top rows are final: every thread reads them from one copy
        let top_values = Mat::<f64>::from_fn(self.top_rows.len(), k, |t, j| x[(self.top_rows[t], j)]);
        let top_values = top_values.as_ref();
        let parts = self.pieces(sn, x.rb_mut());
        parts.into_par_iter().zip(self.parts.par_iter()).for_each(|(pieces, ranges)| {
            let mut tmp = Mat::<f64>::zeros(0, 0);
            for ((r0, r1, mut piece), supernodes) in pieces.into_iter().zip(ranges).rev() {
                for s in supernodes.clone().rev() {
                    let node = llt.supernode(s);
                    let pattern = node.pattern();
                    let mut below = workspace(&mut tmp, pattern.len(), k);
                    for j in 0..k {
                        for (idx, &i) in pattern.iter().enumerate() {
                            below[(idx, j)] =
                                if i < r1 { piece[(i - r0, j)] } else { top_values[(self.top_index[i], j)] };
                        }
                    }
                    let x_top = piece.rb_mut().subrows_mut(node.start() - r0, node.val().ncols());
                    backward_node(node.val(), below.rb(), x_top, Par::Seq);
                }
            }
        });
    }
}

/// One supernode's step of L y = b (`l` its block of L, the diagonal block on top): its own rows
/// `x_top` solved in place, then L_bot x_top returned in the workspace, for the caller to subtract
/// at the node's pattern rows (wherever those rows are kept).
fn forward_node<'t>(
    l: MatRef<'_, f64>,
    mut x_top: MatMut<'_, f64>,
    tmp: &'t mut Mat<f64>,
    par: Par,
) -> MatMut<'t, f64> {
    let (l_top, l_bot) = l.split_at_row(l.ncols());
    solve_lower_triangular_in_place(l_top, x_top.rb_mut(), par);
    let mut update = workspace(tmp, l_bot.nrows(), x_top.ncols());
    if l_bot.nrows() > 0 {
        matmul(update.rb_mut(), Accum::Replace, l_bot, x_top.rb(), 1.0, par);
    }
    update
}

/// One supernode's step of L^T x = y: x_top -= L_bot^T `below` (the solution at the node's
/// pattern rows), then its own rows solved in place.
fn backward_node(l: MatRef<'_, f64>, below: MatRef<'_, f64>, mut x_top: MatMut<'_, f64>, par: Par) {
    let (l_top, l_bot) = l.split_at_row(l.ncols());
    if l_bot.nrows() > 0 {
        matmul(x_top.rb_mut(), Accum::Add, l_bot.transpose(), below, -1.0, par);
    }
    solve_upper_triangular_in_place(l_top.transpose(), x_top, par);
}

/// The first `rows` x `cols` block of a workspace grown as needed.
fn workspace(w: &mut Mat<f64>, rows: usize, cols: usize) -> MatMut<'_, f64> {
    if w.nrows() < rows || w.ncols() < cols {
        *w = Mat::zeros(rows.max(w.nrows()), cols.max(w.ncols()));
    }
    w.as_mut().submatrix_mut(0, 0, rows, cols)
}

/// One element of every cycle of the permutation `p`.
fn cycle_leaders(p: &[usize]) -> Vec<usize> {
    let mut seen = vec![false; p.len()];
    let mut leaders = Vec::new();
    for s in 0..p.len() {
        if seen[s] {
            continue;
        }
        leaders.push(s);
        let mut i = s;
        while !seen[i] {
            seen[i] = true;
            i = p[i];
        }
    }
    leaders
}

/// x[i] = x[p[i]] for every row i of every column, in place along the cycles of p (the same for
/// p and its inverse), columns split between the threads.
fn permute_columns(x: MatMut<'_, f64>, p: &[usize], leaders: &[usize]) {
    let k = x.ncols();
    if k >= 2 {
        let (a, b) = x.split_at_col_mut(k / 2);
        rayon::join(|| permute_columns(a, p, leaders), || permute_columns(b, p, leaders));
        return;
    }
    let mut x = x;
    for j in 0..k {
        let mut col = x.rb_mut().col_mut(j);
        for &s in leaders {
            let saved = col[s];
            let mut i = s;
            loop {
                let next = p[i];
                if next == s {
                    col[i] = saved;
                    break;
                }
                col[i] = col[next];
                i = next;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_in_place_follows_its_cycles() {
        let p = [3, 0, 4, 1, 2, 5];
        let inverse = [1, 3, 4, 0, 2, 5];
        let leaders = cycle_leaders(&p);
        let x0 = Mat::<f64>::from_fn(6, 3, |i, j| (10 * i + j) as f64);
        let mut x = x0.clone();
        permute_columns(x.as_mut(), &p, &leaders);
        for j in 0..3 {
            for i in 0..6 {
                assert_eq!(x[(i, j)], x0[(p[i], j)]);
            }
        }
        permute_columns(x.as_mut(), &inverse, &leaders);
        assert_eq!(x, x0);
    }
}
