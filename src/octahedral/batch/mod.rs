//! Batch baking of an asset library: many meshes — named, found in folders, or listed — each
//! baked to `OUT/<its folder>/<stem>.json` (and its maps), a failing file reported by name and
//! skipped; `K/N` shards that split the sorted inputs by index, so any job runner (Slurm array
//! jobs, Kubernetes Indexed Jobs, GNU parallel) gets the same files on every machine; a manifest
//! per shard, auditable (every input and output by its SHA-256, the settings, the version) and
//! resumable (a journal a shard appends to, and `skip_existing`), and their merge.
//!
//! Invariants: the shard of an input depends only on the sorted list of inputs; two inputs with
//! one output are refused before any work; an input is skipped as done only when its input, its
//! settings and its outputs still hash as an earlier run recorded.

mod inputs;
mod record;
mod shard;

pub use inputs::{BatchInput, MESH_EXTENSIONS, gather, is_mesh, listed};
pub use record::{
    Entry, HashedFile, Journal, Manifest, earlier, journal_path, manifest_path, sha256_of,
    up_to_date,
};
pub use shard::Shard;

use super::bake::{BakeSettings, bake};
use super::file::{FloatMaps, files, save};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a batch could not start or record, or manifests could not merge.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BatchError {
    /// Two inputs would write the same outputs.
    #[error(
        "{first} and {second} would write the same outputs (same name in the same folder): their impostors would overwrite each other"
    )]
    SameStem {
        /// One input.
        first: PathBuf,
        /// The other.
        second: PathBuf,
    },
    /// Manifests of different shard counts, or a shard twice, or one missing.
    #[error("manifests do not form one whole batch: {0}")]
    Shards(String),
    /// A folder of inputs could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The journal or a manifest could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// `--shard auto` found no scheduler's shard, or a malformed one.
    #[error("{reason}")]
    Scheduler {
        /// Why.
        reason: String,
    },
}

/// The inputs of `shard`: every `count`-th of the sorted inputs, starting at `index − 1`.
pub fn shard_inputs(inputs: &[BatchInput], shard: Shard) -> Vec<BatchInput> {
    inputs
        .iter()
        .enumerate()
        .filter(|(i, _)| shard.holds(*i))
        .map(|(_, p)| p.clone())
        .collect()
}

/// How a batch bakes: the settings, whether a `.glb` goes beside each sidecar, and whether an
/// input an earlier run baked (its entry up to date, [`up_to_date`]) is skipped.
#[derive(Clone, Copy, Debug)]
pub struct BatchSettings {
    /// The bake.
    pub bake: BakeSettings,
    /// Also write `<stem>.glb`, its textures so encoded.
    pub glb: Option<super::gltf::TextureFormat>,
    /// Also write the normal and depth maps as OpenEXR floats.
    pub floats: FloatMaps,
    /// Skip what an earlier run in the output folder finished.
    pub skip_existing: bool,
}

/// What happened to one input, as [`bake_all`] reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Baked now.
    Baked,
    /// An earlier run's entry was up to date.
    UpToDate,
    /// It could not be baked (the entry says why).
    Failed,
}

/// Bakes `shard` of `inputs` into `out` (`<folder>/<stem>.json` and its maps, and `<stem>.glb`
/// with `glb`), appending each entry to the shard's journal as it is done, then writing the
/// shard's manifest and removing the journal; `done(entry, outcome)` is called after each. A
/// file that fails is recorded with its error and skipped.
///
/// # Errors
/// When the journal or the manifest cannot be written (a failing input is not an error).
pub fn bake_all(
    inputs: &[BatchInput],
    out: &Path,
    settings: BatchSettings,
    shard: Shard,
    done: &mut dyn FnMut(&Entry, Outcome),
) -> Result<Manifest, BatchError> {
    let earlier: HashMap<PathBuf, Vec<Entry>> = match settings.skip_existing {
        true => earlier(out),
        false => HashMap::new(),
    };
    let mut journal = Journal::open(&journal_path(out, shard))?;
    let mut entries = Vec::new();
    for input in inputs {
        let start = std::time::Instant::now();
        let input_sha256 = sha256_of(&input.path).ok();
        // An earlier entry stands for this run only if it wrote where this run writes, every
        // file this run writes (the .glb too, with `glb`), and is up to date.
        let sidecar = input.sidecar(out);
        let glb = sidecar.with_extension("glb");
        let here = |e: &Entry| {
            let wrote = |path: &PathBuf| e.outputs.iter().any(|o| &o.path == path);
            e.output.as_ref() == Some(&sidecar)
                && (settings.glb.is_none() || wrote(&glb))
                && (settings.floats == FloatMaps::Omitted || wrote(&files(&sidecar)[4]))
        };
        let kept = input_sha256.as_deref().and_then(|h| {
            earlier.get(&input.path).and_then(|es| {
                es.iter()
                    .find(|e| here(e) && up_to_date(e, h, &settings.bake))
            })
        });
        let (entry, outcome) = match kept {
            Some(e) => (e.clone(), Outcome::UpToDate),
            None => {
                let entry = bake_one(input, out, settings, input_sha256);
                let outcome = match entry.error {
                    None => Outcome::Baked,
                    Some(_) => Outcome::Failed,
                };
                let entry = Entry {
                    seconds: start.elapsed().as_secs_f64(),
                    ..entry
                };
                (entry, outcome)
            }
        };
        journal.append(&entry)?;
        done(&entry, outcome);
        entries.push(entry);
    }
    let manifest = Manifest {
        shards: vec![shard],
        entries,
    };
    journal.finish(&manifest, &manifest_path(out, shard))?;
    Ok(manifest)
}

