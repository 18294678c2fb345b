//! Paper 3 split as the paper splits it ("Relief texture mapping re-used by 3D image warping"
//! §2, §6; its CPU twin is the library's `trompe::relief`): the software shader's thread and
//! the frame loop's decisions and pre-warps stay on the CPU ([`Pipeline::prepare_draws`]); the
//! GPU draws the objects without relief with its rasterizer (the tracer's raster pass, shaded as
//! the library's `raster_subset` shades them), then texture-maps each pre-warped relief texture
//! onto its base quad with per-pixel depth over them (`shaders/relief.wgsl`), the frame on the
//! device until it is read back. [`ReliefMapper::map`] maps over a frame the caller gives.
//!
//! Uploads are double-buffered: each object has two texture pairs, a new pre-warp is written
//! into the one the last frame did not read and the pair swapped after, so the frame being
//! drawn reads a whole image, the previous one or the new one, never one being written. A
//! pre-warp that stands (Schaufler's test: the same `Arc`) is not uploaded again.
//!
//! Invariants: a frame depends only on the prepared frame and the camera (one invocation a
//! pixel, the impostors mapped in the frame loop's order); the same prepared frame gives the
//! same bits.

use crate::device::{Gpu, GpuError};
use crate::raster::v4;
use crate::trace::{GpuTracer, Recorded};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec4};
use std::collections::HashMap;
use std::sync::Arc;
use trompe::camera::{Pinhole, Projection};
use trompe::frame::Frame;
use trompe::methods::{MethodError, MethodFrame, MethodSettings};
use trompe::relief::{Pipeline, Prewarped, ReliefDraw};
use trompe::render::Primary;
use trompe::scene::Scene;

/// One impostor's dispatch as the shader reads it (`relief.wgsl`'s `Draw`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuDraw {
    eye: [f32; 4],
    ray_a: [f32; 4],
    ray_b: [f32; 4],
    ray_c: [f32; 4],
    origin: [f32; 4],
    axis_a: [f32; 4],
    axis_b: [f32; 4],
    normal: [f32; 4],
    rect: [u32; 4],
    image: [u32; 4],
    frame: [u32; 4],
}

/// An uploaded pre-warp: its colour and its displacement-and-coverage textures, and its size.
struct Uploaded {
    colour: wgpu::Texture,
    depth: wgpu::Texture,
    size: (u32, u32),
}

/// An object's two texture pairs: `front` is the one frames read.
#[derive(Default)]
struct Buffers {
    pairs: [Option<Uploaded>; 2],
    front: usize,
    /// The pre-warp the front pair holds.
    image: Option<Arc<Prewarped>>,
}

/// What the GPU keeps between frames: each relief object's double-buffered textures.
pub struct ReliefMapper<'a> {
    gpu: &'a Gpu,
    buffers: HashMap<u32, Buffers>,
}

/// A frame texture-mapped on the GPU.
pub struct MappedFrame {
    /// The frame: the background with the impostors composited over it.
    pub frame: Frame,
    /// Pre-warps uploaded for it (0 where every one stood).
    pub uploads: usize,
}

