//! The graph camera (Popescu, Rosen and Adamo-Villani 2009; paper 1 §5; docs/conventions.md §4 — the
//! operations and matrices there are a proposal honouring everything the papers state,
//! implemented as written): a tree of planar-pinhole frusta obtained from one pinhole camera by
//! **bending** and **splitting**. Rays are piecewise linear: a ray changes direction where it
//! crosses the face a child shares with its parent, and stays continuous.
//!
//! Projection: find the frustum holding the point ([`GraphCamera::locate`]), then apply one
//! 4 × 4 matrix `M_j = P_root · A_{j1} ⋯ A_j` that concatenates, along the path to the root, the
//! affine maps `A_k(X) = X + ((n_k·X + e_k)/σ_k)(C_p − C_k)` sending each child apex to its
//! parent's apex while fixing the shared face plane (§4.4). `gd = 1/w`.
//!
//! Invariants (tested): `A_k` fixes its face plane and sends `C_k` to `C_p`; a point on a shared
//! face projects to the same `(u, v, gd)` through parent and child; `gd` decreases along a
//! generalized ray; `unproject(project(X)) = X`; a point lies in at most one frustum (faces
//! shared by a parent and a child belong to the parent).

use super::{CameraError, ImagePoint, Pinhole, Projection};
use crate::geom::polygon::{
    clip, convex_hull_in_plane, newell_normal, polygon_area, share_an_edge,
};
use glam::{DMat4, DVec2, DVec3, DVec4};

pub use crate::geom::Plane;

/// One planar-pinhole frustum of a graph camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Frustum {
    /// Centre of projection `C_j`.
    pub apex: DVec3,
    /// The plane the frustum starts at (the near plane for the root, else the face shared with
    /// the parent), inside toward the frustum.
    pub entry: Plane,
    /// The face shared with the parent (empty for the root), a convex polygon in `entry`.
    pub entry_face: Vec<DVec3>,
    /// Side planes through the apex, inside toward the frustum.
    pub sides: Vec<Plane>,
    /// Where the frustum ends (its children begin), inside toward the apex.
    pub exit: Option<Plane>,
    /// Parent frustum.
    pub parent: Option<usize>,
    /// Child frusta.
    pub children: Vec<usize>,
    /// World → homogeneous root image `(x, y, 1, w)`: `u = x/w`, `v = y/w`, `gd = 1/w`.
    pub matrix: DMat4,
    matrix_inv: DMat4,
}

impl Frustum {
    /// The child of `parent` seen from `apex` through `face` (which lies in the plane
    /// `exit`, the parent's exit), with its concatenated matrix.
    fn child(parent: usize, exit: Plane, face: Vec<DVec3>, apex: DVec3, matrix: DMat4) -> Frustum {
        let entry = exit.flipped();
        let centroid = face.iter().copied().sum::<DVec3>() / face.len() as f64;
        let inside_point = centroid + entry.n * 1e-3;
        let sides = (0..face.len())
            .filter_map(|i| {
                let n = (face[i] - apex).cross(face[(i + 1) % face.len()] - apex);
                let p = Plane::through(apex, n.try_normalize()?);
                Some(if p.eval(inside_point) < 0.0 {
                    p.flipped()
                } else {
                    p
                })
            })
            .collect();
        Frustum {
            apex,
            entry,
            entry_face: face,
            sides,
            exit: None,
            parent: Some(parent),
            children: Vec::new(),
            matrix_inv: matrix.inverse(),
            matrix,
        }
    }

    /// Whether `x` lies in the frustum (boundaries included; `tol` absorbs rounding).
    pub fn contains(&self, x: DVec3, tol: f64) -> bool {
        self.entry.eval(x) >= -tol
            && self.sides.iter().all(|s| s.eval(x) >= -tol)
            && self.exit.is_none_or(|p| p.eval(x) >= -tol)
    }
}

/// A graph camera: a tree of frusta rooted at a pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphCamera {
    root: Pinhole,
    frusta: Vec<Frustum>,
}

/// The affine collineation of §4.4: fixes the plane `p` (`n·X + e = 0`) and sends `from` to `to`.
pub fn face_map(p: Plane, from: DVec3, to: DVec3) -> Result<DMat4, CameraError> {
    let sigma = p.eval(from);
    if sigma.abs() < 1e-12 {
        return Err(CameraError::Degenerate(
            "a frustum apex lies in its entry plane",
        ));
    }
    let delta = to - from;
    // A = | I + δ nᵀ/σ   (e/σ) δ |
    //     | 0ᵀ            1      |
    let col = |k: usize| {
        let mut c = delta * (p.n[k] / sigma);
        c[k] += 1.0;
        c.extend(0.0)
    };
    Ok(DMat4::from_cols(
        col(0),
        col(1),
        col(2),
        (delta * (p.e / sigma)).extend(1.0),
    ))
}

