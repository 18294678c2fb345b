//! The `trace` method on the GPU: Whitted ray tracing through the exact BVH, one compute
//! invocation a pixel (`shaders/trace.wgsl`, compiled after `shaders/bvh.wgsl`), shaded as the
//! library's `render::shading` shades — the GPU's ground truth, and its CPU twin is
//! `trompe render --method trace`.
//!
//! What the shader reads is resolved here, once a scene: each leaf-ordered triangle's normals,
//! texture coordinates, object and material; one material a (object, mesh material) pair, the
//! scene's surface overriding the mesh file's; every texture and the panorama's two images in
//! one texel buffer. Invariant: a frame depends only on the view, the lighting and the settings
//! (one invocation a pixel, no atomics), so the same inputs give the same pixels on one device.

use crate::device::{Gpu, GpuError};
use crate::raster::{
    GpuRasterCamera, corner_buffer, draw_into_visibility, draw_ranges_into_visibility,
    raster_pipeline, v4, visibility_pipeline, visibility_texture,
};
use crate::walk::{UploadedWalks, WalkSet};
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::frame::{Frame, Image, NO_OBJECT, Rgba};
use trompe::render::{Primary, ReflectorImpostors, Refraction};
use trompe::scene::{Lighting, RenderSettings, Surface, View};
use trompe::trace::Bvh;

/// The tracer's source: the BVH walk, then the tracer, its open rays answered exactly.
pub fn shader_source() -> String {
    [
        crate::bvh::SHADER,
        include_str!("../shaders/trace.wgsl"),
        include_str!("../shaders/exact_secondary.wgsl"),
    ]
    .join("\n")
}

/// The impostor methods' source: the tracer with its open rays answered by impostors.
pub fn impostor_shader_source() -> String {
    [
        crate::walk::shader_source(),
        include_str!("../shaders/trace.wgsl").into(),
        include_str!("../shaders/impostor_secondary.wgsl").into(),
    ]
    .join("\n")
}

/// The hybrid method's source: the tracer with the first reflections off mirrors and glass
/// answered by the points splatted through continuous 3-ray cameras (`crate::hybrid`), and the
/// passes that splat them.
pub fn splat_shader_source(f64: bool) -> String {
    [
        crate::bvh::SHADER,
        include_str!("../shaders/trace.wgsl"),
        &crate::c3rc::c3rc_source(f64),
        include_str!("../shaders/splat.wgsl"),
    ]
    .join("\n")
}

/// The class of the triangles of mirror and glass objects (`shaders/impostor_secondary.wgsl`'s
/// `SPECULAR`).
const SPECULAR: u32 = 2;
/// The class of the triangles of glass objects (its `GLASS_CLASS`).
const GLASS_CLASS: u32 = 4;
/// In an object's row of the table of what it sees: it sees every mirror and glass object
/// exactly (the shader's `SEES_EXACTLY`), or itself and the glass (`SEES_GLASS_AND_ITSELF`).
const SEES_EXACTLY: u32 = 1 << 31;
const SEES_GLASS_AND_ITSELF: u32 = 1 << 30;

/// The hybrid method's module's label (its pipelines are cached by it).
pub(crate) const SPLAT_MODULE: &str = "trace.wgsl with splats";

/// Storage buffers the impostor methods' shader reads and writes.
const IMPOSTOR_STORAGE_BUFFERS: u32 = 15;

/// Pending rays a pixel may hold (the shader's `PENDING`): a depth-first walk of mirrors and
/// glass holds at most one more than the recursion limit.
pub const MAX_DEPTH: u32 = 23;

/// The shader's material kinds.
pub(crate) const DIFFUSE: u32 = 0;
pub(crate) const MIRROR: u32 = 1;
pub(crate) const GLASS: u32 = 2;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuTriangle {
    n0: [f32; 4],
    n1: [f32; 4],
    n2: [f32; 4],
    ng: [f32; 4],
    uv01: [f32; 4],
    uv2: [f32; 4],
}

/// A material as the shader reads it (`trace.wgsl`'s `Material`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuMaterial {
    pub(crate) color: [f32; 4],
    pub(crate) ior: [f32; 4],
    pub(crate) texture: [u32; 4],
}

