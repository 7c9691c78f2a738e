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

fn finite(v: f64, what: &str) -> Result<f64, String> {
    if v.is_finite() { Ok(v) } else { Err(format!("{what} = {v} is not a finite number")) }
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
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if n > self.remaining() {
            return Err(format!(
                "truncated: {what} needs {n} bytes at offset {} but only {} remain",
                self.pos,
                self.remaining()
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }
    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.array::<1>(what)?[0])
    }
    /// Only 0 and 1 are booleans.
    pub fn bool(&mut self, what: &str) -> Result<bool, String> {
        match self.u8(what)? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(format!("{what} is {v}, not a boolean (0 or 1)")),
        }
    }
    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    /// A real of a saved state: a non-finite one was never written (every value a state holds
    /// is finite), so it is crafted or corrupt bytes and refused.
    pub fn f64(&mut self, what: &str) -> Result<f64, String> {
        finite(f64::from_le_bytes(self.array(what)?), what)
    }
    /// Fills `out` (its length is the count: sizes come from the reader's side, never the bytes).
    pub fn f64s_into(&mut self, out: &mut [f64], what: &str) -> Result<(), String> {
        let n = out.len().checked_mul(8).ok_or_else(|| format!("{what}: size overflows"))?;
        let raw = self.take(n, what)?;
        for (x, c) in out.iter_mut().zip(raw.chunks_exact(8)) {
            let mut a = [0u8; 8];
            a.copy_from_slice(c);
            *x = finite(f64::from_le_bytes(a), what)?;
        }
        Ok(())
    }
    pub fn f64_array<const N: usize>(&mut self, what: &str) -> Result<[f64; N], String> {
        let mut a = [0.0; N];
        self.f64s_into(&mut a, what)?;
        Ok(a)
    }
    /// A length written by [`Writer::len`], checked to fit in what is left (at `unit` bytes each).
    pub fn len(&mut self, unit: usize, what: &str) -> Result<usize, String> {
        let n = self.u64(what)?;
        let fits = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(unit.max(1)))
            .is_some_and(|bytes| bytes <= self.remaining());
        if !fits {
            return Err(format!(
                "{what} = {n} at offset {} exceeds the {} bytes that remain",
                self.pos - 8,
                self.remaining()
            ));
        }
        Ok(n as usize)
    }
    pub fn str(&mut self, what: &str) -> Result<&'a str, String> {
        let n = self.u32(what)? as usize;
        let raw = self.take(n, what)?;
        std::str::from_utf8(raw).map_err(|_| format!("{what} is not valid UTF-8"))
    }
    /// Everything must have been read.
    pub fn finish(&self, what: &str) -> Result<(), String> {
        match self.remaining() {
            0 => Ok(()),
            n => Err(format!("{n} unexpected bytes after the {what}")),
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
        let read = |bytes: &[u8]| -> Result<Fields, String> {
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
        assert_eq!(read(&bad).unwrap_err(), "b is 2, not a boolean (0 or 1)");
        // a saved state never holds a non-finite real: such bytes are crafted and refused
        for nan in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut bad = out.clone();
            bad[6..14].copy_from_slice(&nan.to_le_bytes());
            assert_eq!(read(&bad).unwrap_err(), format!("d = {nan} is not a finite number"));
        }
    }

    #[test]
    fn lengths_beyond_the_bytes_are_refused_before_allocating() {
        let mut out = Vec::new();
        Writer::new(&mut out).u64(u64::MAX);
        let e = Reader::new(&out).len(8, "n").unwrap_err();
        assert!(e.contains("exceeds"), "{e}");
        let mut out = Vec::new();
        Writer::new(&mut out).u32(1 << 30);
        assert!(Reader::new(&out).str("s").unwrap_err().starts_with("truncated"));
    }
}