impl GraphCamera {
    /// A graph camera with the single frustum of `root` (its near plane as the entry).
    pub fn new(root: Pinhole) -> GraphCamera {
        let (w, h) = root.resolution();
        let c = root.position();
        let corner = |u: f64, v: f64| root.unproject(DVec2::new(u, v), 1.0);
        let quad = [
            corner(0.0, 0.0),
            corner(w as f64, 0.0),
            corner(w as f64, h as f64),
            corner(0.0, h as f64),
        ];
        let centre = root.unproject(DVec2::new(w as f64 / 2.0, h as f64 / 2.0), 1.0);
        let sides = (0..4)
            .map(|i| {
                let n = (quad[i] - c).cross(quad[(i + 1) % 4] - c);
                let p = Plane::through(c, n.normalize());
                if p.eval(centre) < 0.0 { p.flipped() } else { p }
            })
            .collect();
        let entry = Plane::through(c + root.forward() * root.near(), root.forward());
        // P_root (§4.4), by rows: [m1, −m1·C], [m2, −m2·C], [0, 0, 0, 1], [m3, −m3·C], where
        // m1, m2, m3 are the rows of M⁻¹; so x/w = u, y/w = v, w = t. (The constant third row
        // keeps the matrix invertible, which unprojection uses.)
        let m_inv = root.mcmillan_inverse();
        let row = |k: usize| {
            let m = m_inv.row(k);
            DVec4::new(m.x, m.y, m.z, -m.dot(c))
        };
        let p_root = DMat4::from_cols(row(0), row(1), DVec4::W, row(2)).transpose();
        GraphCamera {
            frusta: vec![Frustum {
                apex: c,
                entry,
                entry_face: Vec::new(),
                sides,
                exit: None,
                parent: None,
                children: Vec::new(),
                matrix_inv: p_root.inverse(),
                matrix: p_root,
            }],
            root,
        }
    }

    /// The frusta (index 0 is the root).
    pub fn frusta(&self) -> &[Frustum] {
        &self.frusta
    }

    /// The root pinhole camera (its resolution is the image's).
    pub fn root(&self) -> &Pinhole {
        &self.root
    }

    /// The generalized ray of image point `uv` as a polyline (§4.1): from the root apex to the
    /// exit plane, then from each crossing on, away from the apex of the child whose face it
    /// crosses, and `beyond` past the last face. It ends early where it leaves the imaged
    /// region (a crossing outside every child's face).
    pub fn ray_path(&self, uv: DVec2, beyond: f64) -> Vec<DVec3> {
        let (mut j, mut o) = (0, self.frusta[0].apex);
        let mut d = self.root.ray(uv).dir.as_dvec3();
        let mut path = vec![o];
        while path.len() <= self.frusta.len() {
            let f = &self.frusta[j];
            let Some(exit) = f.exit else {
                path.push(o + d.normalize() * beyond);
                break;
            };
            let t = -exit.eval(o) / exit.n.dot(d);
            if !(t.is_finite() && t >= 0.0) {
                // The ray enters this frustum already past its exit: no part of it is imaged.
                break;
            }
            let q = o + d * t;
            path.push(q);
            let tol = 1e-9 * (1.0 + q.length());
            let Some(&c) = f.children.iter().find(|&&c| {
                let child = &self.frusta[c];
                child.sides.iter().all(|s| s.eval(q) >= -tol)
            }) else {
                break;
            };
            (j, o, d) = (c, q, q - self.frusta[c].apex);
        }
        path
    }

