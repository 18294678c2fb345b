//! What a batch records: a manifest a shard, one entry an input — its SHA-256 and those of the
//! files it names (a glTF's buffers and textures, an OBJ's materials), the settings and the
//! trompe version that baked it, how long it took, and every output with its SHA-256 — and
//! the journal a shard appends to as each input is done, so a shard killed midway (a pre-empted
//! node) can be re-run and skip what is finished.
//!
//! Invariants: an entry reaches the journal only after every output it names is complete on disk
//! (outputs are written atomically), so an output half-written when a run was killed is never
//! taken for done; an entry is up to date only while its input and the files it names, its
//! settings and every output still hash as recorded; a line of the journal cut short by a kill
//! is ignored.

use super::{BakeSettings, BatchError, Shard};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// A file and its SHA-256.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct HashedFile {
    /// The file.
    pub path: PathBuf,
    /// Its SHA-256, hex.
    pub sha256: String,
}

/// One input's outcome.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    /// The mesh file, as given.
    pub input: PathBuf,
    /// Its SHA-256, hex (absent where it could not be read).
    #[serde(default)]
    pub input_sha256: Option<String>,
    /// The files its loading read beside it (a glTF's buffers and textures, an OBJ's material
    /// libraries and textures), each with its SHA-256.
    #[serde(default)]
    pub input_files: Vec<HashedFile>,
    /// The sidecar written (absent when the bake failed).
    pub output: Option<PathBuf>,
    /// Every file written, with its SHA-256.
    #[serde(default)]
    pub outputs: Vec<HashedFile>,
    /// Triangles baked.
    pub triangles: Option<usize>,
    /// Why the file was skipped.
    pub error: Option<String>,
    /// The settings it was baked with.
    #[serde(default)]
    pub settings: Option<BakeSettings>,
    /// The trompe version that baked it.
    #[serde(default)]
    pub trompe: Option<String>,
    /// Seconds the bake took (hashing included).
    #[serde(default)]
    pub seconds: f64,
}

impl Entry {
    /// The same entry without what differs from run to run (the time it took), for comparing
    /// runs.
    pub fn untimed(&self) -> Entry {
        Entry {
            seconds: 0.0,
            ..self.clone()
        }
    }
}

/// A shard's manifest (or several merged).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// The shards it covers (sorted).
    pub shards: Vec<Shard>,
    /// One entry per input, in input order.
    pub entries: Vec<Entry>,
}

/// The SHA-256 of the file at `path`, hex, read in blocks.
///
/// # Errors
/// When the file cannot be read.
pub fn sha256_of(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut block = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut block)?;
        if n == 0 {
            break;
        }
        hasher.update(&block[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

/// The manifest of `shard` in `out`.
pub fn manifest_path(out: &Path, shard: Shard) -> PathBuf {
    out.join(format!("manifest-{}-of-{}.json", shard.index, shard.count))
}

/// The journal of `shard` in `out`, which its entries reach one by one.
pub fn journal_path(out: &Path, shard: Shard) -> PathBuf {
    out.join(format!(
        "manifest-{}-of-{}.partial.jsonl",
        shard.index, shard.count
    ))
}

/// A shard's journal: each finished entry appended as one line of JSON and flushed to disk.
pub struct Journal {
    file: std::fs::File,
    path: PathBuf,
}

impl Journal {
    /// Appends to the journal at `path` (created if need be; entries already there are kept).
    ///
    /// # Errors
    /// When it cannot be opened.
    pub fn open(path: &Path) -> Result<Journal, BatchError> {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|source| BatchError::Write {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(Journal {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Appends `entry` as one line, written (to the operating system) before it returns.
    ///
    /// # Errors
    /// When it cannot be written.
    pub fn append(&mut self, entry: &Entry) -> Result<(), BatchError> {
        let mut line = serde_json::to_vec(entry).map_err(|e| BatchError::Write {
            path: self.path.clone(),
            source: std::io::Error::other(e),
        })?;
        line.push(b'\n');
        // A new line first: a line a kill cut short stays a line of its own, ignored. Not
        // synced to disk: a line a crash loses only means that input is baked again, and one
        // that outlives its outputs is caught by their hashes (`up_to_date`).
        let write = |f: &mut std::fs::File| -> std::io::Result<()> {
            f.write_all(b"\n")?;
            f.write_all(&line)
        };
        write(&mut self.file).map_err(|source| BatchError::Write {
            path: self.path.clone(),
            source,
        })
    }

    /// Writes the shard's `manifest` to `path` (atomically) and removes the journal.
    ///
    /// # Errors
    /// When the manifest cannot be written.
    pub fn finish(self, manifest: &Manifest, path: &Path) -> Result<(), BatchError> {
        let write = |source| BatchError::Write {
            path: path.to_path_buf(),
            source,
        };
        let text =
            serde_json::to_string_pretty(manifest).map_err(|e| write(std::io::Error::other(e)))?;
        crate::files::write_atomically(path, text.as_bytes()).map_err(write)?;
        drop(self.file);
        std::fs::remove_file(&self.path).map_err(|source| BatchError::Write {
            path: self.path,
            source,
        })
    }
}

/// The entries earlier runs recorded in `out` — every manifest and journal there, whichever
/// shard wrote it — by input; unreadable files and lines skipped.
pub fn earlier(out: &Path) -> HashMap<PathBuf, Vec<Entry>> {
    let mut found: HashMap<PathBuf, Vec<Entry>> = HashMap::new();
    let Ok(dir) = std::fs::read_dir(out) else {
        return found;
    };
    let mut names: Vec<PathBuf> = dir.flatten().map(|e| e.path()).collect();
    names.sort();
    for path in names {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !name.starts_with("manifest") {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        let entries: Vec<Entry> = if name.ends_with(".partial.jsonl") {
            text.lines()
                .filter_map(|l| serde_json::from_str(l).ok())
                .collect()
        } else if name.ends_with(".json") {
            serde_json::from_str::<Manifest>(&text)
                .map(|m| m.entries)
                .unwrap_or_default()
        } else {
            continue;
        };
        for e in entries {
            found.entry(e.input.clone()).or_default().push(e);
        }
    }
    found
}

/// Whether `entry` still stands for baking `input` (of SHA-256 `input_sha256`) with `settings`:
/// it baked, from the same bytes (the input's, and those of every file its loading read beside
/// it) with the same settings, and every output it names is on disk with the bytes it recorded.
pub fn up_to_date(entry: &Entry, input_sha256: &str, settings: &BakeSettings) -> bool {
    let unchanged = |files: &[HashedFile]| {
        files
            .iter()
            .all(|f| sha256_of(&f.path).is_ok_and(|h| h == f.sha256))
    };
    entry.error.is_none()
        && entry.input_sha256.as_deref() == Some(input_sha256)
        && entry.settings.as_ref() == Some(settings)
        && !entry.outputs.is_empty()
        && unchanged(&entry.input_files)
        && unchanged(&entry.outputs)
}
