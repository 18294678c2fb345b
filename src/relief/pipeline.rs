//! The relief system of paper 3 (§4–5): a warping loop (the caller's thread, which has priority)
//! that shows every frame, and a rendering thread — the software shader — that makes a new
//! relief impostor when the critical-point heuristic says the current one is obsolete.
//!
//! Per object and frame, a state: **valid** (the last pre-warp still fits: Schaufler's test
//! says no critical texel moved half a texel, so only the texture-mapping phase runs),
//! **warping** (pre-warped for this eye), **stale** (the heuristic says obsolete: the old
//! impostor is still warped while a new one is made) or **fallback** (no impostor is good
//! enough: the mesh is rasterized directly, with the same lighting minus what only the software
//! shader does). Around it: an impostor cache searched by view direction before any new
//! request (the paper's "database" of §7), requests ordered by error when several objects
//! compete, a low-resolution impostor first for an object that has none (progressive
//! resolution), camera-path prediction, and the rendering thread yielding the CPU while the
//! frame loop pre-warps.
//!
//! Invariants: the frame loop never waits on the rendering thread, except in deterministic mode,
//! where a request's result is used exactly `latency` frames after it was made (so that the
//! same camera path gives the same decisions and pixels); an impostor crosses threads whole,
//! through a channel; dropping the pipeline stops the thread within one row of ray tracing.

use super::frames::{
    FrameOutput, ObjectFrame, ObjectState, PreparedDraws, PreparedFrame, ReliefDraw,
};
use super::prewarp::{Coefficients, Eye, Prewarped, prewarp};
use super::raster::raster_subset;
use super::shader::SoftwareShader;
use super::texture::draw;
use super::validity::{Calibration, CriticalPairs, RATIO_THRESHOLD, calibrate};
use super::{DepthEncoding, ReliefError, ReliefImpostor};
use crate::camera::Pinhole;
use crate::progress::Timings;
use crate::scene::View;
use glam::DVec3;
use std::collections::{BTreeMap, BinaryHeap};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// Settings of the relief pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineSettings {
    /// Relief resolution, texels a side.
    pub resolution: u32,
    /// Resolution of the first impostor of an object that has none (progressive); `None` makes
    /// the full one at once.
    pub first_resolution: Option<u32>,
    /// How displacements are stored.
    pub encoding: DepthEncoding,
    /// Pre-warp eight-bit displacements by lookup tables (paper §5).
    pub lut: bool,
    /// Interpolated share (interpolated over direct texels) past which an impostor is obsolete
    /// and a new one is requested — judged each frame by the critical-point heuristic,
    /// calibrated against this measure when the impostor was made.
    pub threshold: f64,
    /// Predicted share past which a frame rasterizes the mesh instead.
    pub fallback: f64,
    /// A new impostor is requested once the predicted share passes `threshold × prefetch`
    /// (1: only when obsolete), so that it can arrive before the old one goes stale.
    pub prefetch: f64,
    /// Camera-path prediction: a request is made for where the eye will be this many frames
    /// ahead at its current velocity (0: for the eye as it is).
    pub predict: u32,
    /// Schaufler's test: skip the pre-warp while no critical texel moved this far (texels).
    pub skip_move: f64,
    /// Impostors kept per object for reuse.
    pub cache_size: usize,
    /// Regions a side for the critical pairs.
    pub grid: u32,
    /// An impostor is never used for an eye further than this from its own direction,
    /// degrees (the heuristic is calibrated up to 24°; past grazing views it cannot judge).
    pub max_angle: f64,
    /// Deterministic mode: a request's impostor is used exactly this many frames later (the
    /// frame loop waits for it if need be). `None`: used as soon as it is ready.
    pub deterministic: Option<u32>,
}