    /// The cross-section of frustum `j` with plane `plane` (a convex polygon): the plane's
    /// square of half-width `extent` around `centre` (a point of the plane), clipped to the
    /// frustum's side planes and its entry plane, so a child's face lies inside its parent.
    fn cross_section(&self, j: usize, plane: Plane, centre: DVec3, extent: f64) -> Vec<DVec3> {
        let n = plane.n.normalize();
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let mut poly: Vec<DVec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, y)| centre + (t * x + b * y) * extent)
            .collect();
        let f = &self.frusta[j];
        for s in f.sides.iter().chain(std::iter::once(&f.entry)) {
            poly = clip(&poly, s);
        }
        poly
    }

    /// Bends frustum `j` at plane `plane` (given by a point on it and a normal): `j` now ends at
    /// its cross-section with the plane, and a child frustum with apex `apex` (on the same side
    /// of the plane as `j`'s apex, §4.4) looks on through that face. `extent` bounds the size of
    /// the face (half-width around `point`). Returns the child's index.
    pub fn bend(
        &mut self,
        j: usize,
        point: DVec3,
        normal: DVec3,
        apex: DVec3,
        extent: f64,
    ) -> Result<usize, CameraError> {
        let face = self.cross_section(self.leaf(j)?, Plane::through(point, normal), point, extent);
        self.add_children(j, point, normal, vec![(face, apex)])
            .map(|k| k[0])
    }

    /// Splits frustum `j` at a plane into two children: the cross-section is cut by the plane
    /// `cut` (through `j`'s apex) into a part on its inside, seen from `apex_in`, and a part on
    /// its outside, seen from `apex_out`. Returns the children's indices.
    #[allow(clippy::too_many_arguments)]
    pub fn split(
        &mut self,
        j: usize,
        point: DVec3,
        normal: DVec3,
        cut: Plane,
        apex_in: DVec3,
        apex_out: DVec3,
        extent: f64,
    ) -> Result<(usize, usize), CameraError> {
        let k = self.split_into(j, point, normal, &[cut], &[apex_in, apex_out], extent)?;
        Ok((k[0], k[1]))
    }

    /// Splits frustum `j` at a plane into `cuts.len() + 1` children, one per apex: piece `i`
    /// of the cross-section lies outside `cuts[i − 1]` and inside `cuts[i]` (cuts through
    /// `j`'s apex, so the pieces tile the face). A piece that is empty is an error. An apex
    /// equal to `j`'s own gives a child that only partitions the image (its `A` is the
    /// identity). Returns the children's indices, in the order of `apexes`.
    pub fn split_into(
        &mut self,
        j: usize,
        point: DVec3,
        normal: DVec3,
        cuts: &[Plane],
        apexes: &[DVec3],
        extent: f64,
    ) -> Result<Vec<usize>, CameraError> {
        if apexes.len() != cuts.len() + 1 {
            return Err(CameraError::Degenerate(
                "a split needs one apex more than it has cuts",
            ));
        }
        let face = self.cross_section(self.leaf(j)?, Plane::through(point, normal), point, extent);
        let pieces = apexes
            .iter()
            .enumerate()
            .map(|(i, &apex)| {
                let mut piece = face.clone();
                if i > 0 {
                    piece = clip(&piece, &cuts[i - 1].flipped());
                }
                if i < cuts.len() {
                    piece = clip(&piece, &cuts[i]);
                }
                (piece, apex)
            })
            .collect();
        self.add_children(j, point, normal, pieces)
    }

    /// Merges frusta `j1` and `j2` (§4.3): their cross-sections with one plane must be
    /// adjacent (share an edge) and form a convex polygon together; the merged child, with
    /// apex `apex`, looks on through their union. As docs/conventions.md proposes, it is kept as two
    /// frusta `pyramid(apex, face₁)` (parent `j1`) and `pyramid(apex, face₂)` (parent `j2`),
    /// so every point keeps one path to the root; operations after a merge apply to each half.
    /// The image is continuous across each face; across the seam between the halves it is
    /// continuous where `j1` and `j2` themselves project their shared boundary alike (as for
    /// the two pieces of a split with one apex). Returns the two halves.
    pub fn merge(
        &mut self,
        j1: usize,
        j2: usize,
        point: DVec3,
        normal: DVec3,
        apex: DVec3,
        extent: f64,
    ) -> Result<[usize; 2], CameraError> {
        if j1 == j2 {
            return Err(CameraError::Degenerate(
                "a frustum cannot merge with itself",
            ));
        }
        let plane = Plane::through(point, normal);
        let f1 = self.cross_section(self.leaf(j1)?, plane, point, extent);
        let f2 = self.cross_section(self.leaf(j2)?, plane, point, extent);
        if f1.len() < 3 || f2.len() < 3 {
            return Err(CameraError::Degenerate("the merge plane misses a frustum"));
        }
        let scale = f1
            .iter()
            .chain(&f2)
            .map(|p| (*p - point).length())
            .fold(1.0, f64::max);
        if !share_an_edge(&f1, &f2, 1e-9 * scale) {
            return Err(CameraError::Degenerate(
                "merged faces must be adjacent (share an edge)",
            ));
        }
        let n = plane.n.normalize();
        let union_area = polygon_area(&convex_hull_in_plane(&[&f1[..], &f2[..]].concat(), n), n);
        let (a1, a2) = (polygon_area(&f1, n), polygon_area(&f2, n));
        if (union_area - a1 - a2).abs() > 1e-6 * union_area.max(1e-300) {
            return Err(CameraError::Degenerate(
                "merged faces must form a convex polygon",
            ));
        }
        let first = self.add_children(j1, point, normal, vec![(f1, apex)])?[0];
        let second = self.add_children(j2, point, normal, vec![(f2, apex)])?[0];
        Ok([first, second])
    }

    /// Rebuilds a graph camera from its root and, for every other frustum in creation order,
    /// `(parent, apex, entry face)` — what [`GraphCamera::parts`] gives back; the matrices are
    /// recomputed. Every parent precedes its children, and the faces of one parent's children
    /// lie in one plane; anything else is an error.
    pub fn from_parts(
        root: Pinhole,
        parts: &[(usize, DVec3, Vec<DVec3>)],
    ) -> Result<GraphCamera, CameraError> {
        let mut g = GraphCamera::new(root);
        for (i, (parent, apex, face)) in parts.iter().enumerate() {
            let own = i + 1;
            if *parent >= own {
                return Err(CameraError::Degenerate(
                    "a graph-camera frustum must follow its parent",
                ));
            }
            if face.len() < 3 || !apex.is_finite() || face.iter().any(|p| !p.is_finite()) {
                return Err(CameraError::Degenerate(
                    "a graph-camera face needs three finite corners and a finite apex",
                ));
            }
            let normal = newell_normal(face)
                .ok_or(CameraError::Degenerate("a graph-camera face has no area"))?;
            let plane = Plane::through(face[0], normal);
            let scale = face.iter().map(|p| p.length()).fold(1.0, f64::max);
            if face.iter().any(|p| plane.eval(*p).abs() > 1e-9 * scale) {
                return Err(CameraError::Degenerate("a graph-camera face is not planar"));
            }
            if let Some(exit) = g.frusta[*parent].exit {
                let along = exit.n.dot(normal).abs();
                if (along - 1.0).abs() > 1e-9
                    || face.iter().any(|p| exit.eval(*p).abs() > 1e-9 * scale)
                {
                    return Err(CameraError::Degenerate(
                        "the faces of one frustum's children must share a plane",
                    ));
                }
            }
            g.add_children(*parent, face[0], normal, vec![(face.clone(), *apex)])?;
        }
        Ok(g)
    }

    /// `(parent, apex, entry face)` of every frustum but the root, in creation order.
    pub fn parts(&self) -> Vec<(usize, DVec3, Vec<DVec3>)> {
        self.frusta[1..]
            .iter()
            .map(|f| (f.parent.unwrap_or(0), f.apex, f.entry_face.clone()))
            .collect()
    }

    /// Ends frustum `j` at a far plane (through `point`, normal `normal`) with no child: what
    /// lies beyond is not imaged. For a corridor that ends at a wall, so its pyramid does not
    /// reach on into space another frustum images.
    pub fn end(&mut self, j: usize, point: DVec3, normal: DVec3) -> Result<(), CameraError> {
        let j = self.leaf(j)?;
        let mut far = Plane::through(
            point,
            normal
                .try_normalize()
                .ok_or(CameraError::Degenerate("a far plane needs a normal"))?,
        );
        if far.eval(self.frusta[j].apex) < 0.0 {
            far = far.flipped();
        }
        self.frusta[j].exit = Some(far);
        Ok(())
    }

    /// `j` itself, when it has no children yet (a frustum ends at one plane).
    fn leaf(&self, j: usize) -> Result<usize, CameraError> {
        match self.frusta.get(j) {
            None => Err(CameraError::Degenerate("no such frustum")),
            Some(f) if f.exit.is_some() => Err(CameraError::Degenerate(
                "the frustum already ends at a face (bend, split or merge it once)",
            )),
            Some(_) => Ok(j),
        }
    }

    /// Adds one child of `j` per `(face, apex)`; all faces lie in the plane through `point`
    /// with normal `normal`, which becomes `j`'s exit.
    fn add_children(
        &mut self,
        j: usize,
        point: DVec3,
        normal: DVec3,
        pieces: Vec<(Vec<DVec3>, DVec3)>,
    ) -> Result<Vec<usize>, CameraError> {
        let parent_apex = self.frusta[j].apex;
        // The parent keeps the side of the plane its apex is on.
        let mut exit = Plane::through(point, normal.normalize());
        if exit.eval(parent_apex) < 0.0 {
            exit = exit.flipped();
        }
        let mut children = Vec::with_capacity(pieces.len());
        for (face, apex) in &pieces {
            if face.len() < 3 {
                return Err(CameraError::Degenerate("the bend plane misses the frustum"));
            }
            if exit.eval(*apex) <= 0.0 {
                return Err(CameraError::Degenerate(
                    "a child apex must lie on its parent apex's side of the bend plane",
                ));
            }
            // §4.4: A_k fixes the face plane (n pointing away from the child apex) and sends
            // the child apex to the parent apex.
            let matrix = self.frusta[j].matrix * face_map(exit, *apex, parent_apex)?;
            if matrix.determinant().abs() < 1e-300 {
                return Err(CameraError::Degenerate("a graph-camera matrix is singular"));
            }
            children.push(Frustum::child(j, exit, face.clone(), *apex, matrix));
        }
        // Validated: commit.
        self.frusta[j].exit = Some(exit);
        let mut indices = Vec::with_capacity(children.len());
        for child in children {
            let k = self.frusta.len();
            self.frusta[j].children.push(k);
            self.frusta.push(child);
            indices.push(k);
        }
        Ok(indices)
    }

    /// The frustum holding `x`: the first in creation order (parents before children), so a
    /// point on a shared face belongs to the parent.
    pub fn locate(&self, x: DVec3) -> Option<usize> {
        self.frusta.iter().position(|f| f.contains(x, 1e-12))
    }

    /// Projects `x` with frustum `j`'s matrix (whether or not `x` lies in it).
    pub fn project_in(&self, j: usize, x: DVec3) -> Option<ImagePoint> {
        let h = self.frusta[j].matrix * x.extend(1.0);
        if h.w <= 0.0 {
            return None;
        }
        Some(ImagePoint {
            uv: DVec2::new(h.x / h.w, h.y / h.w),
            gd: 1.0 / h.w,
            inv_w: 1.0 / h.w,
        })
    }
}

