//! Baking an octahedral atlas: one orthographic frame per grid direction, framed on the object's
//! bounding sphere and rasterized by trompe's rasterizer, holding base colour with coverage, the
//! object-space normal, the depth behind the frame's front plane and an ORM map (ambient
//! occlusion traced through the exact BVH at every vertex — [`AO_RAYS`] cosine-distributed rays
//! reaching one bounding radius — then interpolated; roughness and metalness from the material);
//! then every channel dilated
//! into the empty texels around the object and the rest of each frame filled, frame by frame, so
//! bilinear filtering and mip-maps never pull background into the silhouette.
//!
//! Invariants: frame `(i, j)` is the atlas's texels `[i·s, (i+1)·s) × [j·s, (j+1)·s)`; a frame's
//! camera looks at the sphere's centre from [`Grid::direction`] with image axes
//! [`frame_basis`]; depth is `(front − P)·d / 2r ∈ [0, 1]` (0 on the front plane `c + r·d`);
//! dilation never changes a covered texel and never crosses a frame's border.

use super::mapping::{Grid, frame_basis};
use crate::camera::{Orthographic, Pinhole};
use crate::frame::{Image, Rgba};
use crate::geom::Mesh;
use crate::raster::{StoreFragment, rasterize};
use crate::render::shading::albedo;
use crate::scene::Surface;
use crate::trace::{Bvh, RayQuery};
use glam::{DVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// Bytes a texel of the atlas costs while it is baked: colour, normal and depth, and the
/// frame's own buffers beside them.
pub const BYTES_PER_TEXEL: u64 = 64;

/// Texels of dilation around the object in every frame by default: enough for bilinear reads
/// and the first mip levels a runtime samples at the silhouette.
pub const DEFAULT_DILATION: u32 = 4;

/// How to bake. [`BakeSettings::new`] gives the defaults; [`bake`] checks every field.
///
/// ```
/// use trompe::octahedral::{BakeSettings, Coverage, DEFAULT_DILATION, Grid};
/// let grid = Grid { n: 8, coverage: Coverage::Sphere };
/// let settings = BakeSettings::new(grid, 64);
/// assert_eq!(settings.dilation, DEFAULT_DILATION);
/// assert!(settings.with_dilation(65).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BakeSettings {
    /// The frame grid.
    pub grid: Grid,
    /// Texels a frame side.
    pub frame_size: u32,
    /// Texels of dilation around the object in every frame.
    pub dilation: u32,
    /// How each frame sees the object.
    pub projection: FrameProjection,
}

/// How an atlas frame sees the object.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum FrameProjection {
    /// Parallel rays along the frame's direction, the image the sphere's diameter square: what
    /// engines' octahedral bakers do by default.
    #[default]
    Orthographic,
    /// A pinhole `distance` bounding radii from the centre (more than 1) whose field of view
    /// just holds the sphere: perspective as a camera at that distance sees it, for objects
    /// seen from near.
    Pinhole {
        /// Eye distance from the sphere's centre, in radii.
        distance: f32,
    },
}

impl BakeSettings {
    /// Orthographic frames of `frame_size` texels a side on `grid`, dilated by
    /// [`DEFAULT_DILATION`] texels.
    pub fn new(grid: Grid, frame_size: u32) -> Self {
        Self {
            grid,
            frame_size,
            dilation: DEFAULT_DILATION,
            projection: FrameProjection::Orthographic,
        }
    }

    /// The same, each frame seen through `projection`.
    pub fn with_projection(self, projection: FrameProjection) -> Self {
        Self { projection, ..self }
    }

    /// The same, dilated by `dilation` texels: at most a frame's side.
    pub fn with_dilation(self, dilation: u32) -> Result<Self, BakeError> {
        let settings = Self { dilation, ..self };
        settings.check_dilation()?;
        Ok(settings)
    }

    fn check_dilation(&self) -> Result<(), BakeError> {
        if self.dilation > self.frame_size {
            return Err(BakeError::Dilation {
                dilation: self.dilation,
                frame_size: self.frame_size,
            });
        }
        Ok(())
    }
}

