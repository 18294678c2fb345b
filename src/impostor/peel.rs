//! Layered impostors: depth layers peeled through one camera (beyond paper 1, whose §2.3 walk
//! reads one layer; docs/conventions.md §2.5).
//!
//! One depth image holds, per texel, the nearest surface its camera sees; a reflected ray that
//! passes behind an occluding edge meets surface the image never held. Layer `l + 1` holds, per
//! texel, the nearest surface strictly behind layer `l`'s (depth peeling: the mesh is drawn again
//! with layer `l`'s depth, moved [`PEEL_GAP`] nearer the camera, as a ceiling —
//! [`crate::raster::rasterize_behind`]). Layers after the first hold only triangles whose front
//! (by the mesh's winding) faces the camera: the rays an impostor answers come from around its
//! camera, and meet a back face only from inside the object. Every layer is an [`Impostor`] of its own — the same
//! camera, box and maps — and a walk answers a ray with the nearest crossing of any layer's
//! surface. A device may draw the layers ([`Impostor::peel_drawn`]: a GPU's rasterizer under the
//! same ceiling); the library still chooses the triangles, stops and resolves.
//!
//! Invariants: every layer has the first layer's camera and box; a texel covered in layer
//! `l + 1` is covered in layer `l`, with a larger `gd` there (as drawn, before a SPOC's resolve
//! moves `gd` onto the stored plane); no layer is empty.

use super::builder::{
    Barycentrics, DrawnError, DrawnImage, MapsBefore, Visible, full_barycentrics, resolve,
    resolve_drawn, to_source,
};
use super::{Impostor, ImpostorCamera, SurfaceSample, tessellate};
use crate::camera::Projection;
use crate::frame::{FrameError, Image};
use crate::geom::Mesh;
use crate::raster::{NoAttributes, rasterize, rasterize_behind};
use glam::{Vec2, Vec3};
use thiserror::Error;

/// The most layers an impostor holds.
pub const MAX_LAYERS: u32 = 8;
/// [`Layers::Auto`] adds a layer while it holds more than this share of the first layer's
/// covered texels.
pub const AUTO_SHARE: f64 = 0.01;
/// How much nearer the camera than layer `l`'s drawn `gd` (relative) the ceiling of layer
/// `l + 1` lies: a surface drawn twice (coincident faces) is one layer, not two.
pub const PEEL_GAP: f32 = 1e-4;

/// How many depth layers to peel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Layers {
    /// At most this many (1 to [`MAX_LAYERS`]): peeling stops early at a layer that would hold
    /// nothing.
    Count(u32),
    /// Layers are added while a new one holds more than [`AUTO_SHARE`] of the first layer's
    /// covered texels, at most [`MAX_LAYERS`].
    #[default]
    Auto,
}

impl Layers {
    /// One layer: a plain impostor.
    pub const ONE: Layers = Layers::Count(1);
}

impl std::fmt::Display for Layers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Layers::Count(n) => write!(f, "{n}"),
            Layers::Auto => write!(f, "auto"),
        }
    }
}

impl std::str::FromStr for Layers {
    type Err = LayerError;
    /// `auto`, or a count from 1 to [`MAX_LAYERS`].
    fn from_str(s: &str) -> Result<Layers, LayerError> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Layers::Auto);
        }
        let count = s.parse::<u32>().map_err(|_| LayerError::NotACount {
            given: s.to_string(),
        })?;
        Layers::Count(count).checked()
    }
}

impl Layers {
    /// The most layers peeled, the first included.
    fn most(self) -> usize {
        match self {
            Layers::Count(n) => n as usize,
            Layers::Auto => MAX_LAYERS as usize,
        }
    }

    /// Whether a new layer covering `covered` texels is kept, the first layer covering `first`.
    fn keeps(self, covered: usize, first: usize) -> bool {
        match self {
            Layers::Auto => covered as f64 > AUTO_SHARE * first as f64,
            Layers::Count(_) => covered > 0,
        }
    }

    /// The setting, if its count is in range.
    pub fn checked(self) -> Result<Layers, LayerError> {
        match self {
            Layers::Count(count) if !(1..=MAX_LAYERS).contains(&count) => {
                Err(LayerError::Count { count })
            }
            ok => Ok(ok),
        }
    }
}