impl<'a> ReliefMapper<'a> {
    /// A mapper on `gpu`, holding nothing yet.
    pub fn new(gpu: &'a Gpu) -> ReliefMapper<'a> {
        ReliefMapper {
            gpu,
            buffers: HashMap::new(),
        }
    }

    /// `draws` texture-mapped through `camera` over `background` (its depth tests them), in
    /// order: what the library's `Pipeline::frame` draws on the CPU.
    pub fn map(
        &mut self,
        background: &Frame,
        draws: &[ReliefDraw],
        camera: &Pinhole,
    ) -> Result<MappedFrame, GpuError> {
        let gpu = self.gpu;
        let (w, h) = camera.resolution();
        if background.color.size() != (w, h) {
            return Err(GpuError::Unsupported {
                what: format!(
                    "a {} × {} background under a {w} × {h} camera",
                    background.color.width(),
                    background.color.height()
                ),
            });
        }
        gpu.check_storage("the frame", u64::from(w) * u64::from(h) * 16)?;
        let colour: Vec<Vec4> = background.color.pixels().to_vec();
        let depth_id: Vec<[f32; 4]> = (background.depth.pixels().iter())
            .zip(background.object_id.pixels())
            .map(|(d, id)| [*d, f32::from_bits(*id), 0.0, 0.0])
            .collect();
        let normal: Vec<Vec4> = (background.normal.pixels().iter())
            .map(|n| n.extend(0.0))
            .collect();
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let with = |label: &str, bytes: &[u8]| {
            let b = gpu.buffer(label, bytes.len() as u64, usage);
            gpu.queue.write_buffer(&b, 0, bytes);
            b
        };
        let recorded = Recorded {
            encoder: gpu.device.create_command_encoder(&Default::default()),
            outputs: [
                with("relief frame colour", bytemuck::cast_slice(&colour)),
                with("relief frame depth and id", bytemuck::cast_slice(&depth_id)),
                with("relief frame normal", bytemuck::cast_slice(&normal)),
            ],
            size: (w, h),
        };
        self.map_over(recorded, draws, camera)
    }

    /// `draws` texture-mapped through `camera` over the frame `tracer` draws (its raster pass:
    /// the objects without relief, drawn by the GPU rasterizer and shaded at depth 1), the
    /// frame never leaving the device until it is read back.
    pub(crate) fn map_drawn(
        &mut self,
        tracer: &GpuTracer,
        draws: &[ReliefDraw],
        camera: &Pinhole,
    ) -> Result<MappedFrame, GpuError> {
        let recorded = tracer.record(camera, &[], None)?;
        self.map_over(recorded, draws, camera)
    }

    /// Records `draws`' dispatches after `recorded`'s passes, over its buffers, and reads the
    /// frame back.
    fn map_over(
        &mut self,
        mut recorded: Recorded,
        draws: &[ReliefDraw],
        camera: &Pinhole,
    ) -> Result<MappedFrame, GpuError> {
        let gpu = self.gpu;
        let mut uploads = 0;
        for d in draws {
            uploads += usize::from(self.upload(d)?);
        }
        let pipeline = gpu.compute_pipeline(
            "relief.wgsl",
            include_str!("../shaders/relief.wgsl"),
            "map_relief",
        );
        for d in draws {
            let Some(rect) = covered_rect(d, camera) else {
                continue;
            };
            let Some(uniform) = dispatch(d, camera, rect) else {
                continue;
            };
            let Some(pair) = self
                .buffers
                .get(&d.object)
                .and_then(|b| b.pairs[b.front].as_ref())
            else {
                continue;
            };
            let uniform = gpu.uniform_with("relief draw", bytemuck::bytes_of(&uniform));
            let colour_view = pair.colour.create_view(&Default::default());
            let depth_view = pair.depth.create_view(&Default::default());
            let [colour, depth_id, normal] = &recorded.outputs;
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("relief draw"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    (0, colour.as_entire_binding()),
                    (1, depth_id.as_entire_binding()),
                    (2, normal.as_entire_binding()),
                    (3, wgpu::BindingResource::TextureView(&colour_view)),
                    (4, wgpu::BindingResource::TextureView(&depth_view)),
                    (5, uniform.as_entire_binding()),
                ]
                .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource }),
            });
            let mut pass = recorded.encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(rect[2].div_ceil(8), rect[3].div_ceil(8), 1);
        }
        Ok(MappedFrame {
            frame: recorded.read(gpu)?,
            uploads,
        })
    }

    /// Writes `d`'s pre-warp into its object's back pair and swaps, unless the front pair
    /// already holds it; whether it uploaded.
    fn upload(&mut self, d: &ReliefDraw) -> Result<bool, GpuError> {
        let gpu = self.gpu;
        let buffers = self.buffers.entry(d.object).or_default();
        if buffers
            .image
            .as_ref()
            .is_some_and(|held| Arc::ptr_eq(held, &d.image))
        {
            return Ok(false);
        }
        let image = &d.image;
        let size = (image.width, image.height);
        let texels = image.width as usize * image.height as usize;
        if image.color.len() != texels
            || image.displacement.len() != texels
            || image.flags.len() != texels
        {
            return Err(GpuError::Unsupported {
                what: format!(
                    "a {} × {} pre-warp holding {} colours, {} displacements, {} flags",
                    image.width,
                    image.height,
                    image.color.len(),
                    image.displacement.len(),
                    image.flags.len()
                ),
            });
        }
        gpu.check_texture("a pre-warped relief texture", size.0, size.1)?;
        let back = 1 - buffers.front;
        let fits = buffers.pairs[back].as_ref().is_some_and(|p| p.size == size);
        if !fits {
            let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
            buffers.pairs[back] = Some(Uploaded {
                colour: gpu.texture(
                    "relief colour",
                    size,
                    wgpu::TextureFormat::Rgba8UnormSrgb,
                    usage,
                ),
                depth: gpu.texture(
                    "relief displacement",
                    size,
                    wgpu::TextureFormat::Rg32Float,
                    usage,
                ),
                size,
            });
        }
        let Some(pair) = buffers.pairs[back].as_ref() else {
            return Ok(false);
        };
        let depth: Vec<[f32; 2]> = (image.displacement.iter())
            .zip(&image.flags)
            .map(|(&d, &f)| [d, f32::from(u8::from(f != 0))])
            .collect();
        for (texture, bytes, texel) in [
            (&pair.colour, bytemuck::cast_slice::<_, u8>(&image.color), 4),
            (&pair.depth, bytemuck::cast_slice::<_, u8>(&depth), 8),
        ] {
            gpu.queue.write_texture(
                texture.as_image_copy(),
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size.0 * texel),
                    rows_per_image: Some(size.1),
                },
                crate::device::extent(size),
            );
        }
        buffers.front = back;
        buffers.image = Some(d.image.clone());
        Ok(true)
    }
}

