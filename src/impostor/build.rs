//! Impostor construction (paper 1 §3.1; docs/conventions.md §2.2): rasterize the mesh through the
//! camera, keeping the largest `gd`; through a curved camera, when the rasterizer's set-up finds
//! triangles curved beyond half a pixel, the mesh is tessellated adaptively before anything is
//! drawn, and the tessellation drawn instead. Through a graph camera (§4.5), each frustum draws
//! the pieces of the triangles clipped to it, over one image.

use super::{Impostor, ImpostorCamera};
use crate::camera::Spoc;
use crate::camera::{ImagePoint, Projection};
use crate::frame::packed::{HalfRgba, OctUnit, OpaquePacker, ZERO_UNIT, pack_unit};
use crate::frame::{FrameError, Image};
use crate::geom::NO_OBJECT;
use crate::geom::{Aabb, Material, Mesh};
use crate::raster::{
    BAND_ROWS, DepthTarget, FinishedBand, Fragment, FragmentShader, ItemId, RasterMemory,
    RasterTarget, SetUp, draw_depth_then, rasterize_over, set_up,
};
use glam::{DVec2, Vec2, Vec3};
use rayon::prelude::*;

/// A surface point the impostor stores: what a colour function is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// World position.
    pub position: Vec3,
    /// Unit shading normal.
    pub normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Triangle of the source mesh.
    pub triangle: u32,
}

/// Largest projected deviation of an edge's midpoint from its chord, in pixels (§2.2).
const MAX_DEVIATION_PX: f64 = 0.5;
/// Recursion cap of the tessellation per source triangle.
const MAX_SPLITS: u32 = 12;

/// A sub-triangle's source triangle and the barycentrics of its corners in it.
pub type SourceTriangle = (u32, [Vec3; 3]);

