//! Scenes: the TOML scene file (format in `scenes/README.md`), camera paths and per-object
//! animation (all papers).
//!
//! [`Scene::load`] reads the file, resolves paths relative to it, loads meshes and the panorama
//! and validates everything a user typed. [`Scene::view`] evaluates the scene at one time into a
//! [`View`]: a camera and world-space meshes, which is all a renderer sees.
//!
//! Invariants: a loaded scene's camera is valid at every time; paths are relative to the scene
//! file; unknown keys are errors.

pub mod deform;
mod field;
mod file;
pub mod maze;
mod object;

pub use deform::{DeformKind, Deformation};
pub use field::{FieldCopy, MAX_INSTANCES};
pub use file::SceneFile;
pub use object::MAX_SUBDIVIDE;
use object::load_object;

use crate::camera::{CameraError, Pinhole};
use crate::frame::FrameError;
use crate::frame::envmap::EnvMap;
use crate::geom::{Aabb, Mesh, MeshError, Texture, Warning};
use glam::{Mat4, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use thiserror::Error;

/// Errors from loading a scene: each names the scene file and what in it is wrong.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax, a wrong type or an unknown key (the message gives line and column).
    #[error("{path}: {message}")]
    Parse {
        /// The scene file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{path}: {key}: {reason}")]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// Which key (`camera.resolution`, `object[2].mesh` …).
        key: String,
        /// Why.
        reason: String,
    },
    /// An object's mesh could not be loaded.
    #[error("{path}: {key}: {source}")]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// Which object.
        key: String,
        /// The cause.
        source: Box<MeshError>,
    },
    /// No object of the scene has the name asked for.
    #[error("{path}: no object named {name:?} (it has {available})")]
    NoObject {
        /// The scene file.
        path: PathBuf,
        /// The name asked for.
        name: String,
        /// The names it has, comma-separated.
        available: String,
    },
    /// A floor plan (`.maze`) an object names could not be read.
    #[error("{path}: {key}: {source}")]
    Maze {
        /// The scene file.
        path: PathBuf,
        /// Which object.
        key: String,
        /// The cause.
        source: Box<maze::MazeError>,
    },
    /// An image (panorama, texture) could not be loaded.
    #[error("{path}: {key}: {source}")]
    Image {
        /// The scene file.
        path: PathBuf,
        /// Which key.
        key: String,
        /// The cause.
        source: FrameError,
    },
    /// The camera parameters make no camera.
    #[error("{path}: camera: {source}")]
    Camera {
        /// The scene file.
        path: PathBuf,
        /// The cause.
        source: CameraError,
    },
}

/// How a surface responds to light.
#[derive(Clone, Debug)]
pub enum Surface {
    /// Lambertian. `None` uses the mesh file's materials; `Some` overrides them.
    Diffuse(Option<DiffuseOverride>),
    /// Perfect mirror with a per-channel reflectance.
    Mirror {
        /// Reflectance.
        tint: Vec3,
    },
    /// Smooth dielectric.
    Glass {
        /// Index of refraction.
        ior: f32,
        /// Transmittance.
        tint: Vec3,
    },
}

/// A diffuse colour or texture given in the scene, replacing the mesh file's.
#[derive(Clone, Debug)]
pub struct DiffuseOverride {
    /// Linear colour (multiplies the texture).
    pub color: Vec3,
    /// Texture.
    pub texture: Option<Texture>,
}

/// Motion of an object over time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Animation {
    /// Unit rotation axis through the object's origin.
    pub axis: Vec3,
    /// Radians per second.
    pub angular_speed: f32,
    /// Units per second.
    pub velocity: Vec3,
}

/// One object of a scene.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// Name (for reports and ids).
    pub name: String,
    /// The mesh in object space.
    pub mesh: Arc<Mesh>,
    /// Its surface.
    pub surface: Surface,
    /// Object → world at time 0.
    pub world_from_object: Mat4,
    /// Motion, if any.
    pub animation: Option<Animation>,
    /// Deformation over time (object space), if any.
    pub deform: Option<Deformation>,
    /// The floor plan the mesh was made from, when it is a maze (paper 1 §5): the impostor
    /// methods see it through the maze's graph camera.
    pub maze: Option<MazeObject>,
    /// A baked impostor's sidecar that stands in for the object in mirrors and glass
    /// (`render --method impostor`); it must have been baked from the object as the scene
    /// places it.
    pub impostor: Option<PathBuf>,
    /// Where the object is one copy of a field (the scene file's `instances`): every method
    /// draws it as an object of its own, and the octahedral method bakes one atlas a field.
    pub field: Option<FieldCopy>,
}

