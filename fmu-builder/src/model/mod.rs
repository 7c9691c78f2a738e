//! Stage 2, model: the finite-element model of the part. Element matrices (`fe`), assembly of the
//! free part (`assembly`) on the pattern of its node graph (`node_graph`), the part from
//! whichever source the spec names (`part`), the flanges' slave nodes (`flange`) and their
//! coupling to six-DoF masters (`rigid_coupling`, rigid or distributing as `distributing`
//! defines, its sparse T^T A T in `congruence`), and
//! writers of the full model for CalculiX and Matrix Market (`export`).

pub mod assembly;
mod centre_of_mass;
mod congruence;
pub mod connectivity;
pub mod distributing;
pub mod export;
pub mod fe;
pub mod flange;
mod node_graph;
pub mod part;
pub mod rigid_coupling;
pub mod stress;
pub mod vtk;
