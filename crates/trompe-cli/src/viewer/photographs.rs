//! The viewer's photograph modes: a mesh textured from a COLMAP model's views or from a master
//! encoding ("Master Texture" §4), flown around like a scene. The number keys switch between
//! the four weightings of [`trompe::texturing`], the key that orbits the next object goes to
//! the next photograph's camera, and the split screen sets the frame beside the same blend on
//! the CPU (its twin, whatever the device).
//!
//! Invariant: the photographs are uploaded once; switching weightings remakes only the blend's
//! tables ([`TexturedMesh::set_settings`]).

use super::{FlyCamera, Shown, ViewerError};
use glam::Vec3;
use std::time::Instant;
use trompe::camera::{Pinhole, Projection};
use trompe::geom::Mesh;
use trompe::render::Timings;
use trompe::texturing::Weighting;
use trompe_gpu::TexturedMesh;

/// A mesh textured from photographs, one weighting a key.
pub(super) struct Photographs<'a> {
    textured: TexturedMesh<'a>,
    /// The weightings the number keys switch between, in order.
    weightings: [Weighting; 4],
    /// The photographs' cameras.
    cameras: Vec<Pinhole>,
    /// The world's up: the mean of the photographs' up directions.
    up: Vec3,
    /// The near plane's distance: a thousandth of the mesh's bounding radius.
    near: f64,
    /// The photograph gone to last (the first, where the viewer starts).
    at: usize,
}

impl<'a> Photographs<'a> {
    /// The weightings, by key: ULR, VDTM, the view map, one view a face.
    pub(super) const WEIGHTINGS: [Weighting; 4] = [
        Weighting::Ulr { beta: 0.1 },
        Weighting::Vdtm,
        Weighting::ViewMap,
        Weighting::BestFace,
    ];

    /// `textured`, a textured `mesh`, to fly around; refused without a photograph.
    pub(super) fn new(textured: TexturedMesh<'a>, mesh: &Mesh) -> Result<Self, ViewerError> {
        let cameras = textured.source().cameras();
        if cameras.is_empty() {
            return Err(ViewerError::NoPhotographs {
                what: textured.source().name(),
            });
        }
        // Keep the user's ULR resolution penalty.
        let mut weightings = Self::WEIGHTINGS;
        if let Weighting::Ulr { beta } = textured.settings().weighting {
            weightings[0] = Weighting::Ulr { beta };
        }
        // A photograph's rows run down its image: its up is against its row step.
        let up = cameras
            .iter()
            .map(|c| -c.mcmillan().1.normalize_or_zero().as_vec3())
            .sum::<Vec3>()
            .try_normalize()
            .unwrap_or(Vec3::Y);
        let near = 1e-3 * f64::from(mesh.bounds().radius().max(1e-6));
        Ok(Self {
            textured,
            weightings,
            cameras,
            up,
            near,
            at: 0,
        })
    }

    /// The key of the weighting the viewer starts with: the one it was given.
    pub(super) fn current(&self) -> usize {
        let given = std::mem::discriminant(&self.textured.settings().weighting);
        self.weightings
            .iter()
            .position(|w| std::mem::discriminant(w) == given)
            .unwrap_or(0)
    }

    /// The weightings' names, by key.
    pub(super) fn names(&self) -> Vec<&'static str> {
        self.weightings.iter().map(|w| w.name()).collect()
    }

    /// Where the viewer starts: at the first photograph's camera.
    pub(super) fn start(&self) -> FlyCamera {
        self.looking_through(0)
    }

    /// A fly camera through photograph `i`'s: its eye, its view direction, its vertical field
    /// of view, levelled to the photographs' up.
    fn looking_through(&self, i: usize) -> FlyCamera {
        let c = &self.cameras[i];
        let eye = c.position().as_vec3();
        let (_, b, _) = c.mcmillan();
        let fov_y = 2.0 * (0.5 * f64::from(c.resolution().1) * b.length()).atan();
        FlyCamera::looking_at(
            eye,
            eye + c.forward().as_vec3(),
            self.up,
            fov_y.to_degrees().clamp(1.0, 170.0),
            self.near,
        )
    }

    /// Turns `camera` into the next photograph's.
    pub(super) fn next_photograph(&mut self, camera: &mut FlyCamera) {
        self.at = (self.at + 1) % self.cameras.len();
        *camera = self.looking_through(self.at);
    }

    /// Weighting `current`'s blend through `camera`, and the CPU's if `reference`.
    pub(super) fn frame(
        &mut self,
        current: usize,
        camera: &Pinhole,
        reference: bool,
    ) -> Result<Shown, ViewerError> {
        let mut settings = *self.textured.settings();
        settings.weighting = self.weightings[current];
        self.textured.set_settings(&settings)?;
        let start = Instant::now();
        let blend = self.textured.render(camera)?;
        let timings = Timings(vec![("blend", start.elapsed())]);
        let reference = match reference {
            true => Some(self.textured.render_on_cpu(camera)?.image),
            false => None,
        };
        let source = self.textured.source().name();
        let device = if self.textured.on_gpu() { "GPU" } else { "CPU" };
        let state = vec![format!(
            "{} photographs, k = {}, on the {device}; photograph {} gone to last",
            self.cameras.len(),
            settings.k,
            self.at + 1
        )];
        Ok(Shown {
            image: blend.image.clone(),
            reference,
            timings,
            name: format!("{source} {}", settings.weighting.name()),
            report: blend.to_string(),
            state,
        })
    }
}