impl GraphCamera {
    /// The parameter interval of the ray `o + t·d` inside frustum `j`, within `[t0, t1]`
    /// (Cyrus–Beck against its planes).
    pub fn clip_ray(&self, j: usize, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let f = &self.frusta[j];
        let (mut lo, mut hi) = (t0, t1);
        for p in std::iter::once(&f.entry)
            .chain(&f.sides)
            .chain(f.exit.as_ref())
        {
            let (num, den) = (p.eval(o), p.n.dot(d));
            if den == 0.0 {
                if num < 0.0 {
                    return None;
                }
            } else {
                let t = -num / den;
                if den > 0.0 {
                    lo = lo.max(t);
                } else {
                    hi = hi.min(t);
                }
            }
        }
        (lo < hi).then_some((lo, hi))
    }

    /// Frustum `j` alone as a projective camera (its matrix, no `locate`).
    pub fn frustum(&self, j: usize) -> FrustumProjection<'_> {
        FrustumProjection {
            camera: self,
            index: j,
        }
    }
}

/// One frustum of a graph camera as a [`Projection`]: its matrix applied to any point. Used to
/// rasterize the triangles clipped to that frustum (§4.5) and to walk a ray's piece in it (§4.6).
#[derive(Clone, Copy, Debug)]
pub struct FrustumProjection<'a> {
    camera: &'a GraphCamera,
    index: usize,
}

