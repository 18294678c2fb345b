//! Fidelity of an impostor against the exact BVH (paper 1 §4 and Fig. 6–7): fire a set
//! of rays at an object, compare every impostor answer with the BVH's, and measure how much of
//! the surface the impostor captured.
//!
//! The rays: a reflector's reflected rays (paper 1's setting), rays from a sphere around the
//! object, or — for an impostor baked earlier — rays from the region around its viewpoint.
//!
//! Agreement of one ray: both miss, or both hit with positions within 1.5 texel footprints (the
//! footprint of the impostor texel at the exact hit).

use crate::camera::{Pinhole, Projection};
use crate::geom::{Mesh, Ray};
use crate::impostor::Impostor;
use crate::trace::{Bvh, RayQuery};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

pub use crate::impostor::AGREEMENT_FOOTPRINTS;

/// What [`check`] measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FidelityReport {
    /// Rays fired.
    pub rays: usize,
    /// Rays the BVH says hit.
    pub exact_hits: usize,
    /// Rays the impostor says hit.
    pub impostor_hits: usize,
    /// Rays where both agree (both miss, or both hit within 1.5 footprints).
    pub agreeing: usize,
    /// Rays the BVH hits that the impostor misses.
    pub missed: usize,
    /// Of those, the rays whose exact hit the impostor does not hold ([`holds`] is false: its
    /// texel stores another surface, or none, or the point is outside the image) — a limit of
    /// the camera; the others are misses of the walk.
    pub missed_unheld: usize,
    /// Rays the impostor hits that the BVH misses.
    pub spurious: usize,
    /// Mean distance between impostor and exact hit points, over rays both hit (world units).
    pub mean_position_error: f64,
    /// The same, in texel footprints.
    pub mean_error_footprints: f64,
    /// Median of that error, in texel footprints: the typical hit, which the mean's few far
    /// hits (another surface, on the rays that disagree) do not move.
    pub median_error_footprints: f64,
    /// Mean texel visits per ray.
    pub texel_visits_per_ray: f64,
}

impl FidelityReport {
    /// Fraction of rays that agree.
    pub fn agreement(&self) -> f64 {
        self.agreeing as f64 / self.rays.max(1) as f64
    }
    /// Fraction of the rays either method says hit on which they agree (stricter: ignores the
    /// easy rays both miss).
    pub fn hit_agreement(&self) -> f64 {
        let either = self.exact_hits + self.spurious;
        let both_ok = self.agreeing - (self.rays - either);
        both_ok as f64 / either.max(1) as f64
    }
}

/// Compares the impostor's answer to every ray (its default walk, [`Impostor::walk`]) with the
/// exact answer of `exact`.
pub fn check(impostor: &Impostor, exact: &Bvh, rays: &[Ray]) -> FidelityReport {
    check_by(impostor, exact, rays, false, |r| {
        impostor.walk(r, f32::INFINITY)
    })
    .0
}

/// How one ray's answers disagree, and where (`impostor check --misses`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Disagreement {
    /// The BVH hits here; the impostor misses.
    Missed(Vec3),
    /// Both hit, too far apart: the exact hit.
    Placed(Vec3),
    /// Only the impostor hits, here.
    Spurious(Vec3),
}

/// [`check`], with every ray that does not agree, in the rays' order.
pub fn check_disagreements(
    impostor: &Impostor,
    exact: &Bvh,
    rays: &[Ray],
) -> (FidelityReport, Vec<Disagreement>) {
    check_by(impostor, exact, rays, true, |r| {
        impostor.walk(r, f32::INFINITY)
    })
}

/// [`check`] with a chosen walk ([`Impostor::walk_mode`]).
pub fn check_with(
    impostor: &Impostor,
    exact: &Bvh,
    rays: &[Ray],
    mode: crate::impostor::WalkMode,
) -> FidelityReport {
    check_by(impostor, exact, rays, false, |r| {
        impostor.walk_mode(r, f32::INFINITY, mode)
    })
    .0
}