impl Tessellation {
    /// Sub-triangles from unshared corners (three positions each) and their sources.
    fn new(positions: Vec<Vec3>, source: Vec<SourceTriangle>) -> Tessellation {
        let n = source.len();
        let mesh = Mesh {
            normals: vec![Vec3::Z; positions.len()],
            triangles: (0..n as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect(),
            positions,
            uvs: None,
            face_material: vec![0; n],
            materials: vec![Material::default()],
        };
        Tessellation { mesh, source }
    }
}

/// A tessellated mesh and, for each of its triangles, the source triangle and the barycentrics
/// of its three corners in it.
pub struct Tessellation {
    /// The sub-triangles (unshared corners).
    pub mesh: Mesh,
    /// `(source triangle, corner barycentrics)` per sub-triangle.
    pub source: Vec<SourceTriangle>,
}

/// Splits triangles until every edge's projected midpoint lies within 0.5 px of the midpoint of
/// its projected ends (docs/conventions.md §2.2). Whether an edge splits depends on that edge alone,
/// and it splits at its midpoint, so two triangles sharing an edge split it identically: the
/// tessellation has no T-junctions and the image no cracks.
/// Returns `None` when no edge needs a split (the mesh can be rasterized as it is).
pub fn tessellate<P: Projection>(camera: &P, mesh: &Mesh) -> Option<Tessellation> {
    tessellate_with(camera, mesh, &mut TessellationScratch::default())
}

/// Per-vertex images and per-triangle split flags, kept by an [`ImpostorBuilder`] between
/// builds: allocating them fresh costs more (page faults) than filling them.
#[derive(Default)]
struct TessellationScratch {
    projected: Vec<Option<ImagePoint>>,
    splits: Vec<bool>,
}

/// [`tessellate`] with reusable working memory.
fn tessellate_with<P: Projection>(
    camera: &P,
    mesh: &Mesh,
    scratch: &mut TessellationScratch,
) -> Option<Tessellation> {
    // Split decisions depend on the edge alone (see above).
    // Whether edge (a, b), whose ends project to (pa, pb), must split. The camera's cheap
    // bound settles nearly every edge of a detailed mesh without projecting its midpoint.
    let split_projected = |a: Vec3, b: Vec3, pa: &ImagePoint, pb: &ImagePoint| -> bool {
        if (pa.uv - pb.uv).length_squared() < 1.0
            || camera.midpoint_deviation_bound(&[*pa, *pb]) <= MAX_DEVIATION_PX
        {
            return false;
        }
        let m = (a + b) * 0.5;
        camera
            .project(m.as_dvec3())
            .is_some_and(|pm| (pm.uv - (pa.uv + pb.uv) * 0.5).length() > MAX_DEVIATION_PX)
    };
    let needs_split = |a: Vec3, b: Vec3| -> bool {
        match (camera.project(a.as_dvec3()), camera.project(b.as_dvec3())) {
            (Some(pa), Some(pb)) => split_projected(a, b, &pa, &pb),
            _ => false,
        }
    };
    // Most triangles of a detailed mesh need no split (the paper notes this): find them from
    // the projected vertices alone, and give back the mesh untouched when none does.
    let TessellationScratch { projected, splits } = scratch;
    projected.clear();
    projected.par_extend(
        mesh.positions
            .par_iter()
            .map(|p| camera.project(p.as_dvec3())),
    );
    let projected = &*projected;
    let needs_any_split = |t: usize| {
        let [a, b, c] = mesh.triangles[t].map(|i| i as usize);
        // One bound for the three edges settles nearly every triangle.
        if let (Some(pa), Some(pb), Some(pc)) = (projected[a], projected[b], projected[c]) {
            if camera.midpoint_deviation_bound(&[pa, pb, pc]) <= MAX_DEVIATION_PX {
                return false;
            }
        }
        [(a, b), (b, c), (c, a)]
            .iter()
            .any(|&(i, j)| match (projected[i], projected[j]) {
                (Some(pi), Some(pj)) => {
                    split_projected(mesh.positions[i], mesh.positions[j], &pi, &pj)
                }
                _ => false,
            })
    };
    splits.clear();
    splits.par_extend(
        (0..mesh.triangles.len())
            .into_par_iter()
            .map(needs_any_split),
    );
    let splits = &*splits;
    if !splits.contains(&true) {
        return None;
    }
    // Fixed chunks of source triangles, tessellated in parallel and concatenated in order.
    let tris: Vec<usize> = (0..mesh.triangles.len()).collect();
    let chunks: Vec<(Vec<Vec3>, Vec<SourceTriangle>)> = tris
        .par_chunks(4096)
        .map(|chunk| {
            let mut positions = Vec::with_capacity(chunk.len() * 3);
            let mut source = Vec::with_capacity(chunk.len());
            let mut stack = Vec::new();
            for &t in chunk {
                if !splits[t] {
                    positions.extend_from_slice(&mesh.corners(t));
                    source.push((t as u32, [Vec3::X, Vec3::Y, Vec3::Z]));
                    continue;
                }
                stack.push((mesh.corners(t), [Vec3::X, Vec3::Y, Vec3::Z], 0u32));
                while let Some((p, b, depth)) = stack.pop() {
                    let edges = [(0, 1), (1, 2), (2, 0)];
                    let split = edges
                        .iter()
                        .filter(|&&(i, j)| depth < MAX_SPLITS && needs_split(p[i], p[j]))
                        .max_by(|&&(i, j), &&(k, l)| {
                            p[i].distance_squared(p[j])
                                .total_cmp(&p[k].distance_squared(p[l]))
                        });
                    match split {
                        None => {
                            positions.extend_from_slice(&p);
                            source.push((t as u32, b));
                        }
                        Some(&(i, j)) => {
                            let (pm, bm) = ((p[i] + p[j]) * 0.5, (b[i] + b[j]) * 0.5);
                            let (mut first, mut second) = ((p, b), (p, b));
                            (first.0[j], first.1[j]) = (pm, bm);
                            (second.0[i], second.1[i]) = (pm, bm);
                            stack.push((second.0, second.1, depth + 1));
                            stack.push((first.0, first.1, depth + 1));
                        }
                    }
                }
            }
            (positions, source)
        })
        .collect();
    let mut positions = Vec::new();
    let mut source = Vec::new();
    for (p, s) in chunks {
        positions.extend(p);
        source.extend(s);
    }
    Some(Tessellation::new(positions, source))
}

/// The first pass of construction writes, per fragment that passes the depth test, only its
/// barycentrics (the item buffer holds its triangle): a visibility buffer. Surface attributes
/// are resolved afterwards, once per covered texel ([`resolve_run`]); writing them per
/// fragment into a wide attribute image cost more than the rasterization itself. Two weights
/// are stored, the third is `1 − b₁ − b₂` ([`full_barycentrics`]).
struct Barycentrics;

impl FragmentShader for Barycentrics {
    type Output = Vec2;
    fn shade(&self, f: &Fragment) -> Vec2 {
        Vec2::new(f.bary.y, f.bary.z)
    }
}

/// The three weights from the two a [`Barycentrics`] buffer stores.
fn full_barycentrics(b: Vec2) -> Vec3 {
    Vec3::new(1.0 - b.x - b.y, b.x, b.y)
}

/// A visible point of the source mesh: its triangle and barycentrics, and through a graph
/// camera the frustum that drew it — the view its face normal is turned toward. (Finding a
/// frustum again with `locate` cost 5 % of a graph build, and where frusta meet it may name
/// another one than the frustum that imaged the point: 303 texels of the demo maze at 512².)
#[derive(Clone, Copy, Debug, PartialEq)]
struct Visible {
    triangle: u32,
    bary: Vec3,
    frustum: Option<u32>,
}

/// A run of texels of every map of an impostor (the same texels of each), row-major.
struct TexelMaps<'a> {
    color: &'a mut [HalfRgba],
    normal: &'a mut [OctUnit],
    face_normal: &'a mut [OctUnit],
    /// Through a graph camera only ([`Impostor::position_at`]).
    position: Option<&'a mut [Vec3]>,
    object: &'a mut [u32],
}

impl Impostor {
    /// Its `gd`, and its other maps cut into runs of `n` texels (the last may be shorter) for
    /// parallel filling.
    fn gd_and_texel_runs(&mut self, n: usize) -> (&mut Image<f32>, Vec<TexelMaps<'_>>) {
        let mut positions = self.position.as_mut().map(|p| p.pixels_mut().chunks_mut(n));
        let runs = self
            .color
            .pixels_mut()
            .chunks_mut(n)
            .zip(self.normal.pixels_mut().chunks_mut(n))
            .zip(self.face_normal.pixels_mut().chunks_mut(n))
            .zip(self.object.pixels_mut().chunks_mut(n))
            .map(|(((color, normal), face_normal), object)| TexelMaps {
                color,
                normal,
                face_normal,
                position: positions.as_mut().and_then(|p| p.next()),
                object,
            })
            .collect();
        (&mut self.gd, runs)
    }
}

/// What an impostor's maps hold before a resolve pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MapsBefore {
    /// The result of an earlier resolve: every map is empty wherever `object` is
    /// [`NO_OBJECT`], so only texels with an object need clearing.
    Resolved,
    /// Zeros everywhere, fresh from [`zeroed_impostor`]: an empty texel only needs its object
    /// set to [`NO_OBJECT`], and the other maps' pages of empty rows are never touched.
    Zeroed,
}

