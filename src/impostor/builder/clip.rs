//! Graph-camera construction's clipping (paper 1 §5; `docs/conventions.md` §4): every frustum
//! takes the triangles it meets, cut to its planes by the one polygon clipper
//! ([`crate::geom::clip_polygon`]); groups of triangles wholly outside a plane are skipped and
//! groups wholly inside all of them kept whole.

use super::*;
/// Triangles per group whose box is tested against a frustum's planes before its triangles are
/// (a mesh's consecutive triangles are usually near one another).
pub(super) const CLIP_GROUP: usize = 64;

/// The box of each group of [`CLIP_GROUP`] consecutive triangles of `mesh`.
pub(super) fn group_bounds(mesh: &Mesh) -> Vec<Aabb> {
    let triangles: Vec<usize> = (0..mesh.triangles.len()).collect();
    triangles
        .par_chunks(CLIP_GROUP)
        .map(|group| Aabb::from_points(group.iter().flat_map(|&t| mesh.corners(t))))
        .collect()
}

/// Where a box lies against a plane: wholly inside, wholly outside, or across it — "wholly"
/// with a margin far above the rounding of the corners' own distances, so a box said to be
/// inside (outside) holds no corner that [`clip_triangle`] would find outside (inside).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Side {
    Inside,
    Outside,
    Across,
}

pub(super) fn box_side(plane: &crate::camera::Plane, b: &Aabb) -> Side {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let n = plane.n;
    // The corners farthest along and against the normal.
    let far = glam::DVec3::select(n.cmpge(glam::DVec3::ZERO), hi, lo);
    let near = glam::DVec3::select(n.cmpge(glam::DVec3::ZERO), lo, hi);
    let margin = 1e-9 * (n.abs().dot(lo.abs().max(hi.abs())) + plane.e.abs());
    if plane.eval(far) < -margin {
        Side::Outside
    } else if plane.eval(near) > margin {
        Side::Inside
    } else {
        Side::Across
    }
}

/// Clips triangle `t` (corners `p`) to the convex region inside every plane of `planes`
/// (Sutherland–Hodgman, in 3-D), fan-triangulating what is left into `out`. A triangle wholly
/// outside one plane is dropped at once, one wholly inside all of them kept as it is.
pub(super) fn clip_triangle(
    planes: &[crate::camera::Plane],
    t: usize,
    p: [Vec3; 3],
    out: &mut (Vec<Vec3>, Vec<SourceTriangle>),
) {
    let whole = [Vec3::X, Vec3::Y, Vec3::Z];
    let corners = p.map(|c| c.as_dvec3());
    let mut inside_all = true;
    for plane in planes {
        let d = corners.map(|c| plane.eval(c));
        if d.iter().all(|&x| x < 0.0) {
            return;
        }
        inside_all &= d.iter().all(|&x| x >= 0.0);
    }
    if inside_all {
        out.0.extend_from_slice(&p);
        out.1.push((t as u32, whole));
        return;
    }
    let mut poly: Vec<(glam::DVec3, Vec3)> = corners.into_iter().zip(whole).collect();
    for plane in planes {
        poly = crate::geom::clip_polygon(
            &poly,
            |c| plane.eval(c.0),
            |a, b, s| (a.0 + (b.0 - a.0) * s, a.1 + (b.1 - a.1) * s as f32),
        );
        if poly.len() < 3 {
            return;
        }
    }
    for k in 1..poly.len() - 1 {
        for c in [poly[0], poly[k], poly[k + 1]] {
            out.0.push(c.0.as_vec3());
        }
        out.1
            .push((t as u32, [poly[0].1, poly[k].1, poly[k + 1].1]));
    }
}

/// The planes bounding frustum `j` of `g`, inside toward it: its entry, sides and exit.
pub(super) fn frustum_planes(
    g: &crate::camera::GraphCamera,
    j: usize,
) -> Vec<crate::camera::Plane> {
    let f = &g.frusta()[j];
    std::iter::once(f.entry)
        .chain(f.sides.iter().copied())
        .chain(f.exit)
        .collect()
}

/// Clips every triangle of `mesh` to frustum `j` of `g` ([`clip_triangle`], §4.5), group by
/// group: a group whose box (`groups`, from [`group_bounds`]) is wholly outside one plane is
/// skipped, one wholly inside every plane kept whole — most of a mesh meets one frustum or two.
/// The same pieces, in the same order, as clipping each triangle.
pub(super) fn clip_to_frustum(
    g: &crate::camera::GraphCamera,
    j: usize,
    mesh: &Mesh,
    groups: &[Aabb],
) -> Tessellation {
    let planes = frustum_planes(g, j);
    let mut out = (Vec::new(), Vec::new());
    for (k, b) in groups.iter().enumerate() {
        let (mut outside, mut inside_all) = (false, true);
        for plane in &planes {
            match box_side(plane, b) {
                Side::Outside => {
                    outside = true;
                    break;
                }
                Side::Across => inside_all = false,
                Side::Inside => {}
            }
        }
        if outside {
            continue;
        }
        let first = k * CLIP_GROUP;
        let triangles = first..(first + CLIP_GROUP).min(mesh.triangles.len());
        if inside_all {
            for t in triangles {
                out.0.extend_from_slice(&mesh.corners(t));
                out.1.push((t as u32, [Vec3::X, Vec3::Y, Vec3::Z]));
            }
            continue;
        }
        for t in triangles {
            clip_triangle(&planes, t, mesh.corners(t), &mut out);
        }
    }
    Tessellation::new(out.0, out.1)
}

/// The visible point of the source mesh a fragment of a clipped piece shows (a visibility
/// buffer of the source drawn through its pieces).
pub(super) struct SourcePoint<'a> {
    /// Source triangle and corner barycentrics of each piece.
    pub(super) source: &'a [SourceTriangle],
    /// The frustum drawing them.
    pub(super) frustum: u32,
}

impl FragmentShader for SourcePoint<'_> {
    type Output = Option<Visible>;
    fn shade(&self, f: &Fragment) -> Option<Visible> {
        let b = full_barycentrics(Vec2::new(f.bary.y, f.bary.z));
        Some(Visible {
            frustum: Some(self.frustum),
            ..to_source(Some(self.source), f.item.triangle, b)
        })
    }
}