impl FrameProjection {
    /// The tangent of the half field of view of a pinhole frame at `distance` radii that just
    /// holds the sphere.
    pub fn tan_half_fov(distance: f64) -> f64 {
        1.0 / (distance * distance - 1.0).max(1e-12).sqrt()
    }
}

/// A frame's camera.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameCamera {
    /// Orthographic.
    Orthographic(Orthographic),
    /// Pinhole.
    Pinhole(Pinhole),
}

impl FrameCamera {
    /// The ray through frame pixel position `pixel` (texel centres at `+½`).
    pub fn ray(&self, pixel: glam::DVec2) -> crate::geom::Ray {
        match self {
            FrameCamera::Orthographic(c) => c.ray(pixel),
            FrameCamera::Pinhole(c) => c.ray(pixel),
        }
    }
}

/// Why an atlas could not be baked.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BakeError {
    /// The grid or the atlas has no valid size.
    #[error(transparent)]
    Size(#[from] crate::frame::FrameError),
    /// The atlas would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// A pinhole frame's eye distance is not past the bounding sphere.
    #[error(
        "pinhole frames at {0} bounding radii: the eye must be outside the sphere (more than 1, at most 10 000)"
    )]
    Distance(f32),
    /// A dilation wider than a frame.
    #[error("a dilation of {dilation} texels is wider than a frame ({frame_size} texels a side)")]
    Dilation {
        /// Texels of dilation asked for.
        dilation: u32,
        /// Texels a frame side.
        frame_size: u32,
    },
}

/// A baked atlas, in the object's own space.
#[derive(Clone, Debug)]
pub struct OctahedralAtlas {
    /// How it was baked.
    pub settings: BakeSettings,
    /// The bounding sphere every frame is framed on: centre.
    pub centre: Vec3,
    /// The bounding sphere's radius.
    pub radius: f32,
    /// Linear base colour; alpha is coverage (0 or 1 as baked, dilated colour under alpha 0).
    pub color: Image<Rgba>,
    /// Unit object-space normal, facing the frame's camera (zero where nothing was ever drawn).
    pub normal: Image<Vec3>,
    /// Depth behind the front plane over the sphere's diameter, `[0, 1]`.
    pub depth: Image<f32>,
    /// Linear occlusion (1: nothing occludes), roughness and metalness — glTF's ORM packing.
    pub orm: Image<Vec3>,
    /// The card's outline round every view of the object ([`super::card`]).
    pub card: super::Card,
}

/// Ambient-occlusion rays traced from every vertex.
pub const AO_RAYS: u32 = 32;

/// Per vertex of `mesh`, the share of [`AO_RAYS`] cosine-distributed rays over its normal that
/// leave without meeting the mesh within `reach` (1: open sky, 0: fully occluded). The
/// directions are a fixed spiral turned by an angle hashed from the vertex index, so the result
/// is deterministic. Refused when the mesh's BVH would pass the memory budget.
pub fn vertex_occlusion(mesh: &Mesh, reach: f32) -> Result<Vec<f32>, crate::memory::OverBudget> {
    let bvh = Bvh::build(vec![std::sync::Arc::new(mesh.clone())])?;
    let epsilon = 1e-4 * reach;
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    Ok((0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let (p, n) = (mesh.positions[v], mesh.normals[v]);
            let Some(n) = n.try_normalize() else {
                return 1.0;
            };
            let t = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
            let (a, b) = {
                let a = t.cross(n).normalize();
                (a, n.cross(a))
            };
            let turn = (v as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
            let turn = turn as f32 / (1u64 << 24) as f32 * std::f32::consts::TAU;
            let open = (0..AO_RAYS)
                .filter(|&k| {
                    // Cosine-distributed: uniform on the disc, lifted to the hemisphere.
                    let r2 = (k as f32 + 0.5) / AO_RAYS as f32;
                    let phi = k as f32 * golden + turn;
                    let r = r2.sqrt();
                    let d = a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - r2).sqrt();
                    let ray = crate::geom::Ray::new(p + n * epsilon, d);
                    !bvh.any_hit(&ray, reach)
                })
                .count();
            open as f32 / AO_RAYS as f32
        })
        .collect())
}

