//! Rendering from master textures on the GPU ("Master Texture" §4, the paper's rendering path):
//! every view's master texture is one layer of a texture array (8-bit sRGB, as an encoding's
//! files hold them, or half floats for brighter ones), the mesh carries one atlas point a
//! corner, and a frame is the blend of [`crate::texturing`] over a source (`shaders/master.wgsl`)
//! that asks every view at the pixel's one texture coordinate.
//!
//! The CPU twin is [`trompe::master::render`]: the same sight by the master's alpha and the
//! same bilinear lookup over texels with a colour; the best-face table and the view maps are the
//! library's own ([`trompe::master::render::face_table`]), built once on the CPU.
//!
//! Invariant: the masters are uploaded once and every frame reuses them; a frame's pixels
//! depend only on the masters, the mesh, the camera and the settings.

use crate::device::{Gpu, GpuError};
use crate::methods::DeviceError;
use crate::raster::v4;
use crate::texturing::{Blender, check_settings, entries, halves, padded_layer, texture_array};
use bytemuck::{Pod, Zeroable};
use glam::DVec2;
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba};
use trompe::geom::Mesh;
use trompe::master::layout::Layout;
use trompe::texturing::{Blend, BlendSettings};

/// The master-texture source's WGSL (the blend follows it).
pub const MASTER_SHADER: &str = include_str!("../shaders/master.wgsl");

/// A face as the shader reads it: its corners, and its atlas point and steps.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuFace {
    corners: [[f32; 4]; 3],
    atlas0: [f32; 4],
    atlas1: [f32; 4],
}

/// Master textures uploaded once, rendered through any pinhole.
pub struct GpuMasters<'a> {
    gpu: &'a Gpu,
    blender: Blender,
    faces: wgpu::Buffer,
    masters: wgpu::TextureView,
}

impl<'a> GpuMasters<'a> {
    /// Uploads `masters` (one a view, laid out by `layout`; `cameras` the views' cameras, for the
    /// weights) and `mesh` to `gpu`, to be rendered with `settings`. Refuses what the GPU path
    /// does not do ([`GpuError::Unsupported`]), a layout of another mesh, unpaired cameras,
    /// masters of another size than the layout's, and more views or texels than the device holds.
    pub fn new(
        gpu: &'a Gpu,
        mesh: &Mesh,
        (layout, cameras, masters): (&Layout, &[Pinhole], &[Image<Rgba>]),
        settings: &BlendSettings,
    ) -> Result<Self, DeviceError> {
        check_settings(settings)?;
        trompe::master::render::check(mesh, layout, cameras, masters)?;
        let (w, h) = (layout.width, layout.height);
        if let Some((i, m)) = masters.iter().enumerate().find(|(_, m)| m.size() != (w, h)) {
            let what = format!(
                "master texture {i} is {} × {}, not the layout's {w} × {h}",
                m.width(),
                m.height()
            );
            return Err(GpuError::Unsupported { what }.into());
        }
        let blender = blender(gpu, mesh, (layout, cameras, masters), settings)?;
        let corners: Vec<[glam::Vec3; 3]> = (0..mesh.triangle_count())
            .map(|t| mesh.corners(t))
            .collect();
        let faces: Vec<GpuFace> = corners
            .iter()
            .zip(&layout.faces)
            .map(|(c, place)| {
                let o = place.at(0.0, 0.0);
                let (e1, e2) = (place.at(1.0, 0.0) - o, place.at(0.0, 1.0) - o);
                let pair = |a: DVec2, b: DVec2| [a.x as f32, a.y as f32, b.x as f32, b.y as f32];
                GpuFace {
                    corners: c.map(|p| v4(p, 1.0)),
                    atlas0: pair(o, e1),
                    atlas1: pair(e2, DVec2::ZERO),
                }
            })
            .collect();
        let face_bytes: &[u8] = bytemuck::cast_slice(&faces);
        gpu.check_storage("the mesh's faces", face_bytes.len() as u64)?;
        // Masters within [0, 1] (those read from an encoding's PNGs) as 8-bit sRGB, as they are
        // written and as a renderer holds hundreds of them: the device decodes each texel to
        // linear light, alpha linear (an edge's ½ is 128/255). Brighter ones (in memory, of
        // rendered views) as half floats.
        let layers = (w, h, masters.len() as u32);
        let in_unit = |c: &trompe::frame::Rgba| {
            c.cmpge(glam::Vec4::ZERO).all() && c.cmple(glam::Vec4::ONE).all()
        };
        let masters = if masters.iter().all(|m| m.pixels().iter().all(in_unit)) {
            texture_array(
                gpu,
                "master textures",
                layers,
                (wgpu::TextureFormat::Rgba8UnormSrgb, 4),
                |layer| trompe::frame::io::to_srgb8(&masters[layer as usize]),
            )?
        } else {
            texture_array(
                gpu,
                "master textures",
                layers,
                (wgpu::TextureFormat::Rgba16Float, 8),
                |layer| padded_layer(Some(&masters[layer as usize]), (w, h), halves),
            )?
        };
        Ok(GpuMasters {
            gpu,
            blender,
            faces: gpu.storage_with("faces", face_bytes),
            masters,
        })
    }

