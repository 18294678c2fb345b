//! The shading model every renderer shares: surface albedo and Lambert + environment ambient. The
//! optics of mirrors and glass are in [`crate::geom::optics`].

use crate::frame::Wrap;
use crate::geom::Mesh;
use crate::scene::{Lighting, Surface};
use glam::{Vec2, Vec3};

/// Linear albedo of triangle `triangle` of `mesh` at texture coordinates `uv`.
pub fn albedo(mesh: &Mesh, surface: &Surface, triangle: u32, uv: Vec2) -> Vec3 {
    let (color, texture) = match surface {
        Surface::Diffuse(Some(o)) => (o.color, o.texture.as_ref()),
        _ => {
            let m = mesh
                .face_material
                .get(triangle as usize)
                .copied()
                .unwrap_or(0);
            match mesh.materials.get(m as usize) {
                Some(mat) => (mat.base_color, mat.texture.as_ref()),
                None => (Vec3::splat(0.8), None),
            }
        }
    };
    match texture {
        Some(t) => color * t.sample_uv(uv, Wrap::Repeat).truncate(),
        None => color,
    }
}

/// Lambertian reflection: `albedo · (E_env(n)/π + L_sun · max(0, n·l))`, no shadows.
pub fn lambert(albedo: Vec3, n: Vec3, lighting: &Lighting) -> Vec3 {
    let mut e = lighting.environment.irradiance(n);
    if let Some(sun) = &lighting.light {
        e += sun.radiance * n.dot(sun.direction).max(0.0);
    }
    albedo * e
}
