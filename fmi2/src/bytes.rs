//! Little-endian encoding for serialized FMU states, shared by the layer and the models.
//!
//! Every value is written field by field with `to_le_bytes` (never a struct dump), so the bytes
//! are the same on every platform. The reader never panics: each read checks what is left and
//! reports what it was reading where, and sizes read from the bytes are checked against the
//! bytes that remain before anything is allocated.

/// Appends little-endian values to a byte vector.
pub struct Writer<'a> {
    out: &'a mut Vec<u8>,
}

impl<'a> Writer<'a> {
    pub fn new(out: &'a mut Vec<u8>) -> Self {
        Self { out }
    }
    pub fn u8(&mut self, v: u8) {
        self.out.push(v);
    }
    pub fn bool(&mut self, v: bool) {
        self.out.push(u8::from(v));
    }
    pub fn u32(&mut self, v: u32) {
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    /// Exact bits, NaN payloads included.
    pub fn f64(&mut self, v: f64) {
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f64s(&mut self, v: &[f64]) {
        self.out.reserve(8 * v.len());
        for x in v {
            self.f64(*x);
        }
    }
    /// A length: u64 whatever the platform's usize.
    pub fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }
    /// u32 byte length, then UTF-8.
    pub fn str(&mut self, s: &str) {
        self.u32(u32::try_from(s.len()).unwrap_or(u32::MAX));
        self.out.extend_from_slice(&s.as_bytes()[..s.len().min(u32::MAX as usize)]);
    }
    pub fn bytes(&mut self, b: &[u8]) {
        self.out.extend_from_slice(b);
    }
}

/// A model's own reason to refuse what well-formed bytes hold (a version it does not read, sizes
/// of another body): its typed error, kept as the source.
pub type Refusal = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why bytes of a saved state could not be read; every variant names the field (`what`).
#[derive(Debug)]
pub enum DecodeError {
    /// Fewer bytes remain than the field needs.
    Truncated { what: String, needed: usize, at: usize, remaining: usize },
    /// A real that no saved state holds (every value a state holds is finite).
    NotFinite { what: String, value: f64 },
    /// A byte other than 0 and 1 where a boolean is.
    NotBoolean { what: String, value: u8 },
    /// The byte count of an array does not fit in a usize.
    SizeOverflow { what: String },
    /// A length read from the bytes that exceeds the bytes that remain.
    LengthBeyondBytes { what: String, length: u64, at: usize, remaining: usize },
    /// A string that is not UTF-8.
    NotUtf8 { what: String },
    /// Bytes left over after everything was read.
    Trailing { what: String, count: usize },
    /// The bytes read well but the model refuses what they hold (its error says why).
    Invalid(Refusal),
}

impl DecodeError {
    /// The model's refusal of what the bytes hold.
    pub fn invalid(reason: impl std::error::Error + Send + Sync + 'static) -> Self {
        DecodeError::Invalid(Box::new(reason))
    }
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DecodeError::Truncated { what, needed, at, remaining } => {
                write!(f, "truncated: {what} needs {needed} bytes at offset {at} but only {remaining} remain")
            }
            DecodeError::NotFinite { what, value } => write!(f, "{what} = {value} is not a finite number"),
            DecodeError::NotBoolean { what, value } => write!(f, "{what} is {value}, not a boolean (0 or 1)"),
            DecodeError::SizeOverflow { what } => write!(f, "{what}: size overflows"),
            DecodeError::LengthBeyondBytes { what, length, at, remaining } => {
                write!(f, "{what} = {length} at offset {at} exceeds the {remaining} bytes that remain")
            }
            DecodeError::NotUtf8 { what } => write!(f, "{what} is not valid UTF-8"),
            DecodeError::Trailing { what, count } => write!(f, "{count} unexpected bytes after the {what}"),
            DecodeError::Invalid(reason) => std::fmt::Display::fmt(reason, f),
        }
    }
}

impl std::error::Error for DecodeError {
    /// The model's refusal is shown as it is: its own source comes next.
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            DecodeError::Invalid(reason) => reason.source(),
            _ => None,
        }
    }
}

fn finite(v: f64, what: &str) -> Result<f64, DecodeError> {
    if v.is_finite() { Ok(v) } else { Err(DecodeError::NotFinite { what: what.to_owned(), value: v }) }
}

