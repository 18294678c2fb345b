//! One frame of hybrid reflections (paper 2 §3.2, §5–6): the G-buffer, a C3RC per reflector
//! triangle the eye sees, kd-tree culling, projection and splatting, then the Whitted tracer
//! shading the G-buffer with the splats answering first reflections.
//!
//! Invariants: a splat lands only on pixels where the eye sees the splatting reflector at the
//! depth of the image point (2 % slack), so hidden parts of a reflector show nothing; each pixel
//! keeps the point with the smallest unfolded path `|p − E| + |Q − p|` (the paper's push-back),
//! ties broken by point index, so the frame is the same for any thread count.

use super::HybridReflections;
use crate::camera::{C3rc, Pinhole, Projection};
use crate::frame::{Frame, Image, NO_OBJECT};
use crate::geom::Ray;
use crate::progress::Progress;
use crate::render::shading::{lambert, lit};
use crate::render::{RenderError, Tracer, shade_pixels};
use crate::scene::{Scene, Surface, View};
use crate::trace::{Bvh, Exact, Hit, RayQuery, SecondaryQuery};
use glam::{DMat4, DVec3, Mat3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Bytes a pixel costs in a hybrid frame beyond a traced one: the G-buffer hit, the splat key,
/// the resolved radiance.
pub const BYTES_PER_PIXEL: u64 = 128;

/// Relative depth slack between a splat's image point and the surface the eye sees there.
const DEPTH_SLACK: f32 = 0.02;

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
}

/// A reflector triangle's camera, with what splatting needs.
struct Camera3 {
    /// The reflector object.
    object: u32,
    /// World space.
    world: C3rc,
    /// Largest sweep parameter any diffuse point can have.
    lambda_max: f64,
    /// The reflector triangle's area on screen, pixels (0 when it cannot be projected).
    pixels: f64,
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

    let cameras = reflector_cameras(&view, &gbuffer, clouds);
    stats.c3rcs = cameras.len() as u64;
    stats.reflector_pixels = gbuffer
        .iter()
        .flatten()
        .filter(|h| is_reflector(&view.surfaces[h.object as usize]))
        .count() as u64;
    let placed = Placed::at(clouds, scene, t);

    let splat_size = clouds.settings.splat.clamp(1, 2);
    let start = Instant::now();
    let culled: Vec<(Vec<(u32, u32)>, u64)> = cameras
        .par_iter()
        .map(|cam| cull(cam, clouds, &placed, splat_size))
        .collect();
    stats.cull = start.elapsed();
    for (leaves, tested) in &culled {
        stats.leaves_kept += leaves.len() as u64;
        stats.nodes_tested += tested;
    }

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
    let counts = cameras
        .par_iter()
        .zip(&culled)
        .map(|(cam, (leaves, _))| project(cam, leaves, clouds, &placed, &splat))
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
    let (placements, offsets) = (&placed.world, &placed.offsets);
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
            let global = (key & 0xFFFF_FFFF) as u32;
            let c = offsets.partition_point(|&o| o <= global) - 1;
            let i = (global - offsets[c]) as usize;
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
                let global = (k & 0xFFFF_FFFF) as u32;
                clouds.clouds[offsets.partition_point(|&o| o <= global) - 1].object
            })
            .collect(),
    )?;
    Ok(HybridFrame {
        frame,
        stats,
        reached,
    })
}

fn is_reflector(s: &Surface) -> bool {
    !matches!(s, Surface::Diffuse(_))
}

