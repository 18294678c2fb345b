//! Paper 2's hybrid reflections on the GPU ("Hybrid backward-forward reflection rendering with
//! continuous 3-ray cameras" §3–6; its CPU twin is the library's `trompe::hybrid`), split as the
//! paper splits it: the G-buffer on the GPU (`shaders/splat.wgsl`), the reflector triangles it
//! sees read back; the cameras and the kd-tree culling on the CPU, by the library's own
//! [`SplatPlan`] (a few thousand box tests a frame, where the CPU's branchy tree walk is at
//! home); then on the GPU every planned point projected through its camera's cubic
//! ([`crate::c3rc`], every root), splatted, each pixel resolved to the point nearest the
//! mirror (two 32-bit atomic minimum passes, the CPU's 64-bit key), lit, and the tracer
//! shading the G-buffer with the splats answering the eye's first reflections.
//!
//! Invariants: the points are uploaded once per scene, in object space, and placed each frame
//! by their clouds' rows; a frame's pixels depend only on the scene, the time and the camera
//! (the splat keys' minima do not depend on the order of invocations).

use crate::c3rc::GpuC3rc;
use crate::device::{Gpu, GpuError};
use crate::raster::v4;
use crate::trace::{GpuTracer, SPLAT_MODULE, Secondary, splat_shader_source};
use bytemuck::{Pod, Zeroable};
use glam::{DMat4, Mat3};
use std::time::Instant;
use trompe::camera::Pinhole;
use trompe::frame::{Frame, NO_OBJECT};
use trompe::hybrid::plan::seen_reflectors;
use trompe::hybrid::{FrameStats, HybridReflections, SplatPlan};
use trompe::render::{Primary, Refraction};
use trompe::scene::{Lighting, RenderSettings, Scene, View};
use trompe::trace::Bvh;

/// A planned camera's node as the shader reads it (`splat.wgsl`'s `Item`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuItem {
    camera: u32,
    world: u32,
    cloud: u32,
    first: u32,
    count: u32,
    stride: u32,
    pad: [u32; 2],
}

/// A cloud's placement as the shader reads it (`splat.wgsl`'s `Cloud`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuCloud {
    world: [[f32; 4]; 3],
    normal: [[f32; 4]; 3],
}

/// The splat passes' settings (`splat.wgsl`'s `Splats`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuSplats {
    settings: [u32; 4],
    row: [u32; 4],
}

/// The counters' slots (`splat.wgsl`'s), then one bit a point.
const COUNTERS: usize = 8;
const REFLECTOR_PIXELS: usize = 0;
const PROJECTIONS: usize = 1;
const SPLATS: usize = 2;
const POINTS_SEEN: usize = 3;
const PIXELS_SPLATTED: usize = 4;
const PIXELS_TRACED: usize = 5;

/// The hybrid method's scene on the device: the tracer's upload, the points, the pipelines.
pub struct GpuHybrid<'a> {
    gpu: &'a Gpu,
    tracer: GpuTracer<'a>,
    /// Leaf-ordered triangle → (object, triangle).
    leaves: Vec<(u32, u32)>,
    /// Three texels a point (position, normal, albedo), in object space, in the frame's
    /// numbering; and how many points.
    points: (wgpu::Buffer, u32),
    /// How wide splats are, and whether mirrors hide points.
    splat: u32,
    mirrors_occlude: bool,
}

/// One GPU frame of the hybrid method and what it did.
pub struct GpuHybridFrame {
    /// The frame.
    pub frame: Frame,
    /// The library's statistics, counted on the GPU where the GPU does the work.
    pub stats: FrameStats,
    /// Per pixel, the point whose splat won it, numbered as the library's
    /// [`trompe::hybrid::HybridFrame::winners`] (`NO_OBJECT` where none did).
    pub winners: trompe::frame::Image<u32>,
}