impl GpuMaterial {
    /// A mirror's or glass's (what `surface` is; a diffuse surface's colour comes from
    /// elsewhere: white, untextured).
    pub(crate) fn specular(surface: &Surface) -> Self {
        let (color, ior) = match surface {
            Surface::Mirror { tint } => (v4(*tint, f32::from_bits(MIRROR)), 1.0),
            Surface::Glass { ior, tint } => (v4(*tint, f32::from_bits(GLASS)), *ior),
            Surface::Diffuse(_) => (v4(Vec3::ONE, f32::from_bits(DIFFUSE)), 1.0),
        };
        GpuMaterial {
            color,
            ior: [ior, 0.0, 0.0, 0.0],
            texture: [0; 4],
        }
    }
}

/// The view uniform (`trace.wgsl`'s `View`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuView {
    eye: [f32; 4],
    a: [f32; 4],
    b: [f32; 4],
    c: [f32; 4],
    size: [u32; 4],
    sun_dir: [f32; 4],
    sun: [f32; 4],
    radiance: [u32; 4],
    irradiance: [u32; 4],
    mode: [u32; 4],
    rows: [[f32; 4]; 3],
}

impl GpuView {
    /// The uniform of `lighting` and `settings` (the panorama's two images placed in
    /// `texels`), `mode` as the shader reads it; the camera's fields are
    /// [`GpuView::through`]'s.
    pub(crate) fn lit(
        lighting: &Lighting,
        settings: &RenderSettings,
        mode: [u32; 4],
        texels: &mut Texels,
    ) -> Self {
        let environment = &lighting.environment;
        let radiance = texels.colour(environment.image());
        let irradiance = texels.colour(environment.irradiance_image());
        let sun = lighting.light.as_ref();
        GpuView {
            eye: [0.0, 0.0, 0.0, settings.ray_epsilon],
            a: [0.0; 4],
            b: [0.0; 4],
            c: [0.0; 4],
            size: [0, 0, settings.max_depth, u32::from(sun.is_some())],
            sun_dir: v4(sun.map_or(Vec3::Y, |s| s.direction), environment.rotation()),
            sun: v4(
                sun.map_or(Vec3::ZERO, |s| s.irradiance),
                environment.intensity(),
            ),
            radiance,
            irradiance,
            mode,
            rows: [[0.0; 4]; 3],
        }
    }

    /// This uniform through `camera`: its eye, pixel steps, rows and size.
    pub(crate) fn through(mut self, camera: &Pinhole) -> Self {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let (a, b, c) = camera.mcmillan();
        self.eye = v4(camera.position().as_vec3(), self.eye[3]);
        self.a = v4(a.as_vec3(), 0.0);
        self.b = v4(b.as_vec3(), 0.0);
        self.c = v4(c.as_vec3(), 0.0);
        self.rows = GpuRasterCamera::pinhole(camera).rows();
        self.size[0] = w;
        self.size[1] = h;
        self
    }
}

/// Every image the shader reads, one after another, as `(first texel, width, height)`.
#[derive(Default)]
pub(crate) struct Texels {
    data: Vec<[f32; 4]>,
    placed: HashMap<*const Image<Rgba>, [u32; 4]>,
}

impl Texels {
    /// The texels, as the storage buffer holds them.
    pub(crate) fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.data)
    }

    fn push(&mut self, width: u32, height: u32, texels: impl Iterator<Item = Vec4>) -> [u32; 4] {
        let first = self.data.len() as u32;
        self.data.extend(texels.map(|t| t.to_array()));
        [first, width, height, 1]
    }

    fn colour(&mut self, image: &Image<Vec3>) -> [u32; 4] {
        let (w, h) = image.size();
        self.push(w, h, image.pixels().iter().map(|c| c.extend(1.0)))
    }

    fn texture(&mut self, texture: &Arc<Image<Rgba>>) -> [u32; 4] {
        if let Some(placed) = self.placed.get(&Arc::as_ptr(texture)) {
            return *placed;
        }
        let (w, h) = texture.size();
        let placed = self.push(w, h, texture.pixels().iter().copied());
        self.placed.insert(Arc::as_ptr(texture), placed);
        placed
    }
}