/// A maze an object is made from: the plan and its file (named in errors).
#[derive(Clone, Debug)]
pub struct MazeObject {
    /// The floor plan.
    pub maze: Arc<maze::Maze>,
    /// Its file.
    pub path: PathBuf,
}

/// A camera keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Seconds.
    pub time: f32,
    /// Eye.
    pub position: Vec3,
    /// Target.
    pub look_at: Vec3,
}

/// The viewing camera's parameters (a camera is built per time, along the path).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpec {
    /// Eye.
    pub position: Vec3,
    /// Target.
    pub look_at: Vec3,
    /// Up.
    pub up: Vec3,
    /// Full vertical field of view, degrees.
    pub fov_y: f64,
    /// Pixel intrinsics `[fx, fy, cx, cy]` (focal lengths and principal point, pixels): when
    /// set, they replace `fov_y` and the centred principal point (a real camera's).
    pub intrinsics: Option<[f64; 4]>,
    /// The lens's distortion, when the camera has one: its intrinsics in full, of the camera's
    /// size and pixel intrinsics ([`View::lens`]).
    pub lens: Option<crate::camera::Intrinsics>,
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Near-plane distance.
    pub near: f64,
    /// Keyframes (sorted by time); empty for a still camera.
    pub path: Vec<Keyframe>,
}

/// A directional light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit direction toward the light.
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (colour × intensity; W/m², as Mitsuba,
    /// Blender's sun and glTF's `KHR_lights_punctual` give it): a white Lambertian surface
    /// facing it has radiance `irradiance / π`.
    pub irradiance: Vec3,
}

/// Everything a renderer needs to light a surface.
#[derive(Clone, Debug)]
pub struct Lighting {
    /// Panorama at infinity (a constant background when the scene has none).
    pub environment: EnvMap,
    /// The sun, if any.
    pub light: Option<Light>,
}

/// Renderer settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Ray-tracing recursion limit.
    pub max_depth: u32,
    /// Time of the default view.
    pub time: f32,
    /// Offset along the normal for secondary rays (1e-4 × the scene's radius).
    pub ray_epsilon: f32,
}

/// Why a scene could not be placed at a time.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewError {
    /// The camera at that time.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// An object's placement takes it out of the coordinates trompe can compute with.
    #[error(
        "object {object} (\"{name}\") at t = {time} s: a vertex reaches {value:e}: beyond ±{:e} \
         (or not a number), where trompe's arithmetic overflows f32 (check its translate, scale \
         and animation)",
        crate::geom::MAX_COORDINATE
    )]
    OutOfRange {
        /// The object (scene file order, from 0).
        object: usize,
        /// Its name.
        name: String,
        /// The time.
        time: f32,
        /// The largest coordinate magnitude it reaches (NaN where one is not a number).
        value: f32,
    },
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Viewing camera.
    pub camera: CameraSpec,
    /// Objects (object id = index).
    pub objects: Vec<SceneObject>,
    /// Environment and sun.
    pub lighting: Lighting,
    /// Renderer settings.
    pub render: RenderSettings,
    /// Problems survived while loading.
    pub warnings: Vec<Warning>,
    /// Every file the scene reads: itself, meshes and what they name, textures, the panorama,
    /// baked impostors (sidecar and maps) — what a command must never overwrite.
    pub files: Vec<PathBuf>,
}

/// A scene at one instant: camera and world-space geometry.
#[derive(Clone, Debug)]
pub struct View {
    /// The camera at that time.
    pub camera: Pinhole,
    /// The lens its pixels look through, when it is not a pinhole (a real camera's distortion,
    /// [`crate::camera::Intrinsics`] of the camera's size): pixel `p` sees along the camera's
    /// ray through `lens.undistorted_pixel_of(p)`. Only the exact tracer renders through a
    /// lens; the other methods refuse it.
    pub lens: Option<std::sync::Arc<crate::camera::Intrinsics>>,
    /// World-space meshes (object id = index).
    pub meshes: Vec<Arc<Mesh>>,
    /// Surfaces, by object id.
    pub surfaces: Vec<Surface>,
}

