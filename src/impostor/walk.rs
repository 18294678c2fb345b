//! Ray–impostor intersection (paper 1 §3.2; docs/conventions.md §2.3): clip the ray to the bounding
//! box (its exit grown by the farthest a hit is placed from a stored point, `exit_margin`: the
//! surface a texel stores may reach that far past the geometry's box), follow the clipped
//! segment through the image, and stop at the first place where the ray passes from in front of
//! the stored surface to behind it. The walk every query uses follows the segment's image
//! texel by texel (`texels.rs`); the paper's walk, kept as the reference it is checked
//! against, cuts the segment into sub-segments of about one pixel of image path (interpolated in
//! 3-D, then projected, so the path may curve; twice as dense for the SPOC, §3.4).
//!
//! Where this departs from §2.3, and why: "in front of" is measured as the signed distance from
//! the ray sample to the plane of the triangle its texel stores (texels keep the world position
//! and face normal), not as `gd_ray − gd_stored` — the `gd` difference of the nearest texel is off
//! by up to half a texel's depth gradient, which produced early false crossings on grazing rays.
//! The hit is placed on that plane, so along the camera's own rays a pinhole impostor returns
//! exactly its rasterized point. A crossing whose plane point lies farther than two texel
//! footprints from the stored point is a false crossing — the ray passed behind an occluding
//! edge of the single-layer image, or met a texel plane edge-on — and the walk goes on. Empty
//! texels are "in front" of everything.
//!
//! A layered impostor (`peel.rs`) is walked through every layer, each with these rules, and the
//! nearest crossing wins.

use super::path::ImagePath;
use super::{Impostor, ImpostorCamera};
use crate::camera::{ImagePoint, Projection};
use crate::frame::pixel_centre;
use crate::geom::Ray;
use crate::trace::{Hit, RayQuery};
use glam::{BVec3, DVec2, DVec3, Vec2, Vec3};

/// Thickness, in texel footprints, within which a crossing at a discontinuity is accepted.
const THICKNESS_FOOTPRINTS: f64 = 2.0;
/// Smallest cosine between a texel's plane normal and its view direction used to stretch its
/// footprint (at most 3.3×): enough for corridor walls seen from the corridor's end, small
/// enough not to bridge silhouettes (measured on the maze and the teapot).
const MIN_COS: f64 = 0.3;
/// The farthest, in footprints, a walk ever places a hit from the stored point of its texel (the
/// thickness, stretched by the largest slant): how far the stored surface may reach past the
/// replaced geometry, so how far past its box a walk goes on ([`exit_margin`]).
const REACH_FOOTPRINTS: f64 = THICKNESS_FOOTPRINTS / MIN_COS;
/// Samples per pixel of image path in the graph camera's algorithm 1.
const GRAPH_UNIFORM_DENSITY: f64 = 4.0;
/// Upper bound on sub-segments per ray (bounds the work on degenerate input).
const MAX_STEPS: usize = 1 << 16;

/// How a walk advances along the ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkMode {
    /// Sub-segments of about one pixel of image path, each end projected (paper 1 §3.2;
    /// docs/conventions.md §2.3): the reference the other modes are checked against. The graph
    /// camera takes uniform 3-D steps (§4.6's algorithm 1).
    Linear,
    /// Every texel the image path crosses, once, in order, along its closed form
    /// (`impostor/texels.rs`); for the graph camera frustum by frustum (§4.6's algorithm 2).
    Exact,
    /// [`WalkMode::Exact`], stepping over pyramid nodes the ray passes in front of: the same
    /// hits for fewer texel reads. What [`Impostor::walk`] does.
    Pyramid,
}

/// Work done by one ray walk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WalkStats {
    /// Texels (and pyramid nodes) whose depth was read.
    pub texel_visits: u64,
    /// Length of the ray's image path, in pixels (rounded up).
    pub projection_length: u64,
}

#[derive(Clone, Copy)]
pub(super) struct Sample {
    pub p: ImagePoint,
    /// The sample's texel, if inside the image.
    pub texel: Option<(u32, u32)>,
    /// Stored `gd` at the sample's texel (0 when empty or outside).
    pub stored: f32,
    /// Signed distance from the sample to its texel's plane, positive on the camera's side
    /// (+∞ over empty texels): positive while the ray is in front of the stored surface.
    pub delta: f64,
}