impl PipelineSettings {
    /// Checks every setting against its range: shares and angles must be finite and positive
    /// (a NaN threshold would never call an impostor obsolete), resolutions within
    /// [`super::RESOLUTION_RANGE`]. [`Pipeline::new`] checks the settings it is given.
    pub fn validate(&self) -> Result<(), ReliefError> {
        let positive = |name, value: f64, reason| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ReliefError::Setting {
                    name,
                    value,
                    reason,
                })
            }
        };
        positive(
            "threshold",
            self.threshold,
            "must be a positive share, e.g. 0.2",
        )?;
        positive(
            "fallback",
            self.fallback,
            "must be a positive share, e.g. 0.6",
        )?;
        positive(
            "prefetch",
            self.prefetch,
            "must be a positive factor, e.g. 0.75",
        )?;
        positive(
            "max_angle",
            self.max_angle,
            "must be a positive angle in degrees",
        )?;
        if !(self.skip_move.is_finite() && self.skip_move >= 0.0) {
            return Err(ReliefError::Setting {
                name: "skip_move",
                value: self.skip_move,
                reason: "must be a distance in texels, 0 or more",
            });
        }
        for r in [Some(self.resolution), self.first_resolution]
            .into_iter()
            .flatten()
        {
            if !(super::RESOLUTION_RANGE.0..=super::RESOLUTION_RANGE.1).contains(&r) {
                return Err(ReliefError::Resolution(r));
            }
        }
        Ok(())
    }
}

impl Default for PipelineSettings {
    fn default() -> Self {
        Self {
            resolution: 256,
            first_resolution: Some(64),
            encoding: DepthEncoding::U8,
            lut: true,
            threshold: RATIO_THRESHOLD,
            fallback: 0.6,
            prefetch: 0.75,
            predict: 2,
            skip_move: 0.5,
            cache_size: 16,
            grid: 4,
            max_angle: 45.0,
            deterministic: None,
        }
    }
}

/// An impostor in use, with its critical pairs and their calibration.
struct Current {
    impostor: ReliefImpostor,
    pairs: CriticalPairs,
    calibration: Calibration,
}

/// Per relief object.
struct Slot {
    object: usize,
    current: Option<Arc<Current>>,
    /// The eye and image of the last pre-warp of `current`.
    last: Option<(Coefficients, Arc<Prewarped>)>,
    /// Request in flight: id and resolution.
    pending: Option<(u64, u32)>,
    /// Cached impostors and the frame each was put aside.
    cache: Vec<(Arc<Current>, u64)>,
    /// A new impostor arrived since the last frame.
    fresh: bool,
}

/// A request to the rendering thread.
#[derive(Clone, Debug)]
struct Request {
    id: u64,
    object: usize,
    eye: DVec3,
    resolution: u32,
    priority: f64,
}

impl PartialEq for Request {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}
impl Eq for Request {}
impl PartialOrd for Request {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Request {
    /// Larger error first, then the older request.
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.priority
            .total_cmp(&o.priority)
            .then_with(|| o.id.cmp(&self.id))
    }
}

/// What the two threads share.
#[derive(Default)]
struct Shared {
    queue: Mutex<BinaryHeap<Request>>,
    wake: Condvar,
    stop: AtomicBool,
    /// Set while the frame loop warps: the rendering thread waits between rows.
    busy: Mutex<bool>,
    idle: Condvar,
}

/// A finished request.
struct Generated {
    id: u64,
    object: usize,
    result: Result<Option<Current>, ReliefError>,
}

/// The relief pipeline over a scene: its relief objects warped, the others rasterized.
pub struct Pipeline {
    shader: Arc<SoftwareShader>,
    settings: PipelineSettings,
    slots: Vec<Slot>,
    shared: Arc<Shared>,
    results: Receiver<Generated>,
    arrived: BTreeMap<u64, Generated>,
    /// Frame at which each request in flight was made.
    issued: BTreeMap<u64, u64>,
    worker: Option<JoinHandle<()>>,
    /// The previous frame's eye (for camera-path prediction).
    previous_eye: Option<DVec3>,
    next_id: u64,
    frame: u64,
    /// Requests made and impostors brought into use, over the pipeline's life.
    pub regenerations: u64,
}

