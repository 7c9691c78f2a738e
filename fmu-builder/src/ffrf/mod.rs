//! Stage 4, ffrf: the floating-frame-of-reference terms of the reduced body. Inertia invariants
//! (`invariants`), inertial load cases and their reduced projections (`inertia`), and geometric
//! stiffening under unit loads (`stiffening`); `rows` holds the fields node by node for the
//! mass products both of the first two need.

pub mod inertia;
pub mod invariants;
pub mod prestress;
pub mod rows;
pub mod scene_loads;
pub mod stiffening;
