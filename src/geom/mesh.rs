//! Indexed triangle meshes with per-face materials, and their validation.

use super::Aabb;
use crate::frame::{FrameError, Image, Rgba};
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use thiserror::Error;

/// A texture: linear RGBA, shared between the meshes that use it.
pub type Texture = Arc<Image<Rgba>>;

/// A surface's appearance as a mesh file describes it.
#[derive(Clone, Debug)]
pub struct Material {
    /// Name in the source file (`usemtl`, glTF material name) or `"default"`.
    pub name: String,
    /// Linear diffuse / base colour; multiplies the texture when there is one.
    pub base_color: Vec3,
    /// Base-colour texture, sampled at the mesh UVs.
    pub texture: Option<Texture>,
    /// Metalness, 0 (dielectric) to 1 (metal); multiplies the blue channel of
    /// `metallic_roughness` (glTF's `metallicFactor`).
    pub metallic: f32,
    /// Perceptual roughness, 0 (smooth) to 1; multiplies its green channel (glTF's
    /// `roughnessFactor`).
    pub roughness: f32,
    /// glTF's metallic-roughness texture, linear (green roughness, blue metalness).
    pub metallic_roughness: Option<Texture>,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec3::splat(0.8),
            texture: None,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness: None,
        }
    }
}

/// An indexed triangle mesh. See the module invariants in [`crate::geom`].
///
/// Texture coordinates follow the image convention: `(0, 0)` is the top-left texel (loaders flip
/// OBJ's bottom-up `v`).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals (one per position).
    pub normals: Vec<Vec3>,
    /// Texture coordinates (one per position), if the file had any.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as vertex-index triples, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle, into `materials`.
    pub face_material: Vec<u32>,
    /// Materials (at least one).
    pub materials: Vec<Material>,
}

/// Vertex and triangle counts as the file stores them (before welding or dropping).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SourceCounts {
    /// Vertices declared (OBJ `v` lines, PLY vertex elements, glTF accessor counts per instance).
    pub vertices: usize,
    /// Triangles after fan triangulation, degenerate ones included.
    pub triangles: usize,
}

/// A problem a loader survived; it is reported, not fatal.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Warning {
    /// Triangles with zero area or a repeated vertex were dropped.
    DegenerateTriangles {
        /// The file.
        path: PathBuf,
        /// How many.
        count: usize,
    },
    /// Something the loader does not use was skipped.
    Skipped {
        /// The file.
        path: PathBuf,
        /// What was skipped and why.
        what: String,
    },
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Warning::DegenerateTriangles { path, count } => {
                write!(
                    f,
                    "{}: dropped {count} degenerate triangle(s)",
                    path.display()
                )
            }
            Warning::Skipped { path, what } => write!(f, "{}: skipped {what}", path.display()),
        }
    }
}

/// Errors from loading or validating a mesh: each names the file, the element and the reason.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not well formed.
    #[error("{path}: {element}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where: `line 12`, `vertex 7`, `accessor 3` …
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// A face refers to a vertex (or an OBJ texture coordinate or normal) that does not exist.
    #[error("{path}: {element}: {kind} index {index} out of range (there are {count})")]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// Which face.
        element: String,
        /// What the index counts: `vertex`, `texture coordinate` or `normal`.
        kind: &'static str,
        /// The index as written.
        index: i64,
        /// How many vertices there are.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{path}: {element}: coordinate is not finite")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Which vertex.
        element: String,
    },
    /// A coordinate is finite but beyond [`super::MAX_COORDINATE`].
    #[error(
        "{path}: {element}: coordinate {value:e} is beyond ±{:e}, where trompe's arithmetic \
         overflows f32",
        super::MAX_COORDINATE
    )]
    OutOfRange {
        /// The file.
        path: PathBuf,
        /// Which vertex.
        element: String,
        /// The coordinate.
        value: f32,
    },
    /// A texture the file names could not be loaded.
    #[error("{path}: texture {texture}: {source}")]
    Texture {
        /// The mesh file.
        path: PathBuf,
        /// The texture as named in the file.
        texture: String,
        /// The cause.
        source: FrameError,
    },
    /// What the file asks for would need more memory than the budget allows.
    #[error("{path}: {source}")]
    Memory {
        /// The file.
        path: PathBuf,
        /// What, and how much.
        source: crate::memory::OverBudget,
    },
    /// The file holds no triangle.
    #[error("{path}: no triangles")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The file's format is not one trompe reads.
    #[error("{path}: unsupported format: {reason}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

impl Mesh {
    /// Starts loading triangle `t`'s vertex indices and material index into the cache (a hint:
    /// nothing changes; see [`crate::prefetch`]). Call it a while before
    /// [`Mesh::prefetch_corners`] of the same triangle, which reads the indices.
    #[inline]
    pub(crate) fn prefetch_triangle(&self, t: u32) {
        crate::prefetch::prefetch(&self.triangles, t as usize);
        crate::prefetch::prefetch(&self.face_material, t as usize);
    }