    /// Blends with `settings` from now on: the weighting's per-face table and the shader made
    /// again from `mesh`, `layout`, `cameras` and `masters`, which must be those uploaded; the
    /// masters stay where they are.
    pub fn reweigh(
        &mut self,
        mesh: &Mesh,
        (layout, cameras, masters): (&Layout, &[Pinhole], &[Image<Rgba>]),
        settings: &BlendSettings,
    ) -> Result<(), DeviceError> {
        check_settings(settings)?;
        self.blender = blender(self.gpu, mesh, (layout, cameras, masters), settings)?;
        Ok(())
    }

    /// The mesh through `camera`, blended from the masters: the image and its pixels' counts,
    /// as [`trompe::master::render::render`] makes them.
    pub fn render(&self, camera: &Pinhole) -> Result<Blend, GpuError> {
        let source = entries(&[(1, &self.faces)], &[(3, &self.masters)]);
        self.blender.render(self.gpu, camera, &source)
    }
}

/// The blend of `masters` over `mesh` with `settings`: the weighting's per-face table, the
/// views' centres and the whole shader.
fn blender(
    gpu: &Gpu,
    mesh: &Mesh,
    (layout, cameras, masters): (&Layout, &[Pinhole], &[Image<Rgba>]),
    settings: &BlendSettings,
) -> Result<Blender, DeviceError> {
    let table =
        trompe::master::render::face_table(mesh, (layout, cameras, masters), settings.weighting)?;
    let corners: Vec<[glam::Vec3; 3]> = (0..mesh.triangle_count())
        .map(|t| mesh.corners(t))
        .collect();
    let centres: Vec<glam::DVec3> = cameras.iter().map(|c| c.position()).collect();
    Ok(Blender::new(
        gpu,
        &corners,
        &centres,
        &table,
        settings,
        ("master.wgsl", MASTER_SHADER),
    )?)
}

/// Renders `mesh` through `camera` from the encoding `trompe master encode` wrote in `dir`, on
/// `gpu`, or with the library's [`trompe::master::job::render_folder`] on the CPU without one.
/// On the GPU, a camera with a lens is refused (the GPU rasterizer draws through a pinhole).
pub fn render_folder(
    gpu: Option<&Gpu>,
    dir: &std::path::Path,
    mesh: &Mesh,
    (camera, lens): (&Pinhole, Option<&trompe::camera::Intrinsics>),
    settings: &BlendSettings,
) -> Result<Blend, DeviceError> {
    let Some(gpu) = gpu else {
        let cpu = trompe::master::job::render_folder(dir, mesh, (camera, lens), settings)?;
        return Ok(cpu);
    };
    refuse_lens(lens)?;
    let (manifest, masters) = trompe::master::file::load(dir)?;
    let cameras: Vec<Pinhole> = manifest.views.iter().map(|v| v.pinhole()).collect();
    let uploaded = GpuMasters::new(gpu, mesh, (&manifest.layout, &cameras, &masters), settings)?;
    Ok(uploaded.render(camera)?)
}

/// Refuses a render camera with a lens: the GPU rasterizer draws through a pinhole.
pub(crate) fn refuse_lens(lens: Option<&trompe::camera::Intrinsics>) -> Result<(), GpuError> {
    match lens {
        Some(lens) => Err(crate::texturing::unsupported(&format!(
            "a camera with a {} lens",
            lens.model().name()
        ))),
        None => Ok(()),
    }
}
