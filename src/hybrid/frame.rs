//! One frame of hybrid reflections (paper 2 §3.2, §5–6): the G-buffer, a C3RC per reflector
//! triangle the eye sees, kd-tree culling, projection and splatting, then the Whitted tracer
//! shading the G-buffer with the splats answering first reflections.
//!
//! Invariants: a splat lands only on pixels where the eye sees the splatting reflector at the
//! depth of the image point (2 % slack), so hidden parts of a reflector show nothing; each pixel
//! keeps the point with the smallest unfolded path `|p − E| + |Q − p|` (the paper's push-back),
//! ties broken by point index, so the frame is the same for any thread count.

use super::HybridReflections;
use super::plan::{DEPTH_SLACK, KeptNode, Placement, ReflectorCamera, SplatPlan, is_reflector};
use crate::camera::{Pinhole, Projection};
use crate::frame::{Frame, Image, NO_OBJECT};
use crate::geom::Ray;
use crate::progress::Progress;
use crate::render::shading::{lambert, lit};
use crate::render::{RenderError, Tracer, shade_pixels};
use crate::scene::Scene;
use crate::trace::{Bvh, Exact, Hit, RayQuery, SecondaryQuery};
use glam::{DVec3, Mat3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Bytes a pixel costs in a hybrid frame beyond a traced one: the G-buffer hit, the splat key,
/// the resolved radiance.
pub const BYTES_PER_PIXEL: u64 = 128;

/// What one frame did (paper 2 Table 2's columns, and more).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// C3RCs built: reflector triangles the eye sees.
    pub c3rcs: u64,
    /// kd-tree nodes tested against view volumes.
    pub nodes_tested: u64,
    /// Nodes kept: leaves, or inner nodes the level of detail reads thinned.
    pub leaves_kept: u64,
    /// Points projected (each point read from a kept node, once per C3RC).
    pub points_projected: u64,
    /// Valid projections found.
    pub projections: u64,
    /// Distinct points with at least one valid projection.
    pub points_seen: u64,
    /// Projections that reached a pixel where the reflector is seen.
    pub splats: u64,
    /// Pixels whose reflection a point of a diffuse object gave.
    pub pixels_splatted: u64,
    /// Splatted pixels whose reflected ray meets a mirror or glass before the point, traced
    /// exactly.
    pub pixels_traced: u64,
    /// Pixels where the eye sees a reflector.
    pub reflector_pixels: u64,
    /// Wall time of the G-buffer (primary rays).
    #[serde(serialize_with = "crate::progress::serialize_seconds")]
    pub gbuffer: Duration,
    /// Wall time of the culling.
    #[serde(serialize_with = "crate::progress::serialize_seconds")]
    pub cull: Duration,
    /// Wall time of the projection and splatting.
    #[serde(serialize_with = "crate::progress::serialize_seconds")]
    pub project: Duration,
    /// Wall time of shading.
    #[serde(serialize_with = "crate::progress::serialize_seconds")]
    pub shade: Duration,
    /// Wall time of the BVH build.
    #[serde(serialize_with = "crate::progress::serialize_seconds")]
    pub bvh: Duration,
}

impl FrameStats {
    /// Share of projected points with a valid projection (paper: about 20 %).
    pub fn valid_ratio(&self) -> f64 {
        self.projections as f64 / self.points_projected.max(1) as f64
    }

    /// Valid projections per point that has one (paper: about 4 on the teapot).
    pub fn projections_per_point(&self) -> f64 {
        self.projections as f64 / self.points_seen.max(1) as f64
    }

    /// Culling plus projection: the reflection's own cost.
    pub fn reflection_time(&self) -> Duration {
        self.cull + self.project
    }

    /// The frame's wall time.
    pub fn total(&self) -> Duration {
        self.bvh + self.gbuffer + self.cull + self.project + self.shade
    }
}

impl std::fmt::Display for FrameStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        writeln!(
            f,
            "C3RCs {}, nodes tested {}, nodes kept {}",
            self.c3rcs, self.nodes_tested, self.leaves_kept
        )?;
        writeln!(
            f,
            "points projected {}, valid projections {} ({:.1} %), {:.2} a point seen, splats {}",
            self.points_projected,
            self.projections,
            100.0 * self.valid_ratio(),
            self.projections_per_point(),
            self.splats
        )?;
        writeln!(
            f,
            "reflector pixels {}, reached by a point {} ({:.1} %), of which a mirror hides {}",
            self.reflector_pixels,
            self.pixels_splatted,
            100.0 * self.pixels_splatted as f64 / self.reflector_pixels.max(1) as f64,
            self.pixels_traced
        )?;
        write!(
            f,
            "BVH {:.1} ms, G-buffer {:.1} ms, culling {:.1} ms, projection {:.1} ms, shading {:.1} ms",
            ms(self.bvh),
            ms(self.gbuffer),
            ms(self.cull),
            ms(self.project),
            ms(self.shade)
        )
    }
}

