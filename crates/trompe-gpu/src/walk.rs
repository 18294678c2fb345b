//! Paper 1's walk on the GPU (§3.2; `shaders/walk.wgsl`): impostors built by the library,
//! uploaded as the walk reads them — per texel its plane record ([`trompe::impostor::TexelPlane`])
//! and what a hit shows (shading normal, object, colour), per impostor its camera as rows, its
//! box, its layers and its pyramid of front bounds — and walked one invocation a ray.
//!
//! The shader is the library's texel walk (`src/impostor/texels.rs`) in `f32`: the same samples,
//! the same acceptance rules, every layer, nearest wins, pyramid nodes stepped over; for every
//! impostor camera — pinhole (a cube map is six), orthographic, SPOC (its curved path cut where
//! its coordinates turn) and graph camera (the ray cut at its frusta's faces, none stepped
//! over). A graph camera of more than [`MAX_FRUSTA`] frusta is refused with
//! [`GpuError::Unsupported`].
//!
//! Invariant: record `r` of the texel buffers is texel `(r − first) mod width, (r − first) /
//! width` of the layer whose first record is `first`; a set's buffers are what the shader's
//! bindings 13–17 and 19 read.

use crate::bvh::{LeafHit, MISS, ray_pass};
use crate::device::{Gpu, GpuError};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4};
use trompe::geom::Ray;
use trompe::impostor::{Impostor, ImpostorCamera};

/// The walk's source: compiled after `shaders/bvh.wgsl` (its ray and hit bindings) and
/// `shaders/path.wgsl` (the rays' image paths).
pub fn shader_source() -> String {
    [
        crate::bvh::SHADER,
        include_str!("../shaders/path.wgsl"),
        include_str!("../shaders/walk.wgsl"),
    ]
    .join("\n")
}

/// The shader's camera kinds.
const PINHOLE: u32 = 0;
const ORTHOGRAPHIC: u32 = 1;
const SPOC: u32 = 2;
const GRAPH: u32 = 3;
/// A frustum's record in the shader: a header, its matrix, its inverse, its planes.
const FRUSTUM_STRIDE: usize = 17;
const FRUSTUM_PLANES: usize = 8;
/// The most frusta a graph camera the shader walks may have (its `MAX_FRUSTA`).
pub const MAX_FRUSTA: usize = 64;
/// The shader's flags.
const RADIANCE: u32 = 1;
const MOVED: u32 = 2;

/// An impostor as the shader reads it (`WalkImpostor`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuImpostor {
    u_row: [f32; 4],
    v_row: [f32; 4],
    w_row: [f32; 4],
    g_row: [f32; 4],
    clip_row: [f32; 4],
    eye: [f32; 4],
    m_a: [f32; 4],
    m_b: [f32; 4],
    m_c: [f32; 4],
    box_min: [f32; 4],
    box_max: [f32; 4],
    size: [u32; 4],
    info: [u32; 4],
    graph: [u32; 4],
    built_from_now: [[f32; 4]; 3],
    now_from_built: [[f32; 4]; 3],
}

/// Impostors gathered for the GPU walk, in the order they were added.
#[derive(Default)]
pub struct WalkSet {
    impostors: Vec<GpuImpostor>,
    /// Per layer, its first texel record.
    layers: Vec<u32>,
    planes: Vec<[f32; 4]>,
    looks: Vec<[f32; 4]>,
    pyramid: Vec<f32>,
    /// Every graph camera's frusta, [`FRUSTUM_STRIDE`] rows each.
    frusta: Vec<[f32; 4]>,
}

/// The shader's camera record: its kind, the rows, and McMillan's vectors (a SPOC's).
struct CameraRecord {
    kind: u32,
    rows: [[f32; 4]; 5],
    eye: [f32; 4],
    mcmillan: [[f32; 4]; 3],
    graph: [u32; 4],
}

/// A row `(r, −r·origin)`: `r·(p − origin)` as a dot product with `(p, 1)`.
fn row(r: DVec3, origin: DVec3) -> [f32; 4] {
    r.extend(-r.dot(origin)).as_vec4().to_array()
}

