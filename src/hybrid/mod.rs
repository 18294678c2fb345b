//! Hybrid reflections (paper 2, "Hybrid backward-forward reflection rendering with continuous
//! 3-ray cameras"): what mirrors and glass reflect is not traced but **splatted**. The diffuse
//! objects are sampled as points once ([`points`]) and organised in an eight-way kd-tree
//! ([`kdtree`]); every frame, each reflector triangle the eye sees becomes a continuous 3-ray
//! camera ([`C3rc`](crate::camera::C3rc)), the tree is culled against its view volume, and the
//! surviving points are projected — every valid projection, several where the sweep folds — and
//! splatted as 1–2 pixel squares where the reflector is seen, the point nearest the reflector
//! winning each pixel ([`frame`]). Pixels no point reaches show the environment.
//!
//! The rest of the frame is trompe's Whitted tracer ([`render::Tracer`](crate::render::Tracer))
//! on the same G-buffer: the C3RCs answer only the eye's first reflection off a mirror or glass
//! surface; the rays that go through glass, and reflections of reflections, are traced through
//! the BVH. Reflectors are not points, so they do not appear in one another's splatted
//! reflections (the paper's method reflects diffuse objects only).
//!
//! Invariants: the points and trees are built once per scene and reused for every frame and any
//! rigid (indeed affine) motion of their object; a deforming object's points are carried by its
//! deformation each frame and its tree built again ([`HybridReflections::deformed_at`]); a
//! frame's pixels do not depend on the thread count (splats resolve by an atomic minimum over
//! `(key, point)`).

pub mod frame;
pub mod kdtree;
pub mod plan;
pub mod points;

pub use frame::{FrameStats, HybridFrame, render_frame, render_frame_from};
pub use kdtree::{KdTree, TreeSettings, TreeStats};
pub use plan::{KeptNode, Placement, ReflectorCamera, SplatPlan};
pub use points::PointSet;

use crate::geom::Aabb;
use crate::progress::Progress;
use crate::render::RenderError;
use crate::scene::{Scene, Surface};
use glam::Vec3;
use std::time::{Duration, Instant};

/// How the hybrid method samples, builds and splats.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HybridSettings {
    /// Splat side in pixels (1 or 2).
    pub splat: u32,
    /// Point spacing in scene units for every object; `None`: each object's spacing is derived
    /// from its closest reflection distance ([`HybridReflections::prepare`]).
    pub spacing: Option<f32>,
    /// At most this many points in all (spacings are widened, and the report says so, past it).
    pub max_points: u64,
    /// When kd-tree nodes stop splitting.
    pub tree: TreeSettings,
    /// Seed of the sampling.
    pub seed: u64,
    /// Test each splatted pixel's reflected ray against the mirrors and glass, and trace it
    /// exactly where one of them is nearer than the point: mirrors then hide what is behind
    /// them (beyond paper 2, whose points are seen through every reflector: `false`).
    pub mirrors_occlude: bool,
    /// Read each C3RC's points thinned to what its magnification needs (beyond paper 2, whose
    /// algorithm projects every point of every leaf kept: `false`).
    pub level_of_detail: bool,
}

impl Default for HybridSettings {
    fn default() -> Self {
        HybridSettings {
            splat: 2,
            spacing: None,
            max_points: 4_000_000,
            tree: TreeSettings::default(),
            seed: 1,
            mirrors_occlude: true,
            level_of_detail: true,
        }
    }
}

/// One diffuse object's points and their tree, in object space.
#[derive(Clone, Debug)]
pub struct PointCloud {
    /// The object (its index in the scene).
    pub object: u32,
    /// The spacing it was sampled at.
    pub spacing: f32,
    /// The points, in leaf order.
    pub points: PointSet,
    /// The kd-tree over them.
    pub tree: KdTree,
    /// Time to sample.
    pub sample_time: Duration,
    /// Time to build the tree (paper 2 Table 1).
    pub build_time: Duration,
}

/// The scene's diffuse objects as points, ready for any number of frames.
#[derive(Clone, Debug)]
pub struct HybridReflections {
    /// One cloud per diffuse object.
    pub clouds: Vec<PointCloud>,
    /// The settings used.
    pub settings: HybridSettings,
    /// Whether the point budget widened the spacings past what leaves no holes.
    pub thinned: bool,
}