/// A rendered frame, what it cost, and what each pixel's reflection came from.
#[derive(Clone, Debug)]
pub struct HybridFrame {
    /// The frame.
    pub frame: Frame,
    /// What it did.
    pub stats: FrameStats,
    /// Per pixel, the object whose point the splats put there ([`NO_OBJECT`] where none did:
    /// not a reflector, or the environment shows).
    pub reached: Image<u32>,
    /// Per pixel, the point whose splat won it, in the plan's numbering
    /// ([`Placement::offsets`]; [`NO_OBJECT`] where none did).
    pub winners: Image<u32>,
}

/// Renders `scene` at time `t` with the hybrid method over `clouds`.
pub fn render_frame(
    clouds: &HybridReflections,
    scene: &Scene,
    t: f32,
    progress: &dyn Progress,
) -> Result<HybridFrame, RenderError> {
    render_frame_from(clouds, scene, t, None, progress)
}

/// [`render_frame`] seen through `camera` instead of the scene's, when given (an interactive
/// viewer's, a pinhole: the scene camera's lens is not used).
pub fn render_frame_from(
    clouds: &HybridReflections,
    scene: &Scene,
    t: f32,
    camera: Option<crate::camera::Pinhole>,
    progress: &dyn Progress,
) -> Result<HybridFrame, RenderError> {
    if !t.is_finite() {
        return Err(RenderError::Time(t));
    }
    let mut view = scene.view(t)?;
    if let Some(camera) = camera {
        // A pinhole: the scene camera's lens goes with it.
        view.camera = camera;
        view.lens = None;
    }
    // Deforming objects' points follow their surface this frame.
    let deformed = clouds.deformed_at(scene, t);
    let clouds = deformed.as_ref().unwrap_or(clouds);
    crate::render::check_memory(&view, crate::render::Method::Trace)?;
    let (w, h) = view.camera.resolution();
    crate::memory::check(
        || format!("a {w} × {h} hybrid frame"),
        crate::memory::times(u64::from(w) * u64::from(h), BYTES_PER_PIXEL),
    )?;
    crate::render::check_finite(&view)?;
    let mut stats = FrameStats::default();
    let start = Instant::now();
    let bvh = Bvh::build(view.meshes.clone())?;
    stats.bvh = start.elapsed();

    let start = Instant::now();
    let camera = &view.camera;
    let gbuffer: Vec<Option<Hit>> = (0..h as usize)
        .into_par_iter()
        .flat_map_iter(|y| {
            let bvh = &bvh;
            (0..w as usize).map(move |x| {
                let ray = camera.ray(crate::frame::pixel_centre(x as f64, y as f64));
                bvh.closest_hit(&ray, f32::INFINITY)
            })
        })
        .collect();
    stats.gbuffer = start.elapsed();

    stats.reflector_pixels = gbuffer
        .iter()
        .flatten()
        .filter(|h| is_reflector(&view.surfaces[h.object as usize]))
        .count() as u64;
    let splat_size = clouds.settings.splat.clamp(1, 2);
    let start = Instant::now();
    let seen = super::plan::seen_reflectors(
        &view,
        gbuffer.iter().flatten().map(|h| (h.object, h.triangle)),
    );
    let plan = SplatPlan::new(clouds, scene, &view, t, &seen, splat_size);
    stats.cull = start.elapsed();
    stats.c3rcs = plan.cameras.len() as u64;
    stats.leaves_kept = plan.nodes_kept();
    stats.nodes_tested = plan.nodes_tested;

    let start = Instant::now();
    let keys: Vec<AtomicU64> = (0..gbuffer.len())
        .map(|_| AtomicU64::new(u64::MAX))
        .collect();
    let total_points = clouds.point_count();
    let seen: Vec<AtomicU64> = (0..total_points.div_ceil(64))
        .map(|_| AtomicU64::new(0))
        .collect();
    let splat = Splat {
        camera,
        gbuffer: &gbuffer,
        keys: &keys,
        seen: &seen,
        size: splat_size,
    };
    let counts = plan
        .cameras
        .par_iter()
        .map(|cam| project(cam, clouds, &plan.placement, &splat))
        .reduce(|| [0u64; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
    stats.points_projected = counts[0];
    stats.projections = counts[1];
    stats.splats = counts[2];
    stats.points_seen = seen
        .iter()
        .map(|b| u64::from(b.load(Ordering::Relaxed).count_ones()))
        .sum();
    stats.project = start.elapsed();

    let start = Instant::now();
    let placed = &plan.placement;
    let placements = &placed.world;
    let normal_from_object: Vec<Mat3> = placements
        .iter()
        .map(|m| Mat3::from_mat4(m.as_mat4()).inverse().transpose())
        .collect();
    let radiance: Vec<Reflected> = keys
        .par_iter()
        .zip(&gbuffer)
        .map(|(key, hit)| {
            let key = key.load(Ordering::Relaxed);
            let Some(hit) = hit.as_ref() else {
                return Reflected::Nothing;
            };
            if key == u64::MAX {
                return Reflected::Nothing;
            }
            let (c, i) = placed.locate((key & 0xFFFF_FFFF) as u32);
            let cloud = &clouds.clouds[c];
            let q = placements[c].transform_point3(cloud.points.positions[i].as_dvec3());
            let mut n = (normal_from_object[c] * cloud.points.normals[i]).normalize_or_zero();
            // Lit on the side the reflector sees it from.
            if n.dot(hit.position - q.as_vec3()) < 0.0 {
                n = -n;
            }
            Reflected::Point(
                lambert(cloud.points.albedo[i], n, &scene.lighting, |l| {
                    lit(&bvh, q.as_vec3(), n, l, scene.render.ray_epsilon)
                }),
                (q.as_vec3() - hit.position).length(),
            )
        })
        .collect();
    stats.pixels_splatted = radiance
        .iter()
        .filter(|r| matches!(r, Reflected::Point(..)))
        .count() as u64;

    let mirrors = match clouds.settings.mirrors_occlude {
        true => Some(Bvh::build(
            view.meshes
                .iter()
                .zip(&view.surfaces)
                .filter(|(_, s)| is_reflector(s))
                .map(|(m, _)| m.clone())
                .collect(),
        )?),
        false => None,
    };
    let answers = SplatAnswers {
        camera,
        width: w,
        gbuffer: &gbuffer,
        radiance: &radiance,
        mirrors,
        hidden: AtomicU64::new(0),
        exact: Exact(&bvh),
        epsilon: scene.render.ray_epsilon,
    };
    let tracer = Tracer {
        view: &view,
        primary: &bvh,
        secondary: &answers,
        lighting: &scene.lighting,
        settings: &scene.render,
    };
    let frame = shade_pixels(&tracer, progress, |pixel, _| gbuffer[pixel])?;
    stats.shade = start.elapsed();
    stats.pixels_traced = answers.hidden.load(Ordering::Relaxed);
    let reached = Image::from_vec(
        w,
        h,
        keys.iter()
            .map(|k| {
                let k = k.load(Ordering::Relaxed);
                if k == u64::MAX {
                    return NO_OBJECT;
                }
                clouds.clouds[placed.locate((k & 0xFFFF_FFFF) as u32).0].object
            })
            .collect(),
    )?;
    let winners = Image::from_vec(
        w,
        h,
        keys.iter()
            .map(|k| match k.load(Ordering::Relaxed) {
                u64::MAX => NO_OBJECT,
                k => (k & 0xFFFF_FFFF) as u32,
            })
            .collect(),
    )?;
    Ok(HybridFrame {
        frame,
        stats,
        reached,
        winners,
    })
}

/// Where splats go and what they are tested against.
struct Splat<'a> {
    camera: &'a Pinhole,
    gbuffer: &'a [Option<Hit>],
    keys: &'a [AtomicU64],
    /// One bit a point: has it a valid projection?
    seen: &'a [AtomicU64],
    size: u32,
}

/// Projects the points of `leaves` through `cam` and splats them; returns points projected,
/// valid projections and accepted splats.
fn project(
    cam: &ReflectorCamera,
    clouds: &HybridReflections,
    placed: &Placement,
    splat: &Splat,
) -> [u64; 3] {
    let Placement {
        world: placements,
        inverse,
        offsets,
        ..
    } = placed;
    let (w, h) = splat.camera.resolution();
    let eye = splat.camera.position();
    let mut counts = [0u64; 3];
    let mut local = None;
    for &KeptNode {
        cloud: c,
        node,
        stride,
    } in &cam.nodes
    {
        let cloud = &clouds.clouds[c as usize];
        if local.map(|(lc, _)| lc) != Some(c) {
            local = Some((c, cam.local(&inverse[c as usize])));
        }
        let Some((_, lcam)) = local else { continue };
        let node = &cloud.tree.nodes[node as usize];
        for i in (node.points.0..node.points.0 + node.points.1).step_by(stride.max(1) as usize) {
            counts[0] += 1;
            let q = cloud.points.positions[i as usize].as_dvec3();
            let global = offsets[c as usize] + i;
            lcam.project_each(q, cam.lambda_max, |pr| {
                counts[1] += 1;
                splat.seen[global as usize / 64].fetch_or(1 << (global % 64), Ordering::Relaxed);
                let p: DVec3 = (0..3).map(|k| cam.world.v[k] * pr.bary[k]).sum();
                let qw = placements[c as usize].transform_point3(q);
                let to_p = (p - eye).length();
                let key_len = (to_p + (qw - p).length()) as f32;
                let Some(ip) = splat.camera.project(p) else {
                    return;
                };
                let (x0, y0) = if splat.size == 1 {
                    (ip.uv.x.floor(), ip.uv.y.floor())
                } else {
                    ((ip.uv.x - 0.5).floor(), (ip.uv.y - 0.5).floor())
                };
                let key = (u64::from(key_len.to_bits()) << 32) | u64::from(global);
                for dy in 0..splat.size {
                    for dx in 0..splat.size {
                        let (x, y) = (x0 + dx as f64, y0 + dy as f64);
                        if x < 0.0 || y < 0.0 || x >= w as f64 || y >= h as f64 {
                            continue;
                        }
                        let pix = y as usize * w as usize + x as usize;
                        let Some(seen) = &splat.gbuffer[pix] else {
                            continue;
                        };
                        if seen.object != cam.object
                            || (seen.t - to_p as f32).abs() > DEPTH_SLACK * to_p as f32
                        {
                            continue;
                        }
                        counts[2] += 1;
                        splat.keys[pix].fetch_min(key, Ordering::Relaxed);
                    }
                }
            });
        }
    }
    counts
}

/// What a reflector pixel's splats resolved to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reflected {
    /// No point: the environment shows.
    Nothing,
    /// A diffuse point's radiance, and its distance from the pixel's surface point.
    Point(Vec3, f32),
}

