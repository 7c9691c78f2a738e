//! Reduced geometric stiffness of every unit prestress the scene can apply: centrifugal and
//! angular-acceleration loads if it rotates, translational ones if it has gravity or
//! acceleration, and unit wrenches at every force flange. The runtime scales each by the load's
//! current value (stiffening linear in the loads).

use crate::error::Result;
use crate::ffrf::inertia::{self, LoadCase};
use crate::ffrf::stiffening::reduced_geometric_stiffness;
use crate::input::mesh::Mesh;
use crate::input::spec::Role;
use crate::linalg::sparse::SpdSolve;
use crate::model::assembly::SolidMaterial;
use crate::model::flange::Flange;
use crate::model::rigid_coupling::Assembled;
use faer::{Mat, MatRef};
use fmu_runtime::reduced::Stiffening;

/// The mounted body and what its prestress fields are computed from.
pub struct Prestress<'a> {
    pub mesh: &'a Mesh,
    pub materials: &'a [SolidMaterial],
    pub flanges: &'a [Flange],
    pub model: &'a Assembled,
    pub solver: &'a dyn SpdSolve,
    pub origin: [f64; 3],
    /// The scene's inertial cases and, in the same order, their static shapes where the basis
    /// has them already (mounted DoFs).
    pub cases: &'a [LoadCase],
    pub load_shapes: Option<&'a Mat<f64>>,
    /// The basis on the mesh (3N x r).
    pub phi_mesh: MatRef<'a, f64>,
}

impl Prestress<'_> {
    /// The stiffening terms: `rotates` adds the centrifugal and Euler cases, `translates` the
    /// translational ones; every force flange adds its six unit wrenches.
    pub fn terms(&self, rotates: bool, translates: bool) -> Result<Stiffening> {
        let mut out = Stiffening::default();
        if rotates {
            out.centrifugal = Some(self.centrifugal()?);
            out.euler = Some(self.cases_along(LoadCase::Euler)?);
        }
        if translates {
            out.translation = Some(self.cases_along(LoadCase::Translation)?);
        }
        for k in 0..self.flanges.len() {
            if self.flanges[k].role == Role::Force {
                out.flanges.push(self.flange_wrenches(k)?);
            }
        }
        Ok(out)
    }

    /// K_ab for w_a w_b, row-major over (a, b): K_aa for w_a^2, the symmetric K_ab split evenly
    /// over (a, b) and (b, a) for a != b.
    fn centrifugal(&self) -> Result<Vec<f64>> {
        let rr = self.phi_mesh.ncols().pow(2);
        let mut centrifugal = vec![0.0; 9 * rr];
        for a in 0..3 {
            for b in a..3 {
                let k = self.shape_of(LoadCase::Centrifugal(a, b))?;
                let share = if a == b { 1.0 } else { 0.5 };
                for target in [3 * a + b, 3 * b + a] {
                    for i in 0..rr {
                        centrifugal[target * rr + i] = share * k[i];
                    }
                }
            }
        }
        Ok(centrifugal)
    }

    /// The three cases `case(0..3)`, one r x r block each.
    fn cases_along(&self, case: fn(usize) -> LoadCase) -> Result<Vec<f64>> {
        let mut blocks = Vec::with_capacity(3 * self.phi_mesh.ncols().pow(2));
        for a in 0..3 {
            blocks.extend(self.shape_of(case(a))?);
        }
        Ok(blocks)
    }

    /// The six unit wrenches at force flange `k`, one r x r block each.
    fn flange_wrenches(&self, k: usize) -> Result<Vec<f64>> {
        let nc = self.model.dofs.n_clamped();
        let first = self.model.dofs.flange_first[k];
        let mut unit = Mat::<f64>::zeros(nc, 6);
        for i in 0..6 {
            unit[(first + i, i)] = 1.0;
        }
        self.solver.solve_refined(unit.as_mut());
        let mut blocks = Vec::with_capacity(6 * self.phi_mesh.ncols().pow(2));
        for i in 0..6 {
            blocks.extend(self.reduce_shape(unit.subcols(i, 1))?);
        }
        Ok(blocks)
    }

    /// The static shape of an inertial case: the basis' own where it has one, else solved.
    fn shape_of(&self, case: LoadCase) -> Result<Vec<f64>> {
        let col = self.cases.iter().position(|c| *c == case);
        match (col, self.load_shapes) {
            (Some(c), Some(shapes)) => self.reduce_shape(shapes.subcols(c, 1)),
            _ => {
                let nodes = &self.mesh.nodes;
                let f = inertia::inertial_load(self.model, nodes, self.origin, case);
                let mut u = inertia::restrict(self.model, nodes, self.flanges, f.as_ref());
                self.solver.solve_refined(u.as_mut());
                self.reduce_shape(u.as_ref())
            }
        }
    }

    /// The reduced geometric stiffness (r x r, row-major) of the prestress of the static field
    /// `u_c` (mounted DoFs).
    fn reduce_shape(&self, u_c: MatRef<'_, f64>) -> Result<Vec<f64>> {
        let r = self.phi_mesh.ncols();
        let u = inertia::expand(self.model, &self.mesh.nodes, self.flanges, u_c);
        let u: Vec<f64> = (0..u.nrows()).map(|i| u[(i, 0)]).collect();
        let k = reduced_geometric_stiffness(self.mesh, self.materials, &u, self.phi_mesh)?;
        Ok((0..r * r).map(|i| k[(i / r, i % r)]).collect())
    }
}
