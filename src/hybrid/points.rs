//! Diffuse surfaces as points (paper 2 §3.1): every diffuse triangle is covered by stratified
//! samples, one in each piece of a longest-edge bisection whose pieces have at most `spacing²` of
//! area and edges at most `2·spacing` long, so no stretch of surface wider than about two spacings
//! is left without a point. Each point carries its object-space position, its interpolated
//! normal and its albedo (texture included) — what shading it needs once it is seen in a mirror.
//!
//! A triangle smaller than one piece keeps its one point with a probability of twice its share
//! of a piece's area, so meshes of many tiny triangles are not sampled once per triangle.
//!
//! Invariants: object space; deterministic for a mesh, a spacing and a seed, whatever the thread
//! count; the point count is bounded before anything is allocated ([`estimate`]).

use crate::geom::Mesh;
use crate::geom::SplitMix64;
use crate::render::shading::albedo;
use crate::scene::Surface;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Bytes one point costs: position, normal, albedo.
pub const BYTES_PER_POINT: u64 = 36;

/// Points on the surface of one object, in object space.
#[derive(Clone, Debug, Default)]
pub struct PointSet {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Unit normals (interpolated vertex normals).
    pub normals: Vec<Vec3>,
    /// Linear albedo.
    pub albedo: Vec<Vec3>,
}

impl PointSet {
    /// How many points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The points in the order `order` gives (a permutation of `0..len`).
    pub fn permuted(&self, order: &[u32]) -> PointSet {
        let pick = |v: &[Vec3]| order.iter().map(|&i| v[i as usize]).collect();
        PointSet {
            positions: pick(&self.positions),
            normals: pick(&self.normals),
            albedo: pick(&self.albedo),
        }
    }
}

/// An upper bound on the points [`sample`] makes for `mesh` at `spacing`: each triangle's
/// bisection pieces are bounded by its area and its longest edge.
pub fn estimate(mesh: &Mesh, spacing: f32) -> u64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let area = 0.5 * (b - a).cross(c - a).length();
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let pieces = (2.0 * area / (spacing * spacing)).max(longest / spacing);
            (2.0 * pieces.ceil() as f64 + 1.0) as u64
        })
        .fold(0u64, u64::saturating_add)
}

/// Stratified points over `mesh` about `spacing` apart, coloured as `surface` colours it.
pub fn sample(mesh: &Mesh, surface: &Surface, spacing: f32, seed: u64) -> PointSet {
    let spacing = spacing.max(f32::MIN_POSITIVE);
    let chunks: Vec<PointSet> = (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| sample_triangle(mesh, surface, t, spacing, seed))
        .collect();
    let mut out = PointSet::default();
    for c in chunks {
        out.positions.extend(c.positions);
        out.normals.extend(c.normals);
        out.albedo.extend(c.albedo);
    }
    out
}

/// One point in each piece of the bisection of triangle `t`, pieces held as barycentric corners.
fn sample_triangle(mesh: &Mesh, surface: &Surface, t: usize, spacing: f32, seed: u64) -> PointSet {
    let tri = mesh.triangles[t];
    let corners = mesh.corners(t);
    let at = |b: Vec3| corners[0] * b.x + corners[1] * b.y + corners[2] * b.z;
    let mut rng = SplitMix64::new(seed ^ (t as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut out = PointSet::default();
    let max_area = spacing * spacing;
    let max_edge = 2.0 * spacing;
    // A triangle smaller than a piece gets its one point with a probability in proportion to
    // its area (twice the piece density, so meshes of tiny triangles keep no large gaps).
    let whole = 0.5
        * (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .length();
    let longest_edge = (corners[1] - corners[0])
        .length()
        .max((corners[2] - corners[1]).length())
        .max((corners[0] - corners[2]).length());
    if whole < max_area && longest_edge <= max_edge && rng.next_f32() >= 2.0 * whole / max_area {
        return out;
    }
    let mut stack = vec![[Vec3::X, Vec3::Y, Vec3::Z]];
    while let Some(piece) = stack.pop() {
        let p = piece.map(at);
        let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let edges = [
            (p[1] - p[0]).length(),
            (p[2] - p[1]).length(),
            (p[0] - p[2]).length(),
        ];
        let (k, longest) = edges
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0.0f32), |m, (i, e)| if e > m.1 { (i, e) } else { m });
        if (area > max_area || longest > max_edge) && stack.len() < 64 {
            // Split edge k (from corner k to corner k+1) at its midpoint.
            let (i, j, o) = (k, (k + 1) % 3, (k + 2) % 3);
            let mid = (piece[i] + piece[j]) * 0.5;
            stack.push([piece[i], mid, piece[o]]);
            stack.push([mid, piece[j], piece[o]]);
            continue;
        }
        // A uniform point in the piece.
        let (mut r1, mut r2) = (rng.next_f32(), rng.next_f32());
        if r1 + r2 > 1.0 {
            (r1, r2) = (1.0 - r1, 1.0 - r2);
        }
        let b = piece[0] * (1.0 - r1 - r2) + piece[1] * r1 + piece[2] * r2;
        let n = tri.map(|v| mesh.normals[v as usize]);
        let normal = (n[0] * b.x + n[1] * b.y + n[2] * b.z)
            .try_normalize()
            .unwrap_or_else(|| mesh.face_normal(t));
        let uv = match &mesh.uvs {
            Some(uvs) => {
                let w = tri.map(|v| uvs[v as usize]);
                w[0] * b.x + w[1] * b.y + w[2] * b.z
            }
            None => Vec2::ZERO,
        };
        out.positions.push(at(b));
        out.normals.push(normal);
        out.albedo.push(albedo(mesh, surface, t as u32, uv));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_cover_the_surface_at_the_spacing_and_stay_within_the_estimate() {
        let mesh = crate::geom::plane(1);
        let surface = Surface::Diffuse(None);
        let spacing = 0.05;
        let points = sample(&mesh, &surface, spacing, 7);
        assert!(points.len() as u64 <= estimate(&mesh, spacing));
        // One point per at most spacing² of area.
        assert!(points.len() as f32 >= mesh.area() / (spacing * spacing));
        // No hole: every point of a fine grid has a sample within 2 spacings.
        for i in 0..40 {
            for j in 0..40 {
                let p = Vec3::new(-0.49 + i as f32 * 0.025, 0.0, -0.49 + j as f32 * 0.025);
                let nearest = points
                    .positions
                    .iter()
                    .map(|q| (*q - p).length())
                    .fold(f32::INFINITY, f32::min);
                assert!(nearest <= 2.0 * spacing, "{p}: {nearest}");
            }
        }
        // Deterministic.
        assert_eq!(
            sample(&mesh, &surface, spacing, 7).positions,
            points.positions
        );
    }
}
