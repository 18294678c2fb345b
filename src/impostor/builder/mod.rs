//! Impostor construction (paper 1 §3.1; docs/conventions.md §2.2): rasterize the mesh through the
//! camera, keeping the largest `gd`; through a curved camera, when the rasterizer's set-up finds
//! triangles curved beyond half a pixel, the mesh is tessellated adaptively before anything is
//! drawn, and the tessellation drawn instead. Through a graph camera (§4.5), each frustum draws
//! the pieces of the triangles clipped to it, over one image.

mod clip;
mod drawn;
mod resolve;
mod tessellate;

use clip::*;
pub use drawn::{DrawnError, DrawnImage, DrawnTexel, resolve_drawn};
pub(super) use resolve::impostor_bounds;
use resolve::*;
pub(super) use resolve::{
    Barycentrics, MapsBefore, Visible, full_barycentrics, resolve, to_source, zeroed_impostor,
};
use tessellate::*;
pub use tessellate::{SourceTriangle, Tessellation, tessellate};

use super::{Impostor, ImpostorCamera};
use crate::camera::Spoc;
use crate::camera::{ImagePoint, Projection};
use crate::frame::packed::{HalfRgba, OctUnit, OpaquePacker, ZERO_UNIT, pack_unit};
use crate::frame::{FrameError, Image, texel_centre};
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
    /// maps. The result equals a fresh [`build`]: depth layers it held are dropped (peel
    /// again with [`Impostor::peel`]).
    pub fn rebuild<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        impostor: &mut Impostor,
        mesh: &Mesh,
        object: u32,
        color: &F,
    ) -> Result<(), FrameError> {
        impostor.deeper.clear();
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
        let setup = set_up(projection, &[mesh], &mut self.raster)?;
        let pieces = if curved && setup.stats().has_curved_or_clipped() {
            tessellate_with(projection, mesh, &mut self.tessellation)?
        } else {
            None
        };
        match &pieces {
            None => draw_and_resolve(setup, impostor, source, None, color, before)?,
            Some(t) => {
                let setup = set_up(projection, &[&t.mesh], &mut self.raster)?;
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
        let pieces = graph_pieces(g, mesh);
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

/// What a graph camera's image is drawn from (§4.5): per frustum, in order, the pieces of
/// `mesh`'s triangles clipped to it, each named by its source triangle. Drawn through each
/// frustum's own matrix over one image, the largest `gd` kept and ties to the earlier frustum,
/// they make the image [`ImpostorBuilder::build`] draws, and [`resolve_drawn`] resolves.
pub fn graph_pieces(g: &crate::camera::GraphCamera, mesh: &Mesh) -> Vec<Tessellation> {
    let groups = group_bounds(mesh);
    (0..g.frusta().len())
        .into_par_iter()
        .map(|j| clip_to_frustum(g, j, mesh, &groups))
        .collect()
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
    let inputs = ResolveInputs::of(impostor, (mesh, object), color, before);
    let (gd, runs) = impostor.gd_and_texel_runs((BAND_ROWS * w) as usize);
    let spoc = match &inputs.camera {
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
            tessellate(&spoc, &sphere).unwrap().is_some(),
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
        let tess = tessellate(&spoc, &sphere)
            .unwrap()
            .expect("big triangles must split");
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
