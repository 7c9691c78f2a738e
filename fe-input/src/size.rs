//! The model's size before it is built, against the machine's memory. A box of 1e5 elements per
//! direction, or a mesh file of 1e8 nodes, would otherwise allocate until the allocator aborts
//! the process (or the kernel kills it) with no word about the input. The estimate is made from
//! counts alone, before any FE-sized allocation, and the build is refused with the field, the
//! estimate and the memory this machine has.
//!
//! Where the memory goes (bytes, n = DoFs):
//! - the coupled K and M, the mounted body's K (the factored copy) and one clamped M block, in
//!   compressed columns (16 B per non-zero each; assembly fills them in place, without triplets);
//! - one sparse Cholesky factor (8 B per entry, plus its indices and faer's supernodal workspace:
//!   10 B per entry), the LU of Krylov's complex points counted alike;
//! - the Lanczos space and its M-products, static shapes and the basis: a few hundred FE-sized
//!   vectors.
//!
//! Factor fill: the builder orders by METIS nested dissection (George 1973; Lipton, Rose and
//! Tarjan 1979: O(n^{4/3}) non-zeros for 3D grids, O(n w) for a slender part with w DoFs in a
//! cross-section). `nested_dissection_fill` follows that recursion on a lattice of the part's
//! shape: a separator of s DoFs (a cross-section perpendicular to the longest side) costs s^2
//! (its dense triangle and its coupling to the enclosing separators), then both halves recurse.
//! On a cube of k^3 nodes this gives about 31 k^4; `FILL_SAFETY` covers what METIS leaves more.

use crate::element::ElementKind;
use crate::error::{InputError, Result};
use std::path::Path;

/// METIS's factor against the lattice recursion: the tet10 bracket (an L of plates, its lattice
/// the bounding box) measured 1.57 times the estimate at 80k DoF (30.1 M entries) and 1.85 at
/// 249k (159.7 M); the factor leaves room for the trend to larger meshes.
const FILL_SAFETY: f64 = 2.5;

/// Memory assumed when /proc/meminfo cannot be read (not Linux, a sandbox): a small machine.
const FALLBACK_BYTES: f64 = 8.0 * (1u64 << 30) as f64;

/// FE-sized vectors alive at once: the Lanczos space and its M-products (266 for 26 modes in
/// blocks of 7 at 249k DoF), static shapes, the basis.
const VECTORS: f64 = 300.0;

/// The model's size, estimated from counts (f64: the counts of absurd inputs overflow usize
/// products, and an estimate needs no more than 16 digits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizeEstimate {
    pub nodes: f64,
    pub dofs: f64,
    pub elements: f64,
    /// Non-zeros of the stiffness (DoF level, both triangles).
    pub stiffness_nonzeros: f64,
    /// Non-zeros of one Cholesky factor of the stiffness.
    pub factor_nonzeros: f64,
    pub bytes: f64,
}

/// Average number of nodes an element kind's node shares an element with (itself included):
/// hex8 27 on a regular grid; hex20 81 at a corner and 51 at a mid-edge node (a quarter are
/// corners); tet4 about 15 and tet10 about 30 in Delaunay meshes.
fn neighbours(kind: ElementKind) -> f64 {
    match kind {
        ElementKind::Hex8 => 27.0,
        ElementKind::Hex20 | ElementKind::Hex20R => 60.0,
        ElementKind::Tet4 => 15.0,
        ElementKind::Tet10 => 30.0,
    }
}

/// Non-zeros of the Cholesky factor of the stiffness of `nodes` nodes arranged like a lattice of
/// `dims` node rows (its product the node count), by nested dissection (see the module text).
pub fn nested_dissection_fill(dims: [f64; 3]) -> f64 {
    let nodes = dims.iter().product::<f64>();
    let mut d = dims;
    d.sort_by(|a, b| b.total_cmp(a));
    if nodes <= 64.0 || d[0] <= 2.0 {
        let n = 3.0 * nodes;
        return 0.5 * n * n;
    }
    let separator = 3.0 * d[1] * d[2];
    separator * separator + 2.0 * nested_dissection_fill([(d[0] - 1.0) / 2.0, d[1], d[2]])
}

/// Node rows along each axis of a part of `nodes` nodes spanning `extent` (bounding box): the
/// lattice nested dissection cuts. A flat or degenerate extent counts as one row.
pub fn lattice_of(nodes: f64, extent: [f64; 3]) -> [f64; 3] {
    let longest = extent.iter().fold(0.0f64, |m, &e| m.max(e));
    if !(longest > 0.0) || !longest.is_finite() {
        return [nodes.max(1.0), 1.0, 1.0];
    }
    let rel = extent.map(|e| (e / longest).max(1e-12));
    // rows_i = c rel_i with prod = nodes; rows below one are one (a sheet or a rod)
    let c = (nodes / rel.iter().product::<f64>()).cbrt();
    let mut rows = rel.map(|r| (c * r).max(1.0));
    let scale = nodes / rows.iter().product::<f64>();
    let longest_axis = (0..3).max_by(|&a, &b| rows[a].total_cmp(&rows[b])).unwrap_or(0);
    rows[longest_axis] *= scale;
    rows
}

