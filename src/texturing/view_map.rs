//! Debevec's view map ("Efficient View-Dependent Image-Based Rendering with Projective
//! Texture-Mapping", Debevec, Yu and Borshukov 1998, §4): per polygon, a regularly sampled sphere
//! of viewing directions, each sample holding the view that sees the polygon from nearest that
//! direction. A new viewing direction falls in one spherical triangle of samples; its barycentric
//! coordinates weight the (at most three) views at the triangle's corners — continuous weights,
//! no more than three images a polygon.
//!
//! Invariant: a sample holds a view only if that view sees the polygon's centroid.

use crate::geom::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// No view sees the polygon.
const NONE: u16 = u16::MAX;

/// The view maps of every triangle of a mesh.
#[derive(Clone, Debug)]
pub struct ViewMap {
    /// Unit sample directions (a twice-subdivided icosahedron: 162 directions, 320 triangles).
    directions: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    /// `triangle × directions.len() + sample` → view index, or [`NONE`].
    table: Vec<u16>,
}

impl ViewMap {
    /// The view maps of `mesh`'s triangles over views centred at `centres` (at most 65 535);
    /// `sees(view, triangle, centroid)` says whether a view sees a triangle's centroid.
    pub fn build(
        mesh: &Mesh,
        centres: &[DVec3],
        sees: &(dyn Fn(usize, usize, DVec3) -> bool + Sync),
    ) -> ViewMap {
        let sphere = crate::geom::icosphere(2);
        // The icosphere repeats positions along texture seams: keep one direction per position.
        let mut directions: Vec<DVec3> = Vec::new();
        let remap: Vec<u32> = sphere
            .positions
            .iter()
            .map(|p| {
                let d = p.as_dvec3().normalize();
                match directions.iter().position(|q| q.distance(d) < 1e-6) {
                    Some(i) => i as u32,
                    None => {
                        directions.push(d);
                        directions.len() as u32 - 1
                    }
                }
            })
            .collect();
        let faces: Vec<[u32; 3]> = sphere
            .triangles
            .iter()
            .map(|t| t.map(|i| remap[i as usize]))
            .collect();
        let n = directions.len();
        let table: Vec<u16> = (0..mesh.triangle_count())
            .into_par_iter()
            .flat_map_iter(|t| {
                let c = mesh.corners(t).map(|p| p.as_dvec3());
                let centroid = (c[0] + c[1] + c[2]) / 3.0;
                let seeing: Vec<(u16, DVec3)> = (0..centres.len().min(NONE as usize))
                    .filter(|&i| sees(i, t, centroid))
                    .map(|i| (i as u16, (centres[i] - centroid).normalize()))
                    .collect();
                let row: Vec<u16> = directions
                    .iter()
                    .map(|w| {
                        seeing
                            .iter()
                            .max_by(|a, b| w.dot(a.1).total_cmp(&w.dot(b.1)))
                            .map_or(NONE, |s| s.0)
                    })
                    .collect();
                row
            })
            .collect();
        debug_assert_eq!(n * mesh.triangle_count(), table.len());
        ViewMap {
            directions,
            faces,
            table,
        }
    }

    /// The unit sample directions (the same for every mesh: a twice-subdivided icosahedron).
    pub fn directions(&self) -> &[DVec3] {
        &self.directions
    }

    /// The spherical triangles of the samples, as indices into [`ViewMap::directions`].
    pub fn sphere_faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Per triangle of the mesh, per sample direction: the view the sample holds, or
    /// `u16::MAX` where no view sees the triangle (row-major, [`ViewMap::directions`] a row).
    pub fn table(&self) -> &[u16] {
        &self.table
    }

    /// The views and weights triangle `t` takes seen along unit direction `omega` (from the
    /// surface toward the eye): at most three, weights summing to one; empty when no view sees
    /// the triangle.
    pub fn weights(&self, t: usize, omega: DVec3) -> Vec<(usize, f64)> {
        let n = self.directions.len();
        let row = &self.table[t * n..(t + 1) * n];
        for f in &self.faces {
            let [a, b, c] = f.map(|i| self.directions[i as usize]);
            // Barycentric coordinates of the ray along omega through the face's plane.
            let (wa, wb, wc) = (
                omega.dot(b.cross(c)),
                omega.dot(c.cross(a)),
                omega.dot(a.cross(b)),
            );
            let total = wa + wb + wc;
            let inside =
                (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) || (wa <= 0.0 && wb <= 0.0 && wc <= 0.0);
            if !inside || total.abs() < 1e-300 || omega.dot(a + b + c) <= 0.0 {
                continue;
            }
            let mut out: Vec<(usize, f64)> = Vec::with_capacity(3);
            for (k, w) in [(f[0], wa / total), (f[1], wb / total), (f[2], wc / total)] {
                let v = row[k as usize];
                if v == NONE || w <= 0.0 {
                    continue;
                }
                match out.iter_mut().find(|e| e.0 == v as usize) {
                    Some(e) => e.1 += w,
                    None => out.push((v as usize, w)),
                }
            }
            let sum: f64 = out.iter().map(|e| e.1).sum();
            if sum > 0.0 {
                out.iter_mut().for_each(|e| e.1 /= sum);
            }
            return out;
        }
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_map_blends_at_most_three_views_that_see_the_triangle() {
        let mesh = crate::geom::plane(1);
        // Views above the plane (y = 0, facing +y) and one below it, which sees nothing.
        let centres = [
            DVec3::new(0.0, 3.0, 0.5),
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(-2.0, 2.0, 0.3),
            DVec3::new(0.2, 2.0, 2.0),
            DVec3::new(0.0, -3.0, 0.1),
        ];
        let map = ViewMap::build(&mesh, &centres, &|i, _, _| centres[i].y > 0.0);
        for t in 0..mesh.triangle_count() {
            for k in 0..50 {
                let a = k as f64 * 0.4;
                let omega =
                    DVec3::new(a.cos() * 0.7, 0.5 + 0.01 * k as f64, a.sin() * 0.7).normalize();
                let w = map.weights(t, omega);
                assert!(!w.is_empty() && w.len() <= 3);
                assert!(
                    w.iter().all(|&(i, _)| i != 4),
                    "the view below sees nothing: {w:?}"
                );
                let sum: f64 = w.iter().map(|e| e.1).sum();
                assert!((sum - 1.0).abs() < 1e-9);
            }
            // Looking from straight above the first camera's direction picks it alone.
            let c = mesh.corners(t).map(|p| p.as_dvec3());
            let centroid = (c[0] + c[1] + c[2]) / 3.0;
            let w = map.weights(t, (centres[0] - centroid).normalize());
            assert!(w.iter().any(|&(i, x)| i == 0 && x > 0.5), "{w:?}");
        }
    }
}