impl Impostor {
    /// The first hit of `ray` with `0 < t < t_max`, and the work it took: the texel walk
    /// with the pyramid ([`WalkMode::Pyramid`]).
    pub fn walk(&self, ray: &Ray, t_max: f32) -> (Option<Hit>, WalkStats) {
        self.walk_mode(ray, t_max, WalkMode::Pyramid)
    }

    /// The stretch `[t0, t1]` of `ray` a walk covers: from where it enters the box of the
    /// replaced geometry to where it leaves that box grown by [`Impostor::exit_margin`] (or
    /// `t_max`); `None` when it misses the box.
    fn walk_span(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
        let (t0, _) = self.bounds.intersect(ray, t_max)?;
        let margin = Vec3::splat(self.exit_margin());
        let reach = crate::geom::Aabb {
            min: self.bounds.min - margin,
            max: self.bounds.max + margin,
        };
        let (_, t1) = reach.intersect(ray, t_max)?;
        Some((t0, t1))
    }

    /// [`Impostor::walk`] with a chosen mode.
    pub fn walk_mode(&self, ray: &Ray, t_max: f32, mode: WalkMode) -> (Option<Hit>, WalkStats) {
        match mode {
            WalkMode::Linear => self.walk_linear(ray, t_max),
            WalkMode::Exact => self.walk_exact(ray, t_max, false),
            WalkMode::Pyramid => self.walk_exact(ray, t_max, true),
        }
    }

    /// The linear walk through every layer: the nearest crossing of any layer's surface wins.
    /// Each deeper layer is walked only up to the best hit so far (it can only answer nearer).
    fn walk_linear(&self, ray: &Ray, t_max: f32) -> (Option<Hit>, WalkStats) {
        let (mut best, mut stats) = self.walk_layer(ray, t_max);
        for layer in &self.deeper {
            let limit = best.map_or(t_max, |h| h.t.min(t_max));
            let (hit, more) = layer.walk_layer(ray, limit);
            stats.texel_visits += more.texel_visits;
            stats.projection_length = stats.projection_length.max(more.projection_length);
            if let Some(h) = hit
                && h.t < limit
            {
                best = Some(h);
            }
        }
        (best, stats)
    }

    /// The linear walk through this layer alone.
    fn walk_layer(&self, ray: &Ray, t_max: f32) -> (Option<Hit>, WalkStats) {
        match &self.camera {
            ImpostorCamera::Pinhole(c) => self.walk_with(c, 1.0, ray, t_max),
            ImpostorCamera::Orthographic(c) => self.walk_with(c, 1.0, ray, t_max),
            // A curved image path is longer than its chord: sample twice as densely (§3.4).
            ImpostorCamera::Spoc(c) => self.walk_with(c, 2.0, ray, t_max),
            ImpostorCamera::Graph(g) => self.walk_graph_uniform(g, ray, t_max),
        }
    }

    /// The texel walk (`texels.rs`) of the ray's segment in the walk span, every layer at once.
    fn walk_exact(&self, ray: &Ray, t_max: f32, skip: bool) -> (Option<Hit>, WalkStats) {
        let mut stats = WalkStats::default();
        let Some((t0, t1)) = self.walk_span(ray, t_max) else {
            return (None, stats);
        };
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let (c, e) = (o + d * t0 as f64, o + d * t1 as f64);
        let hit = match &self.camera {
            ImpostorCamera::Pinhole(cam) => {
                self.walk_projective(cam, ray, (c, e), skip, &mut stats)
            }
            ImpostorCamera::Orthographic(cam) => {
                self.walk_projective(cam, ray, (c, e), skip, &mut stats)
            }
            ImpostorCamera::Spoc(cam) => clip_to_domain(cam, c, e)
                .and_then(|(c, e)| ImagePath::spoc(cam, c, e))
                .and_then(|path| self.walk_texels(ray, &path, skip, &mut stats)),
            ImpostorCamera::Graph(g) => self.walk_graph_pieces(g, ray, (t0, t1), &mut stats),
        };
        (hit, stats)
    }

