//! The library's one list of methods ([`trompe::methods::MethodKind`]) with a device: a
//! [`DeviceRenderer`] runs a method on the GPU where this crate has its GPU path, and is the
//! library's CPU [`Renderer`] otherwise. `trompe render --device` and `trompe bench gpu` go
//! through it.
//!
//! | method | on the GPU |
//! |---|---|
//! | `trace` | Whitted ray tracing through the exact BVH, one compute invocation a pixel ([`crate::trace`]); `--primary rasterized` draws the eye's hits with the GPU rasterizer |
//! | `raster` | the eye's hits drawn by the GPU rasterizer into a visibility buffer, shaded at depth 1 (mirrors and glass look the panorama up), shadows traced |
//! | `impostor`, `pinhole-impostor` | the tracer, what mirrors and glass send out answered by walking their impostors in the shader ([`crate::walk`]); impostors drawn by the GPU rasterizer ([`crate::build`]), graph cameras' frustum by frustum; all kept across frames, placed and lit by the library's [`Sequence`] |
//! | `octahedral` | the atlases the library bakes drawn by the engines' shader (`shaders/octahedral_impostor.wgsl`), one instanced draw an atlas, then shaded ([`crate::octahedral`]); kept while nothing moves |
//! | `c3rc` | the G-buffer traced, the library's plan of cameras and culled kd-tree nodes on the CPU, every point projected through its continuous 3-ray camera in a compute shader and splatted (the nearest to the mirror by two 32-bit atomic minimum passes), then the tracer with the splats answering first reflections ([`crate::hybrid`]) |
//! | `relief` | the library's relief pipeline (the software shader's thread, the frame loop's decisions and pre-warps) on the CPU, as paper 3 splits it; the objects without relief drawn by the GPU's rasterizer and each pre-warped relief texture mapped over them onto its base quad with per-pixel depth, uploads double-buffered ([`crate::relief`]) |
//! | `layered`, `projective` | the layers the library photographs and builds (paper 4), or its photographs whole (the paper's baseline), uploaded once and blended by the GPU's texturing shader ([`crate::layers`], [`crate::views`]), over the panorama |
//! | `envmap` | not yet: `--device gpu` refuses it, `--device auto` runs it on the CPU |
//!
//! Invariant: a frame's pixels depend only on the scene, the method, the time and the camera,
//! on either device; the two devices' frames of one input agree within the bounds the tests
//! state (`tests/system/trace.rs`).

use crate::device::{Gpu, GpuError, GpuRequest};
use crate::trace::{GpuTracer, Secondary};
use glam::Mat4;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::methods::{MethodError, MethodFrame, MethodKind, MethodSettings, Renderer};
use trompe::progress::{Progress, Timings};
use trompe::render::{Method, Primary, ReflectorImpostors, Refraction, RenderOptions, Sequence};
use trompe::scene::RenderSettings;
use trompe::scene::Scene;

/// Where a method runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Device {
    /// The library's CPU path.
    #[default]
    Cpu,
    /// The GPU path (a hardware adapter, or a software one such as lavapipe); a method without
    /// one is refused.
    Gpu,
    /// The GPU path where the method has one and a hardware GPU is present, else the CPU.
    Auto,
}

/// Whether `kind` has a GPU path in this crate.
pub fn has_gpu_path(kind: MethodKind) -> bool {
    matches!(
        kind,
        MethodKind::Trace
            | MethodKind::Raster
            | MethodKind::Impostor
            | MethodKind::PinholeImpostor
            | MethodKind::Octahedral
            | MethodKind::Layered
            | MethodKind::Projective
            | MethodKind::C3rc
            | MethodKind::Relief
    )
}

/// The methods with a GPU path, by name.
pub fn gpu_methods() -> Vec<&'static str> {
    MethodKind::ALL
        .into_iter()
        .filter(|k| has_gpu_path(*k))
        .map(MethodKind::name)
        .collect()
}

/// The GPU `device` calls for with `kind`: `None` for the CPU. `Gpu` refuses a method without
/// a GPU path, and fails when no adapter opens; `Auto` falls back to the CPU in both cases.
pub fn open_for(device: Device, kind: MethodKind) -> Result<Option<Gpu>, GpuError> {
    check_device(device, kind)?;
    match device {
        Device::Auto if !has_gpu_path(kind) => Ok(None),
        _ => open(device),
    }
}