/// The pixels `d`'s enlarged quad can cover through `camera`, as `[x, y, columns, rows]`:
/// its corners' projections' box, or the whole frame when a corner is behind the camera (as
/// the library's `relief::texture::draw` bounds it); `None` when it covers none.
fn covered_rect(d: &ReliefDraw, camera: &Pinhole) -> Option<[u32; 4]> {
    let (width, height) = camera.resolution();
    let (mx, my) = (f64::from(d.image.margin.0), f64::from(d.image.margin.1));
    let (fw, fh) = (f64::from(d.frame.width), f64::from(d.frame.height));
    let corners: Option<Vec<_>> = [
        (-mx, -my),
        (fw + mx, -my),
        (-mx, fh + my),
        (fw + mx, fh + my),
    ]
    .into_iter()
    .map(|(u, v)| camera.project(d.frame.point(u, v, 0.0)))
    .collect();
    let (mut cols, mut rows) = ((0.0, f64::from(width)), (0.0, f64::from(height)));
    if let Some(corners) = corners {
        let (lo, hi) = corners.iter().fold(
            (glam::DVec2::INFINITY, glam::DVec2::NEG_INFINITY),
            |(lo, hi), q| (lo.min(q.uv), hi.max(q.uv)),
        );
        cols = (
            lo.x.floor().clamp(0.0, f64::from(width)),
            (hi.x.ceil() + 1.0).clamp(0.0, f64::from(width)),
        );
        rows = (
            lo.y.floor().clamp(0.0, f64::from(height)),
            (hi.y.ceil() + 1.0).clamp(0.0, f64::from(height)),
        );
    }
    let rect = [
        cols.0 as u32,
        rows.0 as u32,
        (cols.1 - cols.0) as u32,
        (rows.1 - rows.0) as u32,
    ];
    (rect[2] > 0 && rect[3] > 0).then_some(rect)
}

/// `d`'s uniform through `camera` over `rect`; `None` where the eye is behind its base plane
/// (nothing to draw, as on the CPU).
fn dispatch(d: &ReliefDraw, camera: &Pinhole, rect: [u32; 4]) -> Option<GpuDraw> {
    let eye = camera.position();
    let f = d.frame.f;
    let height = (eye - d.frame.origin).dot(f);
    if height <= 0.0 {
        return None;
    }
    let (a, b, c) = camera.mcmillan();
    let lane = |v: DVec3, w: f64| v4(v.as_vec3(), w as f32);
    let (width, _) = camera.resolution();
    Some(GpuDraw {
        eye: lane(eye, height),
        ray_a: lane(a, 0.0),
        ray_b: lane(b, 0.0),
        ray_c: lane(c, 0.0),
        origin: lane(d.frame.origin, 0.0),
        axis_a: lane(d.frame.a, 1.0 / d.frame.a.length_squared()),
        axis_b: lane(d.frame.b, 1.0 / d.frame.b.length_squared()),
        normal: lane(f, 0.0),
        rect,
        image: [
            d.image.width,
            d.image.height,
            d.image.margin.0,
            d.image.margin.1,
        ],
        frame: [width, d.object, 0, 0],
    })
}

