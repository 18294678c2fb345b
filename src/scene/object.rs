//! A scene file's object resolved (format in `scenes/README.md`): its mesh loaded (or a maze
//! built), subdivided and normalized, its transform and animation, its surface — diffuse with an
//! optional texture override, mirror or glass, or a baked impostor's sidecar — and the files it
//! read.
//!
//! Invariant: every error names the scene file and the object's key (`object[i].…`).

use super::file::{MaterialFile, ObjectFile, ScaleFile};
use super::{
    Animation, DeformKind, Deformation, DiffuseOverride, MazeObject, SceneError, SceneObject,
    Surface, maze,
};
use crate::frame::{Image, Rgba};
use crate::geom::{Mesh, Warning};
use glam::{EulerRot, Mat4, Quat, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

impl SceneObject {
    /// The mesh in object space at time `t`: deformed, if it deforms.
    pub fn mesh_at(&self, t: f32) -> std::borrow::Cow<'_, Mesh> {
        match &self.deform {
            None => std::borrow::Cow::Borrowed(self.mesh.as_ref()),
            Some(d) => std::borrow::Cow::Owned(d.apply(&self.mesh, t)),
        }
    }

    /// Object → world at time `t`.
    pub fn world_from_object_at(&self, t: f32) -> Mat4 {
        match self.animation {
            None => self.world_from_object,
            Some(a) => {
                let (_, _, origin) = self.world_from_object.to_scale_rotation_translation();
                let spin = Mat4::from_translation(origin + a.velocity * t)
                    * Mat4::from_axis_angle(a.axis, a.angular_speed * t)
                    * Mat4::from_translation(-origin);
                spin * self.world_from_object
            }
        }
    }
}

/// Most subdivision levels a scene object may ask for.
pub const MAX_SUBDIVIDE: u32 = 4;

