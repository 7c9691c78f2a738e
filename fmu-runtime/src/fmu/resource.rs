//! The reduced-model file the FMU's resources hold.

use crate::format::FormatError;
use std::fmt;
use std::path::{Path, PathBuf};

/// Largest reduced-model file read: the largest models we build (hundreds of modes with
/// rotation and stiffening terms, 3 x 3 x r x r each) stay far below it.
const MAX_RESOURCE_BYTES: u64 = 1 << 30;

/// Why the reduced body could not be loaded from the FMU's resources (fmi2Instantiate).
pub enum LoadError {
    /// The host gave no resource location.
    NoResourceLocation,
    /// The file could not be read.
    Unreadable { path: PathBuf, source: std::io::Error },
    /// Not a regular file (a FIFO would block, a link to a device read without end).
    NotAFile(PathBuf),
    /// Larger than any reduced model.
    TooLarge { path: PathBuf, len: u64 },
    /// Grew beyond the limit while it was read.
    Grew(PathBuf),
    /// Not a reduced-model file of this runtime, or changed after the build.
    Malformed { path: PathBuf, source: FormatError },
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::NoResourceLocation => {
                f.write_str("no resource location given: the reduced body lives in the FMU's resources folder")
            }
            LoadError::Unreadable { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            LoadError::NotAFile(path) => write!(f, "{} is not a regular file", path.display()),
            LoadError::TooLarge { path, len } => write!(
                f,
                "{} has {len} bytes, more than any reduced model ({MAX_RESOURCE_BYTES} at most)",
                path.display()
            ),
            LoadError::Grew(path) => {
                write!(f, "{} grew beyond {MAX_RESOURCE_BYTES} bytes while it was read", path.display())
            }
            LoadError::Malformed { path, source } => write!(f, "{}: {source}", path.display()),
        }
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LoadError::Unreadable { source, .. } => Some(source),
            LoadError::Malformed { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// A model file in the FMU's resources folder, read and parsed by `parse` (the sealed-container
/// reader of a body or an assembly); every failure is the instance's (fmi2Instantiate fails).
pub(super) fn load_resource<T>(
    resources: Option<&Path>,
    file: &str,
    parse: impl FnOnce(&[u8]) -> Result<T, FormatError>,
) -> Result<T, fmi2::ModelError> {
    let dir = resources.ok_or(fmi2::ModelError::failed(LoadError::NoResourceLocation))?;
    let path = dir.join(file);
    let bytes = read_resource(&path).map_err(fmi2::ModelError::failed)?;
    parse(&bytes).map_err(|source| fmi2::ModelError::failed(LoadError::Malformed { path, source }))
}

/// The reduced-model file's bytes: a regular file (a FIFO would block fmi2Instantiate, a link
/// to a device would read without end) of at most [`MAX_RESOURCE_BYTES`].
pub(super) fn read_resource(path: &Path) -> Result<Vec<u8>, LoadError> {
    use std::io::Read;
    let unreadable = |source| LoadError::Unreadable { path: path.to_owned(), source };
    let meta = std::fs::metadata(path).map_err(unreadable)?;
    if !meta.is_file() {
        return Err(LoadError::NotAFile(path.to_owned()));
    }
    if meta.len() > MAX_RESOURCE_BYTES {
        return Err(LoadError::TooLarge { path: path.to_owned(), len: meta.len() });
    }
    let file = std::fs::File::open(path).map_err(unreadable)?;
    // the file may grow between the check and the read: never read past the limit
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_RESOURCE_BYTES + 1).read_to_end(&mut bytes).map_err(unreadable)?;
    if bytes.len() as u64 > MAX_RESOURCE_BYTES {
        return Err(LoadError::Grew(path.to_owned()));
    }
    Ok(bytes)
}

/// The message, as the FMU logs it (see `body::BodyError`: no derived dump in the binary).
impl std::fmt::Debug for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}
