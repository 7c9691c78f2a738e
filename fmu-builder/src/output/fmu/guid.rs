//! The FMU's GUID, derived from the reduced model's content.

use fmu_runtime::reduced::ReducedBody;

/// The FMU's GUID: a name-based UUID (RFC 9562 version 5, SHA-1) of the reduced model's bytes in
/// a namespace of this tool, so the same model gives the same GUID on every machine and Rust
/// release, and any change of the model gives another.
pub fn guid_of(bytes: &[u8]) -> String {
    const NAMESPACE: uuid::Uuid = uuid::Uuid::from_u128(0x6f4d_2a61_8e3b_4c57_9a0e_52b1_c3d8_f7e4);
    format!("{{{}}}", uuid::Uuid::new_v5(&NAMESPACE, bytes).hyphenated())
}

/// The GUID of a reduced body: the same model always gets the same GUID.
pub fn guid(reduced: &ReducedBody) -> String {
    guid_of(&reduced.to_bytes())
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
