//! Folders a command fills: each kind of folder trompe makes is one [`FolderKind`], and a
//! folder carries a marker (`.trompe-folder.json`) naming its kind and the files the result is
//! made of. A command writes only into a new or empty folder, or one of its own kind; a result
//! of several files is written into a hidden sibling ([`StagedFolder`]) and swapped in whole.
//!
//! Invariants: a folder's marker is written last, inside the staged folder, so a folder that has
//! one holds a whole result; files in a folder that its marker does not list (a user's) are
//! carried into the new result, never dropped; a staged folder left by a killed writer has a
//! hidden name carrying its process id, and the next writer of the same folder removes it once
//! that process is gone.

use super::{PublishLock, alive};
use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use thiserror::Error;

/// The marker's file name, inside the folder.
pub const MARKER: &str = ".trompe-folder.json";

/// The largest marker read (a marker lists file names; this bounds a hostile one).
const MARKER_LIMIT: u64 = 16 << 20;

/// Every kind of folder a trompe command fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FolderKind {
    /// `views capture`: images and a COLMAP model.
    Capture,
    /// `layers build`: OpenRaster files, `layers.json` and the cameras.
    LayerSet,
    /// `master encode` and `master edit`: master textures, `masters.json`, the baked mesh.
    MasterEncoding,
    /// `relief`: a walk's frames and its table.
    ReliefWalk,
    /// `view`: the viewer's frames, screenshots and saved cameras.
    ViewerFrames,
    /// `render --frames`: a sequence's frames.
    FrameSequence,
    /// `demo`: the HTML report and its images.
    DemoReport,
    /// An octahedral batch: one bake per mesh and the manifest.
    OctahedralBatch,
}

impl FolderKind {
    const ALL: [FolderKind; 8] = [
        FolderKind::Capture,
        FolderKind::LayerSet,
        FolderKind::MasterEncoding,
        FolderKind::ReliefWalk,
        FolderKind::ViewerFrames,
        FolderKind::FrameSequence,
        FolderKind::DemoReport,
        FolderKind::OctahedralBatch,
    ];

    /// The name the marker records.
    pub fn tag(self) -> &'static str {
        match self {
            FolderKind::Capture => "capture",
            FolderKind::LayerSet => "layer-set",
            FolderKind::MasterEncoding => "master-encoding",
            FolderKind::ReliefWalk => "relief-walk",
            FolderKind::ViewerFrames => "viewer-frames",
            FolderKind::FrameSequence => "frame-sequence",
            FolderKind::DemoReport => "demo-report",
            FolderKind::OctahedralBatch => "octahedral-batch",
        }
    }

    /// What the folder is, in a user's words (with the command that makes it).
    pub fn describe(self) -> &'static str {
        match self {
            FolderKind::Capture => "a capture (trompe views capture)",
            FolderKind::LayerSet => "a layer set (trompe layers build)",
            FolderKind::MasterEncoding => "a master encoding (trompe master encode)",
            FolderKind::ReliefWalk => "a relief walk (trompe relief)",
            FolderKind::ViewerFrames => "a viewer's frames (trompe view)",
            FolderKind::FrameSequence => "a frame sequence (trompe render --frames)",
            FolderKind::DemoReport => "a demo report (trompe demo)",
            FolderKind::OctahedralBatch => "an octahedral batch (trompe impostor bake)",
        }
    }

    fn from_tag(tag: &str) -> Option<FolderKind> {
        FolderKind::ALL.into_iter().find(|k| k.tag() == tag)
    }
}

/// A folder refused as an output, or a staged result that could not be published.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FolderError {
    /// The output is a file, not a folder.
    #[error("{path}: not a folder")]
    NotAFolder {
        /// The output.
        path: PathBuf,
    },
    /// The folder holds files no trompe command wrote.
    #[error(
        "{path}: the folder holds files trompe did not write ({example} among them); give a new \
         or empty folder"
    )]
    Foreign {
        /// The folder.
        path: PathBuf,
        /// One file in it.
        example: String,
    },
    /// The folder is another command's result.
    #[error("{path}: the folder is {found}, not {expected}; give a new or empty folder")]
    OtherKind {
        /// The folder.
        path: PathBuf,
        /// What it is.
        found: String,
        /// What the command writes.
        expected: &'static str,
    },
    /// A file of the user's in the folder has the name of a file of the new result.
    #[error(
        "{path}: {file} in the folder is not one trompe wrote, and the new result has a file of \
         that name; the folder is left as it was"
    )]
    Collision {
        /// The folder.
        path: PathBuf,
        /// The file.
        file: String,
    },
    /// Reading or writing failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

