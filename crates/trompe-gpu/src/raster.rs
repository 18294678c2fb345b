//! The visibility pass (paper 1 §6 rasterizes the primary pass; §3.1 builds impostors by
//! rasterization): triangles drawn by the GPU rasterizer (`shaders/raster.wgsl`) through a
//! pinhole, an orthographic camera, a SPOC or a graph camera's frusta into a visibility image —
//! per texel the triangle + 1, the perspective-correct barycentrics of its corners 1 and 2 and
//! the depth drawn — optionally under a depth-peeling ceiling. The tracer reads it as its
//! primary hits (the raster method), Wyman's first pass draws back faces with it, and
//! `build.rs` draws impostors with it.
//!
//! Invariant: reversed depth (1 on the near plane, 0 at infinity), the nearest kept, ties to the
//! earlier draw; a texel 0 holds nothing.

use crate::device::Gpu;
use crate::device::GpuError;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use trompe::camera::Pinhole;
use trompe::trace::Bvh;

/// The visibility pass's source.
pub const RASTER_SHADER: &str = include_str!("../shaders/raster.wgsl");

/// `v` with `w` as a shader's `vec4`.
pub(crate) fn v4(v: Vec3, w: f32) -> [f32; 4] {
    v.extend(w).to_array()
}

/// A corner as the rasterizer reads it.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuCorner {
    position: [f32; 3],
    corner: u32,
    leaf: u32,
}

/// The rasterizer's camera (`shaders/raster.wgsl`'s `Camera`). A pinhole: the rows of `M⁻¹`,
/// the eye with the near plane's `t`, the size. An orthographic camera: the affine rows of its
/// image coordinates and its `gd`, the size, and kind 1.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuRasterCamera {
    row_u: [f32; 4],
    row_v: [f32; 4],
    row_t: [f32; 4],
    eye: [f32; 4],
    size: [f32; 4],
    spoc: [f32; 4],
}

impl GpuRasterCamera {
    /// Its three rows (a pinhole's: `M⁻¹`, applied to a point less the eye).
    pub(crate) fn rows(&self) -> [[f32; 4]; 3] {
        [self.row_u, self.row_v, self.row_t]
    }

    /// Through a pinhole.
    pub(crate) fn pinhole(camera: &Pinhole) -> Self {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let inverse = camera.mcmillan_inverse();
        let row = |i: usize| {
            let r = inverse.row(i).as_vec3();
            [r.x, r.y, r.z, 0.0]
        };
        let t_near = (camera.near() / camera.focal()) as f32;
        GpuRasterCamera {
            row_u: row(0),
            row_v: row(1),
            row_t: row(2),
            eye: v4(camera.position().as_vec3(), t_near),
            size: [w as f32, h as f32, 0.0, 0.0],
            spoc: [0.0; 4],
        }
    }

    /// Through a SPOC: its pinhole's, each corner then pushed from the pole.
    pub(crate) fn spoc(camera: &trompe::camera::Spoc) -> Self {
        let pinhole = camera.pinhole();
        let (z_near, z_far) = camera.depth_range();
        let pole = camera.pole();
        let mut raster = Self::pinhole(pinhole);
        raster.size[2] = 2.0;
        raster.size[3] = pinhole.focal() as f32;
        raster.spoc = [
            pole.x as f32,
            pole.y as f32,
            z_near as f32,
            (camera.strength() / (z_far - z_near)) as f32,
        ];
        raster
    }

    /// Through frustum `j` of a graph camera (§4.5): its matrix takes `(p, 1)` to
    /// `(u·w, v·w, 1, w)` with `gd = 1/w`, the pinhole's form about its apex; depth is
    /// `near · gd`, so every frustum's depths compare as the library compares their `gd`
    /// (`near` at most the smallest `w` drawn, so no depth passes 1).
    pub(crate) fn frustum(g: &trompe::camera::GraphCamera, j: usize, near: f64) -> Self {
        let (w, h) = g.resolution();
        let f = &g.frusta()[j];
        // Rows 0, 1 and 3 (x, y and w) about the apex, where all three vanish.
        let row = |i: usize| {
            let r = f.matrix.row(i);
            let at_apex = r.truncate().dot(f.apex) + r.w;
            [r.x as f32, r.y as f32, r.z as f32, at_apex as f32]
        };
        GpuRasterCamera {
            row_u: row(0),
            row_v: row(1),
            row_t: row(3),
            eye: v4(f.apex.as_vec3(), near as f32),
            size: [w as f32, h as f32, 0.0, 0.0],
            spoc: [0.0; 4],
        }
    }

    /// Through an orthographic camera: `u = (p − corner)·a/|a|²`, `v` likewise, and
    /// `gd = 1 − (p − corner)·dir/depth`, each a row times `(p, 1)`.
    pub(crate) fn orthographic(camera: &trompe::camera::Orthographic) -> Self {
        let (w, h) = trompe::camera::Projection::resolution(camera);
        let (corner, a, b, dir, depth) = camera.parameters();
        let row = |r: glam::DVec3, offset: f64| {
            let v = r.extend(offset - r.dot(corner)).as_vec4();
            v.to_array()
        };
        GpuRasterCamera {
            row_u: row(a / a.length_squared(), 0.0),
            row_v: row(b / b.length_squared(), 0.0),
            row_t: row(-dir / depth, 1.0),
            eye: [0.0; 4],
            size: [w as f32, h as f32, 1.0, 0.0],
            spoc: [0.0; 4],
        }
    }
}