/// The comparison itself; `keep` also lists the rays that disagree.
fn check_by<W>(
    impostor: &Impostor,
    exact: &Bvh,
    rays: &[Ray],
    keep: bool,
    walk: W,
) -> (FidelityReport, Vec<Disagreement>)
where
    W: Fn(&Ray) -> (Option<crate::trace::Hit>, crate::impostor::WalkStats) + Sync,
{
    #[derive(Default, Clone, Copy)]
    struct One {
        exact: bool,
        imp: bool,
        agree: bool,
        err: f64,
        err_fp: f64,
        visits: u64,
        unheld: bool,
        disagreement: Option<Disagreement>,
    }
    impostor.prepare_walks();
    let per_ray: Vec<One> = rays
        .par_iter()
        .map(|r| {
            let e = exact.closest_hit(r, f32::INFINITY);
            let (i, stats) = walk(r);
            let mut one = One {
                exact: e.is_some(),
                imp: i.is_some(),
                visits: stats.texel_visits,
                ..One::default()
            };
            match (e, i) {
                (None, None) => one.agree = true,
                (Some(e), Some(i)) => {
                    let err = e.position.distance(i.position) as f64;
                    let fp = impostor.footprint_of(e.position);
                    one.err = err;
                    one.err_fp = err / fp;
                    one.agree = err <= AGREEMENT_FOOTPRINTS * fp;
                    if !one.agree {
                        one.disagreement = Some(Disagreement::Placed(e.position));
                    }
                }
                (Some(e), None) => {
                    one.unheld = !holds(impostor, e.position).within_footprint;
                    one.disagreement = Some(Disagreement::Missed(e.position));
                }
                (None, Some(i)) => one.disagreement = Some(Disagreement::Spurious(i.position)),
            }
            one
        })
        .collect();
    let both: Vec<&One> = per_ray.iter().filter(|o| o.exact && o.imp).collect();
    let mut errors_fp: Vec<f64> = both.iter().map(|o| o.err_fp).collect();
    errors_fp.sort_by(f64::total_cmp);
    let disagreements = if keep {
        per_ray.iter().filter_map(|o| o.disagreement).collect()
    } else {
        Vec::new()
    };
    let report = FidelityReport {
        rays: rays.len(),
        exact_hits: per_ray.iter().filter(|o| o.exact).count(),
        impostor_hits: per_ray.iter().filter(|o| o.imp).count(),
        agreeing: per_ray.iter().filter(|o| o.agree).count(),
        missed: per_ray.iter().filter(|o| o.exact && !o.imp).count(),
        missed_unheld: per_ray.iter().filter(|o| o.unheld).count(),
        spurious: per_ray.iter().filter(|o| !o.exact && o.imp).count(),
        mean_position_error: both.iter().map(|o| o.err).sum::<f64>() / both.len().max(1) as f64,
        mean_error_footprints: errors_fp.iter().sum::<f64>() / both.len().max(1) as f64,
        median_error_footprints: median(&errors_fp),
        texel_visits_per_ray: per_ray.iter().map(|o| o.visits as f64).sum::<f64>()
            / rays.len().max(1) as f64,
    };
    (report, disagreements)
}

/// The middle of sorted `values` (the mean of the two middle ones for an even count; 0 for
/// none). Also `trompe bench --goal`'s median of its runs' ratios.
pub fn median(values: &[f64]) -> f64 {
    match values.len() {
        0 => 0.0,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// Reflected rays of a reflector: `view` looks at `reflector`; every pixel whose ray hits it
/// spawns the mirror ray about the shading normal (paper 1's setting: the reflector's
/// secondary rays look up the impostor). Refused when the reflector's BVH would pass the
/// memory budget.
pub fn reflected_rays(
    view: &Pinhole,
    reflector: Arc<Mesh>,
) -> Result<Vec<Ray>, crate::memory::OverBudget> {
    let bvh = Bvh::build(vec![reflector.clone()])?;
    let eps = reflector.bounds().radius() * 1e-4;
    let (w, h) = view.resolution();
    let primary: Vec<(Ray, f32)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let r = view.ray(crate::frame::pixel_centre((i % w) as f64, (i / w) as f64));
            (r, f32::INFINITY)
        })
        .collect();
    let mut hits = Vec::new();
    bvh.closest_hits(&primary, &mut hits);
    Ok((primary.iter().zip(&hits))
        .filter_map(|((r, _), hit)| Some(hit.as_ref()?.mirror_ray(r, eps)))
        .collect())
}