fn io_at(path: &Path) -> impl FnOnce(std::io::Error) -> FolderError + '_ {
    move |source| FolderError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The marker's contents.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Marker {
    /// Always `"trompe-folder"`.
    format: String,
    /// [`FolderKind::tag`].
    kind: String,
    /// The result's files, relative, `/`-separated; empty for a folder filled file by file.
    files: Vec<String>,
}

const MARKER_FORMAT: &str = "trompe-folder";

/// What an output folder is before a command writes into it.
#[derive(Debug)]
pub(super) enum FolderState {
    /// Nothing there yet, or an empty folder.
    New,
    /// A result of this kind, made of these files.
    Made(Vec<String>),
}

impl FolderState {
    /// Reads `dir`'s state, refusing a file, a folder of a user's and another kind's result.
    pub(super) fn of(dir: &Path, kind: FolderKind) -> Result<FolderState, FolderError> {
        let entries = match std::fs::read_dir(dir) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(FolderState::New),
            Err(_) if dir.exists() && !dir.is_dir() => {
                return Err(FolderError::NotAFolder {
                    path: dir.to_path_buf(),
                });
            }
            Err(e) => return Err(io_at(dir)(e)),
        };
        let mut example = None;
        for entry in entries {
            let name = entry.map_err(io_at(dir))?.file_name();
            if name != MARKER {
                example = Some(name.to_string_lossy().into_owned());
                break;
            }
        }
        let marker = dir.join(MARKER);
        if !marker.is_file() {
            return match example {
                None => Ok(FolderState::New),
                Some(example) => Err(FolderError::Foreign {
                    path: dir.to_path_buf(),
                    example,
                }),
            };
        }
        let mut text = String::new();
        std::fs::File::open(&marker)
            .and_then(|f| f.take(MARKER_LIMIT).read_to_string(&mut text))
            .map_err(io_at(&marker))?;
        let unreadable = |reason: String| FolderError::Io {
            path: marker.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, reason),
        };
        let found: Marker = serde_json::from_str(&text).map_err(|e| unreadable(e.to_string()))?;
        if found.format != MARKER_FORMAT {
            return Err(unreadable(format!(
                "format {:?} is not {MARKER_FORMAT:?}",
                found.format
            )));
        }
        match FolderKind::from_tag(&found.kind) {
            Some(k) if k == kind => Ok(FolderState::Made(found.files)),
            other => Err(FolderError::OtherKind {
                path: dir.to_path_buf(),
                found: other.map_or_else(
                    || format!("a {:?} folder of another trompe", found.kind),
                    |k| k.describe().to_string(),
                ),
                expected: kind.describe(),
            }),
        }
    }
}

/// Makes `dir` a folder of `kind` filled file by file (frames written as they come): refuses a
/// file, a folder of a user's or another kind's result, then creates it and writes its marker.
pub fn claim_folder(dir: &Path, kind: FolderKind) -> Result<(), FolderError> {
    if let FolderState::New = FolderState::of(dir, kind)? {
        std::fs::create_dir_all(dir).map_err(io_at(dir))?;
        write_marker(dir, kind, Vec::new())?;
    }
    Ok(())
}

fn write_marker(dir: &Path, kind: FolderKind, files: Vec<String>) -> Result<(), FolderError> {
    let marker = Marker {
        format: MARKER_FORMAT.into(),
        kind: kind.tag().into(),
        files,
    };
    let path = dir.join(MARKER);
    let text = serde_json::to_vec_pretty(&marker).map_err(|e| FolderError::Io {
        path: path.clone(),
        source: std::io::Error::other(e),
    })?;
    super::write_atomically(&path, &text).map_err(io_at(&path))
}

