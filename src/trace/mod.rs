//! Ray queries: the [`RayQuery`] trait every ray-answering representation implements, the
//! [`SecondaryQuery`] trait renderers ask for the rays a mirror or glass object sends out, the
//! BVH over triangle meshes (ground truth for every impostor; the CPU "software shader" of
//! paper 3), a brute-force oracle, and the environment map as a hit at infinity.
//!
//! Invariants: nothing here uses impostors — the BVH is the ground truth; impostors implement
//! these traits in the modules above this one. A [`Hit`]'s `t` is the ray
//! parameter (a distance when the direction is unit length); hits satisfy `0 < t < t_max`.

mod bvh;

pub(crate) use bvh::surface_point;
pub use bvh::{
    BUILD_BYTES_PER_TRIANGLE as BVH_BUILD_BYTES_PER_TRIANGLE, BruteForce, Bvh,
    RESIDENT_BYTES_PER_TRIANGLE as BVH_RESIDENT_BYTES_PER_TRIANGLE,
};

use crate::frame::envmap::EnvMap;
use crate::geom::Ray;
use glam::{Vec2, Vec3};

pub use crate::geom::{ENVIRONMENT, NO_OBJECT};

/// What a ray query found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (`f32::INFINITY` for the environment).
    pub t: f32,
    /// World position (the ray's direction, for the environment).
    pub position: Vec3,
    /// Unit shading normal (interpolated vertex normals); its side is not flipped.
    pub normal: Vec3,
    /// Unit geometric normal (counter-clockwise front).
    pub geometric_normal: Vec3,
    /// Texture coordinates (zero when the mesh has none).
    pub uv: Vec2,
    /// Barycentrics of corners 1 and 2.
    pub bary: Vec2,
    /// Object id ([`ENVIRONMENT`] for the environment).
    pub object: u32,
    /// Triangle index within the object.
    pub triangle: u32,
    /// Radiance carried by image-based answers (environment maps, impostors); `None` for geometry,
    /// which the renderer shades from its material.
    pub radiance: Option<Vec3>,
}

/// Anything that answers rays: the exact BVH, an environment map, impostors and billboards.
/// Renderers are generic over it for primary rays, and over [`SecondaryQuery`] for the rays
/// mirrors and glass send out.
pub trait RayQuery: Sync {
    /// The nearest hit with `0 < t < t_max`.
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit>;
    /// Whether anything is hit with `0 < t < t_max` (shadow and visibility rays).
    fn any_hit(&self, ray: &Ray, t_max: f32) -> bool {
        self.closest_hit(ray, t_max).is_some()
    }
    /// The nearest hit of every ray of `rays` (each with its own `t_max`), in order, into
    /// `hits` (replacing what it held): a batch spread over the current thread pool. Each
    /// answer is [`RayQuery::closest_hit`]'s, whatever the thread count; an implementation may
    /// reorder the work (by image position, in packets) but not the answers.
    fn closest_hits(&self, rays: &[(Ray, f32)], hits: &mut Vec<Option<Hit>>) {
        use rayon::prelude::*;
        rays.par_iter()
            .with_min_len(64)
            .map(|(ray, t_max)| self.closest_hit(ray, *t_max))
            .collect_into_vec(hits);
    }
}

impl Hit {
    /// The mirror ray of `ray` at this hit, `epsilon` off the surface
    /// ([`crate::geom::optics::mirror_ray`]).
    pub fn mirror_ray(&self, ray: &Ray, epsilon: f32) -> Ray {
        crate::geom::optics::mirror_ray(
            ray,
            self.position,
            self.normal,
            self.geometric_normal,
            epsilon,
        )
    }
}

/// What answers the rays a mirror or glass object sends out into the open (paper 1 §6: the
/// secondary rays an impostor stands in for the geometry behind). Given the id of the object
/// the ray leaves and the ray, it returns a hit carrying its own radiance (an image-based
/// answer: an impostor's texel, the environment), a hit without radiance on an object the
/// renderer shades itself (one more bounce), or `None` (the renderer takes the environment's
/// radiance).
///
/// Implemented by [`Exact`] (the same scene as primary rays: ground truth), [`EnvironmentOnly`]
/// (classic environment mapping) and, above this module, by per-reflector impostor sets.
pub trait SecondaryQuery: Sync {
    /// The answer to `ray`, sent out by object `reflector`.
    fn secondary_hit(&self, reflector: u32, ray: &Ray) -> Option<Hit>;
}

/// Secondary rays answered exactly by a [`RayQuery`], whichever object sends them.
pub struct Exact<'a, Q: RayQuery>(pub &'a Q);

impl<Q: RayQuery> SecondaryQuery for Exact<'_, Q> {
    fn secondary_hit(&self, _reflector: u32, ray: &Ray) -> Option<Hit> {
        self.0.closest_hit(ray, f32::INFINITY)
    }
}

/// Secondary rays that meet nothing: reflections show only the environment.
pub struct EnvironmentOnly;

impl SecondaryQuery for EnvironmentOnly {
    fn secondary_hit(&self, _reflector: u32, _ray: &Ray) -> Option<Hit> {
        None
    }
}

impl RayQuery for EnvMap {
    /// The environment is hit by every ray whose range reaches infinity.
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        (t_max == f32::INFINITY).then(|| Hit {
            t: f32::INFINITY,
            position: ray.dir,
            normal: -ray.dir.normalize_or_zero(),
            geometric_normal: -ray.dir.normalize_or_zero(),
            uv: self.lookup_uv(ray.dir),
            bary: Vec2::ZERO,
            object: ENVIRONMENT,
            triangle: 0,
            radiance: Some(self.radiance(ray.dir)),
        })
    }
}

/// The nearer of two answers: geometry first, then what lies behind it (e.g. BVH, then sky).
pub struct Nearest<A, B>(pub A, pub B);

impl<A: RayQuery, B: RayQuery> RayQuery for Nearest<A, B> {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        match self.0.closest_hit(ray, t_max) {
            Some(h) => self.1.closest_hit(ray, h.t).or(Some(h)),
            None => self.1.closest_hit(ray, t_max),
        }
    }
    fn any_hit(&self, ray: &Ray, t_max: f32) -> bool {
        self.0.any_hit(ray, t_max) || self.1.any_hit(ray, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Mesh, icosphere};
    use std::sync::Arc;

    #[test]
    fn environment_answers_what_geometry_does_not() {
        let sphere: Arc<Mesh> = Arc::new(icosphere(2));
        let scene = Nearest(
            Bvh::build(vec![sphere]).unwrap(),
            EnvMap::constant(Vec3::ONE),
        );
        let toward = Ray::new(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z);
        let hit = scene.closest_hit(&toward, f32::INFINITY).unwrap();
        assert_eq!(hit.object, 0);
        assert!((hit.t - 2.5).abs() < 0.01, "{}", hit.t);
        let away = Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z);
        let sky = scene.closest_hit(&away, f32::INFINITY).unwrap();
        assert_eq!(sky.object, ENVIRONMENT);
        assert_eq!(sky.radiance, Some(Vec3::ONE));
        // A bounded query never reaches infinity.
        assert!(scene.closest_hit(&away, 100.0).is_none());
        assert!(!scene.any_hit(&away, 100.0));
    }
}
