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
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::frame::{Frame, Image, NO_OBJECT, Rgba};
use trompe::scene::{Lighting, RenderSettings, Surface, View};
use trompe::trace::Bvh;

/// The tracer's source: the BVH walk, then the tracer.
pub fn shader_source() -> String {
    [crate::bvh::SHADER, include_str!("../shaders/trace.wgsl")].join("\n")
}

/// Pending rays a pixel may hold (the shader's `PENDING`): a depth-first walk of mirrors and
/// glass holds at most one more than the recursion limit.
pub const MAX_DEPTH: u32 = 23;

/// The shader's material kinds.
const DIFFUSE: u32 = 0;
const MIRROR: u32 = 1;
const GLASS: u32 = 2;

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

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuMaterial {
    color: [f32; 4],
    ior: [f32; 4],
    texture: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuView {
    eye: [f32; 4],
    a: [f32; 4],
    b: [f32; 4],
    c: [f32; 4],
    size: [u32; 4],
    sun_dir: [f32; 4],
    sun: [f32; 4],
    radiance: [u32; 4],
    irradiance: [u32; 4],
}

/// Every image the shader reads, one after another, as `(first texel, width, height)`.
#[derive(Default)]
struct Texels {
    data: Vec<[f32; 4]>,
    placed: HashMap<*const Image<Rgba>, [u32; 4]>,
}

impl Texels {
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

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    v.extend(w).to_array()
}

/// The `trace` method's frame of `view`, rendered on `gpu`: colour, depth, shading normal and
/// object id, as the CPU tracer fills them.
pub fn render(
    gpu: &Gpu,
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
) -> Result<Frame, GpuError> {
    GpuTracer::new(gpu, view, lighting, settings)?.frame(&view.camera)
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
}

impl<'a> GpuTracer<'a> {
    /// Builds the BVH of `view`'s meshes and uploads the scene (`view`'s camera is not used).
    pub fn new(
        gpu: &'a Gpu,
        view: &View,
        lighting: &Lighting,
        settings: &RenderSettings,
    ) -> Result<GpuTracer<'a>, GpuError> {
        if settings.max_depth > MAX_DEPTH {
            return Err(GpuError::Unsupported {
                what: format!(
                    "a recursion limit of {} (the GPU tracer follows at most {MAX_DEPTH})",
                    settings.max_depth
                ),
            });
        }
        let bvh = Bvh::build(view.meshes.clone());
        let (nodes, corners) = crate::bvh::upload(gpu, &bvh)?;
        // Materials: one a (object, mesh material), the scene's surface deciding.
        let mut texels = Texels::default();
        let environment = &lighting.environment;
        let radiance = texels.colour(environment.image());
        let irradiance = texels.colour(environment.irradiance_image());
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
                Surface::Mirror { tint } => materials.push(GpuMaterial {
                    color: v4(*tint, f32::from_bits(MIRROR)),
                    ior: [1.0, 0.0, 0.0, 0.0],
                    texture: [0; 4],
                }),
                Surface::Glass { ior, tint } => materials.push(GpuMaterial {
                    color: v4(*tint, f32::from_bits(GLASS)),
                    ior: [*ior, 0.0, 0.0, 0.0],
                    texture: [0; 4],
                }),
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
        let triangles: Vec<GpuTriangle> = bvh
            .leaf_sources()
            .iter()
            .map(|&(o, t)| {
                let mesh = &view.meshes[o as usize];
                let corners = mesh.triangles[t as usize].map(|i| i as usize);
                let n = corners.map(|i| mesh.normals[i]);
                let uv = corners.map(|i| mesh.uvs.as_ref().map_or(Vec2::ZERO, |uv| uv[i]));
                GpuTriangle {
                    n0: v4(n[0], f32::from_bits(material_of(o as usize, t as usize))),
                    n1: v4(n[1], f32::from_bits(o)),
                    n2: v4(n[2], 0.0),
                    ng: v4(mesh.face_normal(t as usize), 0.0),
                    uv01: [uv[0].x, uv[0].y, uv[1].x, uv[1].y],
                    uv2: [uv[2].x, uv[2].y, 0.0, 0.0],
                }
            })
            .collect();

        let environment_rotation = environment.rotation();
        let sun = lighting.light.as_ref();
        let uniform = GpuView {
            eye: [0.0, 0.0, 0.0, settings.ray_epsilon],
            a: [0.0; 4],
            b: [0.0; 4],
            c: [0.0; 4],
            size: [0, 0, settings.max_depth, u32::from(sun.is_some())],
            sun_dir: v4(sun.map_or(Vec3::Y, |s| s.direction), environment_rotation),
            sun: v4(
                sun.map_or(Vec3::ZERO, |s| s.irradiance),
                environment.intensity(),
            ),
            radiance,
            irradiance,
        };
        let triangle_bytes: &[u8] = bytemuck::cast_slice(&triangles);
        let texel_bytes: &[u8] = bytemuck::cast_slice(&texels.data);
        gpu.check_storage("the triangles' shading data", triangle_bytes.len() as u64)?;
        gpu.check_storage("the textures and the panorama", texel_bytes.len() as u64)?;
        let scene = [
            nodes,
            corners,
            gpu.storage_with("triangles", triangle_bytes),
            gpu.storage_with("materials", bytemuck::cast_slice(&materials)),
            gpu.storage_with("texels", texel_bytes),
        ];
        let pipeline = gpu.compute_pipeline("trace.wgsl", &shader_source(), "trace_pixels");
        Ok(GpuTracer {
            gpu,
            pipeline,
            scene,
            uniform,
        })
    }

    /// The frame through `camera`.
    pub fn frame(&self, camera: &Pinhole) -> Result<Frame, GpuError> {
        let gpu = self.gpu;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let (a, b, c) = camera.mcmillan();
        let mut uniform = self.uniform;
        uniform.eye = v4(camera.position().as_vec3(), uniform.eye[3]);
        uniform.a = v4(a.as_vec3(), 0.0);
        uniform.b = v4(b.as_vec3(), 0.0);
        uniform.c = v4(c.as_vec3(), 0.0);
        uniform.size[0] = w;
        uniform.size[1] = h;
        let pixels = u64::from(w) * u64::from(h);
        let out_bytes = pixels * 16;
        gpu.check_storage("the frame", out_bytes)?;
        let uniform = gpu.uniform_with("view", bytemuck::bytes_of(&uniform));
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let outputs = ["colour", "depth and id", "normal"].map(|l| gpu.buffer(l, out_bytes, usage));
        let [nodes, corners, triangles, materials, texels] = &self.scene;
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
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }),
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        let read = gpu.read_back(encoder, &outputs, "the frame")?;
        let texels = |i: usize| -> Vec<[f32; 4]> {
            bytemuck::pod_collect_to_vec(&read[i][..out_bytes as usize])
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
