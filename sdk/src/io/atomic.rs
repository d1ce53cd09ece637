//! Atomic saving: write a temporary file next to the target, flush it to disk, then rename it
//! over the target, so a crash never leaves a half-written lens file.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::olf_xml::write_xml;
use crate::system::LensSystem;

/// Saves `system` as our XML at `path`, atomically (temporary file in the same directory,
/// then rename).
pub fn save_xml(system: &LensSystem, path: &Path) -> io::Result<()> {
    write_atomically(path, write_xml(system).as_bytes())
}

/// Writes `bytes` to `path` through a temporary file in the same directory.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let tmp = temp_path(path)?;
    let result = (|| {
        let mut f = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// `.<name>.<pid>.<n>.tmp` beside the target.
fn temp_path(path: &Path) -> io::Result<PathBuf> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("`{}` does not name a file", path.display()),
        )
    })?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp_name = format!(".{}.{}.{n}.tmp", name.to_string_lossy(), std::process::id());
    Ok(path.with_file_name(tmp_name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let tmp = tempfile::Builder::new()
            .prefix("flarebench-atomic-")
            .tempdir()
            .unwrap();
        let dir = tmp.path();
        let target = dir.join("lens.xml");
        write_atomically(&target, b"first").unwrap();
        write_atomically(&target, b"second").unwrap();
        assert_eq!(fs::read(&target).unwrap(), b"second");
        let names: Vec<_> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("lens.xml")]);
        tmp.close().unwrap();
    }

    #[test]
    fn a_missing_directory_is_an_error_not_a_panic() {
        let target = Path::new("/nonexistent-flarebench-dir/lens.xml");
        assert!(write_atomically(target, b"x").is_err());
    }
}
