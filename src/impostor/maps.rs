//! An impostor: its camera, its compact per-texel maps and the bounding box of what it
//! replaces (paper 1 §3; docs/conventions.md §1.2), the walks' index derived from the maps on
//! first use, and the depth layers behind it.
//!
//! Invariant: the impostor never consults the mesh after it is built; a texel's world position
//! is the point of its camera ray at its `gd`, on the plane of the stored triangle.

use super::{ImpostorCamera, MaxPyramid, TexelPlane, builder, front, planes, walk};
use crate::camera::Projection;
use crate::frame::Image;
use crate::frame::packed::{HalfRgba, OctUnit, unpack_rgba, unpack_unit};
use crate::geom::Aabb;
use glam::{DVec2, Vec3, Vec4};

/// An impostor's hit agrees with the exact one within this many of its texel's footprints.
pub const AGREEMENT_FOOTPRINTS: f64 = 1.5;

/// A depth image that stands in for geometry.
///
/// Its maps are compact (24 bytes a texel through a pinhole, orthographic or SPOC camera):
/// colour in half floats and normals in the octahedral encoding ([`crate::frame::packed`]),
/// read through [`Impostor::color_at`], [`Impostor::normal_at`] and
/// [`Impostor::face_normal_at`]. A texel's world position is the point of its camera ray at its
/// `gd` ([`Impostor::position_at`]); only a graph camera, whose rays bend at faces between
/// frusta, keeps it in a map.
#[derive(Clone, Debug)]
pub struct Impostor {
    /// The camera it was built through.
    pub(super) camera: ImpostorCamera,
    /// Linear radiance of the surface each texel shows, in half floats (alpha 1 where covered,
    /// 0 where empty).
    pub(super) color: Image<HalfRgba>,
    /// Generalized depth (0 = empty).
    pub(super) gd: Image<f32>,
    /// Unit shading normal, packed.
    pub(super) normal: Image<OctUnit>,
    /// Unit geometric normal of the stored triangle, turned toward the camera, packed: with the
    /// texel's position, the texel's plane. The walk measures which side of it a ray sample is
    /// on, and places hits on it.
    pub(super) face_normal: Image<OctUnit>,
    /// World position of the surface point, for a graph camera only (see
    /// [`Impostor::position_at`]).
    pub(super) position: Option<Image<Vec3>>,
    /// Object id ([`crate::geom::NO_OBJECT`] where empty).
    pub(super) object: Image<u32>,
    /// World box of the replaced geometry: rays are clipped to it.
    pub(super) bounds: Aabb,
    /// What the walks derive from the maps, built on first use: the max pyramid of the
    /// texels' front bounds (the largest `gd` of a point behind a texel's plane, 0 where empty;
    /// `front.rs`) and the packed [`TexelPlane`]s. Call [`Impostor::maps_changed`] after
    /// editing the maps.
    pub(super) walk_index: std::sync::OnceLock<WalkIndex>,
    /// The depth layers behind this one, nearest first, peeled through the same camera
    /// (`peel.rs`); each holds no layers of its own. Empty for a plain impostor.
    pub(super) deeper: Vec<Impostor>,
}

/// See [`Impostor::pyramid`], [`Impostor::texel_planes`] and [`Impostor::exit_margin`].
#[derive(Clone, Debug)]
pub(super) struct WalkIndex {
    pub(super) pyramid: MaxPyramid,
    pub(super) planes: Image<TexelPlane>,
    pub(super) exit_margin: f32,
}

impl Impostor {
    /// An impostor from its camera, maps and box (the maps all of the camera's size; empty
    /// texels hold `gd` 0 and [`crate::geom::NO_OBJECT`]). `position` is kept for a graph
    /// camera, which needs it, and ignored otherwise (see [`Impostor::position_at`]).
    #[allow(clippy::too_many_arguments)]
    pub fn from_maps(
        camera: ImpostorCamera,
        color: Image<HalfRgba>,
        gd: Image<f32>,
        normal: Image<OctUnit>,
        face_normal: Image<OctUnit>,
        position: Option<Image<Vec3>>,
        object: Image<u32>,
        bounds: Aabb,
    ) -> Impostor {
        let position = position.filter(|_| camera.stores_positions());
        Impostor {
            camera,
            color,
            gd,
            normal,
            face_normal,
            position,
            object,
            bounds,
            walk_index: std::sync::OnceLock::new(),
            deeper: Vec::new(),
        }
    }

