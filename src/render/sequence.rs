//! Frame sequences of animated scenes (paper 1 §6, dynamic scenes): a camera path, rigidly
//! moving objects and deforming ones, rendered frame after frame by any method.
//!
//! Under the impostor methods a [`Sequence`] keeps every impostor it builds between frames. An
//! object that moves rigidly keeps its impostors: a ray is taken into the frame the impostor
//! was built in and its hit carried back, and the impostor's albedo is lit again for the
//! object's new pose (the sun and its shadows do not move with it). An impostor is rebuilt when
//! its object deforms, or when the mirror that sees it has moved, relative to the object, by
//! more than [`REBUILD_SHIFT`] of its bounding radius from where the impostor was built for —
//! past that, the rays come from outside the region the impostor was made to answer.
//!
//! A device that traces frames itself (`trompe-gpu`) takes each frame's view, BVH and
//! impostors from [`Sequence::impostor_answers`], and may draw the impostors the sequence
//! builds ([`Sequence::with_drawer`]); keeping, placing and lighting stay here.
//!
//! Invariants: a sequence's frame at time `t` is, with nothing reused, the frame
//! [`super::render_with`] gives at `t` (the same code builds and lights the impostors); reused
//! impostors differ from rebuilt ones only by the motion's rounding, and by sampling when the
//! mirror has moved less than the threshold; the frames do not depend on the thread count.

use super::impostor::{
    ImpostorInputs, Placement, ReflectorImpostors, Seen, build_unlit, lit, load_baked,
    seen_as_impostor,
};
use super::shading::Shadows;
use super::{Method, Progress, RenderError, RenderOptions, Timings};
use crate::frame::Frame;
use crate::impostor::{Impostor, ImpostorBuilder};
use crate::scene::{Scene, Surface};
use crate::trace::Bvh;
use glam::{Mat4, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

/// How far (a fraction of the mirror's bounding radius) a mirror may move relative to an object
/// before the object's impostors for it are rebuilt.
pub const REBUILD_SHIFT: f32 = 0.25;

/// What a frame of a sequence did with the impostors.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameReport {
    /// Impostors built for this frame (first frame, deformation, a mirror moved too far).
    pub built: usize,
    /// Impostors kept from an earlier frame.
    pub reused: usize,
    /// Kept impostors lit again because something in the scene moved.
    pub relit: usize,
    /// Of those built, how many a device drew ([`Sequence::with_drawer`]).
    pub drawn: usize,
}

impl std::fmt::Display for FrameReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "impostors: {} built", self.built)?;
        if self.drawn > 0 {
            write!(f, " ({} drawn by the device)", self.drawn)?;
        }
        write!(f, ", {} reused ({} relit)", self.reused, self.relit)
    }
}

/// Renders an animated scene frame after frame, keeping impostors between frames.
pub struct Sequence<'a> {
    scene: &'a Scene,
    options: RenderOptions,
    stand_ins: Arc<super::StandIns>,
    /// Per (mirror or glass object, object it sees): its impostors as last built.
    kept: HashMap<(usize, usize), Kept>,
    /// The baked impostors, loaded on the first frame, and each object's pose then.
    baked: Option<Vec<Option<Baked>>>,
    /// Every object's pose when the kept impostors were last lit.
    lit_at: Option<Vec<Mat4>>,
    /// The answers of the last frame, kept while nothing moves or deforms.
    answers: Option<Arc<ReflectorImpostors>>,
    /// What the last frame did with impostors.
    last_report: FrameReport,
    /// The scene's BVH and every object's pose it was built at (no object deforming).
    bvh: Option<(Vec<Mat4>, Arc<Bvh>)>,
    builder: ImpostorBuilder,
    /// What draws impostors elsewhere (a GPU), if anything.
    drawer: Option<Arc<dyn super::ImpostorDrawer + 'a>>,
}

/// What [`Sequence::impostor_answers`] gives: a frame of an impostor method, ready to trace.
pub struct PreparedFrame {
    /// The scene at the frame's time, through the frame's camera.
    pub view: crate::scene::View,
    /// Its BVH (kept between frames while nothing moves or deforms).
    pub bvh: Arc<Bvh>,
    /// The answers to the rays its mirrors and glass send out (the same `Arc` as the last
    /// frame's while nothing moved).
    pub answers: Arc<ReflectorImpostors>,
    /// What preparing it took.
    pub timings: Timings,
    /// What it did with impostors.
    pub report: FrameReport,
}

