//! What a build produces before packaging: the spec, the FE model it came from, the basis, the
//! reduced body and the report.

use crate::input::spec::Spec;
use crate::model::flange::Flange;
use crate::model::part::Part;
use crate::model::rigid_coupling::Assembled;
use crate::output::report::Report;
use crate::reduce::basis::Basis;
use fmu_runtime::reduced::ReducedBody;

pub struct Built {
    pub spec: Spec,
    pub part: Part,
    pub flanges: Vec<Flange>,
    pub model: Assembled,
    pub basis: Basis,
    pub reduced: ReducedBody,
    pub report: Report,
}