/// The `trace` method's frame of `view`, rendered on `gpu`: colour, depth, shading normal and
/// object id, as the CPU tracer fills them.
pub fn render(
    gpu: &Gpu,
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
) -> Result<Frame, GpuError> {
    GpuTracer::new(gpu, view, lighting, settings, Primary::Traced)?.frame(&view.camera)
}

/// A triangle of a glass object, for Wyman's first pass: its leaf, corners and face normal.
struct GlassFace {
    leaf: u32,
    corners: [Vec3; 3],
    normal: Vec3,
}

/// A scene on the device, ready to trace through any camera: its BVH, its triangles' shading
/// data, materials, textures and panorama uploaded once.
pub struct GpuTracer<'a> {
    gpu: &'a Gpu,
    pipeline: wgpu::ComputePipeline,
    /// Nodes, corners, triangles, materials, texels (bindings 0, 1, 5, 6, 7).
    scene: [wgpu::Buffer; 5],
    /// Everything of the view's uniform but the camera's fields.
    uniform: GpuView,
    /// With rasterized primaries: the draw's pipeline and its vertices (the leaf-ordered
    /// triangles' corners, each with its corner number and triangle).
    raster: Option<(wgpu::RenderPipeline, wgpu::Buffer, u32)>,
    /// Under an impostor method: the impostors and each object's list of those it sees
    /// (binding 18).
    impostors: Option<(UploadedWalks, wgpu::Buffer)>,
    /// Under Wyman's refraction: the glass objects' triangles, whose back faces each frame
    /// draws through the eye (binding 20).
    glass: Option<Vec<GlassFace>>,
}

/// What answers the rays mirrors and glass send out into the open.
#[derive(Clone, Copy)]
pub enum Secondary<'s> {
    /// The exact BVH (the `trace` method).
    Exact,
    /// The impostors the library built, placed and lit for this frame, and the mirror and glass
    /// objects seen exactly (paper 1 §6: the `impostor` and `pinhole-impostor` methods); with
    /// the BVH of the view the library built beside them, uploaded rather than built again.
    Impostors {
        /// The answers to the rays mirrors and glass send out.
        answers: &'s ReflectorImpostors,
        /// The view's BVH.
        bvh: &'s Bvh,
    },
    /// The points splatted through continuous 3-ray cameras where the ray is the eye's first
    /// reflection, the exact BVH otherwise (paper 2: the `c3rc` method, [`crate::hybrid`]);
    /// with the view's BVH.
    Splats {
        /// The view's BVH.
        bvh: &'s Bvh,
    },
}

