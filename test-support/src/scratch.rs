//! Folders the tests write FMU resources and input files into: each test (and each fuzz case)
//! gets its own, because tests run in parallel and a fuzz child runs many cases, and each is
//! removed when dropped, also when the test fails.

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A new empty folder under the system's temporary folder, removed with its content on drop.
pub struct Scratch {
    path: PathBuf,
}

impl Scratch {
    /// `<temp>/<tag>-<process id>-<count>`: unique within and across processes.
    pub fn new(tag: &str) -> Self {
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let k = COUNT.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("{tag}-{}-{k}", std::process::id()));
        std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Self { path }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A subfolder, created (e.g. an FMU's `resources`).
    pub fn folder(&self, name: &str) -> PathBuf {
        let path = self.path.join(name);
        std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// `folder` as the `file://` URI fmi2Instantiate takes for fmuResourceLocation.
pub fn file_uri(folder: &Path) -> CString {
    CString::new(format!("file://{}", folder.display())).expect("a path without NUL")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_are_distinct_and_removed_on_drop() {
        let (a, b) = (Scratch::new("test-support-scratch"), Scratch::new("test-support-scratch"));
        assert_ne!(a.path(), b.path());
        let resources = a.folder("resources");
        std::fs::write(resources.join("x"), b"1").unwrap();
        assert_eq!(file_uri(&resources).to_str().unwrap(), format!("file://{}", resources.display()));
        let path = a.path().to_owned();
        drop(a);
        assert!(!path.exists() && b.path().is_dir());
    }
}
