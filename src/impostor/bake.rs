//! Baking: build one impostor of a mesh or a maze and save it — a JSON sidecar, the EXR of its
//! maps beside it ([`super::file`]), and a PNG preview of its colour — what `trompe impostor bake`
//! does, callable from code.

use super::file::{ImpostorFileError, save};
use super::{
    CameraChoice, ImpostorCamera, Paired, StrengthChoice, Subject, SubjectError, ViewCamera,
    albedo_of, build, choose_strength, region_rays,
};
use crate::camera::CameraError;
use crate::frame::FrameError;
use crate::progress::Timings;
use glam::Vec3;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// How to place and size a baked impostor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeSettings {
    /// The camera: placed around a mesh, or a maze's graph camera.
    pub camera: CameraChoice,
    /// Texels a side.
    pub resolution: u32,
    /// Direction from the mesh's centre toward the camera (not zero).
    pub from: Vec3,
    /// Camera distance from the mesh's centre, in bounding-sphere radii (more than 1).
    pub distance: f32,
    /// Depth layers to peel (`peel.rs`; default one).
    pub layers: super::Layers,
}

impl Default for BakeSettings {
    fn default() -> Self {
        BakeSettings {
            camera: CameraChoice::Placed(super::ViewCamera::Spoc(None)),
            resolution: 512,
            from: Vec3::new(0.0, 0.3, 1.0),
            distance: 3.0,
            layers: super::Layers::ONE,
        }
    }
}

/// Why a bake failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BakeError {
    /// The input and the camera do not go together, or the maze's camera failed.
    #[error(transparent)]
    Subject(#[from] SubjectError),
    /// A setting is out of its range.
    #[error("{setting}: {reason}")]
    Setting {
        /// The setting, as the command line names it.
        setting: &'static str,
        /// What it must be.
        reason: &'static str,
    },
    /// The camera could not be placed.
    #[error("{path}: placing the camera: {source}")]
    Camera {
        /// The input.
        path: PathBuf,
        /// Why.
        source: CameraError,
    },
    /// The impostor's maps could not be allocated.
    #[error("building the impostor: {0}")]
    Build(FrameError),
    /// The layers could not be peeled.
    #[error("peeling the impostor's layers: {0}")]
    Layers(#[from] super::LayerError),
    /// The SPOC's strength could not be chosen.
    #[error("choosing the SPOC's strength: {0}")]
    Strength(#[from] super::StrengthError),
    /// The sidecar or its EXR could not be written.
    #[error("saving the impostor: {0}")]
    Save(#[from] ImpostorFileError),
    /// The preview could not be written.
    #[error("writing the preview: {0}")]
    Preview(FrameError),
}

/// What a bake made (as JSON, every field; the timings in milliseconds).
#[derive(serde::Serialize)]
pub struct BakeReport {
    /// The impostor's camera kind.
    pub kind: &'static str,
    /// Texels a side.
    pub resolution: u32,
    /// Fraction of texels covered.
    pub coverage: f64,
    /// Depth layers.
    pub layers: usize,
    /// Bytes of the maps, every layer's.
    pub map_bytes: u64,
    /// For a SPOC baked with the rule's strength: how its strength was chosen
    /// ([`super::choose_strength`]).
    pub strength: Option<StrengthChoice>,
    /// The sidecar, the EXR and the preview, in that order.
    pub files: [PathBuf; 3],
    /// The steps' durations.
    pub timings: Timings,
}

/// Bakes `subject` with `settings` to the sidecar `output` (`NAME.json`; `NAME.exr` and
/// `NAME.png` go beside it). The caller makes sure those paths may be written.
pub fn bake(
    subject: &Subject,
    settings: &BakeSettings,
    output: &Path,
) -> Result<BakeReport, BakeError> {
    let mut timings = Timings::default();
    let place = |kind, mesh: &crate::geom::Mesh| {
        ImpostorCamera::facing_mesh(
            kind,
            mesh,
            settings.from,
            settings.distance,
            settings.resolution,
        )
        .map_err(|source| BakeError::Camera {
            path: subject.path().to_path_buf(),
            source,
        })
    };
    let mut choose = false;
    let camera = match subject.pair(settings.camera)? {
        Paired::Graph { path, maze } => ImpostorCamera::Graph(
            maze.graph_camera(settings.resolution, path)
                .map_err(SubjectError::from)?,
        ),
        Paired::Placed { mesh, kind } => {
            if settings.from.length_squared() == 0.0 {
                return Err(BakeError::Setting {
                    setting: "--from",
                    reason: "must not be zero",
                });
            }
            if !(settings.distance.is_finite() && settings.distance > 1.0) {
                return Err(BakeError::Setting {
                    setting: "--distance",
                    reason: "must be more than 1 radius",
                });
            }
            choose = kind == ViewCamera::Spoc(None);
            place(kind, mesh)?
        }
    };
    let mesh = subject.mesh();
    let built = |camera| -> Result<super::Impostor, BakeError> {
        let mut imp = build(camera, mesh, 0, &albedo_of(mesh)).map_err(BakeError::Build)?;
        if settings.layers != super::Layers::ONE {
            imp.peel(mesh, 0, &albedo_of(mesh), settings.layers)?;
        }
        Ok(imp)
    };
    // At the rule's strength first: what does not fit is refused before any choice.
    let mut imp = timings.time("build impostor", || built(camera))?;
    let mut strength = None;
    if choose {
        // The rule's strength: chosen per object, on rays from within one radius of the
        // viewpoint (the region the rule sizes it for).
        let b = mesh.bounds();
        let eye = b.center() + settings.from.normalize_or_zero() * b.radius() * settings.distance;
        let choice = timings.time("choose the SPOC's strength", || {
            choose_strength(
                mesh,
                |k| {
                    ImpostorCamera::facing_mesh(
                        ViewCamera::Spoc(k),
                        mesh,
                        settings.from,
                        settings.distance,
                        settings.resolution,
                    )
                },
                settings.layers,
                &region_rays(mesh, (eye, b.radius())),
            )
        })?;
        if choice.chosen != choice.rule {
            let camera = place(choice.camera(), mesh)?;
            imp = timings.time("build impostor", || built(camera))?;
        }
        strength = Some(choice);
    }
    timings.time("save", || save(&imp, output))?;
    let preview = output.with_extension("png");
    timings
        .time("write preview", || {
            crate::frame::io::write_png(&preview, &imp.color_image())
        })
        .map_err(BakeError::Preview)?;
    Ok(BakeReport {
        kind: imp.camera.kind(),
        resolution: settings.resolution,
        coverage: imp.coverage(),
        layers: imp.layer_count(),
        map_bytes: imp.map_bytes(),
        strength,
        files: [output.to_path_buf(), output.with_extension("exr"), preview],
        timings,
    })
}

impl fmt::Display for BakeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} impostor {}², {:.1} % of texels covered",
            self.kind,
            self.resolution,
            self.coverage * 100.0
        )?;
        if self.layers > 1 {
            write!(f, ", {} depth layers", self.layers)?;
        }
        writeln!(f, ", maps {:.1} MB", self.map_bytes as f64 / 1e6)?;
        if let Some(s) = &self.strength {
            writeln!(f, "{s}")?;
        }
        let [a, b, c] = &self.files;
        write!(
            f,
            "wrote {}, {} and {}",
            a.display(),
            b.display(),
            c.display()
        )
    }
}