/// A run's texels' `gd` and where the run starts, for a SPOC impostor: its rasterizer draws
/// triangles straight in the image and interpolates `gd` linearly there, while the SPOC's rays
/// curve, so the resolve moves each texel's `gd` to where its centre's ray meets the plane of
/// the stored triangle ([`Spoc::gd_on_plane`]). The texel's position, derived from its `gd`
/// ([`Impostor::position_at`]), is then on that plane, as the walk needs.
struct RunDepth<'a> {
    gd: &'a mut [f32],
    first_pixel: usize,
    spoc: &'a Spoc,
}

/// What resolving a visibility buffer needs besides the visible points.
struct ResolveInputs<'a, F> {
    camera: &'a ImpostorCamera,
    mesh: &'a Mesh,
    object: u32,
    color: &'a F,
    before: MapsBefore,
}

/// Fills a run of texels — whole image rows of `width` texels — from the visible points
/// `visible(i)` of its texels `i` (counted from the run's start), and empties the texels with
/// none. Only the texels of `columns` (inclusive) in each row are resolved: every other one
/// is empty (`None`: all of them). `visible` must answer for every texel of the run, though:
/// texels ahead are asked for their triangle, to prefetch it. After it, every map is empty
/// wherever `object` is [`NO_OBJECT`].
fn resolve_run<F, V>(
    run: &mut TexelMaps<'_>,
    (width, columns): (usize, Option<(usize, usize)>),
    mut depth: Option<RunDepth<'_>>,
    inputs: &ResolveInputs<'_, F>,
    visible: V,
) where
    F: Fn(&SurfaceSample) -> Vec3 + Sync,
    V: Fn(usize) -> Option<Visible>,
{
    let ResolveInputs {
        camera,
        mesh,
        object,
        color,
        before,
    } = inputs;
    let run_len = run.color.len();
    let mut colors = OpaquePacker::default();
    for row_start in (0..run_len).step_by(width) {
        let row_end = (row_start + width).min(run_len);
        // Outside the drawn columns every texel is empty, handled in bulk.
        let (x0, x1) = match columns {
            Some((c0, c1)) => (row_start + c0, (row_start + c1 + 1).min(row_end)),
            None => (row_start, row_start),
        };
        empty_texels(run, row_start..x0, *before);
        empty_texels(run, x1..row_end, *before);
        // The image row of this run row, for a SPOC's texel centres.
        let image_row = depth
            .as_ref()
            .map_or(0.0, |d| ((d.first_pixel + row_start) / width) as f64 + 0.5);
        for x in x0..x1 {
            // The triangles of texels a little ahead, on their way from memory (see
            // `crate::prefetch`): the triangle's indices first, its corners once they are here.
            // Ahead runs on into the next row, so that row's first texels are asked for too.
            let triangle_ahead = |k: usize| (x + k < run_len).then(|| visible(x + k)).flatten();
            if let Some(v) = triangle_ahead(TRIANGLE_AHEAD) {
                mesh.prefetch_triangle(v.triangle);
            }
            if let Some(v) = triangle_ahead(CORNERS_AHEAD) {
                mesh.prefetch_corners(v.triangle);
            }
            let Some(Visible {
                triangle: t,
                bary: b,
                frustum,
            }) = visible(x)
            else {
                empty_texels(run, x..x + 1, *before);
                continue;
            };
            let (s, face, interpolated) = surface_sample(mesh, t, b);
            run.color[x] = colors.pack(color(&s));
            run.normal[x] = pack_normal(interpolated, face);
            // The face normal, turned toward the camera.
            let toward = toward_viewer(camera, s.position.as_dvec3(), frustum);
            run.face_normal[x] = pack_unit(if face.as_dvec3().dot(toward) < 0.0 {
                -face
            } else {
                face
            });
            if let Some(d) = depth.as_mut() {
                let centre = DVec2::new((x - row_start) as f64 + 0.5, image_row);
                let (n, p) = (face.as_dvec3(), s.position.as_dvec3());
                if let Some(gd) = d.spoc.gd_on_plane(centre, n, p, d.gd[x] as f64) {
                    d.gd[x] = gd as f32;
                }
            }
            if let Some(position) = run.position.as_deref_mut() {
                position[x] = s.position;
            }
            run.object[x] = *object;
        }
    }
}

/// How many texels ahead [`resolve_run`] asks for a texel's triangle, and for its corners.
/// The triangle must have arrived when its corners are asked for.
const TRIANGLE_AHEAD: usize = 10;
const CORNERS_AHEAD: usize = 5;

/// Empties the texels `range` of `run`, whose maps hold `before`.
fn empty_texels(run: &mut TexelMaps<'_>, range: std::ops::Range<usize>, before: MapsBefore) {
    match before {
        // Written, not read first: reading a fresh page maps the shared zero page, and the
        // write after it then pays a second fault.
        MapsBefore::Zeroed => run.object[range].fill(NO_OBJECT),
        // Only texels written last time need clearing: most of an impostor's image is empty,
        // and skipping it halves the pass.
        MapsBefore::Resolved => {
            for x in range {
                if run.object[x] != NO_OBJECT {
                    run.color[x] = HalfRgba::default();
                    run.normal[x] = OctUnit::default();
                    run.face_normal[x] = OctUnit::default();
                    if let Some(position) = run.position.as_deref_mut() {
                        position[x] = Vec3::ZERO;
                    }
                    run.object[x] = NO_OBJECT;
                }
            }
        }
    }
}

