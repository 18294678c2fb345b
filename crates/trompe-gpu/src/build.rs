//! Paper 1's impostors built where the paper built them (§3.1): the mesh drawn by the GPU
//! rasterizer through the impostor's camera into a visibility image — per texel the triangle
//! its centre sees and the perspective-correct barycentrics there (`shaders/raster.wgsl`, the
//! primary pass's shader) — read back and resolved into the maps by the library
//! ([`trompe::impostor::resolve_drawn`]), exactly as it resolves its own rasterizer's image.
//!
//! Pinhole and orthographic cameras (a cube map is six pinholes), and the SPOC: the mesh
//! tessellated by the library's rule (§3.1: an edge splits while its image strays half a pixel
//! from its chord), each corner projected through the SPOC in the vertex shader, each texel
//! named by its source triangle. Not here yet: a graph camera's image (frustum by frustum, each
//! frustum's triangles clipped to it) and depth layers by peeling; the library builds those.
//!
//! Invariant: a GPU-built impostor differs from the CPU-built one only where the two
//! rasterizers' coverage rules or depth rounding pick another triangle for a texel
//! (`tests/system/build.rs` states the bound).

use crate::device::{Gpu, GpuError};
use crate::trace::{GpuRasterCamera, draw_into_visibility, raster_pipeline_of, visibility_texture};
use glam::{Vec2, Vec3};
use trompe::geom::Mesh;
use trompe::impostor::{DrawnTexel, Impostor, ImpostorCamera, SurfaceSample};

/// Why an impostor could not be built on the GPU.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The device's.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The library's, resolving the image.
    #[error(transparent)]
    Drawn(#[from] trompe::impostor::DrawnError),
}

/// An impostor of `mesh` (object id `object`) through `camera`, drawn on `gpu` and resolved by
/// the library, each texel coloured by `color` as [`trompe::impostor::build`] colours it.
pub fn build_impostor<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
    gpu: &Gpu,
    camera: ImpostorCamera,
    (mesh, object): (&Mesh, u32),
    color: &F,
) -> Result<Impostor, BuildError> {
    let drawn = draw(gpu, &camera, mesh)?;
    Ok(trompe::impostor::resolve_drawn(
        camera,
        (mesh, object),
        color,
        &drawn,
    )?)
}

/// The GPU as the impostor methods' drawer ([`trompe::render::ImpostorDrawer`]): it draws the
/// pinhole, orthographic and SPOC impostors (cube maps, floors, SPOCs, pinhole-impostor's
/// planar images) and leaves graph cameras to the library.
pub struct GpuDrawer<'a>(pub &'a Gpu);

impl trompe::render::ImpostorDrawer for GpuDrawer<'_> {
    fn draw(
        &self,
        camera: &ImpostorCamera,
        mesh: &Mesh,
    ) -> Option<Result<Vec<DrawnTexel>, String>> {
        match camera {
            ImpostorCamera::Graph(_) => None,
            _ => Some(draw(self.0, camera, mesh).map_err(|e| e.to_string())),
        }
    }
}

/// The visibility image of `mesh` through `camera` (pinhole, orthographic or SPOC), drawn on
/// `gpu`: per texel, row-major, the triangle of `mesh` its centre sees and the barycentrics of
/// its corners 1 and 2 there.
pub fn draw(gpu: &Gpu, camera: &ImpostorCamera, mesh: &Mesh) -> Result<Vec<DrawnTexel>, GpuError> {
    let (w, h) = camera.resolution();
    // Through a SPOC, the tessellation the library would draw, where it splits anything.
    let mut tessellation = None;
    let uniform = match camera {
        ImpostorCamera::Pinhole(c) => GpuRasterCamera::pinhole(c),
        ImpostorCamera::Orthographic(c) => GpuRasterCamera::orthographic(c),
        ImpostorCamera::Spoc(c) => {
            tessellation = trompe::impostor::tessellate(c, mesh)?;
            GpuRasterCamera::spoc(c)
        }
        other => {
            return Err(GpuError::Unsupported {
                what: format!(
                    "drawing a {} impostor on the GPU (it draws pinhole, orthographic and SPOC ones)",
                    other.kind()
                ),
            });
        }
    };
    gpu.check_texture("the impostor's visibility image", w, h)?;
    let drawn = tessellation.as_ref().map_or(mesh, |t| &t.mesh);
    let corners: Vec<[Vec3; 3]> = drawn
        .triangles
        .iter()
        .map(|t| t.map(|i| drawn.positions[i as usize]))
        .collect();
    let raster = raster_pipeline_of(gpu, &corners)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let visibility = visibility_texture(gpu, w, h);
    draw_into_visibility(gpu, &mut encoder, &raster, &uniform, &visibility, (w, h));
    let texels = gpu.read_texture(
        encoder,
        &visibility,
        (w, h),
        "the impostor's visibility image",
    )?;
    let source = tessellation.as_ref().map(|t| t.source.as_slice());
    Ok(texels
        .iter()
        .map(|t| {
            let triangle = t[0].checked_sub(1)?;
            let b = Vec2::new(f32::from_bits(t[1]), f32::from_bits(t[2]));
            match source {
                None => Some((triangle, b)),
                // A sub-triangle's point, named in its source triangle.
                Some(source) => {
                    let &(s, c) = source.get(triangle as usize)?;
                    let w = c[0] * (1.0 - b.x - b.y) + c[1] * b.x + c[2] * b.y;
                    Some((s, Vec2::new(w.y, w.z)))
                }
            }
        })
        .collect())
}
