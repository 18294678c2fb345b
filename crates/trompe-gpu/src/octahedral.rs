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
use glam::{DVec3, DVec4, Quat, Vec3, Vec4};
use trompe::camera::Pinhole;
use trompe::frame::{Frame, Image, NO_OBJECT};
use trompe::octahedral::scene::SceneAtlases;
use trompe::octahedral::{Coverage, CrossFade, FrameProjection, OctahedralAtlas};
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
    /// The cross-fade's start and end (0, 0: the impostor draws every pixel).
    fade: [f32; 2],
    pad: [f32; 2],
}

/// One copy drawn: its offset, object id, rotation and scale (vertex locations 1–4, one a
/// instance): `world = rotation · (scale · p) + offset`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuInstance {
    offset: [f32; 3],
    object: u32,
    rotation: [f32; 4],
    scale: f32,
}

/// A similarity every copy is drawn through, after its own placement: `world = rotation ·
/// (scale · p) + translation`. What an engine's instance transforms are; the scene's own
/// placement is [`Similarity::IDENTITY`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// A unit quaternion.
    pub rotation: Quat,
    /// A uniform scale, positive.
    pub scale: f32,
    /// Applied last.
    pub translation: Vec3,
}

impl Similarity {
    /// No move.
    pub const IDENTITY: Similarity = Similarity {
        rotation: Quat::IDENTITY,
        scale: 1.0,
        translation: Vec3::ZERO,
    };

    /// The point `p` moved.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.rotation * (p * self.scale) + self.translation
    }
}

/// Which fragment entry point draws the impostors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Entry {
    /// `fs_main`: base colour, normal, object id and depth.
    GBuffer,
    /// `fs_depth`: the depth alone, as a shadow map or a depth pre-pass draws.
    DepthOnly,
}

/// An atlas on the device: its three maps, its uniform, and the copies it draws.
struct UploadedAtlas {
    group: wgpu::BindGroup,
    /// Its uniform (binding 1), and what it holds.
    uniform: wgpu::Buffer,
    impostor: GpuImpostor,
    /// Its card's outline as a triangle strip, in the corners buffer.
    card: std::ops::Range<u32>,
    instances: std::ops::Range<u32>,
}

/// A scene's atlases on the device, ready to draw through any camera.
pub struct GpuAtlases<'a> {
    gpu: &'a Gpu,
    pipeline: wgpu::RenderPipeline,
    depth_pipeline: wgpu::RenderPipeline,
    /// Every copy's placement in the scene (offset and object id), before [`Similarity`].
    placed: Vec<GpuInstance>,
    shade: wgpu::ComputePipeline,
    atlases: Vec<UploadedAtlas>,
    /// Every atlas's card outline, and every copy of every atlas, atlas by atlas.
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
        let pipeline = impostor_pipeline(gpu, Entry::GBuffer);
        let depth_pipeline = impostor_pipeline(gpu, Entry::DepthOnly);
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
        let mut corners: Vec<[f32; 2]> = Vec::new();
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
                        rotation: Quat::IDENTITY.to_array(),
                        scale: 1.0,
                    }),
            );
            let mut upload = upload_atlas(gpu, atlas, (&camera, &sampler))?;
            let card = corners.len() as u32;
            corners.extend(atlas.card.strip());
            upload.card = card..corners.len() as u32;
            upload.instances = first..instances.len() as u32;
            uploaded.push(upload);
        }
        if instances.is_empty() {
            instances.push(GpuInstance::zeroed());
        }
        if corners.is_empty() {
            corners.extend(trompe::octahedral::Card::default().strip());
        }
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
            depth_pipeline,
            placed: instances.clone(),
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

    /// Draws every atlas with the dithered cross-fade `fade` from now on (distances in each
    /// bake's units), as an engine hands objects from their meshes to their impostors
    /// (`trompe::octahedral::lod`); `None`, as made, draws every pixel the impostor finds.
    pub fn cross_fade(&mut self, fade: Option<CrossFade>) {
        for atlas in &mut self.atlases {
            atlas.impostor.fade = fade.map_or([0.0; 2], |f| [f.start, f.end]);
            (self.gpu.queue).write_buffer(&atlas.uniform, 0, bytemuck::bytes_of(&atlas.impostor));
        }
    }

    /// Draws every copy through `similarity` from now on (the scene's placement first).
    pub fn place(&mut self, similarity: Similarity) {
        let moved: Vec<GpuInstance> = (self.placed.iter())
            .map(|i| GpuInstance {
                offset: similarity.apply(Vec3::from_array(i.offset)).to_array(),
                rotation: similarity.rotation.normalize().to_array(),
                scale: similarity.scale,
                ..*i
            })
            .collect();
        self.instances = self
            .gpu
            .vertices_with("instances", bytemuck::cast_slice(&moved));
    }

    /// The depth buffer of the impostors drawn through `camera` by `entry` (reversed: 1 on the
    /// near plane, 0 where no surface was kept).
    pub fn depth(&self, camera: &Pinhole, entry: Entry) -> Result<Image<f32>, GpuError> {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let (encoder, views) = self.draw(camera, entry)?;
        let bytes = self
            .gpu
            .read_texture_bytes(encoder, &views.depth, ((w, h), 4), "the depth")?;
        Ok(Image::from_vec(w, h, bytemuck::pod_collect_to_vec(&bytes))?)
    }

    /// Encodes the impostors drawn through `camera` by `entry` into a fresh G-buffer.
    fn draw(
        &self,
        camera: &Pinhole,
        entry: Entry,
    ) -> Result<(wgpu::CommandEncoder, GBuffer), GpuError> {
        let gpu = self.gpu;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        gpu.check_texture("the frame", w, h)?;
        gpu.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(&clip_camera(camera)));
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let g = GBuffer {
            color: gpu.texture("base colour", (w, h), COLOR, usage),
            normal: gpu.texture("normal", (w, h), COLOR, usage),
            object: gpu.texture("object", (w, h), OBJECT, usage),
            depth: gpu.texture("depth", (w, h), DEPTH, usage),
        };
        let views =
            [&g.color, &g.normal, &g.object, &g.depth].map(|t| t.create_view(&Default::default()));
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
            let targets = [
                target(&views[0], 0.0),
                target(&views[1], 0.0),
                target(&views[2], f64::from(NO_OBJECT)),
            ];
            let (pipeline, targets) = match entry {
                Entry::GBuffer => (&self.pipeline, &targets[..]),
                Entry::DepthOnly => (&self.depth_pipeline, &[][..]),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("octahedral impostors"),
                color_attachments: targets,
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
            pass.set_pipeline(pipeline);
            pass.set_vertex_buffer(0, self.corners.slice(..));
            pass.set_vertex_buffer(1, self.instances.slice(..));
            for atlas in &self.atlases {
                pass.set_bind_group(0, &atlas.group, &[]);
                pass.draw(atlas.card.clone(), atlas.instances.clone());
            }
        }
        Ok((encoder, g))
    }

    /// The frame through `camera`: colour and object id, as the CPU twin fills them.
    pub fn frame(&self, camera: &Pinhole) -> Result<Frame, GpuError> {
        let gpu = self.gpu;
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let out_bytes = u64::from(w) * u64::from(h) * 16;
        gpu.check_storage("the frame", out_bytes)?;
        let (mut encoder, g) = self.draw(camera, Entry::GBuffer)?;
        let views = [&g.color, &g.normal, &g.object].map(|t| t.create_view(&Default::default()));
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

/// The bindings of the impostor shader's group 0, shared by both entries' pipelines: the
/// camera and impostor uniforms, the colour and normal-depth atlases, the sampler.
fn atlas_group_layout(gpu: &Gpu) -> wgpu::BindGroupLayout {
    use wgpu::ShaderStages as S;
    let uniform = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: S::VERTEX | S::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: S::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("octahedral atlas"),
            entries: &[
                uniform(0),
                uniform(1),
                texture(2),
                texture(3),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: S::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        })
}