/// Bakes one input and hashes what it wrote.
fn bake_one(
    input: &BatchInput,
    out: &Path,
    settings: BatchSettings,
    input_sha256: Option<String>,
) -> Entry {
    let sidecar = input.sidecar(out);
    let hashed = |path: PathBuf| -> Result<HashedFile, String> {
        let sha256 = sha256_of(&path).map_err(|e| format!("hashing {}: {e}", path.display()))?;
        Ok(HashedFile { path, sha256 })
    };
    let mut input_files = Vec::new();
    let result = (|| -> Result<(usize, Vec<HashedFile>), String> {
        let loaded = crate::geom::io::load(&input.path).map_err(|e| e.to_string())?;
        // What the mesh names beside it (its first file is the input itself).
        input_files = loaded
            .files
            .iter()
            .skip(1)
            .filter(|p| p.is_file())
            .map(|p| hashed(p.clone()))
            .collect::<Result<_, String>>()?;
        let surface = crate::scene::Surface::Diffuse(None);
        let atlas = bake(&loaded.mesh, &surface, settings.bake).map_err(|e| e.to_string())?;
        if let Some(folder) = sidecar.parent() {
            std::fs::create_dir_all(folder)
                .map_err(|e| format!("creating {}: {e}", folder.display()))?;
        }
        let saved = save(&atlas, &sidecar, settings.floats).map_err(|e| e.to_string())?;
        let mut written = super::file::written(&sidecar, &saved);
        if let Some(format) = settings.glb {
            let glb = sidecar.with_extension("glb");
            super::gltf::save(&atlas, &glb, format).map_err(|e| e.to_string())?;
            written.push(glb);
        }
        let outputs = written
            .into_iter()
            .map(hashed)
            .collect::<Result<_, String>>()?;
        Ok((loaded.mesh.triangle_count(), outputs))
    })();
    let (output, outputs, triangles, error) = match result {
        Ok((triangles, outputs)) => (Some(sidecar), outputs, Some(triangles), None),
        Err(error) => (None, Vec::new(), None, Some(error)),
    };
    Entry {
        input: input.path.clone(),
        input_sha256,
        input_files,
        output,
        outputs,
        triangles,
        error,
        settings: Some(settings.bake),
        trompe: Some(env!("CARGO_PKG_VERSION").to_string()),
        seconds: 0.0,
    }
}

/// Every file a batch of `inputs` into `out` may write (for the refusal to overwrite inputs).
pub fn outputs(inputs: &[BatchInput], out: &Path, glb: bool) -> Vec<PathBuf> {
    inputs
        .iter()
        .flat_map(|i| {
            let json = i.sidecar(out);
            let mut all: Vec<PathBuf> = files(&json).to_vec();
            if glb {
                all.push(json.with_extension("glb"));
            }
            all
        })
        .collect()
}

/// Joins shard manifests into one: every shard of one count, each once.
pub fn merge(manifests: &[Manifest]) -> Result<Manifest, BatchError> {
    let mut shards: Vec<Shard> = manifests.iter().flat_map(|m| m.shards.clone()).collect();
    shards.sort_by_key(|s| (s.count, s.index));
    let Some(count) = shards.first().map(|s| s.count) else {
        return Err(BatchError::Shards("no manifest".into()));
    };
    if shards.iter().any(|s| s.count != count) {
        return Err(BatchError::Shards("shard counts differ".into()));
    }
    let indices: Vec<u32> = shards.iter().map(|s| s.index).collect();
    if indices != (1..=count).collect::<Vec<_>>() {
        return Err(BatchError::Shards(format!(
            "have shards {indices:?} of {count}"
        )));
    }
    let mut entries: Vec<Entry> = manifests.iter().flat_map(|m| m.entries.clone()).collect();
    entries.sort_by(|a, b| a.input.cmp(&b.input));
    Ok(Manifest { shards, entries })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_sorted_inputs_and_merge_back() {
        let given: Vec<PathBuf> = ["c.glb", "a.obj", "e.ply", "b.glb", "d.gltf"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let inputs = gather(&given, &[]).unwrap();
        let mut all = Vec::new();
        let mut manifests = Vec::new();
        for k in 1..=3 {
            let shard = Shard { index: k, count: 3 };
            let mine = shard_inputs(&inputs, shard);
            all.extend(mine.iter().map(|i| i.path.clone()));
            manifests.push(Manifest {
                shards: vec![shard],
                entries: mine
                    .iter()
                    .map(|i| Entry {
                        input: i.path.clone(),
                        input_sha256: None,
                        input_files: Vec::new(),
                        output: None,
                        outputs: Vec::new(),
                        triangles: None,
                        error: Some("x".into()),
                        settings: None,
                        trompe: None,
                        seconds: 0.0,
                    })
                    .collect(),
            });
        }
        all.sort();
        let mut want = given.clone();
        want.sort();
        assert_eq!(all, want);
        let merged = merge(&manifests).unwrap();
        assert_eq!(merged.entries.len(), 5);
        assert!(merge(&manifests[..2]).is_err());
        assert!("0/3".parse::<Shard>().is_err() && "4/3".parse::<Shard>().is_err());
        assert_eq!(
            "2/8".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 8 }
        );
        let clash = vec![PathBuf::from("x/duck.glb"), PathBuf::from("x/duck.obj")];
        assert!(matches!(
            gather(&clash, &[]),
            Err(BatchError::SameStem { .. })
        ));
    }
}
