//! The reduced-model file in the FMU's `resources/`: a small, versioned, checksummed container of
//! named little-endian f64 arrays and strings. The builder writes it, the runtime reads it; both
//! go through this module so the layout has one definition.
//!
//! Layout: magic `FLEXBODY`, format version (u32), payload length (u64), payload, CRC-32 of
//! everything before it (u32). Payload: entry count (u32), then per entry a name (u16 length +
//! UTF-8), a kind byte (0 = f64 array, 1 = string), and for arrays the rank (u8), the dimensions
//! (u64 each) and the values; for strings the byte length (u64) and UTF-8 bytes.
//! Named entries (rather than a fixed struct dump) let later versions add fields while old
//! readers still give a precise message about what they miss.

use std::collections::BTreeMap;
use std::fmt;

pub const MAGIC: &[u8; 8] = b"FLEXBODY";
pub const FORMAT_VERSION: u32 = 1;
/// Name of the file inside the FMU's `resources/` folder.
pub const RESOURCE_FILE: &str = "reduced_body.bin";
/// The text entry holding the content's GUID (see [`Container::content_guid`]).
pub const GUID_ENTRY: &str = "guid";

/// RFC 9562 version-5 UUID of `bytes` in this tool's namespace, braced as FMI writes GUIDs.
pub fn name_based_uuid(bytes: &[u8]) -> String {
    const NAMESPACE: [u8; 16] = 0x6f4d_2a61_8e3b_4c57_9a0e_52b1_c3d8_f7e4u128.to_be_bytes();
    let mut sha = sha1_smol::Sha1::new();
    sha.update(&NAMESPACE);
    sha.update(bytes);
    let mut u = [0u8; 16];
    u.copy_from_slice(&sha.digest().bytes()[..16]);
    u[6] = (u[6] & 0x0f) | 0x50; // version 5
    u[8] = (u[8] & 0x3f) | 0x80; // RFC 9562 variant
    let h: String = u.iter().map(|b| format!("{b:02x}")).collect();
    format!("{{{}-{}-{}-{}-{}}}", &h[..8], &h[8..12], &h[12..16], &h[16..20], &h[20..])
}

#[derive(Debug, Clone, PartialEq)]
pub enum Entry {
    Array { dims: Vec<usize>, values: Vec<f64> },
    Text(String),
}

#[derive(Clone, PartialEq)]
pub enum FormatError {
    Truncated { at: usize, needed: usize },
    BadMagic,
    UnsupportedVersion(u32),
    ChecksumMismatch { stored: u32, computed: u32 },
    Malformed(String),
    Missing(String),
    Shape { name: String, found: Vec<usize>, expected: Vec<usize> },
    WrongKind { name: String, expected: &'static str },
}

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FormatError::Truncated { at, needed } => {
                write!(f, "reduced-model file is truncated: needed {needed} more bytes at offset {at}")
            }
            FormatError::BadMagic => write!(f, "not a reduced-model file (the first 8 bytes are not 'FLEXBODY')"),
            FormatError::UnsupportedVersion(v) => write!(
                f,
                "reduced-model file has format version {v}; this runtime reads version {FORMAT_VERSION} (rebuild the FMU with a matching builder)"
            ),
            FormatError::ChecksumMismatch { stored, computed } => {
                write!(f, "reduced-model file is corrupt: CRC-32 stored {stored:#010x}, computed {computed:#010x}")
            }
            FormatError::Malformed(m) => write!(f, "reduced-model file is malformed: {m}"),
            FormatError::Missing(n) => write!(f, "reduced-model file lacks the entry '{n}'"),
            FormatError::Shape { name, found, expected } => {
                write!(f, "reduced-model entry '{name}' has shape {found:?}, expected {expected:?}")
            }
            FormatError::WrongKind { name, expected } => {
                write!(f, "reduced-model entry '{name}' is not {expected}")
            }
        }
    }
}

impl std::error::Error for FormatError {}

/// The message, as the FMU logs it (see `body::BodyError`: no derived dump in the binary).
impl fmt::Debug for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

/// An ordered set of named entries: the container without any physics.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Container {
    entries: BTreeMap<String, Entry>,
}

impl Container {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn put_array(&mut self, name: &str, dims: &[usize], values: &[f64]) {
        debug_assert_eq!(dims.iter().product::<usize>(), values.len());
        self.entries.insert(name.to_owned(), Entry::Array { dims: dims.to_vec(), values: values.to_vec() });
    }

    pub fn put_text(&mut self, name: &str, text: &str) {
        self.entries.insert(name.to_owned(), Entry::Text(text.to_owned()));
    }

    /// Every array with its name, in name order: what the file carries, for checks that must
    /// see all of it.
    pub fn arrays(&self) -> impl Iterator<Item = (&str, &[f64])> {
        self.entries.iter().filter_map(|(name, e)| match e {
            Entry::Array { values, .. } => Some((name.as_str(), values.as_slice())),
            Entry::Text(_) => None,
        })
    }

    /// Copy every entry of `other` in, its name behind `prefix` (a container inside another: an
    /// assembly's bodies).
    pub fn nest(&mut self, prefix: &str, other: &Container) {
        for (name, entry) in &other.entries {
            self.entries.insert(format!("{prefix}{name}"), entry.clone());
        }
    }

