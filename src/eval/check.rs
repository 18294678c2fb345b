//! The `trompe impostor check` experiment (paper 1 §4–6, Fig. 5–7): build an impostor of an
//! object — or take one baked earlier — fire rays at it, compare every answer with the exact
//! BVH, measure how much of the surface it holds, and for a SPOC set the pinhole depth image
//! from the same point beside it.
//!
//! Placement rules (no file is looked up: the default reflector is built in):
//!
//! * A mesh stays in its own coordinates. The reflector — by default a sphere (an icosphere of
//!   four subdivisions) — is scaled to 0.8 of the mesh's largest extent `s` and rests on the
//!   plane of the mesh's lowest point, its centre `distance · s` along `+x` from the mesh's
//!   centre; the viewer looks at it from `s · (−1.4, 0.4, 1.6)` off its centre
//!   ([`ReflectorSetup::beside`]). The impostor camera stands at the reflector's centre.
//! * A maze: the reflector (largest extent half a cell) stands in the first corridor, two cells
//!   in, and the viewer 2.5 cells outside the entrance ([`ReflectorSetup::in_maze`]).
//! * A baked impostor of a mesh: rays come from a sphere of `region` bounding radii around the
//!   impostor's viewpoint, aimed at the mesh's box ([`fidelity::viewpoint_rays`]).

use super::fidelity::{self, FidelityReport, ReflectorSetup, SurfaceCapture};
use super::misses::{MissPicture, miss_picture};
use crate::camera::CameraError;
use crate::frame::FrameError;
use crate::geom::{Mesh, Ray};
use crate::impostor::{
    CameraChoice, Impostor, ImpostorCamera, Layers, Paired, StrengthChoice, StrengthError, Subject,
    SubjectError, ViewCamera, WalkMode, albedo_of, build, choose_strength,
};
use crate::progress::Timings;
use crate::trace::Bvh;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use thiserror::Error;

/// How many surface samples measure the surface an impostor captured.
const SURFACE_SAMPLES: usize = 50_000;

/// The reflector `impostor check` uses when none is given: a sphere.
pub fn default_reflector() -> Mesh {
    crate::geom::icosphere(4)
}

/// Settings of a check that builds its impostor.
#[derive(Clone, Debug)]
pub struct CheckSettings {
    /// The impostor's camera.
    pub camera: CameraChoice,
    /// Its resolution (square).
    pub resolution: u32,
    /// The reflector whose reflected rays are fired ([`default_reflector`] when `None`).
    pub reflector: Option<Mesh>,
    /// Distance between the object's and the reflector's centres, in the object's largest
    /// extents.
    pub distance: f32,
    /// Resolution of the view of the reflector that spawns the rays.
    pub view: u32,
    /// Also fire this many rays from a sphere of 3 bounding radii around the object.
    pub sphere_rays: u32,
    /// Depth layers to peel behind the impostor's first (`impostor/peel.rs`; by default the
    /// automatic number, the configuration that holds paper 1's figures). With more than one,
    /// the report also sets the impostor with 1, 2, 4 and the automatic number of layers beside
    /// it, on the same rays ([`CheckReport::layers_beside`]), and the pinhole beside a SPOC is
    /// peeled alike.
    pub layers: Layers,
    /// Also draw where the impostor (and the pinhole beside a SPOC) disagrees with the BVH
    /// ([`CheckReport::misses`]).
    pub misses: bool,
}

impl Default for CheckSettings {
    fn default() -> Self {
        CheckSettings {
            camera: CameraChoice::Placed(ViewCamera::Spoc(None)),
            resolution: 512,
            reflector: None,
            distance: 1.4,
            view: 1024,
            sphere_rays: 0,
            layers: Layers::Auto,
            misses: false,
        }
    }
}

/// Settings of a check of a baked impostor.
#[derive(Clone, Debug)]
pub struct BakedCheckSettings {
    /// For a maze's graph-camera impostor: the reflector ([`default_reflector`] when `None`).
    pub reflector: Option<Mesh>,
    /// For a maze: resolution of the view of the reflector.
    pub view: u32,
    /// Radius of the region around the viewpoint the rays come from, in bounding radii.
    pub region: f32,
    /// How many rays come from that region.
    pub rays: u32,
    /// Also draw where the impostor disagrees with the BVH ([`CheckReport::misses`]).
    pub misses: bool,
}

