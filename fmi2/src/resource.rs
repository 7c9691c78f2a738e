//! fmuResourceLocation: a file URI (RFC 8089) naming the unpacked `resources` folder.
//!
//! Importers disagree on the spelling (`file:/p`, `file:///p`, `file://localhost/p`,
//! and some prepend an extra slash), so all of them are accepted. Characters are taken
//! literally except `%XX` escapes: sloppy importers pass raw spaces, '#' or '?'.

use std::path::PathBuf;

use percent_encoding::percent_decode_str;

/// What makes an fmuResourceLocation unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unusable {
    NotFileUri,
    RemoteHost,
    RelativePath,
    NotUtf8,
}

/// An fmuResourceLocation that names no local folder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ResourceError {
    pub uri: String,
    pub why: Unusable,
}

impl std::fmt::Display for ResourceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let why = match self.why {
            Unusable::NotFileUri => "only file: URIs are supported",
            Unusable::RemoteHost => "the host must be empty or localhost",
            Unusable::RelativePath => "the path must be absolute",
            Unusable::NotUtf8 => "the decoded path is not valid UTF-8",
        };
        write!(f, "fmuResourceLocation \"{}\" is not usable: {why}", self.uri)
    }
}

impl std::error::Error for ResourceError {}

pub fn parse_resource_location(uri: &str) -> Result<PathBuf, ResourceError> {
    let refuse = |why: Unusable| ResourceError { uri: uri.to_owned(), why };

    let rest = match uri.get(..5) {
        Some(scheme) if scheme.eq_ignore_ascii_case("file:") => &uri[5..],
        _ => return Err(refuse(Unusable::NotFileUri)),
    };
    // "//authority/path": only the local host can be meant.
    let path = match rest.strip_prefix("//") {
        Some(after) if after.starts_with('/') => after,
        Some(after) => {
            let end = after.find('/').unwrap_or(after.len());
            if !after[..end].eq_ignore_ascii_case("localhost") {
                return Err(refuse(Unusable::RemoteHost));
            }
            &after[end..]
        }
        None => rest,
    };
    if !path.starts_with('/') {
        return Err(refuse(Unusable::RelativePath));
    }

    let mut bytes: Vec<u8> = percent_decode_str(path).collect();
    if cfg!(windows) {
        // "/C:/dir" names the drive path "C:/dir".
        if bytes.len() >= 3 && bytes[0] == b'/' && bytes[1].is_ascii_alphabetic() && bytes[2] == b':' {
            bytes.remove(0);
        }
    } else {
        // "file:////p" gives "//p", the same directory as "/p" on POSIX systems.
        while bytes.starts_with(b"//") {
            bytes.remove(0);
        }
    }
    while bytes.len() > 1 && bytes.ends_with(b"/") {
        bytes.pop();
    }
    bytes_to_path(bytes).map_err(|()| refuse(Unusable::NotUtf8))
}

#[cfg(unix)]
fn bytes_to_path(bytes: Vec<u8>) -> Result<PathBuf, ()> {
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

#[cfg(not(unix))]
fn bytes_to_path(bytes: Vec<u8>) -> Result<PathBuf, ()> {
    String::from_utf8(bytes).map(PathBuf::from).map_err(|_| ())
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn ok(uri: &str) -> String {
        parse_resource_location(uri).unwrap().to_str().unwrap().to_owned()
    }

    #[test]
    fn accepted_spellings() {
        for uri in [
            "file:/tmp/fmu/resources",
            "file://localhost/tmp/fmu/resources",
            "FILE://LocalHost/tmp/fmu/resources",
            "file:///tmp/fmu/resources",
            "file:////tmp/fmu/resources",
            "file:///tmp/fmu/resources/",
            "file:/tmp/fmu/resources//",
        ] {
            assert_eq!(ok(uri), "/tmp/fmu/resources", "{uri}");
        }
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(ok("file:///tmp/my%20fmu/res%C3%A4/"), "/tmp/my fmu/resä");
        assert_eq!(ok("file:///tmp/100%/a b#c"), "/tmp/100%/a b#c");
        assert_eq!(ok("file:///"), "/");
    }

    #[test]
    fn refused() {
        for uri in [
            "http://example.com/resources",
            "file://otherhost/resources",
            "file:relative/path",
            "/tmp/fmu/resources",
            "",
            "fil",
        ] {
            assert!(parse_resource_location(uri).is_err(), "{uri}");
        }
    }
}
