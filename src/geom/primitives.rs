//! Built-in shapes for scenes and tests: a plane, a cube and an icosphere, all unit-sized and
//! centred at the origin (the scene transform sizes and places them).

use super::{Material, Mesh};
use glam::{Vec2, Vec3};

fn assemble(
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
) -> Mesh {
    let n = triangles.len();
    Mesh {
        positions,
        normals,
        uvs: Some(uvs),
        triangles,
        face_material: vec![0; n],
        materials: vec![Material::default()],
    }
}

/// A square in the `y = 0` plane, side 1, facing `+y`, split into `n × n` quads.
pub fn plane(n: u32) -> Mesh {
    let n = n.max(1);
    let mut p = Vec::new();
    let mut uv = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (s, t) = (i as f32 / n as f32, j as f32 / n as f32);
            p.push(Vec3::new(s - 0.5, 0.0, t - 0.5));
            uv.push(Vec2::new(s, t));
        }
    }
    let mut tris = Vec::new();
    let idx = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +y.
            tris.push([idx(i, j), idx(i, j + 1), idx(i + 1, j)]);
            tris.push([idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)]);
        }
    }
    let normals = vec![Vec3::Y; p.len()];
    assemble(p, normals, uv, tris)
}

/// A cube of side 1 with flat faces (24 vertices, 12 triangles).
pub fn cube() -> Mesh {
    let mut p = Vec::new();
    let mut nrm = Vec::new();
    let mut uv = Vec::new();
    let mut tris = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let u = Vec3::new(n.y.abs() + n.z.abs(), 0.0, n.x.abs()) * sign.signum();
            let u = if u == Vec3::ZERO { Vec3::X } else { u };
            let v = n.cross(u);
            let base = p.len() as u32;
            for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                p.push(n * 0.5 + u * a + v * b);
                nrm.push(n);
                uv.push(Vec2::new(a + 0.5, 0.5 - b));
            }
            tris.push([base, base + 1, base + 2]);
            tris.push([base, base + 2, base + 3]);
        }
    }
    assemble(p, nrm, uv, tris)
}

/// A sphere of radius 0.5 by `subdivisions` loop-splits of an icosahedron (exact unit normals).
pub fn icosphere(subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(7) {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(tris.len() * 4);
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize());
                p.len() as u32 - 1
            })
        };
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let uv = p
        .iter()
        .map(|d| crate::frame::envmap::direction_to_uv(*d))
        .collect();
    let normals = p.clone();
    let positions = p.iter().map(|d| *d * 0.5).collect();
    assemble(positions, normals, uv, tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_closed_or_flat_with_outward_normals() {
        for (mesh, area) in [(cube(), 6.0), (plane(3), 1.0)] {
            assert!((mesh.area() - area).abs() < 1e-5);
            for t in 0..mesh.triangle_count() {
                let c = mesh.corners(t);
                let centroid = (c[0] + c[1] + c[2]) / 3.0;
                let n = mesh.face_normal(t);
                // Faces point away from the centre (or up, for the plane).
                assert!(n.dot(centroid) > 0.0 || n.dot(Vec3::Y) > 0.99);
            }
        }
        let s = icosphere(3);
        assert_eq!(s.triangle_count(), 20 * 64);
        let area = s.area();
        assert!(
            (area - std::f32::consts::PI).abs() / std::f32::consts::PI < 0.01,
            "{area}"
        );
    }
}
