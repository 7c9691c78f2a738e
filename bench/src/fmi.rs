//! An FMU as a co-simulation master sees it: unzip, read modelDescription.xml, dlopen the
//! binary and call it through the FMI 2.0 C API only. The C types come from fmi2, and every
//! timed call goes through the dlopen'ed library (test-support's loader checks each symbol with
//! dladdr). One exception,
//! `Fmu::open_in_process`: the same FMU (its modelDescription.xml and resources) driven through
//! the runtime's exported C functions as linked into this binary, so that the bench's counting
//! allocator sees their heap allocations (the dlopen'ed binary has its own allocator).

use fmi2::types::*;
use std::collections::HashMap;
use std::ffi::CString;
use std::path::{Path, PathBuf};
use test_support::loader::{Fmi2Functions, FmuBinary};
use test_support::logger;

/// What the master needs from modelDescription.xml.
pub struct ModelDescription {
    pub guid: String,
    pub model_identifier: String,
    pub variables: HashMap<String, u32>,
    pub n_states: usize,
}

fn attribute(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let end = start + tag[start..].find('"')?;
    Some(tag[start..end].replace("&quot;", "\"").replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&"))
}

impl ModelDescription {
    /// Reads the attributes a master needs; the XML is ours, written by fmu-builder, so a plain
    /// scan for the elements suffices.
    pub fn parse(xml: &str) -> Result<Self, String> {
        let root_start = xml.find("<fmiModelDescription").ok_or("no fmiModelDescription element")?;
        let root = &xml[root_start..root_start + xml[root_start..].find('>').ok_or("unterminated root")?];
        let guid = attribute(root, "guid").ok_or("no guid")?;
        let cs_start = xml.find("<CoSimulation").ok_or("no CoSimulation element")?;
        let cs = &xml[cs_start..cs_start + xml[cs_start..].find('>').ok_or("unterminated CoSimulation")?];
        let model_identifier = attribute(cs, "modelIdentifier").ok_or("no modelIdentifier")?;
        let mut variables = HashMap::new();
        for chunk in xml.split("<ScalarVariable").skip(1) {
            let tag = &chunk[..chunk.find('>').ok_or("unterminated ScalarVariable")?];
            let name = attribute(tag, "name").ok_or("ScalarVariable without name")?;
            let vr = attribute(tag, "valueReference").ok_or("ScalarVariable without valueReference")?;
            variables.insert(name, vr.parse().map_err(|e| format!("valueReference {vr}: {e}"))?);
        }
        let n_states = match (xml.find("<Derivatives>"), xml.find("</Derivatives>")) {
            (Some(a), Some(b)) => xml[a..b].matches("<Unknown").count(),
            _ => 0,
        };
        Ok(Self { guid, model_identifier, variables, n_states })
    }

    pub fn vr(&self, name: &str) -> u32 {
        *self.variables.get(name).unwrap_or_else(|| panic!("the FMU has no variable {name}"))
    }

    pub fn vrs(&self, names: &[&str]) -> Vec<u32> {
        names.iter().map(|n| self.vr(n)).collect()
    }
}

/// An unzipped FMU with its binary loaded.
pub struct Fmu {
    pub description: ModelDescription,
    pub binary: PathBuf,
    resource_uri: CString,
    /// The loaded binary `api` points into; None for the in-process runtime.
    _library: Option<FmuBinary>,
    pub api: Fmi2Functions,
}

impl Fmu {
    /// Unzip `fmu` into `dir` and load binaries/linux64/<modelIdentifier>.so.
    pub fn open(fmu: &Path, dir: &Path) -> Result<Self, String> {
        let file = std::fs::File::open(fmu).map_err(|e| format!("{}: {e}", fmu.display()))?;
        let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", fmu.display()))?;
        zip.extract(dir).map_err(|e| format!("unzipping {}: {e}", fmu.display()))?;
        let xml = std::fs::read_to_string(dir.join("modelDescription.xml")).map_err(|e| e.to_string())?;
        let description = ModelDescription::parse(&xml)?;
        let binary = dir.join("binaries/linux64").join(format!("{}.so", description.model_identifier));
        let resources = dir.join("resources").canonicalize().map_err(|e| format!("resources: {e}"))?;
        let resource_uri = CString::new(format!("file://{}", resources.display())).map_err(|e| e.to_string())?;
        let library = FmuBinary::open(&binary)?;
        let api = *library.functions();
        Ok(Self { description, binary, resource_uri, _library: Some(library), api })
    }

    /// The FMU unzipped in `dir` by `open`, driven through the runtime's C functions linked into
    /// this binary (same source as the FMU's binary, built with this workspace): for counting
    /// heap allocations, never for timing.
    pub fn open_in_process(dir: &Path) -> Result<Self, String> {
        let xml = std::fs::read_to_string(dir.join("modelDescription.xml")).map_err(|e| e.to_string())?;
        let description = ModelDescription::parse(&xml)?;
        let resources = dir.join("resources").canonicalize().map_err(|e| format!("resources: {e}"))?;
        let resource_uri = CString::new(format!("file://{}", resources.display())).map_err(|e| e.to_string())?;
        let api = Fmi2Functions {
            instantiate: fmu_runtime::fmi2Instantiate,
            free_instance: fmu_runtime::fmi2FreeInstance,
            setup_experiment: fmu_runtime::fmi2SetupExperiment,
            enter_initialization_mode: fmu_runtime::fmi2EnterInitializationMode,
            exit_initialization_mode: fmu_runtime::fmi2ExitInitializationMode,
            terminate: fmu_runtime::fmi2Terminate,
            new_discrete_states: fmu_runtime::fmi2NewDiscreteStates,
            enter_continuous_time_mode: fmu_runtime::fmi2EnterContinuousTimeMode,
            do_step: fmu_runtime::fmi2DoStep,
            set_real: fmu_runtime::fmi2SetReal,
            get_real: fmu_runtime::fmi2GetReal,
            set_continuous_states: fmu_runtime::fmi2SetContinuousStates,
            get_derivatives: fmu_runtime::fmi2GetDerivatives,
            get_fmu_state: fmu_runtime::fmi2GetFMUstate,
            set_fmu_state: fmu_runtime::fmi2SetFMUstate,
            free_fmu_state: fmu_runtime::fmi2FreeFMUstate,
        };
        Ok(Self { description, binary: PathBuf::from("(in process)"), resource_uri, _library: None, api })
    }

    /// fmi2Instantiate and fmi2SetupExperiment (start 0, no tolerance, no stop time).
    pub fn instantiate(&self, kind: fmi2Type, name: &str) -> Result<Instance<'_>, String> {
        let name = CString::new(name).map_err(|e| e.to_string())?;
        let guid = CString::new(self.description.guid.as_str()).map_err(|e| e.to_string())?;
        let callbacks = logger::callbacks_with(logger::stderr, std::ptr::null_mut());
        // SAFETY: FMI 2.0 contract; all strings live across the call, the layer copies them.
        let c = unsafe {
            (self.api.instantiate)(
                name.as_ptr(),
                kind,
                guid.as_ptr(),
                self.resource_uri.as_ptr(),
                &callbacks,
                fmi2False,
                fmi2False,
            )
        };
        if c.is_null() {
            return Err("fmi2Instantiate returned NULL".into());
        }
        let inst = Instance { fmu: self, c };
        inst.check("fmi2SetupExperiment", unsafe {
            (self.api.setup_experiment)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0)
        })?;
        Ok(inst)
    }
}

