//! modelDescription.xml from the runtime's variable table.
//!
//! Everything is checked and resolved first (`Plan`), then written: the writing itself can only
//! fail on I/O, which a `Vec<u8>` sink does not do. ModelStructure follows the FMI 2.0 standard
//! (docs/REFERENCES.md section 5), the most common reason importers reject an FMU: explicit
//! (possibly empty) dependency lists everywhere, because an absent attribute means "depends on
//! everything".

use crate::error::SharedCause;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::io;

use fmi2::access::effective_initial;
use fmi2::logger::Category;
use fmi2::{Causality, Initial, VarInfo, VarType, Variability};
use fmu_runtime::interface::{Start, UNITS, Variable, VariableTable};
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};

use super::{FmuError, is_model_identifier};

#[derive(Debug, Clone, PartialEq)]
pub struct DefaultExperiment {
    pub start: f64,
    pub stop: f64,
    /// Communication step; some importers use it as their fixed step.
    pub step: f64,
    pub tolerance: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    pub model_name: String,
    pub model_identifier: String,
    pub description: String,
    /// Must equal the GUID stored in the reduced model: the runtime refuses a mismatch.
    pub guid: String,
    pub generation_tool: String,
    /// Written as `generationDateAndTime` (the FMI 2.0 attribute name); xs:dateTime, e.g. `2026-11-22T07:00:00Z` (see [`xs_date_time`]).
    pub generation_date_time: String,
    pub default_experiment: DefaultExperiment,
}

type Result<T> = std::result::Result<T, FmuError>;

fn err<T>(message: impl Into<String>) -> Result<T> {
    Err(FmuError::Description(message.into()))
}

/// The XML text of modelDescription.xml, or what makes the model not describable.
pub fn model_description_xml(info: &ModelInfo, table: &VariableTable) -> Result<String> {
    check_info(info)?;
    let plan = Plan::new(table)?;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    write_document(&mut w, info, &plan)
        .map_err(|e| FmuError::Xml { what: "writing the XML failed", cause: SharedCause::new(e) })?;
    String::from_utf8(w.into_inner())
        .map_err(|e| FmuError::Xml { what: "the XML is not UTF-8", cause: SharedCause::new(e) })
}

/// A time as xs:dateTime in UTC (`YYYY-MM-DDThh:mm:ssZ`), from seconds since the Unix epoch
/// (e.g. SOURCE_DATE_EPOCH for reproducible builds).
pub fn xs_date_time(unix_seconds: u64) -> String {
    let time = std::time::UNIX_EPOCH + std::time::Duration::from_secs(unix_seconds);
    humantime::format_rfc3339_seconds(time).to_string()
}

pub(super) fn check_info(info: &ModelInfo) -> Result<()> {
    for (field, value) in
        [("modelName", &info.model_name), ("guid", &info.guid), ("generationTool", &info.generation_tool)]
    {
        if value.trim().is_empty() {
            return err(format!("{field} is empty"));
        }
    }
    if !is_model_identifier(&info.model_identifier) {
        return err(format!(
            "modelIdentifier '{}' is not a valid C identifier (letters, digits, '_', not starting with a digit)",
            info.model_identifier
        ));
    }
    if !is_xs_date_time(&info.generation_date_time) {
        return err(format!(
            "generationDateAndTime '{}' is not an xs:dateTime such as 2026-11-22T07:00:00Z",
            info.generation_date_time
        ));
    }
    let e = &info.default_experiment;
    let finite = [e.start, e.stop, e.step, e.tolerance].iter().all(|x| x.is_finite());
    if !finite || e.stop <= e.start || e.step <= 0.0 || e.tolerance <= 0.0 {
        return err(format!(
            "DefaultExperiment needs finite startTime < stopTime and positive stepSize and tolerance, got {e:?}"
        ));
    }
    Ok(())
}