/// Why layers could not be peeled.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LayerError {
    /// A layer count out of range.
    #[error("{count} layers: between 1 and {MAX_LAYERS}, or auto")]
    Count {
        /// The count asked for.
        count: u32,
    },
    /// Not a count.
    #[error("layers {given:?}: a count from 1 to {MAX_LAYERS}, or auto")]
    NotACount {
        /// What was given.
        given: String,
    },
    /// A graph camera's frusta draw over one image in turn; peeling them is not done.
    #[error(
        "a graph-camera impostor holds one layer (its frusta are drawn in turn over one image); use --layers 1"
    )]
    GraphCamera,
    /// A layer's maps could not be allocated.
    #[error("peeling a layer: {0}")]
    Maps(#[from] FrameError),
    /// A layer drawn elsewhere ([`Impostor::peel_drawn`]) could not be resolved.
    #[error("a layer drawn elsewhere: {0}")]
    Drawn(#[from] DrawnError),
    /// The device drawing a layer failed, with its reason.
    #[error("drawing a layer: {0}")]
    Device(String),
}

impl Impostor {
    /// How many depth layers it holds (1 for a plain impostor).
    pub fn layer_count(&self) -> usize {
        1 + self.deeper.len()
    }

    /// Layer `l` (0: this impostor's own maps; then each the surface behind the one before).
    pub fn layer(&self, l: usize) -> Option<&Impostor> {
        match l {
            0 => Some(self),
            _ => self.deeper.get(l - 1),
        }
    }

    /// Every layer, nearest first.
    pub fn layers(&self) -> impl Iterator<Item = &Impostor> {
        std::iter::once(self).chain(&self.deeper)
    }

    /// Peels the layers behind this impostor's surface from `mesh` (the mesh it was built
    /// from, object id `object`, coloured by `color`), replacing any it held.
    ///
    /// # Errors
    /// A count out of range, a graph camera asked for more than one layer, or maps that cannot
    /// be allocated.
    pub fn peel<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        mesh: &Mesh,
        object: u32,
        color: &F,
        layers: Layers,
    ) -> Result<(), LayerError> {
        let Some(layers) = self.start_peeling(layers)? else {
            return Ok(());
        };
        let camera = self.camera.clone();
        match &camera {
            ImpostorCamera::Pinhole(c) => self.peel_through(c, mesh, object, color, layers),
            ImpostorCamera::Orthographic(c) => self.peel_through(c, mesh, object, color, layers),
            ImpostorCamera::Spoc(c) => self.peel_through(c, mesh, object, color, layers),
            ImpostorCamera::Graph(_) => Err(LayerError::GraphCamera),
        }
    }

    /// Drops the layers it held and checks `layers`: the layers to peel, or `None` for one
    /// layer (nothing to peel).
    fn start_peeling(&mut self, layers: Layers) -> Result<Option<Layers>, LayerError> {
        let layers = layers.checked()?;
        self.deeper.clear();
        self.maps_changed();
        match (layers, &self.camera) {
            (Layers::ONE, _) => Ok(None),
            (_, ImpostorCamera::Graph(_)) => Err(LayerError::GraphCamera),
            _ => Ok(Some(layers)),
        }
    }

    fn peel_through<P: Projection, F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        projection: &P,
        mesh: &Mesh,
        object: u32,
        color: &F,
        layers: Layers,
    ) -> Result<(), LayerError> {
        // Deeper layers hold surfaces facing the camera (by the mesh's winding): a back face
        // behind the first layer is met only from inside the object, by no ray from outside it,
        // while a walk from the camera's side would take it for the surface the ray passed.
        let (facing, kept) = facing_camera(mesh, &self.camera);
        // Through a curved camera, drawn tessellated, as the first layer was.
        let tessellated = |m: &Mesh| match self.camera.is_curved() {
            true => tessellate(projection, m).map_err(FrameError::from),
            false => Ok(None),
        };
        let pieces = tessellated(&facing)?;
        let (drawn, source) = match &pieces {
            Some(t) => (&t.mesh, Some(t.source.as_slice())),
            None => (&facing, None),
        };
        let most = layers.most();
        let first_covered = self.gd.pixels().iter().filter(|&&g| g > 0.0).count();
        // The first layer's depth as drawn (a SPOC's resolve has since moved its `gd`).
        let first = tessellated(mesh)?;
        let first_drawn = first.as_ref().map_or(mesh, |t| &t.mesh);
        let mut above = rasterize(projection, &[first_drawn], &NoAttributes, ())?
            .0
            .gd;
        let (w, h) = self.gd.size();
        while self.layer_count() < most {
            let ceiling = Image::from_vec(
                w,
                h,
                above
                    .pixels()
                    .iter()
                    .map(|&g| g * (1.0 - PEEL_GAP))
                    .collect(),
            )?;
            let (target, _) =
                rasterize_behind(projection, &[drawn], &Barycentrics, Vec2::ZERO, &ceiling)?;
            let covered = target.gd.pixels().iter().filter(|&&g| g > 0.0).count();
            if !layers.keeps(covered, first_covered) {
                break;
            }
            let mut layer = super::builder::zeroed_impostor(self.camera.clone())?;
            layer.gd = target.gd.clone();
            above = target.gd;
            let (items, bary) = (target.item.pixels(), target.attributes.pixels());
            resolve(&mut layer, (mesh, object), color, MapsBefore::Zeroed, |i| {
                let item = items[i];
                (!item.is_none()).then(|| {
                    let v = to_source(source, item.triangle, full_barycentrics(bary[i]));
                    Visible {
                        triangle: kept[v.triangle as usize],
                        ..v
                    }
                })
            });
            self.deeper.push(layer);
        }
        Ok(())
    }
}

