//! The `octahedral` method on the GPU (beyond the papers: what engines draw far away): the
//! atlases the library bakes ([`SceneAtlases`]: one an object, or a field of instances) uploaded
//! once, and each frame drawn by the engines' shader `shaders/octahedral_impostor.wgsl` — one
//! instanced draw an atlas, a camera-facing card a copy — into base colour, normal and object
//! id, the depth test keeping the nearest surface the alpha test let through; then shaded by
//! `shaders/octahedral_shade.wgsl` as the library's `octahedral::scene` shades (unshadowed,
//! every bounce the environment's). Its CPU twin is `trompe render --method octahedral`.
//!
//! Invariant: a frame depends only on the atlases, the lighting and the camera (no blending, one
//! invocation a pixel), so the same inputs give the same pixels on one device.

use crate::device::{Gpu, GpuError};
use crate::raster::{DEPTH, v4};
use crate::trace::{GpuMaterial, GpuView, Texels};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, DVec4, Vec4};
use trompe::camera::Pinhole;
use trompe::frame::{Frame, NO_OBJECT};
use trompe::octahedral::scene::SceneAtlases;
use trompe::octahedral::{Coverage, FrameProjection, OctahedralAtlas};
use trompe::scene::{Lighting, RenderSettings};

/// The engines' octahedral impostor shader, as the repository ships it.
pub const IMPOSTOR_SHADER: &str = include_str!("../../../shaders/octahedral_impostor.wgsl");

/// The shading pass's source: the tracer's lighting, then the pass.
fn shade_source() -> String {
    [
        crate::trace::shader_source(),
        include_str!("../shaders/octahedral_shade.wgsl").into(),
    ]
    .join("\n")
}

/// The G-buffer's formats: base colour and normal (half floats), object id (and the depth,
/// the rasterizer's reversed one).
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const OBJECT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The shader's `Camera`: world to clip, the eye and the near plane's distance.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuCamera {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
}

/// The shader's `Impostor`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuImpostor {
    centre: [f32; 3],
    radius: f32,
    frames: u32,
    frame_size: u32,
    coverage: u32,
    distance: f32,
}

/// One copy drawn: its translation from the bake's place and its object id (vertex locations
/// 1 and 2, one a instance).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuInstance {
    offset: [f32; 3],
    object: u32,
}

/// An atlas on the device: its three maps, its uniform, and the copies it draws.
struct UploadedAtlas {
    group: wgpu::BindGroup,
    instances: std::ops::Range<u32>,
}

/// A scene's atlases on the device, ready to draw through any camera.
pub struct GpuAtlases<'a> {
    gpu: &'a Gpu,
    pipeline: wgpu::RenderPipeline,
    shade: wgpu::ComputePipeline,
    atlases: Vec<UploadedAtlas>,
    /// The card's four corners, and every copy of every atlas, atlas by atlas.
    corners: wgpu::Buffer,
    instances: wgpu::Buffer,
    /// The camera's uniform, rewritten each frame (binding 0 of every atlas's group).
    camera: wgpu::Buffer,
    /// One material an object (binding 6), the panorama's texels (7), the lighting's uniform.
    materials: wgpu::Buffer,
    texels: wgpu::Buffer,
    uniform: GpuView,
}

