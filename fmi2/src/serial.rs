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

use super::bytes::{DecodeError, Reader, Writer};
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

/// Why serialized FMU state bytes were refused (fmi2DeSerializeFMUstate); checked in the order
/// of the variants, the first failure is the message.
#[derive(Debug)]
pub enum StateError {
    /// Fewer bytes than a header and a CRC, beginning as a state does.
    Truncated {
        len: usize,
    },
    /// Not beginning with [`MAGIC`].
    NotAState,
    /// A format version above [`VERSION`].
    NewerVersion(u32),
    VersionZero,
    /// A payload length no byte count can have.
    ImpossibleLength(u64),
    /// Fewer bytes than the header says.
    ShorterThanHeader {
        len: usize,
        expected: usize,
    },
    /// More bytes than the header says.
    LongerThanHeader {
        len: usize,
        expected: usize,
    },
    /// The CRC-32 stored differs from the bytes'.
    Corrupt {
        stored: u32,
        computed: u32,
    },
    InvalidInterface(u8),
    /// A state of an instance of the other interface.
    OtherInterface {
        saved: Interface,
        current: Interface,
    },
    InvalidModelState {
        code: u8,
        interface: Interface,
    },
    InvalidStatus(u8),
    /// A state of another model (its GUID).
    OtherModel {
        guid: String,
        current: String,
    },
    /// A field of the layer's part unreadable.
    Field(DecodeError),
    /// The model's section refused by [`Model::load_state`].
    ModelSection(DecodeError),
}

impl std::fmt::Display for StateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StateError::Truncated { len } => write!(f, "the serialized FMU state is truncated: {len} bytes"),
            StateError::NotAState => {
                f.write_str("not a serialized FMU state of this runtime (the first 8 bytes are not 'FLEXSTAT')")
            }
            StateError::NewerVersion(version) => write!(
                f,
                "the serialized FMU state was written by a newer runtime (format version {version}; this runtime reads up to {VERSION})"
            ),
            StateError::VersionZero => {
                f.write_str("the serialized FMU state has format version 0, which no runtime writes")
            }
            StateError::ImpossibleLength(payload) => {
                write!(f, "the serialized FMU state claims an impossible payload length {payload}")
            }
            StateError::ShorterThanHeader { len, expected } => {
                write!(f, "the serialized FMU state is truncated: {len} bytes, its header says {expected}")
            }
            StateError::LongerThanHeader { len, expected } => {
                write!(f, "the serialized FMU state has {len} bytes but its header says {expected}")
            }
            StateError::Corrupt { stored, computed } => write!(
                f,
                "the serialized FMU state is corrupt: CRC-32 stored {stored:#010x}, computed {computed:#010x}"
            ),
            StateError::InvalidInterface(code) => write!(f, "invalid interface code {code}"),
            StateError::OtherInterface { saved, current } => write!(
                f,
                "the serialized FMU state is of a {saved:?} instance; this instance was instantiated for {current:?}"
            ),
            StateError::InvalidModelState { code, interface } => {
                write!(f, "invalid model state code {code} for {interface:?}")
            }
            StateError::InvalidStatus(code) => write!(f, "invalid fmi2DoStep status code {code}"),
            StateError::OtherModel { guid, current } => {
                write!(f, "the serialized FMU state belongs to the model with GUID {guid}, not this FMU's {current}")
            }
            StateError::Field(e) => std::fmt::Display::fmt(e, f),
            StateError::ModelSection(e) => write!(f, "model state: {e}"),
        }
    }
}

impl std::error::Error for StateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StateError::Field(e) => e.source(),
            StateError::ModelSection(e) => Some(e),
            _ => None,
        }
    }
}

impl From<DecodeError> for StateError {
    fn from(e: DecodeError) -> Self {
        StateError::Field(e)
    }
}

/// A snapshot from `bytes` for an instance of `interface` whose model is `current`: the
/// model part is loaded into a clone of it, so a failure leaves nothing half-built.
pub fn deserialize<M: Model>(bytes: &[u8], current: &M, interface: Interface) -> Result<Snapshot<M>, StateError> {
    if bytes.len() < HEADER + CRC && MAGIC.starts_with(&bytes[..bytes.len().min(8)]) {
        return Err(StateError::Truncated { len: bytes.len() });
    }
    let mut r = Reader::new(bytes);
    if r.take(8, "magic").ok() != Some(MAGIC.as_slice()) {
        return Err(StateError::NotAState);
    }
    let version = r.u32("format version")?;
    if version > VERSION {
        return Err(StateError::NewerVersion(version));
    }
    if version == 0 {
        return Err(StateError::VersionZero);
    }
    let payload = r.u64("payload length")?;
    let expected = usize::try_from(payload)
        .ok()
        .and_then(|p| p.checked_add(HEADER + CRC))
        .ok_or(StateError::ImpossibleLength(payload))?;
    if bytes.len() < expected {
        return Err(StateError::ShorterThanHeader { len: bytes.len(), expected });
    }
    if bytes.len() > expected {
        return Err(StateError::LongerThanHeader { len: bytes.len(), expected });
    }
    let end = expected - CRC;
    let mut stored = [0u8; 4];
    stored.copy_from_slice(&bytes[end..]);
    let stored = u32::from_le_bytes(stored);
    let computed = crc32fast::hash(&bytes[..end]);
    if stored != computed {
        return Err(StateError::Corrupt { stored, computed });
    }

    let mut r = Reader::new(&bytes[HEADER..end]);
    let code = r.u8("interface")?;
    let saved_interface = interface_of(code).ok_or(StateError::InvalidInterface(code))?;
    if saved_interface != interface {
        return Err(StateError::OtherInterface { saved: saved_interface, current: interface });
    }
    let code = r.u8("model state")?;
    let state = ModelState::from_code(code)
        .filter(|s| s.can_be_saved_in(interface))
        .ok_or(StateError::InvalidModelState { code, interface })?;
    let code = r.u8("fmi2DoStep status")?;
    let last_do_step_status = status_of(code).ok_or(StateError::InvalidStatus(code))?;
    let stop_defined = r.bool("stop time defined")?;
    let time = r.f64("time")?;
    let start_time = r.f64("start time")?;
    let stop = r.f64("stop time")?;
    let guid = r.str("GUID")?;
    if guid != current.guid() {
        return Err(StateError::OtherModel { guid: guid.to_owned(), current: current.guid().to_owned() });
    }
    let n = r.len(1, "model section length")?;
    let section = r.take(n, "model section")?;
    r.finish("model section")?;
    let mut model = current.clone();
    model.load_state(section).map_err(StateError::ModelSection)?;
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
