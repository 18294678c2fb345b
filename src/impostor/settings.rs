//! Named settings for building one impostor of a mesh — the entry point of the library:
//! `Impostor::spoc(&mesh).from(eye).resolution(512).build()?`. Each setting has a default a user
//! can read here; nothing is positional.

use super::{Impostor, ImpostorCamera, ViewCamera, albedo_of, build};
use crate::camera::CameraError;
use crate::frame::FrameError;
use crate::geom::Mesh;
use glam::Vec3;
use thiserror::Error;

/// Why an impostor could not be built from its settings.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ImpostorError {
    /// The camera could not be placed (an eye inside the mesh's bounding sphere, a zero
    /// direction, a mesh with no extent).
    #[error("placing the impostor camera: {0}")]
    Camera(#[from] CameraError),
    /// The maps could not be allocated at this resolution.
    #[error("allocating the impostor's maps: {0}")]
    Maps(#[from] FrameError),
    /// The depth layers could not be peeled.
    #[error("peeling the impostor's layers: {0}")]
    Layers(#[from] super::LayerError),
}

/// Where the camera stands.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Eye {
    /// `distance` bounding radii from the mesh's centre along `direction`.
    Toward { direction: Vec3, distance: f32 },
    /// At this world point.
    At(Vec3),
}

/// The settings of one impostor of a mesh ([`Impostor::spoc`], [`Impostor::pinhole`],
/// [`Impostor::orthographic`]). The defaults are `trompe impostor bake`'s: the camera 3
/// bounding radii from the mesh's centre along `(0, 0.3, 1)`, 512² texels, framed tightly on
/// the mesh, a SPOC's strength chosen for rays from within one bounding radius of the eye,
/// colour = the mesh's albedo, object id 0.
///
/// ```
/// use trompe::{Impostor, Ray, RayQuery, glam::Vec3};
/// let mesh = trompe::geom::icosphere(3);
/// let imp = Impostor::spoc(&mesh).from(Vec3::new(0.0, 0.0, 2.0)).resolution(64).build()?;
/// let hit = imp.closest_hit(&Ray::new(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z), f32::INFINITY);
/// assert!((hit.expect("the sphere is hit").t - 1.5).abs() < 0.02);
/// # Ok::<(), trompe::impostor::ImpostorError>(())
/// ```
#[derive(Clone, Debug)]
#[must_use = "settings build nothing until .build()"]
pub struct ImpostorSettings<'a> {
    mesh: &'a Mesh,
    kind: ViewCamera,
    eye: Eye,
    resolution: u32,
    region: Option<f32>,
    object: u32,
    layers: super::Layers,
}

impl Impostor {
    /// Settings for a single-pole occlusion camera impostor of `mesh` (paper 1 §3).
    pub fn spoc(mesh: &Mesh) -> ImpostorSettings<'_> {
        ImpostorSettings::new(mesh, ViewCamera::Spoc(None))
    }

    /// Settings for a pinhole depth image of `mesh`.
    pub fn pinhole(mesh: &Mesh) -> ImpostorSettings<'_> {
        ImpostorSettings::new(mesh, ViewCamera::Pinhole)
    }

    /// Settings for an orthographic (parallel) depth image of `mesh`.
    pub fn orthographic(mesh: &Mesh) -> ImpostorSettings<'_> {
        ImpostorSettings::new(mesh, ViewCamera::Orthographic)
    }
}

impl<'a> ImpostorSettings<'a> {
    fn new(mesh: &'a Mesh, kind: ViewCamera) -> Self {
        ImpostorSettings {
            mesh,
            kind,
            eye: Eye::Toward {
                direction: Vec3::new(0.0, 0.3, 1.0),
                distance: 3.0,
            },
            resolution: 512,
            region: None,
            object: 0,
            layers: super::Layers::ONE,
        }
    }

    /// The camera at world point `eye` (outside the mesh's bounding sphere).
    pub fn from(mut self, eye: Vec3) -> Self {
        self.eye = Eye::At(eye);
        self
    }

    /// The camera `distance` bounding radii (more than 1) from the mesh's centre, along
    /// `direction`.
    pub fn toward(mut self, direction: Vec3, distance: f32) -> Self {
        self.eye = Eye::Toward {
            direction,
            distance,
        };
        self
    }

    /// Texels a side (default 512).
    pub fn resolution(mut self, side: u32) -> Self {
        self.resolution = side;
        self
    }

    /// A SPOC's strength `k`, instead of the rule `k = 2Δ/z_O` (no effect on other cameras).
    pub fn strength(mut self, k: f64) -> Self {
        if let ViewCamera::Spoc(_) = self.kind {
            self.kind = ViewCamera::Spoc(Some(k));
        }
        self
    }

    /// Radius of the region the rays the impostor answers come from, around the eye (default:
    /// one bounding radius of the mesh); a SPOC's strength rule sizes `k` for it.
    pub fn region(mut self, radius: f32) -> Self {
        self.region = Some(radius);
        self
    }

    /// The object id its texels and hits carry (default 0).
    pub fn object_id(mut self, id: u32) -> Self {
        self.object = id;
        self
    }

    /// Depth layers to peel behind the first (default one: a plain impostor; see
    /// [`super::Layers`]).
    pub fn layers(mut self, layers: super::Layers) -> Self {
        self.layers = layers;
        self
    }

    /// Places the camera these settings describe.
    pub fn camera(&self) -> Result<ImpostorCamera, ImpostorError> {
        let b = self.mesh.bounds();
        let (center, radius) = (b.center(), b.radius());
        let eye = match self.eye {
            Eye::At(eye) => eye,
            Eye::Toward {
                direction,
                distance,
            } => {
                let dir = direction.try_normalize().ok_or(CameraError::Degenerate(
                    "the direction to the camera is zero",
                ))?;
                center + dir * radius * distance
            }
        };
        let region = f64::from(self.region.unwrap_or(radius));
        Ok(ImpostorCamera::fitted(
            self.kind,
            eye,
            center,
            radius,
            region,
            self.resolution,
            &self.mesh.positions,
        )?)
    }

    /// Builds the impostor, its colour the mesh's albedo ([`albedo_of`]).
    pub fn build(&self) -> Result<Impostor, ImpostorError> {
        let color = albedo_of(self.mesh);
        let mut impostor = build(self.camera()?, self.mesh, self.object, &color)?;
        if self.layers != super::Layers::ONE {
            impostor.peel(self.mesh, self.object, &color, self.layers)?;
        }
        Ok(impostor)
    }
}