impl View {
    /// The first object with a coordinate beyond [`crate::geom::MAX_COORDINATE`] (or not a
    /// number), and that coordinate's magnitude: what no method can trace or bake. A view
    /// from [`Scene::view`] has none; one built by hand is checked by the renderers.
    pub fn out_of_range(&self) -> Option<(usize, f32)> {
        self.meshes.iter().enumerate().find_map(|(i, m)| {
            let largest = m.largest_coordinate();
            crate::geom::out_of_range(largest).then_some((i, largest))
        })
    }

    /// Borrowed meshes, in object order (what the rasterizer takes).
    pub fn mesh_refs(&self) -> Vec<&Mesh> {
        self.meshes.iter().map(|m| m.as_ref()).collect()
    }
}

fn vec3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

impl Scene {
    /// Reads and validates a scene file, loading its meshes and images.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_toml(&text, path)
    }

    /// Reads and validates a scene given as TOML text (`path` locates relative paths and names
    /// errors; nothing is read from it).
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().replace('\n', "\n  "),
        })?;
        Self::from_file(path, file)
    }

    /// Resolves a parsed scene file (`path` locates relative paths and names errors).
    pub fn from_file(path: &Path, file: SceneFile) -> Result<Scene, SceneError> {
        let dir = path.parent().unwrap_or(Path::new("."));
        let invalid = |key: &str, reason: String| SceneError::Invalid {
            path: path.to_path_buf(),
            key: key.to_string(),
            reason,
        };
        let finite = |key: &str, v: &[f32]| -> Result<(), SceneError> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(invalid(key, "values must be finite".into()))
            }
        };
        let mut warnings = Vec::new();
        let mut objects = Vec::new();
        let mut files = vec![path.to_path_buf()];
        for (i, o) in file.objects.iter().enumerate() {
            let object = load_object(path, dir, i, o, &mut warnings, &mut files)?;
            if o.instances.is_empty() {
                objects.push(object);
                continue;
            }
            field::expand(object, &o.instances, (path, i), &mut objects)?;
        }
        let bounds = objects.iter().fold(Aabb::EMPTY, |b, o| {
            b.union(o.mesh.bounds().transformed(&o.world_from_object))
        });
        let radius = if bounds.is_empty() {
            1.0
        } else {
            bounds.radius().max(1e-6)
        };
        if !radius.is_finite() {
            return Err(invalid(
                "object",
                "the objects together span more than f32 coordinates hold".into(),
            ));
        }

        let c = &file.camera;
        finite("camera.position", &c.position)?;
        finite("camera.look_at", &c.look_at)?;
        finite("camera.up", &c.up)?;
        let (width, height) = crate::frame::check_size(c.resolution[0], c.resolution[1])
            .map_err(|e| invalid("camera.resolution", e.to_string()))?;
        let near = c.near.unwrap_or(1e-3 * radius as f64);
        if !(near > 0.0 && near.is_finite()) {
            return Err(invalid("camera.near", format!("{near} must be positive")));
        }
        // Either a field of view or a real camera's pixel intrinsics.
        let (fov_y, intrinsics) = match (c.fov_y, [c.fx, c.fy, c.cx, c.cy]) {
            (Some(fov_y), [None, None, None, None]) => (fov_y, None),
            (None, [Some(fx), Some(fy), Some(cx), Some(cy)]) => {
                finite("camera.fx", &[fx as f32, fy as f32, cx as f32, cy as f32])?;
                if !(fx > 0.0 && fy > 0.0) {
                    return Err(invalid(
                        "camera.fx",
                        format!("focal lengths fx = {fx}, fy = {fy} must be positive"),
                    ));
                }
                let fov_y = 2.0 * (height as f64 * 0.5 / fy).atan().to_degrees();
                (fov_y, Some([fx, fy, cx, cy]))
            }
            (Some(_), _) => {
                return Err(invalid(
                    "camera.fov_y",
                    "give either fov_y or the pixel intrinsics fx, fy, cx and cy, not both".into(),
                ));
            }
            (None, _) => {
                return Err(invalid(
                    "camera",
                    "needs fov_y, or all four of fx, fy, cx and cy".into(),
                ));
            }
        };
        // A lens: a COLMAP model and its distortion, on top of the pixel intrinsics.
        let lens = match (&c.model, &c.distortion) {
            (None, None) => None,
            (Some(name), distortion) => {
                let Some(k) = intrinsics else {
                    return Err(invalid(
                        "camera.model",
                        "a lens needs the pixel intrinsics fx, fy, cx and cy".into(),
                    ));
                };
                let model = crate::camera::CameraModel::from_name(name).ok_or_else(|| {
                    invalid(
                        "camera.model",
                        format!(
                            "{name:?} is not a camera model trompe reads ({})",
                            crate::camera::CameraModel::ALL.map(|m| m.name()).join(", ")
                        ),
                    )
                })?;
                let distortion = distortion.as_deref().unwrap_or(&[]);
                let lens =
                    crate::camera::Intrinsics::with_distortion(model, width, height, k, distortion)
                        .map_err(|e| invalid("camera.distortion", e))?;
                (!lens.is_undistorted()).then_some(lens)
            }
            (None, Some(_)) => {
                return Err(invalid(
                    "camera.distortion",
                    "needs the camera model it belongs to (model = \"OPENCV\", …)".into(),
                ));
            }
        };
        let mut keys = Vec::new();
        for (k, kf) in c.path.iter().enumerate() {
            let key = format!("camera.path[{k}]");
            finite(&key, &[kf.time])?;
            finite(&key, &kf.position)?;
            finite(&key, &kf.look_at)?;
            keys.push(Keyframe {
                time: kf.time,
                position: vec3(kf.position),
                look_at: vec3(kf.look_at),
            });
        }
        keys.sort_by(|a, b| a.time.total_cmp(&b.time));
        let camera = CameraSpec {
            position: vec3(c.position),
            look_at: vec3(c.look_at),
            up: vec3(c.up),
            fov_y,
            intrinsics,
            lens,
            width,
            height,
            near,
            path: keys,
        };
        // Validate the camera at its rest pose and at every keyframe now, not at render time.
        for t in std::iter::once(file.render.time).chain(camera.path.iter().map(|k| k.time)) {
            camera.at(t).map_err(|source| SceneError::Camera {
                path: path.to_path_buf(),
                source,
            })?;
        }

        let environment = match &file.environment {
            Some(e) => {
                finite("environment.rotation", &[e.rotation])?;
                finite("environment.intensity", &[e.intensity])?;
                files.push(dir.join(&e.path));
                EnvMap::load(&dir.join(&e.path), e.rotation.to_radians(), e.intensity).map_err(
                    |source| SceneError::Image {
                        path: path.to_path_buf(),
                        key: "environment.path".into(),
                        source,
                    },
                )?
            }
            None => {
                finite("render.background", &file.render.background)?;
                if file.render.background.iter().any(|c| *c < 0.0) {
                    return Err(invalid(
                        "render.background",
                        "a radiance is not negative".into(),
                    ));
                }
                EnvMap::constant(vec3(file.render.background))
            }
        };
        let light = match &file.light {
            Some(l) => {
                finite("light.direction", &l.direction)?;
                finite("light.color", &l.color)?;
                finite("light.intensity", &[l.intensity])?;
                let direction = vec3(l.direction)
                    .try_normalize()
                    .ok_or_else(|| invalid("light.direction", "must not be zero".into()))?;
                Some(Light {
                    direction,
                    irradiance: vec3(l.color) * l.intensity,
                })
            }
            None => None,
        };
        if file.render.max_depth > 64 {
            return Err(invalid(
                "render.max_depth",
                format!("{} is more than 64", file.render.max_depth),
            ));
        }
        Ok(Scene {
            path: path.to_path_buf(),
            camera,
            objects,
            lighting: Lighting { environment, light },
            render: RenderSettings {
                max_depth: file.render.max_depth,
                time: file.render.time,
                ray_epsilon: 1e-4 * radius,
            },
            warnings,
            files,
        })
    }

    /// The index (object id) of the object named `name`, or an error that lists the names the
    /// scene has.
    pub fn object_named(&self, name: &str) -> Result<usize, SceneError> {
        self.objects
            .iter()
            .position(|o| o.name == name)
            .ok_or_else(|| SceneError::NoObject {
                path: self.path.clone(),
                name: name.to_owned(),
                available: self
                    .objects
                    .iter()
                    .map(|o| o.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Every object's pose (world from object) at time `t`: what a renderer compares, with
    /// [`Scene::deforms`], to keep what it built over the scene (a BVH, an upload) while
    /// nothing moves.
    pub fn poses_at(&self, t: f32) -> Vec<glam::Mat4> {
        self.objects
            .iter()
            .map(|o| o.world_from_object_at(t))
            .collect()
    }

    /// Whether an object deforms (its shape changes with time, not only its pose).
    pub fn deforms(&self) -> bool {
        self.objects.iter().any(|o| o.deform.is_some())
    }

    /// The scene at time `t` (seconds): camera along its path, objects animated. Refused where
    /// an object's placement at `t` takes a vertex beyond [`crate::geom::MAX_COORDINATE`] (or to
    /// a non-finite coordinate): no method can trace or bake it.
    pub fn view(&self, t: f32) -> Result<View, ViewError> {
        let camera = self.camera.at(t)?;
        let meshes = self
            .objects
            .iter()
            .enumerate()
            .map(|(object, o)| {
                let mesh = o.mesh_at(t).transformed(&o.world_from_object_at(t));
                let largest = mesh.largest_coordinate();
                if crate::geom::out_of_range(largest) {
                    return Err(ViewError::OutOfRange {
                        object,
                        name: o.name.clone(),
                        time: t,
                        value: largest,
                    });
                }
                Ok(Arc::new(mesh))
            })
            .collect::<Result<_, _>>()?;
        Ok(View {
            lens: self.camera.lens.clone().map(Arc::new),
            camera,
            meshes,
            surfaces: self.objects.iter().map(|o| o.surface.clone()).collect(),
        })
    }
}

impl CameraSpec {
    /// The camera at time `t`: keyframes interpolated linearly, clamped at the ends.
    pub fn at(&self, t: f32) -> Result<Pinhole, CameraError> {
        let (position, look_at) = match self.path.as_slice() {
            [] => (self.position, self.look_at),
            [k] => (k.position, k.look_at),
            keys => {
                let i = keys.partition_point(|k| k.time <= t);
                if i == 0 {
                    (keys[0].position, keys[0].look_at)
                } else if i == keys.len() {
                    (keys[i - 1].position, keys[i - 1].look_at)
                } else {
                    let (a, b) = (&keys[i - 1], &keys[i]);
                    let s = (t - a.time) / (b.time - a.time).max(f32::MIN_POSITIVE);
                    (a.position.lerp(b.position, s), a.look_at.lerp(b.look_at, s))
                }
            }
        };
        let camera = match self.intrinsics {
            Some(k) => {
                Pinhole::with_intrinsics(position, look_at, self.up, k, self.width, self.height)?
            }
            None => Pinhole::look_at(
                position,
                look_at,
                self.up,
                self.fov_y,
                self.width,
                self.height,
            )?,
        };
        Ok(camera.with_near(self.near))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: "t.toml".into(),
            message: e.to_string(),
        })?;
        Scene::from_file(Path::new("t.toml"), file)
    }

    const CAMERA: &str =
        "[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [32, 24]\n";

    #[test]
    fn a_camera_with_pixel_intrinsics_projects_through_its_principal_point() {
        let camera = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nfx = 40\nfy = 44\n\
                      cx = 19.5\ncy = 9.25\nresolution = [32, 24]\n";
        let s = parse(&format!("{camera}[[object]]\nshape = \"cube\"\n")).unwrap();
        let pinhole = s.camera.at(0.0).unwrap();
        // The point looked at lands on the principal point; one unit right at depth 3 lands
        // fx / 3 pixels right of it.
        use crate::camera::Projection;
        let p = pinhole.project(glam::DVec3::ZERO).unwrap().uv;
        assert!((p - glam::DVec2::new(19.5, 9.25)).length() < 1e-9, "{p}");
        let q = pinhole.project(glam::DVec3::X).unwrap().uv;
        assert!((q.x - (19.5 + 40.0 / 3.0)).abs() < 1e-9, "{q}");
        // Both a field of view and intrinsics, or intrinsics only in part: named errors.
        for (text, key) in [
            (
                camera.replace("fx = 40", "fx = 40\nfov_y = 30"),
                "camera.fov_y",
            ),
            (camera.replace("fx = 40\n", ""), "camera"),
            (camera.replace("fy = 44", "fy = -44"), "camera.fx"),
        ] {
            let err = parse(&format!("{text}[[object]]\nshape = \"cube\"\n"))
                .unwrap_err()
                .to_string();
            assert!(err.contains(key), "{err}");
        }
    }

    #[test]
    fn a_camera_may_have_a_colmap_lens_and_a_wrong_one_is_named() {
        let camera = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nfx = 40\nfy = 44\n\
                      cx = 19.5\ncy = 9.25\nresolution = [32, 24]\n";
        let with = |lens: &str| parse(&format!("{camera}{lens}\n[[object]]\nshape = \"cube\"\n"));
        let s = with("model = \"OPENCV\"\ndistortion = [-0.1, 0.02, 0.001, 0.0]").unwrap();
        let lens = s.camera.lens.expect("a lens");
        assert_eq!(lens.model(), crate::camera::CameraModel::OpenCv);
        assert_eq!(
            lens.params(),
            [40.0, 44.0, 19.5, 9.25, -0.1, 0.02, 0.001, 0.0]
        );
        let view = parse(&format!("{camera}model = \"OPENCV\"\ndistortion = [-0.1, 0.0, 0.0, 0.0]\n[[object]]\nshape = \"cube\"\n"))
            .unwrap()
            .view(0.0)
            .unwrap();
        assert!(view.lens.is_some());
        // A lens model without distortion is a pinhole.
        assert!(with("model = \"PINHOLE\"").unwrap().camera.lens.is_none());
        for (lens, key, says) in [
            ("model = \"FISHEYE\"", "camera.model", "FISHEYE"),
            (
                "model = \"OPENCV\"\ndistortion = [0.1]",
                "camera.distortion",
                "takes 4",
            ),
            (
                "model = \"SIMPLE_RADIAL\"\ndistortion = [0.1]",
                "camera.distortion",
                "one focal",
            ),
            ("distortion = [0.1]", "camera.distortion", "model"),
        ] {
            let err = with(lens).unwrap_err().to_string();
            assert!(err.contains(key) && err.contains(says), "{lens}: {err}");
        }
        let fov = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
                   resolution = [32, 24]\nmodel = \"RADIAL\"\ndistortion = [0.1, 0.0]\n";
        let err = parse(&format!("{fov}[[object]]\nshape = \"cube\"\n")).unwrap_err();
        assert!(err.to_string().contains("pixel intrinsics"), "{err}");
    }

    #[test]
    fn a_minimal_scene_loads() {
        let s = parse(&format!("{CAMERA}[[object]]\nshape = \"cube\"\n")).unwrap();
        assert_eq!(s.objects.len(), 1);
        let v = s.view(0.0).unwrap();
        assert_eq!(v.meshes[0].triangle_count(), 12);
    }

    #[test]
    fn unknown_keys_and_bad_values_are_errors() {
        let e = parse(&format!(
            "{CAMERA}[[object]]\nshape = \"cube\"\ncolour = 1\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("colour"), "{e}");
        let e = parse(&format!(
            "{CAMERA}[[object]]\nshape = \"cube\"\nmaterial = {{ type = \"glass\", iorr = 1.5 }}\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("iorr"), "{e}");
        let e = parse(&CAMERA.replace("[32, 24]", "[1000000, 1000000]")).unwrap_err();
        assert!(e.to_string().contains("camera.resolution"), "{e}");
        let e = parse(&CAMERA.replace("[32, 24]", "[0, 24]")).unwrap_err();
        assert!(e.to_string().contains("camera.resolution"), "{e}");
        let e = parse(&format!("{CAMERA}[[object]]\nshape = \"teapot\"\n")).unwrap_err();
        assert!(e.to_string().contains("object[0].shape"), "{e}");
        let e = parse(&format!("{CAMERA}[[object]]\nmesh = \"missing.obj\"\n")).unwrap_err();
        assert!(e.to_string().contains("missing.obj"), "{e}");
        let e = parse(&CAMERA.replace("look_at = [0, 0, 0]", "look_at = [0, 1, 3]")).unwrap_err();
        assert!(e.to_string().contains("camera"), "{e}");
    }

    #[test]
    fn camera_path_and_animation_move_things() {
        let text = format!(
            "{CAMERA}[[camera.path]]\ntime = 0\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\n\
             [[camera.path]]\ntime = 2\nposition = [2, 1, 3]\nlook_at = [0, 0, 0]\n\
             [[object]]\nshape = \"cube\"\ntranslate = [1, 0, 0]\n[object.animate]\ndegrees_per_second = 90\n"
        );
        let s = parse(&text).unwrap();
        let mid = s.camera.at(1.0).unwrap();
        assert!((mid.position() - glam::DVec3::new(1.0, 1.0, 3.0)).length() < 1e-6);
        // A quarter turn about +y through the object's origin after one second.
        let b0 = s.view(0.0).unwrap().meshes[0].bounds();
        let b1 = s.view(1.0).unwrap().meshes[0].bounds();
        assert!((b0.center() - b1.center()).length() < 1e-5);
        let p = s.objects[0]
            .world_from_object_at(1.0)
            .transform_point3(Vec3::new(0.5, 0.0, 0.0));
        assert!((p - Vec3::new(1.0, 0.0, -0.5)).length() < 1e-5, "{p}");
    }
}
