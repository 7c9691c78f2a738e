//! modelDescription.xml of an assembly: Co-Simulation only, its variables from the runtime's
//! assembly table (the one definition the binary serves), every output depending on every input
//! (the joints couple all of them).

use crate::error::SharedCause;
use std::io;

use fmi2::Causality;
use fmu_runtime::interface::UNITS;
use fmu_runtime::interface::assembly::AssemblyTable;
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};

use super::FmuError;
use super::model_description::{
    ModelInfo, W, attrs, causality_name, check_info, root_attributes, variability_name, write_default_experiment,
    write_log_categories, write_units,
};

type Result<T> = std::result::Result<T, FmuError>;

pub fn assembly_description_xml(info: &ModelInfo, table: &AssemblyTable) -> Result<String> {
    check_info(info)?;
    let mut names = std::collections::HashSet::new();
    for v in &table.variables {
        if !names.insert(v.name.as_str()) {
            return Err(FmuError::Description(format!("two variables are named '{}'", v.name)));
        }
    }
    let units: Vec<(&str, [i32; 4])> =
        UNITS.iter().filter(|(u, _)| table.variables.iter().any(|v| v.unit == Some(*u))).copied().collect();
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    write_document(&mut w, info, table, &units)
        .map_err(|e| FmuError::Xml { what: "writing the XML failed", cause: SharedCause::new(e) })?;
    String::from_utf8(w.into_inner())
        .map_err(|e| FmuError::Xml { what: "the XML is not UTF-8", cause: SharedCause::new(e) })
}

fn write_document(w: &mut W, info: &ModelInfo, table: &AssemblyTable, units: &[(&str, [i32; 4])]) -> io::Result<()> {
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let root = root_attributes(info);
    w.create_element("fmiModelDescription").with_attributes(attrs(&root)).write_inner_content(|w| {
        let cs = [
            ("modelIdentifier", info.model_identifier.clone()),
            ("needsExecutionTool", "false".into()),
            ("canBeInstantiatedOnlyOncePerProcess", "false".into()),
            ("canNotUseMemoryManagementFunctions", "true".into()),
            ("canGetAndSetFMUstate", "true".into()),
            ("canSerializeFMUstate", "true".into()),
            ("providesDirectionalDerivative", "false".into()),
            ("canHandleVariableCommunicationStepSize", "true".into()),
            ("canInterpolateInputs", "true".into()),
            ("maxOutputDerivativeOrder", "0".into()),
        ];
        w.create_element("CoSimulation").with_attributes(attrs(&cs)).write_empty()?;
        write_units(w, units)?;
        write_log_categories(w)?;
        write_default_experiment(w, info)?;
        w.create_element("ModelVariables").write_inner_content(|w| {
            for v in &table.variables {
                let sv = [
                    ("name", v.name.clone()),
                    ("valueReference", v.vr.to_string()),
                    ("description", v.description.clone()),
                    ("causality", causality_name(v.causality).to_string()),
                    ("variability", variability_name(v.variability).to_string()),
                ];
                let mut ty = Vec::new();
                if let Some(unit) = v.unit {
                    ty.push(("unit", unit.to_string()));
                }
                if let Some(start) = v.start {
                    ty.push(("start", format!("{start:?}")));
                }
                w.create_element("ScalarVariable").with_attributes(attrs(&sv)).write_inner_content(|w| {
                    w.create_element("Real").with_attributes(attrs(&ty)).write_empty()?;
                    Ok(())
                })?;
            }
            Ok(())
        })?;
        let outputs: Vec<u32> =
            table.variables.iter().filter(|v| v.causality == Causality::Output).map(|v| v.vr).collect();
        w.create_element("ModelStructure").write_inner_content(|w| {
            if outputs.is_empty() {
                return Ok(());
            }
            // no dependencies attribute: each output depends on every input (FMI 2.0, 2.2.8)
            for list in ["Outputs", "InitialUnknowns"] {
                w.create_element(list).write_inner_content(|w| {
                    for vr in &outputs {
                        w.create_element("Unknown").with_attribute(("index", vr.to_string().as_str())).write_empty()?;
                    }
                    Ok(())
                })?;
            }
            Ok(())
        })?;
        Ok(())
    })?;
    Ok(())
}