impl Pipeline {
    /// A pipeline over `shader`'s scene, with relief impostors for the objects `relief` (scene
    /// ids; the others are rasterized every frame). Starts the rendering thread.
    pub fn new(
        shader: Arc<SoftwareShader>,
        relief: &[usize],
        settings: PipelineSettings,
    ) -> Result<Self, ReliefError> {
        settings.validate()?;
        for &o in relief {
            shader.bounds(o)?;
        }
        let shared = Arc::new(Shared::default());
        let (tx, rx) = channel();
        let worker = {
            let (shader, shared) = (shader.clone(), shared.clone());
            let (encoding, grid) = (settings.encoding, settings.grid);
            std::thread::Builder::new()
                .name("relief software shader".into())
                .spawn(move || render_thread(&shader, &shared, encoding, grid, &tx))
                .map_err(|_| ReliefError::Worker("could not be started"))?
        };
        let slots = relief
            .iter()
            .map(|&object| Slot {
                object,
                current: None,
                last: None,
                pending: None,
                cache: Vec::new(),
                fresh: false,
            })
            .collect();
        Ok(Self {
            shader,
            settings,
            slots,
            shared,
            results: rx,
            arrived: BTreeMap::new(),
            issued: BTreeMap::new(),
            worker: Some(worker),
            previous_eye: None,
            next_id: 0,
            frame: 0,
            regenerations: 0,
        })
    }

    /// Renders the next frame through `camera`.
    pub fn frame(&mut self, camera: &Pinhole) -> Result<FrameOutput, ReliefError> {
        let PreparedFrame {
            background: mut frame,
            draws,
            objects,
            mut timings,
        } = self.prepare(camera)?;
        timings.time("texture map", || {
            for d in &draws {
                draw(&d.image, &d.frame, camera, &mut frame, d.object);
            }
        });
        Ok(FrameOutput {
            frame,
            objects,
            timings,
        })
    }

    /// The frame through `camera` up to its texture-mapping phase: impostors collected,
    /// decided, pre-warped; the rest rasterized. [`Pipeline::frame`] maps the impostors on the
    /// CPU; the GPU crate maps them on the graphics hardware.
    pub fn prepare(&mut self, camera: &Pinhole) -> Result<PreparedFrame, ReliefError> {
        let PreparedDraws {
            rasterized,
            draws,
            objects,
            mut timings,
        } = self.prepare_draws(camera)?;
        let background = raster_subset(
            self.shader.view(),
            self.shader.lighting(),
            camera,
            &rasterized,
            &mut timings,
        )?;
        Ok(PreparedFrame {
            background,
            draws,
            objects,
            timings,
        })
    }

    /// The scene the pipeline stands on (still: as it was when the pipeline started).
    pub fn view(&self) -> &View {
        self.shader.view()
    }

    /// Its lighting.
    pub fn lighting(&self) -> &crate::scene::Lighting {
        self.shader.lighting()
    }

    /// The frame through `camera` up to its drawing: impostors collected, decided,
    /// pre-warped; which objects are drawn directly ([`raster_subset`] draws them on the CPU).
    pub fn prepare_draws(&mut self, camera: &Pinhole) -> Result<PreparedDraws, ReliefError> {
        let mut timings = Timings::default();
        timings.time("collect", || self.collect())?;
        let eye = camera.position();
        let mut outputs = Vec::with_capacity(self.slots.len());
        let regenerated: Vec<bool> = self
            .slots
            .iter_mut()
            .map(|s| std::mem::take(&mut s.fresh))
            .collect();
        // Decide and pre-warp with the rendering thread held off (the warping thread's
        // priority, paper §6); it runs again while the frame is composed.
        self.set_busy(true);
        let decided = timings.time("pre-warp", || {
            (0..self.slots.len())
                .map(|i| self.decide(i, eye, regenerated[i]))
                .collect::<Vec<_>>()
        });
        self.set_busy(false);
        // The frame: rasterized objects first (with their ids), then the warped impostors.
        let fallback: Vec<usize> = decided
            .iter()
            .filter(|d| d.state == ObjectState::Fallback)
            .map(|d| d.object)
            .collect();
        let relief: Vec<usize> = self.slots.iter().map(|s| s.object).collect();
        let view = self.shader.view();
        let rasterized: Vec<usize> = (0..view.meshes.len())
            .filter(|o| !relief.contains(o) || fallback.contains(o))
            .collect();
        let draws = self
            .slots
            .iter()
            .zip(&decided)
            .filter_map(|(slot, d)| match (&slot.last, &slot.current) {
                (Some((_, image)), Some(cur)) if d.state != ObjectState::Fallback => {
                    Some(ReliefDraw {
                        object: slot.object as u32,
                        image: image.clone(),
                        frame: cur.impostor.frame,
                    })
                }
                _ => None,
            })
            .collect();
        outputs.extend(decided);
        self.previous_eye = Some(eye);
        self.frame += 1;
        Ok(PreparedDraws {
            rasterized,
            draws,
            objects: outputs,
            timings,
        })
    }