/// The visibility buffer's texel format: leaf + 1, b1 bits, b2 bits.
const VISIBILITY: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
pub(crate) const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The depth test of every GPU draw: reversed depth ([`DEPTH`], 1 on the near plane), the
/// nearest kept, ties to the earlier draw.
pub(crate) fn nearest_kept() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// Draws `raster`'s triangles through `camera` into `visibility` (`w × h`, cleared first),
/// recorded in `encoder`.
pub(crate) fn draw_into_visibility(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    (pipeline, vertices, vertex_count): &(wgpu::RenderPipeline, wgpu::Buffer, u32),
    camera: &GpuRasterCamera,
    visibility: &wgpu::Texture,
    size: (u32, u32),
) {
    let draws = [(*camera, 0..*vertex_count)];
    draw_ranges_into_visibility(
        gpu,
        encoder,
        (pipeline, vertices),
        (&draws, None),
        visibility,
        size,
    );
}

/// One draw of the visibility pass: a range of the corners drawn through a camera.
pub(crate) type RasterDraw = (GpuRasterCamera, std::ops::Range<u32>);

/// [`draw_into_visibility`] of several ranges of the vertices, each through its own camera, in
/// order, over one image and one depth buffer: a graph camera's frusta, each drawing the
/// triangles clipped to it (paper 1 §4.5). A fragment replaces a texel only when strictly
/// nearer, so ties keep the earlier draw. With a `ceiling` (group 1 of a pipeline drawing
/// behind one, [`visibility_pipeline`]), only fragments strictly behind it are drawn.
pub(crate) fn draw_ranges_into_visibility(
    gpu: &Gpu,
    encoder: &mut wgpu::CommandEncoder,
    (pipeline, vertices): (&wgpu::RenderPipeline, &wgpu::Buffer),
    (draws, ceiling): (&[RasterDraw], Option<&wgpu::BindGroup>),
    visibility: &wgpu::Texture,
    (w, h): (u32, u32),
) {
    let groups: Vec<wgpu::BindGroup> = draws
        .iter()
        .map(|(camera, _)| {
            let uniform = gpu.uniform_with("raster camera", bytemuck::bytes_of(camera));
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("raster"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                }],
            })
        })
        .collect();
    let depth = gpu.texture(
        "raster depth",
        (w, h),
        DEPTH,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let (color_view, depth_view) = (
        visibility.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("visibility"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &color_view,
            resolve_target: None,
            depth_slice: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations {
                // Reversed depth: 0 is infinitely far.
                load: wgpu::LoadOp::Clear(0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        ..Default::default()
    });
    pass.set_pipeline(pipeline);
    pass.set_vertex_buffer(0, vertices.slice(..));
    if let Some(ceiling) = ceiling {
        pass.set_bind_group(1, ceiling, &[]);
    }
    for ((_, range), group) in draws.iter().zip(&groups) {
        pass.set_bind_group(0, group, &[]);
        pass.draw(range.clone(), 0..1);
    }
}

/// A `w × h` visibility texture, drawn into and read by the shading pass (or read back).
pub(crate) fn visibility_texture(gpu: &Gpu, w: u32, h: u32) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
        | wgpu::TextureUsages::TEXTURE_BINDING
        | wgpu::TextureUsages::COPY_SRC;
    gpu.texture("visibility", (w, h), VISIBILITY, usage)
}

/// The primary pass's pipeline and vertices: every leaf-ordered triangle's three corners.
pub(crate) fn raster_pipeline(
    gpu: &Gpu,
    bvh: &Bvh,
) -> Result<(wgpu::RenderPipeline, wgpu::Buffer, u32), GpuError> {
    raster_pipeline_of(gpu, bvh.leaf_corners())
}

/// The visibility pass's pipeline and vertices: the three corners of every triangle of
/// `triangles`, each drawn with its index.
pub(crate) fn raster_pipeline_of(
    gpu: &Gpu,
    triangles: &[[Vec3; 3]],
) -> Result<(wgpu::RenderPipeline, wgpu::Buffer, u32), GpuError> {
    let numbered: Vec<(u32, [Vec3; 3])> = triangles
        .iter()
        .enumerate()
        .map(|(leaf, &c)| (leaf as u32, c))
        .collect();
    let (vertices, count) = corner_buffer(gpu, &numbered)?;
    Ok((visibility_pipeline(gpu, false), vertices, count))
}

/// The visibility pass's vertices: the three corners of each triangle, each with its corner
/// number and the triangle's number given beside it; and how many corners.
pub(crate) fn corner_buffer(
    gpu: &Gpu,
    triangles: &[(u32, [Vec3; 3])],
) -> Result<(wgpu::Buffer, u32), GpuError> {
    let mut corners: Vec<GpuCorner> = triangles
        .iter()
        .flat_map(|&(leaf, c)| {
            (0..3u32).map(move |k| GpuCorner {
                position: c[k as usize].to_array(),
                corner: k,
                leaf,
            })
        })
        .collect();
    let count = corners.len() as u32;
    // A buffer is never empty; nothing past `count` is drawn.
    if corners.is_empty() {
        corners.push(GpuCorner::zeroed());
    }
    let bytes: &[u8] = bytemuck::cast_slice(&corners);
    gpu.check_storage("the triangles' corners", bytes.len() as u64)?;
    Ok((gpu.vertices_with("corners", bytes), count))
}

/// The visibility pass's pipeline; `behind`: under a depth-peeling ceiling bound as group 1
/// (`raster.wgsl`'s `visible_behind`).
pub(crate) fn visibility_pipeline(gpu: &Gpu, behind: bool) -> wgpu::RenderPipeline {
    let (name, fragment) = match behind {
        false => ("visibility", "visible"),
        true => ("visibility behind a ceiling", "visible_behind"),
    };
    gpu.render_pipeline(name, || {
        let module = gpu.module("raster.wgsl", RASTER_SHADER);
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32x2];
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("visibility"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("draw_corner"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<GpuCorner>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &attributes,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(nearest_kept()),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: VISIBILITY,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    })
}