/// Fills the impostor's maps from the visible points `visible(i)` of texels `i` (row-major),
/// in parallel over rows (see [`resolve_run`]).
fn resolve<F, V>(
    impostor: &mut Impostor,
    (mesh, object): (&Mesh, u32),
    color: &F,
    before: MapsBefore,
    visible: V,
) where
    F: Fn(&SurfaceSample) -> Vec3 + Sync,
    V: Fn(usize) -> Option<Visible> + Sync,
{
    let row = impostor.color.size().0 as usize;
    let camera = impostor.camera.clone();
    let inputs = ResolveInputs {
        camera: &camera,
        mesh,
        object,
        color,
        before,
    };
    impostor
        .gd_and_texel_runs(row)
        .1
        .into_par_iter()
        .enumerate()
        .for_each(|(y, mut run)| {
            let whole_row = (row, Some((0, row - 1)));
            resolve_run(&mut run, whole_row, None, &inputs, |x| visible(y * row + x));
        });
    finish_resolve(impostor, mesh);
}

/// Sets the bounds of a freshly resolved impostor (the mesh's box, padded) and drops what was
/// derived from its old maps.
fn finish_resolve(impostor: &mut Impostor, mesh: &Mesh) {
    impostor.bounds = impostor_bounds(mesh);
    impostor.maps_changed();
}

/// The bounds of an impostor of `mesh`: the mesh's box padded by 10⁻⁴ of its largest extent.
pub(super) fn impostor_bounds(mesh: &Mesh) -> Aabb {
    let b = mesh.bounds();
    let pad = b.extent().max_element() * 1e-4;
    Aabb {
        min: b.min - Vec3::splat(pad),
        max: b.max + Vec3::splat(pad),
    }
}

/// An impostor sized for its camera whose maps are all zeros — object 0 everywhere, so not yet
/// a valid impostor: resolve it with [`MapsBefore::Zeroed`]. Its memory is not touched here
/// (see [`Image::zeroed`]): the parallel resolve takes the page faults, band by band.
fn zeroed_impostor(camera: ImpostorCamera) -> Result<Impostor, FrameError> {
    let (w, h) = camera.resolution();
    // Allocated on two threads, half the bytes each (colour and normal; face normal, object
    // and gd): memory the allocator recycles (a process that builds again and again) it
    // clears itself, and that clearing then runs on both cores.
    let ((color, normal), (face_normal, object, gd)) = rayon::join(
        || (Image::zeroed(w, h), Image::zeroed(w, h)),
        || {
            (
                Image::zeroed(w, h),
                Image::zeroed(w, h),
                Image::zeroed(w, h),
            )
        },
    );
    let position = if camera.stores_positions() {
        Some(Image::zeroed(w, h)?)
    } else {
        None
    };
    Ok(Impostor::from_maps(
        camera,
        color?,
        gd?,
        normal?,
        face_normal?,
        position,
        object?,
        Aabb {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
        },
    ))
}

/// The surface point with barycentrics `b` in triangle `t` of `m`.
/// Also returns the triangle's face normal `(p₁ − p₀) × (p₂ − p₀)` and the interpolated vertex
/// normal, neither normalized: the maps pack them, and packing normalizes ([`pack_normal`]).
// Inlined, like the other per-texel calls of `resolve_run` (`gd_on_plane`, `pack_rgba`, the
// prefetches, `toward_camera`): as calls, each handed its results back through memory and the
// texel's work could not be scheduled as one; inlining them cut the fresh SPOC build by about
// 7 % (`trompe bench`, the fresh SPOC line).
#[inline(always)]
fn surface_sample(m: &Mesh, t: u32, b: Vec3) -> (SurfaceSample, Vec3, Vec3) {
    let [i0, i1, i2] = m.triangles[t as usize].map(|i| i as usize);
    let [p0, p1, p2] = [i0, i1, i2].map(|i| m.positions[i]);
    let position = p0 * b.x + p1 * b.y + p2 * b.z;
    let face = (p1 - p0).cross(p2 - p0);
    let interpolated = m.normals[i0] * b.x + m.normals[i1] * b.y + m.normals[i2] * b.z;
    // The colour callback may use the unit normal; when it does not, being inlined, this
    // square root and division are not computed at all.
    let normal = interpolated
        .try_normalize()
        .unwrap_or_else(|| face.normalize_or_zero());
    let uv = m
        .uvs
        .as_ref()
        .map_or(Vec2::ZERO, |uv| uv[i0] * b.x + uv[i1] * b.y + uv[i2] * b.z);
    let sample = SurfaceSample {
        position,
        normal,
        uv,
        triangle: t,
    };
    (sample, face, interpolated)
}

/// The packed shading normal of a surface sample: its `interpolated` vertex normal, or the
/// triangle's `face` normal where that is zero — as [`surface_sample`]'s unit normal, but
/// without normalizing first, since the octahedral packing divides by the 1-norm anyway.
#[inline(always)]
fn pack_normal(interpolated: Vec3, face: Vec3) -> OctUnit {
    match pack_unit(interpolated) {
        ZERO_UNIT => pack_unit(face),
        code => code,
    }
}

/// The direction from `p` toward the camera that sees it: through a graph camera, toward the
/// apex of the frustum that drew it when known.
fn toward_viewer(camera: &ImpostorCamera, p: glam::DVec3, frustum: Option<u32>) -> glam::DVec3 {
    match (camera, frustum) {
        (ImpostorCamera::Graph(g), Some(j)) => g.frusta()[j as usize].apex - p,
        _ => camera.toward_camera(p),
    }
}

/// The source triangle and barycentrics of a fragment of sub-triangle `t` (or of `t` itself
/// when the mesh was not tessellated).
fn to_source(source: Option<&[SourceTriangle]>, t: u32, bary: Vec3) -> Visible {
    let (triangle, bary) = match source {
        Some(src) => {
            let (s, c) = src[t as usize];
            (s, c[0] * bary.x + c[1] * bary.y + c[2] * bary.z)
        }
        None => (t, bary),
    };
    Visible {
        triangle,
        bary,
        frustum: None,
    }
}