impl Projection for FrustumProjection<'_> {
    fn resolution(&self) -> (u32, u32) {
        self.camera.root.resolution()
    }
    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        self.camera.project_in(self.index, p)
    }
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        let w = 1.0 / gd;
        let x = self.camera.frusta[self.index].matrix_inv * DVec4::new(uv.x * w, uv.y * w, 1.0, w);
        x.truncate() / x.w
    }
    /// The homogeneous `w`, affine in `p` and positive in front of the frustum's apex.
    fn clip_distance(&self, p: DVec3) -> f64 {
        (self.camera.frusta[self.index].matrix * p.extend(1.0)).w - 1e-9
    }

    /// One frustum is projective: it images a segment straight.
    fn midpoint_deviation_bound(&self, _: &[ImagePoint]) -> f64 {
        0.0
    }
}

/// A graph camera is not a [`Projection`]: its image is one, but its near boundary is no single
/// plane, so no clip distance affine in the world point exists, and a segment crossing a shared
/// face bends there. Only one frustum at a time ([`FrustumProjection`]) is a projection; these
/// are what the whole camera answers.
impl GraphCamera {
    /// Image size in pixels `(width, height)` (the root's).
    pub fn resolution(&self) -> (u32, u32) {
        self.root.resolution()
    }

    /// Projects a world point through the frustum that holds it; `None` outside every frustum.
    pub fn project(&self, p: DVec3) -> Option<ImagePoint> {
        self.project_in(self.locate(p)?, p)
    }

