//! The shading model every renderer shares: surface albedo and Lambert + environment ambient. The
//! optics of mirrors and glass are in [`crate::geom::optics`].

use crate::frame::Wrap;
use crate::geom::Mesh;
use crate::geom::Ray;
use crate::scene::{Lighting, Surface};
use crate::trace::RayQuery;
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

/// Lambertian reflection: `albedo · (E_env(n) + E_sun · max(0, n·l) · visible) / π`, where
/// `visible(l)` says whether the light is seen from the surface along `l` (a shadow ray; asked
/// only when the surface faces the light).
pub fn lambert(
    albedo: Vec3,
    n: Vec3,
    lighting: &Lighting,
    visible: impl FnOnce(Vec3) -> bool,
) -> Vec3 {
    // The environment's term is already divided by π.
    let mut e = lighting.environment.irradiance(n);
    if let Some(sun) = &lighting.light {
        let cos = n.dot(sun.direction);
        if cos > 0.0 && visible(sun.direction) {
            e += sun.irradiance * (cos / std::f32::consts::PI);
        }
    }
    albedo * e
}

/// Whether the light along `l` reaches `position`: the shadow ray `epsilon` off the surface
/// along `n` (the normal on the side being lit) meets nothing in `occluders`.
pub fn lit(occluders: &dyn RayQuery, position: Vec3, n: Vec3, l: Vec3, epsilon: f32) -> bool {
    !occluders.any_hit(&Ray::new(position + n * epsilon, l), f32::INFINITY)
}

/// What casts the light's shadows on surfaces shaded away from the tracer (impostor texels,
/// splatted points): the scene's occluders and the shadow ray's offset.
#[derive(Clone, Copy)]
pub struct Shadows<'a> {
    /// What blocks the light (the scene's BVH).
    pub occluders: &'a dyn RayQuery,
    /// Offset of the shadow ray's origin along the normal.
    pub epsilon: f32,
}

impl Shadows<'_> {
    /// [`lit`] through these occluders.
    pub fn lit(&self, position: Vec3, n: Vec3, l: Vec3) -> bool {
        lit(self.occluders, position, n, l, self.epsilon)
    }
}

impl std::fmt::Debug for Shadows<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shadows")
            .field("epsilon", &self.epsilon)
            .finish_non_exhaustive()
    }
}
