//! The continuous 3-ray camera's projection on the GPU (paper 2, "Hybrid backward-forward
//! reflection rendering with continuous 3-ray cameras" §3–5; the library's `trompe::camera::C3rc`
//! is its CPU twin): `shaders/c3rc.wgsl` with its arithmetic type chosen for the device — f64
//! where the adapter has 64-bit floats, as the library computes, f32 otherwise — the cameras as
//! the shader reads them, and the projection alone, for checking it against the library's roots.
//!
//! Invariant: a camera reaches the shader as f64 values split into two f32 (`hi + lo`), so the
//! f64 shader starts from the library's own numbers.

use crate::device::{Gpu, GpuError};
use crate::raster::v4;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use trompe::camera::C3rc;

/// `shaders/c3rc.wgsl` after the definitions of its `real` and tolerances: f64 and the CPU's
/// where the device has 64-bit floats, f32 and tolerances f32 can hold otherwise.
pub fn c3rc_source(f64: bool) -> String {
    let prelude = match f64 {
        true => {
            "alias real = f64;\nconst C3RC_TINY: real = 1e-12;\nconst C3RC_MERGE: real = 1e-12;\n\
             const C3RC_SNAP: real = 1e-12;\n"
        }
        false => {
            "alias real = f32;\nconst C3RC_TINY: real = 1e-7;\nconst C3RC_MERGE: real = 1e-6;\n\
             const C3RC_SNAP: real = 1e-6;\n"
        }
    };
    format!("{prelude}{}", include_str!("../shaders/c3rc.wgsl"))
}

/// A continuous 3-ray camera as the shader reads it (`c3rc.wgsl`'s `C3rc`): each f64 value as
/// the f32 sum `hi + lo`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuC3rc {
    v: [[f32; 4]; 3],
    d: [[f32; 4]; 3],
    n: [[f32; 4]; 3],
    v_lo: [[f32; 4]; 3],
    d_lo: [[f32; 4]; 3],
    n_lo: [[f32; 4]; 3],
}

impl GpuC3rc {
    /// `c` with its sweep normal's terms computed in f64; `lambda_max` (∞ as the shader's
    /// `FAR`) and the reflector `object` ride in the spare lanes.
    pub(crate) fn new(c: &C3rc, lambda_max: f64, object: u32) -> GpuC3rc {
        let (e2, e3) = (c.v[1] - c.v[0], c.v[2] - c.v[0]);
        let (g2, g3) = (c.d[1] - c.d[0], c.d[2] - c.d[0]);
        let n = [e2.cross(e3), e2.cross(g3) + g2.cross(e3), g2.cross(g3)];
        let lane = |p: DVec3, w: f32| v4(p.as_vec3(), w);
        let low = |p: DVec3| v4((p - p.as_vec3().as_dvec3()).as_vec3(), 0.0);
        let lambda_max = if lambda_max.is_finite() {
            lambda_max as f32
        } else {
            f32::MAX
        };
        GpuC3rc {
            v: [
                lane(c.v[0], lambda_max),
                lane(c.v[1], f32::from_bits(object)),
                lane(c.v[2], 0.0),
            ],
            d: c.d.map(|d| lane(d, 0.0)),
            n: n.map(|n| lane(n, 0.0)),
            v_lo: c.v.map(low),
            d_lo: c.d.map(low),
            n_lo: n.map(low),
        }
    }
}

/// Every projection of each `(camera, point, λ max)` through its camera, computed by the
/// GPU's projection (`shaders/c3rc.wgsl`) as `(λ, barycentrics)`, nearest sweep first: the
/// projection alone, for checking it against the library's [`C3rc::project`].
pub fn project_pairs(
    gpu: &Gpu,
    pairs: &[(C3rc, DVec3, f64)],
) -> Result<Vec<Vec<(f64, DVec3)>>, GpuError> {
    #[repr(C)]
    #[derive(Clone, Copy, Pod, Zeroable)]
    struct Pair {
        camera: GpuC3rc,
        point: [f32; 4],
    }
    let uploaded: Vec<Pair> = pairs
        .iter()
        .map(|(c, q, lambda_max)| {
            let lambda_max = if lambda_max.is_finite() {
                *lambda_max as f32
            } else {
                f32::MAX
            };
            Pair {
                camera: GpuC3rc::new(c, f64::INFINITY, 0),
                point: v4(q.as_vec3(), lambda_max),
            }
        })
        .collect();
    let bytes: &[u8] = bytemuck::cast_slice(&uploaded);
    gpu.check_storage("the projection pairs", bytes.len() as u64)?;
    gpu.check_storage("their projections", pairs.len() as u64 * 64)?;
    let input = gpu.storage_with("projection pairs", bytes);
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let output = gpu.buffer("projections", pairs.len() as u64 * 64, usage);
    let source = [
        c3rc_source(gpu.has_f64()),
        include_str!("../shaders/c3rc_project.wgsl").into(),
    ]
    .join("\n");
    let pipeline = gpu.compute_pipeline("c3rc_project.wgsl", &source, "project_pairs");
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("project pairs"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        let groups = (pairs.len() as u32).div_ceil(64);
        pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
    }
    let read = gpu.read_back(encoder, &[output], "the projections")?;
    let texels: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read[0]);
    Ok(texels
        .chunks_exact(4)
        .take(pairs.len())
        .map(|t| {
            let len = (t[0][0] as usize).min(3);
            t[1..=len]
                .iter()
                .map(|p| (f64::from(p[0]), Vec3::new(p[1], p[2], p[3]).as_dvec3()))
                .collect()
        })
        .collect())
}
