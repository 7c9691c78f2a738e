//! The table of a body: its families laid out, one variable per place, value references 1.. in
//! order.

use super::family::{At, Family, Nominal, Scope, Shape, StartRule, Structure, Value};
use super::{FAMILIES, Quantity, Start, Variable, VariableTable, modal_nominals};
use crate::reduced::ReducedBody;
use fmi2::{Initial, VarType};
use std::collections::HashMap;

const AXES: [&str; 3] = ["x", "y", "z"];

impl VariableTable {
    pub fn new(body: &ReducedBody) -> Self {
        let (nd, nr) = (body.n_dynamic(), body.n_relaxing());
        let structure = Structure {
            n_dynamic: nd,
            n_integrated: nd + nr,
            solved_modes: body.n_modes() > nd,
            rotates: body.rotation.is_some(),
            free: body.free_floating,
        };
        let mut table = Self { variables: Vec::new(), n_dynamic: nd, n_relaxing: nr, structure };
        let layout = Layout { body, nominal: modal_nominals(body) };
        // a flange's (a stress point's) families follow one another, flange by flange
        for run in FAMILIES.chunk_by(|a, b| a.scope == b.scope) {
            for owner in 0..layout.owners(run[0].scope) {
                for family in run {
                    for at in places(family.shape, owner, body.n_modes()) {
                        let variable = layout.variable(&table, family, at);
                        table.variables.push(variable);
                    }
                }
            }
        }
        table.link_derivatives();
        table
    }

    /// Points each state derivative at its state.
    fn link_derivatives(&mut self) {
        let states: HashMap<_, u32> = self
            .variables
            .iter()
            .filter(|v| self.is_state(v.quantity))
            .filter_map(|v| v.quantity.role().map(|role| ((role, v.quantity.at), v.vr)))
            .collect();
        for v in &mut self.variables {
            if let Some(role) = v.quantity.family.derivative_of {
                v.derivative_of = states.get(&(role, v.quantity.at)).copied();
            }
        }
    }
}

/// The places of a family within one owner, in table order.
fn places(shape: Shape, owner: usize, n_modes: usize) -> Vec<At> {
    let at = |i, j| At { owner, i, j };
    match shape {
        Shape::Scalar => vec![at(0, 0)],
        Shape::Vector(n) => (0..n).map(|i| at(i, 0)).collect(),
        Shape::Matrix => (0..9).map(|k| at(k / 3, k % 3)).collect(),
        Shape::Modes => (0..n_modes).map(|i| at(i, 0)).collect(),
        Shape::Component(i) => vec![at(i, 0)],
    }
}

struct Layout<'b> {
    body: &'b ReducedBody,
    nominal: Vec<f64>,
}

impl Layout<'_> {
    fn owners(&self, scope: Scope) -> usize {
        let b = self.body;
        match scope {
            Scope::Every => 1,
            Scope::Mounted => usize::from(!b.free_floating),
            Scope::Free => usize::from(b.free_floating),
            Scope::Flange => b.flanges.len(),
            Scope::StressPoint => b.stress_points.len(),
        }
    }

    fn variable(&self, table: &VariableTable, family: &'static Family, at: At) -> Variable {
        let quantity = Quantity { family, at };
        let dynamic = at.i < table.n_dynamic;
        let (initial, start) = match family.start {
            StartRule::None => (family.initial, None),
            StartRule::Zero => (family.initial, Some(Start::Real(0.0))),
            StartRule::Identity => (family.initial, Some(Start::Real(if at.i == at.j { 1.0 } else { 0.0 }))),
            StartRule::False => (family.initial, Some(Start::Boolean(false))),
            StartRule::MassDamping => (family.initial, Some(Start::Real(self.body.alpha))),
            StartRule::StiffnessDamping => (family.initial, Some(Start::Real(self.body.beta))),
            StartRule::DynamicModes if dynamic => (Some(Initial::Approx), Some(Start::Real(0.0))),
            StartRule::DynamicModes => (Some(Initial::Calculated), None),
        };
        let state = table.is_state(quantity);
        let nominal = match family.nominal {
            Nominal::ModalCoordinate if state => Some(self.nominal[at.i]),
            Nominal::ModalVelocity if state => Some(self.body.omega[at.i] * self.nominal[at.i]),
            _ => None,
        };
        Variable {
            vr: table.variables.len() as u32 + 1,
            name: self.name(family, at),
            description: self.description(table, family, at),
            var_type: match family.value {
                Value::Real(_) => VarType::Real,
                Value::Switch => VarType::Boolean,
            },
            causality: family.causality,
            variability: family.variability,
            initial,
            start,
            unit: family.unit,
            quantity,
            derivative_of: None,
            nominal,
        }
    }

    fn owner_name(&self, family: &Family, at: At) -> Option<(&'static str, &str)> {
        let b = self.body;
        match family.scope {
            Scope::Mounted => Some(("<mount>", &b.mount)),
            Scope::Flange => Some(("<flange>", &b.flanges[at.owner].name)),
            Scope::StressPoint => Some(("<point>", &b.stress_points[at.owner].name)),
            Scope::Every | Scope::Free => None,
        }
    }

    /// The pattern's indices numbered, then its owner named (so that no name is read as a
    /// pattern).
    fn name(&self, family: &Family, at: At) -> String {
        let name = family
            .pattern
            .replace("[i,j]", &format!("[{},{}]", at.i + 1, at.j + 1))
            .replace("[i]", &format!("[{}]", at.i + 1))
            .replace("[k]", &format!("[{}]", at.i + 1));
        match self.owner_name(family, at) {
            Some((placeholder, owner)) => name.replace(placeholder, owner),
            None => name,
        }
    }

    fn description(&self, table: &VariableTable, family: &Family, at: At) -> String {
        let mut text = family.description.to_string();
        if !text.contains('{') {
            return text;
        }
        let b = self.body;
        let number = (at.i + 1).to_string();
        let kind = if at.i < table.n_dynamic {
            ""
        } else if at.i < table.n_dynamic + table.n_relaxing {
            ", relaxing in Model Exchange: damped without inertia"
        } else {
            ", quasi-static in Model Exchange"
        };
        let fields: [(&str, &dyn Fn() -> String); 7] = [
            ("{axis}", &|| AXES.get(at.i).copied().unwrap_or_default().to_string()),
            ("{row}", &|| number.clone()),
            ("{column}", &|| (at.j + 1).to_string()),
            ("{index}", &|| number.clone()),
            ("{mode}", &|| number.clone()),
            ("{frequency}", &|| format!("{:.4}", b.omega[at.i] / (2.0 * std::f64::consts::PI))),
            ("{kind}", &|| kind.to_string()),
        ];
        for (placeholder, value) in fields {
            if text.contains(placeholder) {
                text = text.replace(placeholder, &value());
            }
        }
        // last: the point's description is the stress point's own text, never a template
        if family.scope == Scope::StressPoint {
            text = text.replace("{point}", &b.stress_points[at.owner].description);
        }
        text
    }
}
