//! Scratch memory lent to the hot paths, in the manner of faer's `StackReq` / `MemStack` but
//! hand-written (the runtime stays lean): a computation states how many values it needs as a
//! [`WorkspaceReq`], a function of the mode count; its owner allocates a [`Workspace`] of that
//! size once, when the body is instantiated, and lends it as `&mut` to every call. A hot
//! function that takes `&mut Workspace` thereby says in its signature that it allocates nothing:
//! its scratch is the caller's.
//!
//! The workspace is scratch, not state: every call writes the values it reads, so a saved FMU
//! state leaves it out and a copy (an FMU state restored by cloning) gets a buffer of its own
//! whatever it holds.
//!
//! A workspace smaller than the call needs is refused with [`WorkspaceTooSmall`] before the call
//! changes anything: no panic, which the FMI layer would have to catch at its C boundary.

/// How many `f64` a computation needs as scratch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WorkspaceReq {
    len: usize,
}

impl WorkspaceReq {
    /// Nothing: the requirement of a computation without scratch.
    pub const EMPTY: Self = Self { len: 0 };

    /// Consecutive slices of these lengths, all in use at once.
    pub const fn slices(lens: &[usize]) -> Self {
        let mut len = 0;
        let mut k = 0;
        while k < lens.len() {
            len += lens[k];
            k += 1;
        }
        Self { len }
    }

    /// Both in use at once: the sum.
    pub const fn and(self, other: Self) -> Self {
        Self { len: self.len + other.len }
    }

    /// One after the other (each call's slices are free again when it returns): the larger.
    pub const fn or(self, other: Self) -> Self {
        Self { len: if self.len > other.len { self.len } else { other.len } }
    }

    /// Number of `f64` values.
    pub const fn len(self) -> usize {
        self.len
    }

    pub const fn is_empty(self) -> bool {
        self.len == 0
    }
}

/// A workspace with fewer values than a computation needs: the call was refused, nothing done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WorkspaceTooSmall {
    pub needed: usize,
    pub available: usize,
}

impl std::fmt::Display for WorkspaceTooSmall {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the workspace holds {} values, the computation needs {} (a workspace made for fewer modes)",
            self.available, self.needed
        )
    }
}

impl std::error::Error for WorkspaceTooSmall {}

/// Scratch values of the size a [`WorkspaceReq`] asked for, allocated once; calls carve it into
/// the slices they document.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    values: Vec<f64>,
}

impl Workspace {
    /// A workspace for `req` (the only allocation: at the body's instantiation).
    pub fn new(req: WorkspaceReq) -> Self {
        Self { values: vec![0.0; req.len()] }
    }

    /// Number of `f64` values it holds.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Ok if it holds what `req` asks for; else the refusal a call returns before any work.
    pub fn check(&self, req: WorkspaceReq) -> Result<(), WorkspaceTooSmall> {
        if self.values.len() < req.len() {
            return Err(WorkspaceTooSmall { needed: req.len(), available: self.values.len() });
        }
        Ok(())
    }

    /// Its leading values as `K` consecutive slices of the lengths `lens` (their contents are
    /// whatever the last call left: scratch to be written before it is read), or Err if it
    /// holds fewer than their sum.
    pub fn carve<const K: usize>(&mut self, lens: [usize; K]) -> Result<[&mut [f64]; K], WorkspaceTooSmall> {
        self.check(WorkspaceReq::slices(&lens))?;
        let mut rest: &mut [f64] = &mut self.values;
        Ok(lens.map(|len| {
            // within bounds: the check above covers the sum of the lengths
            let (slice, tail) = std::mem::take(&mut rest).split_at_mut(len);
            rest = tail;
            slice
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requirements_add_for_slices_in_use_together_and_take_the_larger_for_successive_ones() {
        let a = WorkspaceReq::slices(&[3, 4]);
        let b = WorkspaceReq::slices(&[5]);
        assert_eq!((a.len(), a.and(b).len(), a.or(b).len(), b.or(a).len()), (7, 12, 7, 7));
        assert!(WorkspaceReq::EMPTY.is_empty() && WorkspaceReq::EMPTY.or(b) == b);
    }

    #[test]
    fn carving_gives_disjoint_slices_or_refuses_a_small_workspace() {
        let mut ws = Workspace::new(WorkspaceReq::slices(&[2, 3]));
        let [x, y] = ws.carve([2, 3]).unwrap();
        x.fill(1.0);
        y.fill(2.0);
        assert_eq!(ws.values, [1.0, 1.0, 2.0, 2.0, 2.0]);
        // a prefix is fine, more is refused (no panic) and leaves the values alone
        assert!(ws.carve([1, 1]).is_ok());
        let refused = ws.carve([4, 2]).unwrap_err();
        assert_eq!(refused, WorkspaceTooSmall { needed: 6, available: 5 });
        assert!(refused.to_string().contains("holds 5 values, the computation needs 6"));
        assert_eq!(ws.values, [1.0, 1.0, 2.0, 2.0, 2.0]);
    }
}