/// Builds an impostor of `mesh` (object id `object`) through `camera`, colouring each texel with
/// `color` (e.g. the scene's shading of that surface point). To build again and again (a
/// dynamic scene), keep an [`ImpostorBuilder`] and call [`ImpostorBuilder::rebuild`].
pub fn build<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
    camera: ImpostorCamera,
    mesh: &Mesh,
    object: u32,
    color: &F,
) -> Result<Impostor, FrameError> {
    ImpostorBuilder::default().build(camera, mesh, object, color)
}

/// Builds impostors while keeping its working memory — the rasterizer's here, the impostor's
/// own maps in [`ImpostorBuilder::rebuild`] — so a rebuild every frame (paper 1 §6 rebuilds
/// its impostors for dynamic scenes) allocates nothing.
#[derive(Default)]
pub struct ImpostorBuilder {
    raster: RasterMemory<Vec2>,
    tessellation: TessellationScratch,
    /// A graph camera's visibility image, which every frustum draws over (§4.5).
    graph_target: Option<RasterTarget<Option<Visible>>>,
}

impl ImpostorBuilder {
    /// A builder with no memory yet.
    pub fn new() -> ImpostorBuilder {
        ImpostorBuilder::default()
    }

    /// Builds a new impostor (see [`build`]).
    pub fn build<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        camera: ImpostorCamera,
        mesh: &Mesh,
        object: u32,
        color: &F,
    ) -> Result<Impostor, FrameError> {
        let mut impostor = zeroed_impostor(camera)?;
        self.build_into(&mut impostor, (mesh, object), color, MapsBefore::Zeroed)?;
        Ok(impostor)
    }

    /// Builds `impostor` again through its own camera, from `mesh` as it is now, reusing its
    /// maps. The result equals a fresh [`build`].
    pub fn rebuild<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        impostor: &mut Impostor,
        mesh: &Mesh,
        object: u32,
        color: &F,
    ) -> Result<(), FrameError> {
        self.build_into(impostor, (mesh, object), color, MapsBefore::Resolved)
    }

    /// Draws `mesh` through the camera of `impostor` and resolves it into its maps, which hold
    /// `before`.
    fn build_into<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        impostor: &mut Impostor,
        (mesh, object): (&Mesh, u32),
        color: &F,
        before: MapsBefore,
    ) -> Result<(), FrameError> {
        // One match, then everything runs monomorphised through the concrete camera.
        let camera = impostor.camera.clone();
        match &camera {
            ImpostorCamera::Pinhole(c) => {
                self.build_through(c, impostor, (mesh, object), color, before)
            }
            ImpostorCamera::Orthographic(c) => {
                self.build_through(c, impostor, (mesh, object), color, before)
            }
            ImpostorCamera::Spoc(c) => {
                self.build_through(c, impostor, (mesh, object), color, before)
            }
            ImpostorCamera::Graph(_) => {
                self.build_graph_into(impostor, (mesh, object), color, before)
            }
        }
    }

    /// [`Self::build_into`] through one camera model `P`, the impostor's own.
    fn build_through<P: Projection, F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        projection: &P,
        impostor: &mut Impostor,
        (mesh, object): (&Mesh, u32),
        color: &F,
        before: MapsBefore,
    ) -> Result<(), FrameError> {
        // Detailed meshes rarely need splitting (paper 1 §3.1): the mesh is drawn as it is
        // unless, through a curved camera, set-up finds triangles the camera may curve by more
        // than the tolerance, or that it had to clip. Then, before anything is drawn, the mesh
        // is tessellated, and when some edge does need splitting (set-up's test is a bound)
        // the tessellation is drawn instead of the mesh.
        let curved = impostor.camera.is_curved();
        let source = (mesh, object);
        let setup = set_up(projection, &[mesh], &mut self.raster);
        let pieces = if curved && setup.stats().has_curved_or_clipped() {
            tessellate_with(projection, mesh, &mut self.tessellation)
        } else {
            None
        };
        match &pieces {
            None => draw_and_resolve(setup, impostor, source, None, color, before)?,
            Some(t) => {
                let setup = set_up(projection, &[&t.mesh], &mut self.raster);
                let drawn = Some(t.source.as_slice());
                draw_and_resolve(setup, impostor, source, drawn, color, before)?
            }
        };
        finish_resolve(impostor, mesh);
        Ok(())
    }

    /// Graph-camera construction (§4.5): every frustum rasterizes the triangles clipped to it
    /// with its own matrix, over one visibility image (kept between builds); the largest `gd`
    /// wins (frusta in order, so ties keep the earlier one). Then resolved into the maps of
    /// `impostor`, which hold `before`.
    fn build_graph_into<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        impostor: &mut Impostor,
        (mesh, object): (&Mesh, u32),
        color: &F,
        before: MapsBefore,
    ) -> Result<(), FrameError> {
        let ImpostorCamera::Graph(g) = &impostor.camera else {
            unreachable!("called for graph cameras only")
        };
        let (w, h) = g.resolution();
        let groups = group_bounds(mesh);
        let pieces: Vec<Tessellation> = (0..g.frusta().len())
            .into_par_iter()
            .map(|j| clip_to_frustum(g, j, mesh, &groups))
            .collect();
        let target = match &mut self.graph_target {
            Some(t) if t.gd.size() == (w, h) => {
                t.gd.pixels_mut().par_iter_mut().for_each(|v| *v = 0.0);
                t.item
                    .pixels_mut()
                    .par_iter_mut()
                    .for_each(|v| *v = ItemId::NONE);
                t.attributes
                    .pixels_mut()
                    .par_iter_mut()
                    .for_each(|v| *v = None);
                t
            }
            slot => slot.insert(RasterTarget::new(w, h, None)?),
        };
        for (j, piece) in pieces.iter().enumerate() {
            if !piece.source.is_empty() {
                let shader = SourcePoint {
                    source: &piece.source,
                    frustum: j as u32,
                };
                rasterize_over(&g.frustum(j), &[&piece.mesh], &shader, None, target)?;
            }
        }
        // The drawn depth becomes the impostor's; its old one is cleared next time.
        std::mem::swap(&mut impostor.gd, &mut target.gd);
        let visible = &target.attributes;
        resolve(impostor, (mesh, object), color, before, |i| {
            visible.pixels()[i]
        });
        Ok(())
    }
}

