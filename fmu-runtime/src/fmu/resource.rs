//! The reduced-model file the FMU's resources hold.

/// Largest reduced-model file read: the largest models we build (hundreds of modes with
/// rotation and stiffening terms, 3 x 3 x r x r each) stay far below it.
const MAX_RESOURCE_BYTES: u64 = 1 << 30;

/// The reduced-model file's bytes: a regular file (a FIFO would block fmi2Instantiate, a link
/// to a device would read without end) of at most [`MAX_RESOURCE_BYTES`].
pub(super) fn read_resource(path: &std::path::Path) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", path.display()));
    }
    if meta.len() > MAX_RESOURCE_BYTES {
        return Err(format!(
            "{} has {} bytes, more than any reduced model ({MAX_RESOURCE_BYTES} at most)",
            path.display(),
            meta.len()
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    // the file may grow between the check and the read: never read past the limit
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_RESOURCE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if bytes.len() as u64 > MAX_RESOURCE_BYTES {
        return Err(format!("{} grew beyond {MAX_RESOURCE_BYTES} bytes while it was read", path.display()));
    }
    Ok(bytes)
}