    /// The entries whose names start with `prefix`, the prefix taken off.
    pub fn nested(&self, prefix: &str) -> Container {
        let entries = self
            .entries
            .range(prefix.to_owned()..)
            .take_while(|(name, _)| name.starts_with(prefix))
            .map(|(name, e)| (name[prefix.len()..].to_owned(), e.clone()))
            .collect();
        Container { entries }
    }

    pub fn contains(&self, name: &str) -> bool {
        self.entries.contains_key(name)
    }

    /// The array `name`, checked against the expected shape.
    pub fn array(&self, name: &str, expected: &[usize]) -> Result<&[f64], FormatError> {
        match self.entries.get(name) {
            None => Err(FormatError::Missing(name.to_owned())),
            Some(Entry::Array { dims, values }) => {
                if dims.as_slice() != expected {
                    return Err(FormatError::Shape {
                        name: name.to_owned(),
                        found: dims.clone(),
                        expected: expected.to_vec(),
                    });
                }
                Ok(values)
            }
            Some(Entry::Text(_)) => Err(FormatError::WrongKind { name: name.to_owned(), expected: "an array" }),
        }
    }

    /// The dimensions of the array `name`, to size the others by.
    pub fn dims(&self, name: &str) -> Result<&[usize], FormatError> {
        match self.entries.get(name) {
            None => Err(FormatError::Missing(name.to_owned())),
            Some(Entry::Array { dims, .. }) => Ok(dims),
            Some(Entry::Text(_)) => Err(FormatError::WrongKind { name: name.to_owned(), expected: "an array" }),
        }
    }

    pub fn scalar(&self, name: &str) -> Result<f64, FormatError> {
        Ok(self.array(name, &[1])?[0])
    }

    pub fn text(&self, name: &str) -> Result<&str, FormatError> {
        match self.entries.get(name) {
            None => Err(FormatError::Missing(name.to_owned())),
            Some(Entry::Text(t)) => Ok(t),
            Some(Entry::Array { .. }) => Err(FormatError::WrongKind { name: name.to_owned(), expected: "text" }),
        }
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let mut payload = Vec::new();
        payload.extend_from_slice(&(self.entries.len() as u32).to_le_bytes());
        for (name, entry) in &self.entries {
            payload.extend_from_slice(&(name.len() as u16).to_le_bytes());
            payload.extend_from_slice(name.as_bytes());
            match entry {
                Entry::Array { dims, values } => {
                    payload.push(0);
                    payload.push(dims.len() as u8);
                    for d in dims {
                        payload.extend_from_slice(&(*d as u64).to_le_bytes());
                    }
                    for v in values {
                        payload.extend_from_slice(&v.to_le_bytes());
                    }
                }
                Entry::Text(t) => {
                    payload.push(1);
                    payload.extend_from_slice(&(t.len() as u64).to_le_bytes());
                    payload.extend_from_slice(t.as_bytes());
                }
            }
        }
        let mut out = Vec::with_capacity(payload.len() + 24);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&payload);
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// The GUID of this content: a name-based UUID (RFC 9562 version 5, SHA-1) of the
    /// container's bytes with the `guid` entry empty, in a namespace of this tool. The builder
    /// stores it as the FMU's GUID and the runtime recomputes it on loading, so any change of a
    /// resource file after the build (even one that keeps its CRC valid) no longer matches the
    /// GUID of modelDescription.xml, and the same model gets the same GUID on every machine.
    pub fn content_guid(&self) -> String {
        let mut unnamed = self.clone();
        unnamed.put_text(GUID_ENTRY, "");
        name_based_uuid(&unnamed.to_bytes())
    }