/// The GPU `device` calls for, for work that has a GPU path: `None` for the CPU. `Gpu` fails
/// when no adapter opens; `Auto` opens a hardware GPU or falls back to the CPU.
pub fn open(device: Device) -> Result<Option<Gpu>, GpuError> {
    match device {
        Device::Cpu => Ok(None),
        Device::Gpu => GpuRequest::new().open().map(Some),
        Device::Auto => Ok(GpuRequest::new().software(false).open().ok()),
    }
}

/// Refuses `--device gpu` for a method without a GPU path, before any work.
pub fn check_device(device: Device, kind: MethodKind) -> Result<(), GpuError> {
    match device {
        Device::Gpu if !has_gpu_path(kind) => Err(no_gpu_path(kind)),
        _ => Ok(()),
    }
}

/// The refusal of a method without a GPU path.
fn no_gpu_path(kind: MethodKind) -> GpuError {
    GpuError::Unsupported {
        what: format!(
            "--method {} has no GPU path yet (methods on the GPU: {})",
            kind.name(),
            gpu_methods().join(", ")
        ),
    }
}

/// Why a frame could not be made, on either device.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// The CPU method's error.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// The GPU's.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The scene at that time.
    #[error(transparent)]
    View(#[from] trompe::scene::ViewError),
    /// Master textures that do not fit the mesh, or could not be read.
    #[error(transparent)]
    Master(#[from] trompe::master::MasterError),
}

/// A method prepared over a scene on one device.
pub enum DeviceRenderer<'a> {
    /// The library's CPU renderer.
    Cpu(Box<Renderer<'a>>),
    /// A GPU path.
    Gpu(Box<GpuMethod<'a>>),
    /// The octahedral method on the GPU.
    Octahedral(Box<GpuOctahedral<'a>>),
    /// The layered and projective methods on the GPU.
    Photographed(Box<GpuPhotographed<'a>>),
    /// The `c3rc` method on the GPU.
    Hybrid(Box<crate::hybrid::GpuHybridMethod<'a>>),
    /// The `relief` method on the GPU.
    Relief(Box<crate::relief::GpuReliefMethod<'a>>),
}

/// The layered or projective method on the GPU, over one scene: the library's photographs of it
/// (cut into layers, or whole), uploaded on the first frame and kept, as the CPU keeps them.
pub struct GpuPhotographed<'a> {
    gpu: &'a Gpu,
    scene: &'a Scene,
    kind: MethodKind,
    settings: MethodSettings,
    kept: Option<Photographs<'a>>,
}

/// What a photographed method keeps on the device.
enum Photographs<'a> {
    /// The layers (`layered`).
    Layers(crate::layers::GpuLayers<'a>),
    /// The whole photographs (`projective`).
    Whole(crate::views::GpuViews<'a>),
}

/// The octahedral method on the GPU, over one scene.
pub struct GpuOctahedral<'a> {
    gpu: &'a Gpu,
    scene: &'a Scene,
    settings: MethodSettings,
    /// The atlases on the device and the objects' poses they were baked at: kept while nothing
    /// moves or deforms, as the CPU keeps its atlases.
    /// With what a frame that keeps them reports.
    kept: Option<(Vec<Mat4>, crate::octahedral::GpuAtlases<'a>, String)>,
}

/// A method on the GPU, over one scene.
pub struct GpuMethod<'a> {
    gpu: &'a Gpu,
    scene: &'a Scene,
    /// One with [`has_gpu_path`].
    kind: MethodKind,
    /// How the eye's hits are found.
    primary: Primary,
    /// How the eye's refractions into glass are found.
    refraction: Refraction,
    /// The scene on the device and the objects' poses it was uploaded at: kept while nothing
    /// moves or deforms (the camera may move), as the CPU keeps its BVH.
    kept: Option<(Vec<Mat4>, GpuTracer<'a>)>,
    /// Under an impostor method: the library's sequence, which builds, keeps, places and lights
    /// the impostors, and the answers the kept upload holds.
    impostors: Option<(Sequence<'a>, Option<Arc<ReflectorImpostors>>)>,
}

impl<'a> DeviceRenderer<'a> {
    /// `kind` over `scene` on `gpu`, or on the CPU without one.
    pub fn new(
        scene: &'a Scene,
        kind: MethodKind,
        settings: MethodSettings,
        gpu: Option<&'a Gpu>,
    ) -> Result<Self, DeviceError> {
        match gpu {
            None => Ok(DeviceRenderer::Cpu(Box::new(Renderer::new(
                scene, kind, settings,
            )?))),
            Some(_) if !has_gpu_path(kind) => Err(no_gpu_path(kind).into()),
            Some(gpu) if matches!(kind, MethodKind::Layered | MethodKind::Projective) => {
                // The CPU renderer's checks, and the GPU blend's, before any work.
                Renderer::new(scene, kind, settings.clone())?;
                crate::texturing::check_settings(&settings.layers)?;
                Ok(DeviceRenderer::Photographed(Box::new(GpuPhotographed {
                    gpu,
                    scene,
                    kind,
                    settings,
                    kept: None,
                })))
            }
            Some(gpu) if kind == MethodKind::Octahedral => {
                // The CPU renderer's checks of the settings, before any work.
                Renderer::new(scene, kind, settings.clone())?;
                Ok(DeviceRenderer::Octahedral(Box::new(GpuOctahedral {
                    gpu,
                    scene,
                    settings,
                    kept: None,
                })))
            }
            Some(gpu) => {
                if let Some(reason) = kind.refusal() {
                    return Err(MethodError::Refused {
                        method: kind,
                        reason,
                    }
                    .into());
                }
                // The GPU draws through a pinhole: a lens is the CPU tracer's alone.
                if let Some(lens) = &scene.camera.lens {
                    return Err(MethodError::from(trompe::render::RenderError::Lens {
                        lens: lens.model().name(),
                        method: "the GPU",
                    })
                    .into());
                }
                if kind == MethodKind::Relief {
                    // The CPU renderer's checks of the settings, before any work.
                    Renderer::new(scene, kind, settings.clone())?;
                    return Ok(DeviceRenderer::Relief(Box::new(
                        crate::relief::GpuReliefMethod::new(gpu, scene, settings),
                    )));
                }
                if kind == MethodKind::C3rc {
                    return Ok(DeviceRenderer::Hybrid(Box::new(
                        crate::hybrid::GpuHybridMethod::new(gpu, scene, settings.hybrid),
                    )));
                }
                // The raster method's glass looks the panorama up: it refracts nothing.
                let (primary, refraction) = match kind {
                    MethodKind::Raster => (Primary::Rasterized, Refraction::Exact),
                    _ => (settings.primary, settings.refraction),
                };
                let resolution = settings.impostor_resolution;
                let method = match kind {
                    MethodKind::Impostor => Some(Method::Impostor(resolution)),
                    MethodKind::PinholeImpostor => Some(Method::PinholeImpostor(resolution)),
                    _ => None,
                };
                let impostors = method.map(|method| {
                    let options = RenderOptions {
                        method,
                        refraction: settings.refraction,
                        mirrors: settings.mirrors,
                        primary,
                    };
                    let drawer = Arc::new(crate::build::GpuDrawer(gpu));
                    (Sequence::new(scene, options).with_drawer(drawer), None)
                });
                Ok(DeviceRenderer::Gpu(Box::new(GpuMethod {
                    gpu,
                    scene,
                    kind,
                    primary,
                    refraction,
                    kept: None,
                    impostors,
                })))
            }
        }
    }

    /// The method.
    pub fn kind(&self) -> MethodKind {
        match self {
            DeviceRenderer::Cpu(r) => r.kind(),
            DeviceRenderer::Gpu(m) => m.kind,
            DeviceRenderer::Octahedral(_) => MethodKind::Octahedral,
            DeviceRenderer::Photographed(m) => m.kind,
            DeviceRenderer::Hybrid(_) => MethodKind::C3rc,
            DeviceRenderer::Relief(_) => MethodKind::Relief,
        }
    }

    /// The adapter's name, or `"CPU"`.
    pub fn device_name(&self) -> &str {
        match self {
            DeviceRenderer::Cpu(_) => "CPU",
            DeviceRenderer::Gpu(m) => m.gpu.name(),
            DeviceRenderer::Octahedral(m) => m.gpu.name(),
            DeviceRenderer::Photographed(m) => m.gpu.name(),
            DeviceRenderer::Hybrid(m) => m.device_name(),
            DeviceRenderer::Relief(m) => m.device_name(),
        }
    }

    /// The frame at time `t` through `camera`, or the scene's camera at `t`.
    pub fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn Progress,
    ) -> Result<MethodFrame, DeviceError> {
        match self {
            DeviceRenderer::Cpu(renderer) => Ok(renderer.frame(t, camera, progress)?),
            DeviceRenderer::Octahedral(m) => m.frame(t, camera, progress),
            DeviceRenderer::Photographed(m) => m.frame(t, camera, progress),
            DeviceRenderer::Hybrid(m) => m.frame(t, camera, progress),
            DeviceRenderer::Relief(m) => m.frame(t, camera, progress),
            DeviceRenderer::Gpu(m) => {
                let GpuMethod {
                    gpu,
                    scene,
                    kind,
                    primary,
                    refraction,
                    kept,
                    impostors,
                } = m.as_mut();
                debug_assert!(has_gpu_path(*kind));
                // The same refusal as the CPU renderer's, before any work.
                if !t.is_finite() {
                    return Err(MethodError::from(trompe::render::RenderError::Time(t)).into());
                }
                let poses = scene.poses_at(t);
                let still = !scene.deforms();
                // Under an impostor method the library prepares the frame (the view, the
                // impostors kept, placed and lit); the upload stands while its answers do.
                let (view, answers, mut timings, built) = match impostors {
                    Some((sequence, _)) => {
                        let prepared = sequence
                            .impostor_answers(t, camera)
                            .map_err(MethodError::from)?
                            .ok_or_else(|| GpuError::Unsupported {
                                what: format!("{kind}: a method that builds no impostors"),
                            })?;
                        let report = prepared.report.to_string();
                        let answers = Some((prepared.answers, prepared.bvh));
                        (prepared.view, answers, prepared.timings, Some(report))
                    }
                    None => {
                        let mut view = scene.view(t)?;
                        if let Some(camera) = camera {
                            view.camera = camera;
                        }
                        (view, None, Timings::default(), None)
                    }
                };
                let same_answers = match (impostors.as_ref().and_then(|i| i.1.as_ref()), &answers) {
                    (Some(a), Some((b, _))) => Arc::ptr_eq(a, b),
                    (None, None) => true,
                    _ => false,
                };
                let reused =
                    still && same_answers && kept.as_ref().is_some_and(|(at, _)| at == &poses);
                let (_, tracer) = match &mut *kept {
                    Some(k) if reused => k,
                    slot => {
                        // The raster method: what mirrors and glass send out takes the
                        // panorama's radiance (depth 1), as on the CPU.
                        let settings = match kind {
                            MethodKind::Raster => RenderSettings {
                                max_depth: 1,
                                ..scene.render
                            },
                            _ => scene.render,
                        };
                        let secondary = match &answers {
                            Some((answers, bvh)) => Secondary::Impostors { answers, bvh },
                            None => Secondary::Exact,
                        };
                        let tracer = timings.time("build BVH, upload the scene", || {
                            GpuTracer::with_secondary(
                                gpu,
                                &view,
                                &scene.lighting,
                                &settings,
                                (*primary, *refraction),
                                secondary,
                            )
                        })?;
                        slot.insert((poses, tracer))
                    }
                };
                if let Some((_, held)) = impostors {
                    *held = answers.map(|(a, _)| a);
                }
                let frame = timings.time("GPU frame", || tracer.frame(&view.camera))?;
                trompe::render::check_radiance(&frame).map_err(MethodError::from)?;
                if !still {
                    *kept = None;
                }
                progress.advance(u64::from(frame.color.height()));
                let scene_state = if reused { "kept" } else { "uploaded" };
                let report = match built {
                    Some(impostors) => {
                        format!("on {}: scene {scene_state}; {impostors}", gpu.name())
                    }
                    None => format!("on {}: scene {scene_state}", gpu.name()),
                };
                Ok(MethodFrame {
                    frame,
                    timings,
                    report,
                    state: Vec::new(),
                })
            }
        }
    }
}

impl GpuOctahedral<'_> {
    /// The frame at time `t` through `camera`, or the scene's camera at `t`: the atlases baked
    /// by the library (kept while nothing moves), drawn and shaded on the GPU.
    fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn Progress,
    ) -> Result<MethodFrame, DeviceError> {
        if !t.is_finite() {
            return Err(MethodError::from(trompe::render::RenderError::Time(t)).into());
        }
        let scene = self.scene;
        let mut timings = Timings::default();
        let poses = scene.poses_at(t);
        let still = !scene.deforms();
        let rebake = !matches!(&self.kept, Some((at, _, _)) if still && *at == poses);
        let n = self.settings.octahedral_frames;
        let (atlases, report) = match (rebake, &self.kept) {
            (false, Some((_, atlases, kept))) => (atlases, kept.clone()),
            _ => {
                let bake = self.settings.octahedral_bake();
                let baked = timings
                    .time("bake atlases", || {
                        trompe::octahedral::scene::SceneAtlases::bake(scene, t, bake, &())
                    })
                    .map_err(MethodError::from)?;
                let uploaded = timings.time("upload atlases", || {
                    crate::octahedral::GpuAtlases::new(
                        self.gpu,
                        &baked,
                        &scene.lighting,
                        &scene.render,
                    )
                })?;
                let kept = (poses, uploaded, baked.report(n, false));
                (&self.kept.insert(kept).1, baked.report(n, true))
            }
        };
        let camera = match camera {
            Some(c) => c,
            None => scene.camera.at(t).map_err(MethodError::from)?,
        };
        let frame = timings.time("GPU frame", || atlases.frame(&camera))?;
        trompe::render::check_radiance(&frame).map_err(MethodError::from)?;
        progress.advance(u64::from(frame.color.height()));
        Ok(MethodFrame {
            frame,
            timings,
            report: format!("on {}: {report}", self.gpu.name()),
            state: Vec::new(),
        })
    }
}

impl GpuPhotographed<'_> {
    /// The frame at time `t` through `camera`, or the scene's camera at `t`: the library's
    /// photographs of the scene (taken, and cut into layers, on the first frame, then kept)
    /// blended on the GPU, over the panorama.
    fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn Progress,
    ) -> Result<MethodFrame, DeviceError> {
        if !t.is_finite() {
            return Err(MethodError::from(trompe::render::RenderError::Time(t)).into());
        }
        let mut timings = Timings::default();
        let (gpu, scene, settings) = (self.gpu, self.scene, &self.settings);
        let uploaded = match self.kept.take() {
            Some(kept) => kept,
            None if self.kind == MethodKind::Layered => {
                let set = trompe::methods::scene_layers(scene, settings, &mut timings)?;
                Photographs::Layers(timings.time("upload layers", || {
                    crate::layers::GpuLayers::new(gpu, &set, &settings.layers)
                })?)
            }
            None => {
                let (views, meshes) =
                    trompe::methods::scene_photographs(scene, settings, &mut timings)?;
                let meshes: Vec<&trompe::geom::Mesh> = meshes.iter().collect();
                Photographs::Whole(timings.time("upload photographs", || {
                    crate::views::GpuViews::photographs(gpu, &meshes, &views, &settings.layers)
                })?)
            }
        };
        let uploaded = self.kept.insert(uploaded);
        let camera = match camera {
            Some(c) => c,
            None => scene.camera.at(t).map_err(MethodError::from)?,
        };
        let blend = timings.time("GPU frame", || match uploaded {
            Photographs::Layers(layers) => layers.render(&camera),
            Photographs::Whole(views) => views.render(&camera),
        })?;
        let frame = trompe::methods::over_environment(scene, &camera, &blend.image)?;
        progress.advance(u64::from(frame.color.height()));
        Ok(MethodFrame {
            frame,
            timings,
            report: format!(
                "on {}: {} holes of {} pixels",
                gpu.name(),
                blend.holes,
                blend.covered
            ),
            state: Vec::new(),
        })
    }
}
