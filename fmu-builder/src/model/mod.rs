//! Stage 2, model: the finite-element model of the part. Element matrices (`fe`), assembly of the
//! free part (`assembly`), the part from whichever source the spec names (`part`), the flanges'
//! slave nodes (`flange`) and their rigid coupling to six-DoF masters (`rigid_coupling`), and
//! writers of the full model for CalculiX and Matrix Market (`export`).

pub mod assembly;
pub mod connectivity;
pub mod export;
pub mod fe;
pub mod flange;
pub mod part;
pub mod rigid_coupling;