impl HybridReflections {
    /// Samples every diffuse object of `scene` and builds its tree. Without a spacing in
    /// `settings`, each object gets the spacing that leaves no hole for the splat size at its
    /// closest reflection distance (seen at the scene's time): a gap of two spacings must image
    /// within `splat` pixels in a flat mirror, whose image is the largest a mirror that does not
    /// converge rays makes, at the unfolded distance eye → nearest reflector → object.
    pub fn prepare(
        scene: &Scene,
        settings: HybridSettings,
    ) -> Result<HybridReflections, RenderError> {
        if let Some(s) = settings.spacing.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(RenderError::Setting {
                name: "spacing",
                value: f64::from(s),
                reason: "must be a positive number of scene units",
            });
        }
        let t = scene.render.time;
        let view = scene.view(t)?;
        let eye = view.camera.position().as_vec3();
        let pixel_angle = (scene.camera.fov_y.to_radians() / f64::from(scene.camera.height)) as f32;
        let reflectors: Vec<Aabb> = (0..view.meshes.len())
            .filter(|&o| !matches!(view.surfaces[o], Surface::Diffuse(_)))
            .map(|o| view.meshes[o].bounds())
            .collect();
        let diffuse: Vec<usize> = (0..view.meshes.len())
            .filter(|&o| matches!(view.surfaces[o], Surface::Diffuse(_)) && !reflectors.is_empty())
            .collect();
        let mut spacings: Vec<f32> = diffuse
            .iter()
            .map(|&o| {
                settings.spacing.unwrap_or_else(|| {
                    let object = view.meshes[o].bounds();
                    let closest = reflectors
                        .iter()
                        .map(|r| point_box_distance(eye, r) + box_box_distance(r, &object))
                        .fold(f32::INFINITY, f32::min)
                        .max(1e-3);
                    settings.splat.max(1) as f32 * pixel_angle * closest / 2.0
                })
            })
            .collect();
        // The budget, before anything is allocated: widen every spacing alike past it.
        let estimate = |s: &[f32]| -> u64 {
            diffuse
                .iter()
                .zip(s)
                .map(|(&o, &s)| {
                    points::estimate(&scene.objects[o].mesh, s * world_scale(scene, o, t))
                })
                .fold(0u64, u64::saturating_add)
        };
        // Points are indexed in 32 bits.
        let budget = settings.max_points.clamp(1, u64::from(u32::MAX) / 2);
        let mut thinned = false;
        for _ in 0..8 {
            let n = estimate(&spacings);
            if n <= budget {
                break;
            }
            let widen = (n as f32 / budget as f32).sqrt() * 1.05;
            spacings.iter_mut().for_each(|s| *s *= widen);
            thinned = true;
        }
        crate::memory::check(
            || format!("{} points for hybrid reflections", estimate(&spacings)),
            crate::memory::times(estimate(&spacings), points::BYTES_PER_POINT + 8),
        )?;
        let clouds = diffuse
            .iter()
            .zip(&spacings)
            .map(|(&o, &spacing)| {
                let object = &scene.objects[o];
                // Sampled in object space: the spacing asked for is in the world.
                let local = spacing * world_scale(scene, o, t);
                let start = Instant::now();
                let sampled = points::sample(&object.mesh, &object.surface, local, settings.seed);
                let sample_time = start.elapsed();
                let start = Instant::now();
                let (tree, points) = KdTree::build(&sampled, settings.tree);
                PointCloud {
                    object: o as u32,
                    spacing,
                    points,
                    tree,
                    sample_time,
                    build_time: start.elapsed(),
                }
            })
            .collect();
        Ok(HybridReflections {
            clouds,
            settings,
            thinned,
        })
    }

    /// The clouds as `scene`'s deforming objects stand at time `t`: each deforming object's
    /// points carried by its deformation (normals by the Jacobian, as its mesh's are) and its
    /// tree built again over them; `None` when no cloud's object deforms (the clouds stand as
    /// prepared, placed by rigid motion alone).
    pub fn deformed_at(&self, scene: &Scene, t: f32) -> Option<HybridReflections> {
        let deforming = |c: &PointCloud| {
            scene
                .objects
                .get(c.object as usize)
                .and_then(|o| o.deform.as_ref())
        };
        if !self.clouds.iter().any(|c| deforming(c).is_some()) {
            return None;
        }
        let clouds = self
            .clouds
            .iter()
            .map(|c| {
                let Some(d) = deforming(c) else {
                    return c.clone();
                };
                let start = Instant::now();
                let (positions, normals) = c
                    .points
                    .positions
                    .iter()
                    .zip(&c.points.normals)
                    .map(|(&p, &n)| d.carry(p, n, t))
                    .unzip();
                let moved = PointSet {
                    positions,
                    normals,
                    albedo: c.points.albedo.clone(),
                };
                let (tree, points) = KdTree::build(&moved, self.settings.tree);
                PointCloud {
                    object: c.object,
                    spacing: c.spacing,
                    points,
                    tree,
                    sample_time: c.sample_time,
                    build_time: start.elapsed(),
                }
            })
            .collect();
        Some(HybridReflections {
            clouds,
            settings: self.settings,
            thinned: self.thinned,
        })
    }

    /// What the points and trees are, with one frame's statistics: the report of
    /// `trompe render --method c3rc`.
    pub fn report(&self, scene: &Scene, frame: FrameStats) -> HybridReport {
        let objects = self
            .clouds
            .iter()
            .map(|c| CloudReport {
                name: scene
                    .objects
                    .get(c.object as usize)
                    .map_or_else(|| format!("object {}", c.object), |o| o.name.clone()),
                points: c.points.len(),
                spacing: c.spacing,
                tree: c.tree.stats(),
                sample_time: c.sample_time,
                build_time: c.build_time,
            })
            .collect();
        HybridReport {
            objects,
            thinned: self.thinned,
            frame,
        }
    }

    /// All points.
    pub fn point_count(&self) -> usize {
        self.clouds.iter().map(|c| c.points.len()).sum()
    }

    /// Renders `scene` at time `t` (the scene these clouds were prepared from).
    pub fn render_at(
        &self,
        scene: &Scene,
        t: f32,
        progress: &dyn Progress,
    ) -> Result<HybridFrame, RenderError> {
        render_frame(self, scene, t, progress)
    }
}

