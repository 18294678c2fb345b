//! What an impostor is built of, and through which camera: a mesh in its own coordinates, seen
//! through a pinhole, orthographic or SPOC camera placed around it (paper 1 §3), or a maze floor
//! plan, seen through the graph camera of its corridors (paper 1 §5). One place pairs an input
//! with its camera, so every command refuses a mismatched pair with the same words.

use super::ViewCamera;
use crate::geom::Mesh;
use crate::geom::MeshError;
use crate::geom::io::load;
use crate::scene::maze::{Maze, MazeError};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The camera an impostor is built through, as a user names it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraChoice {
    /// A camera placed around a mesh ([`super::ImpostorCamera::fitted`]).
    Placed(ViewCamera),
    /// The graph camera of a maze's corridors ([`Maze::graph_camera`]).
    Graph,
}

/// A loaded input: a mesh, or a maze and its geometry.
pub enum Subject {
    /// A mesh file (.obj, .ply, .gltf, .glb) in its own coordinates.
    Mesh {
        /// Where it was read from.
        path: PathBuf,
        /// The mesh.
        mesh: Mesh,
        /// Every file read: the mesh file and what it names (materials, textures, buffers).
        files: Vec<PathBuf>,
    },
    /// A maze floor plan (.maze).
    Maze {
        /// Where it was read from.
        path: PathBuf,
        /// The plan.
        maze: Maze,
        /// Its walls and floor.
        mesh: Mesh,
    },
}

/// Why an input or its camera was refused.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SubjectError {
    /// The mesh file could not be read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The floor plan could not be read, or its graph camera built.
    #[error(transparent)]
    Maze(#[from] MazeError),
    /// A graph camera was asked for a mesh.
    #[error("{path}: --camera graph is built from a maze floor plan (.maze)")]
    GraphNeedsMaze {
        /// The mesh file.
        path: PathBuf,
    },
    /// A placed camera was asked for a maze.
    #[error("{path}: a maze floor plan needs --camera graph")]
    MazeNeedsGraph {
        /// The floor plan.
        path: PathBuf,
    },
}

/// Whether `path` names a maze floor plan (its extension is `.maze`, any case).
pub fn is_maze(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("maze"))
}

impl Subject {
    /// Reads `path`: a floor plan when it ends in `.maze`, a mesh otherwise. Returns the
    /// loader's warnings (problems it survived) beside it.
    pub fn load(path: &Path) -> Result<(Subject, Vec<String>), SubjectError> {
        if is_maze(path) {
            let maze = Maze::load(path)?;
            let mesh = maze.mesh();
            let path = path.to_path_buf();
            return Ok((Subject::Maze { path, maze, mesh }, Vec::new()));
        }
        let loaded = load(path)?;
        let warnings = loaded.warnings.iter().map(ToString::to_string).collect();
        let subject = Subject::Mesh {
            path: path.to_path_buf(),
            mesh: loaded.mesh,
            files: loaded.files,
        };
        Ok((subject, warnings))
    }

    /// The file it was read from.
    pub fn path(&self) -> &Path {
        match self {
            Subject::Mesh { path, .. } | Subject::Maze { path, .. } => path,
        }
    }

    /// Every file it was read from: a mesh's and what it names, or the floor plan.
    pub fn files(&self) -> Vec<PathBuf> {
        match self {
            Subject::Mesh { files, .. } => files.clone(),
            Subject::Maze { path, .. } => vec![path.clone()],
        }
    }

    /// Its geometry (a maze's walls and floor).
    pub fn mesh(&self) -> &Mesh {
        match self {
            Subject::Mesh { mesh, .. } | Subject::Maze { mesh, .. } => mesh,
        }
    }

    /// Pairs this input with a camera, refusing one that does not go with it: a graph camera
    /// needs a maze, a maze needs a graph camera.
    pub fn pair(&self, choice: CameraChoice) -> Result<Paired<'_>, SubjectError> {
        match (self, choice) {
            (Subject::Mesh { mesh, .. }, CameraChoice::Placed(kind)) => {
                Ok(Paired::Placed { mesh, kind })
            }
            (Subject::Maze { path, maze, .. }, CameraChoice::Graph) => {
                Ok(Paired::Graph { path, maze })
            }
            (Subject::Mesh { path, .. }, CameraChoice::Graph) => {
                Err(SubjectError::GraphNeedsMaze { path: path.clone() })
            }
            (Subject::Maze { path, .. }, CameraChoice::Placed(_)) => {
                Err(SubjectError::MazeNeedsGraph { path: path.clone() })
            }
        }
    }
}

/// An input paired with a camera that goes with it ([`Subject::pair`]).
pub enum Paired<'a> {
    /// A mesh and the kind of camera to place around it.
    Placed {
        /// The mesh.
        mesh: &'a Mesh,
        /// The camera.
        kind: ViewCamera,
    },
    /// A maze, seen through its graph camera.
    Graph {
        /// Its floor plan's file.
        path: &'a Path,
        /// The plan.
        maze: &'a Maze,
    },
}