    /// The texel walk of the world segment `[c, e]` of `ray` through a projective camera.
    fn walk_projective<P: Projection>(
        &self,
        camera: &P,
        ray: &Ray,
        (c, e): (DVec3, DVec3),
        skip: bool,
        stats: &mut WalkStats,
    ) -> Option<Hit> {
        let (c, e) = clip_to_domain(camera, c, e)?;
        let (pc, pe) = (camera.project(c)?, camera.project(e)?);
        let path = ImagePath::projective(c, e, pc, pe);
        self.walk_texels(ray, &path, skip, stats)
    }

    /// Algorithm 2 of §4.6: clip the ray to every frustum, order the pieces along the ray, and
    /// walk each piece texel by texel with its frustum's matrix (a straight image segment). A
    /// graph camera's texels have no front bounds: no node is stepped over.
    fn walk_graph_pieces(
        &self,
        g: &crate::camera::GraphCamera,
        ray: &Ray,
        (t0, t1): (f32, f32),
        stats: &mut WalkStats,
    ) -> Option<Hit> {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let mut pieces: Vec<(f64, f64, usize)> = (0..g.frusta().len())
            .filter_map(|j| {
                g.clip_ray(j, o, d, t0 as f64, t1 as f64)
                    .map(|(a, b)| (a, b, j))
            })
            .collect();
        pieces.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
        pieces.into_iter().find_map(|(a, b, j)| {
            self.walk_projective(&g.frustum(j), ray, (o + d * a, o + d * b), false, stats)
        })
    }

    /// Algorithm 1 of §4.6: uniform steps in 3-D, each sample `locate`d and projected with
    /// its frustum's matrix. The step count comes from the image length of the path, measured
    /// on 33 coarse samples, at [`GRAPH_UNIFORM_DENSITY`] samples per pixel (the path bends
    /// where the ray crosses faces, which the samples do not know). Samples no frustum holds
    /// are not imaged: they count as empty and the walk goes on.
    fn walk_graph_uniform(
        &self,
        g: &crate::camera::GraphCamera,
        ray: &Ray,
        t_max: f32,
    ) -> (Option<Hit>, WalkStats) {
        let mut stats = WalkStats::default();
        let Some((t0, t1)) = self.walk_span(ray, t_max) else {
            return (None, stats);
        };
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let (c, e) = (o + d * t0 as f64, o + d * t1 as f64);
        let coarse: Vec<Option<DVec2>> = (0..=32)
            .map(|k| g.project(c.lerp(e, k as f64 / 32.0)).map(|p| p.uv))
            .collect();
        let length: f64 = coarse
            .windows(2)
            .filter_map(|w| Some((w[1]? - w[0]?).length()))
            .sum();
        stats.projection_length = length.ceil() as u64;
        let n = ((length * GRAPH_UNIFORM_DENSITY).ceil() as usize).clamp(1, MAX_STEPS);
        let empty = Sample {
            p: ImagePoint {
                uv: DVec2::ZERO,
                gd: 0.0,
                inv_w: 0.0,
            },
            texel: None,
            stored: 0.0,
            delta: f64::INFINITY,
        };
        let mut prev = self.sample(g, c, &mut stats).unwrap_or(empty);
        for k in 1..=n {
            let cur = self
                .sample(g, c.lerp(e, k as f64 / n as f64), &mut stats)
                .unwrap_or(empty);
            if prev.delta > 0.0
                && cur.delta <= 0.0
                && let Some(hit) = self.accept(ray, &prev, &cur)
            {
                return (Some(hit), stats);
            }
            prev = cur;
        }
        (None, stats)
    }

    fn sample<P: ProjectPoint>(
        &self,
        camera: &P,
        s: DVec3,
        stats: &mut WalkStats,
    ) -> Option<Sample> {
        let p = camera.land(s)?;
        stats.texel_visits += 1;
        let texel = self.texel(p.uv);
        let (stored, delta) = match texel {
            Some((x, y)) => self.texel_plane_side(s, x, y),
            None => (0.0, f64::INFINITY),
        };
        Some(Sample {
            p,
            texel,
            stored,
            delta,
        })
    }

