//! The FMU of a reduced body: modelDescription.xml, binaries, resources and documentation.

use crate::error::{BuildError, Result};
use crate::input::spec::Spec;
use crate::output::binaries::{Platform, PlatformBinary, fmi2_functions};
use crate::output::documentation;
use crate::output::finite;
use crate::output::fmu;
use crate::output::report::Report;
use fmu_runtime::format::RESOURCE_FILE;
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::ReducedBody;
use std::path::Path;

/// The runtime cdylib, built by build.rs: the FMU's binaries/linux64/<id>.so.
pub const RUNTIME_SO: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/fmu_runtime.so"));

/// The FMU of a reduced body, with the builder's linux64 runtime and `others` (runtimes built for
/// other platforms, the command line's `--platform-binary`; a linux64 one replaces the builder's
/// own), each checked again against the FMU's modelDescription.xml.
pub fn write_fmu(
    spec: &Spec,
    reduced: &ReducedBody,
    report: &Report,
    output: &Path,
    others: &[PlatformBinary],
) -> Result<()> {
    // nothing non-finite leaves the builder: not in the report, not in the body, not in the
    // FMU's first steps
    finite::check_report(report)?;
    finite::check_reduced(reduced)?;
    finite::smoke_step(reduced)?;
    let id = fmu::model_identifier(&spec.name);
    let table = VariableTable::new(reduced);
    let experiment = report.default_experiment;
    let info = fmu::ModelInfo {
        model_name: spec.name.clone(),
        model_identifier: id.clone(),
        description: spec.description.clone().unwrap_or_else(|| {
            format!("Reduced flexible body '{}' ({} modal coordinates)", spec.name, reduced.n_modes())
        }),
        guid: reduced.guid.clone(),
        generation_tool: format!("fmu-builder {}", env!("CARGO_PKG_VERSION")),
        generation_date_time: generation_time()?,
        default_experiment: fmu::DefaultExperiment {
            start: 0.0,
            stop: experiment.stop_time,
            step: experiment.step_size,
            tolerance: experiment.tolerance,
        },
    };
    let xml = fmu::model_description_xml(&info, &table).map_err(|e| {
        BuildError::Numerical(format!(
            "{e}: a flange's name (flanges[].name) collides with another variable of the FMU; rename the flange"
        ))
    })?;
    let input =
        documentation::input_listing(spec).map_err(|e| BuildError::Numerical(format!("serialising the input: {e}")))?;
    let report_json =
        serde_json::to_vec_pretty(report).map_err(|e| BuildError::Numerical(format!("serialising the report: {e}")))?;
    let required = fmi2_functions::required(&xml);
    for binary in others {
        binary.check(&required)?;
    }
    let mut binaries: Vec<(Platform, &[u8])> = others.iter().map(|b| (b.platform, b.data.as_slice())).collect();
    if !binaries.iter().any(|(p, _)| *p == Platform::Linux64) {
        binaries.insert(0, (Platform::Linux64, RUNTIME_SO));
    }
    let archive = fmu::FmuArchive {
        model_description: xml,
        model_identifier: &id,
        binaries,
        resources: vec![(RESOURCE_FILE.to_string(), reduced.to_bytes())],
        documentation: vec![
            ("index.html".to_string(), documentation::index_html(report, &table, &input).into_bytes()),
            ("report.json".to_string(), report_json),
            ("input.json".to_string(), input.clone().into_bytes()),
        ],
    };
    fmu::write_fmu(output, &archive).map_err(|e| match e {
        fmu::FmuError::Archive { path, message } => BuildError::Io { path, message },
        other => BuildError::Numerical(other.to_string()),
    })
}

/// The FMU's generation time: `SOURCE_DATE_EPOCH` (seconds since 1970, UTC) when set, as
/// reproducible builds specify, so that the same input and builder version give the same FMU
/// bytes; else now.
fn generation_time() -> Result<String> {
    let secs = match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(text) => text.trim().parse::<u64>().ok().filter(|s| (0..253_402_300_800).contains(s)).ok_or_else(|| {
            BuildError::Numerical(format!(
                "the environment variable SOURCE_DATE_EPOCH is {text:?}: expected whole seconds since 1970-01-01 UTC"
            ))
        })?,
        Err(_) => std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
    };
    Ok(fmu::xs_date_time(secs))
}
