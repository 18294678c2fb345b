//! The JSON sidecars trompe writes beside its maps, told apart by their `format` field: a
//! depth-image impostor ([`crate::impostor::file`]) or an octahedral atlas
//! ([`crate::octahedral::file`]). Commands that take "an impostor's sidecar" ask here which one
//! they were given, then call that kind's loader.

use std::path::{Path, PathBuf};
use thiserror::Error;

/// What a sidecar describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SidecarKind {
    /// A depth-image impostor through any camera: `"trompe-impostor"`.
    Impostor,
    /// An octahedral atlas for engines: `"trompe-octahedral-impostor"`.
    Octahedral,
}

/// Why a file is not a sidecar trompe reads.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SidecarError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not JSON with a `format` string.
    #[error("{path}: not an impostor's sidecar (a NAME.json trompe wrote): {reason}")]
    NotASidecar {
        /// The file.
        path: PathBuf,
        /// What the JSON parser said.
        reason: String,
    },
    /// A `format` trompe does not know.
    #[error(
        "{path}: format {format:?} is not one trompe reads (expected {:?} or {:?})",
        crate::impostor::file::FORMAT,
        crate::octahedral::file::FORMAT
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its `format`.
        format: String,
    },
}

impl SidecarKind {
    /// The kind of sidecar `path` is, from its `format` field.
    pub fn of(path: &Path) -> Result<SidecarKind, SidecarError> {
        #[derive(serde::Deserialize)]
        struct Format {
            format: String,
        }
        let text = std::fs::read_to_string(path).map_err(|source| SidecarError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let format = serde_json::from_str::<Format>(&text)
            .map_err(|e| SidecarError::NotASidecar {
                path: path.to_path_buf(),
                reason: e.to_string(),
            })?
            .format;
        if format == crate::impostor::file::FORMAT {
            Ok(SidecarKind::Impostor)
        } else if format == crate::octahedral::file::FORMAT {
            Ok(SidecarKind::Octahedral)
        } else {
            Err(SidecarError::UnknownFormat {
                path: path.to_path_buf(),
                format,
            })
        }
    }
}