/// A baked impostor and its object's pose when it was loaded.
type Baked = (Arc<Impostor>, Mat4);

/// Impostors of one object for one mirror, kept between frames.
struct Kept {
    /// As built: albedo colours (or none, for a mirror).
    unlit: Vec<Arc<Impostor>>,
    /// As last lit.
    lit: Vec<Arc<Impostor>>,
    /// The object's pose (object → world) when they were built.
    pose: Mat4,
    /// The mirror's centre when they were built (world).
    eye: Vec3,
}

impl<'a> Sequence<'a> {
    /// A sequence of `scene`'s frames rendered as `options` say.
    pub fn new(scene: &'a Scene, options: RenderOptions) -> Self {
        Self {
            scene,
            options,
            stand_ins: Arc::new(super::StandIns::of(scene)),
            kept: HashMap::new(),
            baked: None,
            lit_at: None,
            bvh: None,
            answers: None,
            last_report: FrameReport::default(),
            builder: ImpostorBuilder::new(),
            drawer: None,
        }
    }

    /// The same sequence, the impostors `drawer` draws (a GPU's rasterizer) resolved from its
    /// images rather than built by the library (paper 1 §3.1 builds impostors on the GPU).
    pub fn with_drawer(self, drawer: Arc<dyn super::ImpostorDrawer + 'a>) -> Self {
        Self {
            drawer: Some(drawer),
            ..self
        }
    }

    /// The frame at time `t` (seconds), its timings and what it did with impostors.
    pub fn frame(
        &mut self,
        t: f32,
        progress: &dyn Progress,
    ) -> Result<(Frame, Timings, FrameReport), RenderError> {
        self.frame_from(t, None, progress)
    }

    /// [`Sequence::frame`] seen through `camera` instead of the scene's (an interactive
    /// viewer's, a pinhole: the scene camera's lens is not used), when given.
    pub fn frame_from(
        &mut self,
        t: f32,
        camera: Option<crate::camera::Pinhole>,
        progress: &dyn Progress,
    ) -> Result<(Frame, Timings, FrameReport), RenderError> {
        if !t.is_finite() {
            return Err(RenderError::Time(t));
        }
        let scene = self.scene;
        let mut timings = Timings::default();
        let mut view = timings.time("evaluate scene", || scene.view(t))?;
        if let Some(camera) = camera {
            // A pinhole: the scene camera's lens goes with it.
            view.camera = camera;
            view.lens = None;
        }
        super::check_memory(&view, self.options.method)?;
        super::check_finite(&view)?;
        if self.options.method == Method::Raster {
            let lighting = (&scene.lighting, &scene.render);
            let frame = super::render_view(
                &view,
                lighting,
                self.options,
                &self.stand_ins,
                progress,
                &mut timings,
            )?;
            return Ok((frame, timings, FrameReport::default()));
        }
        let bvh = self.bvh_at(&view, t, &mut timings)?;
        let Some(resolution) = self.options.method.impostor_resolution() else {
            // (The raster method returned above.)
            let exact = crate::trace::Exact(bvh.as_ref());
            let secondary: &dyn crate::trace::SecondaryQuery =
                if self.options.method == Method::Trace {
                    &exact
                } else {
                    &crate::trace::EnvironmentOnly
                };
            let frame = self.trace(&view, &bvh, secondary, progress, &mut timings)?;
            return Ok((frame, timings, FrameReport::default()));
        };
        let secondary = self.answers(&view, &bvh, (t, resolution), &mut timings)?;
        let report = self.last_report.clone();
        let frame = self.trace(&view, &bvh, secondary.as_ref(), progress, &mut timings)?;
        Ok((frame, timings, report))
    }