/// `[-]YYYY-MM-DDThh:mm:ss[.s+][Z|(+|-)hh:mm]`, with field ranges checked (the FMI schema
/// types the attribute xs:dateTime and validating importers reject anything else).
fn is_xs_date_time(s: &str) -> bool {
    let s = s.strip_prefix('-').unwrap_or(s);
    let (date, rest) = match s.split_once('T') {
        Some(p) => p,
        None => return false,
    };
    let num = |t: &str, n: usize, lo: u32, hi: u32| {
        t.len() == n && t.bytes().all(|b| b.is_ascii_digit()) && t.parse::<u32>().is_ok_and(|v| (lo..=hi).contains(&v))
    };
    let d: Vec<&str> = date.split('-').collect();
    let date_ok = d.len() == 3
        && d[0].len() >= 4
        && d[0].bytes().all(|b| b.is_ascii_digit())
        && num(d[1], 2, 1, 12)
        && num(d[2], 2, 1, 31);
    let (time, zone) = match rest.find(['Z', '+', '-']) {
        Some(i) => rest.split_at(i),
        None => (rest, ""),
    };
    let (hms, frac) = match time.split_once('.') {
        Some((hms, frac)) => (hms, Some(frac)),
        None => (time, None),
    };
    let t: Vec<&str> = hms.split(':').collect();
    let time_ok = t.len() == 3
        && num(t[0], 2, 0, 23)
        && num(t[1], 2, 0, 59)
        && num(t[2], 2, 0, 59)
        && frac.is_none_or(|f| !f.is_empty() && f.bytes().all(|b| b.is_ascii_digit()));
    let zone_ok = zone.is_empty()
        || zone == "Z"
        || (zone.len() == 6 && zone.is_ascii() && {
            let (h, m) = zone[1..].split_at(2);
            num(h, 2, 0, 14) && m.starts_with(':') && num(&m[1..], 2, 0, 59)
        });
    date_ok && time_ok && zone_ok
}

/// A number as xs:double that parses back to the same f64. Debug formatting round-trips and
/// switches to exponent notation for very large or small magnitudes (Display would write
/// hundreds of digits); non-finite values have no place in a start value.
fn xs_double(x: f64, what: &str) -> Result<String> {
    if x.is_finite() { Ok(format!("{x:?}")) } else { err(format!("{what} is {x}, expected a finite number")) }
}

pub(super) fn causality_name(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::CalculatedParameter => "calculatedParameter",
        Causality::Input => "input",
        Causality::Output => "output",
        Causality::Local => "local",
        Causality::Independent => "independent",
    }
}

pub(super) fn variability_name(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

fn initial_name(i: Initial) -> &'static str {
    match i {
        Initial::Exact => "exact",
        Initial::Approx => "approx",
        Initial::Calculated => "calculated",
    }
}

fn effective(v: &Variable) -> Option<Initial> {
    effective_initial(&VarInfo {
        var_type: v.var_type,
        causality: v.causality,
        variability: v.variability,
        initial: v.initial,
    })
}

/// One `<Unknown>` of ModelStructure, with 1-based ModelVariables indices.
struct Unknown {
    index: usize,
    dependencies: Vec<usize>,
}

/// One ScalarVariable with every attribute already resolved to its text.
struct Row<'t> {
    var: &'t Variable,
    start: Option<String>,
    /// 1-based index of the state this variable is the derivative of.
    derivative: Option<usize>,
}

struct Plan<'t> {
    /// Unit name and its base-unit exponents (kg, m, s, rad); all zero for dimensionless.
    units: Vec<(&'t str, [i32; 4])>,
    rows: Vec<Row<'t>>,
    outputs: Vec<Unknown>,
    derivatives: Vec<Unknown>,
    initial_unknowns: Vec<Unknown>,
}

impl<'t> Plan<'t> {
    fn new(table: &'t VariableTable) -> Result<Self> {
        // ModelStructure refers to variables by their position in ModelVariables, the table by
        // value reference: one map between the two, and every reference must resolve.
        let mut index: HashMap<u32, usize> = HashMap::new();
        let mut names = HashSet::new();
        for (i, v) in table.variables.iter().enumerate() {
            if index.insert(v.vr, i + 1).is_some() {
                return err(format!("value reference {} is used twice (again by '{}')", v.vr, v.name));
            }
            if !names.insert(v.name.as_str()) {
                return err(format!("variable name '{}' is used twice", v.name));
            }
        }
        let to_index = |vr: u32, context: &str| -> Result<usize> {
            match index.get(&vr) {
                Some(&i) => Ok(i),
                None => err(format!("{context} refers to value reference {vr}, which no variable has")),
            }
        };
        let unknown = |v: &Variable, deps: Vec<u32>, list: &str| -> Result<Unknown> {
            let context = format!("{list} entry '{}'", v.name);
            let mut dependencies = deps.into_iter().map(|vr| to_index(vr, &context)).collect::<Result<Vec<_>>>()?;
            dependencies.sort_unstable();
            dependencies.dedup();
            Ok(Unknown { index: to_index(v.vr, &context)?, dependencies })
        };
        let var = |vr: u32, list: &str| -> Result<&'t Variable> {
            match table.get(vr) {
                Some(v) if v.vr == vr => Ok(v),
                _ => err(format!("{list} lists value reference {vr}, which no variable has")),
            }
        };