/// Roughness and metalness of `mesh`'s triangle `tri` at texture coordinates `uv`, as `surface`
/// makes it: a scene's mirror is a smooth metal, its glass a smooth dielectric, a colour it
/// gives a rough dielectric; else the mesh's material (factors times its texture).
pub fn roughness_metalness(mesh: &Mesh, surface: &Surface, tri: usize, uv: Vec2) -> (f32, f32) {
    match surface {
        Surface::Mirror { .. } => (0.0, 1.0),
        Surface::Glass { .. } => (0.0, 0.0),
        Surface::Diffuse(Some(_)) => (1.0, 0.0),
        Surface::Diffuse(None) => {
            let m = mesh
                .face_material
                .get(tri)
                .and_then(|&i| mesh.materials.get(i as usize));
            let Some(m) = m else {
                return (1.0, 0.0);
            };
            let (mut r, mut k) = (m.roughness, m.metallic);
            if let Some(t) = &m.metallic_roughness {
                let c = t.sample_uv(uv, crate::frame::Wrap::Repeat);
                (r, k) = (r * c.y, k * c.z);
            }
            (r, k)
        }
    }
}

impl OctahedralAtlas {
    /// Atlas side in texels.
    pub fn side(&self) -> u32 {
        self.settings.grid.n * self.settings.frame_size
    }

    /// The camera of frame `(i, j)`.
    pub fn frame_camera(&self, i: u32, j: u32) -> FrameCamera {
        frame_camera(
            &self.settings,
            self.centre.as_dvec3(),
            f64::from(self.radius),
            i,
            j,
        )
    }
}

fn frame_camera(s: &BakeSettings, centre: DVec3, radius: f64, i: u32, j: u32) -> FrameCamera {
    let d = s.grid.direction(i, j);
    let (_, up) = frame_basis(d);
    // Valid by construction: a positive radius, a unit direction, a distance past the sphere.
    let made = match s.projection {
        FrameProjection::Orthographic => Orthographic::look_at(
            (centre + d * radius).as_vec3(),
            centre.as_vec3(),
            up.as_vec3(),
            radius,
            2.0 * radius,
            s.frame_size,
            s.frame_size,
        )
        .map(FrameCamera::Orthographic),
        FrameProjection::Pinhole { distance } => {
            let distance = f64::from(distance);
            let fov = 2.0 * FrameProjection::tan_half_fov(distance).atan().to_degrees();
            Pinhole::look_at(
                (centre + d * (radius * distance)).as_vec3(),
                centre.as_vec3(),
                up.as_vec3(),
                fov,
                s.frame_size,
                s.frame_size,
            )
            .map(|c| FrameCamera::Pinhole(c.with_near(radius * (distance - 1.0) * 0.5)))
        }
    };
    match made {
        Ok(c) => c,
        Err(_) => unreachable!("a frame camera has a positive radius and a unit direction"),
    }
}