    /// Takes finished impostors from the rendering thread: all that are ready, or in
    /// deterministic mode exactly those due this frame (waiting for them).
    fn collect(&mut self) -> Result<(), ReliefError> {
        let due = |issued: u64, frame: u64, latency: u32| issued + latency as u64 <= frame;
        match self.settings.deterministic {
            None => {
                while let Ok(g) = self.results.try_recv() {
                    self.arrived.insert(g.id, g);
                }
            }
            Some(latency) => {
                let frame = self.frame;
                while self
                    .issued
                    .iter()
                    .any(|(id, &at)| due(at, frame, latency) && !self.arrived.contains_key(id))
                {
                    let g = self
                        .results
                        .recv()
                        .map_err(|_| ReliefError::Worker("it stopped before answering"))?;
                    self.arrived.insert(g.id, g);
                }
            }
        }
        let ready: Vec<u64> = self
            .arrived
            .keys()
            .copied()
            .filter(|id| match self.settings.deterministic {
                None => true,
                Some(l) => self
                    .issued
                    .get(id)
                    .is_some_and(|&at| due(at, self.frame, l)),
            })
            .collect();
        for id in ready {
            let Some(g) = self.arrived.remove(&id) else {
                continue;
            };
            self.issued.remove(&id);
            let Some(slot) = self.slots.iter_mut().find(|s| s.object == g.object) else {
                continue;
            };
            if slot.pending.map(|p| p.0) == Some(id) {
                slot.pending = None;
            }
            let made = match g.result {
                // The eye moved inside the object before the impostor was made: none.
                Err(ReliefError::EyeInside { .. }) => None,
                other => other?,
            };
            if let Some(made) = made {
                if let Some(old) = slot.current.take() {
                    slot.cache.push((old, self.frame));
                    if slot.cache.len() > self.settings.cache_size {
                        // Evict the least recently used.
                        if let Some(i) = (0..slot.cache.len()).min_by_key(|&i| slot.cache[i].1) {
                            slot.cache.remove(i);
                        }
                    }
                }
                slot.current = Some(Arc::new(made));
                slot.last = None;
                slot.fresh = true;
                self.regenerations += 1;
            }
        }
        Ok(())
    }

