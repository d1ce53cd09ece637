//! Noticing that a file was rewritten — a plugin library rebuilt by cargo, a lens file saved —
//! by polling its metadata (`compare --watch`, the window's `--algo` plugins).
//!
//! Polling rather than the system's file events (inotify and its kin, through the `notify`
//! crate): the files watched are a handful, so a `stat` of each every [`POLL_INTERVAL`] costs
//! nothing measurable, and polling needs no dependency, behaves the same on every platform and
//! file system (network and container mounts included, where events are unreliable), and is
//! not misled by the way a library is replaced — cargo links a new file over the old path,
//! which events report on the directory as a create or a rename rather than a change of the
//! file watched. A change is reported once the file has stopped changing (its stamp the same
//! for [`SETTLE_POLLS`] polls: a file written in steps is not taken half written) and only when
//! its content differs from what was last taken (a rebuild that relinks the same bytes, or a
//! `touch`, is not a change).

use std::hash::Hasher;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// Time between two polls.
pub const POLL_INTERVAL: Duration = Duration::from_millis(200);
/// Polls for which a changed file's stamp must stay the same before it is taken.
pub const SETTLE_POLLS: u32 = 2;

/// What identifies a version of a file without reading it: size, modification time and (on
/// Unix) the inode, which changes when cargo links a new library over the old path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Stamp {
    len: u64,
    modified: Option<SystemTime>,
    inode: u64,
}

fn stamp(path: &Path) -> Option<Stamp> {
    let m = std::fs::metadata(path).ok()?;
    #[cfg(unix)]
    let inode = std::os::unix::fs::MetadataExt::ino(&m);
    #[cfg(not(unix))]
    let inode = 0;
    Some(Stamp {
        len: m.len(),
        modified: m.modified().ok(),
        inode,
    })
}

/// A hash of the file's bytes (`None` when it cannot be read).
fn content_hash(path: &Path) -> Option<u64> {
    let bytes = std::fs::read(path).ok()?;
    let mut h = std::hash::DefaultHasher::new();
    h.write(&bytes);
    Some(h.finish())
}

/// One file watched for changes.
#[derive(Debug)]
pub struct WatchedFile {
    path: PathBuf,
    /// The stamp of the version last taken.
    taken: Option<Stamp>,
    /// The stamp at the last poll, and for how many polls since it has not changed.
    seen: Option<Stamp>,
    quiet_polls: u32,
    /// The content hash of the version last taken.
    content: Option<u64>,
}

impl WatchedFile {
    /// Starts watching `path`, its present version taken as seen.
    pub fn new(path: &Path) -> WatchedFile {
        let s = stamp(path);
        WatchedFile {
            path: path.to_path_buf(),
            taken: s,
            seen: s,
            quiet_polls: 0,
            content: content_hash(path),
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Looks at the file once; true when it has changed since the version last taken, has
    /// stopped changing, and holds other bytes — that version is then taken. A missing file is
    /// not a change (cargo may be between removing the old library and linking the new).
    pub fn poll(&mut self) -> bool {
        let now = stamp(&self.path);
        if now == self.seen {
            self.quiet_polls = self.quiet_polls.saturating_add(1);
        } else {
            self.seen = now;
            self.quiet_polls = 0;
        }
        if now.is_none() || now == self.taken || self.quiet_polls < SETTLE_POLLS {
            return false;
        }
        self.taken = now;
        let content = content_hash(&self.path);
        if content.is_none() || content == self.content {
            return false;
        }
        self.content = content;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Polls until `poll` says changed, at most `n` times; the number of polls it took.
    fn polls_until_change(w: &mut WatchedFile, n: u32) -> Option<u32> {
        (1..=n).find(|_| w.poll())
    }

    #[test]
    fn a_rewrite_is_reported_once_after_it_settles_and_a_same_content_rewrite_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("libx.so");
        std::fs::write(&path, b"first").unwrap();
        let mut w = WatchedFile::new(&path);
        assert_eq!(polls_until_change(&mut w, 5), None, "nothing changed");

        std::fs::write(&path, b"second version").unwrap();
        // The first poll sees the new stamp; it must then stay for SETTLE_POLLS polls.
        assert_eq!(polls_until_change(&mut w, 10), Some(SETTLE_POLLS + 1));
        assert_eq!(polls_until_change(&mut w, 5), None, "reported once");

        // Written in steps: each step restarts the wait.
        std::fs::write(&path, b"third, part").unwrap();
        assert!(!w.poll());
        std::fs::write(&path, b"third, part two").unwrap();
        assert!(!w.poll());
        assert_eq!(polls_until_change(&mut w, 10), Some(SETTLE_POLLS));

        // The same bytes again (a relink, a touch): a new stamp, not a change.
        std::fs::remove_file(&path).unwrap();
        assert_eq!(
            polls_until_change(&mut w, 5),
            None,
            "missing is not a change"
        );
        std::fs::write(&path, b"third, part two").unwrap();
        assert_eq!(polls_until_change(&mut w, 10), None);

        std::fs::write(&path, b"fourth").unwrap();
        assert_eq!(polls_until_change(&mut w, 10), Some(SETTLE_POLLS + 1));
    }

    #[test]
    fn a_file_that_appears_later_is_a_change() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("later.so");
        let mut w = WatchedFile::new(&path);
        assert!(!w.poll());
        std::fs::write(&path, b"built").unwrap();
        assert_eq!(polls_until_change(&mut w, 10), Some(SETTLE_POLLS + 1));
    }
}