/// Bakes `mesh`, coloured as `surface` colours it, into an atlas.
pub fn bake(
    mesh: &Mesh,
    surface: &Surface,
    settings: BakeSettings,
) -> Result<OctahedralAtlas, BakeError> {
    let n = settings.grid.n;
    if !super::mapping::FRAMES_RANGE.contains(&n) || settings.frame_size == 0 {
        return Err(crate::frame::FrameError::InvalidSize {
            width: u64::from(n),
            height: u64::from(settings.frame_size),
            reason: "an octahedral grid has 2 to 64 frames a side, each at least one texel",
        }
        .into());
    }
    settings.check_dilation()?;
    if let FrameProjection::Pinhole { distance } = settings.projection
        && !(distance.is_finite() && distance > 1.0 && distance <= 1e4)
    {
        return Err(BakeError::Distance(distance));
    }
    let b = mesh.bounds();
    let centre = b.center();
    let radius = mesh
        .positions
        .iter()
        .map(|p| (*p - centre).length())
        .fold(0.0f32, f32::max)
        .max(1e-6)
        * 1.001;
    let s = settings.frame_size;
    let side64 = u64::from(n) * u64::from(s);
    let (side, _) = crate::frame::check_size(side64, side64)?;
    crate::memory::check(
        || format!("an octahedral atlas of {side} × {side}"),
        crate::memory::times(side64 * side64, BYTES_PER_TEXEL),
    )?;
    let occlusion = vertex_occlusion(mesh, radius)?;
    let frames: Vec<FrameTexels> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % n, k / n);
            bake_frame(
                (mesh, surface, &occlusion),
                &settings,
                centre.as_dvec3(),
                f64::from(radius),
                i,
                j,
            )
        })
        .collect::<Result<_, _>>()?;
    let mut color = Image::new(side, side, Vec4::ZERO)?;
    let mut normal = Image::new(side, side, Vec3::ZERO)?;
    let mut depth = Image::new(side, side, 1.0f32)?;
    let mut orm = Image::new(side, side, Vec3::new(1.0, 1.0, 0.0))?;
    for (k, (c, nm, d, o)) in frames.into_iter().enumerate() {
        let (i, j) = (k as u32 % n, k as u32 / n);
        for y in 0..s {
            for x in 0..s {
                let t = (y * s + x) as usize;
                let (ax, ay) = (i * s + x, j * s + y);
                color.set(ax, ay, c[t]);
                normal.set(ax, ay, nm[t]);
                depth.set(ax, ay, d[t]);
                orm.set(ax, ay, o[t]);
            }
        }
    }
    let card = super::Card::around(mesh.positions.iter().copied(), centre, radius, s);
    Ok(OctahedralAtlas {
        settings,
        centre,
        radius,
        color,
        normal,
        depth,
        orm,
        card,
    })
}

/// One frame's colour, normal, depth and ORM texels.
type FrameTexels = (Vec<Rgba>, Vec<Vec3>, Vec<f32>, Vec<Vec3>);

fn bake_frame(
    (mesh, surface, occlusion): (&Mesh, &Surface, &[f32]),
    settings: &BakeSettings,
    centre: DVec3,
    radius: f64,
    i: u32,
    j: u32,
) -> Result<FrameTexels, crate::frame::FrameError> {
    let d = settings.grid.direction(i, j);
    let front = centre + d * radius;
    let (target, _) = match frame_camera(settings, centre, radius, i, j) {
        FrameCamera::Orthographic(c) => rasterize(&c, &[mesh], &StoreFragment, None)?,
        FrameCamera::Pinhole(c) => rasterize(&c, &[mesh], &StoreFragment, None)?,
    };
    let s = settings.frame_size as usize;
    let mut color = vec![Vec4::ZERO; s * s];
    let mut normal = vec![Vec3::ZERO; s * s];
    let mut depth = vec![1.0f32; s * s];
    let mut orm = vec![Vec3::new(1.0, 1.0, 0.0); s * s];
    for (t, f) in target.attributes.pixels().iter().enumerate() {
        let Some(f) = f else { continue };
        let tri = f.item.triangle as usize;
        let idx = mesh.triangles[tri];
        let b = f.bary;
        let p: Vec3 = (0..3).map(|k| mesh.positions[idx[k] as usize] * b[k]).sum();
        let mut nm: Vec3 = (0..3).map(|k| mesh.normals[idx[k] as usize] * b[k]).sum();
        nm = nm.try_normalize().unwrap_or_else(|| mesh.face_normal(tri));
        if nm.dot(d.as_vec3()) < 0.0 {
            nm = -nm;
        }
        let uv = match &mesh.uvs {
            Some(uvs) => (0..3).map(|k| uvs[idx[k] as usize] * b[k]).sum(),
            None => glam::Vec2::ZERO,
        };
        color[t] = albedo(mesh, surface, tri as u32, uv).extend(1.0);
        let ao: f32 = (0..3).map(|k| occlusion[idx[k] as usize] * b[k]).sum();
        let (rough, metal) = roughness_metalness(mesh, surface, tri, uv);
        orm[t] = Vec3::new(ao, rough, metal);
        normal[t] = nm;
        depth[t] = (((front - p.as_dvec3()).dot(d)) / (2.0 * radius)).clamp(0.0, 1.0) as f32;
    }
    dilate(
        &mut color,
        (&mut normal, &mut depth, &mut orm),
        s,
        settings.dilation,
    );
    Ok((color, normal, depth, orm))
}

