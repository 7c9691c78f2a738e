//! A free-floating body's frame sits at its centre of mass: its mass properties moved there.

use crate::model::assembly::MassProperties;

impl MassProperties {
    /// The centre of mass (mesh coordinates) and the mass properties about it (parallel-axis
    /// theorem), from those about the mesh origin.
    pub fn about_centre_of_mass(self) -> ([f64; 3], MassProperties) {
        let c = self.first_moment.map(|m| m / self.mass);
        let c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        let mut inertia = self.inertia;
        for i in 0..3 {
            for j in 0..3 {
                inertia[3 * i + j] -= self.mass * (if i == j { c2 } else { 0.0 } - c[i] * c[j]);
            }
        }
        (c, MassProperties { mass: self.mass, first_moment: [0.0; 3], inertia, volume: self.volume })
    }
}