/// The rows of `m` (affine) the shader multiplies `(p, 1)` by.
fn rows(m: Mat4) -> [[f32; 4]; 3] {
    [0, 1, 2].map(|i| m.row(i).to_array())
}

impl WalkSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// How many impostors it holds.
    pub fn len(&self) -> usize {
        self.impostors.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.impostors.is_empty()
    }

    /// Adds `impostor` (every layer), carried by `now_from_built` (rigid) from where it was
    /// built, its hits carrying its colour when `radiance`; its index in the set.
    pub fn push(
        &mut self,
        impostor: &Impostor,
        now_from_built: Mat4,
        radiance: bool,
    ) -> Result<u32, GpuError> {
        let (w, h) = impostor.gd().size();
        let camera = self.camera_record(impostor.camera())?;
        let index = self.impostors.len() as u32;
        let first_layer = self.layers.len() as u32;
        for layer in impostor.layers() {
            let first = self.planes.len() / 2;
            self.layers.push(first as u32);
            let planes = layer.texel_planes();
            let (object, shading) = (layer.object(), layer.normal());
            debug_assert_eq!(planes.size(), (w, h));
            debug_assert_eq!(shading.size(), (w, h));
            for y in 0..h {
                for x in 0..w {
                    let t = planes.get(x, y);
                    self.planes.push(t.point.extend(t.gd).to_array());
                    self.planes.push(t.normal.extend(t.front).to_array());
                    if t.gd > 0.0 {
                        let id = f32::from_bits(object.get(x, y));
                        self.looks.push(layer.normal_at(x, y).extend(id).to_array());
                        self.looks
                            .push(layer.color_at(x, y).truncate().extend(0.0).to_array());
                    } else {
                        self.looks.extend([[0.0; 4]; 2]);
                    }
                }
            }
        }
        let pyramid = impostor.pyramid();
        let first_node = self.pyramid.len() as u32;
        for l in 1..pyramid.level_count() {
            self.pyramid.extend_from_slice(pyramid.level(l).pixels());
        }
        let bounds = impostor.bounds();
        let moved = now_from_built != Mat4::IDENTITY;
        let flags = (u32::from(radiance) * RADIANCE) | (u32::from(moved) * MOVED);
        let [u_row, v_row, w_row, g_row, clip_row] = camera.rows;
        let [m_a, m_b, m_c] = camera.mcmillan;
        self.impostors.push(GpuImpostor {
            u_row,
            v_row,
            w_row,
            g_row,
            clip_row,
            eye: camera.eye,
            m_a,
            m_b,
            m_c,
            box_min: bounds.min.extend(impostor.exit_margin()).to_array(),
            box_max: bounds.max.extend(0.0).to_array(),
            size: [w, h, first_layer, impostor.layer_count() as u32],
            info: [pyramid.level_count() as u32, first_node, camera.kind, flags],
            graph: camera.graph,
            built_from_now: rows(now_from_built.inverse()),
            now_from_built: rows(now_from_built),
        });
        Ok(index)
    }

    /// What the shader reads of `camera` (a graph camera's frusta added to the set's).
    fn camera_record(&mut self, camera: &ImpostorCamera) -> Result<CameraRecord, GpuError> {
        let pinhole_rows = |c: &trompe::camera::Pinhole| {
            let inverse = c.mcmillan_inverse();
            let centre = c.position();
            let mut clip = row(c.forward(), centre);
            clip[3] -= c.near() as f32;
            [
                row(inverse.row(0), centre),
                row(inverse.row(1), centre),
                row(inverse.row(2), centre),
                [0.0; 4],
                clip,
            ]
        };
        let texel = |a: DVec3, b: DVec3| a.length().max(b.length()) as f32;
        Ok(match camera {
            ImpostorCamera::Pinhole(c) => {
                let (a, b, _) = c.mcmillan();
                CameraRecord {
                    kind: PINHOLE,
                    rows: pinhole_rows(c),
                    eye: c.position().as_vec3().extend(texel(a, b)).to_array(),
                    mcmillan: [[0.0; 4]; 3],
                    graph: [0; 4],
                }
            }
            ImpostorCamera::Orthographic(c) => {
                let (corner, a, b, dir, depth) = c.parameters();
                let mut g = row(-dir / depth, corner);
                g[3] += 1.0;
                CameraRecord {
                    kind: ORTHOGRAPHIC,
                    rows: [
                        row(a / a.length_squared(), corner),
                        row(b / b.length_squared(), corner),
                        [0.0, 0.0, 0.0, 1.0],
                        g,
                        row(dir, corner),
                    ],
                    eye: (-dir).as_vec3().extend(texel(a, b)).to_array(),
                    mcmillan: [[0.0; 4]; 3],
                    graph: [0; 4],
                }
            }
            ImpostorCamera::Spoc(c) => {
                let pinhole = c.pinhole();
                let (a, b, m_c) = pinhole.mcmillan();
                let (z_near, z_far) = c.depth_range();
                let pole = c.pole();
                let mut rows = pinhole_rows(pinhole);
                rows[3] = [
                    pole.x as f32,
                    pole.y as f32,
                    z_near as f32,
                    (c.strength() / (z_far - z_near)) as f32,
                ];
                CameraRecord {
                    kind: SPOC,
                    rows,
                    eye: pinhole.position().as_vec3().extend(texel(a, b)).to_array(),
                    mcmillan: [
                        a.as_vec3().extend(pinhole.focal() as f32).to_array(),
                        b.as_vec3().extend(0.0).to_array(),
                        m_c.as_vec3().extend(0.0).to_array(),
                    ],
                    graph: [0; 4],
                }
            }
            ImpostorCamera::Graph(g) => {
                let frusta = g.frusta();
                if frusta.len() > MAX_FRUSTA {
                    return Err(GpuError::Unsupported {
                        what: format!(
                            "a graph camera of {} frusta (the GPU walks at most {MAX_FRUSTA})",
                            frusta.len()
                        ),
                    });
                }
                let first = self.frusta.len() / FRUSTUM_STRIDE;
                for f in frusta {
                    let planes: Vec<_> = std::iter::once(&f.entry)
                        .chain(&f.sides)
                        .chain(f.exit.as_ref())
                        .collect();
                    if planes.len() > FRUSTUM_PLANES {
                        return Err(GpuError::Unsupported {
                            what: format!(
                                "a graph camera's frustum of {} planes (the GPU walks at most \
                                 {FRUSTUM_PLANES})",
                                planes.len()
                            ),
                        });
                    }
                    let count = f32::from_bits(planes.len() as u32);
                    self.frusta.push(f.apex.as_vec3().extend(count).to_array());
                    for m in [f.matrix, f.matrix.inverse()] {
                        for i in 0..4 {
                            self.frusta.push(m.row(i).as_vec4().to_array());
                        }
                    }
                    for k in 0..FRUSTUM_PLANES {
                        self.frusta.push(
                            planes
                                .get(k)
                                .map_or([0.0; 4], |p| p.n.extend(p.e).as_vec4().to_array()),
                        );
                    }
                }
                let root = g.root();
                let (a, b, _) = root.mcmillan();
                CameraRecord {
                    kind: GRAPH,
                    rows: [[0.0; 4]; 5],
                    eye: root.position().as_vec3().extend(texel(a, b)).to_array(),
                    mcmillan: [[0.0; 4]; 3],
                    graph: [first as u32, frusta.len() as u32, 0, 0],
                }
            }
        })
    }

    /// The set on `gpu`: bindings 13 to 17 and 19 of a shader that includes `shaders/walk.wgsl`.
    pub fn upload(&self, gpu: &Gpu) -> Result<UploadedWalks, GpuError> {
        // A binding is never empty: an empty set is one zeroed record.
        fn bytes<T: Pod>(data: &[T]) -> Vec<u8> {
            let mut b = bytemuck::cast_slice(data).to_vec();
            b.resize(b.len().max(std::mem::size_of::<GpuImpostor>()), 0);
            b
        }
        let parts = [
            ("the impostors", bytes(&self.impostors)),
            ("the impostors' layers", bytes(&self.layers)),
            ("the impostors' texel planes", bytes(&self.planes)),
            ("the impostors' colours and normals", bytes(&self.looks)),
            ("the impostors' pyramids", bytes(&self.pyramid)),
            ("the graph cameras' frusta", bytes(&self.frusta)),
        ];
        for (what, b) in &parts {
            gpu.check_storage(what, b.len() as u64)?;
        }
        Ok(UploadedWalks {
            buffers: parts.map(|(what, b)| gpu.storage_with(what, &b)),
            layers: self.layers.clone(),
            widths: self.impostors.iter().map(|i| i.size[0]).collect(),
            first_layers: self.impostors.iter().map(|i| i.size[2]).collect(),
        })
    }
}