pub use crate::geom::sphere_rays;

/// Rays from the region an impostor serves: `count` rays from points spread over the sphere of
/// radius `region` around its camera's viewpoint ([`crate::impostor::ImpostorCamera::viewpoint`]), each
/// aimed at a point of `target` (the object's box). These are the rays a baked impostor was
/// built to answer: the SPOC's strength is chosen for secondary rays from such a region (§3.2).
pub fn viewpoint_rays(
    impostor: &Impostor,
    region: f32,
    target: crate::geom::Aabb,
    count: usize,
    seed: u64,
) -> Vec<Ray> {
    let eye = impostor.camera().viewpoint().as_vec3();
    sphere_rays(eye, region, target, count, seed)
}

/// How much of a mesh's surface an impostor stores (fractions of area-weighted samples).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceCapture {
    /// Samples whose texel holds a point within 1.5 footprints of them (the footprint measured
    /// across the line of sight, as in the ray agreement test).
    pub within_footprint: f64,
    /// Samples whose texel holds a point within 1.5 times the texel's extent on the stored
    /// surface — the footprint stretched by 1/cos θ (at most 20×) on a plane seen at θ from its
    /// normal. A texel on a grazing surface covers that much of it.
    pub within_texel: f64,
}

/// Whether an impostor holds one surface point, by the two measures of [`SurfaceCapture`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Held {
    /// The texel the point projects to stores a point within 1.5 footprints of it (the
    /// footprint across the line of sight).
    pub within_footprint: bool,
    /// … within 1.5 times the texel's extent on the stored surface.
    pub within_texel: bool,
}

/// Whether the impostor holds the surface point `p` in any of its layers ([`Held`]; neither
/// when `p` is outside the camera's image or its texel is empty in every layer).
pub fn holds(impostor: &Impostor, p: Vec3) -> Held {
    impostor
        .layers()
        .map(|layer| layer_holds(layer, p))
        .fold(Held::default(), |a, b| Held {
            within_footprint: a.within_footprint || b.within_footprint,
            within_texel: a.within_texel || b.within_texel,
        })
}

/// [`holds`] for one layer.
fn layer_holds(impostor: &Impostor, p: Vec3) -> Held {
    let Some(q) = impostor.camera().project(p.as_dvec3()) else {
        return Held::default();
    };
    let Some((x, y)) = impostor.texel(q.uv) else {
        return Held::default();
    };
    if impostor.gd().get(x, y) <= 0.0 {
        return Held::default();
    }
    let stored = impostor.position_at(x, y);
    let distance = stored.distance(p) as f64;
    let footprint = impostor.footprint(q.uv, q.gd);
    let n = impostor.face_normal_at(x, y).as_dvec3();
    let view = impostor
        .camera()
        .toward_camera_along_ray(q.uv, q.gd, stored.as_dvec3());
    let cos = n.dot(view).abs().max(0.05);
    Held {
        within_footprint: distance <= AGREEMENT_FOOTPRINTS * footprint,
        within_texel: distance <= AGREEMENT_FOOTPRINTS * footprint / cos,
    }
}