    /// The container of an FMU's resource file: its stored GUID must be its content's, so a
    /// file changed after the build (however consistent) is refused rather than run under the
    /// modelDescription.xml of another model.
    pub fn from_sealed_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        let c = Self::from_bytes(bytes)?;
        let (stored, computed) = (c.text(GUID_ENTRY)?, c.content_guid());
        if stored != computed {
            return Err(FormatError::Malformed(format!(
                "its content does not match its GUID {stored} (the content's is {computed}): the file was changed after the build"
            )));
        }
        Ok(c)
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        let mut r = Reader { bytes, pos: 0 };
        if r.take(8).map_err(|_| FormatError::BadMagic)? != MAGIC {
            return Err(FormatError::BadMagic);
        }
        let version = r.u32()?;
        if version != FORMAT_VERSION {
            return Err(FormatError::UnsupportedVersion(version));
        }
        let len = usize::try_from(r.u64()?).map_err(|_| FormatError::Malformed("payload length overflows".into()))?;
        let payload_start = r.pos;
        let payload_end =
            payload_start.checked_add(len).ok_or_else(|| FormatError::Malformed("payload length overflows".into()))?;
        let file_end =
            payload_end.checked_add(4).ok_or_else(|| FormatError::Malformed("payload length overflows".into()))?;
        if file_end > bytes.len() {
            return Err(FormatError::Truncated { at: bytes.len(), needed: file_end - bytes.len() });
        }
        let stored = u32::from_le_bytes(bytes[payload_end..payload_end + 4].try_into().unwrap_or([0; 4]));
        let computed = crc32fast::hash(&bytes[..payload_end]);
        if stored != computed {
            return Err(FormatError::ChecksumMismatch { stored, computed });
        }
        if payload_end + 4 != bytes.len() {
            return Err(FormatError::Malformed(format!(
                "{} trailing bytes after the checksum",
                bytes.len() - payload_end - 4
            )));
        }
        let mut r = Reader { bytes: &bytes[..payload_end], pos: payload_start };
        let count = r.u32()?;
        let mut entries = BTreeMap::new();
        for _ in 0..count {
            let name_len = r.u16()? as usize;
            let name = std::str::from_utf8(r.take(name_len)?)
                .map_err(|_| FormatError::Malformed("entry name is not UTF-8".into()))?
                .to_owned();
            let entry = match r.u8()? {
                0 => read_array(&mut r, &name)?,
                1 => {
                    let n = usize::try_from(r.u64()?)
                        .map_err(|_| FormatError::Malformed(format!("length of '{name}' overflows")))?;
                    let t = std::str::from_utf8(r.take(n)?)
                        .map_err(|_| FormatError::Malformed(format!("text '{name}' is not UTF-8")))?;
                    Entry::Text(t.to_owned())
                }
                k => return Err(FormatError::Malformed(format!("entry '{name}' has unknown kind {k}"))),
            };
            if entries.insert(name.clone(), entry).is_some() {
                return Err(FormatError::Malformed(format!("entry '{name}' appears twice")));
            }
        }
        if r.pos != payload_end {
            return Err(FormatError::Malformed("payload has unread bytes".into()));
        }
        Ok(Self { entries })
    }
}

/// An array entry after its name and kind: rank, dimensions, values (finite only).
fn read_array(r: &mut Reader, name: &str) -> Result<Entry, FormatError> {
    let rank = r.u8()? as usize;
    let mut dims = Vec::with_capacity(rank);
    let mut total: usize = 1;
    for _ in 0..rank {
        let d = usize::try_from(r.u64()?)
            .map_err(|_| FormatError::Malformed(format!("dimension of '{name}' overflows")))?;
        total = total.checked_mul(d).ok_or_else(|| FormatError::Malformed(format!("size of '{name}' overflows")))?;
        dims.push(d);
    }
    let nbytes = total.checked_mul(8).ok_or_else(|| FormatError::Malformed(format!("size of '{name}' overflows")))?;
    let raw = r.take(nbytes)?;
    let values: Vec<f64> = raw.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect();
    // the builder writes finite numbers only: anything else is damage or forgery
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(FormatError::Malformed(format!(
            "entry '{name}' holds {} at index {i}, not a finite number",
            values[i]
        )));
    }
    Ok(Entry::Array { dims, values })
}

struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], FormatError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(FormatError::Truncated { at: self.pos, needed: n.saturating_sub(self.bytes.len() - self.pos) })?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, FormatError> {
        Ok(self.take(1)?[0])
    }
    fn u16(&mut self) -> Result<u16, FormatError> {
        Ok(u16::from_le_bytes(self.take(2)?.try_into().unwrap_or([0; 2])))
    }
    fn u32(&mut self) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap_or([0; 4])))
    }
    fn u64(&mut self) -> Result<u64, FormatError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap_or([0; 8])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Container {
        let mut c = Container::new();
        c.put_text("guid", "{abc}");
        c.put_array("omega", &[3], &[1.0, 2.0, 3.5]);
        c.put_array("c_t", &[3, 2], &[1., 2., 3., 4., 5., 6.]);
        c
    }

    #[test]
    fn round_trip() {
        let c = sample();
        let back = Container::from_bytes(&c.to_bytes()).unwrap();
        assert_eq!(back, c);
        assert_eq!(back.array("c_t", &[3, 2]).unwrap()[5], 6.0);
        assert_eq!(back.text("guid").unwrap(), "{abc}");
    }

    #[test]
    fn corrupt_truncated_and_foreign_files_are_refused() {
        let bytes = sample().to_bytes();
        let mut flipped = bytes.clone();
        flipped[30] ^= 0x40;
        assert!(matches!(Container::from_bytes(&flipped), Err(FormatError::ChecksumMismatch { .. })));
        for cut in [0, 5, 12, 20, bytes.len() - 1] {
            assert!(Container::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        assert_eq!(Container::from_bytes(b"PK\x03\x04 not ours"), Err(FormatError::BadMagic));
        let mut newer = bytes.clone();
        newer[8] = 99;
        assert_eq!(Container::from_bytes(&newer), Err(FormatError::UnsupportedVersion(99)));
    }

    #[test]
    fn shape_and_missing_entries_are_named() {
        let c = sample();
        assert!(matches!(c.array("c_t", &[3, 3]), Err(FormatError::Shape { .. })));
        assert_eq!(c.array("nope", &[1]), Err(FormatError::Missing("nope".into())));
        assert!(c.text("omega").is_err());
    }
}