/// Draws `setup` — a mesh set up through the impostor's camera, or its tessellation, whose
/// sub-triangles' sources `drawn` names — into its `gd`, resolving each band of the visibility
/// buffer into its other maps (surface points of `mesh`; the maps hold `before`) as soon as the
/// band is drawn.
fn draw_and_resolve<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
    setup: SetUp<'_, Vec2>,
    impostor: &mut Impostor,
    (mesh, object): (&Mesh, u32),
    source: Option<&[SourceTriangle]>,
    color: &F,
    before: MapsBefore,
) -> Result<crate::raster::RasterStats, FrameError> {
    let w = impostor.camera.resolution().0;
    let camera = impostor.camera.clone();
    let inputs = ResolveInputs {
        camera: &camera,
        mesh,
        object,
        color,
        before,
    };
    let (gd, runs) = impostor.gd_and_texel_runs((BAND_ROWS * w) as usize);
    let spoc = match &camera {
        ImpostorCamera::Spoc(s) => Some(s),
        _ => None,
    };
    let finish = |band: FinishedBand<'_, Vec2>, run: &mut TexelMaps<'_>| {
        let depth = spoc.map(|spoc| RunDepth {
            gd: &mut *band.gd,
            first_pixel: band.first_pixel,
            spoc,
        });
        let columns = band.columns.map(|(a, b)| (a as usize, b as usize));
        resolve_run(run, (w as usize, columns), depth, &inputs, |x| {
            let item = band.item[x];
            (item != ItemId::NONE).then(|| {
                let b = full_barycentrics(band.attributes[x]);
                to_source(source, item.triangle, b)
            })
        });
    };
    let target = DepthTarget {
        gd,
        zeroed: before == MapsBefore::Zeroed,
    };
    draw_depth_then(setup, &Barycentrics, Vec2::ZERO, target, runs, finish)
}

/// Triangles per group whose box is tested against a frustum's planes before its triangles are
/// (a mesh's consecutive triangles are usually near one another).
const CLIP_GROUP: usize = 64;

/// The box of each group of [`CLIP_GROUP`] consecutive triangles of `mesh`.
fn group_bounds(mesh: &Mesh) -> Vec<Aabb> {
    let triangles: Vec<usize> = (0..mesh.triangles.len()).collect();
    triangles
        .par_chunks(CLIP_GROUP)
        .map(|group| Aabb::from_points(group.iter().flat_map(|&t| mesh.corners(t))))
        .collect()
}

/// Where a box lies against a plane: wholly inside, wholly outside, or across it — "wholly"
/// with a margin far above the rounding of the corners' own distances, so a box said to be
/// inside (outside) holds no corner that [`clip_triangle`] would find outside (inside).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Inside,
    Outside,
    Across,
}

fn box_side(plane: &crate::camera::Plane, b: &Aabb) -> Side {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let n = plane.n;
    // The corners farthest along and against the normal.
    let far = glam::DVec3::select(n.cmpge(glam::DVec3::ZERO), hi, lo);
    let near = glam::DVec3::select(n.cmpge(glam::DVec3::ZERO), lo, hi);
    let margin = 1e-9 * (n.abs().dot(lo.abs().max(hi.abs())) + plane.e.abs());
    if plane.eval(far) < -margin {
        Side::Outside
    } else if plane.eval(near) > margin {
        Side::Inside
    } else {
        Side::Across
    }
}

/// Clips triangle `t` (corners `p`) to the convex region inside every plane of `planes`
/// (Sutherland–Hodgman, in 3-D), fan-triangulating what is left into `out`. A triangle wholly
/// outside one plane is dropped at once, one wholly inside all of them kept as it is.
fn clip_triangle(
    planes: &[crate::camera::Plane],
    t: usize,
    p: [Vec3; 3],
    out: &mut (Vec<Vec3>, Vec<SourceTriangle>),
) {
    let whole = [Vec3::X, Vec3::Y, Vec3::Z];
    let corners = p.map(|c| c.as_dvec3());
    let mut inside_all = true;
    for plane in planes {
        let d = corners.map(|c| plane.eval(c));
        if d.iter().all(|&x| x < 0.0) {
            return;
        }
        inside_all &= d.iter().all(|&x| x >= 0.0);
    }
    if inside_all {
        out.0.extend_from_slice(&p);
        out.1.push((t as u32, whole));
        return;
    }
    let mut poly: Vec<(glam::DVec3, Vec3)> = corners.into_iter().zip(whole).collect();
    for plane in planes {
        let mut next = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (da, db) = (plane.eval(a.0), plane.eval(b.0));
            if da >= 0.0 {
                next.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                // From the inside corner toward the outside one (same cut from both sides).
                let ((pi, bi), (po, bo), di, d_o) = if da >= 0.0 {
                    (a, b, da, db)
                } else {
                    (b, a, db, da)
                };
                let s = di / (di - d_o);
                next.push((pi + (po - pi) * s, bi + (bo - bi) * s as f32));
            }
        }
        poly = next;
        if poly.len() < 3 {
            return;
        }
    }
    for k in 1..poly.len() - 1 {
        for c in [poly[0], poly[k], poly[k + 1]] {
            out.0.push(c.0.as_vec3());
        }
        out.1
            .push((t as u32, [poly[0].1, poly[k].1, poly[k + 1].1]));
    }
}

