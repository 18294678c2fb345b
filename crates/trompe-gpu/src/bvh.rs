//! The exact ray query on the GPU: the library's BVH ([`trompe::trace::Bvh`], obvhs's
//! compressed wide nodes built on the CPU) uploaded as it is and walked by
//! `shaders/bvh.wgsl`, one invocation a ray.
//!
//! It answers the same questions as the CPU [`trompe::trace::RayQuery`] — the closest hit and
//! whether anything is hit — with the same traversal order and the same watertight triangle
//! test, so a hit names the same triangle; the surface point is then made on the CPU by the
//! library's own [`Bvh::hit_on_leaf`]. Invariant: the node, corner and source buffers are the
//! BVH's own, in its leaf order.

use crate::device::{Gpu, GpuError};
use bytemuck::{Pod, Zeroable};
use trompe::geom::Ray;
use trompe::trace::{Bvh, Hit};

/// The walker's source.
pub const SHADER: &str = include_str!("../shaders/bvh.wgsl");

/// Rays a workgroup answers (the shader's `@workgroup_size`).
const GROUP: u32 = 64;

/// A ray as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuRay {
    origin: [f32; 3],
    t_max: f32,
    dir: [f32; 3],
    _pad: f32,
}

/// A hit as the shader writes it: `triangle` is the leaf-ordered index, or [`MISS`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct LeafHit {
    /// Distance along the ray.
    pub t: f32,
    /// The leaf-ordered triangle, or [`MISS`].
    pub triangle: u32,
    /// Barycentric weight of corner 1.
    pub b1: f32,
    /// Barycentric weight of corner 2.
    pub b2: f32,
}

/// [`LeafHit::triangle`] of a ray that hit nothing.
pub const MISS: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    rays: u32,
    any_hit: u32,
    _pad: u32,
    row: u32,
}

/// The node and triangle-corner buffers of `bvh`, bindings 0 and 1 of every shader that
/// includes `shaders/bvh.wgsl`.
pub(crate) fn upload(gpu: &Gpu, bvh: &Bvh) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
    let node_bytes: &[u8] = bytemuck::cast_slice(bvh.wide_nodes());
    let corners: Vec<[f32; 4]> = bvh
        .leaf_corners()
        .iter()
        .flat_map(|t| t.map(|c| c.extend(0.0).to_array()))
        .collect();
    let corner_bytes: &[u8] = bytemuck::cast_slice(&corners);
    gpu.check_storage("the BVH's nodes", node_bytes.len() as u64)?;
    gpu.check_storage("the BVH's triangles", corner_bytes.len() as u64)?;
    Ok((
        gpu.storage_with("bvh nodes", node_bytes),
        gpu.storage_with("bvh corners", corner_bytes),
    ))
}

/// A BVH on the device, ready for ray queries.
pub struct GpuBvh<'a> {
    gpu: &'a Gpu,
    bvh: &'a Bvh,
    nodes: wgpu::Buffer,
    corners: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
}

impl<'a> GpuBvh<'a> {
    /// Uploads `bvh` to `gpu`.
    pub fn upload(gpu: &'a Gpu, bvh: &'a Bvh) -> Result<GpuBvh<'a>, GpuError> {
        let (nodes, corners) = upload(gpu, bvh)?;
        let pipeline = gpu.compute_pipeline("bvh.wgsl", SHADER, "trace_rays");
        Ok(GpuBvh {
            gpu,
            bvh,
            nodes,
            corners,
            pipeline,
        })
    }

    /// The closest hit of every ray below `t_max`, as the library's hits.
    pub fn closest_hits(&self, rays: &[Ray], t_max: f32) -> Result<Vec<Option<Hit>>, GpuError> {
        let leaf = self.leaf_hits(rays, t_max, false)?;
        Ok(rays
            .iter()
            .zip(&leaf)
            .map(|(ray, h)| {
                (h.triangle != MISS)
                    .then(|| {
                        self.bvh
                            .hit_on_leaf(h.triangle, ray, h.t, glam::Vec2::new(h.b1, h.b2))
                    })
                    .flatten()
            })
            .collect())
    }

    /// Whether each ray hits anything below `t_max` (shadow rays).
    pub fn any_hits(&self, rays: &[Ray], t_max: f32) -> Result<Vec<bool>, GpuError> {
        Ok(self
            .leaf_hits(rays, t_max, true)?
            .iter()
            .map(|h| h.triangle != MISS)
            .collect())
    }

    /// The shader's answers as it wrote them: per ray, the leaf-ordered triangle and where.
    pub fn leaf_hits(
        &self,
        rays: &[Ray],
        t_max: f32,
        any_hit: bool,
    ) -> Result<Vec<LeafHit>, GpuError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let gpu = self.gpu;
        let packed: Vec<GpuRay> = rays
            .iter()
            .map(|r| GpuRay {
                origin: r.origin.to_array(),
                t_max,
                dir: r.dir.to_array(),
                _pad: 0.0,
            })
            .collect();
        let ray_bytes: &[u8] = bytemuck::cast_slice(&packed);
        let hit_bytes = (rays.len() * std::mem::size_of::<LeafHit>()) as u64;
        gpu.check_storage("the rays", ray_bytes.len() as u64)?;
        gpu.check_storage("the hits", hit_bytes)?;
        let groups = (rays.len() as u32).div_ceil(GROUP);
        let row_groups = groups.min(gpu.max_groups());
        let params = Params {
            rays: rays.len() as u32,
            any_hit: u32::from(any_hit),
            _pad: 0,
            row: row_groups * GROUP,
        };
        let ray_buffer = gpu.storage_with("rays", ray_bytes);
        let hits = gpu.buffer(
            "hits",
            hit_bytes,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let uniform = gpu.uniform_with("bvh params", bytemuck::bytes_of(&params));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bvh query"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                (0, &self.nodes),
                (1, &self.corners),
                (2, &ray_buffer),
                (3, &hits),
                (4, &uniform),
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
            pass.dispatch_workgroups(row_groups, groups.div_ceil(row_groups), 1);
        }
        let bytes = gpu.read_back(encoder, &[hits], "the hits")?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[0][..hit_bytes as usize],
        ))
    }
}