    /// The state of slot `i` for `eye`: cache lookup, request, pre-warp.
    fn decide(&mut self, i: usize, eye: DVec3, regenerated: bool) -> ObjectFrame {
        let settings = self.settings.clone();
        let frame_no = self.frame;
        // The heuristic, and the share it predicts.
        let cos_max = settings.max_angle.to_radians().cos();
        let judge = |c: &Current| {
            let fr = &c.impostor.frame;
            if (eye - fr.centre()).normalize_or_zero().dot(fr.f) < cos_max {
                return (f64::INFINITY, f64::INFINITY);
            }
            let k = Coefficients::new(fr, Eye::Point(eye));
            let e = c.pairs.error(k.as_ref());
            match k {
                Some(k) => (e, c.calibration.predict(e, k.epipole)),
                None => (f64::INFINITY, f64::INFINITY),
            }
        };
        let slot = &mut self.slots[i];
        let (mut error, mut predicted) = slot
            .current
            .as_ref()
            .map_or((f64::INFINITY, f64::INFINITY), |c| judge(c));
        let mut cache_hit = false;
        let full = slot
            .current
            .as_ref()
            .is_some_and(|c| c.impostor.frame.width == settings.resolution);
        if predicted > settings.threshold || !full {
            // The cache: the impostor there the heuristic judges best for this eye.
            let best = slot
                .cache
                .iter()
                .enumerate()
                .map(|(j, (c, _))| (j, judge(c)))
                .min_by(|a, b| a.1.1.total_cmp(&b.1.1));
            if let Some((j, (e, p))) = best {
                let better_res = slot.cache[j].0.impostor.frame.width >= settings.resolution;
                if p <= settings.threshold && (p < predicted || !full) && better_res {
                    let (cached, _) = slot.cache.remove(j);
                    if let Some(old) = slot.current.replace(cached) {
                        slot.cache.push((old, frame_no));
                    }
                    slot.last = None;
                    (error, predicted) = (e, p);
                    cache_hit = true;
                }
            }
        }
        let full = slot
            .current
            .as_ref()
            .is_some_and(|c| c.impostor.frame.width == settings.resolution);
        // A request when obsolete, or to replace a low-resolution first impostor.
        let mut request = None;
        // No relief frame faces an eye inside the object's bounding sphere: it falls back.
        let outside = self
            .shader
            .bounds(slot.object)
            .is_ok_and(|(c, r)| (eye - c).length() > r * 1.01);
        if outside
            && slot.pending.is_none()
            && (predicted > settings.threshold * settings.prefetch || !full)
        {
            let resolution = match (&slot.current, settings.first_resolution) {
                (None, Some(r)) => r.min(settings.resolution),
                _ => settings.resolution,
            };
            request = Some((slot.object, resolution, predicted));
        }
        let state = match &slot.current {
            None => ObjectState::Fallback,
            Some(_) if predicted > settings.fallback => ObjectState::Fallback,
            Some(c) => {
                let k = Coefficients::new(&c.impostor.frame, Eye::Point(eye));
                let fits = match (&slot.last, &k) {
                    (Some((then, _)), Some(now)) => {
                        c.pairs.largest_move(then, now) < settings.skip_move
                    }
                    _ => false,
                };
                if fits {
                    ObjectState::Valid
                } else {
                    match (k, prewarp(&c.impostor, Eye::Point(eye), settings.lut)) {
                        (Some(k), Some(p)) if p.direct > 0 => {
                            slot.last = Some((k, Arc::new(p)));
                            if predicted > settings.threshold {
                                ObjectState::Stale
                            } else {
                                ObjectState::Warping
                            }
                        }
                        _ => ObjectState::Fallback,
                    }
                }
            }
        };
        let (ratio, resolution) = match (state, &slot.last, &slot.current) {
            (ObjectState::Fallback, _, _) => (None, 0),
            (_, Some((_, p)), Some(c)) => (Some(p.interpolated_ratio()), c.impostor.frame.width),
            _ => (None, 0),
        };
        let object = slot.object;
        if let Some((object, resolution, error)) = request {
            let eye = self.request_eye(object, eye);
            let id = self.next_id;
            self.next_id += 1;
            self.slots[i].pending = Some((id, resolution));
            self.issued.insert(id, frame_no);
            let priority = if error.is_finite() { error } else { f64::MAX };
            if let Ok(mut q) = self.shared.queue.lock() {
                q.push(Request {
                    id,
                    object,
                    eye,
                    resolution,
                    priority,
                });
            }
            self.shared.wake.notify_one();
        }
        ObjectFrame {
            object,
            state,
            error,
            predicted,
            ratio,
            regenerated: regenerated && !cache_hit,
            cache_hit,
            regenerating: self.slots[i].pending.is_some(),
            resolution,
        }
    }