    /// The point of the frustum whose inverse matrix lands inside it (rays are disjoint, so at
    /// most one does, up to rounding on shared faces).
    pub fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        let w = 1.0 / gd;
        let h = DVec4::new(uv.x * w, uv.y * w, 1.0, w);
        let candidate = |f: &Frustum| {
            let x = f.matrix_inv * h;
            x.truncate() / x.w
        };
        self.frusta
            .iter()
            .map(|f| (f, candidate(f)))
            .find(|(f, x)| f.contains(*x, 1e-9 * (1.0 + x.length())))
            .map_or_else(|| candidate(&self.frusta[0]), |(_, x)| x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A corridor camera: a root looking down −z, bent 90° toward −x at z = −3 (the apex
    /// rotated about the vertical axis through the corner).
    fn corridor() -> GraphCamera {
        let root = Pinhole::look_at(
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::Y,
            60.0,
            64,
            64,
        )
        .unwrap()
        .with_near(0.1);
        let mut g = GraphCamera::new(root);
        // Bend plane: the diagonal through the corner (0, ·, −3), normal along (1, 0, 1)/√2;
        // new apex: the root apex rotated 90° about the vertical axis through (0, ·, −3).
        let corner = DVec3::new(0.0, 1.0, -3.0);
        let apex = corner + DVec3::new(3.0, 0.0, 0.0);
        g.bend(0, corner, DVec3::new(1.0, 0.0, 1.0), apex, 50.0)
            .unwrap();
        g
    }

    fn random_point(i: u32) -> DVec3 {
        let h = |k: u32| {
            ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_007) as f64 / 10_007.0
        };
        DVec3::new(-8.0 + 10.0 * h(1), -1.0 + 4.0 * h(2), -9.0 + 9.0 * h(3))
    }

    #[test]
    fn every_generalized_ray_projects_to_its_pixel_with_decreasing_gd() {
        let (g, _) = split_and_merged();
        let (w, h) = g.resolution();
        for (py, px) in (0..h)
            .step_by(3)
            .flat_map(|y| (0..w).step_by(3).map(move |x| (y, x)))
        {
            let uv = crate::frame::pixel_centre(px as f64, py as f64);
            let path = g.ray_path(uv, 4.0);
            assert!(path.len() >= 3, "{uv}: {path:?}");
            let mut last_gd = f64::INFINITY;
            for seg in path.windows(2).skip(1) {
                for k in 0..=10 {
                    let x = seg[0].lerp(seg[1], k as f64 / 10.0);
                    let p = g.project(x).unwrap();
                    assert!((p.uv - uv).length() < 1e-6, "{uv}: {x} → {}", p.uv);
                    assert!(p.gd <= last_gd * (1.0 + 1e-12), "{uv}: gd rises at {x}");
                    last_gd = p.gd;
                }
            }
        }
    }

    #[test]
    fn parts_rebuild_the_same_camera() {
        let (g, _) = split_and_merged();
        let again = GraphCamera::from_parts(g.root().clone(), &g.parts()).unwrap();
        assert_eq!(again.frusta().len(), g.frusta().len());
        for (a, b) in again.frusta().iter().zip(g.frusta()) {
            assert!(
                a.matrix.abs_diff_eq(b.matrix, 1e-9),
                "{} vs {}",
                a.matrix,
                b.matrix
            );
            assert_eq!(a.parent, b.parent);
        }
        // A child before its parent, or a warped face, is refused.
        let mut bad = g.parts();
        bad[0].0 = 3;
        assert!(GraphCamera::from_parts(g.root().clone(), &bad).is_err());
        let mut bad = g.parts();
        bad[2].2[0].z += 0.5;
        assert!(GraphCamera::from_parts(g.root().clone(), &bad).is_err());
    }

    #[test]
    fn face_map_fixes_its_plane_and_moves_the_apex() {
        let p = Plane::through(
            DVec3::new(0.0, 0.0, -3.0),
            DVec3::new(0.3, 0.1, -1.0).normalize(),
        );
        let (from, to) = (DVec3::new(2.0, 0.5, 0.0), DVec3::new(0.0, 0.0, 0.5));
        let a = face_map(p, from, to).unwrap();
        assert!((a.transform_point3(from) - to).length() < 1e-12);
        for i in 0..100 {
            let q = random_point(i);
            let on = q - p.n * p.eval(q) / p.n.length_squared();
            assert!((a.transform_point3(on) - on).length() < 1e-9);
        }
    }

    #[test]
    fn unproject_inverts_project_and_points_have_one_frustum() {
        let g = corridor();
        assert_eq!(g.frusta().len(), 2);
        let mut projected = 0;
        for i in 0..4000 {
            let x = random_point(i);
            let inside = g.frusta().iter().filter(|f| f.contains(x, 0.0)).count();
            assert!(inside <= 1, "{x} in {inside} frusta");
            if let Some(q) = g.project(x) {
                projected += 1;
                let back = g.unproject(q.uv, q.gd);
                assert!(
                    (back - x).length() < 1e-7 * (1.0 + x.length()),
                    "{x} → {back}"
                );
            }
        }
        assert!(projected > 200, "{projected}");
    }

    #[test]
    fn shared_face_projects_identically_from_both_frusta() {
        let g = corridor();
        let face = &g.frusta()[1].entry_face;
        for i in 0..face.len() {
            for s in [0.0, 0.3, 0.7] {
                let x = face[i].lerp(face[(i + 1) % face.len()], s);
                let centroid = face.iter().copied().sum::<DVec3>() / face.len() as f64;
                let x = x.lerp(centroid, 0.2);
                let (a, b) = (g.project_in(0, x).unwrap(), g.project_in(1, x).unwrap());
                assert!(
                    (a.uv - b.uv).length() < 1e-9 && (a.gd - b.gd).abs() < 1e-12,
                    "{x}"
                );
            }
        }
    }

    #[test]
    fn generalized_rays_are_continuous_with_decreasing_gd() {
        // Follow the ray of one pixel: from the root apex to the face, then from the child
        // apex through the crossing point. Every sample projects to the same pixel with
        // decreasing gd.
        let g = corridor();
        let root = &g.frusta()[0];
        let child = &g.frusta()[1];
        let exit = root.exit.unwrap();
        let uv = DVec2::new(30.5, 33.5);
        let dir = g.root.ray(uv).dir.as_dvec3();
        let t_face = -exit.eval(root.apex) / exit.n.dot(dir);
        let q = root.apex + dir * t_face;
        let mut last_gd = f64::INFINITY;
        let mut samples = 0;
        for k in 1..=40 {
            let x = if k <= 20 {
                root.apex + dir * (t_face * k as f64 / 20.0)
            } else {
                q + (q - child.apex).normalize() * (k - 20) as f64 * 0.2
            };
            let Some(p) = g.project(x) else { continue };
            assert!((p.uv - uv).length() < 1e-7, "sample {k}: {} vs {uv}", p.uv);
            assert!(p.gd < last_gd, "sample {k}: gd {} after {last_gd}", p.gd);
            last_gd = p.gd;
            samples += 1;
        }
        assert!(samples > 30, "{samples}");
    }

    #[test]
    fn a_child_apex_across_the_bend_plane_is_refused() {
        let root = Pinhole::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0, 8, 8).unwrap();
        let mut g = GraphCamera::new(root);
        let err = g.bend(
            0,
            DVec3::new(0.0, 0.0, -3.0),
            DVec3::Z,
            DVec3::new(0.0, 0.0, -5.0),
            10.0,
        );
        assert!(err.is_err());
        // Splitting gives two children on either side of the cut.
        let cut = Plane::through(DVec3::ZERO, DVec3::X);
        let (a, b) = g
            .split(
                0,
                DVec3::new(0.0, 0.0, -3.0),
                DVec3::Z,
                cut,
                DVec3::new(0.5, 0.0, -0.5),
                DVec3::new(-0.5, 0.0, -0.5),
                10.0,
            )
            .unwrap();
        assert_eq!((a, b), (1, 2));
        assert!(g.frusta()[1].entry_face.iter().all(|p| p.x >= -1e-12));
        assert!(g.frusta()[2].entry_face.iter().all(|p| p.x <= 1e-12));
    }