impl Impostor {
    /// [`Impostor::peel`] with each layer's visibility image drawn elsewhere — a GPU's
    /// rasterizer (paper 1 §3.1 builds impostors by rasterization; `trompe-gpu`'s build).
    ///
    /// `draw` is called once a layer with the triangles of `mesh` facing the camera (by its
    /// winding; their indices are the drawn image's), and returns the nearest of them strictly
    /// behind the layer it drew before, under a ceiling [`PEEL_GAP`] nearer the camera than
    /// that layer's depth as drawn; before its first call, that layer is the first: `mesh`
    /// drawn whole through the impostor's camera. Which triangles are drawn, when peeling stops
    /// and how a layer is resolved are the library's, as in [`Impostor::peel`].
    ///
    /// # Errors
    /// What [`Impostor::peel`] refuses, the device's reason where `draw` failed, and an image
    /// of the wrong size or naming a triangle the facing mesh lacks.
    pub fn peel_drawn<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
        &mut self,
        (mesh, object): (&Mesh, u32),
        color: &F,
        layers: Layers,
        draw: &mut dyn FnMut(&Mesh) -> Result<DrawnImage, String>,
    ) -> Result<(), LayerError> {
        let Some(layers) = self.start_peeling(layers)? else {
            return Ok(());
        };
        let (facing, kept) = facing_camera(mesh, &self.camera);
        let first_covered = self.gd.pixels().iter().filter(|&&g| g > 0.0).count();
        while self.layer_count() < layers.most() {
            let mut drawn = draw(&facing).map_err(LayerError::Device)?;
            let covered = drawn.texels.iter().filter(|t| t.is_some()).count();
            if !layers.keeps(covered, first_covered) {
                break;
            }
            for (texel, d) in drawn.texels.iter_mut().enumerate() {
                if let Some((triangle, _)) = d {
                    *triangle = *kept.get(*triangle as usize).ok_or(DrawnError::Triangle {
                        texel,
                        triangle: *triangle,
                        count: kept.len(),
                    })?;
                }
            }
            let layer = resolve_drawn(self.camera.clone(), (mesh, object), color, &drawn)?;
            self.deeper.push(layer);
        }
        Ok(())
    }
}

/// The triangles of `mesh` whose front (counter-clockwise side) faces `camera`, as a mesh
/// sharing its vertices, and the index in `mesh` of each.
fn facing_camera(mesh: &Mesh, camera: &ImpostorCamera) -> (Mesh, Vec<u32>) {
    let kept: Vec<u32> = (0..mesh.triangles.len())
        .filter(|&t| {
            let [a, b, c] = mesh.corners(t);
            let centroid = ((a + b + c) / 3.0).as_dvec3();
            let face = (b - a).cross(c - a).as_dvec3();
            face.dot(camera.toward_camera(centroid)) > 0.0
        })
        .map(|t| t as u32)
        .collect();
    let facing = Mesh {
        triangles: kept.iter().map(|&t| mesh.triangles[t as usize]).collect(),
        face_material: kept
            .iter()
            .map(|&t| mesh.face_material.get(t as usize).copied().unwrap_or(0))
            .collect(),
        ..mesh.clone()
    };
    (facing, kept)
}