    /// What the frame at time `t` is traced with under an impostor method — the view (seen
    /// through `camera` when given), the scene's BVH and the impostors' answers, kept, placed
    /// and lit as [`Sequence::frame_from`] keeps, places and lights them — for a device that
    /// traces it itself (`trompe-gpu`); `None` for a method without impostors.
    pub fn impostor_answers(
        &mut self,
        t: f32,
        camera: Option<crate::camera::Pinhole>,
    ) -> Result<Option<PreparedFrame>, RenderError> {
        if !t.is_finite() {
            return Err(RenderError::Time(t));
        }
        let Some(resolution) = self.options.method.impostor_resolution() else {
            return Ok(None);
        };
        let mut timings = Timings::default();
        let mut view = timings.time("evaluate scene", || self.scene.view(t))?;
        if let Some(camera) = camera {
            view.camera = camera;
        }
        super::check_memory(&view, self.options.method)?;
        super::check_finite(&view)?;
        let bvh = self.bvh_at(&view, t, &mut timings)?;
        let answers = self.answers(&view, &bvh, (t, resolution), &mut timings)?;
        Ok(Some(PreparedFrame {
            view,
            bvh,
            answers,
            timings,
            report: self.last_report.clone(),
        }))
    }

    /// The BVH of `view` (the scene at `t`): the last one while nothing moved or deformed.
    fn bvh_at(
        &mut self,
        view: &crate::scene::View,
        t: f32,
        timings: &mut Timings,
    ) -> Result<Arc<Bvh>, crate::memory::OverBudget> {
        let poses = self.scene.poses_at(t);
        let still = !self.scene.deforms();
        Ok(match &self.bvh {
            Some((at, bvh)) if still && at == &poses => bvh.clone(),
            _ => {
                // The last one is let go first: the two are never held together.
                self.bvh = None;
                let bvh = Arc::new(timings.time("build BVH", || Bvh::build(view.meshes.clone()))?);
                self.bvh = still.then(|| (poses, bvh.clone()));
                bvh
            }
        })
    }

    /// The answers to the rays mirrors and glass of `view` (the scene at `t`) send out, from
    /// impostors of `resolution²` texels: the last frame's while nothing moved, otherwise kept
    /// or built, placed and lit ([`Sequence::impostors`]); records what it did.
    fn answers(
        &mut self,
        view: &crate::scene::View,
        bvh: &Bvh,
        (t, resolution): (f32, u32),
        timings: &mut Timings,
    ) -> Result<Arc<ReflectorImpostors>, RenderError> {
        let scene = self.scene;
        let stand_ins = self.stand_ins.clone();
        let poses = scene.poses_at(t);
        let still = !scene.deforms();
        let drawer = self.drawer.clone();
        let inputs = ImpostorInputs {
            shadows: Some(Shadows {
                occluders: bvh,
                epsilon: scene.render.ray_epsilon,
            }),
            pinhole: matches!(self.options.method, Method::PinholeImpostor(_)),
            refraction: self.options.refraction,
            mirrors: self.options.mirrors,
            primary: self.options.primary,
            mazes: &stand_ins.mazes,
            drawer: drawer.as_deref().map(|d| d as &dyn super::ImpostorDrawer),
            ..ImpostorInputs::new(resolution)
        };
        crate::frame::check_size(u64::from(resolution), u64::from(resolution))?;
        // Anything that moved changes the light's shadows: every kept impostor is lit again.
        let moved = self.lit_at.as_ref() != Some(&poses) || !still;
        if self.baked.is_none() {
            let files = &self.stand_ins.baked;
            let loaded = timings.time("load baked impostors", || load_baked(view, files))?;
            self.baked = Some(
                loaded
                    .into_iter()
                    .zip(&poses)
                    .map(|(imp, pose)| imp.map(|i| (Arc::new(i), *pose)))
                    .collect(),
            );
        }
        let secondary = match &self.answers {
            // Nothing moved or deformed: every impostor, lit as it is, and the specular BVH
            // stand.
            Some(answers) if !moved => {
                self.last_report = FrameReport {
                    reused: self.last_report.built + self.last_report.reused,
                    ..FrameReport::default()
                };
                answers.clone()
            }
            _ => {
                let mut report = FrameReport::default();
                let per_object = timings.time("build, keep and light impostors", || {
                    self.impostors(view, &inputs, &poses, moved, &mut report)
                })?;
                let answers = Arc::new(timings.time("specular BVH", || {
                    ReflectorImpostors::assemble(view, per_object, self.options.mirrors)
                })?);
                self.answers = Some(answers.clone());
                self.last_report = report;
                answers
            }
        };
        self.lit_at = Some(poses);
        Ok(secondary)
    }

