//! Never lose a user's file: atomic replacement of outputs ([`write_atomically`]), results of
//! several files published whole (a folder staged then swapped in, [`StagedFolder`]; files
//! beside each other named by an index written last with their checksums, [`Parts`]), and the
//! plan a command checks before any work ([`OutputPlan`]). The lowest layer: every writer in the
//! crate goes through here.
//!
//! Invariant: an output is either left as it was or replaced whole; a failed or killed write
//! leaves only hidden temporary names (a later writer of the same output clears them), never a
//! truncated or mixed result.

mod folder;
mod parts;
mod plan;

pub use folder::{FolderError, FolderKind, MARKER, StagedFolder, claim_folder};
pub use parts::{Part, PartError, checksum_file};
pub use plan::{OutputError, OutputPlan};

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Holds the folder of a multi-file artefact (an impostor's EXR and the sidecar that names it)
/// while one writer publishes it: a second writer to the same folder waits, so concurrent
/// writers leave one complete result, never one's sidecar beside another's maps. The lock is
/// the operating system's advisory lock on the folder, released when the guard drops or the
/// process dies (a killed writer never leaves it held). Where a folder cannot be locked (a
/// platform that does not open folders as files), writers proceed unserialised.
pub struct PublishLock {
    _folder: Option<std::fs::File>,
}

impl PublishLock {
    /// Waits for, then takes, the publishing lock of `path`'s folder.
    pub fn of(path: &Path) -> PublishLock {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let folder = std::fs::File::open(dir).ok().filter(|f| f.lock().is_ok());
        PublishLock { _folder: folder }
    }
}

/// Writes `bytes` to `path` as a whole: into a temporary file in the same folder, flushed to
/// disk, then renamed over `path` (a rename within one file system is atomic). On any error the
/// temporary file is removed and `path` is as it was.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    StagedFile::write(path, bytes)?.commit()
}

/// A file written whole under a hidden temporary name beside its path, flushed to disk, and made
/// current by [`StagedFile::commit`] (one rename). A result of several files beside each other
/// stages every part first, then commits them one after the other: the window in which a kill
/// leaves some parts new is a few renames long, not the time to encode and write them.
/// Dropped uncommitted, the temporary file is removed.
pub struct StagedFile {
    tmp: PathBuf,
    path: PathBuf,
    committed: bool,
}

/// Removes what writers that died left in `dir` (`.NAME.PID-N.tmp` of a process that is gone),
/// once a process: a batch writing thousands of files into one folder reads it once, not once a
/// file.
fn remove_litter(dir: &Path) {
    static CLEANED: std::sync::LazyLock<std::sync::Mutex<std::collections::HashSet<PathBuf>>> =
        std::sync::LazyLock::new(Default::default);
    let mut cleaned = CLEANED.lock().unwrap_or_else(|e| e.into_inner());
    if cleaned.contains(dir) {
        return;
    }
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let file_name = entry.file_name().to_string_lossy().into_owned();
            let pid = file_name
                .strip_prefix('.')
                .and_then(|rest| rest.strip_suffix(".tmp"))
                .and_then(|rest| rest.rsplit_once('.'))
                .and_then(|(_, tag)| tag.split_once('-'))
                .filter(|(_, n)| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|(p, _)| p.parse::<u32>().ok());
            if pid.is_some_and(|p| !alive(p)) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
    cleaned.insert(dir.to_path_buf());
}

impl StagedFile {
    /// Writes `bytes` under a temporary name beside `path`, flushed to disk.
    pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<StagedFile> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = path
            .file_name()
            .ok_or_else(|| std::io::Error::other("the path names no file"))?;
        let prefix = format!(".{}.", name.to_string_lossy());
        remove_litter(dir);
        let staged = StagedFile {
            tmp: dir.join(format!(
                "{prefix}{}-{}.tmp",
                std::process::id(),
                NEXT.fetch_add(1, Ordering::Relaxed)
            )),
            path: path.to_path_buf(),
            committed: false,
        };
        let mut f = std::fs::File::create_new(&staged.tmp)?;
        f.write_all(bytes)?;
        f.sync_data()?;
        Ok(staged)
    }

    /// Renames the temporary file over the path.
    pub fn commit(mut self) -> std::io::Result<()> {
        std::fs::rename(&self.tmp, &self.path)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for StagedFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Whether process `pid` runs (Linux: it has a `/proc` entry; elsewhere, assumed).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_atomic_write_replaces_whole_or_leaves_the_old_file() {
        let d = crate::test_scratch::scratch("files_atomic");
        let f = d.join("x.png");
        write_atomically(&f, b"old").unwrap();
        write_atomically(&f, b"new contents").unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"new contents");
        // A write that cannot land (its target is a folder) leaves no temporary behind.
        let folder = d.join("sub");
        std::fs::create_dir_all(&folder).unwrap();
        assert!(write_atomically(&folder, b"x").is_err());
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        assert_eq!(std::fs::read(&f).unwrap(), b"new contents");
    }

    #[test]
    fn what_dead_writers_left_is_removed_and_nothing_else() {
        let d = crate::test_scratch::scratch("files_litter");
        // A writer of another file that died (no process has that id), and files of the
        // user's that only look alike.
        let dead = d.join(".y.exr.4294967295-3.tmp");
        let mine = [
            ".notes.tmp",
            ".y.exr.tmp",
            ".y.exr.12-x.tmp",
            "y.exr.4294967295-3.tmp",
        ]
        .map(|n| d.join(n));
        std::fs::write(&dead, b"torn").unwrap();
        for m in &mine {
            std::fs::write(m, b"the user's").unwrap();
        }
        write_atomically(&d.join("x.png"), b"x").unwrap();
        assert!(!dead.exists());
        assert!(mine.iter().all(|m| m.exists()));
    }
}
