use super::family::{Scope, Shape, StateOf};
use super::*;
use crate::reduced::{free_two_mode_body, two_mode_body};
use std::collections::BTreeSet;

#[test]
fn every_name_finds_its_value_reference() {
    let table = VariableTable::new(&two_mode_body());
    for v in &table.variables {
        assert_eq!(table.value_reference(&v.name), Some(v.vr), "{}", v.name);
        assert_eq!(table.get(v.vr).map(|w| &w.name), Some(&v.name));
    }
    assert_eq!(table.value_reference("tip.f[1]"), table.variable("tip.f[1]").map(|v| v.vr));
    assert!(table.value_reference("tip.f[1]").is_some());
    assert_eq!(table.value_reference("no.such[1]"), None);
}

/// The pattern's index is the shape's, and no two families share a pattern.
#[test]
fn patterns_agree_with_shapes() {
    let mut seen = BTreeSet::new();
    for f in FAMILIES {
        assert!(seen.insert(f.pattern), "{} twice", f.pattern);
        let index = match f.shape {
            Shape::Scalar | Shape::Component(_) => "",
            Shape::Vector(_) => "[i]",
            Shape::Matrix => "[i,j]",
            Shape::Modes => "[k]",
        };
        let bracket = f.pattern.find('[').map_or("", |at| &f.pattern[at..at + f.pattern[at..].find(']').unwrap() + 1]);
        assert_eq!(bracket, index, "{}", f.pattern);
    }
    let stress: Vec<&str> = FAMILIES
        .iter()
        .filter(|f| f.scope == Scope::StressPoint)
        .map(|f| f.pattern.trim_start_matches("<point>."))
        .collect();
    assert_eq!(stress, STRESS_COMPONENTS);
    for (i, f) in FAMILIES.iter().filter(|f| f.scope == Scope::StressPoint).enumerate() {
        assert_eq!(f.shape, Shape::Component(i), "{}", f.pattern);
    }
}

/// What the host sets can be set and read, an input's rate set, and every input and state can
/// seed a directional derivative.
#[test]
fn knowns_and_states_are_accessible() {
    for f in FAMILIES {
        let real = matches!(f.value, Value::Real(_));
        if real && matches!(f.causality, fmi2::Causality::Input | fmi2::Causality::Parameter) {
            assert!(f.write.is_some() && f.role.is_some(), "{}", f.pattern);
        }
        if f.causality == fmi2::Causality::Input {
            assert!(f.seed.is_some() && f.rate.is_some(), "{}", f.pattern);
        }
        if f.state != StateOf::Never {
            assert!(f.seed.is_some() && f.role.is_some(), "{}", f.pattern);
        }
        assert_eq!(f.causality == fmi2::Causality::Input, f.rate.is_some(), "{}", f.pattern);
    }
}

/// The bodies docs/VARIABLES.md names in its `in` column.
fn scope_in_docs(scope: Scope) -> &'static str {
    match scope {
        Scope::Every | Scope::Flange => "every body",
        Scope::Mounted => "mounted body",
        Scope::Free => "free-floating body",
        Scope::StressPoint => "with `outputs.stress`",
    }
}

/// docs/VARIABLES.md's table (generated from built FMUs by tests/gen_variables.py) lists
/// exactly the families: pattern, causality, variability, unit and which bodies have them.
#[test]
fn variables_md_lists_the_families() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/VARIABLES.md")).unwrap();
    let section = doc.split("<!-- BEGIN generated").nth(1).and_then(|s| s.split("<!-- END").next()).unwrap();
    let documented: BTreeSet<[String; 5]> = section
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split(" | ").map(str::trim).collect();
            let name = cells[0].trim_matches('`').replace("stress.n<id>.", "<point>.");
            [name, cells[1].into(), cells[2].into(), cells[3].into(), cells[5].into()]
        })
        .collect();
    let described: BTreeSet<[String; 5]> = FAMILIES
        .iter()
        .map(|f| {
            [
                f.pattern.to_string(),
                format!("{:?}", f.causality).to_lowercase(),
                format!("{:?}", f.variability).to_lowercase(),
                f.unit.unwrap_or("-").to_string(),
                scope_in_docs(f.scope).to_string(),
            ]
        })
        .collect();
    let missing: Vec<_> = described.difference(&documented).collect();
    let stale: Vec<_> = documented.difference(&described).collect();
    assert!(
        missing.is_empty() && stale.is_empty(),
        "docs/VARIABLES.md differs from the families (tests/gen_variables.py --write): missing {missing:?}, stale {stale:?}"
    );
}

/// Each state derivative names its state, and the derivatives follow the state order.
#[test]
fn derivatives_point_at_their_states() {
    for body in [two_mode_body(), free_two_mode_body()] {
        let table = VariableTable::new(&body);
        let states = table.states();
        let derivatives = table.derivatives();
        assert_eq!(states.len(), derivatives.len());
        for (s, d) in states.iter().zip(&derivatives) {
            assert_eq!(table.get(*d).unwrap().derivative_of, Some(*s));
        }
    }
}