/// How much of `mesh`'s surface the impostor stores ([`SurfaceCapture`]), from `samples`
/// area-weighted points.
pub fn surface_captured(
    impostor: &Impostor,
    mesh: &Mesh,
    samples: usize,
    seed: u64,
) -> SurfaceCapture {
    let points = crate::geom::sample_surface(mesh, samples, seed);
    let per_point: Vec<Held> = points.par_iter().map(|p| holds(impostor, *p)).collect();
    let total = points.len().max(1) as f64;
    SurfaceCapture {
        within_footprint: per_point.iter().filter(|h| h.within_footprint).count() as f64 / total,
        within_texel: per_point.iter().filter(|h| h.within_texel).count() as f64 / total,
    }
}

/// The paper's setting (Fig. 1, 6–7): a target object, a reflector beside it, and a viewer who
/// sees the target in the reflector. Everything in world space.
pub struct ReflectorSetup {
    /// The object replaced by an impostor (largest extent 1, resting on `y = 0` at the origin).
    pub target: Arc<Mesh>,
    /// The reflector (largest extent 0.8, along `+x`).
    pub reflector: Arc<Mesh>,
    /// The viewer, looking at the reflector from `+z`.
    pub view: Pinhole,
}

/// Refuses a mesh that cannot be placed: one with no finite, non-zero extent.
fn has_extent(meshes: &[&Mesh]) -> Result<(), crate::camera::CameraError> {
    for m in meshes {
        let e = m.bounds().extent().max_element();
        if !(e.is_finite() && e > 0.0) {
            return Err(crate::camera::CameraError::Degenerate(
                "a mesh with no extent cannot be placed",
            ));
        }
    }
    Ok(())
}

fn fit(mesh: &Mesh, size: f32, at: Vec3) -> Mesh {
    let b = mesh.bounds();
    let s = size / b.extent().max_element().max(f32::MIN_POSITIVE);
    let base = Vec3::new(b.center().x, b.min.y, b.center().z);
    mesh.transformed(
        &(glam::Mat4::from_translation(at)
            * glam::Mat4::from_scale(Vec3::splat(s))
            * glam::Mat4::from_translation(-base)),
    )
}

impl ReflectorSetup {
    /// Places `target` and `reflector` (its centre `distance` units along `+x`; 1.1 puts the
    /// two 0.25 apart) and a `view_size²` viewer.
    pub fn new(
        target: &Mesh,
        reflector: &Mesh,
        distance: f32,
        view_size: u32,
    ) -> Result<Self, crate::camera::CameraError> {
        has_extent(&[target, reflector])?;
        let target = Arc::new(fit(target, 1.0, Vec3::ZERO));
        let reflector = Arc::new(fit(reflector, 0.8, Vec3::new(distance, 0.0, 0.0)));
        Self::viewed(target, reflector, 1.0, view_size)
    }

    /// The setting with a viewer looking at the reflector from `scale · (−1.4, 0.4, 1.6)` off
    /// its centre.
    fn viewed(
        target: Arc<Mesh>,
        reflector: Arc<Mesh>,
        scale: f32,
        view_size: u32,
    ) -> Result<Self, crate::camera::CameraError> {
        let rc = reflector.bounds().center();
        let view = Pinhole::look_at(
            rc + Vec3::new(-1.4, 0.4, 1.6) * scale,
            rc,
            Vec3::Y,
            30.0,
            view_size,
            view_size,
        )?;
        Ok(Self {
            target,
            reflector,
            view,
        })
    }

    /// The same setting in `target`'s own coordinates: `target` is kept as it is; with `s` its
    /// largest extent, the reflector is scaled to `0.8 s` and rests on the plane of the
    /// target's lowest point, its centre `distance · s` along `+x` from the target's centre;
    /// the viewer looks at it from `s · (−1.4, 0.4, 1.6)` off its centre. It is [`Self::new`]'s
    /// setting scaled by `s` and moved onto the target.
    pub fn beside(
        target: &Mesh,
        reflector: &Mesh,
        distance: f32,
        view_size: u32,
    ) -> Result<Self, crate::camera::CameraError> {
        has_extent(&[target, reflector])?;
        let b = target.bounds();
        let s = b.extent().max_element();
        let base = Vec3::new(b.center().x, b.min.y, b.center().z);
        let at = base + Vec3::new(distance * s, 0.0, 0.0);
        let reflector = Arc::new(fit(reflector, 0.8 * s, at));
        Self::viewed(Arc::new(target.clone()), reflector, s, view_size)
    }

