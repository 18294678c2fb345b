//! The TOML scene file, as written (before paths are resolved and meshes loaded).
//! Every table refuses keys it does not know, so a typo is an error, not a silent default.

use serde::Deserialize;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The viewing camera.
    pub camera: CameraFile,
    /// Panorama around the scene.
    pub environment: Option<EnvironmentFile>,
    /// The directional light.
    pub light: Option<LightFile>,
    /// Renderer settings.
    #[serde(default)]
    pub render: RenderFile,
    /// The objects.
    #[serde(default, rename = "object")]
    pub objects: Vec<ObjectFile>,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    /// Eye position.
    pub position: [f32; 3],
    /// Point looked at.
    pub look_at: [f32; 3],
    /// Up vector (default `+y`).
    #[serde(default = "up")]
    pub up: [f32; 3],
    /// Full vertical field of view, degrees (or the pixel intrinsics below).
    pub fov_y: Option<f64>,
    /// Focal length along x, pixels (with `fy`, `cx` and `cy`, instead of `fov_y`).
    pub fx: Option<f64>,
    /// Focal length along y, pixels.
    pub fy: Option<f64>,
    /// Principal point, pixels from the image's left edge.
    pub cx: Option<f64>,
    /// Principal point, pixels from the image's top edge.
    pub cy: Option<f64>,
    /// A COLMAP camera model whose lens distortion the camera has (with the pixel intrinsics):
    /// `SIMPLE_RADIAL`, `RADIAL`, `OPENCV` or `FULL_OPENCV`.
    pub model: Option<String>,
    /// That model's parameters after its focal length(s) and principal point, in COLMAP's
    /// order (`OPENCV`: `k1, k2, p1, p2`).
    pub distortion: Option<Vec<f64>>,
    /// `[width, height]` in pixels.
    pub resolution: [u64; 2],
    /// Near-plane distance (default 1e-3 × the scene's size).
    pub near: Option<f64>,
    /// Keyframes of a camera path.
    #[serde(default)]
    pub path: Vec<KeyframeFile>,
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

/// `[[camera.path]]`: the camera at one time.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeFile {
    /// Seconds.
    pub time: f32,
    /// Eye position.
    pub position: [f32; 3],
    /// Point looked at.
    pub look_at: [f32; 3],
}

/// `[environment]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentFile {
    /// `.hdr` or `.exr` equirectangular panorama, relative to the scene file.
    pub path: String,
    /// Rotation about `+y`, degrees.
    #[serde(default)]
    pub rotation: f32,
    /// Radiance multiplier.
    #[serde(default = "one")]
    pub intensity: f32,
}

fn one() -> f32 {
    1.0
}

/// `[light]`: a directional light (the sun).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightFile {
    /// Direction *toward* the light.
    pub direction: [f32; 3],
    /// Linear colour.
    #[serde(default = "white")]
    pub color: [f32; 3],
    /// Multiplier.
    #[serde(default = "one")]
    pub intensity: f32,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

/// `[render]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderFile {
    /// Ray-tracing recursion limit.
    #[serde(default = "max_depth")]
    pub max_depth: u32,
    /// Time (seconds) at which animation and the camera path are evaluated.
    #[serde(default)]
    pub time: f32,
    /// Radiance where rays escape, when there is no environment.
    #[serde(default = "background")]
    pub background: [f32; 3],
}

impl Default for RenderFile {
    fn default() -> Self {
        Self {
            max_depth: max_depth(),
            time: 0.0,
            background: background(),
        }
    }
}

fn max_depth() -> u32 {
    6
}
fn background() -> [f32; 3] {
    [0.05, 0.05, 0.05]
}

/// `[[object]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectFile {
    /// Name (default: the mesh file's stem or the shape).
    pub name: Option<String>,
    /// Mesh file (`.obj`, `.ply`, `.gltf`, `.glb`), relative to the scene file.
    pub mesh: Option<String>,
    /// Or a built-in shape: `plane`, `cube`, `sphere`.
    pub shape: Option<String>,
    /// Rescale the mesh so its largest extent is this, centred on `x = z = 0`, resting on `y = 0`.
    pub fit: Option<f32>,
    /// Split every triangle into four at its edge midpoints this many times (0–4): positions stay
    /// on the original faces, normals and texture coordinates are interpolated.
    pub subdivide: Option<u32>,
    /// Translation.
    #[serde(default)]
    pub translate: [f32; 3],
    /// Rotation, degrees about `x`, then `y`, then `z`.
    #[serde(default)]
    pub rotate: [f32; 3],
    /// Uniform or per-axis scale.
    pub scale: Option<ScaleFile>,
    /// Surface (default: the mesh file's own materials).
    pub material: Option<MaterialFile>,
    /// Motion over time.
    pub animate: Option<AnimateFile>,
    /// A deformation over time, in the object's own frame.
    pub deform: Option<DeformFile>,
    /// A baked impostor (its JSON sidecar, relative to the scene file) that stands in for this
    /// diffuse object in what mirrors and glass see, instead of one built for each of them.
    pub impostor: Option<String>,
    /// A field of copies: one object a translation (world units, applied after every other
    /// key), named `NAME#0`, `NAME#1` …; none or empty: the object itself.
    #[serde(default)]
    pub instances: Vec<[f32; 3]>,
}

/// A uniform or per-axis scale.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum ScaleFile {
    /// Same on every axis.
    Uniform(f32),
    /// Per axis.
    PerAxis([f32; 3]),
}

/// An object's surface.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum MaterialFile {
    /// Lambertian, with a colour or a texture (relative path) replacing the file's.
    Diffuse {
        /// Linear colour.
        color: Option<[f32; 3]>,
        /// Texture image, sampled at the mesh UVs.
        texture: Option<String>,
    },
    /// A perfect mirror.
    Mirror {
        /// Reflectance per channel.
        #[serde(default = "white")]
        tint: [f32; 3],
    },
    /// A smooth dielectric: Fresnel reflection and refraction.
    Glass {
        /// Index of refraction.
        #[serde(default = "glass_ior")]
        ior: f32,
        /// Transmittance per channel.
        #[serde(default = "white")]
        tint: [f32; 3],
    },
}

fn glass_ior() -> f32 {
    1.5
}

/// `[object.animate]`: a rotation about an axis through the object's origin and a drift.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimateFile {
    /// Rotation axis (default `+y`).
    #[serde(default = "up")]
    pub axis: [f32; 3],
    /// Angular speed, degrees per second.
    #[serde(default)]
    pub degrees_per_second: f32,
    /// Velocity, units per second.
    #[serde(default)]
    pub velocity: [f32; 3],
}

/// `[object.deform]`: a twist, a bend or a wave over time, in the object's own frame.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeformFile {
    /// `twist`, `bend` or `wave`.
    pub kind: String,
    /// Degrees at the top (twist, bend), or the amplitude as a fraction of the height (wave).
    pub amount: f32,
    /// Cycles a second.
    #[serde(default = "one")]
    pub hz: f32,
    /// Wave only: wavelength as a fraction of the height.
    #[serde(default = "one")]
    pub wavelength: f32,
}