/// Reads what [`Writer`] wrote; every method names the field in its error.
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, pos: 0 }
    }
    pub fn position(&self) -> usize {
        self.pos
    }
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], DecodeError> {
        if n > self.remaining() {
            return Err(DecodeError::Truncated {
                what: what.to_owned(),
                needed: n,
                at: self.pos,
                remaining: self.remaining(),
            });
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], DecodeError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }
    pub fn u8(&mut self, what: &str) -> Result<u8, DecodeError> {
        Ok(self.array::<1>(what)?[0])
    }
    /// Only 0 and 1 are booleans.
    pub fn bool(&mut self, what: &str) -> Result<bool, DecodeError> {
        match self.u8(what)? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(DecodeError::NotBoolean { what: what.to_owned(), value: v }),
        }
    }
    pub fn u32(&mut self, what: &str) -> Result<u32, DecodeError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    pub fn u64(&mut self, what: &str) -> Result<u64, DecodeError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    /// A real of a saved state: a non-finite one was never written (every value a state holds
    /// is finite), so it is crafted or corrupt bytes and refused.
    pub fn f64(&mut self, what: &str) -> Result<f64, DecodeError> {
        finite(f64::from_le_bytes(self.array(what)?), what)
    }
    /// Fills `out` (its length is the count: sizes come from the reader's side, never the bytes).
    pub fn f64s_into(&mut self, out: &mut [f64], what: &str) -> Result<(), DecodeError> {
        let n = out.len().checked_mul(8).ok_or_else(|| DecodeError::SizeOverflow { what: what.to_owned() })?;
        let raw = self.take(n, what)?;
        for (x, c) in out.iter_mut().zip(raw.chunks_exact(8)) {
            let mut a = [0u8; 8];
            a.copy_from_slice(c);
            *x = finite(f64::from_le_bytes(a), what)?;
        }
        Ok(())
    }
    pub fn f64_array<const N: usize>(&mut self, what: &str) -> Result<[f64; N], DecodeError> {
        let mut a = [0.0; N];
        self.f64s_into(&mut a, what)?;
        Ok(a)
    }
    /// A length written by [`Writer::len`], checked to fit in what is left (at `unit` bytes each).
    pub fn len(&mut self, unit: usize, what: &str) -> Result<usize, DecodeError> {
        let n = self.u64(what)?;
        let fits = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(unit.max(1)))
            .is_some_and(|bytes| bytes <= self.remaining());
        if !fits {
            return Err(DecodeError::LengthBeyondBytes {
                what: what.to_owned(),
                length: n,
                at: self.pos - 8,
                remaining: self.remaining(),
            });
        }
        Ok(n as usize)
    }
    pub fn str(&mut self, what: &str) -> Result<&'a str, DecodeError> {
        let n = self.u32(what)? as usize;
        let raw = self.take(n, what)?;
        std::str::from_utf8(raw).map_err(|_| DecodeError::NotUtf8 { what: what.to_owned() })
    }
    /// Everything must have been read.
    pub fn finish(&self, what: &str) -> Result<(), DecodeError> {
        match self.remaining() {
            0 => Ok(()),
            n => Err(DecodeError::Trailing { what: what.to_owned(), count: n }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_every_truncation_is_an_error() {
        let mut out = Vec::new();
        let mut w = Writer::new(&mut out);
        w.u8(7);
        w.bool(true);
        w.u32(0xdead_beef);
        w.f64(f64::from_bits(0x0000_0000_0000_1234)); // a denormal: bits kept
        w.f64s(&[1.5, -0.0]);
        w.str("{guid}");
        w.len(2);
        w.bytes(&[1, 2]);
        type Fields = (u8, bool, u32, u64, [f64; 2], String, usize);
        let read = |bytes: &[u8]| -> Result<Fields, DecodeError> {
            let mut r = Reader::new(bytes);
            let v = (
                r.u8("a")?,
                r.bool("b")?,
                r.u32("c")?,
                r.f64("d")?.to_bits(),
                r.f64_array::<2>("e")?,
                r.str("f")?.to_owned(),
                r.len(1, "g")?,
            );
            r.take(v.6, "h")?;
            r.finish("test")?;
            Ok(v)
        };
        let (a, b, c, d, e, f, _) = read(&out).unwrap();
        assert_eq!((a, b, c, d, f.as_str()), (7, true, 0xdead_beef, 0x0000_0000_0000_1234, "{guid}"));
        assert_eq!(e[1].to_bits(), (-0.0f64).to_bits());
        for cut in 0..out.len() {
            assert!(read(&out[..cut]).is_err(), "cut at {cut}");
        }
        let mut bad = out.clone();
        bad[1] = 2;
        let e = read(&bad).unwrap_err();
        assert!(matches!(&e, DecodeError::NotBoolean { what, value: 2 } if what == "b"), "{e:?}");
        assert_eq!(e.to_string(), "b is 2, not a boolean (0 or 1)");
        // a saved state never holds a non-finite real: such bytes are crafted and refused
        for nan in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut bad = out.clone();
            bad[6..14].copy_from_slice(&nan.to_le_bytes());
            assert_eq!(read(&bad).unwrap_err().to_string(), format!("d = {nan} is not a finite number"));
        }
    }

    /// A model's refusal of what the bytes hold keeps its type (and its message).
    #[test]
    fn a_models_refusal_is_kept_as_it_is() {
        #[derive(Debug)]
        struct Version(u32);
        impl std::fmt::Display for Version {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "state version {} is not 1", self.0)
            }
        }
        impl std::error::Error for Version {}
        let e = DecodeError::invalid(Version(7));
        assert_eq!(e.to_string(), "state version 7 is not 1");
        assert!(matches!(&e, DecodeError::Invalid(r) if r.downcast_ref::<Version>().is_some_and(|v| v.0 == 7)));
    }

    #[test]
    fn lengths_beyond_the_bytes_are_refused_before_allocating() {
        let mut out = Vec::new();
        Writer::new(&mut out).u64(u64::MAX);
        let e = Reader::new(&out).len(8, "n").unwrap_err().to_string();
        assert!(e.contains("exceeds"), "{e}");
        let mut out = Vec::new();
        Writer::new(&mut out).u32(1 << 30);
        assert!(Reader::new(&out).str("s").unwrap_err().to_string().starts_with("truncated"));
    }
}
