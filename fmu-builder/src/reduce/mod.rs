//! Stage 3, reduce: the reduction basis of the coupled model (`basis`: Craig-Bampton, modal with
//! static correction, Krylov moment matching), the frequency responses of the full and reduced
//! models (`frf`), the choice of reduced order (`order`), the cutoff between dynamic and
//! quasi-static modes (`cutoff`), and the accuracy comparison against
//! the full model that every build must pass (`accuracy`).

pub mod accuracy;
pub mod band_response;
pub mod basis;
pub mod compared_band;
pub mod cutoff;
pub mod damping;
pub mod experiment;
pub mod free_body;
pub mod frf;
pub mod order;
pub mod order_selection;
