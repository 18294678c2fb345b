//! What a hybrid frame splats (paper 2 §4–5): one continuous 3-ray camera for every reflector
//! triangle the eye sees, the kd-tree nodes each camera's view volume keeps, and the stride
//! each node is read with — the work of a frame before any point is projected. The CPU's
//! splatting ([`super::frame`]) and the GPU crate's read the same plan, so both devices
//! project the same points through the same cameras.
//!
//! Invariants: cameras are in (object, triangle) order and each camera's nodes sorted, so a
//! plan does not depend on the thread count; a node is dropped only when its box lies outside
//! the camera's view volume (no point of it can project), and read thinned only where the
//! level of detail says its points overfill the reflector's pixels.

use super::HybridReflections;
use super::kdtree::Node;
use crate::camera::{C3rc, Projection};
use crate::scene::{Scene, Surface, View};
use glam::{DMat4, DVec3};
use rayon::prelude::*;

/// Relative depth slack between a splat's image point and the surface the eye sees there.
pub const DEPTH_SLACK: f32 = 0.02;

/// Points a splat's area should receive for the reflection to show no holes.
pub const POINTS_PER_SPLAT: f64 = 4.0;

/// Whether a surface reflects (a mirror or glass): what the C3RCs are built over.
pub fn is_reflector(s: &Surface) -> bool {
    !matches!(s, Surface::Diffuse(_))
}

/// A reflector triangle's camera and what it reads.
#[derive(Clone, Debug)]
pub struct ReflectorCamera {
    /// The reflector object.
    pub object: u32,
    /// The camera, in world space.
    pub world: C3rc,
    /// Largest sweep parameter any diffuse point can have.
    pub lambda_max: f64,
    /// The reflector triangle's area on screen, pixels (0 when it cannot be projected).
    pub pixels: f64,
    /// The nodes the camera reads, sorted by (cloud, node).
    pub nodes: Vec<KeptNode>,
}

/// A kd-tree node a camera reads: a leaf, or an inner node read thinned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct KeptNode {
    /// The cloud (its index in [`HybridReflections::clouds`]).
    pub cloud: u32,
    /// The node in that cloud's tree.
    pub node: u32,
    /// Every how many of the node's points are read (1: all).
    pub stride: u32,
}

/// Where each cloud is in a frame.
#[derive(Clone, Debug)]
pub struct Placement {
    /// Object → world, a cloud each.
    pub world: Vec<DMat4>,
    /// World → object.
    pub inverse: Vec<DMat4>,
    /// World units per object unit.
    pub scales: Vec<f64>,
    /// Each cloud's first point in the frame's point numbering (the splat key's index).
    pub offsets: Vec<u32>,
}

impl Placement {
    /// The clouds of `clouds` as `scene` places them at time `t`.
    pub fn at(clouds: &HybridReflections, scene: &Scene, t: f32) -> Placement {
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
        Placement {
            inverse: world.iter().map(|m| m.inverse()).collect(),
            scales: world.iter().map(mean_scale).collect(),
            world,
            offsets,
        }
    }

    /// The cloud a point of the frame's numbering belongs to, and its index in that cloud.
    pub fn locate(&self, global: u32) -> (usize, usize) {
        let c = self
            .offsets
            .partition_point(|&o| o <= global)
            .saturating_sub(1);
        (c, (global - self.offsets[c]) as usize)
    }
}

/// A frame's cameras and what each reads.
#[derive(Clone, Debug)]
pub struct SplatPlan {
    /// One camera per reflector triangle the eye sees, in (object, triangle) order.
    pub cameras: Vec<ReflectorCamera>,
    /// Where the clouds are.
    pub placement: Placement,
    /// kd-tree nodes tested against view volumes.
    pub nodes_tested: u64,
}

impl SplatPlan {
    /// The plan of a frame of `view` (the scene at time `t`) whose eye sees the reflector
    /// triangles `seen` (per object, per triangle), splats `splat` pixels wide.
    pub fn new(
        clouds: &HybridReflections,
        scene: &Scene,
        view: &View,
        t: f32,
        seen: &[Vec<bool>],
        splat: u32,
    ) -> SplatPlan {
        let placement = Placement::at(clouds, scene, t);
        let mut cameras = reflector_cameras(view, seen, clouds);
        let tested: u64 = cameras
            .par_iter_mut()
            .map(|cam| {
                let (nodes, tested) = cull(cam, clouds, &placement, splat);
                cam.nodes = nodes;
                tested
            })
            .sum();
        SplatPlan {
            cameras,
            placement,
            nodes_tested: tested,
        }
    }

    /// Nodes kept, over every camera.
    pub fn nodes_kept(&self) -> u64 {
        self.cameras.iter().map(|c| c.nodes.len() as u64).sum()
    }
}

/// Per object of `view`, per triangle: whether it is a reflector triangle one of `hits`
/// (object, triangle) sees.
pub fn seen_reflectors(view: &View, hits: impl Iterator<Item = (u32, u32)>) -> Vec<Vec<bool>> {
    let mut seen: Vec<Vec<bool>> = view
        .meshes
        .iter()
        .map(|m| vec![false; m.triangle_count()])
        .collect();
    for (o, t) in hits {
        let reflects = view.surfaces.get(o as usize).is_some_and(is_reflector);
        if let Some(flag) = seen.get_mut(o as usize).and_then(|s| s.get_mut(t as usize))
            && reflects
        {
            *flag = true;
        }
    }
    seen
}