impl<'a> GpuTracer<'a> {
    /// Builds the BVH of `view`'s meshes and uploads the scene (`view`'s camera is not used);
    /// `primary` says whether the eye's hits are traced or rasterized (the raster method, with
    /// `settings.max_depth` 1).
    pub fn new(
        gpu: &'a Gpu,
        view: &View,
        lighting: &Lighting,
        settings: &RenderSettings,
        primary: Primary,
    ) -> Result<GpuTracer<'a>, GpuError> {
        Self::with_secondary(
            gpu,
            view,
            lighting,
            settings,
            (primary, Refraction::Exact),
            Secondary::Exact,
        )
    }

    /// [`GpuTracer::new`], the eye's refractions into glass found as `refraction` says (exactly,
    /// or by Wyman's image-space approximation as `trompe::render::wyman` finds them), and the
    /// rays mirrors and glass send out into the open answered as `secondary` says.
    pub fn with_secondary(
        gpu: &'a Gpu,
        view: &View,
        lighting: &Lighting,
        settings: &RenderSettings,
        (primary, refraction): (Primary, Refraction),
        secondary: Secondary<'_>,
    ) -> Result<GpuTracer<'a>, GpuError> {
        if settings.max_depth > MAX_DEPTH {
            return Err(GpuError::Unsupported {
                what: format!(
                    "a recursion limit of {} (the GPU tracer follows at most {MAX_DEPTH})",
                    settings.max_depth
                ),
            });
        }
        // Materials: one a (object, mesh material), the scene's surface deciding.
        let wyman = refraction == Refraction::Wyman;
        let mode = [
            u32::from(primary == Primary::Rasterized),
            u32::from(wyman),
            0,
            0,
        ];
        let mut texels = Texels::default();
        let uniform = GpuView::lit(lighting, settings, mode, &mut texels);
        let mut materials = Vec::new();
        let mut first_material = Vec::with_capacity(view.meshes.len());
        for (mesh, surface) in view.meshes.iter().zip(&view.surfaces) {
            first_material.push(materials.len() as u32);
            let diffuse = |color: Vec3, texture: Option<&Arc<Image<Rgba>>>, texels: &mut Texels| {
                GpuMaterial {
                    color: v4(color, f32::from_bits(DIFFUSE)),
                    ior: [1.0, 0.0, 0.0, 0.0],
                    texture: texture.map_or([0; 4], |t| texels.texture(t)),
                }
            };
            match surface {
                Surface::Mirror { .. } | Surface::Glass { .. } => {
                    materials.push(GpuMaterial::specular(surface))
                }
                Surface::Diffuse(Some(o)) => {
                    materials.push(diffuse(o.color, o.texture.as_ref(), &mut texels))
                }
                Surface::Diffuse(None) => {
                    for m in &mesh.materials {
                        materials.push(diffuse(m.base_color, m.texture.as_ref(), &mut texels));
                    }
                    // A face whose material index is out of range is shaded 0.8 grey, as on the CPU.
                    materials.push(diffuse(Vec3::splat(0.8), None, &mut texels));
                }
            }
        }
        let (impostors, built);
        let bvh = match secondary {
            Secondary::Exact => {
                impostors = None;
                built = Bvh::build(view.meshes.clone())?;
                &built
            }
            Secondary::Impostors { answers, bvh } => {
                impostors = Some(upload_impostors(gpu, view, answers, &first_material)?);
                bvh
            }
            Secondary::Splats { bvh } => {
                impostors = None;
                bvh
            }
        };
        let specular = |o: u32| match view.surfaces.get(o as usize) {
            Some(Surface::Diffuse(_)) | None => crate::bvh::EVERY_TRIANGLE,
            Some(Surface::Mirror { .. }) => SPECULAR,
            Some(Surface::Glass { .. }) => SPECULAR | GLASS_CLASS,
        };
        let (nodes, corners) = crate::bvh::upload(gpu, bvh, &specular)?;
        let material_of = |object: usize, triangle: usize| -> u32 {
            let first = first_material[object];
            match &view.surfaces[object] {
                Surface::Diffuse(None) => {
                    let mesh = &view.meshes[object];
                    let m = mesh.face_material.get(triangle).copied().unwrap_or(0) as usize;
                    first + m.min(mesh.materials.len()) as u32
                }
                _ => first,
            }
        };
        // Under Wyman's refraction, d_N at each glass vertex (one ray each, on the CPU as the
        // paper precomputes it), and the glass triangles whose back faces each frame draws.
        let d_n = match wyman {
            true => trompe::render::wyman::vertex_distances(view)?,
            false => Vec::new(),
        };
        let triangles: Vec<GpuTriangle> = bvh
            .leaf_sources()
            .iter()
            .map(|&(o, t)| {
                let mesh = &view.meshes[o as usize];
                let corners = mesh.triangles[t as usize].map(|i| i as usize);
                let n = corners.map(|i| mesh.normals[i]);
                let uv = corners.map(|i| mesh.uvs.as_ref().map_or(Vec2::ZERO, |uv| uv[i]));
                let d = d_n
                    .get(o as usize)
                    .filter(|d| !d.is_empty())
                    .map_or([0.0; 3], |d| {
                        corners.map(|i| d.get(i).copied().unwrap_or(0.0))
                    });
                GpuTriangle {
                    n0: v4(n[0], f32::from_bits(material_of(o as usize, t as usize))),
                    n1: v4(n[1], f32::from_bits(o)),
                    n2: v4(n[2], d[0]),
                    ng: v4(mesh.face_normal(t as usize), d[1]),
                    uv01: [uv[0].x, uv[0].y, uv[1].x, uv[1].y],
                    uv2: [uv[2].x, uv[2].y, d[2], 0.0],
                }
            })
            .collect();
        let glass = wyman.then(|| {
            bvh.leaf_sources()
                .iter()
                .zip(bvh.leaf_corners())
                .enumerate()
                .filter(|(_, ((o, _), _))| {
                    matches!(view.surfaces.get(*o as usize), Some(Surface::Glass { .. }))
                })
                .map(|(leaf, (&(o, t), &corners))| GlassFace {
                    leaf: leaf as u32,
                    corners,
                    normal: view.meshes[o as usize].face_normal(t as usize),
                })
                .collect()
        });

        let raster = match primary {
            Primary::Traced => None,
            Primary::Rasterized => Some(raster_pipeline(gpu, bvh)?),
        };
        let triangle_bytes: &[u8] = bytemuck::cast_slice(&triangles);
        let texel_bytes = texels.bytes();
        gpu.check_storage("the triangles' shading data", triangle_bytes.len() as u64)?;
        gpu.check_storage("the textures and the panorama", texel_bytes.len() as u64)?;
        let scene = [
            nodes,
            corners,
            // At least one triangle's worth: a binding holds one element, read by no one in a
            // scene without triangles.
            gpu.storage_with("triangles", &{
                let mut bytes = triangle_bytes.to_vec();
                bytes.resize(bytes.len().max(size_of::<GpuTriangle>()), 0);
                bytes
            }),
            gpu.storage_with("materials", bytemuck::cast_slice(&materials)),
            gpu.storage_with("texels", texel_bytes),
        ];
        let pipeline = match (impostors.is_some(), secondary) {
            (_, Secondary::Splats { .. }) => gpu.compute_pipeline(
                SPLAT_MODULE,
                &splat_shader_source(gpu.has_f64()),
                "trace_pixels",
            ),
            (false, _) => gpu.compute_pipeline("trace.wgsl", &shader_source(), "trace_pixels"),
            (true, _) => gpu.compute_pipeline(
                "trace.wgsl with impostors",
                &impostor_shader_source(),
                "trace_pixels",
            ),
        };
        Ok(GpuTracer {
            gpu,
            pipeline,
            scene,
            uniform,
            raster,
            impostors,
            glass,
        })
    }

    /// The frame through `camera`.
    pub fn frame(&self, camera: &Pinhole) -> Result<Frame, GpuError> {
        self.frame_with(camera, &[], None)
    }

    /// With rasterized primaries: the visibility buffer through `camera`, drawn into a new
    /// texture (recorded in `encoder`) for [`GpuTracer::frame_with`] and the passes before it.
    pub(crate) fn visibility(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Pinhole,
    ) -> Option<wgpu::Texture> {
        let raster = self.raster.as_ref()?;
        Some(self.draw_visibility(encoder, raster, camera))
    }

    /// The scene's buffers as the shaders bind them: nodes, corners, triangles, materials,
    /// texels.
    pub(crate) fn scene_entries(&self) -> [(u32, &wgpu::Buffer); 5] {
        let [nodes, corners, triangles, materials, texels] = &self.scene;
        [
            (0, nodes),
            (1, corners),
            (5, triangles),
            (6, materials),
            (7, texels),
        ]
    }

    /// The view uniform through `camera`.
    pub(crate) fn view_through(&self, camera: &Pinhole) -> GpuView {
        self.uniform.through(camera)
    }

    /// [`GpuTracer::frame`], the shader also bound to `extra` (what its secondary rays read),
    /// and the eye's hits read from `drawn` where given ([`GpuTracer::visibility`]'s).
    pub(crate) fn frame_with(
        &self,
        camera: &Pinhole,
        extra: &[(u32, &wgpu::Buffer)],
        drawn: Option<&wgpu::Texture>,
    ) -> Result<Frame, GpuError> {
        self.record(camera, extra, drawn)?.read(self.gpu)
    }

    /// [`GpuTracer::frame_with`]'s pass recorded, not yet submitted: later passes may draw over
    /// its buffers before [`Recorded::read`] reads the frame back.
    pub(crate) fn record(
        &self,
        camera: &Pinhole,
        extra: &[(u32, &wgpu::Buffer)],
        drawn: Option<&wgpu::Texture>,
    ) -> Result<Recorded, GpuError> {
        let gpu = self.gpu;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let uniform = self.uniform.through(camera);
        let pixels = u64::from(w) * u64::from(h);
        let out_bytes = pixels * 16;
        gpu.check_storage("the frame", out_bytes)?;
        let uniform = gpu.uniform_with("view", bytemuck::bytes_of(&uniform));
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let outputs = ["colour", "depth and id", "normal"].map(|l| gpu.buffer(l, out_bytes, usage));
        if self.raster.is_some() {
            gpu.check_texture("the visibility buffer", w, h)?;
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let visibility = match (drawn, &self.raster) {
            (Some(drawn), _) => drawn.clone(),
            (None, Some(raster)) => self.draw_visibility(&mut encoder, raster, camera),
            // Not read: a binding stands in.
            (None, None) => visibility_texture(gpu, 1, 1),
        };
        let visibility_view = visibility.create_view(&Default::default());
        let backs = match &self.glass {
            Some(glass) => self.draw_back_faces(&mut encoder, glass, camera)?,
            // Not read: a binding stands in.
            None => visibility_texture(gpu, 1, 1),
        };
        let backs_view = backs.create_view(&Default::default());
        let [nodes, corners, triangles, materials, texels] = &self.scene;
        let walks = self
            .impostors
            .iter()
            .flat_map(|(walks, reflectors)| walks.entries().into_iter().chain([(18, reflectors)]));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("trace"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                (0, nodes),
                (1, corners),
                (5, triangles),
                (6, materials),
                (7, texels),
                (8, &uniform),
                (9, &outputs[0]),
                (10, &outputs[1]),
                (11, &outputs[2]),
            ]
            .into_iter()
            .chain(walks)
            .chain(extra.iter().copied())
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .chain([
                wgpu::BindGroupEntry {
                    binding: 12,
                    resource: wgpu::BindingResource::TextureView(&visibility_view),
                },
                wgpu::BindGroupEntry {
                    binding: 20,
                    resource: wgpu::BindingResource::TextureView(&backs_view),
                },
            ])
            .collect::<Vec<_>>(),
        });
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        Ok(Recorded {
            encoder,
            outputs,
            size: (w, h),
        })
    }
}

