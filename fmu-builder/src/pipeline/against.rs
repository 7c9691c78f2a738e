//! A numerical failure deep in a stage, put against the input that drives that stage, with what
//! to change: the user fixes their input, not our code. The failure stays the error's source.

use crate::error::{InputHint, Result};
use std::path::Path;

/// The mesh and material, when assembling them fails.
pub(super) const GEOMETRY: InputHint =
    InputHint { field: "geometry", hint: "check the mesh (element shapes, node order) and the material" };

/// The model, when a factorisation fails: a mechanism or a mount that does not hold the part.
const MODEL: InputHint = InputHint {
    field: "geometry",
    hint: "check the mesh for mechanisms and extreme element proportions, and that the mount flange (flanges[].nodes) holds the part",
};

/// The reduction's settings, for any other numerical failure of the reduction.
const REDUCTION: InputHint = InputHint {
    field: "reduction",
    hint: "change the reduction (method, reduction.modes or max_frequency, expansion points, scene.band and tolerance) or check \
           that the flanges hold the part and the material and damping are those of a real solid",
};

pub(super) trait Against<T> {
    /// A numerical failure as one of the input's `place`; other errors unchanged.
    fn against(self, file: &Path, place: InputHint) -> Result<T>;
    /// A numerical failure of the reduction, against the input most likely behind it: a
    /// factorisation that fails is the model's (mesh, flanges), anything else the reduction's
    /// settings.
    fn against_stage(self, file: &Path) -> Result<T>;
}

impl<T> Against<T> for Result<T> {
    fn against(self, file: &Path, place: InputHint) -> Result<T> {
        self.map_err(|e| e.in_input(file, place))
    }

    fn against_stage(self, file: &Path) -> Result<T> {
        self.map_err(|e| {
            let place = match &e {
                e if e.is_singular() => MODEL,
                _ => REDUCTION,
            };
            e.in_input(file, place)
        })
    }
}