/// Grows every channel `radius` texels into the uncovered texels of one `s × s` frame — each
/// round, an uncovered texel with covered (or already grown) 8-neighbours takes their mean —
/// then fills the rest of the frame with the nearest grown texel. Coverage stays 0 outside.
pub fn dilate(
    color: &mut [Rgba],
    (normal, depth, orm): (&mut [Vec3], &mut [f32], &mut [Vec3]),
    s: usize,
    radius: u32,
) {
    let mut filled: Vec<bool> = color.iter().map(|c| c.w > 0.0).collect();
    for _ in 0..radius {
        let mut grown = Vec::new();
        for y in 0..s {
            for x in 0..s {
                let t = y * s + x;
                if filled[t] {
                    continue;
                }
                let (mut c, mut nm, mut dp, mut count) = (Vec3::ZERO, Vec3::ZERO, 0.0f32, 0);
                let mut o = Vec3::ZERO;
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                        if nx < 0 || ny < 0 || nx >= s as i64 || ny >= s as i64 {
                            continue;
                        }
                        let u = ny as usize * s + nx as usize;
                        if filled[u] {
                            c += color[u].truncate();
                            nm += normal[u];
                            dp += depth[u];
                            o += orm[u];
                            count += 1;
                        }
                    }
                }
                if count > 0 {
                    let k = count as f32;
                    grown.push((t, c / k, nm.normalize_or_zero(), dp / k, o / k));
                }
            }
        }
        if grown.is_empty() {
            break;
        }
        for (t, c, nm, dp, o) in grown {
            color[t] = c.extend(0.0);
            normal[t] = nm;
            depth[t] = dp;
            orm[t] = o;
            filled[t] = true;
        }
    }
    // The rest of the frame takes its nearest filled texel (found by two chamfer sweeps), so
    // that every mip level of the frame holds the object's colours and never the background.
    let Some(nearest) = nearest_filled(&filled, s) else {
        return;
    };
    for (t, &from) in nearest.iter().enumerate() {
        if !filled[t] {
            color[t] = color[from].truncate().extend(0.0);
            normal[t] = normal[from];
            depth[t] = depth[from];
            orm[t] = orm[from];
        }
    }
}

/// For every texel of an `s × s` frame, a filled texel near it (itself where filled): the
/// nearest one propagated through 8-neighbours by a forward and a backward sweep. `None` when
/// nothing is filled.
fn nearest_filled(filled: &[bool], s: usize) -> Option<Vec<usize>> {
    if !filled.contains(&true) {
        return None;
    }
    const NONE: usize = usize::MAX;
    let mut nearest: Vec<usize> = (0..s * s)
        .map(|t| if filled[t] { t } else { NONE })
        .collect();
    let distance = |t: usize, from: usize| {
        let (dx, dy) = (
            (t % s) as i64 - (from % s) as i64,
            (t / s) as i64 - (from / s) as i64,
        );
        dx * dx + dy * dy
    };
    let relax = |t: usize, x: i64, y: i64, nearest: &mut Vec<usize>| {
        if x < 0 || y < 0 || x >= s as i64 || y >= s as i64 {
            return;
        }
        let from = nearest[y as usize * s + x as usize];
        if from != NONE && (nearest[t] == NONE || distance(t, from) < distance(t, nearest[t])) {
            nearest[t] = from;
        }
    };
    for t in 0..s * s {
        let (x, y) = ((t % s) as i64, (t / s) as i64);
        for (dx, dy) in [(-1, 0), (-1, -1), (0, -1), (1, -1)] {
            relax(t, x + dx, y + dy, &mut nearest);
        }
    }
    for t in (0..s * s).rev() {
        let (x, y) = ((t % s) as i64, (t / s) as i64);
        for (dx, dy) in [(1, 0), (1, 1), (0, 1), (-1, 1)] {
            relax(t, x + dx, y + dy, &mut nearest);
        }
    }
    Some(nearest)
}