    /// The camera it was built through.
    pub fn camera(&self) -> &ImpostorCamera {
        &self.camera
    }

    /// The colour map: linear radiance (or albedo, as baked) in half floats, alpha 1 where
    /// covered ([`Impostor::color_at`] reads one texel).
    pub fn color(&self) -> &Image<HalfRgba> {
        &self.color
    }

    /// The generalized-depth map (`gd = 1/t`, 0 = empty; `docs/conventions.md` §1.2).
    pub fn gd(&self) -> &Image<f32> {
        &self.gd
    }

    /// The shading normals, packed ([`Impostor::normal_at`] reads one).
    pub fn normal(&self) -> &Image<OctUnit> {
        &self.normal
    }

    /// The stored triangles' face normals, turned toward the camera, packed
    /// ([`Impostor::face_normal_at`] reads one).
    pub fn face_normal(&self) -> &Image<OctUnit> {
        &self.face_normal
    }

    /// The object ids ([`crate::geom::NO_OBJECT`] where empty).
    pub fn object(&self) -> &Image<u32> {
        &self.object
    }

    /// World box of the replaced geometry: rays are clipped to it.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Gives every covered texel the object id `id` (an impostor baked with one id, placed in
    /// a scene where its object has another).
    pub fn set_object_id(&mut self, id: u32) {
        for o in self.object.pixels_mut() {
            if *o != crate::geom::NO_OBJECT {
                *o = id;
            }
        }
        for layer in &mut self.deeper {
            layer.set_object_id(id);
        }
    }

    /// Colour of texel `(x, y)`.
    #[inline]
    pub fn color_at(&self, x: u32, y: u32) -> Vec4 {
        unpack_rgba(self.color.get(x, y))
    }

    /// Unit shading normal of texel `(x, y)` (zero where empty).
    #[inline]
    pub fn normal_at(&self, x: u32, y: u32) -> Vec3 {
        self.unit_at(&self.normal, x, y)
    }

    /// Unit face normal of texel `(x, y)`, turned toward the camera (zero where empty).
    #[inline]
    pub fn face_normal_at(&self, x: u32, y: u32) -> Vec3 {
        self.unit_at(&self.face_normal, x, y)
    }

    pub(super) fn unit_at(&self, map: &Image<OctUnit>, x: u32, y: u32) -> Vec3 {
        if self.gd.get(x, y) > 0.0 {
            unpack_unit(map.get(x, y))
        } else {
            Vec3::ZERO
        }
    }

    /// Replaces the colour of every covered texel by `shade(colour, shading normal, position)`
    /// — for instance an albedo baked by `trompe impostor bake` lit by a scene's lights, as the
    /// impostor method lights the impostors it builds. Empty texels keep theirs. Rows are shaded
    /// in parallel; the result does not depend on the thread count.
    pub fn relight<F: Fn(Vec3, Vec3, Vec3) -> Vec3 + Sync>(&mut self, shade: F) {
        self.relight_layer(&shade);
        for layer in &mut self.deeper {
            layer.relight_layer(&shade);
        }
    }

