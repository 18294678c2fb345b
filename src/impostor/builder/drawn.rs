//! Impostors from a visibility image drawn elsewhere (paper 1 §3.1 builds impostors by
//! rasterization on graphics hardware): a GPU's rasterizer draws the mesh through the
//! impostor's camera — per texel the triangle its centre sees and that point's barycentrics —
//! and the library resolves the image into the maps exactly as it resolves its own
//! (`resolve.rs`), so an impostor built either way is walked, saved and lit alike.
//!
//! Invariants: the depth of a texel is that of the point its barycentrics name (for a projective
//! camera the depth a rasterizer interpolates at the texel's centre; through a graph camera,
//! through the frustum that drew it); an image naming a triangle the mesh does not have or a
//! frustum the camera does not have, or of the wrong size, is refused, never read past.

use super::SurfaceSample;
use super::resolve::{MapsBefore, Visible, full_barycentrics, resolve, zeroed_impostor};
use crate::frame::FrameError;
use crate::geom::Mesh;
use crate::impostor::{Impostor, ImpostorCamera};
use glam::{Vec2, Vec3};
use thiserror::Error;

/// What a visibility image drawn elsewhere holds at one texel: the triangle of the mesh its
/// centre sees and the barycentric weights of that triangle's corners 1 and 2 there (`None`:
/// nothing).
pub type DrawnTexel = Option<(u32, Vec2)>;

/// A visibility image drawn elsewhere, row-major: per texel what it sees and, through a graph
/// camera, the frustum that drew it (`None` for the cameras drawn in one pass).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawnImage {
    /// What each texel sees.
    pub texels: Vec<DrawnTexel>,
    /// Through a graph camera, per texel the frustum whose clipped triangles drew it.
    pub frusta: Option<Vec<u32>>,
}

/// Why a visibility image drawn elsewhere could not be resolved.
#[derive(Debug, Error)]
pub enum DrawnError {
    /// The image is not the camera's size.
    #[error("a visibility image of {got} texels for a camera of {width} × {height}")]
    Size {
        /// Texels given.
        got: usize,
        /// The camera's width.
        width: u32,
        /// The camera's height.
        height: u32,
    },
    /// A texel names a triangle the mesh does not have.
    #[error("texel {texel} of the visibility image names triangle {triangle} of a mesh of {count}")]
    Triangle {
        /// The texel, row-major.
        texel: usize,
        /// The triangle it names.
        triangle: u32,
        /// The mesh's triangles.
        count: usize,
    },
    /// A graph camera's image without the frustum of each texel, or another camera's with it.
    #[error(
        "a {0} camera's visibility image needs the frustum of each texel exactly when it is a graph camera's (drawn frustum by frustum, its triangles clipped to each: `graph_pieces`)"
    )]
    Camera(&'static str),
    /// A texel names a frustum the graph camera does not have.
    #[error("texel {texel} of the visibility image names frustum {frustum} of a camera of {count}")]
    Frustum {
        /// The texel, row-major.
        texel: usize,
        /// The frustum it names.
        frustum: u32,
        /// The camera's frusta.
        count: usize,
    },
    /// The maps could not be allocated.
    #[error(transparent)]
    Maps(#[from] FrameError),
}

/// An impostor of `mesh` (object id `object`) through `camera` from `drawn`, the visibility
/// image a rasterizer drew of it through that camera, each texel coloured by `color` as
/// [`super::build`] colours it. Through a SPOC the image is drawn from the mesh's
/// [`super::tessellate`]ion, each texel named by its source triangle, and each texel's depth is
/// then moved onto its triangle's plane, as a build's are. Through a graph camera it is drawn
/// frustum by frustum from [`super::graph_pieces`] (the largest `gd` kept, ties to the earlier
/// frustum), and names each texel's frustum.
pub fn resolve_drawn<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
    camera: ImpostorCamera,
    (mesh, object): (&Mesh, u32),
    color: &F,
    drawn: &DrawnImage,
) -> Result<Impostor, DrawnError> {
    let (width, height) = camera.resolution();
    let frusta = match (&camera, &drawn.frusta) {
        (ImpostorCamera::Graph(g), Some(frusta)) if frusta.len() == drawn.texels.len() => {
            let count = g.frusta().len();
            if let Some((texel, &frustum)) = frusta
                .iter()
                .enumerate()
                .find(|(_, f)| **f as usize >= count)
            {
                return Err(DrawnError::Frustum {
                    texel,
                    frustum,
                    count,
                });
            }
            Some(frusta.as_slice())
        }
        (ImpostorCamera::Graph(_), Some(frusta)) => {
            return Err(DrawnError::Size {
                got: frusta.len(),
                width,
                height,
            });
        }
        (ImpostorCamera::Graph(_), None) | (_, Some(_)) => {
            return Err(DrawnError::Camera(camera.kind()));
        }
        (_, None) => None,
    };
    let drawn = drawn.texels.as_slice();
    if drawn.len() as u64 != u64::from(width) * u64::from(height) {
        return Err(DrawnError::Size {
            got: drawn.len(),
            width,
            height,
        });
    }
    let count = mesh.triangle_count();
    if let Some((texel, &Some((triangle, _)))) = drawn
        .iter()
        .enumerate()
        .find(|(_, d)| d.is_some_and(|(t, _)| t as usize >= count))
    {
        return Err(DrawnError::Triangle {
            texel,
            triangle,
            count,
        });
    }
    let mut impostor = zeroed_impostor(camera)?;
    // Each texel's depth: that of the point it sees (0, empty, where the camera refuses the
    // point: a hair behind its near plane).
    // Through a graph camera, through the frustum that drew the texel, as a build measures it.
    let depth: Vec<f32> = drawn
        .iter()
        .enumerate()
        .map(|(i, d)| {
            d.map_or(0.0, |(t, b)| {
                let corners = mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]);
                let w = full_barycentrics(b);
                let p = (corners[0] * w.x + corners[1] * w.y + corners[2] * w.z).as_dvec3();
                let seen = match (&impostor.camera, frusta) {
                    (ImpostorCamera::Graph(g), Some(f)) => g.project_in(f[i] as usize, p),
                    (camera, _) => camera.project(p),
                };
                seen.map_or(0.0, |q| q.gd as f32)
            })
        })
        .collect();
    impostor.gd.pixels_mut().copy_from_slice(&depth);
    let visible = |i: usize| {
        let (triangle, b) = drawn[i].filter(|_| depth[i] > 0.0)?;
        Some(Visible {
            triangle,
            bary: full_barycentrics(b),
            frustum: frusta.map(|f| f[i]),
        })
    };
    resolve(
        &mut impostor,
        (mesh, object),
        color,
        MapsBefore::Zeroed,
        visible,
    );
    Ok(impostor)
}