/// The textures one draw fills.
struct GBuffer {
    color: wgpu::Texture,
    normal: wgpu::Texture,
    object: wgpu::Texture,
    depth: wgpu::Texture,
}

/// The engine shader's pipeline: instanced cards, three targets (none for the depth-only
/// entry), reversed depth (the nearest kept, ties to the earlier draw).
fn impostor_pipeline(gpu: &Gpu, entry: Entry) -> wgpu::RenderPipeline {
    let (name, entry_point) = match entry {
        Entry::GBuffer => ("octahedral impostors", "fs_main"),
        Entry::DepthOnly => ("octahedral impostors, depth only", "fs_depth"),
    };
    gpu.render_pipeline(name, || {
        let module = gpu.module("octahedral_impostor.wgsl", IMPOSTOR_SHADER);
        let corner = wgpu::vertex_attr_array![0 => Float32x2];
        let instance = wgpu::vertex_attr_array![
            1 => Float32x3, 2 => Uint32, 3 => Float32x4, 4 => Float32
        ];
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let g_buffer = [target(COLOR), target(COLOR), target(OBJECT)];
        let group = atlas_group_layout(gpu);
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(name),
                bind_group_layouts: &[Some(&group)],
                immediate_size: 0,
            });
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
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
                    entry_point: Some(entry_point),
                    compilation_options: Default::default(),
                    targets: match entry {
                        Entry::GBuffer => &g_buffer,
                        Entry::DepthOnly => &[],
                    },
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
    atlas: &OctahedralAtlas,
    (camera, sampler): (&wgpu::Buffer, &wgpu::Sampler),
) -> Result<UploadedAtlas, GpuError> {
    let side = atlas.side();
    gpu.check_texture("an octahedral atlas", side, side)?;
    let to_half = half::f16::from_f32;
    let color: Vec<half::f16> = atlas
        .color
        .pixels()
        .iter()
        .flat_map(|c| c.to_array().map(to_half))
        .collect();
    // The normal and depth packed as the .glb packs them (rgb = n·½ + ½, a = depth), in half
    // floats rather than 8 bits.
    let normal_depth: Vec<half::f16> = (atlas.normal.pixels().iter())
        .zip(atlas.depth.pixels())
        .flat_map(|(&n, &d)| {
            trompe::octahedral::packing::pack_texel(n, d)
                .to_array()
                .map(to_half)
        })
        .collect();
    let maps = [
        ("atlas colour", bytemuck::cast_slice::<_, u8>(&color)),
        (
            "atlas normal and depth",
            bytemuck::cast_slice(&normal_depth),
        ),
    ]
    .map(|(label, bytes)| {
        let texture = gpu.texture(
            label,
            (side, side),
            COLOR,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        gpu.queue.write_texture(
            texture.as_image_copy(),
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side * 8),
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
        fade: [0.0; 2],
        pad: [0.0; 2],
    };
    let impostor = uniform;
    let uniform = gpu.uniform_with("impostor", bytemuck::bytes_of(&uniform));
    let texture = |binding, view| wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    };
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("octahedral atlas"),
        layout: &atlas_group_layout(gpu),
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
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
        ],
    });
    Ok(UploadedAtlas {
        group,
        uniform,
        impostor,
        card: 0..0,
        instances: 0..0,
    })
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