    /// Where to make a new impostor of `object` for: the eye, or with camera-path prediction
    /// the eye `predict` frames ahead at its velocity (unless that is inside the object).
    fn request_eye(&self, object: usize, eye: DVec3) -> DVec3 {
        let (Some(previous), n) = (self.previous_eye, self.settings.predict) else {
            return eye;
        };
        let ahead = eye + (eye - previous) * n as f64;
        match self.shader.bounds(object) {
            Ok((c, r)) if (ahead - c).length() > r * 1.01 && ahead.is_finite() => ahead,
            _ => eye,
        }
    }

    fn set_busy(&self, busy: bool) {
        if let Ok(mut b) = self.shared.busy.lock() {
            *b = busy;
        }
        if !busy {
            self.shared.idle.notify_all();
        }
    }

    /// The impostor object `object` shows now, if any.
    pub fn current(&self, object: usize) -> Option<&ReliefImpostor> {
        self.slots
            .iter()
            .find(|s| s.object == object)
            .and_then(|s| s.current.as_ref())
            .map(|c| &c.impostor)
    }

    /// Impostors held in the caches, over all objects.
    pub fn cached(&self) -> usize {
        self.slots.iter().map(|s| s.cache.len()).sum()
    }

    /// Bytes of every impostor held (in use and cached).
    pub fn bytes(&self) -> usize {
        self.slots
            .iter()
            .flat_map(|s| s.current.iter().chain(s.cache.iter().map(|c| &c.0)))
            .map(|c| c.impostor.bytes())
            .sum()
    }

    /// The settings.
    pub fn settings(&self) -> &PipelineSettings {
        &self.settings
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        self.set_busy(false);
        self.shared.wake.notify_all();
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

/// The rendering thread: highest-error request first, one row at a time, waiting while the
/// frame loop is busy; then the new impostor's critical pairs and their calibration.
fn render_thread(
    shader: &SoftwareShader,
    shared: &Shared,
    encoding: DepthEncoding,
    grid: u32,
    results: &Sender<Generated>,
) {
    loop {
        let request = {
            let Ok(mut q) = shared.queue.lock() else {
                return;
            };
            loop {
                if shared.stop.load(Ordering::SeqCst) {
                    return;
                }
                if let Some(r) = q.pop() {
                    break r;
                }
                q = match shared.wake.wait(q) {
                    Ok(q) => q,
                    Err(_) => return,
                };
            }
        };
        let cancel = || {
            if let Ok(mut busy) = shared.busy.lock() {
                while *busy && !shared.stop.load(Ordering::SeqCst) {
                    busy = match shared.idle.wait(busy) {
                        Ok(b) => b,
                        Err(_) => return true,
                    };
                }
            }
            shared.stop.load(Ordering::SeqCst)
        };
        let result = shader
            .impostor(
                request.object,
                request.eye,
                request.resolution,
                encoding,
                &cancel,
            )
            .and_then(|made| {
                let Some(impostor) = made else {
                    return Ok(None);
                };
                let (centre, _) = shader.bounds(request.object)?;
                let pairs = CriticalPairs::of(&impostor, grid);
                let calibration = calibrate(&impostor, &pairs, centre);
                Ok(Some(Current {
                    impostor,
                    pairs,
                    calibration,
                }))
            });
        if shared.stop.load(Ordering::SeqCst) {
            return;
        }
        let generated = Generated {
            id: request.id,
            object: request.object,
            result,
        };
        if results.send(generated).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::shader::tests::sphere_on_floor;
    use super::*;
    use glam::Vec3;

    fn camera(eye: Vec3) -> Pinhole {
        Pinhole::look_at(eye, Vec3::new(0.0, 1.2, 0.0), Vec3::Y, 45.0, 64, 48).unwrap()
    }

    fn eyes(n: usize, speed: f32) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let a = i as f32 * speed;
                Vec3::new(5.0 * a.sin(), 1.8 + 0.5 * (a * 0.7).sin(), 5.0 * a.cos())
            })
            .collect()
    }

    fn settings() -> PipelineSettings {
        PipelineSettings {
            resolution: 48,
            first_resolution: Some(16),
            predict: 0,
            ..Default::default()
        }
    }