/// One camera for every reflector triangle some pixel sees, in (object, triangle) order.
fn reflector_cameras(
    view: &View,
    gbuffer: &[Option<Hit>],
    clouds: &HybridReflections,
) -> Vec<Camera3> {
    let mut seen: Vec<Vec<bool>> = view
        .meshes
        .iter()
        .map(|m| vec![false; m.triangle_count()])
        .collect();
    for h in gbuffer.iter().flatten() {
        if is_reflector(&view.surfaces[h.object as usize]) {
            seen[h.object as usize][h.triangle as usize] = true;
        }
    }
    // The farthest any diffuse point can be from a reflector point: from the clouds' boxes.
    let corners: Vec<DVec3> = clouds
        .clouds
        .iter()
        .flat_map(|c| {
            let b = view.meshes[c.object as usize].bounds();
            (0..8).map(move |k| {
                DVec3::new(
                    if k & 1 == 0 { b.min.x } else { b.max.x } as f64,
                    if k & 2 == 0 { b.min.y } else { b.max.y } as f64,
                    if k & 4 == 0 { b.min.z } else { b.max.z } as f64,
                )
            })
        })
        .collect();
    let eye = view.camera.position();
    let mut out = Vec::new();
    for (o, flags) in seen.iter().enumerate() {
        let mesh = &view.meshes[o];
        for (tri, _) in flags.iter().enumerate().filter(|(_, s)| **s) {
            let idx = mesh.triangles[tri];
            let v = idx.map(|i| mesh.positions[i as usize].as_dvec3());
            let n = idx.map(|i| mesh.normals[i as usize].as_dvec3());
            let Some(world) = C3rc::reflector(v, n, eye) else {
                continue;
            };
            // |Q − p| ≤ max over the box corners of the distance to a vertex, and λ = |Q − p| /
            // |Σ bᵢ dᵢ|, whose smallest value is the distance from the origin to the triangle
            // of the dᵢ.
            let far = corners
                .iter()
                .map(|q| v.iter().map(|vi| (*q - *vi).length()).fold(0.0, f64::max))
                .fold(0.0, f64::max);
            let shortest = origin_to_triangle(world.d);
            let lambda_max = if shortest > 1e-6 {
                far / shortest * (1.0 + 1e-9)
            } else {
                f64::INFINITY
            };
            let screen = v.map(|p| view.camera.project(p).map(|ip| ip.uv));
            let pixels = match screen {
                [Some(a), Some(b), Some(c)] => 0.5 * (b - a).perp_dot(c - a).abs(),
                _ => 0.0,
            };
            out.push(Camera3 {
                object: o as u32,
                world,
                lambda_max,
                pixels,
            });
        }
    }
    out
}

/// The camera moved into an object's space (affine maps keep the sweep, its λ and barycentrics).
fn into_object(c: &C3rc, inverse: &DMat4) -> C3rc {
    C3rc {
        v: c.v.map(|p| inverse.transform_point3(p)),
        d: c.d.map(|d| inverse.transform_vector3(d)),
    }
}

/// The nodes `(cloud, node)` whose boxes the camera may see and whose points it reads: leaves,
/// or inner nodes whose points it needs so few of (a stride of a leaf's worth or more, see
/// [`stride`]) that reading them thinned beats descending; and the nodes tested.
fn cull(
    cam: &Camera3,
    clouds: &HybridReflections,
    placed: &Placed,
    splat: u32,
) -> (Vec<(u32, u32)>, u64) {
    let (inverse, scales) = (&placed.inverse, &placed.scales);
    let mut kept = Vec::new();
    let mut tested = 0u64;
    let leaf_points = clouds.settings.tree.leaf_points.max(1);
    let lod = clouds.settings.level_of_detail;
    for (c, cloud) in clouds.clouds.iter().enumerate() {
        if cloud.tree.nodes.is_empty() {
            continue;
        }
        let local = into_object(&cam.world, &inverse[c]);
        let mut stack = vec![0u32];
        while let Some(id) = stack.pop() {
            let node = &cloud.tree.nodes[id as usize];
            tested += 1;
            let (lo, hi) = (node.lo.as_dvec3(), node.hi.as_dvec3());
            if !local.may_see_box(lo, hi, cam.lambda_max) {
                continue;
            }
            let coarse = || {
                let step = stride(cam, &local, node, cloud.spacing, scales[c], splat, lod);
                (node.points.1 as usize).div_ceil(step) <= leaf_points
            };
            if node.leaf || coarse() {
                kept.push((c as u32, id));
            } else {
                stack.extend(node.first..node.first + node.count);
            }
        }
    }
    kept.sort_unstable();
    (kept, tested)
}