impl<'a> GpuHybrid<'a> {
    /// Uploads `view`'s scene (its BVH built here) and the points of `clouds` (which the
    /// library prepared over the same scene).
    pub fn new(
        gpu: &'a Gpu,
        view: &View,
        lighting: &Lighting,
        settings: &RenderSettings,
        clouds: &HybridReflections,
    ) -> Result<GpuHybrid<'a>, GpuError> {
        let bvh = Bvh::build(view.meshes.clone())?;
        let tracer = GpuTracer::with_secondary(
            gpu,
            view,
            lighting,
            settings,
            (Primary::Rasterized, Refraction::Exact),
            Secondary::Splats { bvh: &bvh },
        )?;
        let mut texels: Vec<[f32; 4]> = Vec::with_capacity(3 * clouds.point_count());
        for cloud in &clouds.clouds {
            let p = &cloud.points;
            for ((x, n), a) in p.positions.iter().zip(&p.normals).zip(&p.albedo) {
                texels.extend([v4(*x, 0.0), v4(*n, 0.0), v4(*a, 0.0)]);
            }
        }
        let bytes: &[u8] = bytemuck::cast_slice(&texels);
        gpu.check_storage("the points", bytes.len() as u64)?;
        let count = u32::try_from(clouds.point_count()).map_err(|_| GpuError::Unsupported {
            what: format!("{} points (at most 2³² − 1)", clouds.point_count()),
        })?;
        Ok(GpuHybrid {
            gpu,
            tracer,
            leaves: bvh.leaf_sources().to_vec(),
            points: (gpu.storage_with("points", bytes), count),
            splat: clouds.settings.splat.clamp(1, 2),
            mirrors_occlude: clouds.settings.mirrors_occlude,
        })
    }

    /// The frame of `view` (the scene at time `t`, through its camera), its points those of
    /// `clouds` (the ones uploaded).
    pub fn frame(
        &self,
        clouds: &HybridReflections,
        scene: &Scene,
        view: &View,
        t: f32,
    ) -> Result<GpuHybridFrame, GpuError> {
        let gpu = self.gpu;
        let camera: &Pinhole = &view.camera;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let pixels = u64::from(w) * u64::from(h);
        let mut stats = FrameStats::default();
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        for (what, bytes) in [("the G-buffer", pixels * 32), ("the splats", pixels * 16)] {
            gpu.check_storage(what, bytes)?;
        }
        let gbuffer = gpu.buffer("g-buffer", pixels * 32, storage);
        let splatted = gpu.buffer("splats", pixels * 16, storage);
        let keys = gpu.buffer("splat keys", pixels * 8, storage);
        let words = COUNTERS as u64 + u64::from(self.points.1.div_ceil(32));
        let counters = gpu.buffer("counters", words * 4, storage);
        let seen = gpu.buffer("seen leaves", self.leaves.len() as u64 * 4, storage);
        let uniform = gpu.uniform_with(
            "view",
            bytemuck::bytes_of(&self.tracer.view_through(camera)),
        );

        // The G-buffer, and the reflector triangles it sees, read back.
        let start = Instant::now();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let scene_entries = self.tracer.scene_entries();
        gpu.check_texture("the visibility buffer", w, h)?;
        let visibility = self
            .tracer
            .visibility(&mut encoder, camera)
            .ok_or_else(|| GpuError::Unsupported {
                what: "a hybrid frame without a visibility pass".into(),
            })?;
        let visibility_view = visibility.create_view(&Default::default());
        self.pass(
            &mut encoder,
            "splat_gbuffer",
            &[
                scene_entries[1],
                scene_entries[2],
                scene_entries[3],
                (8, &uniform),
                (13, &gbuffer),
                (14, &splatted),
                (15, &counters),
                (21, &keys),
                (22, &seen),
            ],
            Some(&visibility_view),
            (w.div_ceil(8), h.div_ceil(8)),
        );
        let read = gpu.read_back(encoder, std::slice::from_ref(&seen), "the reflectors seen")?;
        let flags: Vec<u32> = bytemuck::pod_collect_to_vec(&read[0]);
        stats.gbuffer = start.elapsed();

        // The plan, on the CPU.
        let start = Instant::now();
        let hits = flags
            .iter()
            .zip(&self.leaves)
            .filter(|(f, _)| **f != 0)
            .map(|(_, source)| *source);
        let seen = seen_reflectors(view, hits);
        let plan = SplatPlan::new(clouds, scene, view, t, &seen, self.splat);
        stats.c3rcs = plan.cameras.len() as u64;
        stats.leaves_kept = plan.nodes_kept();
        stats.nodes_tested = plan.nodes_tested;
        let n = plan.cameras.len();
        let clouds_n = clouds.clouds.len();
        let mut cameras: Vec<GpuC3rc> = plan
            .cameras
            .iter()
            .map(|c| GpuC3rc::new(&c.world, c.lambda_max, c.object))
            .collect();
        for c in &plan.cameras {
            for inverse in &plan.placement.inverse {
                cameras.push(GpuC3rc::new(&c.local(inverse), c.lambda_max, c.object));
            }
        }
        let mut items = Vec::new();
        for (i, c) in plan.cameras.iter().enumerate() {
            for kept in &c.nodes {
                let cloud = &clouds.clouds[kept.cloud as usize];
                let (first, count) = cloud.tree.nodes[kept.node as usize].points;
                let stride = kept.stride.max(1);
                stats.points_projected += u64::from(count.div_ceil(stride));
                items.push(GpuItem {
                    camera: (n + i * clouds_n + kept.cloud as usize) as u32,
                    world: i as u32,
                    cloud: kept.cloud,
                    first: plan.placement.offsets[kept.cloud as usize] + first,
                    count,
                    stride,
                    pad: [0; 2],
                });
            }
        }
        let placed: Vec<GpuCloud> = plan
            .placement
            .world
            .iter()
            .zip(&plan.placement.offsets)
            .zip(&clouds.clouds)
            .map(|((m, offset), cloud)| cloud_rows(m, *offset, cloud.object))
            .collect();
        stats.cull = start.elapsed();

        // Projection, splatting, resolution, then the tracer.
        let start = Instant::now();
        let row = gpu.max_groups().min(65535);
        let item_count = items.len() as u32;
        let splats = GpuSplats {
            settings: [
                self.splat,
                item_count,
                clouds_n as u32,
                u32::from(self.mirrors_occlude),
            ],
            row: [row, 0, 0, 0],
        };
        let splats = gpu.uniform_with("splat settings", bytemuck::bytes_of(&splats));
        for (what, bytes) in [
            ("the cameras", std::mem::size_of_val(cameras.as_slice())),
            ("the planned nodes", std::mem::size_of_val(items.as_slice())),
        ] {
            gpu.check_storage(what, bytes as u64)?;
        }
        // A binding holds at least one element, read by no one where there are none.
        let at_least_one = |bytes: &[u8], element: usize| {
            let mut padded = bytes.to_vec();
            padded.resize(bytes.len().max(element), 0);
            padded
        };
        let cameras = gpu.storage_with(
            "cameras",
            &at_least_one(bytemuck::cast_slice(&cameras), size_of::<GpuC3rc>()),
        );
        let items = gpu.storage_with(
            "planned nodes",
            &at_least_one(bytemuck::cast_slice(&items), size_of::<GpuItem>()),
        );
        let placed = gpu.storage_with(
            "clouds",
            &at_least_one(bytemuck::cast_slice(&placed), size_of::<GpuCloud>()),
        );
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let splat_entries = [
            (8, &uniform),
            (13, &gbuffer),
            (15, &counters),
            (16, &cameras),
            (17, &items),
            (18, &self.points.0),
            (19, &placed),
            (21, &keys),
            (23, &splats),
        ];
        if item_count > 0 {
            let groups = (item_count.min(row), item_count.div_ceil(row));
            self.pass(&mut encoder, "splat_lengths", &splat_entries, None, groups);
            self.pass(&mut encoder, "splat_indices", &splat_entries, None, groups);
        }
        self.pass(
            &mut encoder,
            "splat_resolve",
            &[
                scene_entries[0],
                scene_entries[1],
                scene_entries[4],
                (8, &uniform),
                (13, &gbuffer),
                (14, &splatted),
                (15, &counters),
                (18, &self.points.0),
                (19, &placed),
                (21, &keys),
                (23, &splats),
            ],
            None,
            (w.div_ceil(8), h.div_ceil(8)),
        );
        gpu.queue.submit([encoder.finish()]);
        stats.project = start.elapsed();
        let start = Instant::now();
        let frame = self.tracer.frame_with(
            camera,
            &[
                (13, &gbuffer),
                (14, &splatted),
                (15, &counters),
                (23, &splats),
            ],
            Some(&visibility),
        )?;
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let read = gpu.read_back(encoder, &[counters, keys], "the counters")?;
        stats.shade = start.elapsed();
        let counted: Vec<u32> = bytemuck::pod_collect_to_vec(&read[0]);
        let keys: Vec<u32> = bytemuck::pod_collect_to_vec(&read[1]);
        let winners = keys
            .chunks_exact(2)
            .take(pixels as usize)
            .map(|k| if k[0] == u32::MAX { NO_OBJECT } else { k[1] })
            .collect();
        let count = |slot: usize| u64::from(counted.get(slot).copied().unwrap_or(0));
        stats.reflector_pixels = count(REFLECTOR_PIXELS);
        stats.projections = count(PROJECTIONS);
        stats.splats = count(SPLATS);
        stats.points_seen = count(POINTS_SEEN);
        stats.pixels_splatted = count(PIXELS_SPLATTED);
        stats.pixels_traced = count(PIXELS_TRACED);
        Ok(GpuHybridFrame {
            frame,
            stats,
            winners: trompe::frame::Image::from_vec(w, h, winners)?,
        })
    }

    /// Records a dispatch of `entry` of the splat module over `groups`, bound to `entries` and
    /// to `visibility` (binding 12) where given.
    fn pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: &'static str,
        entries: &[(u32, &wgpu::Buffer)],
        visibility: Option<&wgpu::TextureView>,
        groups: (u32, u32),
    ) {
        let gpu = self.gpu;
        let source = splat_shader_source(gpu.has_f64());
        let pipeline = gpu.compute_pipeline(SPLAT_MODULE, &source, entry);
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(entry),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries
                .iter()
                .map(|(binding, b)| wgpu::BindGroupEntry {
                    binding: *binding,
                    resource: b.as_entire_binding(),
                })
                .chain(visibility.map(|v| wgpu::BindGroupEntry {
                    binding: 12,
                    resource: wgpu::BindingResource::TextureView(v),
                }))
                .collect::<Vec<_>>(),
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(entry),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }
}