/// A frame's passes recorded into `encoder`, writing `outputs` — colour, (depth, object id
/// bits) and normal, a `vec4<f32>` a pixel each, as `shaders/trace.wgsl` writes them.
pub(crate) struct Recorded {
    pub(crate) encoder: wgpu::CommandEncoder,
    pub(crate) outputs: [wgpu::Buffer; 3],
    pub(crate) size: (u32, u32),
}

impl Recorded {
    /// Submits the passes and reads the frame back: depth, normal and id where a surface was
    /// found, the colour everywhere.
    pub(crate) fn read(self, gpu: &Gpu) -> Result<Frame, GpuError> {
        let (w, h) = self.size;
        let pixels = u64::from(w) * u64::from(h);
        let read = gpu.read_back(self.encoder, &self.outputs, "the frame")?;
        let texels = |i: usize| -> Vec<[f32; 4]> {
            bytemuck::pod_collect_to_vec(&read[i][..pixels as usize * 16])
        };
        let (color, depth_id, normal) = (texels(0), texels(1), texels(2));
        let mut frame = Frame::new(w, h)?;
        for (i, ((c, d), n)) in color.iter().zip(&depth_id).zip(&normal).enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            frame.color.set(x, y, Vec4::from_array(*c));
            let id = d[1].to_bits();
            if id != NO_OBJECT {
                frame.depth.set(x, y, d[0]);
                frame.object_id.set(x, y, id);
                frame.normal.set(x, y, Vec4::from_array(*n).truncate());
            }
        }
        Ok(frame)
    }
}