impl<'a> GpuAtlases<'a> {
    /// Uploads `atlases` and the scene's `lighting` to `gpu`.
    pub fn new(
        gpu: &'a Gpu,
        atlases: &SceneAtlases,
        lighting: &Lighting,
        settings: &RenderSettings,
    ) -> Result<Self, GpuError> {
        let pipeline = impostor_pipeline(gpu);
        let shade = gpu.compute_pipeline("octahedral_shade.wgsl", &shade_source(), "shade_atlases");
        let camera = gpu.buffer(
            "octahedral camera",
            std::mem::size_of::<GpuCamera>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("atlas"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // Every copy, atlas by atlas, in object order within each.
        let placed = atlases.placed();
        let mut instances = Vec::with_capacity(placed.len());
        let mut uploaded = Vec::new();
        for (index, atlas) in atlases.atlases().enumerate() {
            let first = instances.len() as u32;
            instances.extend(
                placed
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.atlas == index)
                    .map(|(object, p)| GpuInstance {
                        offset: p.offset.to_array(),
                        object: object as u32,
                    }),
            );
            let group = upload_atlas(gpu, &pipeline, atlas, (&camera, &sampler))?;
            uploaded.push(UploadedAtlas {
                group,
                instances: first..instances.len() as u32,
            });
        }
        if instances.is_empty() {
            instances.push(GpuInstance::zeroed());
        }
        let corners: [[f32; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [1.0, 1.0]];
        let surfaces: Vec<_> = atlases.surfaces().map(GpuMaterial::specular).collect();
        let materials: Vec<GpuMaterial> = placed
            .iter()
            .map(|p| {
                surfaces
                    .get(p.atlas)
                    .copied()
                    .unwrap_or_else(GpuMaterial::zeroed)
            })
            .collect();
        let materials: &[u8] = bytemuck::cast_slice(&materials);
        gpu.check_storage("the objects' materials", materials.len() as u64)?;
        let mut texels = Texels::default();
        let uniform = GpuView::lit(lighting, settings, [0; 4], &mut texels);
        gpu.check_storage("the panorama", texels.bytes().len() as u64)?;
        Ok(GpuAtlases {
            gpu,
            pipeline,
            shade,
            atlases: uploaded,
            corners: gpu.vertices_with("card corners", bytemuck::cast_slice(&corners)),
            instances: gpu.vertices_with("instances", bytemuck::cast_slice(&instances)),
            camera,
            materials: gpu.storage_with("materials", materials),
            texels: gpu.storage_with("texels", texels.bytes()),
            uniform,
        })
    }

    /// The frame through `camera`: colour and object id, as the CPU twin fills them.
    pub fn frame(&self, camera: &Pinhole) -> Result<Frame, GpuError> {
        let gpu = self.gpu;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        gpu.check_texture("the frame", w, h)?;
        let out_bytes = u64::from(w) * u64::from(h) * 16;
        gpu.check_storage("the frame", out_bytes)?;
        gpu.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(&clip_camera(camera)));
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let color = gpu.texture("base colour", (w, h), COLOR, usage);
        let normal = gpu.texture("normal", (w, h), COLOR, usage);
        let object = gpu.texture("object", (w, h), OBJECT, usage);
        let depth = gpu.texture("depth", (w, h), DEPTH, usage);
        let views = [&color, &normal, &object, &depth].map(|t| t.create_view(&Default::default()));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let target = |view, clear: f64| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: clear,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("octahedral impostors"),
                color_attachments: &[
                    target(&views[0], 0.0),
                    target(&views[1], 0.0),
                    target(&views[2], f64::from(NO_OBJECT)),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &views[3],
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_vertex_buffer(0, self.corners.slice(..));
            pass.set_vertex_buffer(1, self.instances.slice(..));
            for atlas in &self.atlases {
                pass.set_bind_group(0, &atlas.group, &[]);
                pass.draw(0..4, atlas.instances.clone());
            }
        }
        let uniform = gpu.uniform_with("view", bytemuck::bytes_of(&self.uniform.through(camera)));
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let outputs = ["colour", "depth and id"].map(|l| gpu.buffer(l, out_bytes, storage));
        let buffers = [
            (6, &self.materials),
            (7, &self.texels),
            (8, &uniform),
            (9, &outputs[0]),
            (10, &outputs[1]),
        ];
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("octahedral shading"),
            layout: &self.shade.get_bind_group_layout(0),
            entries: &buffers
                .into_iter()
                .map(|(binding, b)| wgpu::BindGroupEntry {
                    binding,
                    resource: b.as_entire_binding(),
                })
                .chain((0..3).map(|k| wgpu::BindGroupEntry {
                    binding: 21 + k as u32,
                    resource: wgpu::BindingResource::TextureView(&views[k]),
                }))
                .collect::<Vec<_>>(),
        });
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.shade);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        let read = gpu.read_back(encoder, &outputs, "the frame")?;
        let texels = |i: usize| -> Vec<[f32; 4]> {
            bytemuck::pod_collect_to_vec(&read[i][..out_bytes as usize])
        };
        let (color, depth_id) = (texels(0), texels(1));
        let mut frame = Frame::new(w, h)?;
        for (i, (c, d)) in color.iter().zip(&depth_id).enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            frame.color.set(x, y, Vec4::from_array(*c));
            frame.object_id.set(x, y, d[1].to_bits());
        }
        Ok(frame)
    }
}