/// A cloud's rows object → world and its normals' rows (the inverse transpose), its first
/// point and object in the spare lanes.
fn cloud_rows(m: &DMat4, first: u32, object: u32) -> GpuCloud {
    let m = m.as_mat4();
    let normal = Mat3::from_mat4(m).inverse().transpose();
    let row = |k: usize| m.row(k).to_array();
    let nrow = |k: usize, w: f32| v4(normal.row(k), w);
    GpuCloud {
        world: [row(0), row(1), row(2)],
        normal: [
            nrow(0, f32::from_bits(first)),
            nrow(1, f32::from_bits(object)),
            nrow(2, 0.0),
        ],
    }
}

/// The `c3rc` method on the GPU, over one scene: the library's points and trees, prepared on
/// the first frame and kept (a deforming object's carried each frame, as on the CPU), and the
/// scene on the device, kept while nothing moves.
pub struct GpuHybridMethod<'a> {
    gpu: &'a Gpu,
    scene: &'a Scene,
    settings: trompe::hybrid::HybridSettings,
    /// The points and trees, once prepared.
    clouds: Option<HybridReflections>,
    /// The upload and the objects' poses it was made at.
    kept: Option<(Vec<glam::Mat4>, GpuHybrid<'a>)>,
}

impl<'a> GpuHybridMethod<'a> {
    /// The method over `scene` on `gpu`, sampled and splatted as `settings` say.
    pub fn new(
        gpu: &'a Gpu,
        scene: &'a Scene,
        settings: trompe::hybrid::HybridSettings,
    ) -> GpuHybridMethod<'a> {
        GpuHybridMethod {
            gpu,
            scene,
            settings,
            clouds: None,
            kept: None,
        }
    }

    /// The adapter's name.
    pub fn device_name(&self) -> &str {
        self.gpu.name()
    }

    /// The frame at time `t` through `camera` (a pinhole), or the scene's camera at `t`.
    pub fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn trompe::progress::Progress,
    ) -> Result<trompe::methods::MethodFrame, crate::methods::DeviceError> {
        use trompe::methods::MethodError;
        if !t.is_finite() {
            return Err(MethodError::from(trompe::render::RenderError::Time(t)).into());
        }
        let scene = self.scene;
        let mut timings = trompe::progress::Timings::default();
        let clouds = match self.clouds.take() {
            Some(clouds) => clouds,
            None => timings
                .time("sample points, build trees", || {
                    HybridReflections::prepare(scene, self.settings)
                })
                .map_err(MethodError::from)?,
        };
        let clouds = &*self.clouds.insert(clouds);
        let mut view = scene.view(t)?;
        if let Some(camera) = camera {
            view.camera = camera;
            view.lens = None;
        }
        let deformed = clouds.deformed_at(scene, t);
        let points = deformed.as_ref().unwrap_or(clouds);
        let poses = scene.poses_at(t);
        let reused = deformed.is_none() && matches!(&self.kept, Some((at, _)) if *at == poses);
        let uploaded = match &mut self.kept {
            Some((_, uploaded)) if reused => uploaded,
            slot => {
                let uploaded = timings.time("build BVH, upload the scene and points", || {
                    GpuHybrid::new(self.gpu, &view, &scene.lighting, &scene.render, points)
                })?;
                &slot.insert((poses, uploaded)).1
            }
        };
        let done = timings.time("GPU frame", || uploaded.frame(points, scene, &view, t))?;
        trompe::render::check_radiance(&done.frame).map_err(MethodError::from)?;
        progress.advance(u64::from(done.frame.color.height()));
        let state = if reused { "kept" } else { "uploaded" };
        Ok(trompe::methods::MethodFrame {
            frame: done.frame,
            timings,
            report: format!(
                "on {}: scene {state}; {}",
                self.gpu.name(),
                clouds.report(scene, done.stats)
            ),
            state: Vec::new(),
        })
    }
}