    fn walk_with<P: Projection>(
        &self,
        camera: &P,
        density: f64,
        ray: &Ray,
        t_max: f32,
    ) -> (Option<Hit>, WalkStats) {
        let mut stats = WalkStats::default();
        let Some((t0, t1)) = self.walk_span(ray, t_max) else {
            return (None, stats);
        };
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let Some((c, e)) = clip_to_domain(camera, o + d * t0 as f64, o + d * t1 as f64) else {
            return (None, stats);
        };
        let (Some(pc), Some(pe)) = (camera.project(c), camera.project(e)) else {
            return (None, stats);
        };
        let chord = (pe.uv - pc.uv).length();
        stats.projection_length = chord.ceil() as u64;
        let n = ((chord * density).ceil() as usize).clamp(1, MAX_STEPS);
        let Some(mut prev) = self.sample(camera, c, &mut stats) else {
            return (None, stats);
        };
        for k in 1..=n {
            let Some(cur) = self.sample(camera, c + (e - c) * (k as f64 / n as f64), &mut stats)
            else {
                return (None, stats);
            };
            if prev.delta > 0.0
                && cur.delta <= 0.0
                && let Some(hit) = self.accept(ray, &prev, &cur)
            {
                return (Some(hit), stats);
            }
            prev = cur;
        }
        (None, stats)
    }

    /// The stored `gd` of texel `(x, y)` and the signed distance from `s` to its plane (+∞
    /// when the texel is empty). Emptiness is read from the compact `gd` map (sixteen texels a
    /// cache line, and most samples of a walk lie over empty texels), the plane from the
    /// texel's packed record (one line) only when it is covered.
    pub(super) fn texel_plane_side(&self, s: DVec3, x: u32, y: u32) -> (f32, f64) {
        let gd = self.gd.get(x, y);
        if gd > 0.0 {
            let t = self.texel_planes().get(x, y);
            (gd, (s - t.point.as_dvec3()).dot(t.normal.as_dvec3()))
        } else {
            (0.0, f64::INFINITY)
        }
    }

    /// Places the hit on the stored surface where the ray crosses it within one sub-segment,
    /// and applies the discontinuity rules.
    pub(super) fn accept(&self, ray: &Ray, a: &Sample, b: &Sample) -> Option<Hit> {
        if a.stored <= 0.0 || b.stored <= 0.0 {
            return None;
        }
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        // Candidates: the ray's crossing of the texel plane at b, then at a; each must lie
        // within the thickness of the point its texel stores.
        for sample in [b, a] {
            let (tx, ty) = sample.texel?;
            let plane = self.texel_planes().get(tx, ty);
            let (stored_point, n) = (plane.point.as_dvec3(), plane.normal.as_dvec3());
            let denom = d.dot(n);
            if denom.abs() < 1e-9 {
                continue;
            }
            let x = o + d * ((stored_point - o).dot(n) / denom);
            // The texel covers its footprint stretched by 1/cos θ on a plane seen at θ from
            // its normal (grazing walls of a corridor seen from its end).
            let view = self.camera.toward_camera_along_ray(
                sample.p.uv,
                sample.stored as f64,
                stored_point,
            );
            let cos = n.dot(view).abs().max(MIN_COS);
            let footprint = self.footprint(sample.p.uv, sample.stored as f64) / cos;
            if (x - stored_point).length() <= THICKNESS_FOOTPRINTS * footprint {
                return Some(self.hit(ray, x, (tx, ty)));
            }
        }
        // Neither plane is near: the sign change came from a depth discontinuity (the ray passed
        // behind an occluding edge) or from a texel plane seen edge-on; not a hit.
        None
    }

    fn hit(&self, ray: &Ray, x: DVec3, (tx, ty): (u32, u32)) -> Hit {
        let t = (x - ray.origin.as_dvec3()).dot(ray.dir.as_dvec3()) as f32;
        let normal = self.normal_at(tx, ty);
        Hit {
            t,
            position: x.as_vec3(),
            normal,
            geometric_normal: self.face_normal_at(tx, ty),
            uv: pixel_centre(f64::from(tx), f64::from(ty)).as_vec2(),
            bary: Vec2::ZERO,
            object: self.object.get(tx, ty),
            triangle: 0,
            radiance: Some(self.color_at(tx, ty).truncate()),
        }
    }
}

impl RayQuery for Impostor {
    fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.walk(ray, t_max).0.filter(|h| h.t > 0.0 && h.t < t_max)
    }

    /// Builds what the walks derive from the maps once, before the batch's threads start
    /// (see [`Impostor::prepare_walks`]), then answers every ray as [`RayQuery::closest_hit`].
    fn closest_hits(&self, rays: &[(Ray, f32)], hits: &mut Vec<Option<Hit>>) {
        use rayon::prelude::*;
        self.prepare_walks();
        rays.par_iter()
            .with_min_len(64)
            .map(|(ray, t_max)| self.closest_hit(ray, *t_max))
            .collect_into_vec(hits);
    }
}