/// One camera for every reflector triangle flagged in `seen`, in (object, triangle) order,
/// its nodes not yet culled.
fn reflector_cameras(
    view: &View,
    seen: &[Vec<bool>],
    clouds: &HybridReflections,
) -> Vec<ReflectorCamera> {
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
            out.push(ReflectorCamera {
                object: o as u32,
                world,
                lambda_max,
                pixels,
                nodes: Vec::new(),
            });
        }
    }
    out
}

impl ReflectorCamera {
    /// The camera moved into an object's space by `inverse` (world → object): affine maps keep
    /// the sweep, its λ and barycentrics.
    pub fn local(&self, inverse: &DMat4) -> C3rc {
        C3rc {
            v: self.world.v.map(|p| inverse.transform_point3(p)),
            d: self.world.d.map(|d| inverse.transform_vector3(d)),
        }
    }
}

/// The nodes whose boxes the camera may see and whose points it reads: leaves, or inner nodes
/// whose points it needs so few of (a stride of a leaf's worth or more, see [`stride`]) that
/// reading them thinned beats descending; and the nodes tested.
fn cull(
    cam: &ReflectorCamera,
    clouds: &HybridReflections,
    placement: &Placement,
    splat: u32,
) -> (Vec<KeptNode>, u64) {
    let mut kept = Vec::new();
    let mut tested = 0u64;
    let leaf_points = clouds.settings.tree.leaf_points.max(1);
    let lod = clouds.settings.level_of_detail;
    for (c, cloud) in clouds.clouds.iter().enumerate() {
        if cloud.tree.nodes.is_empty() {
            continue;
        }
        let local = cam.local(&placement.inverse[c]);
        let mut stack = vec![0u32];
        while let Some(id) = stack.pop() {
            let node = &cloud.tree.nodes[id as usize];
            tested += 1;
            let (lo, hi) = (node.lo.as_dvec3(), node.hi.as_dvec3());
            if !local.may_see_box(lo, hi, cam.lambda_max) {
                continue;
            }
            let step = stride(
                cam,
                &local,
                node,
                cloud.spacing,
                placement.scales[c],
                splat,
                lod,
            );
            if node.leaf || (node.points.1 as usize).div_ceil(step) <= leaf_points {
                kept.push(KeptNode {
                    cloud: c as u32,
                    node: id,
                    stride: step as u32,
                });
            } else {
                stack.extend(node.first..node.first + node.count);
            }
        }
    }
    kept.sort_unstable();
    (kept, tested)
}

/// World units per object unit of a placement: its mean scale.
fn mean_scale(m: &DMat4) -> f64 {
    let (s, _, _) = m.to_scale_rotation_translation();
    (s.x.abs() * s.y.abs() * s.z.abs()).cbrt()
}

/// Every how many points of `node` the camera needs (level of detail, beyond paper 2): a
/// surface of `spacing`-apart points facing the reflector at sweep `λ` puts about
/// `A(λ) / spacing²` points into the reflector triangle's `pixels`, where `A(λ) = |n(λ)|/2` is
/// the area of the sweeping triangle. Where that is more than [`POINTS_PER_SPLAT`] a splat, the
/// leaf is read with a stride. `A` is taken at its least over the node's sweep range,
/// `λ ≥` the distance from the triangle to the node's box (construction rays are unit, so
/// `|Σ bᵢ dᵢ| ≤ 1`); surfaces seen obliquely only hold more points. A sweep that folds
/// (`A` reaches 0) gets every point.
fn stride(
    cam: &ReflectorCamera,
    local: &C3rc,
    node: &Node,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hybrid::HybridSettings;
    use crate::trace::{Bvh, RayQuery};

    #[test]
    fn culling_real_trees_drops_no_leaf_with_a_seen_point() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/c3rc-bunny.toml");
        let mut scene = Scene::load(&path).unwrap();
        (scene.camera.width, scene.camera.height) = (120, 80);
        let clouds = HybridReflections::prepare(&scene, HybridSettings::default()).unwrap();
        let view = scene.view(0.0).unwrap();
        let bvh = Bvh::build(view.meshes.clone()).unwrap();
        let hits = (0..80)
            .flat_map(|y| (0..120).map(move |x| (x, y)))
            .filter_map(|(x, y)| {
                let ray = view
                    .camera
                    .ray(crate::frame::pixel_centre(x as f64, y as f64));
                bvh.closest_hit(&ray, f32::INFINITY)
            })
            .map(|h| (h.object, h.triangle));
        let seen = seen_reflectors(&view, hits);
        let plan = SplatPlan::new(&clouds, &scene, &view, 0.0, &seen, 2);
        assert!(plan.cameras.len() > 100);
        let (mut kept, mut dropped_leaves) = (0, 0);
        for cam in plan.cameras.iter().step_by(7) {
            kept += cam.nodes.len();
            for (c, cloud) in clouds.clouds.iter().enumerate() {
                // The points the kept nodes read (thinned or not).
                let mut read = vec![false; cloud.points.len()];
                for n in cam.nodes.iter().filter(|n| n.cloud == c as u32) {
                    let (first, count) = cloud.tree.nodes[n.node as usize].points;
                    read[first as usize..(first + count) as usize].fill(true);
                }
                let local = cam.local(&plan.placement.inverse[c]);
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