    #[test]
    fn deterministic_mode_repeats_its_decisions_and_pixels() {
        let (view, lighting, rs) = sphere_on_floor();
        let shader = SoftwareShader::new(&view, &lighting, &rs).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let s = PipelineSettings {
                    deterministic: Some(2),
                    ..settings()
                };
                let mut p = Pipeline::new(shader.clone(), &[1], s).unwrap();
                eyes(40, 0.08)
                    .iter()
                    .map(|&e| {
                        let out = p.frame(&camera(e)).unwrap();
                        (out.objects, out.frame.color.into_vec())
                    })
                    .collect::<Vec<_>>()
            })
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a, b);
        let states: Vec<_> = a.iter().map(|(o, _)| o[0].state).collect();
        // It started in fallback, then warped, and regenerated along the way.
        assert_eq!(states[0], ObjectState::Fallback);
        assert!(states.contains(&ObjectState::Warping), "{states:?}");
        assert!(a.iter().filter(|(o, _)| o[0].regenerated).count() >= 2);
    }

    #[test]
    fn a_still_camera_reuses_its_warp_and_a_turned_one_comes_back_from_the_cache() {
        let (view, lighting, rs) = sphere_on_floor();
        let shader = SoftwareShader::new(&view, &lighting, &rs).unwrap();
        let s = PipelineSettings {
            deterministic: Some(1),
            first_resolution: None,
            ..settings()
        };
        let mut p = Pipeline::new(shader, &[1], s).unwrap();
        let (front, side) = (Vec3::new(0.0, 1.8, 5.0), Vec3::new(5.0, 1.8, 0.0));
        let mut states = Vec::new();
        for eye in [front, front, front, front, side, side, side, front, front] {
            let out = p.frame(&camera(eye)).unwrap();
            states.push((out.objects[0].state, out.objects[0].cache_hit));
        }
        use ObjectState::{Fallback, Valid, Warping};
        // No impostor, then one made for the front: warped once, then reused unwarped.
        assert_eq!(
            &states[..4],
            &[
                (Fallback, false),
                (Warping, false),
                (Valid, false),
                (Valid, false)
            ]
        );
        // 90° away: obsolete past use until one is made for the side.
        assert_eq!(states[4], (Fallback, false));
        assert_eq!(states[5].0, Warping);
        // Back to the front: the first impostor returns from the cache.
        assert_eq!(states[7], (Warping, true));
        assert_eq!(states[8], (Valid, false));
        assert_eq!(p.cached(), 1);
    }

    #[test]
    fn a_fast_random_path_neither_deadlocks_nor_shows_a_half_made_impostor() {
        let (view, lighting, rs) = sphere_on_floor();
        let shader = SoftwareShader::new(&view, &lighting, &rs).unwrap();
        let mut p = Pipeline::new(shader.clone(), &[0, 1], settings()).unwrap();
        let mut seed = 3u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut checked = 0;
        for i in 0..600 {
            if checked >= 3 {
                break;
            }
            // A frame's pace: the rendering thread has the idle time an interactive loop leaves.
            std::thread::sleep(std::time::Duration::from_millis(1));
            let a = rnd() * 6.3;
            let eye = Vec3::new(6.0 * a.sin(), 1.0 + 3.0 * rnd(), 6.0 * a.cos());
            let out = p.frame(&camera(eye)).unwrap();
            assert_eq!(out.objects.len(), 2);
            // Every few frames: the ball's impostor in use is exactly what the shader makes for
            // its eye — whole, never a half-written one.
            if i % 20 == 0
                && let Some(imp) = p.current(1)
            {
                let again = shader
                    .impostor(1, imp.eye, imp.frame.width, imp.encoding(), &|| false)
                    .unwrap()
                    .unwrap();
                assert_eq!(&again, imp);
                checked += 1;
            }
        }
        assert!(checked >= 3, "{checked}");
        // Shut down while the thread may be mid-impostor: bounded time.
        let started = std::time::Instant::now();
        drop(p);
        assert!(started.elapsed() < std::time::Duration::from_secs(5));
    }
}