    /// [`Impostor::relight`] of this layer's maps.
    pub(super) fn relight_layer<F: Fn(Vec3, Vec3, Vec3) -> Vec3 + Sync>(&mut self, shade: &F) {
        use rayon::prelude::*;
        let (w, _) = self.gd.size();
        let mut color = self.color.clone();
        color
            .pixels_mut()
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    let (x, y) = (x as u32, y as u32);
                    if self.gd.get(x, y) > 0.0 {
                        let c = self.color_at(x, y);
                        let lit = shade(c.truncate(), self.normal_at(x, y), self.position_at(x, y));
                        *texel = crate::frame::packed::pack_rgba(lit.extend(c.w));
                    }
                }
            });
        self.color = color;
    }

    /// World position of the surface point texel `(x, y)` shows (zero where empty): the point
    /// of the camera's ray through the texel's centre at the texel's `gd`. The rasterizer
    /// interpolates `gd = 1/t` at pixel centres, so through a pinhole or orthographic camera
    /// this is the point where the centre's ray meets the stored triangle; through a SPOC, whose
    /// rays curve, the triangle is drawn straight in the image when it curves by less than half
    /// a pixel (§2.2), and the point is within that of it. A graph camera's rays bend where
    /// frusta meet and a texel's `gd` alone may not say which frustum holds the point: it keeps
    /// positions in a map.
    #[inline]
    pub fn position_at(&self, x: u32, y: u32) -> Vec3 {
        if let Some(map) = &self.position {
            return map.get(x, y);
        }
        let gd = self.gd.get(x, y);
        if gd <= 0.0 {
            return Vec3::ZERO;
        }
        let centre = crate::frame::pixel_centre(x as f64, y as f64);
        self.camera.unproject(centre, gd as f64).as_vec3()
    }

    /// Every texel's colour, as an image (for files, previews and billboards).
    pub fn color_image(&self) -> Image<crate::frame::Rgba> {
        self.map_image(|x, y| self.color_at(x, y))
    }

    /// Every texel's shading normal, as an image.
    pub fn normal_image(&self) -> Image<Vec3> {
        self.map_image(|x, y| self.normal_at(x, y))
    }

    /// Every texel's face normal, as an image.
    pub fn face_normal_image(&self) -> Image<Vec3> {
        self.map_image(|x, y| self.face_normal_at(x, y))
    }

    /// Every texel's world position, as an image.
    pub fn position_image(&self) -> Image<Vec3> {
        self.map_image(|x, y| self.position_at(x, y))
    }

    /// The image of `f(x, y)` over the impostor's texels, rows in parallel.
    pub(super) fn map_image<T: Copy + Default + Send + Sync>(
        &self,
        f: impl Fn(u32, u32) -> T + Sync,
    ) -> Image<T> {
        use rayon::prelude::*;
        let (w, h) = self.gd.size();
        let mut data = vec![T::default(); w as usize * h as usize];
        data.par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, v) in row.iter_mut().enumerate() {
                    *v = f(x as u32, y as u32);
                }
            });
        Image::from_vec(w, h, data).expect("the size of the impostor's maps")
    }

    /// The pyramid of front bounds the walk steps over nodes with — for a layered impostor,
    /// the largest of every layer's — built on the first walk (so building an impostor that
    /// is never walked does not pay for it).
    pub fn pyramid(&self) -> &MaxPyramid {
        &self.walk_index().pyramid
    }

    /// Builds now what the walks derive from the maps (the pyramid and the texel planes),
    /// rather than on the first walk: before walking from many threads at once, which would
    /// otherwise each build it.
    pub fn prepare_walks(&self) {
        for layer in self.layers() {
            layer.walk_index();
        }
    }

    /// The texels as the walks read them, packed ([`TexelPlane`]), built with the pyramid.
    pub fn texel_planes(&self) -> &Image<TexelPlane> {
        &self.walk_index().planes
    }

    /// Built in parallel outside the cell, then stored: a rayon worker waiting inside
    /// `OnceLock::get_or_init` for its parallel build may steal another job that walks this
    /// impostor and enter the same initialization again — a deadlock. Here two threads that
    /// meet the empty cell at once both build (the same index), and one result is kept.
    pub(super) fn walk_index(&self) -> &WalkIndex {
        if let Some(index) = self.walk_index.get() {
            return index;
        }
        let mut front = front::front_bounds(self);
        let planes = planes::texel_planes(self, front.pixels());
        // The walk tests every layer at each texel: it may step over a node only in front of
        // them all.
        for layer in &self.deeper {
            for (mine, theirs) in front
                .pixels_mut()
                .iter_mut()
                .zip(layer.pyramid().level(0).pixels())
            {
                *mine = mine.max(*theirs);
            }
        }
        let pyramid = MaxPyramid::new(&front);
        let exit_margin = walk::exit_margin(self);
        let _ = self.walk_index.set(WalkIndex {
            pyramid,
            planes,
            exit_margin,
        });
        self.walk_index.get().expect("the cell was just set")
    }

    /// How far past [`Impostor::bounds`] a walk goes on before it gives up on a ray (see
    /// `walk::exit_margin`), derived with the pyramid.
    pub fn exit_margin(&self) -> f32 {
        self.walk_index().exit_margin
    }

    /// Drops what the walks derived from the maps after they were edited; the next walk
    /// rebuilds it.
    pub fn maps_changed(&mut self) {
        self.walk_index = std::sync::OnceLock::new();
    }

    /// Stored `gd` at image point `uv` (nearest texel; 0 outside the image).
    #[inline]
    pub fn gd_at(&self, uv: DVec2) -> f32 {
        match self.texel(uv) {
            Some((x, y)) => self.gd.get(x, y),
            None => 0.0,
        }
    }

    /// The texel containing image point `uv`, if inside the image.
    #[inline]
    pub fn texel(&self, uv: DVec2) -> Option<(u32, u32)> {
        let (w, h) = self.gd.size();
        // Compared before truncating: for non-negative values truncation is the floor, and
        // `f64::floor` without SSE 4.1 is a library call, once per walk sample. NaN fails here.
        (uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w as f64 && uv.y < h as f64)
            .then_some((uv.x as u32, uv.y as u32))
    }

    /// The footprint ([`Impostor::footprint`]) of the texel the world point `p` projects to;
    /// infinite where it projects nowhere.
    pub fn footprint_of(&self, p: Vec3) -> f64 {
        self.camera
            .project(p.as_dvec3())
            .map_or(f64::INFINITY, |q| self.footprint(q.uv, q.gd))
    }

    /// Whether the impostor's answer `own` to a ray agrees with the exact answer `exact`: both
    /// miss, or both hit within [`AGREEMENT_FOOTPRINTS`] footprints of the texel at the exact
    /// hit (`docs/fidelity.md`).
    pub fn agrees(
        &self,
        exact: Option<&crate::trace::Hit>,
        own: Option<&crate::trace::Hit>,
    ) -> bool {
        match (exact, own) {
            (None, None) => true,
            (Some(e), Some(i)) => {
                f64::from(e.position.distance(i.position))
                    <= AGREEMENT_FOOTPRINTS * self.footprint_of(e.position)
            }
            _ => false,
        }
    }

    /// World size of one texel at image point `uv` and depth `gd` (its footprint). For a
    /// graph camera, measured with the matrix of the frustum holding the point, so a texel
    /// next to a face between frusta does not span both.
    pub fn footprint(&self, uv: DVec2, gd: f64) -> f64 {
        fn size<P: Projection>(camera: &P, uv: DVec2, gd: f64) -> f64 {
            let p = camera.unproject(uv, gd);
            let px = camera.unproject(uv + DVec2::X, gd);
            let py = camera.unproject(uv + DVec2::Y, gd);
            (px - p).length().max((py - p).length())
        }
        match &self.camera {
            ImpostorCamera::Graph(g) => {
                let j = g.locate(g.unproject(uv, gd)).unwrap_or(0);
                size(&g.frustum(j), uv, gd)
            }
            ImpostorCamera::Pinhole(c) => size(c, uv, gd),
            ImpostorCamera::Orthographic(c) => size(c, uv, gd),
            ImpostorCamera::Spoc(c) => size(c, uv, gd),
        }
    }

    /// Whether building an impostor of `mesh` as it is now gives this one's box — the check that
    /// a loaded impostor goes with a mesh, in the same coordinates (to 10⁻⁵ of its extent).
    pub fn was_built_from(&self, mesh: &crate::geom::Mesh) -> bool {
        let expected = builder::impostor_bounds(mesh);
        let tolerance = expected.extent().max_element() * 1e-5;
        (self.bounds.min - expected.min).abs().max_element() <= tolerance
            && (self.bounds.max - expected.max).abs().max_element() <= tolerance
    }

    /// Bytes its maps take, every layer's (what the walks derive from them is built on
    /// demand and not counted).
    pub fn map_bytes(&self) -> u64 {
        self.layers()
            .map(|l| {
                let texels = l.gd.pixels().len() as u64;
                let per_texel = 24 + if l.position.is_some() { 12 } else { 0 };
                texels * per_texel
            })
            .sum()
    }

    /// Fraction of texels that are covered.
    pub fn coverage(&self) -> f64 {
        self.gd.pixels().iter().filter(|&&g| g > 0.0).count() as f64 / self.gd.pixels().len() as f64
    }
}