    /// Paper 1's Fig. 5 setting: the reflector (largest extent 0.5) stands on the floor of the
    /// maze's first corridor, two cells in, and the viewer looks at it from 2.5 cells outside
    /// the entrance. The target is the maze itself, in its own coordinates.
    pub fn in_maze(
        maze: &crate::scene::maze::Maze,
        reflector: &Mesh,
        view_size: u32,
    ) -> Result<Self, crate::camera::CameraError> {
        has_extent(&[reflector])?;
        // The viewer stands 2.5 cells outside the entrance, wherever the camera's root is.
        let (root, dir) = maze.entrance_view();
        let entrance = root + dir * crate::scene::maze::ROOT_BACK;
        let (eye, at) = (entrance - dir * 2.5, entrance + dir * 2.0);
        let reflector = Arc::new(fit(
            reflector,
            0.5,
            Vec3::new(at.x as f32, 0.0, at.z as f32),
        ));
        let view = Pinhole::look_at(
            eye.as_vec3(),
            reflector.bounds().center(),
            Vec3::Y,
            25.0,
            view_size,
            view_size,
        )?;
        Ok(Self {
            target: Arc::new(maze.mesh()),
            reflector,
            view,
        })
    }

    /// The reflected rays of the viewer's pixels that see the reflector, kept when they enter
    /// the target's bounding box (the only rays an impostor is ever asked about).
    pub fn rays(&self) -> Result<Vec<Ray>, crate::memory::OverBudget> {
        self.rays_seen_by(&self.view)
    }

    /// Rays like [`Self::rays`] but none of them: those a second viewer sees, standing where
    /// the viewer's reflection in the reflector's `z` plane would, at the viewer's resolution
    /// or 1024² if more.
    /// What a SPOC's strength is chosen on ([`crate::impostor::choose_strength`]).
    pub fn held_out_rays(&self) -> Result<Vec<Ray>, crate::memory::OverBudget> {
        let rc = self.reflector.bounds().center();
        let offset = self.view.position().as_vec3() - rc;
        let (w, h) = self.view.resolution();
        let second = Pinhole::look_at(
            rc + offset * Vec3::new(1.0, 1.0, -1.0),
            rc,
            Vec3::Y,
            30.0,
            w.max(1024),
            h.max(1024),
        );
        match second {
            Ok(view) => self.rays_seen_by(&view),
            Err(_) => Ok(Vec::new()),
        }
    }

    fn rays_seen_by(&self, view: &Pinhole) -> Result<Vec<Ray>, crate::memory::OverBudget> {
        let b = self.target.bounds();
        Ok(reflected_rays(view, self.reflector.clone())?
            .into_iter()
            .filter(|r| b.intersect(r, f32::INFINITY).is_some())
            .collect())
    }

    /// An impostor camera at the reflector's centre looking at the target, framed tightly on
    /// it ([`crate::impostor::ImpostorCamera::fitted`]), `size²` texels; the SPOC strength follows from
    /// the reflector's radius (the region of the rays).
    pub fn camera(
        &self,
        kind: crate::impostor::ViewCamera,
        size: u32,
    ) -> Result<crate::impostor::ImpostorCamera, crate::camera::CameraError> {
        let (eye, tb) = (self.reflector.bounds().center(), self.target.bounds());
        let region = self.reflector.bounds().radius() as f64;
        crate::impostor::ImpostorCamera::fitted(
            kind,
            eye,
            tb.center(),
            tb.radius(),
            region,
            size,
            &self.target.positions,
        )
    }
}