        let mut rows = Vec::with_capacity(table.variables.len());
        let mut units: Vec<(&str, [i32; 4])> = Vec::new();
        for v in &table.variables {
            rows.push(row(v, &to_index)?);
            add_unit(&mut units, v)?;
        }

        let outputs = table
            .variables
            .iter()
            .filter(|v| v.causality == Causality::Output)
            .map(|v| unknown(v, table.dependencies(v), "Outputs"))
            .collect::<Result<Vec<_>>>()?;

        let mut derivatives = Vec::new();
        for vr in table.derivatives() {
            let v = var(vr, "Derivatives")?;
            if v.derivative_of.is_none() {
                return err(format!("'{}' is listed as a state derivative but names no state", v.name));
            }
            derivatives.push(unknown(v, table.dependencies(v), "Derivatives")?);
        }

        // Exactly: outputs, calculated parameters, states and derivatives whose effective
        // initial is approx or calculated; each once, in index order (the BTreeMap).
        let mut initial_candidates: Vec<&Variable> = table
            .variables
            .iter()
            .filter(|v| matches!(v.causality, Causality::Output | Causality::CalculatedParameter))
            .collect();
        for vr in table.states().into_iter().chain(table.derivatives()) {
            initial_candidates.push(var(vr, "the state list")?);
        }
        let mut initial = BTreeMap::new();
        for v in initial_candidates {
            if matches!(effective(v), Some(Initial::Approx | Initial::Calculated)) {
                let u = unknown(v, table.initial_dependencies(v), "InitialUnknowns")?;
                initial.insert(u.index, u);
            }
        }

        Ok(Plan { units, rows, outputs, derivatives, initial_unknowns: initial.into_values().collect() })
    }
}

/// The variable's unit with its base-unit exponents, once per unit.
fn add_unit<'t>(units: &mut Vec<(&'t str, [i32; 4])>, v: &'t Variable) -> Result<()> {
    if let Some(unit) = v.unit
        && !units.iter().any(|(u, _)| *u == unit)
    {
        let exponents = match UNITS.iter().find(|(u, _)| *u == unit) {
            Some((_, e)) => *e,
            None if unit == "1" => [0; 4],
            None => return err(format!("unit '{unit}' of '{}' has no definition in interface::UNITS", v.name)),
        };
        units.push((unit, exponents));
    }
    Ok(())
}

/// Resolves a variable's start and derivative, enforcing where FMI 2.0 requires or forbids a
/// start value (section 2.2.7): FMPy rejects either mistake.
fn row<'t>(v: &'t Variable, to_index: &dyn Fn(u32, &str) -> Result<usize>) -> Result<Row<'t>> {
    let initial = effective(v);
    let needs_start = v.causality == Causality::Input || matches!(initial, Some(Initial::Exact | Initial::Approx));
    let forbids_start = v.causality == Causality::Independent || initial == Some(Initial::Calculated);
    match (&v.start, needs_start, forbids_start) {
        (None, true, _) => return err(format!("'{}' needs a start value (causality and initial require one)", v.name)),
        (Some(_), _, true) => return err(format!("'{}' must not have a start value (it is calculated)", v.name)),
        _ => {}
    }
    let start = match (v.var_type, v.start) {
        (_, None) => None,
        (VarType::Real, Some(Start::Real(x))) => Some(xs_double(x, &format!("start of '{}'", v.name))?),
        (VarType::Boolean, Some(Start::Boolean(b))) => Some(b.to_string()),
        (t, Some(s)) => return err(format!("'{}' is of type {t:?} but has the start value {s:?}", v.name)),
    };
    let derivative = match v.derivative_of {
        Some(vr) if v.var_type == VarType::Real => Some(to_index(vr, &format!("derivative of '{}'", v.name))?),
        Some(_) => return err(format!("'{}' is a derivative but not Real", v.name)),
        None => None,
    };
    if v.unit.is_some() && v.var_type != VarType::Real {
        return err(format!("'{}' has a unit but is not Real", v.name));
    }
    Ok(Row { var: v, start, derivative })
}

pub(super) type W = Writer<Vec<u8>>;