    /// A root split in two at z = −3 (both halves keep the root apex), the halves merged again
    /// at z = −5 with an apex moved sideways.
    fn split_and_merged() -> (GraphCamera, [usize; 2]) {
        let root = Pinhole::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0, 32, 32)
            .unwrap()
            .with_near(0.1);
        let mut g = GraphCamera::new(root);
        let cut = Plane::through(DVec3::ZERO, DVec3::X);
        let (a, b) = g
            .split(
                0,
                DVec3::new(0.0, 0.0, -3.0),
                DVec3::Z,
                cut,
                DVec3::ZERO,
                DVec3::ZERO,
                10.0,
            )
            .unwrap();
        let m = g
            .merge(
                a,
                b,
                DVec3::new(0.0, 0.0, -5.0),
                DVec3::Z,
                DVec3::new(1.0, 0.2, -1.0),
                10.0,
            )
            .unwrap();
        (g, m)
    }

    #[test]
    fn merged_halves_are_continuous_across_their_faces_and_their_seam() {
        let (g, [m1, m2]) = split_and_merged();
        assert_eq!(g.frusta().len(), 5);
        for &m in &[m1, m2] {
            let f = &g.frusta()[m];
            let parent = f.parent.unwrap();
            let centroid = f.entry_face.iter().copied().sum::<DVec3>() / f.entry_face.len() as f64;
            for &v in &f.entry_face {
                let x = v.lerp(centroid, 0.3);
                let (a, b) = (
                    g.project_in(parent, x).unwrap(),
                    g.project_in(m, x).unwrap(),
                );
                assert!((a.uv - b.uv).length() < 1e-9 && (a.gd - b.gd).abs() < 1e-12);
            }
        }
        // The seam: the plane x = 0 beyond the merge face, seen from the merged apex.
        let seam = Plane::through(DVec3::ZERO, DVec3::X);
        let apex = g.frusta()[m1].apex;
        for k in 0..50 {
            let on_face = DVec3::new(0.0, -1.0 + 0.04 * k as f64, -5.0);
            let x = on_face + (on_face - apex) * (0.2 + 0.1 * k as f64);
            let x = x - seam.n * seam.eval(x);
            let (a, b) = (g.project_in(m1, x).unwrap(), g.project_in(m2, x).unwrap());
            assert!(
                (a.uv - b.uv).length() < 1e-9 && (a.gd - b.gd).abs() < 1e-12,
                "{x}"
            );
        }
        // Every point still has one frustum and unprojects back.
        for i in 0..4000 {
            let x = DVec3::new(-6.0, -3.0, -12.0)
                + (random_point(i) - DVec3::new(-8.0, -1.0, -9.0)) * DVec3::new(1.2, 1.5, 1.3);
            let inside = g.frusta().iter().filter(|f| f.contains(x, 0.0)).count();
            assert!(inside <= 1, "{x} in {inside} frusta");
            if let Some(q) = g.project(x) {
                let back = g.unproject(q.uv, q.gd);
                assert!(
                    (back - x).length() < 1e-7 * (1.0 + x.length()),
                    "{x} → {back}"
                );
            }
        }
    }

    #[test]
    fn merge_needs_adjacent_faces_and_a_leaf_ends_once() {
        let root = Pinhole::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0, 32, 32).unwrap();
        let mut g = GraphCamera::new(root);
        let cuts = [
            Plane::through(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.2)),
            Plane::through(DVec3::ZERO, DVec3::new(1.0, 0.0, -0.2)),
        ];
        let k = g
            .split_into(
                0,
                DVec3::new(0.0, 0.0, -3.0),
                DVec3::Z,
                &cuts,
                &[DVec3::ZERO; 3],
                10.0,
            )
            .unwrap();
        assert_eq!(k, vec![1, 2, 3]);
        let far = (
            DVec3::new(0.0, 0.0, -5.0),
            DVec3::Z,
            DVec3::new(0.0, 0.0, -1.0),
        );
        // Pieces 0 and 2 are not adjacent.
        assert!(g.merge(k[0], k[2], far.0, far.1, far.2, 10.0).is_err());
        assert!(g.merge(k[0], k[1], far.0, far.1, far.2, 10.0).is_ok());
        // The root already ends at the split plane.
        assert!(
            g.bend(0, DVec3::new(0.0, 0.0, -4.0), DVec3::Z, DVec3::ZERO, 10.0)
                .is_err()
        );
    }
}
