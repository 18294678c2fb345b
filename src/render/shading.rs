//! The shading model every renderer shares: surface albedo, Lambert + environment ambient, and
//! [`surface_radiance`], the one place a surface's kind — diffuse, mirror, glass — decides what
//! leaves it. The tracer follows the rays mirrors and glass send out; methods that answer them
//! from the environment alone (the raster method at depth 1, the octahedral scene) give
//! [`surface_radiance`] the environment as their answer. The optics are in
//! [`crate::geom::optics`].

use crate::frame::Wrap;
use crate::geom::Mesh;
use crate::geom::Ray;
use crate::geom::optics::{fresnel, reflect, refract};
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

/// Which side of a surface a ray it sends out leaves from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The side the surface was seen from (a reflection).
    Near,
    /// The other side (a refraction through glass).
    Far,
}

/// A ray a mirror or glass surface sends out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounce {
    /// Its direction.
    pub dir: Vec3,
    /// The side it leaves from.
    pub side: Side,
    /// Whether it goes into the open (rather than into the glass object).
    pub outward: bool,
}

/// Radiance leaving a surface back along the ray direction `d`: `n` is the shading normal
/// turned toward the viewer and `front` whether the ray met the surface's front side
/// ([`crate::geom::optics::facing`]). A diffuse surface is lit by [`lambert`] (`albedo` asked
/// only there, `visible` its shadow test); a mirror sends out its reflection, glass its
/// reflection and refraction weighted by the exact Fresnel term, each answered by `follow`.
pub fn surface_radiance(
    surface: &Surface,
    d: Vec3,
    (n, front): (Vec3, bool),
    albedo: impl FnOnce() -> Vec3,
    lighting: &Lighting,
    visible: impl FnOnce(Vec3) -> bool,
    follow: impl Fn(Bounce) -> Vec3,
) -> Vec3 {
    match surface {
        Surface::Diffuse(_) => lambert(albedo(), n, lighting, visible),
        Surface::Mirror { tint } => {
            *tint
                * follow(Bounce {
                    dir: reflect(d, n),
                    side: Side::Near,
                    outward: true,
                })
        }
        Surface::Glass { ior, tint } => {
            let eta = if front { 1.0 / ior } else { *ior };
            let kr = fresnel((-d.dot(n)).max(0.0), eta);
            let reflected = follow(Bounce {
                dir: reflect(d, n),
                side: Side::Near,
                outward: front,
            });
            let transmitted = match refract(d, n, eta) {
                Some(t) if kr < 1.0 => {
                    *tint
                        * follow(Bounce {
                            dir: t,
                            side: Side::Far,
                            outward: !front,
                        })
                }
                _ => Vec3::ZERO,
            };
            kr * reflected + (1.0 - kr) * transmitted
        }
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
