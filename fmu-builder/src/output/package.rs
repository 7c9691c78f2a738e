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

/// The runtime cdylib (built once by `cargo xtask runtime`, embedded by build.rs): the FMU's binaries/linux64/<id>.so.
pub const RUNTIME_SO: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/fmu_runtime.so"));
/// Which kind of binary `RUNTIME_SO` is ("portable, ...", "native, ...", "prebuilt, ..."; build.rs).
pub const RUNTIME_KIND: &str = env!("FMU_RUNTIME_LINUX64");
/// The newest glibc version a natively linked `RUNTIME_SO` needs, e.g. "2.34" (build.rs); empty
/// for a portable or prebuilt one.
const RUNTIME_NATIVE_GLIBC: &str = env!("FMU_RUNTIME_NATIVE_GLIBC");

/// Why an FMU with the builder's own linux64 binary may not load on an older Linux, where that
/// binary was linked natively (zig or cargo-zigbuild missing when the builder was built); None
/// for a portable one or where `others` brings its own linux64 binary. Said on every FMU built
/// (and by `--version`): the FMU works on the build machine, so nothing else would show it before
/// a user on RHEL/Rocky 8 or Ubuntu 20.04 fails to load it.
pub fn native_runtime_warning(others: &[PlatformBinary]) -> Option<String> {
    if !RUNTIME_KIND.starts_with("native") || others.iter().any(|b| b.platform == Platform::Linux64) {
        return None;
    }
    let needs = if RUNTIME_NATIVE_GLIBC.is_empty() {
        "this build machine's glibc or newer".to_string()
    } else {
        format!("glibc {RUNTIME_NATIVE_GLIBC} or newer (GLIBC_{RUNTIME_NATIVE_GLIBC}, this build machine's)")
    };
    Some(format!(
        "the FMU's linux64 binary is linked natively and needs {needs}: it does not load where glibc is older \
         (RHEL/Rocky 8: 2.28, Ubuntu 20.04 and Debian 11: 2.31). For one that loads on glibc 2.17 or newer, set up \
         zig and cargo-zigbuild (`bash tests/run.sh --setup-only` in the source tree, or `pip install ziglang` and \
         `cargo install --locked cargo-zigbuild`), then rebuild the builder (`cargo xtask build`, \
         or `cargo xtask runtime` and `cargo install` again): it is linked portable from then on"
    ))
}

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
        BuildError::numerical(format!(
            "{e}: a flange's name (flanges[].name) collides with another variable of the FMU; rename the flange"
        ))
        .caused_by(e)
    })?;
    let mut listed = spec.clone();
    listed.reduction.backend = listed.reduction.backend.packaged();
    let input = documentation::input_listing(&listed)
        .map_err(|e| BuildError::internal(format!("serialising the input: {e}")).caused_by(e))?;
    let report_json = serde_json::to_vec_pretty(&report.as_packaged())
        .map_err(|e| BuildError::internal(format!("serialising the report: {e}")).caused_by(e))?;
    let binaries = runtime_binaries(&xml, others)?;
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
    fmu::write_fmu(output, &archive)
}

/// The FMU's binaries: `others`, each checked against the functions `xml` needs, and the
/// builder's own linux64 runtime unless one of them replaces it.
fn runtime_binaries<'a>(xml: &str, others: &'a [PlatformBinary]) -> Result<Vec<(Platform, &'a [u8])>> {
    let required = fmi2_functions::required(xml);
    for binary in others {
        binary.check(&required)?;
    }
    let mut binaries: Vec<(Platform, &[u8])> = others.iter().map(|b| (b.platform, b.data.as_slice())).collect();
    if !binaries.iter().any(|(p, _)| *p == Platform::Linux64) {
        binaries.insert(0, (Platform::Linux64, RUNTIME_SO));
    }
    Ok(binaries)
}

/// The FMU's generation time: `SOURCE_DATE_EPOCH` (seconds since 1970, UTC) when set, as
/// reproducible builds specify, so that the same input and builder version give the same FMU
/// bytes; else now.
fn generation_time() -> Result<String> {
    let secs = match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(text) => text.trim().parse::<u64>().ok().filter(|s| (0..253_402_300_800).contains(s)).ok_or_else(|| {
            BuildError::numerical(format!(
                "the environment variable SOURCE_DATE_EPOCH is {text:?}: expected whole seconds since 1970-01-01 UTC"
            ))
        })?,
        Err(_) => std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
    };
    Ok(fmu::xs_date_time(secs))
}

/// The FMU of an assembly: Co-Simulation, the runtime's assembly table as its variables, the
/// assembly's file (every body inside) as its resource, and a page that lists the bodies, their
/// reductions' figures, the joints and the variables.
#[allow(clippy::too_many_arguments)]
pub fn write_assembly_fmu(
    spec: &crate::input::assembly::AssemblySpec,
    description: &fmu_runtime::assembly::description::AssemblyDescription,
    table: &fmu_runtime::interface::assembly::AssemblyTable,
    reports: &[(String, Report)],
    (stop, step): (f64, f64),
    output: &Path,
    others: &[PlatformBinary],
) -> Result<()> {
    use fmu_runtime::assembly::description::ASSEMBLY_FILE;
    for (_, report) in reports {
        finite::check_report(report)?;
    }
    let id = fmu::model_identifier(&spec.name);
    let info = fmu::ModelInfo {
        model_name: spec.name.clone(),
        model_identifier: id.clone(),
        description: spec.description.clone().unwrap_or_else(|| {
            format!("Assembly '{}' of {} bodies and {} joints", spec.name, spec.bodies.len(), spec.joints.len())
        }),
        guid: description.guid.clone(),
        generation_tool: format!("fmu-builder {}", env!("CARGO_PKG_VERSION")),
        generation_date_time: generation_time()?,
        default_experiment: fmu::DefaultExperiment {
            start: 0.0,
            stop,
            step,
            tolerance: spec.experiment.as_ref().and_then(|e| e.tolerance).unwrap_or(1e-6),
        },
    };
    let xml = fmu::assembly_description::assembly_description_xml(&info, table).map_err(|e| {
        BuildError::numerical(format!(
            "{e}: a body's, joint's or external flange's name collides with another variable of the FMU; rename it"
        ))
        .caused_by(e)
    })?;
    let binaries = runtime_binaries(&xml, others)?;
    let input = serde_json::to_string_pretty(spec)
        .map_err(|e| BuildError::internal(format!("serialising the input: {e}")).caused_by(e))?;
    let archive = fmu::FmuArchive {
        model_description: xml,
        model_identifier: &id,
        binaries,
        resources: vec![(ASSEMBLY_FILE.to_string(), description.to_bytes())],
        documentation: vec![
            ("index.html".to_string(), documentation::assembly_html(spec, description, table, reports).into_bytes()),
            ("input.json".to_string(), input.into_bytes()),
        ],
    };
    fmu::write_fmu(output, &archive)
}