/// The engine shader's pipeline: instanced cards, three targets, reversed depth (the nearest
/// kept, ties to the earlier draw).
fn impostor_pipeline(gpu: &Gpu) -> wgpu::RenderPipeline {
    gpu.render_pipeline("octahedral impostors", || {
        let module = gpu.module("octahedral_impostor.wgsl", IMPOSTOR_SHADER);
        let corner = wgpu::vertex_attr_array![0 => Float32x2];
        let instance = wgpu::vertex_attr_array![1 => Float32x3, 2 => Uint32];
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("octahedral impostors"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[
                        Some(wgpu::VertexBufferLayout {
                            array_stride: 8,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &corner,
                        }),
                        Some(wgpu::VertexBufferLayout {
                            array_stride: std::mem::size_of::<GpuInstance>() as u64,
                            step_mode: wgpu::VertexStepMode::Instance,
                            attributes: &instance,
                        }),
                    ],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleStrip,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(crate::raster::nearest_kept()),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[target(COLOR), target(COLOR), target(OBJECT)],
                }),
                multiview_mask: None,
                cache: None,
            })
    })
}

/// `atlas`'s maps as half-float textures and its uniform, bound with the frame's `camera`
/// uniform and `sampler` as the shader's group 0.
fn upload_atlas(
    gpu: &Gpu,
    pipeline: &wgpu::RenderPipeline,
    atlas: &OctahedralAtlas,
    (camera, sampler): (&wgpu::Buffer, &wgpu::Sampler),
) -> Result<wgpu::BindGroup, GpuError> {
    let side = atlas.side();
    gpu.check_texture("an octahedral atlas", side, side)?;
    let to_half = half::f16::from_f32;
    let color: Vec<half::f16> = atlas
        .color
        .pixels()
        .iter()
        .flat_map(|c| c.to_array().map(to_half))
        .collect();
    let normal: Vec<half::f16> = atlas
        .normal
        .pixels()
        .iter()
        .flat_map(|n| n.extend(0.0).to_array().map(to_half))
        .collect();
    let depth: Vec<half::f16> = atlas.depth.pixels().iter().map(|&d| to_half(d)).collect();
    let maps = [
        (
            "atlas colour",
            COLOR,
            bytemuck::cast_slice::<_, u8>(&color),
            8,
        ),
        ("atlas normal", COLOR, bytemuck::cast_slice(&normal), 8),
        (
            "atlas depth",
            wgpu::TextureFormat::R16Float,
            bytemuck::cast_slice(&depth),
            2,
        ),
    ]
    .map(|(label, format, bytes, texel)| {
        let texture = gpu.texture(
            label,
            (side, side),
            format,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        gpu.queue.write_texture(
            texture.as_image_copy(),
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side * texel),
                rows_per_image: Some(side),
            },
            crate::device::extent((side, side)),
        );
        texture.create_view(&Default::default())
    });
    let settings = &atlas.settings;
    let uniform = GpuImpostor {
        centre: atlas.centre.to_array(),
        radius: atlas.radius,
        frames: settings.grid.n,
        frame_size: settings.frame_size,
        coverage: match settings.grid.coverage {
            Coverage::Sphere => 0,
            Coverage::Hemisphere => 1,
        },
        distance: match settings.projection {
            FrameProjection::Orthographic => 0.0,
            FrameProjection::Pinhole { distance } => distance,
        },
    };
    let uniform = gpu.uniform_with("impostor", bytemuck::bytes_of(&uniform));
    let texture = |binding, view| wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    };
    Ok(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("octahedral atlas"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: uniform.as_entire_binding(),
            },
            texture(2, &maps[0]),
            texture(3, &maps[1]),
            texture(4, &maps[2]),
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
        ],
    }))
}

/// `camera` as the shader's world-to-clip matrix: `x, y` from its pixel rows, `w` the ray
/// parameter `t` of its McMillan model, and reversed depth `z / w = t_near / t` (1 on the near
/// plane, 0 at infinity); computed in f64 about the eye.
fn clip_camera(camera: &Pinhole) -> GpuCamera {
    let (w, h) = trompe::camera::Projection::resolution(camera);
    let inverse = camera.mcmillan_inverse();
    let eye = camera.position();
    let (row_u, row_v, row_t) = (inverse.row(0), inverse.row(1), inverse.row(2));
    let t_near = camera.near() / camera.focal();
    // Each row applied to X − eye: the eye's term moves into the fourth column.
    let row = |r: DVec3| DVec4::new(r.x, r.y, r.z, -r.dot(eye));
    let rows = [
        row(row_u * (2.0 / f64::from(w)) - row_t),
        row(row_t - row_v * (2.0 / f64::from(h))),
        DVec4::new(0.0, 0.0, 0.0, t_near),
        row(row_t),
    ];
    let m = glam::DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose();
    GpuCamera {
        view_proj: m.as_mat4().to_cols_array_2d(),
        eye: v4(eye.as_vec3(), camera.near() as f32),
    }
}