/// How far past the box of the replaced geometry a walk goes on: [`REACH_FOOTPRINTS`] of the
/// largest texel footprint in the box (footprints grow with depth, so it is at a corner the
/// camera sees). Where the geometry's surface is its box — the walls of a room — a ray meeting
/// one wall within a texel of an edge may cross the plane of the texel there, the other wall's,
/// just outside the box: a walk stopped at the box lost that hit (348 of 4 800 rays aimed next
/// to a room's edges; 17 with a margin of 2 footprints, none with this one).
pub(super) fn exit_margin(impostor: &Impostor) -> f32 {
    let b = impostor.bounds;
    let largest_footprint = (0..8)
        .map(|i| Vec3::select(BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), b.max, b.min))
        .filter_map(|corner| impostor.camera.project(corner.as_dvec3()))
        .map(|q| impostor.footprint(q.uv, q.gd))
        .filter(|f| f.is_finite())
        .fold(0.0f64, f64::max);
    (REACH_FOOTPRINTS * largest_footprint) as f32
}

/// The part of the segment `[c, e]` inside the camera's domain (`clip_distance ≥ 0`, affine in
/// the point, so cut where it crosses zero), or `None` when none of it is: a ray that starts
/// behind a pinhole impostor's near plane — a reflector inside the panorama of pinholes around
/// it — still meets what lies in front.
fn clip_to_domain<P: Projection>(camera: &P, c: DVec3, e: DVec3) -> Option<(DVec3, DVec3)> {
    let (dc, de) = (camera.clip_distance(c), camera.clip_distance(e));
    if dc >= 0.0 && de >= 0.0 {
        return Some((c, e));
    }
    if !(dc >= 0.0 || de >= 0.0) {
        return None;
    }
    // A hair inside the domain, so the cut end projects.
    let s = (dc / (dc - de)).clamp(0.0, 1.0);
    let cut = c + (e - c) * s;
    let inward = if dc < 0.0 { e - cut } else { c - cut };
    let cut = cut + inward * 1e-9;
    Some(if dc < 0.0 { (cut, e) } else { (c, cut) })
}

/// What a sampled walk asks of a camera: where a point lands. Every [`Projection`] answers it,
/// and so does a whole graph camera (through the frustum holding the point), which is not one.
trait ProjectPoint {
    fn land(&self, p: DVec3) -> Option<crate::camera::ImagePoint>;
}

impl<P: Projection> ProjectPoint for P {
    #[inline]
    fn land(&self, p: DVec3) -> Option<crate::camera::ImagePoint> {
        self.project(p)
    }
}

impl ProjectPoint for crate::camera::GraphCamera {
    #[inline]
    fn land(&self, p: DVec3) -> Option<crate::camera::ImagePoint> {
        crate::camera::GraphCamera::project(self, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pinhole;
    use glam::Vec3;

    #[test]
    fn segments_are_cut_where_they_enter_the_cameras_domain() {
        let cam = Pinhole::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 64)
            .unwrap()
            .with_near(0.1);
        let front = DVec3::new(0.2, 0.1, -3.0);
        let behind = DVec3::new(-0.1, 0.0, 2.0);
        // Wholly in front: unchanged. Wholly behind: nothing.
        assert_eq!(
            clip_to_domain(&cam, front, front * 2.0),
            Some((front, front * 2.0))
        );
        assert_eq!(clip_to_domain(&cam, behind, behind * 2.0), None);
        // Across the near plane, either way round: the part in front, which projects.
        for (a, b) in [(behind, front), (front, behind)] {
            let (c, e) = clip_to_domain(&cam, a, b).unwrap();
            let kept = if a == front { c } else { e };
            assert_eq!(kept, front);
            let cut = if a == front { e } else { c };
            assert!(cam.clip_distance(cut) >= 0.0 && cam.clip_distance(cut) < 1e-6);
            // On the segment.
            let along = (cut - a).cross(b - a).length();
            assert!(along < 1e-9, "{cut} is off the segment");
            assert!(cam.project(c).is_some() && cam.project(e).is_some());
        }
    }
}