/// What `trompe info` says of a baked impostor ([`Impostor::summary`]).
pub struct ImpostorSummary<'a> {
    path: &'a std::path::Path,
    impostor: &'a Impostor,
}

impl Impostor {
    /// Camera, size, viewpoint, coverage and box, for printing.
    pub fn summary<'a>(&'a self, path: &'a std::path::Path) -> ImpostorSummary<'a> {
        ImpostorSummary {
            path,
            impostor: self,
        }
    }
}

/// As JSON: every figure the text shows.
impl serde::Serialize for ImpostorSummary<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let imp = self.impostor;
        let (w, h) = imp.gd.size();
        let b = imp.bounds;
        let mut doc = serde_json::json!({
            "kind": "impostor",
            "path": self.path,
            "camera": imp.camera.kind(),
            "size": [w, h],
            "viewpoint": imp.camera.viewpoint().to_array(),
            "coverage": imp.coverage(),
            "layers": imp.layers().map(|l| l.coverage()).collect::<Vec<_>>(),
            "map_bytes": imp.map_bytes(),
            "bounds": { "min": b.min.to_array(), "max": b.max.to_array() },
        });
        match &imp.camera {
            ImpostorCamera::Spoc(c) => {
                let (near, far) = c.depth_range();
                doc["spoc"] =
                    serde_json::json!({ "strength": c.strength(), "depth_range": [near, far] });
            }
            ImpostorCamera::Graph(g) => doc["frusta"] = g.frusta().len().into(),
            ImpostorCamera::Pinhole(_) | ImpostorCamera::Orthographic(_) => {}
        }
        doc.serialize(s)
    }
}

