//! The body's own degrees of freedom: what its equations integrate.

use super::FrameState;

/// The body's generalized coordinates and their rates: the modal coordinates q, q' and, for a
/// free-floating body, the rigid frame's pose and velocity. The host's integrator (Model
/// Exchange) or the step (Co-Simulation) moves them; everything the body evaluates follows from
/// them and the [`BodyInputs`](super::BodyInputs). Kept in one struct so that a saved state
/// ([`BodyState`](super::BodyState)) takes and gives them as they are, and a step's undo copies
/// them in one call.
#[derive(Debug, Clone, PartialEq)]
pub struct Coordinates<T = f64> {
    pub q: Vec<T>,
    pub qd: Vec<T>,
    /// Some exactly for free-floating bodies.
    pub frame: Option<FrameState<T>>,
}

impl<T: Copy> Coordinates<T> {
    pub fn map<U>(&self, f: impl Fn(T) -> U) -> Coordinates<U> {
        Coordinates {
            q: self.q.iter().map(|&x| f(x)).collect(),
            qd: self.qd.iter().map(|&x| f(x)).collect(),
            frame: self.frame.map(|fr| fr.map(&f)),
        }
    }

    /// `other`'s values into this one's storage (no allocation; the sizes must agree).
    pub(super) fn copy_from(&mut self, other: &Self) {
        self.q.copy_from_slice(&other.q);
        self.qd.copy_from_slice(&other.qd);
        self.frame = other.frame;
    }
}
