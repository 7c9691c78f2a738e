//! The FMU's GUID, derived from the reduced model's content.

use fmu_runtime::reduced::ReducedBody;

/// A name-based UUID (RFC 9562 version 5, SHA-1) of `bytes` in a namespace of this tool.
pub fn guid_of(bytes: &[u8]) -> String {
    fmu_runtime::format::name_based_uuid(bytes)
}

/// The FMU's GUID: the UUID of the reduced model's content (its bytes with the GUID left
/// empty), so the same model gets the same GUID on every machine and Rust release, any change
/// of the model gives another, and the runtime recomputes it to detect a changed resource file.
pub fn guid(reduced: &ReducedBody) -> String {
    reduced.to_container().content_guid()
}

#[cfg(test)]
mod tests {
    /// The GUID is RFC 9562's version-5 UUID, as any implementation computes it: the expected
    /// value comes from Python's `uuid.uuid5` with the same namespace and name.
    #[test]
    fn guid_is_a_standard_name_based_uuid() {
        assert_eq!(super::guid_of(b"reduced body"), "{7f7ca901-e4fb-5418-9b2f-592a98c5c92c}");
        assert_ne!(super::guid_of(b"reduced body"), super::guid_of(b"reduced body "));
    }
}