impl GpuTracer<'_> {
    /// Draws the visibility buffer through `camera` into a new texture (recorded in `encoder`).
    fn draw_visibility(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        raster: &(wgpu::RenderPipeline, wgpu::Buffer, u32),
        camera: &Pinhole,
    ) -> wgpu::Texture {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let visibility = visibility_texture(self.gpu, w, h);
        let uniform = GpuRasterCamera::pinhole(camera);
        draw_into_visibility(self.gpu, encoder, raster, &uniform, &visibility, (w, h));
        visibility
    }

    /// Wyman's first pass: the back faces of the glass objects (those facing away from the
    /// eye, chosen as `trompe::render::wyman::BackFaces` chooses them) drawn through `camera`
    /// into a new visibility texture, the nearest kept.
    fn draw_back_faces(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        glass: &[GlassFace],
        camera: &Pinhole,
    ) -> Result<wgpu::Texture, GpuError> {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let eye = camera.position().as_vec3();
        let backs: Vec<(u32, [Vec3; 3])> = glass
            .iter()
            .filter(|f| {
                let [a, b, c] = f.corners;
                f.normal.dot((a + b + c) / 3.0 - eye) > 0.0
            })
            .map(|f| (f.leaf, f.corners))
            .collect();
        let visibility = visibility_texture(self.gpu, w, h);
        let (vertices, count) = corner_buffer(self.gpu, &backs)?;
        let pipeline = visibility_pipeline(self.gpu, false);
        let draws = [(GpuRasterCamera::pinhole(camera), 0..count)];
        draw_ranges_into_visibility(
            self.gpu,
            encoder,
            (&pipeline, &vertices),
            (&draws, None),
            &visibility,
            (w, h),
        );
        Ok(visibility)
    }
}