/// One fmi2Component; freed on drop.
pub struct Instance<'a> {
    pub fmu: &'a Fmu,
    pub c: fmi2Component,
}

impl Instance<'_> {
    pub fn check(&self, what: &str, status: fmi2Status) -> Result<(), String> {
        if status == fmi2Status::fmi2OK { Ok(()) } else { Err(format!("{what} returned {status:?}")) }
    }

    pub fn set(&self, names: &[&str], values: &[f64]) -> Result<(), String> {
        let vrs = self.fmu.description.vrs(names);
        self.check("fmi2SetReal", unsafe { (self.fmu.api.set_real)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) })
    }

    pub fn get(&self, vrs: &[u32], values: &mut [f64]) -> Result<(), String> {
        assert_eq!(vrs.len(), values.len());
        self.check("fmi2GetReal", unsafe {
            (self.fmu.api.get_real)(self.c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr())
        })
    }

    pub fn initialize(&self) -> Result<(), String> {
        self.check("fmi2EnterInitializationMode", unsafe { (self.fmu.api.enter_initialization_mode)(self.c) })?;
        self.check("fmi2ExitInitializationMode", unsafe { (self.fmu.api.exit_initialization_mode)(self.c) })
    }

    /// Model Exchange after initialisation: event iteration, then continuous-time mode.
    pub fn enter_continuous_time(&self) -> Result<(), String> {
        let mut info = fmi2EventInfo::default();
        loop {
            self.check("fmi2NewDiscreteStates", unsafe { (self.fmu.api.new_discrete_states)(self.c, &mut info) })?;
            if info.newDiscreteStatesNeeded == fmi2False {
                break;
            }
        }
        self.check("fmi2EnterContinuousTimeMode", unsafe { (self.fmu.api.enter_continuous_time_mode)(self.c) })
    }

    #[inline]
    pub fn do_step(&self, t: f64, h: f64) -> fmi2Status {
        unsafe { (self.fmu.api.do_step)(self.c, t, h, fmi2True) }
    }

    pub fn get_state(&self) -> Result<fmi2FMUstate, String> {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        self.check("fmi2GetFMUstate", unsafe { (self.fmu.api.get_fmu_state)(self.c, &mut s) })?;
        Ok(s)
    }

    pub fn set_state(&self, s: fmi2FMUstate) -> Result<(), String> {
        self.check("fmi2SetFMUstate", unsafe { (self.fmu.api.set_fmu_state)(self.c, s) })
    }

    pub fn free_state(&self, mut s: fmi2FMUstate) -> Result<(), String> {
        self.check("fmi2FreeFMUstate", unsafe { (self.fmu.api.free_fmu_state)(self.c, &mut s) })
    }
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        unsafe {
            (self.fmu.api.terminate)(self.c);
            (self.fmu.api.free_instance)(self.c);
        }
    }
}