impl SizeEstimate {
    /// From the counts: nodes, per-kind element counts, stiffness non-zeros when known (a matrix
    /// file's), and the factor fill.
    pub fn new(nodes: f64, elements: &[(ElementKind, f64)], stiffness_nonzeros: Option<f64>, factor_fill: f64) -> Self {
        let dofs = 3.0 * nodes;
        let element_count: f64 = elements.iter().map(|(_, n)| n).sum();
        let nnz_k = stiffness_nonzeros.unwrap_or_else(|| {
            let mean = if element_count > 0.0 {
                elements.iter().map(|(k, n)| n * neighbours(*k)).sum::<f64>() / element_count
            } else {
                27.0
            };
            9.0 * nodes * mean
        });
        let factor = (FILL_SAFETY * factor_fill).max(nnz_k / 2.0);
        // assembly fills the free-free K and M in place; the element matrices go a batch at a time
        let matrices = 4.0 * 16.0 * nnz_k;
        let solve = 10.0 * factor + 8.0 * VECTORS * dofs;
        let bytes = matrices + solve;
        SizeEstimate { nodes, dofs, elements: element_count, stiffness_nonzeros: nnz_k, factor_nonzeros: factor, bytes }
    }

    /// Ok when the estimate fits in `available` bytes; else the complaint, for the caller to
    /// put against the field that made the model this large.
    pub fn fits(&self, available: Memory) -> std::result::Result<(), crate::error::Refusal> {
        crate::out_of_memory::record_estimate(self.bytes, available.bytes, available.source);
        if self.bytes <= available.bytes {
            return Ok(());
        }
        Err(crate::error::Refusal::from(format!(
            "the model would have {} nodes ({} DoFs{}), a stiffness with about {} non-zeros and a sparse Cholesky factor \
             with about {} (nested-dissection estimate): about {} of memory, but {} {} available ({}). Use fewer \
             elements: the factor grows like (DoFs)^(4/3) for a solid part",
            count(self.nodes),
            count(self.dofs),
            if self.elements > 0.0 { format!(", {} elements", count(self.elements)) } else { String::new() },
            count(self.stiffness_nonzeros),
            count(self.factor_nonzeros),
            gib(self.bytes),
            gib(available.bytes),
            if available.source.starts_with("no ") { "is assumed" } else { "are" },
            available.source,
        )))
    }
}

fn count(v: f64) -> String {
    if v < 1e6 { format!("{v:.0}") } else { format!("{v:.1e}") }
}

fn gib(bytes: f64) -> String {
    let g = bytes / (1u64 << 30) as f64;
    if g < 1e4 { format!("{g:.1} GiB") } else { format!("{g:.1e} GiB") }
}

/// Memory the build may use, and where the figure comes from.
#[derive(Debug, Clone, Copy)]
pub struct Memory {
    pub bytes: f64,
    pub source: &'static str,
}