/// The planes bounding frustum `j` of `g`, inside toward it: its entry, sides and exit.
fn frustum_planes(g: &crate::camera::GraphCamera, j: usize) -> Vec<crate::camera::Plane> {
    let f = &g.frusta()[j];
    std::iter::once(f.entry)
        .chain(f.sides.iter().copied())
        .chain(f.exit)
        .collect()
}

/// Clips every triangle of `mesh` to frustum `j` of `g` ([`clip_triangle`], §4.5), group by
/// group: a group whose box (`groups`, from [`group_bounds`]) is wholly outside one plane is
/// skipped, one wholly inside every plane kept whole — most of a mesh meets one frustum or two.
/// The same pieces, in the same order, as clipping each triangle.
fn clip_to_frustum(
    g: &crate::camera::GraphCamera,
    j: usize,
    mesh: &Mesh,
    groups: &[Aabb],
) -> Tessellation {
    let planes = frustum_planes(g, j);
    let mut out = (Vec::new(), Vec::new());
    for (k, b) in groups.iter().enumerate() {
        let (mut outside, mut inside_all) = (false, true);
        for plane in &planes {
            match box_side(plane, b) {
                Side::Outside => {
                    outside = true;
                    break;
                }
                Side::Across => inside_all = false,
                Side::Inside => {}
            }
        }
        if outside {
            continue;
        }
        let first = k * CLIP_GROUP;
        let triangles = first..(first + CLIP_GROUP).min(mesh.triangles.len());
        if inside_all {
            for t in triangles {
                out.0.extend_from_slice(&mesh.corners(t));
                out.1.push((t as u32, [Vec3::X, Vec3::Y, Vec3::Z]));
            }
            continue;
        }
        for t in triangles {
            clip_triangle(&planes, t, mesh.corners(t), &mut out);
        }
    }
    Tessellation::new(out.0, out.1)
}

/// The visible point of the source mesh a fragment of a clipped piece shows (a visibility
/// buffer of the source drawn through its pieces).
struct SourcePoint<'a> {
    /// Source triangle and corner barycentrics of each piece.
    source: &'a [SourceTriangle],
    /// The frustum drawing them.
    frustum: u32,
}

impl FragmentShader for SourcePoint<'_> {
    type Output = Option<Visible>;
    fn shade(&self, f: &Fragment) -> Option<Visible> {
        let b = full_barycentrics(Vec2::new(f.bary.y, f.bary.z));
        Some(Visible {
            frustum: Some(self.frustum),
            ..to_source(Some(self.source), f.item.triangle, b)
        })
    }
}