/// A result of several files being written into a hidden sibling of its folder, then made
/// current by one atomic swap ([`StagedFolder::publish`]). Dropped unpublished, it removes what
/// it wrote and the folder is as it was.
///
/// ```
/// use trompe::files::{FolderKind, StagedFolder};
/// let out = std::env::temp_dir().join(format!("trompe-doc-staged-{}", std::process::id()));
/// let staged = StagedFolder::begin(&out, FolderKind::Capture)?;
/// std::fs::write(staged.path().join("cameras.txt"), "# none\n")?;
/// staged.publish()?;
/// assert!(out.join("cameras.txt").is_file());
/// # std::fs::remove_dir_all(&out)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct StagedFolder {
    target: PathBuf,
    staging: PathBuf,
    kind: FolderKind,
    published: bool,
}

impl StagedFolder {
    /// Refuses `target` unless it is new, empty or a result of `kind`; removes what killed
    /// writers of it left; makes the hidden folder to write into. Writers of one folder run at
    /// once; their publishing is serialised ([`StagedFolder::publish`]).
    pub fn begin(target: &Path, kind: FolderKind) -> Result<StagedFolder, FolderError> {
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| FolderError::NotAFolder {
                path: target.to_path_buf(),
            })?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(io_at(&parent))?;
        FolderState::of(target, kind)?;
        // What writers that died left (their process is gone), under the lock.
        let prefix = format!(".{name}.staging-");
        {
            let _lock = PublishLock::of(target);
            for entry in std::fs::read_dir(&parent).map_err(io_at(&parent))? {
                let entry = entry.map_err(io_at(&parent))?;
                let file_name = entry.file_name().to_string_lossy().into_owned();
                let Some(rest) = file_name.strip_prefix(&prefix) else {
                    continue;
                };
                let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
                if pid.is_some_and(|p| !alive(p)) {
                    let litter = entry.path();
                    std::fs::remove_dir_all(&litter).map_err(io_at(&litter))?;
                }
            }
        }
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let staging = parent.join(format!(
            "{prefix}{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir(&staging).map_err(io_at(&staging))?;
        Ok(StagedFolder {
            target: target.to_path_buf(),
            staging,
            kind,
            published: false,
        })
    }

    /// The folder to write the result into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder the result will be published as.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Makes the staged result current, under the publishing lock of the folder's parent (a
    /// second writer waits): carries in the files of the user's that the folder holds now (a
    /// name the new result also has is refused, and nothing changes), writes the marker, and
    /// swaps the staged folder with the old one in one step.
    pub fn publish(mut self) -> Result<(), FolderError> {
        let _lock = PublishLock::of(&self.target);
        // The folder as it is now: another writer may have published since `begin`.
        let earlier = match FolderState::of(&self.target, self.kind)? {
            FolderState::New => Vec::new(),
            FolderState::Made(files) => files,
        };
        let mut files = relative_files(&self.staging).map_err(io_at(&self.staging))?;
        files.retain(|f| f != MARKER);
        files.sort();
        if self.target.is_dir() {
            for f in relative_files(&self.target).map_err(io_at(&self.target))? {
                if f == MARKER || earlier.contains(&f) {
                    continue;
                }
                if files.binary_search(&f).is_ok() {
                    return Err(FolderError::Collision {
                        path: self.target.clone(),
                        file: f,
                    });
                }
                let (from, to) = (self.target.join(&f), self.staging.join(&f));
                if let Some(dir) = to.parent() {
                    std::fs::create_dir_all(dir).map_err(io_at(dir))?;
                }
                if std::fs::hard_link(&from, &to).is_err() {
                    std::fs::copy(&from, &to).map_err(io_at(&from))?;
                }
            }
        }
        write_marker(&self.staging, self.kind, files)?;
        pause_for_tests();
        if self.target.exists() {
            swap(&self.staging, &self.target).map_err(io_at(&self.target))?;
            // The staged name now holds the old result.
            self.published = true;
            std::fs::remove_dir_all(&self.staging).map_err(io_at(&self.staging))?;
        } else {
            std::fs::rename(&self.staging, &self.target).map_err(io_at(&self.target))?;
            self.published = true;
        }
        Ok(())
    }
}

impl Drop for StagedFolder {
    fn drop(&mut self) {
        if !self.published {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

/// Every file under `dir`, as relative `/`-separated paths (links are not followed).
fn relative_files(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((folder, prefix)) = stack.pop() {
        for entry in std::fs::read_dir(&folder)? {
            let entry = entry?;
            let name = format!("{prefix}{}", entry.file_name().to_string_lossy());
            if entry.file_type()?.is_dir() {
                stack.push((entry.path(), format!("{name}/")));
            } else {
                out.push(name);
            }
        }
    }
    Ok(out)
}

/// Exchanges two folders in one step: `renameat2(RENAME_EXCHANGE)` on Linux; elsewhere (or on
/// a file system without it) the old folder is renamed aside first, a window in which a reader
/// finds no folder, never a mixed one.
fn swap(staged: &Path, target: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        match renameat_with(CWD, staged, CWD, target, RenameFlags::EXCHANGE) {
            Ok(()) => return Ok(()),
            Err(e) if e == rustix::io::Errno::INVAL || e == rustix::io::Errno::NOSYS => {}
            Err(e) => return Err(e.into()),
        }
    }
    let aside = staged.with_extension("old");
    std::fs::rename(target, &aside)?;
    std::fs::rename(staged, target)?;
    std::fs::rename(&aside, staged)
}

/// A test hook: `TROMPE_TEST_PAUSE_IN_PUBLISH_MS` (at most 10 s) holds a writer with its result
/// staged and its marker written, just before the swap, so that tests can kill it or race it
/// there.
fn pause_for_tests() {
    if let Some(ms) = std::env::var("TROMPE_TEST_PAUSE_IN_PUBLISH_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms.min(10_000)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn publish(out: &Path, kind: FolderKind, files: &[(&str, &str)]) -> Result<(), FolderError> {
        let staged = StagedFolder::begin(out, kind)?;
        for (name, text) in files {
            let p = staged.path().join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, text).unwrap();
        }
        staged.publish()
    }

    #[test]
    fn a_result_replaces_the_last_whole_and_keeps_the_users_files() {
        let d = crate::test_scratch::scratch("files_folder");
        let out = d.join("capture");
        publish(
            &out,
            FolderKind::Capture,
            &[
                ("cameras.txt", "1"),
                ("images/a.png", "a"),
                ("images/b.png", "b"),
            ],
        )
        .unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        publish(
            &out,
            FolderKind::Capture,
            &[("cameras.txt", "2"), ("images/a.png", "a2")],
        )
        .unwrap();
        let mut files = relative_files(&out).unwrap();
        files.sort();
        assert_eq!(
            files,
            [MARKER, "cameras.txt", "images/a.png", "notes.txt"],
            "the old result's b.png is gone, the user's notes kept"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("cameras.txt")).unwrap(),
            "2"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("notes.txt")).unwrap(),
            "mine"
        );
        // The user's file named like a result file: refused, nothing changes.
        let err = publish(&out, FolderKind::Capture, &[("notes.txt", "x")]).unwrap_err();
        assert!(matches!(err, FolderError::Collision { .. }), "{err}");
        assert_eq!(
            std::fs::read_to_string(out.join("cameras.txt")).unwrap(),
            "2"
        );
        // No staged folder is left beside it.
        let litter: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .collect();
        assert!(litter.is_empty(), "{litter:?}");
    }