/// Secondary rays answered by the splats where they are the eye's first reflection, exactly
/// through the BVH otherwise.
struct SplatAnswers<'a> {
    camera: &'a Pinhole,
    width: u32,
    gbuffer: &'a [Option<Hit>],
    radiance: &'a [Reflected],
    /// The mirrors and glass alone, when they hide points.
    mirrors: Option<Bvh>,
    /// Splatted pixels a mirror hid.
    hidden: AtomicU64,
    exact: Exact<'a, Bvh>,
    epsilon: f32,
}

impl SecondaryQuery for SplatAnswers<'_> {
    fn secondary_hit(&self, reflector: u32, ray: &Ray) -> Option<Hit> {
        let first = self.camera.project(ray.origin.as_dvec3()).and_then(|ip| {
            let (w, h) = self.camera.resolution();
            let (x, y) = (ip.uv.x.floor(), ip.uv.y.floor());
            if x < 0.0 || y < 0.0 || x >= f64::from(w) || y >= f64::from(h) {
                return None;
            }
            let pix = y as usize * self.width as usize + x as usize;
            let hit = self.gbuffer[pix].as_ref()?;
            let near = 2.0 * self.epsilon + 1e-6 * (1.0 + hit.position.length());
            (hit.object == reflector && (hit.position - ray.origin).length() <= near).then_some(pix)
        });
        match first {
            Some(pix) => match self.radiance[pix] {
                Reflected::Nothing => None,
                Reflected::Point(_, distance)
                    if self
                        .mirrors
                        .as_ref()
                        .is_some_and(|m| m.closest_hit(ray, distance).is_some()) =>
                {
                    self.hidden.fetch_add(1, Ordering::Relaxed);
                    self.exact.secondary_hit(reflector, ray)
                }
                Reflected::Point(l, _) => Some(Hit {
                    t: f32::INFINITY,
                    position: ray.dir,
                    normal: -ray.dir,
                    geometric_normal: -ray.dir,
                    uv: glam::Vec2::ZERO,
                    bary: glam::Vec2::ZERO,
                    object: crate::trace::ENVIRONMENT,
                    triangle: 0,
                    radiance: Some(l),
                }),
            },
            None => self.exact.secondary_hit(reflector, ray),
        }
    }
}