/// A colour function that returns the mesh's albedo (material colour × texture), unlit.
pub fn albedo_of(mesh: &Mesh) -> impl Fn(&SurfaceSample) -> Vec3 + Sync + '_ {
    move |s: &SurfaceSample| {
        let m = mesh
            .face_material
            .get(s.triangle as usize)
            .copied()
            .unwrap_or(0);
        match mesh.materials.get(m as usize) {
            Some(mat) => match &mat.texture {
                Some(t) => {
                    mat.base_color * t.sample_uv(s.uv, crate::frame::Wrap::Repeat).truncate()
                }
                None => mat.base_color,
            },
            None => Vec3::splat(0.8),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Spoc;
    use crate::raster::rasterize;

    #[test]
    fn a_shading_normal_packs_as_its_unit_vector_and_falls_back_to_the_face() {
        // Packing skips the normalization: the code must be that of the unit normal (at most a
        // rounding step apart), and a zero or non-finite normal gives the face's.
        let mut rng = crate::geom::SplitMix64::new(3);
        for _ in 0..10_000 {
            let n = rng.unit_vector() * (0.01 + 100.0 * rng.next_f32());
            let (a, b) = (pack_normal(n, Vec3::X), pack_unit(n.normalize()));
            assert!((a[0] - b[0]).abs() <= 1 && (a[1] - b[1]).abs() <= 1, "{n}");
        }
        let face = Vec3::new(0.0, 3.0, -4.0);
        for bad in [
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
        ] {
            assert_eq!(pack_normal(bad, face), pack_unit(face), "{bad}");
        }
    }

    /// Clipping group by group gives the pieces of clipping each triangle, and drawing every
    /// frustum's pieces over one image equals drawing each into an image of its own and keeping,
    /// per texel, the largest `gd` in frustum order (§4.5 as first written): on the demo maze
    /// with four spheres in its corridors, through its 34 frusta, every map is identical.
    #[test]
    fn graph_frusta_drawn_over_one_image_equal_their_merged_images() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/maze.maze");
        let maze = crate::scene::maze::Maze::load(&path).unwrap();
        let g = maze.graph_camera(160, &path).unwrap();
        let mesh = maze.with_objects(&crate::geom::icosphere(3), 4);
        let groups = group_bounds(&mesh);
        let color = albedo_of(&mesh);
        let imp = build(ImpostorCamera::Graph(g.clone()), &mesh, 2, &color).unwrap();
        // The per-frustum merge.
        let (w, h) = g.resolution();
        let mut gd = Image::new(w, h, 0.0f32).unwrap();
        let mut visible: Vec<Option<Visible>> = vec![None; (w * h) as usize];
        for j in 0..g.frusta().len() {
            let planes = frustum_planes(&g, j);
            let mut out = (Vec::new(), Vec::new());
            for t in 0..mesh.triangles.len() {
                clip_triangle(&planes, t, mesh.corners(t), &mut out);
            }
            let piece = Tessellation::new(out.0, out.1);
            let grouped = clip_to_frustum(&g, j, &mesh, &groups);
            assert!(
                grouped.mesh.positions == piece.mesh.positions,
                "frustum {j}"
            );
            assert!(grouped.source == piece.source, "frustum {j}");
            if piece.source.is_empty() {
                continue;
            }
            let (t, _) =
                rasterize(&g.frustum(j), &[&piece.mesh], &Barycentrics, Vec2::ZERO).unwrap();
            for (i, &g_new) in t.gd.pixels().iter().enumerate() {
                if g_new > gd.pixels()[i] {
                    gd.pixels_mut()[i] = g_new;
                    let b = full_barycentrics(t.attributes.pixels()[i]);
                    let tri = t.item.pixels()[i].triangle;
                    visible[i] = Some(Visible {
                        frustum: Some(j as u32),
                        ..to_source(Some(&piece.source), tri, b)
                    });
                }
            }
        }
        let mut merged = zeroed_impostor(ImpostorCamera::Graph(g.clone())).unwrap();
        merged.gd = gd;
        resolve(&mut merged, (&mesh, 2), &color, MapsBefore::Zeroed, |i| {
            visible[i]
        });
        assert!(imp.coverage() > 0.3, "{}", imp.coverage());
        assert!(imp.gd == merged.gd && imp.position_image() == merged.position_image());
        assert!(imp.color == merged.color && imp.normal == merged.normal);
        assert!(imp.face_normal == merged.face_normal && imp.object == merged.object);
        assert_eq!(imp.bounds, merged.bounds);
    }

    #[test]
    fn a_tessellated_impostor_rebuilt_equals_a_fresh_build() {
        // Through a curved camera a coarse mesh is tessellated before anything is drawn: a
        // rebuild over an older impostor's maps must clear them as a fresh build starts empty.
        let sphere = crate::geom::icosphere(1);
        let spoc = Spoc::around(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.5, 1.2, 256).unwrap();
        assert!(
            tessellate(&spoc, &sphere).is_some(),
            "the case must tessellate"
        );
        let camera = ImpostorCamera::Spoc(spoc);
        let color = |s: &SurfaceSample| s.normal.abs();
        let mut builder = ImpostorBuilder::new();
        let mut imp = builder.build(camera.clone(), &sphere, 3, &color).unwrap();
        let moved = sphere.transformed(
            &(glam::Mat4::from_translation(Vec3::new(0.2, -0.1, 0.0))
                * glam::Mat4::from_scale(Vec3::splat(0.5))),
        );
        builder.rebuild(&mut imp, &moved, 3, &color).unwrap();
        let fresh = build(camera, &moved, 3, &color).unwrap();
        assert!(imp.gd == fresh.gd && imp.color == fresh.color && imp.object == fresh.object);
        assert!(imp.normal == fresh.normal && imp.face_normal == fresh.face_normal);
        assert!(fresh.coverage() > 0.01);
    }

    #[test]
    fn spoc_tessellation_splits_big_triangles_without_cracks() {
        // A coarse sphere seen by a SPOC aimed at its centre images to a disc: every row of the
        // image must be covered on one interval, with no pinholes between shared edges.
        let sphere = crate::geom::icosphere(1);
        let spoc = Spoc::around(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.5, 1.2, 512).unwrap();
        let tess = tessellate(&spoc, &sphere).expect("big triangles must split");
        assert!(
            tess.source.len() > 2 * sphere.triangle_count(),
            "{}",
            tess.source.len()
        );
        let imp = build(
            ImpostorCamera::Spoc(spoc.clone()),
            &sphere,
            0,
            &|_: &SurfaceSample| Vec3::ONE,
        )
        .unwrap();
        let mut rows_checked = 0;
        for y in 0..512 {
            let covered: Vec<u32> = (0..512).filter(|&x| imp.gd.get(x, y) > 0.0).collect();
            if let (Some(&first), Some(&last)) = (covered.first(), covered.last()) {
                assert_eq!(covered.len() as u32, last - first + 1, "row {y} has a hole");
                rows_checked += 1;
            }
        }
        assert!(rows_checked > 20);
        // The builder drew the tessellation, not the coarse mesh: the rasterizer flagged the
        // coarse triangles as curved.
        let shader = crate::raster::NoAttributes;
        let (coarse, stats) = rasterize(&spoc, &[&sphere], &shader, ()).unwrap();
        assert!(stats.curved > 0 && stats.clipped == 0, "{stats:?}");
        let (fine, _) = rasterize(&spoc, &[&tess.mesh], &shader, ()).unwrap();
        let covered = |gd: &Image<f32>| gd.pixels().iter().map(|&g| g > 0.0).collect::<Vec<_>>();
        assert!(covered(&imp.gd) == covered(&fine.gd) && covered(&imp.gd) != covered(&coarse.gd));
        // The resolve moved each texel's gd onto its triangle's plane: by a fraction of it.
        let moved = (imp.gd.pixels().iter().zip(fine.gd.pixels()))
            .map(|(&a, &b)| ((a - b) / b.max(1e-6)).abs())
            .fold(0.0f32, f32::max);
        assert!(moved < 0.01, "{moved}");
        let pinhole = rasterize(spoc.pinhole(), &[&sphere], &shader, ())
            .unwrap()
            .1;
        assert_eq!(pinhole.curved, 0);
        // Every stored position lies on the sphere's triangles (radius between inscribed and 0.5).
        for (p, &g) in imp.position_image().pixels().iter().zip(imp.gd.pixels()) {
            if g > 0.0 {
                assert!(p.length() <= 0.5 + 1e-5 && p.length() > 0.39, "{p}");
            }
        }
    }
}