/// A [`WalkSet`] on the device.
pub struct UploadedWalks {
    buffers: [wgpu::Buffer; 6],
    layers: Vec<u32>,
    widths: Vec<u32>,
    first_layers: Vec<u32>,
}

/// A GPU walk's hit, as the library's walk names it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkHit {
    /// Distance along the ray.
    pub t: f32,
    /// The layer (0 = the front one).
    pub layer: u32,
    /// The texel `(x, y)` of that layer whose surface was hit.
    pub texel: (u32, u32),
}

impl UploadedWalks {
    /// The buffers at their bindings.
    pub(crate) fn entries(&self) -> [(u32, &wgpu::Buffer); 6] {
        let [a, b, c, d, e, f] = &self.buffers;
        [(13, a), (14, b), (15, c), (16, d), (17, e), (19, f)]
    }

    /// Every ray's walk of impostor `index` (the library's [`Impostor::walk`], kept where
    /// `0 < t < t_max`), on the GPU.
    pub fn walk(
        &self,
        gpu: &Gpu,
        index: u32,
        rays: &[Ray],
        t_max: f32,
    ) -> Result<Vec<Option<WalkHit>>, GpuError> {
        let i = index as usize;
        if i >= self.widths.len() {
            return Err(GpuError::Unsupported {
                what: format!("walking impostor {index} of a set of {}", self.widths.len()),
            });
        }
        let pipeline = gpu.compute_pipeline("walk.wgsl", &shader_source(), "walk_rays");
        // What a hit shows (binding 16) is not read by a bare walk.
        let walked: Vec<_> = self
            .entries()
            .into_iter()
            .filter(|(b, _)| *b != 16)
            .collect();
        let answers: Vec<LeafHit> = ray_pass(gpu, &pipeline, &walked, rays, t_max, index)?;
        Ok(answers
            .iter()
            .map(|h| {
                (h.triangle != MISS).then(|| {
                    let layer = h.b1.to_bits();
                    let first = self.layers[(self.first_layers[i] + layer) as usize];
                    let texel = h.triangle - first;
                    let w = self.widths[i];
                    WalkHit {
                        t: h.t,
                        layer,
                        texel: (texel % w, texel / w),
                    }
                })
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use trompe::camera::Projection;

    #[test]
    fn rows_are_the_cameras_projection() {
        let cam = trompe::camera::Pinhole::look_at(
            Vec3::new(0.5, 1.0, 4.0),
            Vec3::ZERO,
            Vec3::Y,
            50.0,
            64,
            48,
        )
        .unwrap();
        let inverse = cam.mcmillan_inverse();
        let centre = cam.position();
        let p = DVec3::new(0.2, -0.3, 0.4);
        let h = p.extend(1.0).as_vec4();
        let rows = [0, 1, 2].map(|i| glam::Vec4::from_array(row(inverse.row(i), centre)));
        let w = rows[2].dot(h) as f64;
        let want = cam.project(p).unwrap();
        assert!((rows[0].dot(h) as f64 / w - want.uv.x).abs() < 1e-4);
        assert!((rows[1].dot(h) as f64 / w - want.uv.y).abs() < 1e-4);
        assert!((1.0 / w - want.gd).abs() < 1e-6);
    }
}