pub(super) fn load_object(
    scene: &Path,
    dir: &Path,
    index: usize,
    o: &ObjectFile,
    warnings: &mut Vec<Warning>,
    files: &mut Vec<PathBuf>,
) -> Result<SceneObject, SceneError> {
    let key = |k: &str| format!("object[{index}]{k}");
    let invalid = |k: &str, reason: String| SceneError::Invalid {
        path: scene.to_path_buf(),
        key: key(k),
        reason,
    };
    let mut maze_object = None;
    let (mut mesh, default_name) = match (&o.mesh, &o.shape) {
        (Some(m), None) if m.to_ascii_lowercase().ends_with(".maze") => {
            // A floor plan: its walls and floor (paper 1's maze, Fig. 4).
            let plan = dir.join(m);
            let maze = maze::Maze::load(&plan).map_err(|source| SceneError::Maze {
                path: scene.to_path_buf(),
                key: key(".mesh"),
                source: Box::new(source),
            })?;
            let mesh = maze.mesh();
            maze_object = Some(MazeObject {
                maze: Arc::new(maze),
                path: plan.clone(),
            });
            files.push(plan);
            (mesh, "maze".to_string())
        }
        (Some(m), None) => {
            let mesh_path = dir.join(m);
            let loaded = crate::geom::io::load(&mesh_path).map_err(|source| SceneError::Mesh {
                path: scene.to_path_buf(),
                key: key(".mesh"),
                source: Box::new(source),
            })?;
            warnings.extend(loaded.warnings);
            files.extend(loaded.files);
            let stem = mesh_path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("mesh")
                .to_string();
            (loaded.mesh, stem)
        }
        (None, Some(s)) => {
            let mesh = match s.as_str() {
                "plane" => crate::geom::plane(1),
                "cube" => crate::geom::cube(),
                "sphere" => crate::geom::icosphere(4),
                other => {
                    return Err(invalid(
                        ".shape",
                        format!("unknown shape {other:?} (plane, cube or sphere)"),
                    ));
                }
            };
            (mesh, s.clone())
        }
        _ => return Err(invalid("", "needs exactly one of `mesh` or `shape`".into())),
    };
    if let Some(levels) = o.subdivide {
        if levels > MAX_SUBDIVIDE {
            return Err(invalid(
                ".subdivide",
                format!(
                    "{levels} is more than {MAX_SUBDIVIDE} (each level makes four times the triangles)"
                ),
            ));
        }
        crate::memory::check(
            || format!("object[{index}] subdivided {levels} times"),
            crate::memory::times(
                mesh.triangle_count() as u64,
                64u64.saturating_mul(4u64.pow(levels)),
            ),
        )
        .map_err(|e| invalid(".subdivide", e.to_string()))?;
        for _ in 0..levels {
            mesh = mesh.subdivided();
        }
    }
    if let Some(fit) = o.fit {
        if !(fit > 0.0 && fit.is_finite()) {
            return Err(invalid(".fit", format!("{fit} must be positive")));
        }
        let b = mesh.bounds();
        let s = fit / b.extent().max_element().max(f32::MIN_POSITIVE);
        let base = Vec3::new(b.center().x, b.min.y, b.center().z);
        mesh =
            mesh.transformed(&(Mat4::from_scale(Vec3::splat(s)) * Mat4::from_translation(-base)));
    }
    let scale = match &o.scale {
        None => Vec3::ONE,
        Some(ScaleFile::Uniform(s)) => Vec3::splat(*s),
        Some(ScaleFile::PerAxis(s)) => Vec3::from_array(*s),
    };
    let all: Vec<f32> = [o.translate, o.rotate, scale.to_array()].concat();
    if !all.iter().all(|x| x.is_finite()) || scale.cmpeq(Vec3::ZERO).any() {
        return Err(invalid(
            "",
            "translate, rotate and scale must be finite and scale non-zero".into(),
        ));
    }
    let [rx, ry, rz] = o.rotate.map(f32::to_radians);
    let world_from_object = Mat4::from_scale_rotation_translation(
        scale,
        Quat::from_euler(EulerRot::ZYX, rz, ry, rx),
        Vec3::from_array(o.translate),
    );
    if !mesh
        .bounds()
        .transformed(&world_from_object)
        .extent()
        .is_finite()
    {
        return Err(invalid(
            "",
            "the transformed mesh has coordinates too large to represent".into(),
        ));
    }
    let colours: Vec<f32> = match &o.material {
        Some(MaterialFile::Diffuse { color, .. }) => color.map_or(vec![], |c| c.to_vec()),
        Some(MaterialFile::Mirror { tint }) | Some(MaterialFile::Glass { tint, .. }) => {
            tint.to_vec()
        }
        None => vec![],
    };
    if !colours.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(invalid(
            ".material",
            "colours and tints must be finite and non-negative".into(),
        ));
    }
    let surface = match &o.material {
        None => Surface::Diffuse(None),
        Some(MaterialFile::Diffuse { color, texture }) => {
            if let Some(t) = texture {
                files.push(dir.join(t));
            }
            let texture = match texture {
                Some(t) => Some(Arc::new(load_image(
                    scene,
                    &dir.join(t),
                    &key(".material.texture"),
                )?)),
                None => None,
            };
            Surface::Diffuse(Some(DiffuseOverride {
                color: color.map_or(Vec3::ONE, Vec3::from_array),
                texture,
            }))
        }
        Some(MaterialFile::Mirror { tint }) => Surface::Mirror {
            tint: Vec3::from_array(*tint),
        },
        Some(MaterialFile::Glass { ior, tint }) => {
            if !(*ior >= 1.0 && *ior < 5.0) {
                return Err(invalid(".material.ior", format!("{ior} must be in [1, 5)")));
            }
            Surface::Glass {
                ior: *ior,
                tint: Vec3::from_array(*tint),
            }
        }
    };
    let animation = match &o.animate {
        None => None,
        Some(a) => {
            let values = [a.axis.as_slice(), &a.velocity, &[a.degrees_per_second]].concat();
            if !values.iter().all(|x| x.is_finite()) {
                return Err(invalid(
                    ".animate",
                    "axis, degrees_per_second and velocity must be finite".into(),
                ));
            }
            let axis = Vec3::from_array(a.axis)
                .try_normalize()
                .ok_or_else(|| invalid(".animate.axis", "must not be zero".into()))?;
            Some(Animation {
                axis,
                angular_speed: a.degrees_per_second.to_radians(),
                velocity: Vec3::from_array(a.velocity),
            })
        }
    };
    if maze_object.is_some()
        && (o.fit.is_some()
            || o.subdivide.is_some()
            || world_from_object != Mat4::IDENTITY
            || o.animate.is_some()
            || o.deform.is_some())
    {
        return Err(invalid(
            ".mesh",
            "a maze stands where its plan puts it (one metre a cell from the origin): give it no fit, subdivide, translate, rotate, scale, animate or deform".into(),
        ));
    }
    let deform = match &o.deform {
        None => None,
        Some(d) => {
            let kind = match d.kind.as_str() {
                "twist" => DeformKind::Twist,
                "bend" => DeformKind::Bend,
                "wave" => DeformKind::Wave,
                other => {
                    return Err(invalid(
                        ".deform.kind",
                        format!("unknown deformation {other:?} (twist, bend or wave)"),
                    ));
                }
            };
            if ![d.amount, d.hz, d.wavelength].iter().all(|x| x.is_finite()) {
                return Err(invalid(
                    ".deform",
                    "amount, hz and wavelength must be finite".into(),
                ));
            }
            if d.wavelength <= 0.0 {
                return Err(invalid(
                    ".deform.wavelength",
                    format!("{} must be positive", d.wavelength),
                ));
            }
            Some(Deformation::of(&mesh, kind, d.amount, d.hz, d.wavelength))
        }
    };
    if o.impostor.is_some() && (deform.is_some() || !matches!(surface, Surface::Diffuse(_))) {
        if deform.is_some() {
            return Err(invalid(
                ".impostor",
                "a deforming object cannot stand in as one baked impostor".into(),
            ));
        }
        return Err(invalid(
            ".impostor",
            "only a diffuse object stands in as an impostor (mirrors and glass are traced)".into(),
        ));
    }
    Ok(SceneObject {
        name: o.name.clone().unwrap_or(default_name),
        mesh: Arc::new(mesh),
        surface,
        world_from_object,
        animation,
        deform,
        maze: maze_object,
        impostor: o.impostor.as_ref().map(|p| {
            let sidecar = dir.join(p);
            files.push(sidecar.with_extension("exr"));
            files.push(sidecar.clone());
            sidecar
        }),
        field: None,
    })
}

fn load_image(scene: &Path, path: &Path, key: &str) -> Result<Image<Rgba>, SceneError> {
    crate::frame::io::read_color(path).map_err(|source| SceneError::Image {
        path: scene.to_path_buf(),
        key: key.to_string(),
        source,
    })
}