/// The objects `objects` of `view` on the device, drawn by the GPU rasterizer and shaded as the
/// library's `relief::raster::raster_subset` shades them; the other objects' meshes left
/// empty, so the ids stay the scene's.
fn directly_drawn<'a>(
    gpu: &'a Gpu,
    view: &trompe::scene::View,
    lighting: &trompe::scene::Lighting,
    objects: &[usize],
) -> Result<GpuTracer<'a>, GpuError> {
    let meshes: Vec<Arc<trompe::geom::Mesh>> = (view.meshes.iter().enumerate())
        .map(|(o, m)| match objects.contains(&o) {
            true => m.clone(),
            false => Arc::new(trompe::geom::Mesh {
                materials: m.materials.clone(),
                ..trompe::geom::Mesh::default()
            }),
        })
        .collect();
    let drawn: Vec<Arc<trompe::geom::Mesh>> = objects
        .iter()
        .filter_map(|&o| view.meshes.get(o).cloned())
        .collect();
    let settings = trompe::relief::raster::raster_settings(&drawn);
    let subset = trompe::scene::View {
        lens: None,
        camera: view.camera.clone(),
        meshes,
        surfaces: view.surfaces.clone(),
    };
    GpuTracer::new(gpu, &subset, lighting, &settings, Primary::Rasterized)
}

/// The `relief` method on the GPU, over one scene: the library's pipeline (the software
/// shader's thread, the frame loop's decisions and pre-warps) started on the first frame and
/// kept; each frame, the objects drawn directly are drawn by the GPU rasterizer (the `raster`
/// method's pass, as the library's `raster_subset` draws them) and the impostors texture-mapped
/// over them, on the device.
pub struct GpuReliefMethod<'a> {
    scene: &'a Scene,
    settings: MethodSettings,
    /// The pipeline and the time its still scene stands at.
    kept: Option<(Pipeline, f32)>,
    mapper: ReliefMapper<'a>,
    /// The objects drawn directly, uploaded: kept while the same objects are.
    drawn: Option<(Vec<usize>, GpuTracer<'a>)>,
}

impl<'a> GpuReliefMethod<'a> {
    /// The method over `scene` on `gpu`.
    pub fn new(gpu: &'a Gpu, scene: &'a Scene, settings: MethodSettings) -> GpuReliefMethod<'a> {
        GpuReliefMethod {
            scene,
            settings,
            kept: None,
            mapper: ReliefMapper::new(gpu),
            drawn: None,
        }
    }

    /// The adapter's name.
    pub fn device_name(&self) -> &str {
        self.mapper.gpu.name()
    }

    /// The frame at time `t` through `camera`, or the scene's camera at `t`.
    pub fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn trompe::progress::Progress,
    ) -> Result<MethodFrame, crate::methods::DeviceError> {
        if !t.is_finite() {
            return Err(MethodError::from(trompe::render::RenderError::Time(t)).into());
        }
        let scene = self.scene;
        let mut timings = trompe::progress::Timings::default();
        let (mut pipeline, time) = match self.kept.take() {
            Some(kept) => kept,
            None => (
                trompe::methods::start_relief(scene, t, &self.settings, &mut timings)?,
                t,
            ),
        };
        // Relief impostors are of a still scene: the scene as it stood when the pipeline
        // started, seen through the camera of now.
        let camera = match camera {
            Some(c) => c,
            None => scene.camera.at(t).map_err(MethodError::from)?,
        };
        let prepared = pipeline.prepare_draws(&camera).map_err(MethodError::from);
        let (report, state) = match &prepared {
            Ok(p) => trompe::methods::relief_report(scene, &pipeline, time, &p.objects),
            Err(_) => Default::default(),
        };
        let mut prepared = match prepared {
            Ok(p) => p,
            Err(e) => {
                self.kept = Some((pipeline, time));
                return Err(e.into());
            }
        };
        timings.0.append(&mut prepared.timings.0);
        let gpu = self.mapper.gpu;
        let tracer = match &mut self.drawn {
            Some((objects, tracer)) if *objects == prepared.rasterized => tracer,
            slot => {
                let view = pipeline.view();
                let tracer = timings.time("upload the objects drawn directly", || {
                    directly_drawn(gpu, view, pipeline.lighting(), &prepared.rasterized)
                })?;
                &slot.insert((prepared.rasterized.clone(), tracer)).1
            }
        };
        self.kept = Some((pipeline, time));
        let mapped = timings.time("GPU frame", || {
            self.mapper.map_drawn(tracer, &prepared.draws, &camera)
        })?;
        trompe::render::check_radiance(&mapped.frame).map_err(MethodError::from)?;
        progress.advance(u64::from(mapped.frame.color.height()));
        Ok(MethodFrame {
            frame: mapped.frame,
            timings,
            report: format!(
                "on {}: {report}; {} pre-warps uploaded",
                self.mapper.gpu.name(),
                mapped.uploads
            ),
            state,
        })
    }
}
