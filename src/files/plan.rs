//! The plan a command checks before any work: every path it reads, every path and folder it
//! writes, so that an output is never an input, two outputs are never one file, an output has a
//! known extension and an existing folder, and a folder another command made is never filled
//! by a command of another kind.
//!
//! Invariant: [`OutputPlan::check`] reads the file system and writes nothing.

use super::folder::{FolderKind, FolderState};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a command's outputs were refused, before any work.
#[derive(Debug, Error, PartialEq, Eq)]
#[non_exhaustive]
pub enum OutputError {
    /// An output is a file the command reads.
    #[error("{output}: refusing to overwrite an input file ({input} is read by this command)")]
    IsInput {
        /// The output.
        output: PathBuf,
        /// The input it is.
        input: PathBuf,
    },
    /// Two outputs are the same file.
    #[error("{first} and {second} are the same file: each output needs its own")]
    SameOutput {
        /// One output.
        first: PathBuf,
        /// The other.
        second: PathBuf,
    },
    /// An output's extension is not one the command writes there.
    #[error("{path}: expected a file ending in {expected}")]
    Extension {
        /// The output.
        path: PathBuf,
        /// What it may end in.
        expected: String,
    },
    /// An output folder cannot take the command's result (a file, a user's folder, another
    /// command's result).
    #[error("{reason}")]
    Folder {
        /// The folder.
        path: PathBuf,
        /// Why, naming the folder and what it holds ([`super::FolderError`]'s words).
        reason: String,
    },
    /// An output's folder does not exist.
    #[error("{path}: the folder {folder} does not exist")]
    NoFolder {
        /// The output.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
}

/// The paths one command reads and writes, checked together before it starts.
#[derive(Clone, Debug, Default)]
pub struct OutputPlan {
    inputs: Vec<PathBuf>,
    outputs: Vec<(PathBuf, &'static [&'static str])>,
    folders: Vec<(PathBuf, FolderKind)>,
    creates_folders: bool,
}

impl OutputPlan {
    /// An empty plan.
    pub fn new() -> Self {
        OutputPlan::default()
    }

    /// Files the command reads.
    pub fn reads<P: Into<PathBuf>>(&mut self, paths: impl IntoIterator<Item = P>) -> &mut Self {
        self.inputs.extend(paths.into_iter().map(Into::into));
        self
    }

    /// A file the command writes, which must end in one of `extensions` (lower case, no dot).
    pub fn writes(
        &mut self,
        path: impl Into<PathBuf>,
        extensions: &'static [&'static str],
    ) -> &mut Self {
        self.outputs.push((path.into(), extensions));
        self
    }

    /// A folder the command fills with a result of `kind` (published whole through
    /// [`super::StagedFolder`], or claimed with [`super::claim_folder`]): it must be new, empty
    /// or a result of that kind, and no file the command reads may be one of the result's files.
    pub fn writes_folder(&mut self, dir: impl Into<PathBuf>, kind: FolderKind) -> &mut Self {
        self.folders.push((dir.into(), kind));
        self
    }

    /// The command makes its outputs' missing folders itself (after [`OutputPlan::check`]):
    /// a missing folder is then not refused.
    pub fn creating_folders(&mut self) -> &mut Self {
        self.creates_folders = true;
        self
    }

    /// Makes the outputs' missing folders.
    pub fn make_folders(&self) -> std::io::Result<()> {
        for (path, _) in &self.outputs {
            if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(d)?;
            }
        }
        Ok(())
    }

    /// Refuses an output that is an input (the same file by any path, links included), two
    /// outputs that are one file, an unknown extension or a missing folder. Paths under a folder
    /// that does not exist yet cannot be an existing file, and are compared by their spelling.
    pub fn check(&self) -> Result<(), OutputError> {
        self.check_overwrites()?;
        self.check_writable()
    }

    /// Refuses one more output, decided while the command runs (a screenshot, a frame), if it
    /// is a file the command reads.
    pub fn check_output(&self, output: &Path) -> Result<(), OutputError> {
        let Some(id) = Identity::of(output) else {
            return Ok(());
        };
        match self
            .inputs
            .iter()
            .find(|i| Identity::of(i).is_some_and(|i| i.same(&id)))
        {
            Some(input) => Err(OutputError::IsInput {
                output: output.to_path_buf(),
                input: input.clone(),
            }),
            None => Ok(()),
        }
    }

    /// Only the first half of [`OutputPlan::check`]: no output is an input or another output
    /// (what a command can say before it has read everything it will read).
    pub fn check_overwrites(&self) -> Result<(), OutputError> {
        let inputs: Vec<(Identity, &PathBuf)> = self
            .inputs
            .iter()
            .filter_map(|p| Identity::of(p).map(|id| (id, p)))
            .collect();
        for (dir, kind) in &self.folders {
            let earlier = match FolderState::of(dir, *kind) {
                Ok(FolderState::New) => continue,
                Ok(FolderState::Made(files)) => files,
                Err(e) => {
                    return Err(OutputError::Folder {
                        path: dir.clone(),
                        reason: e.to_string(),
                    });
                }
            };
            for file in earlier {
                let Some(id) = Identity::of(&dir.join(&file)) else {
                    continue;
                };
                if let Some((_, input)) = inputs.iter().find(|(i, _)| i.same(&id)) {
                    return Err(OutputError::IsInput {
                        output: dir.join(&file),
                        input: (*input).clone(),
                    });
                }
            }
        }
        let mut seen: Vec<(Identity, &PathBuf, &[&str])> = Vec::new();
        for (path, extensions) in &self.outputs {
            // What it would destroy first, then whether it can be written.
            if let Some(id) = Identity::of(path) {
                if let Some((_, input)) = inputs.iter().find(|(i, _)| i.same(&id)) {
                    return Err(OutputError::IsInput {
                        output: path.clone(),
                        input: (*input).clone(),
                    });
                }
                if let Some((_, first, first_extensions)) =
                    seen.iter().find(|(i, _, _)| i.same(&id))
                {
                    // A wrong extension explains the clash: `-o a.exr` where `a.json` is asked
                    // for and `a.exr` goes beside it.
                    check_extension(first, first_extensions)?;
                    check_extension(path, extensions)?;
                    return Err(OutputError::SameOutput {
                        first: (*first).clone(),
                        second: path.clone(),
                    });
                }
                seen.push((id, path, extensions));
            }
        }
        Ok(())
    }

    /// The second half of [`OutputPlan::check`]: every output has a known extension and a
    /// folder.
    fn check_writable(&self) -> Result<(), OutputError> {
        for (path, extensions) in &self.outputs {
            check_extension(path, extensions)?;
            let folder = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            if !folder.is_dir() && !self.creates_folders {
                return Err(OutputError::NoFolder {
                    path: path.clone(),
                    folder,
                });
            }
        }
        Ok(())
    }
}

