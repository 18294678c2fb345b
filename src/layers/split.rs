//! Newell splits: a triangle cut by a plane into pieces that lie on one side each — how
//! "Layered view-dependent projective textures" §4.1 breaks the visibility cycles that remain
//! among triangles (Newell, Newell and Sancha, "A solution to the hidden surface problem",
//! 1972).
//!
//! Invariants: the pieces tile the triangle exactly (the same plane, the same area); the first
//! piece keeps the triangle's index, the others are appended, so existing triangle indices stay
//! valid; normals and texture coordinates are interpolated; replaying the same splits on the
//! same mesh gives the same mesh.

use crate::geom::Mesh;
use crate::geom::{Plane, clip_polygon};
use glam::{DVec3, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// One split: triangle `triangle` of object `object` cut by the plane `n·x + e = 0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Split {
    /// The object.
    pub object: u32,
    /// The triangle cut (it keeps its index as the first piece).
    pub triangle: u32,
    /// The plane's unit normal and offset.
    pub plane: [f64; 4],
    /// The pieces' triangle indices, `triangle` first.
    pub pieces: Vec<u32>,
}

/// How far (relative to the triangle's size) a corner must lie from the plane to count as on
/// one side: a plane through a corner or an edge does not split.
const SIDE_EPS: f64 = 1e-6;

/// A corner being clipped: position, normal, texture coordinate.
#[derive(Clone, Copy)]
struct Corner {
    p: DVec3,
    n: Vec3,
    uv: Vec2,
}

/// Splits triangle `t` of `mesh` (object `object`) by `plane` when the plane has corners
/// strictly on both sides; `None` (the mesh untouched) otherwise.
pub fn split_triangle(mesh: &mut Mesh, object: u32, t: u32, plane: &Plane) -> Option<Split> {
    let tri = *mesh.triangles.get(t as usize)?;
    let corners: Vec<Corner> = tri
        .iter()
        .map(|&i| Corner {
            p: mesh.positions[i as usize].as_dvec3(),
            n: mesh.normals[i as usize],
            uv: mesh.uvs.as_ref().map_or(Vec2::ZERO, |u| u[i as usize]),
        })
        .collect();
    let size = (corners[1].p - corners[0].p)
        .length()
        .max((corners[2].p - corners[0].p).length());
    let d: Vec<f64> = corners.iter().map(|c| plane.eval(c.p)).collect();
    let eps = SIDE_EPS * size.max(f64::MIN_POSITIVE);
    if !(d.iter().any(|&x| x > eps) && d.iter().any(|&x| x < -eps)) {
        return None;
    }
    let lerp = |a: &Corner, b: &Corner, s: f64| Corner {
        p: a.p.lerp(b.p, s),
        n: a.n.lerp(b.n, s as f32).try_normalize().unwrap_or(a.n),
        uv: a.uv.lerp(b.uv, s as f32),
    };
    let front = clip_polygon(&corners, |c| plane.eval(c.p), lerp);
    let back = clip_polygon(&corners, |c| -plane.eval(c.p), lerp);
    let material = mesh.face_material.get(t as usize).copied().unwrap_or(0);
    let mut pieces = Vec::new();
    for poly in [front, back] {
        let base = mesh.positions.len() as u32;
        for c in &poly {
            mesh.positions.push(c.p.as_vec3());
            mesh.normals.push(c.n);
            if let Some(u) = mesh.uvs.as_mut() {
                u.push(c.uv);
            }
        }
        for k in 1..poly.len().saturating_sub(1) as u32 {
            let tri = [base, base + k, base + k + 1];
            if pieces.is_empty() {
                mesh.triangles[t as usize] = tri;
                pieces.push(t);
            } else {
                pieces.push(mesh.triangles.len() as u32);
                mesh.triangles.push(tri);
                mesh.face_material.push(material);
            }
        }
    }
    Some(Split {
        object,
        triangle: t,
        plane: [plane.n.x, plane.n.y, plane.n.z, plane.e],
        pieces,
    })
}

/// Replays `split` on `mesh`: the same cut, checked to give the same piece indices.
pub fn replay(mesh: &mut Mesh, split: &Split) -> Option<()> {
    let [x, y, z, e] = split.plane;
    let plane = Plane {
        n: DVec3::new(x, y, z),
        e,
    };
    let again = split_triangle(mesh, split.object, split.triangle, &plane)?;
    (again.pieces == split.pieces).then_some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_tile_the_triangle_and_lie_on_one_side_each() {
        let mut mesh = crate::geom::plane(1);
        let t0 = mesh.triangle_count();
        let area = mesh.area();
        let plane = Plane::through(
            DVec3::new(0.1, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.3).normalize(),
        );
        let s = (0..t0 as u32)
            .find_map(|t| split_triangle(&mut mesh, 0, t, &plane))
            .expect("the plane crosses the square");
        assert_eq!(s.pieces.len(), 3);
        assert!((mesh.area() - area).abs() < 1e-5);
        for &p in &s.pieces {
            let d: Vec<f64> = mesh
                .corners(p as usize)
                .iter()
                .map(|c| plane.eval(c.as_dvec3()))
                .collect();
            assert!(
                d.iter().all(|&x| x >= -1e-6) || d.iter().all(|&x| x <= 1e-6),
                "{d:?}"
            );
        }
        // A plane through no interior point does not split.
        let far = Plane::through(DVec3::new(5.0, 0.0, 0.0), DVec3::X);
        assert!(split_triangle(&mut mesh, 0, 0, &far).is_none());
    }
}
