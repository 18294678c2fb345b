//! What a batch bakes and where each result goes: meshes named one by one, folders walked for
//! the formats trompe reads, and lists of paths (one a line, as `--inputs-from` reads them);
//! each input's outputs in the output folder under the input's own folder, relative to the
//! folder walked (or, for meshes named or listed, to the deepest folder that holds them all), so
//! `a/tree.glb` and `b/tree.glb` both have a place.
//!
//! Invariants: the inputs come sorted by path, each once; no two inputs share an output (refused
//! before any work); an output folder never climbs out of the output folder (`..` is resolved
//! before the paths are compared).

use super::BatchError;
use std::path::{Component, Path, PathBuf};

/// The extensions of the mesh files a folder's walk takes (any case).
pub const MESH_EXTENSIONS: [&str; 4] = ["obj", "ply", "gltf", "glb"];

/// One input of a batch and the folder its outputs go to, relative to the output folder.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct BatchInput {
    /// The mesh file, as given or found.
    pub path: PathBuf,
    /// Where its outputs go, under the output folder.
    pub folder: PathBuf,
}

impl BatchInput {
    /// The sidecar this input bakes to in `out`: `out/<folder>/<stem>.json`.
    pub fn sidecar(&self, out: &Path) -> PathBuf {
        out.join(&self.folder)
            .join(format!("{}.json", stem(&self.path)))
    }
}

/// The inputs of a batch from `given` (each a mesh file, or a folder whose mesh files are walked
/// for, its subfolders mirrored) and `listed` (mesh files read from lists), sorted by path.
///
/// # Errors
/// A folder that cannot be read, or two inputs whose outputs would be the same files.
pub fn gather(given: &[PathBuf], listed: &[PathBuf]) -> Result<Vec<BatchInput>, BatchError> {
    let mut found = Vec::new();
    let mut loose: Vec<&PathBuf> = Vec::new();
    for p in given {
        if p.is_dir() {
            let mut files = Vec::new();
            walk(p, &mut files)?;
            for f in files {
                let folder = f
                    .parent()
                    .and_then(|d| d.strip_prefix(p).ok())
                    .map(Path::to_path_buf)
                    .unwrap_or_default();
                found.push(BatchInput { path: f, folder });
            }
        } else {
            loose.push(p);
        }
    }
    loose.extend(listed);
    // Meshes named or listed: their folders relative to the deepest one holding them all.
    let folders: Vec<PathBuf> = loose
        .iter()
        .map(|p| lexical(p.parent().unwrap_or(Path::new(""))))
        .collect();
    let common = folders
        .iter()
        .skip(1)
        .fold(folders.first().cloned(), |c, f| {
            c.map(|c| {
                c.components()
                    .zip(f.components())
                    .take_while(|(a, b)| a == b)
                    .map(|(a, _)| a)
                    .collect()
            })
        });
    for (p, f) in loose.into_iter().zip(&folders) {
        let folder = common
            .as_ref()
            .and_then(|c| f.strip_prefix(c).ok())
            .map(Path::to_path_buf)
            .unwrap_or_default();
        found.push(BatchInput {
            path: p.clone(),
            folder,
        });
    }
    found.sort();
    found.dedup_by(|a, b| a.path == b.path);
    let mut outputs: Vec<(PathBuf, &PathBuf)> = found
        .iter()
        .map(|i| (i.sidecar(Path::new("")), &i.path))
        .collect();
    outputs.sort();
    for w in outputs.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(BatchError::SameStem {
                first: w[0].1.clone(),
                second: w[1].1.clone(),
            });
        }
    }
    Ok(found)
}

/// Paths listed in `text`, one a line (as `--inputs-from` reads a file or standard input):
/// surrounding blanks trimmed, blank lines and lines starting with `#` skipped.
pub fn listed(text: &str) -> Vec<PathBuf> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(PathBuf::from)
        .collect()
}

/// The mesh files under `folder`, depth first in name order: hidden entries (a name starting
/// with `.`) skipped, and folders reached through a symbolic link not entered (no walk loops).
fn walk(folder: &Path, into: &mut Vec<PathBuf>) -> Result<(), BatchError> {
    let read = |e: std::io::Error| BatchError::Read {
        path: folder.to_path_buf(),
        source: e,
    };
    let mut entries: Vec<std::fs::DirEntry> = std::fs::read_dir(folder)
        .map_err(read)?
        .collect::<Result<_, _>>()
        .map_err(read)?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        if e.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        let path = e.path();
        let kind = e.file_type().map_err(read)?;
        if kind.is_dir() {
            walk(&path, into)?;
        } else if is_mesh(&path) && (kind.is_file() || path.is_file()) {
            into.push(path);
        }
    }
    Ok(())
}

/// Whether `path` has a mesh extension trompe reads.
pub fn is_mesh(path: &Path) -> bool {
    path.extension()
        .map(|x| x.to_string_lossy().to_ascii_lowercase())
        .is_some_and(|x| MESH_EXTENSIONS.contains(&x.as_str()))
}

/// `path` absolute, its `.` and `..` resolved by name (no file system access).
fn lexical(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

pub(super) fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_meshes_keep_their_folders_below_the_one_holding_them_all() {
        let given: Vec<PathBuf> = ["lib/a/tree.glb", "lib/b/tree.glb", "lib/rock.obj"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let inputs = gather(&given, &[]).unwrap();
        let out = Path::new("out");
        let sidecars: Vec<PathBuf> = inputs.iter().map(|i| i.sidecar(out)).collect();
        assert_eq!(
            sidecars,
            ["out/a/tree.json", "out/b/tree.json", "out/rock.json"]
                .iter()
                .map(PathBuf::from)
                .collect::<Vec<_>>()
        );
        // One folder: the outputs lie flat, as they always have.
        let flat = gather(
            &[PathBuf::from("x/duck.glb")],
            &[PathBuf::from("x/box.obj")],
        )
        .unwrap();
        assert!(flat.iter().all(|i| i.folder.as_os_str().is_empty()));
        // `..` never takes an output out of the output folder.
        let climbing = gather(
            &[PathBuf::from("a/../../b/c.obj"), PathBuf::from("d/e.obj")],
            &[],
        )
        .unwrap();
        for i in &climbing {
            assert!(
                !i.folder.components().any(|c| c == Component::ParentDir),
                "{i:?}"
            );
        }
        // Two inputs with one output are refused.
        let clash = gather(
            &[PathBuf::from("a/tree.glb"), PathBuf::from("a/tree.obj")],
            &[],
        );
        assert!(matches!(clash, Err(BatchError::SameStem { .. })));
        assert_eq!(
            listed("# assets\n a.glb \n\nb/c.obj\r\n"),
            vec![PathBuf::from("a.glb"), PathBuf::from("b/c.obj")]
        );
    }
}