impl Default for BakedCheckSettings {
    fn default() -> Self {
        BakedCheckSettings {
            reflector: None,
            view: 1024,
            region: 1.0,
            rays: 20_000,
            misses: false,
        }
    }
}

/// Why a check could not run.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CheckError {
    /// The input and the camera do not go together.
    #[error(transparent)]
    Subject(#[from] SubjectError),
    /// A camera could not be placed.
    #[error("placing the {what}: {source}")]
    Camera {
        /// Which camera or object.
        what: &'static str,
        /// Why.
        source: CameraError,
    },
    /// The impostor's maps could not be allocated.
    #[error("building the impostor: {0}")]
    Build(#[from] FrameError),
    /// The impostor's layers could not be peeled.
    #[error("peeling the impostor's layers: {0}")]
    Layers(#[from] crate::impostor::LayerError),
    /// The SPOC's strength could not be chosen.
    #[error("choosing the SPOC's strength: {0}")]
    Strength(#[from] StrengthError),
    /// The exact BVH the impostor is checked against would pass the memory budget.
    #[error("checking against the exact ray tracer: {0}")]
    Memory(#[from] crate::memory::OverBudget),
    /// A setting is out of its range.
    #[error("{setting} {value}: {reason}")]
    Setting {
        /// The setting, as the command line names it.
        setting: &'static str,
        /// Its value.
        value: f32,
        /// What it must be.
        reason: &'static str,
    },
    /// A baked impostor holds a camera its input does not go with.
    #[error("{sidecar}: holds a {kind} impostor; {reason}")]
    WrongInput {
        /// The impostor's sidecar.
        sidecar: PathBuf,
        /// Its camera.
        kind: &'static str,
        /// What it goes with.
        reason: String,
    },
    /// A baked impostor was not baked from the mesh it is checked against.
    #[error(
        "{sidecar}: was not baked from {mesh} as it is (the impostor's box {impostor_box:?} is not the object's {mesh_box:?}, padded by 10⁻⁴ of its extent)"
    )]
    Mismatch {
        /// The impostor's sidecar.
        sidecar: PathBuf,
        /// The mesh file.
        mesh: PathBuf,
        /// The impostor's box, min and max.
        impostor_box: [[f32; 3]; 2],
        /// The mesh's box, min and max.
        mesh_box: [[f32; 3]; 2],
    },
}

fn camera_err(what: &'static str) -> impl FnOnce(CameraError) -> CheckError {
    move |source| CheckError::Camera { what, source }
}

/// What a check measured.
pub struct CheckReport {
    /// The impostor checked.
    pub impostor: Impostor,
    /// The rays' answers against the exact BVH.
    pub fidelity: FidelityReport,
    /// How much of the surface the impostor holds.
    pub captured: SurfaceCapture,
    /// For a SPOC: the pinhole depth image from the same point on the same rays (paper 1
    /// Fig. 6–7).
    pub pinhole_beside: Option<(FidelityReport, SurfaceCapture)>,
    /// For a graph camera: §4.6's algorithm 1 (uniform 3-D steps) beside the default walk.
    pub algorithm_1: Option<FidelityReport>,
    /// When layers were asked for: the same camera with 1, 2, 4 and the automatic number of
    /// layers, on the same rays.
    pub layers_beside: Vec<LayerRow>,
    /// For a SPOC built with the rule's strength: how its strength was chosen
    /// ([`choose_strength`]).
    pub strength: Option<StrengthChoice>,
    /// When asked for: where the impostor, then the pinhole beside it, disagree with the BVH
    /// ([`super::misses::miss_picture`]; [`super::misses::side_by_side`] joins them).
    pub misses: Vec<MissPicture>,
    /// The steps' durations.
    pub timings: Timings,
}

/// One impostor of a layer comparison ([`CheckReport::layers_beside`]).
#[derive(Clone, Debug)]
pub struct LayerRow {
    /// The layers asked for.
    pub asked: Layers,
    /// The layers it holds.
    pub layers: usize,
    /// Its answers against the exact BVH.
    pub fidelity: FidelityReport,
    /// Bytes of its maps.
    pub map_bytes: u64,
}

/// An impostor to check, the object it replaces, the rays, the camera of the pinhole to
/// set beside a SPOC, and the layers it was asked for (other layer counts are set beside it
/// when that is more than one).
struct Checked {
    impostor: Impostor,
    target: Arc<Mesh>,
    rays: Vec<Ray>,
    pinhole_beside: Option<ImpostorCamera>,
    /// The layers the impostor was asked for: with more than one, other counts are set beside
    /// it.
    layers: Layers,
    /// The layers the pinhole beside it is peeled into: as many as the impostor's.
    pinhole_layers: Layers,
    strength: Option<StrengthChoice>,
    /// Whether to draw the disagreements.
    misses: bool,
}

/// Builds an impostor of `subject` through `settings.camera` and checks it on the reflector's
/// rays (and as many sphere rays as asked).
pub fn check_built(subject: &Subject, settings: &CheckSettings) -> Result<CheckReport, CheckError> {
    let mut timings = Timings::default();
    let reflector = settings.reflector.clone().unwrap_or_else(default_reflector);
    let mut choose = false;
    let (setup, camera) = match subject.pair(settings.camera)? {
        Paired::Graph { path, maze } => {
            let setup = ReflectorSetup::in_maze(maze, &reflector, settings.view)
                .map_err(camera_err("reflector"))?;
            let camera = maze
                .graph_camera(settings.resolution, path)
                .map_err(SubjectError::from)?;
            (setup, ImpostorCamera::Graph(camera))
        }
        Paired::Placed { mesh, kind } => {
            if !(settings.distance.is_finite() && settings.distance > 0.0) {
                return Err(CheckError::Setting {
                    setting: "--distance",
                    value: settings.distance,
                    reason: "must be a positive number of the object's extents",
                });
            }
            let setup = ReflectorSetup::beside(mesh, &reflector, settings.distance, settings.view)
                .map_err(camera_err("reflector"))?;
            choose = kind == ViewCamera::Spoc(None);
            let camera = setup
                .camera(kind, settings.resolution)
                .map_err(camera_err("impostor camera"))?;
            (setup, camera)
        }
    };
    let built = |camera| -> Result<Impostor, CheckError> {
        let albedo = albedo_of(&setup.target);
        let mut impostor = build(camera, &setup.target, 0, &albedo)?;
        if settings.layers != Layers::ONE {
            impostor.peel(&setup.target, 0, &albedo, settings.layers)?;
        }
        Ok(impostor)
    };
    // At the rule's strength first: what does not fit is refused before any choice.
    let mut impostor = timings.time("build impostor", || built(camera))?;
    let mut strength = None;
    if choose {
        // The rule's strength: chosen per object, on rays a second viewer sees in the mirror.
        let choice = timings.time("choose the SPOC's strength", || {
            let rays = setup.held_out_rays()?;
            choose_strength(
                &setup.target,
                |k| setup.camera(ViewCamera::Spoc(k), settings.resolution),
                settings.layers,
                &rays,
            )
        })?;
        if choice.chosen != choice.rule {
            let camera = setup
                .camera(choice.camera(), settings.resolution)
                .map_err(camera_err("impostor camera"))?;
            impostor = timings.time("build impostor", || built(camera))?;
        }
        strength = Some(choice);
    }
    let pinhole_beside = match &impostor.camera() {
        ImpostorCamera::Spoc(_) => Some(
            setup
                .camera(ViewCamera::Pinhole, settings.resolution)
                .map_err(camera_err("pinhole camera"))?,
        ),
        _ => None,
    };
    let mut rays = timings.time("reflected rays", || setup.rays())?;
    let b = setup.target.bounds();
    rays.extend(fidelity::sphere_rays(
        b.center(),
        b.radius() * 3.0,
        b,
        settings.sphere_rays as usize,
        1,
    ));
    let checked = Checked {
        impostor,
        target: setup.target,
        rays,
        pinhole_beside,
        layers: settings.layers,
        pinhole_layers: settings.layers,
        strength,
        misses: settings.misses,
    };
    measure(checked, timings)
}

/// Checks `impostor`, baked from `subject` (its sidecar `sidecar`), on rays from around its
/// viewpoint — for a graph camera, on the reflector's rays in the maze.
pub fn check_baked(
    subject: &Subject,
    impostor: Impostor,
    sidecar: &Path,
    settings: &BakedCheckSettings,
) -> Result<CheckReport, CheckError> {
    let mut timings = Timings::default();
    if !(settings.region.is_finite() && settings.region > 0.0) {
        return Err(CheckError::Setting {
            setting: "--region",
            value: settings.region,
            reason: "must be a positive number of radii",
        });
    }
    let graph = matches!(impostor.camera(), ImpostorCamera::Graph(_));
    let wrong = |reason: String| CheckError::WrongInput {
        sidecar: sidecar.to_path_buf(),
        kind: impostor.camera().kind(),
        reason,
    };
    let (target, setup) = match (subject, graph) {
        (Subject::Maze { maze, mesh, .. }, true) => {
            let reflector = settings.reflector.clone().unwrap_or_else(default_reflector);
            let setup = ReflectorSetup::in_maze(maze, &reflector, settings.view)
                .map_err(camera_err("reflector"))?;
            (Arc::new(mesh.clone()), Some(setup))
        }
        (Subject::Mesh { mesh, .. }, false) => (Arc::new(mesh.clone()), None),
        (Subject::Mesh { path, .. }, true) => {
            return Err(wrong(format!(
                "a graph-camera impostor is checked against its maze floor plan (.maze), not {}",
                path.display()
            )));
        }
        (Subject::Maze { .. }, false) => {
            return Err(wrong(
                "a maze floor plan goes with a graph-camera one".to_string(),
            ));
        }
    };
    if !impostor.was_built_from(&target) {
        let (ib, tb) = (impostor.bounds(), target.bounds());
        return Err(CheckError::Mismatch {
            sidecar: sidecar.to_path_buf(),
            mesh: subject.path().to_path_buf(),
            impostor_box: [ib.min.to_array(), ib.max.to_array()],
            mesh_box: [tb.min.to_array(), tb.max.to_array()],
        });
    }
    let b = target.bounds();
    // The pinhole beside a baked SPOC holds as many layers as it does.
    let pinhole_layers = match impostor.layer_count() {
        1 => Layers::ONE,
        n => Layers::Count(n as u32),
    };
    let (rays, pinhole_beside) = match setup {
        Some(setup) => (timings.time("reflected rays", || setup.rays())?, None),
        None => {
            let region = settings.region * b.radius();
            let rays = fidelity::viewpoint_rays(&impostor, region, b, settings.rays as usize, 1);
            let pinhole = match &impostor.camera() {
                ImpostorCamera::Spoc(_) => Some(
                    ImpostorCamera::fitted(
                        ViewCamera::Pinhole,
                        impostor.camera().viewpoint().as_vec3(),
                        b.center(),
                        b.radius(),
                        f64::from(region),
                        impostor.gd().size().0,
                        &target.positions,
                    )
                    .map_err(camera_err("pinhole camera"))?,
                ),
                _ => None,
            };
            (rays, pinhole)
        }
    };
    let checked = Checked {
        impostor,
        target,
        rays,
        pinhole_beside,
        layers: Layers::ONE,
        pinhole_layers,
        strength: None,
        misses: settings.misses,
    };
    measure(checked, timings)
}

/// Fires the rays at the impostor and at the exact BVH, and everything set beside it.
fn measure(checked: Checked, mut timings: Timings) -> Result<CheckReport, CheckError> {
    let Checked {
        impostor,
        target,
        rays,
        pinhole_beside,
        layers,
        pinhole_layers,
        strength,
        misses,
    } = checked;
    let mut pictures = Vec::new();
    let exact = timings.time("build BVH", || Bvh::build(vec![target.clone()]))?;
    // The rays that disagree are kept only to be drawn.
    let check = |impostor: &Impostor| {
        if misses {
            fidelity::check_disagreements(impostor, &exact, &rays)
        } else {
            (fidelity::check(impostor, &exact, &rays), Vec::new())
        }
    };
    let (fidelity, disagreements) = timings.time("check", || check(&impostor));
    let captured = timings.time("surface captured", || {
        fidelity::surface_captured(&impostor, &target, SURFACE_SAMPLES, 1)
    });
    if misses {
        pictures.push(miss_picture("impostor", &impostor, &disagreements));
    }
    drop(disagreements);
    let pinhole_beside = match pinhole_beside {
        Some(camera) => {
            let mut p = timings.time("build pinhole impostor", || {
                build(camera, &target, 0, &albedo_of(&target))
            })?;
            if pinhole_layers != Layers::ONE {
                timings.time("peel pinhole layers", || {
                    p.peel(&target, 0, &albedo_of(&target), pinhole_layers)
                })?;
            }
            let (r, disagreements) = timings.time("check pinhole", || check(&p));
            let c = fidelity::surface_captured(&p, &target, SURFACE_SAMPLES, 1);
            if misses {
                pictures.push(miss_picture("pinhole beside", &p, &disagreements));
            }
            Some((r, c))
        }
        None => None,
    };
    let algorithm_1 = matches!(impostor.camera(), ImpostorCamera::Graph(_)).then(|| {
        timings.time("check (algorithm 1)", || {
            fidelity::check_with(&impostor, &exact, &rays, WalkMode::Linear)
        })
    });
    let mut layers_beside = Vec::new();
    if layers != Layers::ONE {
        for asked in [
            Layers::ONE,
            Layers::Count(2),
            Layers::Count(4),
            Layers::Auto,
        ] {
            if asked == layers {
                layers_beside.push(LayerRow {
                    asked,
                    layers: impostor.layer_count(),
                    fidelity,
                    map_bytes: impostor.map_bytes(),
                });
                continue;
            }
            let albedo = albedo_of(&target);
            let mut other = build(impostor.camera().clone(), &target, 0, &albedo)?;
            other.peel(&target, 0, &albedo, asked)?;
            let fidelity = timings.time("check layers", || fidelity::check(&other, &exact, &rays));
            layers_beside.push(LayerRow {
                asked,
                layers: other.layer_count(),
                fidelity,
                map_bytes: other.map_bytes(),
            });
        }
    }
    Ok(CheckReport {
        impostor,
        fidelity,
        captured,
        pinhole_beside,
        algorithm_1,
        layers_beside,
        strength,
        misses: pictures,
        timings,
    })
}

/// As JSON: every figure the text shows (the impostor by its camera, size, coverage, layers and
/// bytes; each ray report with its agreement shares; the timings in milliseconds).
impl serde::Serialize for CheckReport {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde_json::json;
        let fidelity = |r: &FidelityReport| {
            let mut v = json!(r);
            v["agreement"] = r.agreement().into();
            v["hit_agreement"] = r.hit_agreement().into();
            v
        };
        let imp = &self.impostor;
        let (w, h) = imp.gd().size();
        let mut impostor = json!({
            "camera": imp.camera().kind(),
            "size": [w, h],
            "coverage": imp.coverage(),
            "layers": imp.layer_count(),
            "map_bytes": imp.map_bytes(),
        });
        match &imp.camera() {
            ImpostorCamera::Spoc(c) => impostor["spoc_strength"] = c.strength().into(),
            ImpostorCamera::Graph(g) => impostor["frusta"] = g.frusta().len().into(),
            _ => {}
        }
        json!({
            "impostor": impostor,
            "fidelity": fidelity(&self.fidelity),
            "captured": self.captured,
            "pinhole_beside": self.pinhole_beside.as_ref().map(|(r, c)| {
                json!({ "fidelity": fidelity(r), "captured": c })
            }),
            "algorithm_1": self.algorithm_1.as_ref().map(fidelity),
            "strength": self.strength,
            "layers_beside": self.layers_beside.iter().map(|row| json!({
                "asked": row.asked.to_string(),
                "layers": row.layers,
                "fidelity": fidelity(&row.fidelity),
                "map_bytes": row.map_bytes,
            })).collect::<Vec<_>>(),
            "misses": self.misses.iter().map(|m| json!({
                "name": m.name,
                "missed": m.missed,
                "placed": m.placed,
                "spurious": m.spurious,
                "outside": m.outside,
            })).collect::<Vec<_>>(),
            "timings_ms": self.timings,
        })
        .serialize(s)
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let imp = &self.impostor;
        match &imp.camera() {
            _ if self.strength.is_some() => writeln!(
                f,
                "{}",
                self.strength
                    .as_ref()
                    .map_or(String::new(), |s| s.to_string())
            )?,
            ImpostorCamera::Spoc(s) => writeln!(f, "SPOC strength k = {:.3}", s.strength())?,
            ImpostorCamera::Graph(g) => writeln!(f, "graph camera: {} frusta", g.frusta().len())?,
            _ => {}
        }
        let (w, h) = imp.gd().size();
        writeln!(
            f,
            "impostor  {} {w}×{h}, {:.1} % of texels covered, {} layer{}, maps {:.1} MB",
            imp.camera().kind(),
            imp.coverage() * 100.0,
            imp.layer_count(),
            if imp.layer_count() == 1 { "" } else { "s" },
            imp.map_bytes() as f64 / 1e6
        )?;
        let (r, c) = (&self.fidelity, &self.captured);
        writeln!(f, "rays      {} ({} hit the object)", r.rays, r.exact_hits)?;
        writeln!(
            f,
            "agreement {:.3} % of rays (hit/miss and position within 1.5 texels)",
            r.agreement() * 100.0
        )?;
        writeln!(
            f,
            "          {:.3} % of the rays that either method says hit",
            r.hit_agreement() * 100.0
        )?;
        writeln!(
            f,
            "missed    {} ({} on surface the impostor does not hold, {} by the walk)   spurious {}",
            r.missed,
            r.missed_unheld,
            r.missed - r.missed_unheld,
            r.spurious
        )?;
        writeln!(
            f,
            "position  mean error {:.3e} world units = {:.3} texel footprints (median {:.2e})",
            r.mean_position_error, r.mean_error_footprints, r.median_error_footprints
        )?;
        writeln!(
            f,
            "surface   {:.1} % captured within 1.5 footprints, {:.1} % within 1.5 texel extents on the surface",
            c.within_footprint * 100.0,
            c.within_texel * 100.0
        )?;
        write!(
            f,
            "walk      {:.1} texel visits per ray",
            r.texel_visits_per_ray
        )?;
        if let Some((rp, cp)) = &self.pinhole_beside {
            write!(
                f,
                "\nbeside it, the pinhole depth image from the same point: agreement {:.3} %, on hits {:.3} %, missed {}, surface {:.1} % / {:.1} %",
                rp.agreement() * 100.0,
                rp.hit_agreement() * 100.0,
                rp.missed,
                cp.within_footprint * 100.0,
                cp.within_texel * 100.0
            )?;
        }
        if !self.layers_beside.is_empty() {
            write!(
                f,
                "\nlayers    asked  held  agreement  missed (unheld / walk)  spurious  visits/ray  maps"
            )?;
            for row in &self.layers_beside {
                let r = &row.fidelity;
                write!(
                    f,
                    "\n          {:>5}  {:>4}  {:>8.3} %  {:>6} ({:>6} / {:>4})  {:>8}  {:>10.1}  {:.1} MB",
                    row.asked.to_string(),
                    row.layers,
                    r.agreement() * 100.0,
                    r.missed,
                    r.missed_unheld,
                    r.missed - r.missed_unheld,
                    r.spurious,
                    r.texel_visits_per_ray,
                    row.map_bytes as f64 / 1e6
                )?;
            }
        }
        if let Some(r1) = &self.algorithm_1 {
            write!(
                f,
                "\nalgorithm 1 (uniform 3-D steps): agreement {:.3} %, on hits {:.3} %, {:.1} texel visits per ray",
                r1.agreement() * 100.0,
                r1.hit_agreement() * 100.0,
                r1.texel_visits_per_ray
            )?;
        }
        for m in &self.misses {
            write!(
                f,
                "\nmisses    {}: {} missed (red), {} too far apart (orange), {} spurious (blue); {} outside its image",
                m.name, m.missed, m.placed, m.spurious, m.outside
            )?;
        }
        Ok(())
    }
}