/// Samples the scene's diffuse objects, builds their trees and renders one frame at time `t`:
/// `trompe render --method c3rc`.
pub fn render(
    scene: &Scene,
    t: f32,
    settings: HybridSettings,
    progress: &dyn Progress,
) -> Result<(crate::frame::Frame, HybridReport), RenderError> {
    let clouds = HybridReflections::prepare(scene, settings)?;
    let HybridFrame { frame, stats, .. } = clouds.render_at(scene, t, progress)?;
    Ok((frame, clouds.report(scene, stats)))
}

/// One object's points and tree, as a report gives them.
#[derive(Clone, Debug)]
pub struct CloudReport {
    /// The object's name.
    pub name: String,
    /// Points.
    pub points: usize,
    /// Spacing, scene units.
    pub spacing: f32,
    /// The tree.
    pub tree: TreeStats,
    /// Time to sample.
    pub sample_time: Duration,
    /// Time to build the tree.
    pub build_time: Duration,
}

/// What a hybrid render did: the pre-process and the frame.
#[derive(Clone, Debug)]
pub struct HybridReport {
    /// Per diffuse object.
    pub objects: Vec<CloudReport>,
    /// Whether the point budget widened the spacings.
    pub thinned: bool,
    /// The frame.
    pub frame: FrameStats,
}

impl std::fmt::Display for HybridReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for o in &self.objects {
            writeln!(
                f,
                "{}: {} points {:.4} apart (sampled in {:.1} ms); kd-tree {} nodes, {} leaves, mean depth {:.1}, {:.0} points a leaf, built in {:.1} ms",
                o.name,
                o.points,
                o.spacing,
                o.sample_time.as_secs_f64() * 1e3,
                o.tree.nodes,
                o.tree.leaves,
                o.tree.mean_depth,
                o.tree.points_per_leaf,
                o.build_time.as_secs_f64() * 1e3
            )?;
        }
        if self.thinned {
            writeln!(
                f,
                "warning: the point budget widened the spacings; reflections may show holes (give --spacing, or a larger budget)"
            )?;
        }
        write!(f, "{}", self.frame)
    }
}

/// Object-space units per world unit for object `o` at time `t` (its mean scale, inverted).
fn world_scale(scene: &Scene, o: usize, t: f32) -> f32 {
    let m = scene.objects[o].world_from_object_at(t);
    let (scale, _, _) = m.to_scale_rotation_translation();
    let s = (scale.x.abs() * scale.y.abs() * scale.z.abs()).cbrt();
    if s.is_finite() && s > 0.0 {
        1.0 / s
    } else {
        1.0
    }
}

fn point_box_distance(p: Vec3, b: &Aabb) -> f32 {
    (b.min - p).max(p - b.max).max(Vec3::ZERO).length()
}

fn box_box_distance(a: &Aabb, b: &Aabb) -> f32 {
    (a.min - b.max).max(b.min - a.max).max(Vec3::ZERO).length()
}
