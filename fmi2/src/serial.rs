//! Serialized FMU states (canSerializeFMUstate): a [`Snapshot`] as portable bytes.
//!
//! Layout (all integers and reals little-endian; offsets in bytes, G = GUID length,
//! M = model section length):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `FLEXSTAT` |
//! | 8 | 4 | format version (u32), [`VERSION`] |
//! | 12 | 8 | payload length P (u64) = 40 + G + M |
//! | 20 | 1 | interface: 0 Model Exchange, 1 Co-Simulation |
//! | 21 | 1 | model state ([`ModelState::code`]) |
//! | 22 | 1 | last fmi2DoStep status (fmi2Status: 0 OK .. 4 Fatal) |
//! | 23 | 1 | stop time defined (0/1) |
//! | 24 | 8 | time (f64) |
//! | 32 | 8 | start time (f64) |
//! | 40 | 8 | stop time (f64; 0 when undefined) |
//! | 48 | 4 | GUID length G (u32) |
//! | 52 | G | GUID (UTF-8) |
//! | 52+G | 8 | model section length M (u64) |
//! | 60+G | M | model section ([`Model::save_state`]) |
//! | 20+P | 4 | CRC-32 (IEEE) of bytes 0 .. 20+P |
//!
//! The immutable model data (what [`Model::instantiate`] loads from the resources) is not
//! in it: the GUID ties the bytes to the model they belong to. Reading checks, in this order:
//! magic, version, length, CRC, then every field; the first failure is the message, and
//! nothing is built from bytes that fail any check.

use super::bytes::{Reader, Writer};
use super::instance::Snapshot;
use super::state::ModelState;
use super::types::fmi2Status;
use super::{Interface, Model};

pub const MAGIC: &[u8; 8] = b"FLEXSTAT";
pub const VERSION: u32 = 1;
/// Magic, version, payload length.
const HEADER: usize = 20;
const CRC: usize = 4;

fn interface_code(i: Interface) -> u8 {
    match i {
        Interface::ModelExchange => 0,
        Interface::CoSimulation => 1,
    }
}

fn interface_of(code: u8) -> Option<Interface> {
    match code {
        0 => Some(Interface::ModelExchange),
        1 => Some(Interface::CoSimulation),
        _ => None,
    }
}

fn status_code(s: fmi2Status) -> u8 {
    match s {
        fmi2Status::fmi2OK => 0,
        fmi2Status::fmi2Warning => 1,
        fmi2Status::fmi2Discard => 2,
        fmi2Status::fmi2Error => 3,
        fmi2Status::fmi2Fatal => 4,
        fmi2Status::fmi2Pending => 5,
    }
}

/// fmi2Pending is refused: fmi2DoStep is never asynchronous here.
fn status_of(code: u8) -> Option<fmi2Status> {
    match code {
        0 => Some(fmi2Status::fmi2OK),
        1 => Some(fmi2Status::fmi2Warning),
        2 => Some(fmi2Status::fmi2Discard),
        3 => Some(fmi2Status::fmi2Error),
        4 => Some(fmi2Status::fmi2Fatal),
        _ => None,
    }
}

pub fn serialize<M: Model>(s: &Snapshot<M>) -> Vec<u8> {
    let mut model = Vec::new();
    s.model.save_state(&mut model);
    let guid = s.model.guid();
    let mut out = Vec::with_capacity(HEADER + 40 + guid.len() + model.len() + CRC);
    let mut w = Writer::new(&mut out);
    w.bytes(MAGIC);
    w.u32(VERSION);
    w.len(40 + guid.len() + model.len());
    w.u8(interface_code(s.interface));
    w.u8(s.state.code());
    w.u8(status_code(s.last_do_step_status));
    w.bool(s.stop_time.is_some());
    w.f64(s.time);
    w.f64(s.start_time);
    w.f64(s.stop_time.unwrap_or(0.0));
    w.str(guid);
    w.len(model.len());
    w.bytes(&model);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// A snapshot from `bytes` for an instance of `interface` whose model is `current`: the
/// model part is loaded into a clone of it, so a failure leaves nothing half-built.
pub fn deserialize<M: Model>(bytes: &[u8], current: &M, interface: Interface) -> Result<Snapshot<M>, String> {
    if bytes.len() < HEADER + CRC && MAGIC.starts_with(&bytes[..bytes.len().min(8)]) {
        return Err(format!("the serialized FMU state is truncated: {} bytes", bytes.len()));
    }
    let mut r = Reader::new(bytes);
    if r.take(8, "magic").ok() != Some(MAGIC.as_slice()) {
        return Err("not a serialized FMU state of this runtime (the first 8 bytes are not 'FLEXSTAT')".into());
    }
    let version = r.u32("format version")?;
    if version > VERSION {
        return Err(format!(
            "the serialized FMU state was written by a newer runtime (format version {version}; this runtime reads up to {VERSION})"
        ));
    }
    if version == 0 {
        return Err("the serialized FMU state has format version 0, which no runtime writes".into());
    }
    let payload = r.u64("payload length")?;
    let expected = usize::try_from(payload)
        .ok()
        .and_then(|p| p.checked_add(HEADER + CRC))
        .ok_or_else(|| format!("the serialized FMU state claims an impossible payload length {payload}"))?;
    if bytes.len() < expected {
        return Err(format!(
            "the serialized FMU state is truncated: {} bytes, its header says {expected}",
            bytes.len()
        ));
    }
    if bytes.len() > expected {
        return Err(format!("the serialized FMU state has {} bytes but its header says {expected}", bytes.len()));
    }
    let end = expected - CRC;
    let mut stored = [0u8; 4];
    stored.copy_from_slice(&bytes[end..]);
    let stored = u32::from_le_bytes(stored);
    let computed = crc32fast::hash(&bytes[..end]);
    if stored != computed {
        return Err(format!(
            "the serialized FMU state is corrupt: CRC-32 stored {stored:#010x}, computed {computed:#010x}"
        ));
    }

    let mut r = Reader::new(&bytes[HEADER..end]);
    let code = r.u8("interface")?;
    let saved_interface = interface_of(code).ok_or_else(|| format!("invalid interface code {code}"))?;
    if saved_interface != interface {
        return Err(format!(
            "the serialized FMU state is of a {saved_interface:?} instance; this instance was instantiated for {interface:?}"
        ));
    }
    let code = r.u8("model state")?;
    let state = ModelState::from_code(code)
        .filter(|s| s.can_be_saved_in(interface))
        .ok_or_else(|| format!("invalid model state code {code} for {interface:?}"))?;
    let code = r.u8("fmi2DoStep status")?;
    let last_do_step_status = status_of(code).ok_or_else(|| format!("invalid fmi2DoStep status code {code}"))?;
    let stop_defined = r.bool("stop time defined")?;
    let time = r.f64("time")?;
    let start_time = r.f64("start time")?;
    let stop = r.f64("stop time")?;
    let guid = r.str("GUID")?;
    if guid != current.guid() {
        return Err(format!(
            "the serialized FMU state belongs to the model with GUID {guid}, not this FMU's {}",
            current.guid()
        ));
    }
    let n = r.len(1, "model section length")?;
    let section = r.take(n, "model section")?;
    r.finish("model section")?;
    let mut model = current.clone();
    model.load_state(section).map_err(|e| format!("model state: {e}"))?;
    Ok(Snapshot {
        magic: super::instance::SNAPSHOT_MAGIC,
        model,
        interface,
        state,
        time,
        start_time,
        stop_time: stop_defined.then_some(stop),
        last_do_step_status,
    })
}