    /// Traces `view` through `bvh`, the rays mirrors and glass send out answered by
    /// `secondary`, as the options say.
    fn trace(
        &self,
        view: &crate::scene::View,
        bvh: &Bvh,
        secondary: &dyn crate::trace::SecondaryQuery,
        progress: &dyn Progress,
        timings: &mut Timings,
    ) -> Result<Frame, RenderError> {
        let tracer = super::Tracer {
            view,
            primary: bvh,
            secondary,
            lighting: &self.scene.lighting,
            settings: &self.scene.render,
        };
        let choices = (self.options.refraction, self.options.primary);
        super::trace_frame(&tracer, choices, progress, timings)
    }

    /// Per object of `view`, the impostors its rays meet: kept, placed and lit again where
    /// their object moved rigidly, built where it deformed or the mirror moved too far.
    fn impostors(
        &mut self,
        view: &crate::scene::View,
        inputs: &ImpostorInputs<'_>,
        poses: &[Mat4],
        moved: bool,
        report: &mut FrameReport,
    ) -> Result<Vec<Vec<Seen>>, RenderError> {
        let lighting = &self.scene.lighting;
        let mut out = Vec::with_capacity(view.surfaces.len());
        for (r, surface) in view.surfaces.iter().enumerate() {
            let mut seen = Vec::new();
            if matches!(surface, Surface::Diffuse(_)) {
                out.push(seen);
                continue;
            }
            let mirror = view.meshes[r].bounds();
            let (eye, region) = (mirror.center(), mirror.radius());
            for o in (0..view.surfaces.len()).filter(|&o| o != r) {
                if !seen_as_impostor(view, o, inputs.mirrors) {
                    continue;
                }
                let radiance = matches!(view.surfaces[o], Surface::Diffuse(_));
                let baked = self
                    .baked
                    .as_ref()
                    .and_then(|b| b.get(o).cloned().flatten());
                // `fresh`: built (or loaded) for this frame, not kept from an earlier one.
                let (kept, fresh) = match (baked, self.kept.remove(&(r, o))) {
                    (Some((imp, pose)), previous) => {
                        let fresh = previous.is_none();
                        let lit = previous.map_or_else(Vec::new, |k| k.lit);
                        let kept = Kept {
                            unlit: vec![imp],
                            lit,
                            pose,
                            eye,
                        };
                        (kept, fresh)
                    }
                    (None, Some(k))
                        if self.scene.objects[o].deform.is_none()
                            // A maze's graph camera does not depend on where the mirror is.
                            && (self.scene.objects[o].maze.is_some()
                            // Where the mirror is now, in the frame the impostors were built in.
                            || k.eye.distance(
                                k.pose.transform_point3(poses[o].inverse().transform_point3(eye)),
                            ) <= REBUILD_SHIFT * region) =>
                    {
                        report.reused += k.unlit.len();
                        (k, false)
                    }
                    (None, _) => {
                        let built = build_unlit(
                            view,
                            (r, o),
                            inputs,
                            &mut self.builder,
                            &mut report.drawn,
                        )?;
                        report.built += built.len();
                        let kept = Kept {
                            unlit: built.into_iter().map(Arc::new).collect(),
                            lit: Vec::new(),
                            pose: poses[o],
                            eye,
                        };
                        (kept, true)
                    }
                };
                let placement = if poses[o] == kept.pose {
                    None
                } else {
                    Placement::of(poses[o] * kept.pose.inverse())
                };
                let lit = if !radiance {
                    kept.unlit.clone()
                } else if fresh || moved || kept.lit.is_empty() {
                    if !fresh {
                        report.relit += kept.unlit.len();
                    }
                    kept.unlit
                        .iter()
                        .map(|u| Arc::new(lit(u, placement, lighting, inputs.shadows)))
                        .collect()
                } else {
                    kept.lit
                };
                seen.extend(lit.iter().map(|impostor| Seen {
                    impostor: impostor.clone(),
                    placement,
                    radiance,
                }));
                self.kept.insert((r, o), Kept { lit, ..kept });
            }
            out.push(seen);
        }
        Ok(out)
    }
}