/// The impostors every mirror and glass object of `view` sees, walked by the shader, and the
/// table of which each sees (`shaders/impostor_secondary.wgsl`'s `reflectors`), with each
/// object's first material (`first_material`: what a mirror's stored surface is shaded by).
fn upload_impostors(
    gpu: &Gpu,
    view: &View,
    answers: &ReflectorImpostors,
    first_material: &[u32],
) -> Result<(UploadedWalks, wgpu::Buffer), GpuError> {
    let storage = gpu.limits().max_storage_buffers_per_shader_stage;
    if storage < IMPOSTOR_STORAGE_BUFFERS {
        return Err(GpuError::Unsupported {
            what: format!(
                "the impostor methods on an adapter with {storage} storage buffers a shader \
                 stage (they read {IMPOSTOR_STORAGE_BUFFERS})"
            ),
        });
    }
    let objects = view.surfaces.len() as u32;
    let specular: Vec<u32> = (0..objects)
        .filter(|&o| !matches!(view.surfaces[o as usize], Surface::Diffuse(_)))
        .collect();
    let glass = |o: u32| matches!(view.surfaces[o as usize], Surface::Glass { .. });
    let mut set = WalkSet::new();
    // One upload of an impostor several objects see.
    let mut placed: HashMap<(*const trompe::impostor::Impostor, bool), u32> = HashMap::new();
    let mut table = vec![0u32; 3 * objects as usize];
    for o in 0..objects {
        let mut seen = Vec::new();
        for s in answers.seen_by(o) {
            let key = (std::ptr::from_ref(s.impostor), s.radiance);
            let index = match placed.get(&key) {
                Some(&i) => i,
                None => {
                    let i = set.push(s.impostor, s.now_from_built, s.radiance)?;
                    placed.insert(key, i);
                    i
                }
            };
            seen.push(index);
        }
        let exactly = answers.seen_exactly_by(o);
        let glass_and_itself: Vec<u32> = (0..objects).filter(|&g| g == o || glass(g)).collect();
        let flag = if exactly.is_empty() {
            0
        } else if exactly == specular.as_slice() {
            SEES_EXACTLY
        } else if exactly == glass_and_itself.as_slice() {
            SEES_GLASS_AND_ITSELF
        } else {
            return Err(GpuError::Unsupported {
                what: format!(
                    "object {o} seeing the mirror and glass objects {exactly:?} exactly (the GPU \
                     sees all of them, or itself and the glass)"
                ),
            });
        };
        let row = 3 * o as usize;
        table[row] = table.len() as u32;
        table[row + 1] = seen.len() as u32 | flag;
        table[row + 2] = first_material.get(o as usize).copied().unwrap_or(0);
        table.extend(seen);
    }
    let walks = set.upload(gpu)?;
    let bytes: &[u8] = bytemuck::cast_slice(&table);
    gpu.check_storage("the impostors each object sees", bytes.len() as u64)?;
    let mut padded = bytes.to_vec();
    padded.resize(padded.len().max(16), 0);
    Ok((walks, gpu.storage_with("reflectors", &padded)))
}