/// Refuses `path` unless its extension is one of `extensions` (any case).
fn check_extension(path: &Path, extensions: &[&str]) -> Result<(), OutputError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match extensions.contains(&ext.as_str()) {
        true => Ok(()),
        false => Err(OutputError::Extension {
            path: path.to_path_buf(),
            expected: extensions
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join(" or "),
        }),
    }
}

/// What makes two paths one file: the canonical path (its folder's, for a file not yet
/// written), and for an existing file its device and inode (hard links).
#[derive(Clone, Debug)]
struct Identity {
    canonical: PathBuf,
    inode: Option<(u64, u64)>,
}

impl Identity {
    fn of(path: &Path) -> Option<Identity> {
        let canonical = match std::fs::canonicalize(path) {
            Ok(c) => c,
            Err(_) => {
                let folder = match path.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                match std::fs::canonicalize(folder) {
                    Ok(f) => f.join(path.file_name()?),
                    Err(_) => std::path::absolute(path).ok()?,
                }
            }
        };
        Some(Identity {
            inode: inode(path),
            canonical,
        })
    }

    fn same(&self, other: &Identity) -> bool {
        self.canonical == other.canonical
            || matches!((self.inode, other.inode), (Some(a), Some(b)) if a == b)
    }
}

#[cfg(unix)]
fn inode(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode(_: &Path) -> Option<(u64, u64)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_that_are_inputs_or_each_other_are_refused_before_any_work() {
        let d = crate::test_scratch::scratch("files_plan");
        let mesh = d.join("teapot.obj");
        std::fs::write(&mesh, "v 0 0 0\n").unwrap();
        let link = d.join("link.obj");
        let _ = std::fs::hard_link(&mesh, &link);
        let mut plan = OutputPlan::new();
        plan.reads([&mesh])
            .writes(d.join("out.png"), &["png", "exr"]);
        assert_eq!(plan.check(), Ok(()));
        // The input by another spelling, and by a hard link.
        let other = d.join(".").join("teapot.obj");
        for out in [other, link.clone()] {
            let mut p = OutputPlan::new();
            p.reads([&mesh]).writes(out.clone(), &["obj"]);
            assert!(
                matches!(p.check(), Err(OutputError::IsInput { .. })),
                "{out:?}"
            );
        }
        let mut p = OutputPlan::new();
        p.writes(d.join("a.exr"), &["exr"])
            .writes(d.join("./a.exr"), &["exr"]);
        assert!(matches!(p.check(), Err(OutputError::SameOutput { .. })));
        // Two outputs one file because one was named with the other's extension: the
        // extension is what is wrong.
        let mut p = OutputPlan::new();
        p.writes(d.join("b.exr"), &["json"])
            .writes(d.join("b.exr"), &["exr"]);
        assert!(
            matches!(&p.check(), Err(OutputError::Extension { expected, .. }) if expected == ".json"),
            "{:?}",
            p.check()
        );
        let mut p = OutputPlan::new();
        p.writes(d.join("a.jpg"), &["png", "exr"]);
        assert!(matches!(p.check(), Err(OutputError::Extension { .. })));
        let mut p = OutputPlan::new();
        p.writes(d.join("nowhere/a.png"), &["png"]);
        assert!(matches!(p.check(), Err(OutputError::NoFolder { .. })));
        assert_eq!(std::fs::read_to_string(&mesh).unwrap(), "v 0 0 0\n");
    }
}
