//! A walk along a scene's camera path through the relief pipeline (paper 3 §6: "17 images for a
//! complete walk around the object"): every frame's image and decisions, each frame scored
//! against the true render of that frame (the software shader through the view camera), the
//! pipeline's frame time beside direct rasterization of the same scene, and how often the
//! critical-point heuristic and the brute-force ratio agree.
//!
//! Invariants: the walk's eyes are the scene's camera path sampled evenly over its keyframes'
//! times, or, for a scene without a path, one orbit around its `look_at` at the camera's
//! distance and height.

use super::frames::{ObjectFrame, ObjectState};
use super::pipeline::{Pipeline, PipelineSettings};
use super::raster::raster_subset;
use super::shader::SoftwareShader;
use super::validity::{Calibration, CriticalPairs, calibrate, verdicts};
use super::{DepthEncoding, ReliefError};
use crate::camera::Pinhole;
use crate::frame::Frame;
use crate::frame::metrics::psnr;
use crate::progress::{Progress, Timings};
use crate::scene::Scene;
use glam::Vec3;
use std::time::{Duration, Instant};

/// Settings of a walk.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkSettings {
    /// Frames along the path.
    pub frames: u32,
    /// The pipeline's settings.
    pub pipeline: PipelineSettings,
    /// Objects drawn as relief impostors (scene ids); empty: every object.
    pub objects: Vec<usize>,
    /// Render the true frame too and score each frame against it.
    pub score: bool,
}

impl Default for WalkSettings {
    fn default() -> Self {
        Self {
            frames: 120,
            pipeline: PipelineSettings::default(),
            objects: Vec::new(),
            score: true,
        }
    }
}

/// One frame of a walk.
#[derive(Clone, Debug)]
pub struct WalkFrame {
    /// Scene time of the frame.
    pub time: f32,
    /// The eye.
    pub eye: Vec3,
    /// Per relief object.
    pub objects: Vec<ObjectFrame>,
    /// The pipeline's time for the frame (without the wait for the rendering thread that
    /// deterministic mode imposes).
    pub frame_time: Duration,
    /// Direct rasterization of the whole scene from the same camera.
    pub raster_time: Duration,
    /// PSNR against the true render (when scored).
    pub psnr: Option<f64>,
    /// PSNR of direct rasterization against the true render (when scored).
    pub raster_psnr: Option<f64>,
}

/// What a walk measured.
#[derive(Clone, Debug)]
pub struct WalkReport {
    /// Every frame.
    pub frames: Vec<WalkFrame>,
    /// Impostors the rendering thread delivered and the pipeline used.
    pub regenerations: u64,
    /// Bytes of impostors held at the end (in use and cached).
    pub bytes: usize,
    /// The interpolated share past which an impostor is obsolete.
    pub threshold: f64,
}

impl WalkReport {
    /// Frames in which any object was in `state`.
    pub fn count(&self, state: ObjectState) -> usize {
        self.frames
            .iter()
            .filter(|f| f.objects.iter().any(|o| o.state == state))
            .count()
    }

    /// Frames in which a cached impostor came back.
    pub fn cache_hits(&self) -> usize {
        self.frames
            .iter()
            .filter(|f| f.objects.iter().any(|o| o.cache_hit))
            .count()
    }

    /// Mean PSNR of the scored frames (infinite frames count as 100 dB).
    pub fn mean_psnr(&self) -> Option<f64> {
        mean(self.frames.iter().filter_map(|f| f.psnr))
    }

