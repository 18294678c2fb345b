//! Fields of instances (beyond the papers: what engines instance): an object of the scene file
//! with `instances` becomes that many copies, each an object of its own that every method draws,
//! moved by its translation; the octahedral method bakes one atlas a field
//! (`crate::octahedral::scene`).
//!
//! Invariants: a copy's pose at every time is the field's first copy's moved by its offset;
//! copies are named `NAME#k`, in the order the file lists them.

use super::{SceneError, SceneObject};
use glam::{Mat4, Vec3};
use std::path::Path;

/// One copy of a field of instances: the same mesh, surface, motion and deformation as the
/// field's first copy, moved by a translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldCopy {
    /// The object id of the field's first copy.
    pub first: usize,
    /// This copy's translation from the first (world units): its pose at every time is the
    /// first's, moved by it.
    pub offset: Vec3,
}

/// Most copies one object's `instances` may ask for.
pub const MAX_INSTANCES: usize = 4096;

/// Appends to `objects` the copies of `object` (object `index` of the scene file `scene`) that
/// `instances` asks for; refuses too many, a coordinate that is not finite, a maze or a baked
/// impostor (which stand where they were made), and copies past the memory limit.
pub(super) fn expand(
    object: SceneObject,
    instances: &[[f32; 3]],
    (scene, index): (&Path, usize),
    objects: &mut Vec<SceneObject>,
) -> Result<(), SceneError> {
    let invalid = |reason: String| SceneError::Invalid {
        path: scene.to_path_buf(),
        key: format!("object[{index}].instances"),
        reason,
    };
    if instances.len() > MAX_INSTANCES {
        return Err(invalid(format!(
            "{} copies is more than {MAX_INSTANCES}",
            instances.len()
        )));
    }
    if !instances.as_flattened().iter().all(|x| x.is_finite()) {
        return Err(invalid("values must be finite".into()));
    }
    if object.impostor.is_some() || object.maze.is_some() {
        return Err(invalid(
            "a maze or an object with a baked impostor stands where it was made: it has no \
             copies"
                .into(),
        ));
    }
    // Every copy is a mesh of its own in each view: its triangles, that many times.
    let copies = instances.len() as u64;
    crate::memory::check(
        || format!("object[{index}]'s {copies} copies"),
        crate::memory::times(
            (object.mesh.triangle_count() as u64).saturating_mul(copies),
            64,
        ),
    )
    .map_err(|e| invalid(e.to_string()))?;
    let first = objects.len();
    let Some(origin) = instances.first().map(|a| Vec3::from_array(*a)) else {
        return Ok(());
    };
    for (k, at) in instances.iter().enumerate() {
        let at = Vec3::from_array(*at);
        let mut copy = object.clone();
        copy.name = format!("{}#{k}", object.name);
        copy.world_from_object = Mat4::from_translation(at) * object.world_from_object;
        copy.field = Some(FieldCopy {
            first,
            offset: at - origin,
        });
        objects.push(copy);
    }
    Ok(())
}