impl Memory {
    /// MemAvailable of /proc/meminfo (MemTotal on old kernels), capped by the cgroup v2 limit
    /// and the process's own limits (`ulimit -v`: RLIMIT_AS, less what the process has mapped
    /// already; `ulimit -d`: RLIMIT_DATA); a fixed 8 GiB where none can be read.
    pub fn of_this_machine() -> Memory {
        let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
        let field = |name: &str| {
            meminfo.lines().find(|l| l.starts_with(name)).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        };
        let (mut bytes, mut source) = match (field("MemAvailable:"), field("MemTotal:")) {
            (Some(kib), _) => (kib * 1024.0, "MemAvailable in /proc/meminfo"),
            (None, Some(kib)) => (kib * 1024.0, "MemTotal in /proc/meminfo"),
            _ => (FALLBACK_BYTES, "no /proc/meminfo: 8 GiB"),
        };
        let cgroup =
            std::fs::read_to_string("/sys/fs/cgroup/memory.max").ok().and_then(|s| s.trim().parse::<f64>().ok());
        let limits = [
            (cgroup, "the cgroup limit /sys/fs/cgroup/memory.max"),
            (address_space_left(), "the process's address-space limit (ulimit -v, RLIMIT_AS) less what it has mapped"),
            (rlimit(libc::RLIMIT_DATA), "the process's data limit (ulimit -d, RLIMIT_DATA)"),
        ];
        for (limit, name) in limits {
            if let Some(limit) = limit
                && limit < bytes
            {
                (bytes, source) = (limit, name);
            }
        }
        Memory { bytes, source }
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
type RlimitResource = libc::__rlimit_resource_t;
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
type RlimitResource = libc::c_int;

/// The soft limit `resource` of this process in bytes; None when unlimited or unreadable.
fn rlimit(resource: RlimitResource) -> Option<f64> {
    let mut r = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
    // SAFETY: getrlimit writes one rlimit struct we own
    if unsafe { libc::getrlimit(resource, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    Some(r.rlim_cur as f64)
}

/// RLIMIT_AS less the address space already mapped (VmSize: the binary, its libraries, thread
/// stacks), which the build cannot use.
fn address_space_left() -> Option<f64> {
    let limit = rlimit(libc::RLIMIT_AS)?;
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let mapped_kib = status
        .lines()
        .find(|l| l.starts_with("VmSize:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        .unwrap_or(0.0);
    Some((limit - mapped_kib * 1024.0).max(0.0))
}

/// Elements and nodes of one box of the mesher, by checked arithmetic (None: beyond u128).
fn box_counts(elements: [usize; 3], kind: ElementKind) -> Option<(u128, u128)> {
    let e = elements.map(|n| n as u128);
    let n_elements = e[0].checked_mul(e[1])?.checked_mul(e[2])?;
    let corners = (e[0] + 1).checked_mul(e[1] + 1)?.checked_mul(e[2] + 1)?;
    let nodes = match kind {
        // mid-edge nodes: edges along x, y, z
        ElementKind::Hex20 | ElementKind::Hex20R => {
            let along = |a: usize, b: usize, c: usize| e[a].checked_mul(e[b] + 1)?.checked_mul(e[c] + 1);
            corners.checked_add(along(0, 1, 2)?)?.checked_add(along(1, 0, 2)?)?.checked_add(along(2, 0, 1)?)?
        }
        _ => corners,
    };
    Some((n_elements, nodes))
}

/// Checks the boxes of `geometry.boxes` against the machine's memory before meshing them; the
/// error names the box whose element counts contribute most.
pub fn check_boxes(file: &Path, boxes: &[[usize; 3]], kind: ElementKind, memory: Memory) -> Result<SizeEstimate> {
    let mut nodes = 0.0;
    let mut elements = 0.0;
    let mut fill = 0.0;
    let mut largest = (0usize, 0.0f64);
    for (i, &e) in boxes.iter().enumerate() {
        let field = format!("geometry.boxes[{i}].elements");
        let Some((n_elements, n_nodes)) = box_counts(e, kind) else {
            return Err(InputError::field(file, field, format!("{e:?} elements: the element count overflows")));
        };
        // lattice rows: hex20 has half the nodes of its doubled lattice (no face or body centres)
        let step = if kind == ElementKind::Hex8 { 1.0 } else { 2.0 };
        let mut rows = e.map(|n| step * n as f64 + 1.0);
        let density = n_nodes as f64 / rows.iter().product::<f64>();
        rows = rows.map(|r| r * density.cbrt());
        let box_fill = nested_dissection_fill(rows);
        nodes += n_nodes as f64;
        elements += n_elements as f64;
        fill += box_fill;
        if box_fill >= largest.1 {
            largest = (i, box_fill);
        }
    }
    let estimate = SizeEstimate::new(nodes, &[(kind, elements)], None, fill);
    estimate.fits(memory).map_err(|m| {
        let (i, _) = largest;
        InputError::field(file, format!("geometry.boxes[{i}].elements"), format!("{:?} {kind} elements: {m}", boxes[i]))
    })?;
    Ok(estimate)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MACHINE: Memory = Memory { bytes: 16.0 * (1u64 << 30) as f64, source: "a test's 16 GiB" };

    #[test]
    fn fill_grows_like_n_to_four_thirds_in_3d_and_like_n_for_rods() {
        let cube = |k: f64| nested_dissection_fill([k, k, k]);
        let ratio = cube(64.0) / cube(32.0);
        assert!((ratio / 16.0 - 1.0).abs() < 0.1, "{ratio}"); // (8 n)^(4/3) / n^(4/3) = 16
        let rod = |l: f64| nested_dissection_fill([l, 5.0, 5.0]);
        let ratio = rod(20000.0) / rod(10000.0);
        assert!((ratio / 2.0 - 1.0).abs() < 0.05, "{ratio}");
        // a lattice of a part's shape keeps its node count and its aspect
        let rows = lattice_of(1e6, [1.0, 0.01, 0.02]);
        assert!((rows.iter().product::<f64>() / 1e6 - 1.0).abs() < 1e-9 && rows[0] > 50.0 * rows[1], "{rows:?}");
    }

    #[test]
    fn huge_boxes_are_refused_with_their_field_and_small_ones_pass() {
        let file = Path::new("in.json");
        for e in [[100000, 100000, 100000], [100000, 10, 10], [usize::MAX, usize::MAX, 2]] {
            let m = check_boxes(file, &[[2, 2, 2], e], ElementKind::Hex20, MACHINE).unwrap_err().to_string();
            assert!(
                m.contains("geometry.boxes[1].elements") && m.contains("GiB") && m.contains("fewer elements")
                    || m.contains("overflows"),
                "{m}"
            );
        }
        // the paper's beam and a 1e5-DoF solid pass on a 16 GiB machine
        let beam = check_boxes(file, &[[50, 2, 2]], ElementKind::Hex20, MACHINE).unwrap();
        assert!(beam.bytes < 5e8, "{beam:?}");
        let solid = check_boxes(file, &[[20, 20, 20]], ElementKind::Hex20, MACHINE).unwrap();
        assert!((solid.dofs - 3.0 * 35_721.0).abs() < 1.0 && solid.bytes < 8e9, "{solid:?}");
    }
}
