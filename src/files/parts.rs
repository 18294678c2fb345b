//! Results made of files beside each other (an impostor's sidecar and its maps): the index,
//! written last, records each part's size and checksum, and a loader refuses a part that does
//! not match — so a reader never takes one writer's index with another's maps, and a result torn
//! by a kill is refused by name instead of read wrong.
//!
//! Invariant: [`Part::of`] and [`Part::verify`] read in fixed-size blocks; nothing is held whole.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// One file of a result, as its index records it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// The file's name, relative to the index's folder.
    pub file: String,
    /// Its size in bytes.
    pub bytes: u64,
    /// Its FNV-1a 64 checksum, 16 hexadecimal digits.
    pub fnv1a: String,
}

/// A part that is not the file its index was written with.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PartError {
    /// The part cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The part.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The part's size or checksum is not the recorded one.
    #[error(
        "{path} is not the file its index was written with ({bytes} bytes, checksum {fnv1a}; \
         the index says {expected_bytes} bytes, {expected_fnv1a}): write the result again"
    )]
    Mismatch {
        /// The part.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// Its checksum.
        fnv1a: String,
        /// The recorded size.
        expected_bytes: u64,
        /// The recorded checksum.
        expected_fnv1a: String,
    },
}

impl Part {
    /// The record of the file `name` in `dir`.
    pub fn of(dir: &Path, name: &str) -> Result<Part, PartError> {
        let path = dir.join(name);
        let (bytes, sum) = checksum_file(&path).map_err(|source| PartError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(Part {
            file: name.to_string(),
            bytes,
            fnv1a: format!("{sum:016x}"),
        })
    }

    /// The record of `name` whose bytes are `bytes` (before they are written).
    pub fn of_bytes(name: &str, bytes: &[u8]) -> Part {
        Part {
            file: name.to_string(),
            bytes: bytes.len() as u64,
            fnv1a: format!("{:016x}", fnv1a(bytes.iter().copied(), FNV_OFFSET)),
        }
    }

    /// Refuses the file in `dir` unless it is the one recorded.
    pub fn verify(&self, dir: &Path) -> Result<(), PartError> {
        let found = Part::of(dir, &self.file)?;
        if found.bytes != self.bytes || found.fnv1a != self.fnv1a {
            return Err(PartError::Mismatch {
                path: dir.join(&self.file),
                bytes: found.bytes,
                fnv1a: found.fnv1a,
                expected_bytes: self.bytes,
                expected_fnv1a: self.fnv1a.clone(),
            });
        }
        Ok(())
    }
}

/// FNV-1a, 64 bits: a checksum that tells two files apart (not a defence against forgery).
pub(crate) fn fnv1a(bytes: impl IntoIterator<Item = u8>, mut hash: u64) -> u64 {
    for b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// FNV-1a's starting value.
pub(crate) const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// Size and FNV-1a 64 checksum of the file at `path`, read in blocks.
pub fn checksum_file(path: &Path) -> std::io::Result<(u64, u64)> {
    let mut f = std::fs::File::open(path)?;
    let (mut hash, mut size, mut block) = (FNV_OFFSET, 0u64, vec![0u8; 1 << 16]);
    loop {
        let n = f.read(&mut block)?;
        if n == 0 {
            return Ok((size, hash));
        }
        size += n as u64;
        hash = fnv1a(block[..n].iter().copied(), hash);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_changed_after_its_record_is_refused_by_name() {
        let d = crate::test_scratch::scratch("files_parts");
        std::fs::write(d.join("a.png"), b"first").unwrap();
        let part = Part::of(&d, "a.png").unwrap();
        assert_eq!(part, Part::of_bytes("a.png", b"first"));
        part.verify(&d).unwrap();
        std::fs::write(d.join("a.png"), b"other").unwrap();
        let err = part.verify(&d).unwrap_err().to_string();
        assert!(err.contains("a.png") && err.contains("5 bytes"), "{err}");
        std::fs::remove_file(d.join("a.png")).unwrap();
        assert!(matches!(part.verify(&d), Err(PartError::Io { .. })));
    }
}
