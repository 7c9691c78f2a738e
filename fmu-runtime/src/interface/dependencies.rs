//! The ModelStructure of a body, from its families' dependency rules.

use super::family::{Initially, Role};
use super::{Variable, VariableTable};

impl VariableTable {
    /// Inputs and states a variable depends on (for ModelStructure), ascending.
    pub fn dependencies(&self, var: &Variable) -> Vec<u32> {
        let s = &self.structure;
        if s.free {
            // a free body's frame couples everything: every output and derivative may depend on
            // every state and load
            return self.select(|k| self.is_state(*k) || k.role().is_some_and(Role::is_flange_load));
        }
        let q = var.quantity;
        self.select(|k| (q.family.depends)(s, q.at, k))
    }

    /// Inputs a variable depends on during initialisation (InitialUnknowns): the states are
    /// unknowns then, so a dependence on a state stands for what the state starts from. Parameters
    /// are knowns of the initialisation too (FMI 2.0, ModelStructure).
    pub fn initial_dependencies(&self, var: &Variable) -> Vec<u32> {
        let s = &self.structure;
        if let Initially::StartsFrom(rule) = var.quantity.family.initially {
            return self.select(|k| rule(s, k));
        }
        let mut deps = Vec::new();
        for vr in self.dependencies(var) {
            let Some(v) = self.get(vr) else { continue };
            match v.quantity.family.initially {
                Initially::StartsFrom(rule) => deps.extend(self.select(|k| rule(s, k))),
                _ => deps.push(vr),
            }
        }
        // gravity and damping enter the modal acceleration directly, and through a free body's
        // frame every unknown
        if s.free || matches!(var.quantity.family.initially, Initially::ThroughAcceleration) {
            deps.extend(self.select(|k| k.role().is_some_and(Role::is_load_parameter)));
        }
        deps.sort_unstable();
        deps.dedup();
        deps
    }
}
