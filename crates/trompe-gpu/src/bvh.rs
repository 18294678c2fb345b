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
pub(crate) struct GpuRay {
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

/// The classes every triangle is in: what [`upload`] gives a triangle unless told otherwise,
/// and what the shader's `query` accepts.
pub(crate) const EVERY_TRIANGLE: u32 = 1;

/// The most objects the shader tells apart (`shaders/bvh.wgsl`'s `query_selected`: an object's
/// id rides as an `f32`, exact below 2²⁴).
pub(crate) const MAX_OBJECTS: u32 = 1 << 24;

/// The node and triangle-corner buffers of `bvh`, bindings 0 and 1 of every shader that
/// includes `shaders/bvh.wgsl`; each triangle in the classes `classes(object)` says (bits the
/// shader's `query_classes` selects by; each holds [`EVERY_TRIANGLE`]), and its object.
pub(crate) fn upload(
    gpu: &Gpu,
    bvh: &Bvh,
    classes: &dyn Fn(u32) -> u32,
) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
    let node_bytes: &[u8] = bytemuck::cast_slice(bvh.wide_nodes());
    let corners: Vec<[f32; 4]> = bvh
        .leaf_corners()
        .iter()
        .zip(bvh.leaf_sources())
        .flat_map(|(t, &(object, _))| {
            // Kept in the mantissa of a normal number (1.0 and up), so no device flushes it.
            let bits =
                f32::from_bits(0x3f80_0000 | ((classes(object) | EVERY_TRIANGLE) & 0x7f_ffff));
            [
                t[0].extend(bits),
                t[1].extend(object as f32),
                t[2].extend(0.0),
            ]
            .map(|c| c.to_array())
        })
        .collect();
    if let Some(&(object, _)) = bvh.leaf_sources().iter().find(|s| s.0 >= MAX_OBJECTS) {
        return Err(GpuError::Unsupported {
            what: format!("object {object} (the GPU tells {MAX_OBJECTS} objects apart)"),
        });
    }
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
        let (nodes, corners) = upload(gpu, bvh, &|_| EVERY_TRIANGLE)?;
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
        ray_pass(
            self.gpu,
            &self.pipeline,
            &[(0, &self.nodes), (1, &self.corners)],
            rays,
            t_max,
            u32::from(any_hit),
        )
    }
}

/// Runs `pipeline` (an entry point of a shader that includes `shaders/bvh.wgsl`) over `rays`,
/// one invocation a ray: the rays at binding 2, the answers at 3, the parameters at 4 — their
/// word `any_hit` set to `word` — and `scene`'s buffers at their bindings. The answers as the
/// shader wrote them.
pub(crate) fn ray_pass(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    scene: &[(u32, &wgpu::Buffer)],
    rays: &[Ray],
    t_max: f32,
    word: u32,
) -> Result<Vec<LeafHit>, GpuError> {
    if rays.is_empty() {
        return Ok(Vec::new());
    }
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
        any_hit: word,
        _pad: 0,
        row: row_groups * GROUP,
    };
    let ray_buffer = gpu.storage_with("rays", ray_bytes);
    let hits = gpu.buffer(
        "hits",
        hit_bytes,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let uniform = gpu.uniform_with("ray params", bytemuck::bytes_of(&params));
    let entries: Vec<wgpu::BindGroupEntry> = scene
        .iter()
        .copied()
        .chain([(2, &ray_buffer), (3, &hits), (4, &uniform)])
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("ray pass"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(row_groups, groups.div_ceil(row_groups), 1);
    }
    let bytes = gpu.read_back(encoder, &[hits], "the hits")?;
    Ok(bytemuck::pod_collect_to_vec(
        &bytes[0][..hit_bytes as usize],
    ))
}