    #[test]
    fn another_kind_or_a_users_folder_is_refused_before_any_work() {
        let d = crate::test_scratch::scratch("files_folder_kind");
        let out = d.join("layers");
        publish(&out, FolderKind::LayerSet, &[("layers.json", "{}")]).unwrap();
        let err = StagedFolder::begin(&out, FolderKind::Capture)
            .err()
            .unwrap();
        assert!(
            err.to_string()
                .contains("is a layer set (trompe layers build)"),
            "{err}"
        );
        let mine = d.join("mine");
        std::fs::create_dir_all(&mine).unwrap();
        std::fs::write(mine.join("photo.jpg"), "x").unwrap();
        let err = StagedFolder::begin(&mine, FolderKind::MasterEncoding)
            .err()
            .unwrap();
        assert!(matches!(err, FolderError::Foreign { .. }), "{err}");
        let file = d.join("file");
        std::fs::write(&file, "x").unwrap();
        assert!(matches!(
            StagedFolder::begin(&file, FolderKind::Capture),
            Err(FolderError::NotAFolder { .. })
        ));
        // An unpublished result leaves nothing behind, and a killed one's litter is cleared.
        let litter = d.join(".layers.staging-999999999-1");
        std::fs::create_dir_all(&litter).unwrap();
        drop(StagedFolder::begin(&out, FolderKind::LayerSet).unwrap());
        assert!(!litter.exists());
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            3,
            "layers, mine, file and nothing else"
        );
    }
}
