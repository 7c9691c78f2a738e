//! Which fmu-runtime source a binary was built from: every runtime build carries
//! `FMU_RUNTIME_BUILD_ID=<version>+src.<hash of its sources>` as an exported C string
//! (fmu-runtime/build.rs). A binary built elsewhere must carry this builder's identity: the
//! reduced-model file and the variable numbering the builder writes are its own runtime's. The
//! text is found in the file's bytes, so the check is the same for every format, and for every
//! slice of a universal binary.

use crate::error::Refusal;
use fmu_runtime::{BUILD_ID, BUILD_ID_MARKER};

/// Ok when every identity in `data` is `expected`; else what was found.
pub fn check(data: &[u8], expected: &str) -> Result<(), Refusal> {
    let found = identities(data);
    if found.is_empty() {
        return Err(Refusal::from(format!(
            "carries no fmu-runtime build identity ({BUILD_ID_MARKER}...): it is not a build of this project's fmu-runtime, or of one older than the identity; build it from the source of this builder (fmu-runtime {expected})"
        )));
    }
    match found.iter().find(|id| id.as_str() != expected) {
        Some(other) => Err(Refusal::from(format!(
            "was built from fmu-runtime {other}, this builder's runtime is {expected} (version + hash of fmu-runtime/src and fmi2/src): build it from the same commit as the builder"
        ))),
        None => Ok(()),
    }
}

/// This builder's own runtime identity.
pub fn own() -> &'static str {
    BUILD_ID
}

/// Every identity in `data`: the text after each marker up to the NUL, when it is printable.
fn identities(data: &[u8]) -> Vec<String> {
    let marker = BUILD_ID_MARKER.as_bytes();
    let mut found = Vec::new();
    let mut start = 0;
    while let Some(at) = find(&data[start..], marker) {
        let text = &data[start + at + marker.len()..];
        let end = text.iter().take(200).position(|&b| b == 0);
        if let Some(end) = end
            && text[..end].iter().all(|b| b.is_ascii_graphic())
        {
            found.push(String::from_utf8_lossy(&text[..end]).into_owned());
        }
        start += at + marker.len();
    }
    found
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::package::RUNTIME_SO;

    #[test]
    fn the_embedded_runtime_carries_this_builders_identity() {
        assert_eq!(identities(RUNTIME_SO), [BUILD_ID]);
        check(RUNTIME_SO, own()).unwrap();
    }

    #[test]
    fn a_missing_or_foreign_identity_is_refused() {
        let e = check(b"no identity here", own()).unwrap_err().reason;
        assert!(e.contains("carries no fmu-runtime build identity"), "{e}");
        let foreign = format!("xx{BUILD_ID_MARKER}0.0.9+src.0123456789abcdef\0yy");
        let e = check(foreign.as_bytes(), own()).unwrap_err().reason;
        assert!(e.contains("was built from fmu-runtime 0.0.9+src.0123456789abcdef"), "{e}");
        // a marker at the very end, or without its NUL, is no identity
        assert!(identities(BUILD_ID_MARKER.as_bytes()).is_empty());
    }
}
