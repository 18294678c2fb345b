//! Batch baking of an asset library: many meshes, each baked to `OUT/<stem>.json` (and its maps),
//! a failing file reported by name and skipped; `K/N` shards that split the sorted inputs by
//! index, so any job runner (Slurm array jobs, Kubernetes indexed Jobs, GNU parallel) gets the
//! same files on every machine; a JSON manifest per shard, and their merge.
//!
//! Invariants: the shard of an input depends only on the sorted list of inputs; two inputs with
//! one stem are refused before any work (their outputs would collide); a manifest holds no
//! timings, so the same inputs give byte-identical manifests.

use super::bake::{BakeSettings, bake};
use super::file::{files, save};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Which part of the inputs one machine bakes: shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// 1 ..= count.
    pub index: u32,
    /// Shards in all.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("{s:?}: expected K/N, e.g. 2/8"))?;
        let (k, n): (u32, u32) = (
            k.trim()
                .parse()
                .map_err(|_| format!("{s:?}: K is not a number"))?,
            n.trim()
                .parse()
                .map_err(|_| format!("{s:?}: N is not a number"))?,
        );
        if n == 0 || k == 0 || k > n {
            return Err(format!("{s:?}: need 1 ≤ K ≤ N"));
        }
        Ok(Shard { index: k, count: n })
    }
}

/// One input's outcome.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    /// The mesh file, as given.
    pub input: PathBuf,
    /// The sidecar written (absent when the bake failed).
    pub output: Option<PathBuf>,
    /// Triangles baked.
    pub triangles: Option<usize>,
    /// Why the file was skipped.
    pub error: Option<String>,
}

/// A shard's manifest (or several merged).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// The shards it covers (sorted).
    pub shards: Vec<Shard>,
    /// One entry per input, in input order.
    pub entries: Vec<Entry>,
}

/// Why a batch could not start, or manifests could not merge.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BatchError {
    /// Two inputs would write the same outputs.
    #[error("{first} and {second} have the same name: their impostors would overwrite each other")]
    SameStem {
        /// One input.
        first: PathBuf,
        /// The other.
        second: PathBuf,
    },
    /// Manifests of different shard counts, or a shard twice, or one missing.
    #[error("manifests do not form one whole batch: {0}")]
    Shards(String),
}

/// The inputs of `shard`: every `count`-th of the sorted inputs, starting at `index − 1`.
/// Refuses inputs whose stems collide.
pub fn shard_inputs(inputs: &[PathBuf], shard: Shard) -> Result<Vec<PathBuf>, BatchError> {
    let mut sorted = inputs.to_vec();
    sorted.sort();
    sorted.dedup();
    let mut stems: Vec<(String, &PathBuf)> = sorted.iter().map(|p| (stem(p), p)).collect();
    stems.sort();
    for w in stems.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(BatchError::SameStem {
                first: w[0].1.clone(),
                second: w[1].1.clone(),
            });
        }
    }
    Ok(sorted
        .into_iter()
        .enumerate()
        .filter(|(i, _)| *i as u32 % shard.count == shard.index - 1)
        .map(|(_, p)| p)
        .collect())
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The sidecar `input` bakes to in `out`.
pub fn output_for(input: &Path, out: &Path) -> PathBuf {
    out.join(format!("{}.json", stem(input)))
}

/// Bakes each of `inputs` into `out` (`<stem>.json` and its maps, and `<stem>.glb` with
/// `glb`); `done(input, entry, seconds)` is called after each. A file that fails is recorded
/// with its error and skipped.
pub fn bake_all(
    inputs: &[PathBuf],
    out: &Path,
    settings: BakeSettings,
    glb: bool,
    shard: Shard,
    done: &mut dyn FnMut(&Entry, f64),
) -> Manifest {
    let mut entries = Vec::new();
    for input in inputs {
        let start = std::time::Instant::now();
        let sidecar = output_for(input, out);
        let result = (|| -> Result<usize, String> {
            let loaded = crate::geom::io::load(input).map_err(|e| e.to_string())?;
            let surface = crate::scene::Surface::Diffuse(None);
            let atlas = bake(&loaded.mesh, &surface, settings).map_err(|e| e.to_string())?;
            save(&atlas, &sidecar).map_err(|e| e.to_string())?;
            if glb {
                super::gltf::export(&sidecar, &sidecar.with_extension("glb"))
                    .map_err(|e| e.to_string())?;
            }
            Ok(loaded.mesh.triangle_count())
        })();
        let entry = match result {
            Ok(triangles) => Entry {
                input: input.clone(),
                output: Some(sidecar),
                triangles: Some(triangles),
                error: None,
            },
            Err(error) => Entry {
                input: input.clone(),
                output: None,
                triangles: None,
                error: Some(error),
            },
        };
        done(&entry, start.elapsed().as_secs_f64());
        entries.push(entry);
    }
    Manifest {
        shards: vec![shard],
        entries,
    }
}

/// Every file a batch of `inputs` into `out` may write (for the refusal to overwrite inputs).
pub fn outputs(inputs: &[PathBuf], out: &Path, glb: bool) -> Vec<PathBuf> {
    inputs
        .iter()
        .flat_map(|i| {
            let json = output_for(i, out);
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
        let inputs: Vec<PathBuf> = ["c.glb", "a.obj", "e.ply", "b.glb", "d.gltf"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let mut all = Vec::new();
        let mut manifests = Vec::new();
        for k in 1..=3 {
            let shard = Shard { index: k, count: 3 };
            let mine = shard_inputs(&inputs, shard).unwrap();
            all.extend(mine.clone());
            manifests.push(Manifest {
                shards: vec![shard],
                entries: mine
                    .iter()
                    .map(|i| Entry {
                        input: i.clone(),
                        output: None,
                        triangles: None,
                        error: Some("x".into()),
                    })
                    .collect(),
            });
        }
        all.sort();
        let mut want = inputs.clone();
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
        let clash = vec![PathBuf::from("x/duck.glb"), PathBuf::from("y/duck.obj")];
        assert!(matches!(
            shard_inputs(&clash, Shard { index: 1, count: 1 }),
            Err(BatchError::SameStem { .. })
        ));
    }
}