pub(super) fn attrs<'a>(pairs: &'a [(&'a str, String)]) -> impl Iterator<Item = (&'a str, &'a str)> {
    pairs.iter().map(|(k, v)| (*k, v.as_str()))
}

fn write_document(w: &mut W, info: &ModelInfo, plan: &Plan) -> io::Result<()> {
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let root = root_attributes(info);
    w.create_element("fmiModelDescription").with_attributes(attrs(&root)).write_inner_content(|w| {
        write_interfaces(w, &info.model_identifier)?;
        write_units(w, &plan.units)?;
        write_log_categories(w)?;
        write_default_experiment(w, info)?;
        w.create_element("ModelVariables")
            .write_inner_content(|w| plan.rows.iter().try_for_each(|r| write_variable(w, r)))?;
        write_model_structure(w, plan)
    })?;
    Ok(())
}

/// Capability flags: what the runtime's fmi layer implements (fmu-runtime/src/fmi), and what
/// the body model provides (fmu-runtime/src/fmu/mod.rs says so in constants).
fn write_interfaces(w: &mut W, model_identifier: &str) -> io::Result<()> {
    use fmu_runtime::fmu::{CAN_INTERPOLATE_INPUTS, MAX_OUTPUT_DERIVATIVE_ORDER, PROVIDES_DIRECTIONAL_DERIVATIVE};
    let flag = |b: bool| if b { "true" } else { "false" };
    let max_order = MAX_OUTPUT_DERIVATIVE_ORDER.to_string();
    let common = [
        ("modelIdentifier", model_identifier),
        ("needsExecutionTool", "false"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
        // the runtime allocates with Rust's allocator and accepts NULL memory callbacks
        ("canNotUseMemoryManagementFunctions", "true"),
        ("canGetAndSetFMUstate", "true"),
        // fmi2SerializeFMUstate and friends: fmi2/src/serial.rs
        ("canSerializeFMUstate", "true"),
        // exact, by the body's equations in dual numbers (fmu-runtime/src/scalar.rs)
        ("providesDirectionalDerivative", flag(PROVIDES_DIRECTIONAL_DERIVATIVE)),
    ];
    w.create_element("ModelExchange").with_attributes(common).write_empty()?;
    let cs = [
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canInterpolateInputs", flag(CAN_INTERPOLATE_INPUTS)),
        ("maxOutputDerivativeOrder", max_order.as_str()),
    ];
    w.create_element("CoSimulation").with_attributes(common.into_iter().chain(cs)).write_empty()?;
    Ok(())
}

/// The root element's attributes: the model's identity and the naming convention.
pub(super) fn root_attributes(info: &ModelInfo) -> [(&'static str, String); 8] {
    [
        ("fmiVersion", "2.0".to_string()),
        ("modelName", info.model_name.clone()),
        ("guid", info.guid.clone()),
        ("description", info.description.clone()),
        ("generationTool", info.generation_tool.clone()),
        ("generationDateAndTime", info.generation_date_time.clone()),
        ("variableNamingConvention", "structured".to_string()),
        ("numberOfEventIndicators", "0".to_string()),
    ]
}

/// The DefaultExperiment element (its numbers finite: checked in check_info).
pub(super) fn write_default_experiment(w: &mut W, info: &ModelInfo) -> io::Result<()> {
    let e = &info.default_experiment;
    let experiment = [
        ("startTime", format!("{:?}", e.start)),
        ("stopTime", format!("{:?}", e.stop)),
        ("tolerance", format!("{:?}", e.tolerance)),
        ("stepSize", format!("{:?}", e.step)),
    ];
    w.create_element("DefaultExperiment").with_attributes(attrs(&experiment)).write_empty()?;
    Ok(())
}

pub(super) fn write_units(w: &mut W, units: &[(&str, [i32; 4])]) -> io::Result<()> {
    if units.is_empty() {
        return Ok(()); // the schema wants at least one Unit inside UnitDefinitions
    }
    w.create_element("UnitDefinitions").write_inner_content(|w| {
        for (name, e) in units {
            let base: Vec<(&str, String)> = ["kg", "m", "s", "rad"]
                .into_iter()
                .zip(e)
                .filter(|(_, x)| **x != 0)
                .map(|(k, x)| (k, x.to_string()))
                .collect();
            w.create_element("Unit").with_attribute(("name", *name)).write_inner_content(|w| {
                // An empty BaseUnit states "dimensionless" (all exponents default to 0).
                w.create_element("BaseUnit").with_attributes(attrs(&base)).write_empty()?;
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

pub(super) fn write_log_categories(w: &mut W) -> io::Result<()> {
    w.create_element("LogCategories").write_inner_content(|w| {
        for c in Category::ALL {
            let description = match c {
                Category::LogAll => "Everything the model reports",
                Category::LogStatusWarning => {
                    "Warnings (the call still succeeds with fmi2OK) and calls that return fmi2Discard"
                }
                Category::LogStatusError => "Calls that return fmi2Error (always reported)",
            };
            let name = c.name().to_string_lossy();
            w.create_element("Category")
                .with_attributes([("name", name.as_ref()), ("description", description)])
                .write_empty()?;
        }
        Ok(())
    })?;
    Ok(())
}

fn write_variable(w: &mut W, r: &Row) -> io::Result<()> {
    let v = r.var;
    let mut sv = vec![
        ("name", v.name.clone()),
        ("valueReference", v.vr.to_string()),
        ("description", v.description.clone()),
        ("causality", causality_name(v.causality).to_string()),
        ("variability", variability_name(v.variability).to_string()),
    ];
    if let Some(i) = v.initial {
        sv.push(("initial", initial_name(i).to_string()));
    }
    let mut ty = Vec::new();
    if let Some(unit) = v.unit {
        ty.push(("unit", unit.to_string()));
    }
    if let Some(start) = &r.start {
        ty.push(("start", start.clone()));
    }
    if let Some(nominal) = v.nominal {
        ty.push(("nominal", format!("{nominal:e}")));
    }
    if let Some(d) = r.derivative {
        ty.push(("derivative", d.to_string()));
    }
    let element = match v.var_type {
        VarType::Real => "Real",
        VarType::Integer => "Integer",
        VarType::Boolean => "Boolean",
        VarType::String => "String",
    };
    w.create_element("ScalarVariable").with_attributes(attrs(&sv)).write_inner_content(|w| {
        w.create_element(element).with_attributes(attrs(&ty)).write_empty()?;
        Ok(())
    })?;
    Ok(())
}

fn write_model_structure(w: &mut W, plan: &Plan) -> io::Result<()> {
    w.create_element("ModelStructure").write_inner_content(|w| {
        for (list, unknowns) in [
            ("Outputs", &plan.outputs),
            ("Derivatives", &plan.derivatives),
            ("InitialUnknowns", &plan.initial_unknowns),
        ] {
            // The schema forbids empty lists: leave the element out instead.
            if unknowns.is_empty() {
                continue;
            }
            w.create_element(list).write_inner_content(|w| {
                for u in unknowns.iter() {
                    let deps: Vec<String> = u.dependencies.iter().map(|d| d.to_string()).collect();
                    let kinds = vec!["dependent"; deps.len()];
                    let a = [
                        ("index", u.index.to_string()),
                        ("dependencies", deps.join(" ")),
                        ("dependenciesKind", kinds.join(" ")),
                    ];
                    w.create_element("Unknown").with_attributes(attrs(&a)).write_empty()?;
                }
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmu_runtime::reduced::two_mode_body;
    use quick_xml::Reader;

    fn info() -> ModelInfo {
        ModelInfo {
            model_name: "Test".into(),
            model_identifier: "Test".into(),
            description: "Reduced flexible body <test> & co".into(),
            guid: "{test}".into(),
            generation_tool: "fmu-builder test".into(),
            generation_date_time: "2026-11-22T07:00:00Z".into(),
            default_experiment: DefaultExperiment { start: 0.0, stop: 1.0, step: 1e-3, tolerance: 1e-6 },
        }
    }

    /// Element path (names from the root) and attributes of every element, in document order.
    struct Element {
        path: Vec<String>,
        attrs: HashMap<String, String>,
    }

    impl Element {
        fn attr(&self, key: &str) -> Option<&str> {
            self.attrs.get(key).map(String::as_str)
        }
        fn parent(&self) -> &str {
            self.path.iter().rev().nth(1).map_or("", String::as_str)
        }
        fn name(&self) -> &str {
            self.path.last().map_or("", String::as_str)
        }
    }

    fn parse(xml: &str) -> Vec<Element> {
        let mut reader = Reader::from_str(xml);
        let mut stack: Vec<String> = Vec::new();
        let mut out = Vec::new();
        loop {
            let event = reader.read_event().expect("well-formed XML");
            let (e, empty) = match &event {
                Event::Start(e) => (e, false),
                Event::Empty(e) => (e, true),
                Event::End(_) => {
                    stack.pop();
                    continue;
                }
                Event::Eof => break,
                _ => continue,
            };
            let name = e.name().as_ref().to_string();
            let attrs = e
                .attributes()
                .map(|a| {
                    let a = a.unwrap();
                    (
                        a.key.as_ref().to_string(),
                        a.normalized_value(quick_xml::XmlVersion::Implicit1_0).unwrap().into_owned(),
                    )
                })
                .collect();
            stack.push(name);
            out.push(Element { path: stack.clone(), attrs });
            if empty {
                stack.pop();
            }
        }
        assert!(stack.is_empty());
        out
    }

    fn unknowns<'e>(doc: &'e [Element], list: &str) -> Vec<&'e Element> {
        doc.iter().filter(|e| e.name() == "Unknown" && e.parent() == list).collect()
    }

    fn indices(s: &str) -> Vec<usize> {
        s.split_whitespace().map(|x| x.parse().unwrap()).collect()
    }

    fn setup() -> (VariableTable, Vec<Element>, HashMap<u32, usize>) {
        let table = VariableTable::new(&two_mode_body());
        let xml = model_description_xml(&info(), &table).unwrap();
        let doc = parse(&xml);
        let vars: Vec<&Element> = doc.iter().filter(|e| e.name() == "ScalarVariable").collect();
        assert_eq!(vars.len(), table.variables.len());
        // index of a value reference, read from the XML itself
        let index =
            vars.iter().enumerate().map(|(i, e)| (e.attr("valueReference").unwrap().parse().unwrap(), i + 1)).collect();
        (table, doc, index)
    }

    fn check_unknown(u: &Element, expected_deps: Vec<usize>) {
        let deps = indices(u.attr("dependencies").expect("explicit dependencies"));
        let kinds: Vec<&str> =
            u.attr("dependenciesKind").expect("explicit dependenciesKind").split_whitespace().collect();
        assert_eq!(deps, expected_deps, "Unknown index {:?}", u.attr("index"));
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
        assert_eq!(kinds.len(), deps.len());
        assert!(kinds.iter().all(|k| *k == "dependent"));
    }

    #[test]
    fn top_level_order_follows_the_schema() {
        let (_, doc, _) = setup();
        let top: Vec<&str> = doc.iter().filter(|e| e.path.len() == 2).map(|e| e.name()).collect();
        assert_eq!(
            top,
            [
                "ModelExchange",
                "CoSimulation",
                "UnitDefinitions",
                "LogCategories",
                "DefaultExperiment",
                "ModelVariables",
                "ModelStructure"
            ]
        );
        let root = &doc[0];
        assert_eq!(root.attr("fmiVersion"), Some("2.0"));
        assert_eq!(root.attr("variableNamingConvention"), Some("structured"));
        assert_eq!(root.attr("generationDateAndTime"), Some("2026-11-22T07:00:00Z"));
        assert_eq!(root.attr("description"), Some("Reduced flexible body <test> & co"));
        let cs = doc.iter().find(|e| e.name() == "CoSimulation").unwrap();
        assert_eq!(cs.attr("canHandleVariableCommunicationStepSize"), Some("true"));
        assert_eq!(cs.attr("canInterpolateInputs"), Some("true"));
        assert_eq!(cs.attr("maxOutputDerivativeOrder"), Some("1"));
        // the runtime implements the FMU state functions, serialization included, for both
        for interface in ["ModelExchange", "CoSimulation"] {
            let e = doc.iter().find(|e| e.name() == interface).unwrap();
            assert_eq!(e.attr("canGetAndSetFMUstate"), Some("true"), "{interface}");
            assert_eq!(e.attr("canSerializeFMUstate"), Some("true"), "{interface}");
            assert_eq!(e.attr("providesDirectionalDerivative"), Some("true"), "{interface}");
        }
        assert_eq!(cs.attr("modelIdentifier"), Some("Test"));
        let structure: Vec<&str> = doc.iter().filter(|e| e.parent() == "ModelStructure").map(|e| e.name()).collect();
        assert_eq!(structure, ["Outputs", "Derivatives", "InitialUnknowns"]);
    }

    #[test]
    fn model_structure_matches_the_table() {
        let (table, doc, index) = setup();
        let idx = |vr: &u32| index[vr];

        let outputs = unknowns(&doc, "Outputs");
        let expected: Vec<&Variable> = table.variables.iter().filter(|v| v.causality == Causality::Output).collect();
        assert_eq!(outputs.len(), expected.len());
        for (u, v) in outputs.iter().zip(&expected) {
            assert_eq!(u.attr("index").unwrap().parse::<usize>().unwrap(), idx(&v.vr));
            check_unknown(u, table.dependencies(v).iter().map(idx).collect());
        }

        let derivatives = unknowns(&doc, "Derivatives");
        let expected = table.derivatives();
        assert_eq!(derivatives.len(), expected.len());
        for (u, vr) in derivatives.iter().zip(&expected) {
            assert_eq!(u.attr("index").unwrap().parse::<usize>().unwrap(), idx(vr));
            check_unknown(u, table.dependencies(table.get(*vr).unwrap()).iter().map(idx).collect());
        }

        // outputs, then q, qd (initial approx) and der(qd) (calculated), each once, by index
        let mut expected: Vec<u32> = table
            .variables
            .iter()
            .filter(|v| {
                v.causality == Causality::Output
                    || v.name.starts_with("q[")
                    || v.name.starts_with("qd[")
                    || v.name.starts_with("der(qd[")
            })
            .map(|v| v.vr)
            .collect();
        expected.sort_by_key(idx);
        let initial = unknowns(&doc, "InitialUnknowns");
        let got: Vec<usize> = initial.iter().map(|u| u.attr("index").unwrap().parse().unwrap()).collect();
        assert_eq!(got, expected.iter().map(idx).collect::<Vec<_>>());
        for (u, vr) in initial.iter().zip(&expected) {
            check_unknown(u, table.initial_dependencies(table.get(*vr).unwrap()).iter().map(idx).collect());
        }
    }

    #[test]
    fn every_unit_is_defined() {
        let (table, doc, _) = setup();
        let defined: Vec<&str> = doc.iter().filter(|e| e.name() == "Unit").map(|e| e.attr("name").unwrap()).collect();
        let used: HashSet<&str> =
            doc.iter().filter_map(|e| if e.name() == "Real" { e.attr("unit") } else { None }).collect();
        assert!(used.contains("1") && used.contains("N.m"));
        for u in &used {
            assert!(defined.contains(u), "unit {u} used but not defined");
        }
        assert_eq!(defined.len(), used.len(), "only used units are defined, each once");
        let n = doc.iter().position(|e| e.name() == "Unit" && e.attr("name") == Some("N")).unwrap();
        let base = &doc[n + 1];
        assert_eq!(base.name(), "BaseUnit");
        assert_eq!((base.attr("kg"), base.attr("m"), base.attr("s")), (Some("1"), Some("1"), Some("-2")));
        assert_eq!(table.variables.iter().filter(|v| v.unit == Some("1")).count(), 18);
    }

    #[test]
    fn flange_displacement_depends_on_the_modal_coordinates_only() {
        let (table, doc, index) = setup();
        let q: Vec<usize> = table.variables.iter().filter(|v| v.name.starts_with("q[")).map(|v| index[&v.vr]).collect();
        assert_eq!(q.len(), 2);
        let vars: Vec<&Element> = doc.iter().filter(|e| e.name() == "ScalarVariable").collect();
        for i in 1..=3 {
            let name = format!("tip.u[{i}]");
            let k = vars.iter().position(|e| e.attr("name") == Some(&name)).unwrap() + 1;
            let u = unknowns(&doc, "Outputs").into_iter().find(|u| u.attr("index") == Some(&k.to_string())).unwrap();
            assert_eq!(indices(u.attr("dependencies").unwrap()), q, "{name}");
        }
    }

    #[test]
    fn derivative_attributes_point_at_the_states() {
        let (_, doc, _) = setup();
        let vars: Vec<&Element> = doc.iter().filter(|e| e.name() == "ScalarVariable").collect();
        let reals: Vec<&Element> = doc.iter().filter(|e| e.parent() == "ScalarVariable").collect();
        let position = |name: &str| vars.iter().position(|e| e.attr("name") == Some(name)).unwrap();
        for j in 1..=2 {
            let qd = position(&format!("qd[{j}]"));
            let dqd = position(&format!("der(qd[{j}])"));
            assert_eq!(reals[qd].attr("derivative"), Some((position(&format!("q[{j}]")) + 1).to_string().as_str()));
            assert_eq!(reals[dqd].attr("derivative"), Some((qd + 1).to_string().as_str()));
            assert_eq!(reals[dqd].attr("start"), None, "calculated: no start");
            assert_eq!(vars[qd].attr("initial"), Some("approx"));
        }
        let n_derivative = reals.iter().filter(|r| r.attr("derivative").is_some()).count();
        assert_eq!(n_derivative, unknowns(&doc, "Derivatives").len());
        let boolean = vars.iter().position(|e| e.attr("name") == Some("static_start")).unwrap();
        assert_eq!(reals[boolean].name(), "Boolean");
        assert_eq!(reals[boolean].attr("start"), Some("false"));
    }

    #[test]
    fn numbers_round_trip() {
        let mut body = two_mode_body();
        body.beta = 1.234_567_890_123_456_7e-300;
        let table = VariableTable::new(&body);
        let doc = parse(&model_description_xml(&info(), &table).unwrap());
        let vars: Vec<&Element> = doc.iter().filter(|e| e.name() == "ScalarVariable").collect();
        let reals: Vec<&Element> = doc.iter().filter(|e| e.parent() == "ScalarVariable").collect();
        let k = vars.iter().position(|e| e.attr("name") == Some("damping.beta")).unwrap();
        let text = reals[k].attr("start").unwrap();
        assert!(text.len() < 30, "{text}");
        assert_eq!(text.parse::<f64>().unwrap(), body.beta);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let mut body = two_mode_body();
        body.alpha = f64::NAN;
        let e = model_description_xml(&info(), &VariableTable::new(&body)).unwrap_err();
        assert!(e.to_string().contains("damping.alpha"), "{e}");

        let table = VariableTable::new(&two_mode_body());
        for (f, what) in [
            (
                (|i: &mut ModelInfo| i.generation_date_time = "22.11.2026".into()) as fn(&mut ModelInfo),
                "generationDateAndTime",
            ),
            (|i| i.model_identifier = "my model".into(), "modelIdentifier"),
            (|i| i.guid.clear(), "guid"),
            (|i| i.default_experiment.step = 0.0, "DefaultExperiment"),
            (|i| i.default_experiment.stop = f64::INFINITY, "DefaultExperiment"),
        ] {
            let mut i = info();
            f(&mut i);
            let e = model_description_xml(&i, &table).unwrap_err();
            assert!(e.to_string().contains(what), "{e}");
        }

        let mut t = table.clone();
        t.variables[0].unit = Some("furlong");
        assert!(model_description_xml(&info(), &t).unwrap_err().to_string().contains("furlong"));
        let mut t = table.clone();
        let last = t.variables.len() - 1;
        t.variables[last].derivative_of = Some(10_000);
        assert!(model_description_xml(&info(), &t).unwrap_err().to_string().contains("10000"));
        let mut t = table.clone();
        t.variables[1].name = t.variables[0].name.clone();
        assert!(model_description_xml(&info(), &t).unwrap_err().to_string().contains("twice"));
        let mut t = table;
        t.variables[0].start = None; // an input without start
        assert!(model_description_xml(&info(), &t).unwrap_err().to_string().contains("needs a start"));
    }

    #[test]
    fn date_times() {
        assert_eq!(xs_date_time(0), "1970-01-01T00:00:00Z");
        assert_eq!(xs_date_time(1_795_330_800), "2026-11-22T07:00:00Z");
        assert_eq!(xs_date_time(951_782_400), "2000-02-29T00:00:00Z");
        // `date -u -d @1795000000 +%Y-%m-%dT%H:%M:%SZ` (GNU coreutils)
        assert_eq!(xs_date_time(1_795_000_000), "2026-11-18T11:06:40Z");
        for ok in
            ["2026-11-22T07:00:00Z", "2026-11-22T07:00:00", "2026-11-22T07:00:00.25+01:00", "2026-01-31T23:59:59-05:30"]
        {
            assert!(is_xs_date_time(ok), "{ok}");
        }
        for bad in [
            "",
            "2026-11-22",
            "2026-13-01T00:00:00Z",
            "2026-11-22 07:00:00",
            "2026-11-22T24:00:00Z",
            "2026-11-22T07:00:00.Z",
            "2026-11-22T07:00:00+1:00",
            "2026-11-22T07:00:00é",
            "2026-11-22T07:00:00+1é:0",
        ] {
            assert!(!is_xs_date_time(bad), "{bad}");
        }
    }
}
