//! The viewer's scene mode: every method of the library's one list that renders a scene
//! ([`trompe::methods::MethodKind::for_scenes`]), each on the GPU where one is given and the
//! method has a GPU path, and `trace` on the CPU for the split screen.
//!
//! Invariant: the methods are the library's, on their device; the viewer only chooses settings
//! (the impostor and environment methods' primary rays rasterized, the relief method's latency).

use super::{FlyCamera, RELIEF_LATENCY, Shown, ViewerError};
use trompe::camera::Pinhole;
use trompe::methods::{MethodKind, MethodSettings, Renderer};
use trompe::render::Primary;
use trompe::scene::Scene;
use trompe_gpu::{DeviceRenderer, Gpu};

/// A scene's methods.
pub(super) struct SceneMethods<'a> {
    scene: &'a Scene,
    /// The methods the number keys switch between, in [`MethodKind::for_scenes`] order, each
    /// on the GPU where one was given and the method has a GPU path.
    renderers: Vec<DeviceRenderer<'a>>,
    /// `trace`, for the split screen (on the CPU: the reference).
    exact: Renderer<'a>,
    gpu: Option<&'a Gpu>,
    impostor_resolution: u32,
    /// The object orbited, if one was chosen.
    selected: Option<usize>,
}

impl<'a> SceneMethods<'a> {
    /// The methods over `scene`, impostors of `impostor_resolution²`, those with a GPU path on
    /// `gpu` if given.
    pub(super) fn new(
        scene: &'a Scene,
        impostor_resolution: u32,
        gpu: Option<&'a Gpu>,
    ) -> Result<Self, ViewerError> {
        Ok(Self {
            scene,
            renderers: renderers(scene, impostor_resolution, false, gpu),
            exact: Renderer::new(scene, MethodKind::Trace, MethodSettings::default())?,
            gpu,
            impostor_resolution,
            selected: None,
        })
    }

    /// The methods' names, by key.
    pub(super) fn names(&self) -> Vec<&'static str> {
        self.renderers.iter().map(|r| r.kind().name()).collect()
    }

    /// Lets the relief method use each impostor as soon as its thread makes it.
    pub(super) fn go_live(&mut self) {
        self.renderers = renderers(self.scene, self.impostor_resolution, true, self.gpu);
    }

    /// Turns `camera` to orbit the next object of the scene (in the scene file's order).
    pub(super) fn orbit_next(&mut self, c: &mut FlyCamera, time: f32) {
        let objects = &self.scene.objects;
        if objects.is_empty() {
            return;
        }
        let next = self.selected.map_or(0, |i| (i + 1) % objects.len());
        self.selected = Some(next);
        let o = &objects[next];
        let centre = o
            .world_from_object_at(time)
            .transform_point3(o.mesh.bounds().center());
        let distance = c.eye.distance(centre).max(1e-3);
        let keep = FlyCamera::looking_at(c.eye, centre, c.up, c.fov_y, c.near);
        (c.yaw, c.pitch, c.target, c.orbit) = (keep.yaw, keep.pitch, centre, true);
        c.eye = centre - c.direction() * distance;
    }

    /// Method `current`'s frame at `time` through `camera`, and `trace`'s if `reference`.
    pub(super) fn frame(
        &mut self,
        current: usize,
        time: f32,
        camera: &Pinhole,
        reference: bool,
    ) -> Result<Shown, ViewerError> {
        let renderer = &mut self.renderers[current];
        let kind = renderer.kind();
        let out = renderer.frame(time, Some(camera.clone()), &())?;
        let reference = match reference {
            true => Some(
                self.exact
                    .frame(time, Some(camera.clone()), &())?
                    .frame
                    .color,
            ),
            false => None,
        };
        let resolution = matches!(kind, MethodKind::Impostor | MethodKind::PinholeImpostor)
            .then_some(self.impostor_resolution);
        Ok(Shown {
            image: out.frame.color,
            reference,
            timings: out.timings,
            name: format!(
                "{}{}",
                kind.name(),
                resolution.map_or(String::new(), |r| format!(" {r}^2"))
            ),
            report: out.report,
            state: out.state,
        })
    }
}

/// Every method that renders a scene, prepared over `scene` as the viewer runs them: the
/// impostor and environment methods find what the eye sees by rasterizing (faster; differs on
/// silhouette pixels only); the relief method uses a new impostor [`RELIEF_LATENCY`] frames
/// after its request, or as soon as it is made when `live`. A method with a GPU path runs on
/// `gpu` when one is given.
fn renderers<'a>(
    scene: &'a Scene,
    impostor_resolution: u32,
    live: bool,
    gpu: Option<&'a Gpu>,
) -> Vec<DeviceRenderer<'a>> {
    MethodKind::for_scenes()
        .filter_map(|kind| {
            let mut settings = MethodSettings {
                impostor_resolution,
                ..Default::default()
            };
            if matches!(
                kind,
                MethodKind::Impostor | MethodKind::PinholeImpostor | MethodKind::EnvMap
            ) {
                settings.primary = Primary::Rasterized;
            }
            settings.relief.deterministic = (!live).then_some(RELIEF_LATENCY);
            let device = gpu.filter(|_| trompe_gpu::has_gpu_path(kind));
            DeviceRenderer::new(scene, kind, settings, device).ok()
        })
        .collect()
}