impl std::fmt::Display for ImpostorSummary<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let imp = self.impostor;
        let (w, h) = imp.gd.size();
        let v = imp.camera.viewpoint();
        writeln!(f, "{}", self.path.display())?;
        writeln!(
            f,
            "  impostor   {} camera, {w}×{h} texels",
            imp.camera.kind()
        )?;
        writeln!(f, "  viewpoint  [{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z)?;
        match &imp.camera {
            ImpostorCamera::Spoc(s) => {
                let (near, far) = s.depth_range();
                writeln!(
                    f,
                    "  SPOC       strength k = {:.4}, depth ramp from {near:.4} to {far:.4}",
                    s.strength()
                )?;
            }
            ImpostorCamera::Graph(g) => writeln!(f, "  frusta     {}", g.frusta().len())?,
            ImpostorCamera::Pinhole(_) | ImpostorCamera::Orthographic(_) => {}
        }
        writeln!(f, "  covered    {:.1} % of texels", imp.coverage() * 100.0)?;
        if imp.layer_count() > 1 {
            let shares: Vec<String> = imp
                .layers()
                .map(|l| format!("{:.1} %", l.coverage() * 100.0))
                .collect();
            writeln!(
                f,
                "  layers     {} (covering {} of texels)",
                imp.layer_count(),
                shares.join(", ")
            )?;
        }
        writeln!(f, "  maps       {:.1} MB", imp.map_bytes() as f64 / 1e6)?;
        let b = imp.bounds;
        write!(
            f,
            "  bounds     [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
            b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
        )
    }
}