/// Where each cloud is this frame.
struct Placed {
    /// Object → world.
    world: Vec<DMat4>,
    /// World → object.
    inverse: Vec<DMat4>,
    /// World units per object unit.
    scales: Vec<f64>,
    /// Each cloud's first point in the frame's point numbering.
    offsets: Vec<u32>,
}

impl Placed {
    /// The clouds of `clouds` as `scene` places them at time `t`.
    fn at(clouds: &HybridReflections, scene: &Scene, t: f32) -> Placed {
        let world: Vec<DMat4> = clouds
            .clouds
            .iter()
            .map(|c| {
                scene.objects[c.object as usize]
                    .world_from_object_at(t)
                    .as_dmat4()
            })
            .collect();
        let offsets = clouds
            .clouds
            .iter()
            .scan(0u32, |acc, c| {
                let o = *acc;
                *acc += c.points.len() as u32;
                Some(o)
            })
            .collect();
        Placed {
            inverse: world.iter().map(|m| m.inverse()).collect(),
            scales: world.iter().map(mean_scale).collect(),
            world,
            offsets,
        }
    }
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
    cam: &Camera3,
    leaves: &[(u32, u32)],
    clouds: &HybridReflections,
    placed: &Placed,
    splat: &Splat,
) -> [u64; 3] {
    let Placed {
        world: placements,
        inverse,
        scales,
        offsets,
    } = placed;
    let (w, h) = splat.camera.resolution();
    let eye = splat.camera.position();
    let mut counts = [0u64; 3];
    let mut local = None;
    for &(c, node) in leaves {
        let cloud = &clouds.clouds[c as usize];
        if local.map(|(lc, _)| lc) != Some(c) {
            local = Some((c, into_object(&cam.world, &inverse[c as usize])));
        }
        let Some((_, lcam)) = local else { continue };
        let node = &cloud.tree.nodes[node as usize];
        let step = stride(
            cam,
            &lcam,
            node,
            cloud.spacing,
            scales[c as usize],
            splat.size,
            clouds.settings.level_of_detail,
        );
        for i in (node.points.0..node.points.0 + node.points.1).step_by(step) {
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

/// World units per object unit of a placement: its mean scale.
fn mean_scale(m: &DMat4) -> f64 {
    let (s, _, _) = m.to_scale_rotation_translation();
    (s.x.abs() * s.y.abs() * s.z.abs()).cbrt()
}

/// Points a splat's area should receive for the reflection to show no holes.
pub const POINTS_PER_SPLAT: f64 = 4.0;

/// Every how many points of `node` the camera needs (level of detail, beyond paper 2): a
/// surface of `spacing`-apart points facing the reflector at sweep `λ` puts about
/// `A(λ) / spacing²` points into the reflector triangle's `pixels`, where `A(λ) = |n(λ)|/2` is
/// the area of the sweeping triangle. Where that is more than [`POINTS_PER_SPLAT`] a splat, the
/// leaf is read with a stride. `A` is taken at its least over the node's sweep range,
/// `λ ≥` the distance from the triangle to the node's box (construction rays are unit, so
/// `|Σ bᵢ dᵢ| ≤ 1`); surfaces seen obliquely only hold more points. A sweep that folds
/// (`A` reaches 0) gets every point.
fn stride(
    cam: &Camera3,
    local: &C3rc,
    node: &super::kdtree::Node,
    spacing: f32,
    scale: f64,
    splat: u32,
    lod: bool,
) -> usize {
    if !lod || cam.pixels <= 0.0 || spacing.is_nan() || spacing <= 0.0 {
        return 1;
    }
    // Distance from the triangle's box to the node's box, in object space, then world.
    let (tlo, thi) = local.hull_box(0.0, 0.0);
    let gap = (node.lo.as_dvec3() - thi)
        .max(tlo - node.hi.as_dvec3())
        .max(DVec3::ZERO)
        .length();
    let lambda_lo = gap * scale;
    let area = cam.world.least_sweep_area(lambda_lo, cam.lambda_max);
    let per_pixel = area / (f64::from(spacing) * f64::from(spacing) * cam.pixels);
    let k = per_pixel * f64::from(splat * splat) / POINTS_PER_SPLAT;
    if k.is_finite() && k >= 2.0 {
        (k.floor() as usize).min(node.points.1 as usize).max(1)
    } else {
        1
    }
}

/// The distance from the origin to the triangle `t`.
fn origin_to_triangle(t: [DVec3; 3]) -> f64 {
    let (a, b, c) = (t[0], t[1], t[2]);
    let n = (b - a).cross(c - a);
    let mut best = a.length().min(b.length()).min(c.length());
    for (p, q) in [(a, b), (b, c), (c, a)] {
        let e = q - p;
        let s = (-p.dot(e) / e.length_squared().max(1e-300)).clamp(0.0, 1.0);
        best = best.min((p + e * s).length());
    }
    if n.length_squared() > 1e-300 {
        // The origin's foot on the plane, if inside the triangle.
        let foot = n * (a.dot(n) / n.length_squared());
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|(p, q)| (*q - *p).cross(foot - *p).dot(n) >= 0.0);
        if inside {
            best = best.min(foot.length());
        }
    }
    best
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hybrid::HybridSettings;

    #[test]
    fn culling_real_trees_drops_no_leaf_with_a_seen_point() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/c3rc-bunny.toml");
        let mut scene = Scene::load(&path).unwrap();
        (scene.camera.width, scene.camera.height) = (120, 80);
        let clouds = HybridReflections::prepare(&scene, HybridSettings::default()).unwrap();
        let view = scene.view(0.0).unwrap();
        let bvh = Bvh::build(view.meshes.clone()).unwrap();
        let gbuffer: Vec<Option<Hit>> = (0..80)
            .flat_map(|y| (0..120).map(move |x| (x, y)))
            .map(|(x, y)| {
                let ray = view
                    .camera
                    .ray(crate::frame::pixel_centre(x as f64, y as f64));
                bvh.closest_hit(&ray, f32::INFINITY)
            })
            .collect();
        let cameras = reflector_cameras(&view, &gbuffer, &clouds);
        assert!(cameras.len() > 100);
        let placed = Placed::at(&clouds, &scene, 0.0);
        let inverse = &placed.inverse;
        let (mut kept, mut dropped_leaves) = (0, 0);
        for cam in cameras.iter().step_by(7) {
            let (nodes, _) = cull(cam, &clouds, &placed, 2);
            kept += nodes.len();
            for (c, cloud) in clouds.clouds.iter().enumerate() {
                // The points the kept nodes read (thinned or not).
                let mut read = vec![false; cloud.points.len()];
                for &(_, id) in nodes.iter().filter(|(nc, _)| *nc == c as u32) {
                    let (first, count) = cloud.tree.nodes[id as usize].points;
                    read[first as usize..(first + count) as usize].fill(true);
                }
                let local = into_object(&cam.world, &inverse[c]);
                for node in cloud.tree.nodes.iter().filter(|n| n.leaf) {
                    if read[node.first as usize] {
                        continue;
                    }
                    dropped_leaves += 1;
                    for i in node.first..node.first + node.count {
                        let q = cloud.points.positions[i as usize].as_dvec3();
                        assert!(
                            !local.sees(q, cam.lambda_max),
                            "a dropped leaf holds point {i}, which the camera sees"
                        );
                    }
                }
            }
        }
        println!("kept {kept} leaves, dropped {dropped_leaves}");
        assert!(kept > 0 && dropped_leaves > kept);
    }
}