    /// The scored frame with the lowest PSNR: its index and PSNR.
    pub fn lowest_psnr(&self) -> Option<(usize, f64)> {
        self.frames
            .iter()
            .enumerate()
            .filter_map(|(k, f)| f.psnr.map(|p| (k, p)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Mean PSNR of direct rasterization against the truth.
    pub fn mean_raster_psnr(&self) -> Option<f64> {
        mean(self.frames.iter().filter_map(|f| f.raster_psnr))
    }

    /// Mean frame time of the pipeline and of direct rasterization.
    pub fn mean_times(&self) -> (Duration, Duration) {
        let n = self.frames.len().max(1) as u32;
        (
            self.frames.iter().map(|f| f.frame_time).sum::<Duration>() / n,
            self.frames.iter().map(|f| f.raster_time).sum::<Duration>() / n,
        )
    }

    /// Share of (frame, object) pairs showing an impostor on which the heuristic (its predicted
    /// share past the threshold) and the brute force (the warp's actual share past it) give the
    /// same verdict, and how many pairs were compared.
    pub fn agreement(&self) -> (f64, usize) {
        let pairs: Vec<bool> = self
            .frames
            .iter()
            .flat_map(|f| &f.objects)
            .filter_map(|o| {
                o.ratio
                    .map(|r| (o.predicted > self.threshold) == (r > self.threshold))
            })
            .collect();
        let agree = pairs.iter().filter(|&&a| a).count();
        (agree as f64 / pairs.len().max(1) as f64, pairs.len())
    }
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = values.map(|p| p.min(100.0)).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// The cameras of a walk of `frames` frames over `scene` (module doc).
pub fn path(scene: &Scene, frames: u32) -> Result<Vec<(f32, Pinhole)>, ReliefError> {
    let spec = &scene.camera;
    let n = frames.max(1);
    let mut out = Vec::with_capacity(n as usize);
    match (spec.path.first(), spec.path.last()) {
        (Some(first), Some(last)) if spec.path.len() > 1 => {
            for i in 0..n {
                let s = if n == 1 {
                    0.0
                } else {
                    i as f32 / (n - 1) as f32
                };
                let t = first.time + (last.time - first.time) * s;
                out.push((t, spec.at(t)?));
            }
        }
        _ => {
            let centre = spec.look_at;
            let r = spec.position - centre;
            let (radius, height) = (Vec3::new(r.x, 0.0, r.z).length(), r.y);
            let start = r.x.atan2(r.z);
            for i in 0..n {
                let a = start + std::f32::consts::TAU * i as f32 / n as f32;
                let eye = centre + Vec3::new(radius * a.sin(), height, radius * a.cos());
                let camera =
                    Pinhole::look_at(eye, centre, spec.up, spec.fov_y, spec.width, spec.height)?
                        .with_near(spec.near);
                out.push((scene.render.time, camera));
            }
        }
    }
    Ok(out)
}

/// Receives each frame of a walk: its index, the frame, and its true render when scored.
pub type FrameSink<'a> = dyn FnMut(usize, &Frame, Option<&Frame>) -> Result<(), ReliefError> + 'a;

/// Walks `scene`'s camera path through the relief pipeline. `sink(i, frame, truth)` receives
/// every frame (and its true render when scored) as it is made.
pub fn walk(
    scene: &Scene,
    settings: &WalkSettings,
    progress: &dyn Progress,
    sink: &mut FrameSink<'_>,
) -> Result<WalkReport, ReliefError> {
    let view = scene.view(scene.render.time)?;
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render)?;
    let objects: Vec<usize> = if settings.objects.is_empty() {
        (0..view.meshes.len()).collect()
    } else {
        settings.objects.clone()
    };
    let others: Vec<usize> = (0..view.meshes.len())
        .filter(|o| !objects.contains(o))
        .collect();
    let all: Vec<usize> = (0..view.meshes.len()).collect();
    let cameras = path(scene, settings.frames)?;
    let mut pipeline = Pipeline::new(shader.clone(), &objects, settings.pipeline.clone())?;
    let mut frames = Vec::with_capacity(cameras.len());
    for (i, (time, camera)) in cameras.iter().enumerate() {
        let started = Instant::now();
        let out = pipeline.frame(camera)?;
        // Less the wait for the rendering thread that deterministic mode imposes.
        let waited: Duration = out
            .timings
            .0
            .iter()
            .filter(|(name, _)| *name == "collect")
            .map(|(_, d)| *d)
            .sum();
        let frame_time = started.elapsed().saturating_sub(waited);
        let started = Instant::now();
        let raster = raster_subset(
            &view,
            &scene.lighting,
            camera,
            &all,
            &mut Timings::default(),
        )?;
        let raster_time = started.elapsed();
        let (mut score, mut raster_score, mut truth) = (None, None, None);
        if settings.score {
            let t = true_frame(&shader, camera, &objects, &others)?;
            score = Some(psnr(&t.color, &out.frame.color, None)?);
            raster_score = Some(psnr(&t.color, &raster.color, None)?);
            truth = Some(t);
        }
        sink(i, &out.frame, truth.as_ref())?;
        frames.push(WalkFrame {
            time: *time,
            eye: camera.position().as_vec3(),
            objects: out.objects,
            frame_time,
            raster_time,
            psnr: score,
            raster_psnr: raster_score,
        });
        progress.advance(1);
    }
    Ok(WalkReport {
        frames,
        regenerations: pipeline.regenerations,
        bytes: pipeline.bytes(),
        threshold: settings.pipeline.threshold,
    })
}

/// The frame a relief walk stands for: the relief objects ray traced by the software shader,
/// the others rasterized, the nearer winning.
pub fn true_frame(
    shader: &SoftwareShader,
    camera: &Pinhole,
    relief: &[usize],
    others: &[usize],
) -> Result<Frame, ReliefError> {
    let mut traced = shader.render(camera, relief)?;
    if others.is_empty() {
        return Ok(traced);
    }
    let raster = raster_subset(
        shader.view(),
        shader.lighting(),
        camera,
        others,
        &mut Timings::default(),
    )?;
    for i in 0..traced.color.pixels().len() {
        let (r, t) = (raster.depth.pixels()[i], traced.depth.pixels()[i]);
        let relief_hit = relief.contains(&(traced.object_id.pixels()[i] as usize));
        if r < t || (!relief_hit && r.is_finite()) {
            traced.color.pixels_mut()[i] = raster.color.pixels()[i];
            traced.depth.pixels_mut()[i] = r;
            traced.object_id.pixels_mut()[i] = raster.object_id.pixels()[i];
        }
    }
    Ok(traced)
}

/// The heuristic against the brute force with no pipeline in between: impostors of `object`
/// made at every `every`-th eye of `eyes` (and calibrated), each judged at the `span` eyes that
/// follow by the heuristic's predicted share and by the warp's actual share. Returns
/// `(predicted, actual)` per judged eye.
pub fn verdicts_along(
    shader: &SoftwareShader,
    object: usize,
    eyes: &[Vec3],
    every: usize,
    span: usize,
    resolution: u32,
    grid: u32,
) -> Result<Vec<(f64, f64)>, ReliefError> {
    let mut out = Vec::new();
    for start in (0..eyes.len()).step_by(every.max(1)) {
        let eye = eyes[start].as_dvec3();
        let Some(imp) = shader.impostor(object, eye, resolution, DepthEncoding::U8, &|| false)?
        else {
            continue;
        };
        let pairs = CriticalPairs::of(&imp, grid);
        let (centre, _) = shader.bounds(object)?;
        let calibration: Calibration = calibrate(&imp, &pairs, centre);
        for e in eyes.iter().skip(start).take(span) {
            let v = verdicts(&imp, &pairs, e.as_dvec3());
            let foot = imp.frame.coordinates(e.as_dvec3());
            out.push((calibration.predict(v.heuristic, (foot.x, foot.y)), v.ratio));
        }
    }
    Ok(out)
}

impl std::fmt::Display for WalkReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.frames.len();
        let (pipeline, raster) = self.mean_times();
        writeln!(
            f,
            "{n} frames: {} warped, {} valid without a warp, {} stale, {} fallback; {} impostors made, {} cache hits",
            self.count(ObjectState::Warping),
            self.count(ObjectState::Valid),
            self.count(ObjectState::Stale),
            self.count(ObjectState::Fallback),
            self.regenerations,
            self.cache_hits(),
        )?;
        writeln!(
            f,
            "frame time {:.1} ms through relief impostors, {:.1} ms by direct rasterization",
            pipeline.as_secs_f64() * 1e3,
            raster.as_secs_f64() * 1e3
        )?;
        if let (Some(p), Some(r), Some((k, low))) = (
            self.mean_psnr(),
            self.mean_raster_psnr(),
            self.lowest_psnr(),
        ) {
            writeln!(
                f,
                "against the software shader's true render: relief {p:.2} dB, direct rasterization {r:.2} dB (mean PSNR); lowest relief frame {low:.2} dB (frame {k})"
            )?;
        }
        let (agree, pairs) = self.agreement();
        write!(
            f,
            "heuristic and brute force (obsolete past {:.0} % interpolated) agree on {:.1} % of {pairs} impostor frames; {:.1} MB of impostors held",
            self.threshold * 100.0,
            agree * 100.0,
            self.bytes as f64 / 1e6
        )
    }
}

impl WalkReport {
    /// The per-frame table as CSV: frame, time, eye, then per object its state, heuristic
    /// error, ratio, regenerated and cache-hit flags; frame times and PSNRs.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "frame,time,eye_x,eye_y,eye_z,object,state,error,predicted,ratio,regenerated,cache_hit,resolution,frame_ms,raster_ms,psnr,raster_psnr\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.4}"));
        for (i, fr) in self.frames.iter().enumerate() {
            for o in &fr.objects {
                s.push_str(&format!(
                    "{i},{:.4},{:.4},{:.4},{:.4},{},{},{:.4},{:.4},{},{},{},{},{:.3},{:.3},{},{}\n",
                    fr.time,
                    fr.eye.x,
                    fr.eye.y,
                    fr.eye.z,
                    o.object,
                    o.state,
                    o.error,
                    o.predicted,
                    opt(o.ratio),
                    o.regenerated as u8,
                    o.cache_hit as u8,
                    o.resolution,
                    fr.frame_time.as_secs_f64() * 1e3,
                    fr.raster_time.as_secs_f64() * 1e3,
                    opt(fr.psnr),
                    opt(fr.raster_psnr),
                ));
            }
        }
        s
    }
}