    /// Starts loading the position, normal and texture coordinates of triangle `t`'s corners
    /// into the cache (a hint: nothing changes).
    #[inline]
    pub(crate) fn prefetch_corners(&self, t: u32) {
        let Some(corners) = self.triangles.get(t as usize) else {
            return;
        };
        for &i in corners {
            crate::prefetch::prefetch(&self.positions, i as usize);
            crate::prefetch::prefetch(&self.normals, i as usize);
            if let Some(uvs) = &self.uvs {
                crate::prefetch::prefetch(uvs, i as usize);
            }
        }
    }

    /// Builds a mesh from raw arrays, validating it (module invariants): indices in range, finite
    /// coordinates; degenerate triangles are dropped and counted in a warning; missing normals are
    /// computed (area-weighted, welded by position).
    #[allow(clippy::too_many_arguments)]
    pub fn from_parts(
        path: &std::path::Path,
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        triangles: Vec<[u32; 3]>,
        face_material: Vec<u32>,
        mut materials: Vec<Material>,
        warnings: &mut Vec<Warning>,
    ) -> Result<Mesh, MeshError> {
        let path_buf = path.to_path_buf();
        for (i, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(MeshError::NonFinite {
                    path: path_buf,
                    element: format!("vertex {i}"),
                });
            }
            let largest = p.abs().max_element();
            if largest > super::MAX_COORDINATE {
                return Err(MeshError::OutOfRange {
                    path: path_buf,
                    element: format!("vertex {i}"),
                    value: largest,
                });
            }
        }
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let n = positions.len();
        let mut kept = Vec::with_capacity(triangles.len());
        let mut kept_mat = Vec::with_capacity(triangles.len());
        let mut degenerate = 0;
        for (f, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        path: path_buf,
                        element: format!("triangle {f}"),
                        kind: "vertex",
                        index: i as i64,
                        count: n,
                    });
                }
            }
            let [a, b, c] = tri.map(|i| positions[i as usize]);
            if (b - a).cross(c - a).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            kept.push(*tri);
            let m = face_material.get(f).copied().unwrap_or(0);
            kept_mat.push(if (m as usize) < materials.len() { m } else { 0 });
        }
        if degenerate > 0 {
            warnings.push(Warning::DegenerateTriangles {
                path: path_buf.clone(),
                count: degenerate,
            });
        }
        if kept.is_empty() {
            return Err(MeshError::Empty { path: path_buf });
        }
        let mut mesh = Mesh {
            positions,
            normals: Vec::new(),
            uvs: uvs.filter(|u| u.len() == n),
            triangles: kept,
            face_material: kept_mat,
            materials,
        };
        match normals {
            Some(ns) if ns.len() == n && ns.iter().all(|v| v.is_finite()) => {
                mesh.normals = ns;
                mesh.repair_normals();
            }
            _ => mesh.compute_normals(),
        }
        Ok(mesh)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Bounding box of the positions.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }

    /// Unit geometric normal of triangle `t` (counter-clockwise front).
    pub fn face_normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.corners(t);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Area-weighted vertex normals, accumulated over vertices that share a position, so seams
    /// duplicated in the file (the teapot's) do not show. A vertex whose sum cancels (opposite
    /// duplicate faces, as in the dragon) falls back to the normal of one of its faces.
    pub fn compute_normals(&mut self) {
        let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        let rep: Vec<u32> = self
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                *weld
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert(i as u32)
            })
            .collect();
        let mut sum = vec![Vec3::ZERO; self.positions.len()];
        let mut any_face = vec![Vec3::ZERO; self.positions.len()];
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            let area_n = (b - a).cross(c - a); // |·| = 2 × area
            for &i in &self.triangles[t] {
                let r = rep[i as usize] as usize;
                sum[r] += area_n;
                any_face[r] = area_n;
            }
        }
        self.normals = rep
            .iter()
            .map(|&r| {
                let r = r as usize;
                sum[r]
                    .try_normalize()
                    .or_else(|| any_face[r].try_normalize())
                    .unwrap_or(Vec3::Y)
            })
            .collect();
    }

    /// Normalizes file normals; zero ones fall back to computed normals.
    fn repair_normals(&mut self) {
        if self.normals.iter().all(|n| n.try_normalize().is_some()) {
            for n in &mut self.normals {
                *n = n.normalize();
            }
            return;
        }
        let file = std::mem::take(&mut self.normals);
        self.compute_normals();
        for (n, f) in self.normals.iter_mut().zip(file) {
            if let Some(f) = f.try_normalize() {
                *n = f;
            }
        }
    }

    /// This mesh moved by `m` (normals by its inverse transpose).
    /// The largest coordinate magnitude of its vertices (NaN if one is not a number; 0 for no
    /// vertex): what [`super::MAX_COORDINATE`] bounds.
    pub fn largest_coordinate(&self) -> f32 {
        // (`f32::max` and glam's `max_element` drop NaNs: they are looked for first.)
        self.positions
            .iter()
            .map(|p| {
                if p.is_nan() {
                    f32::NAN
                } else {
                    p.abs().max_element()
                }
            })
            .fold(0.0f32, |a, b| {
                if a.is_nan() || b.is_nan() {
                    f32::NAN
                } else {
                    a.max(b)
                }
            })
    }

    /// This mesh with every vertex and normal transformed by `m`.
    pub fn transformed(&self, m: &Mat4) -> Mesh {
        let normal_m = Mat3::from_mat4(*m).inverse().transpose();
        let flip = Mat3::from_mat4(*m).determinant() < 0.0;
        Mesh {
            positions: self
                .positions
                .iter()
                .map(|&p| m.transform_point3(p))
                .collect(),
            normals: self
                .normals
                .iter()
                .map(|&n| (normal_m * n).normalize_or(n))
                .collect(),
            uvs: self.uvs.clone(),
            triangles: if flip {
                self.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
            } else {
                self.triangles.clone()
            },
            face_material: self.face_material.clone(),
            materials: self.materials.clone(),
        }
    }

    /// Every triangle split into four at its edge midpoints (shared edges share their
    /// midpoint): positions stay on the faces, normals and texture coordinates are interpolated.
    pub fn subdivided(&self) -> Mesh {
        let mut out = self.clone();
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, out: &mut Mesh| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (i, j) = (a as usize, b as usize);
                out.positions
                    .push((self.positions[i] + self.positions[j]) * 0.5);
                out.normals.push(
                    (self.normals[i] + self.normals[j])
                        .try_normalize()
                        .unwrap_or(self.normals[i]),
                );
                if let (Some(uv), Some(src)) = (out.uvs.as_mut(), self.uvs.as_ref()) {
                    uv.push((src[i] + src[j]) * 0.5);
                }
                (out.positions.len() - 1) as u32
            })
        };
        out.triangles.clear();
        out.face_material.clear();
        for (t, &[a, b, c]) in self.triangles.iter().enumerate() {
            let (ab, bc, ca) = (
                mid(a, b, &mut out),
                mid(b, c, &mut out),
                mid(c, a, &mut out),
            );
            out.triangles
                .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            let m = self.face_material.get(t).copied().unwrap_or(0);
            out.face_material.extend([m; 4]);
        }
        out
    }

    /// Appends `other`, re-indexing its vertices and materials.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        let mat_base = self.materials.len() as u32;
        match (&mut self.uvs, &other.uvs) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (Some(a), None) => a.extend(std::iter::repeat_n(Vec2::ZERO, other.positions.len())),
            (None, Some(b)) if self.positions.is_empty() => self.uvs = Some(b.clone()),
            (None, Some(b)) => {
                let mut u = vec![Vec2::ZERO; self.positions.len()];
                u.extend_from_slice(b);
                self.uvs = Some(u);
            }
            (None, None) => {}
        }
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        self.face_material
            .extend(other.face_material.iter().map(|m| m + mat_base));
        self.materials.extend(other.materials.iter().cloned());
    }

    /// Total surface area.
    pub fn area(&self) -> f32 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                (b - a).cross(c - a).length() * 0.5
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn validation_drops_degenerates_and_rejects_bad_indices() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X * 2.0];
        let mut w = Vec::new();
        let m = Mesh::from_parts(
            Path::new("t"),
            p.clone(),
            None,
            None,
            vec![[0, 1, 2], [0, 1, 3], [1, 1, 2]],
            vec![],
            vec![],
            &mut w,
        )
        .unwrap();
        assert_eq!(m.triangle_count(), 1);
        assert_eq!(
            w,
            vec![Warning::DegenerateTriangles {
                path: "t".into(),
                count: 2
            }]
        );
        assert!((m.normals[0] - Vec3::Z).length() < 1e-6);
        let err = Mesh::from_parts(
            Path::new("t"),
            p.clone(),
            None,
            None,
            vec![[0, 1, 9]],
            vec![],
            vec![],
            &mut w,
        );
        assert!(matches!(
            err,
            Err(MeshError::IndexOutOfRange { index: 9, .. })
        ));
        let mut nan = p;
        nan[2].y = f32::NAN;
        let err = Mesh::from_parts(
            Path::new("t"),
            nan,
            None,
            None,
            vec![[0, 1, 2]],
            vec![],
            vec![],
            &mut w,
        );
        assert!(matches!(err, Err(MeshError::NonFinite { .. })));
    }

    #[test]
    fn opposite_duplicate_faces_do_not_make_nan_normals() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut w = Vec::new();
        let m = Mesh::from_parts(
            Path::new("t"),
            p,
            None,
            None,
            vec![[0, 1, 2], [0, 2, 1]],
            vec![],
            vec![],
            &mut w,
        )
        .unwrap();
        assert!(
            m.normals
                .iter()
                .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-5)
        );
    }
}
