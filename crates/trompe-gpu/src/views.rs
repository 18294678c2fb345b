//! View-dependent projective texturing from calibrated views on the GPU: every view's image one
//! layer of a texture array and its depth map a layer of another (each padded to the largest
//! view), and a frame the blend of [`crate::texturing`] over a source (`shaders/views.wgsl`)
//! that tests each view's visibility against its depth map and looks its image up on the
//! point's surface.
//!
//! The CPU twin is [`trompe::views::blend`] with [`trompe::views::visibility`]: the same
//! seen / edge / hidden rule and the same depth-aware bilinear lookup; the best-face table and
//! the view maps are the library's own, built once on the CPU from the same views.
//!
//! The same source projects whole photographs, without depth maps ([`GpuViews::photographs`]):
//! paper 4's baseline, [`trompe::layers::render::render_projective`] on the GPU.
//!
//! Not on the GPU (refused before any work): a view with lens distortion (its image is looked up
//! through the lens on the CPU), and what [`crate::texturing`] refuses.
//!
//! Invariant: the views are uploaded once and every frame reuses them.

use crate::device::{Gpu, GpuError};
use crate::methods::DeviceError;
use crate::raster::v4;
use crate::texturing::{
    Blender, check_settings, entries, halves, padded_layer, texture_array, unsupported,
};
use bytemuck::{Pod, Zeroable};
use trompe::camera::{Intrinsics, Pinhole};
use trompe::geom::Mesh;
use trompe::texturing::{Blend, BlendSettings};
use trompe::views::CalibratedView;
use trompe::views::blend::ViewSource;
use trompe::views::visibility::DepthMap;

/// The calibrated views' source WGSL (the blend follows it).
pub const VIEWS_SHADER: &str = include_str!("../shaders/views.wgsl");

/// The views' whole source: the rules of images with depth, then the views'.
pub fn views_source() -> String {
    format!("{DEPTH_IMAGES_SHADER}\n{VIEWS_SHADER}")
}

/// The rules of images with depth (`shaders/depth_images.wgsl`), shared with the layers.
pub const DEPTH_IMAGES_SHADER: &str = include_str!("../shaders/depth_images.wgsl");

/// A view as the shader reads it (`shaders/views.wgsl`'s `View`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuView {
    depth_rows: [[f32; 4]; 3],
    depth_eye: [f32; 4],
    rotation: [[f32; 4]; 3],
    centre: [f32; 4],
    intrinsics: [f32; 4],
    size: [f32; 4],
}

/// Calibrated views and their depth maps uploaded once, rendered through any pinhole.
pub struct GpuViews<'a> {
    gpu: &'a Gpu,
    blender: Blender,
    faces: wgpu::Buffer,
    views: wgpu::Buffer,
    images: wgpu::TextureView,
    depths: wgpu::TextureView,
    /// The view left out of every blend, if any.
    exclude: Option<usize>,
}

impl<'a> GpuViews<'a> {
    /// Uploads `views` (their images loaded), their depth maps `depth` (one a view,
    /// [`DepthMap::of_all`]) and `mesh` to `gpu`, to be rendered with `settings`; `exclude`
    /// leaves one view out (leave-one-out scoring), as [`trompe::views::blend::render`] does.
    pub fn new(
        gpu: &'a Gpu,
        mesh: &Mesh,
        (views, depth): (&[CalibratedView], &[DepthMap]),
        settings: &BlendSettings,
        exclude: Option<usize>,
    ) -> Result<Self, DeviceError> {
        Self::upload(gpu, &[mesh], (views, Some(depth)), settings, exclude)
    }

    /// Uploads `views`' whole photographs (their images loaded) and `meshes` to `gpu`: plain
    /// projective texturing, each photograph projected onto everything in its frame, hidden or
    /// not, as [`trompe::layers::render::render_projective`] does (paper 4's baseline).
    pub fn photographs(
        gpu: &'a Gpu,
        meshes: &[&Mesh],
        views: &[CalibratedView],
        settings: &BlendSettings,
    ) -> Result<Self, DeviceError> {
        Self::upload(gpu, meshes, (views, None), settings, None)
    }

    /// Uploads `views` and `meshes` (their faces one after another), each view seen through its
    /// depth map or, without depth maps, projected whole.
    fn upload(
        gpu: &'a Gpu,
        meshes: &[&Mesh],
        (views, depth): (&[CalibratedView], Option<&[DepthMap]>),
        settings: &BlendSettings,
        exclude: Option<usize>,
    ) -> Result<Self, DeviceError> {
        check_settings(settings)?;
        // A view takes part where it has an image, a depth map (when seen through them), and
        // is not left out.
        let has_depth = |i: usize| depth.is_none_or(|d| i < d.len());
        let takes_part = |i: usize| views[i].image.is_some() && has_depth(i) && Some(i) != exclude;
        if let Some(v) = (0..views.len())
            .filter(|&i| takes_part(i))
            .map(|i| &views[i])
            .find(|v| !v.intrinsics.is_undistorted())
        {
            let what = format!(
                "view {} has {} lens distortion, looked up through the lens on the CPU only",
                v.name,
                v.intrinsics.model().name()
            );
            return Err(unsupported(&what).into());
        }
        let depth_of = |i: usize| depth.and_then(|d| d.get(i));
        if let Some(i) = (0..views.len()).filter(|&i| takes_part(i)).find(|&i| {
            let image = views[i].image.as_ref().map(|m| m.size());
            depth_of(i).is_some_and(|d| Some(d.gd().size()) != image)
        }) {
            let what = format!(
                "view {}'s depth map is not the size of its image",
                views[i].name
            );
            return Err(GpuError::Unsupported { what }.into());
        }
        let blender = blender(gpu, meshes, (views, depth), settings, exclude)?;
        let corners: Vec<[glam::Vec3; 3]> = meshes
            .iter()
            .flat_map(|m| (0..m.triangle_count()).map(|t| m.corners(t)))
            .collect();
        let faces: Vec<[[f32; 4]; 3]> = corners.iter().map(|c| c.map(|p| v4(p, 1.0))).collect();
        let face_bytes: &[u8] = bytemuck::cast_slice(&faces);
        gpu.check_storage("the mesh's faces", face_bytes.len() as u64)?;
        let gpu_views: Vec<GpuView> = (0..views.len())
            .map(|i| gpu_view(&views[i], depth_of(i), takes_part(i)))
            .collect();
        let layers = views.len() as u32;
        let image_size = |i: usize| views[i].image.as_ref().map_or((1, 1), |m| m.size());
        let depth_size = |i: usize| depth_of(i).map_or((1, 1), |d| d.gd().size());
        let largest = |size: &dyn Fn(usize) -> (u32, u32)| {
            (0..views.len()).fold((1, 1), |(w, h), i| {
                let (a, b) = size(i);
                (w.max(a), h.max(b))
            })
        };
        let (iw, ih) = largest(&image_size);
        let (dw, dh) = largest(&depth_size);
        // Half floats for the photographs' 8-bit texels; depth in full.
        let images = texture_array(
            gpu,
            "views' images",
            (iw, ih, layers),
            (wgpu::TextureFormat::Rgba16Float, 8),
            |layer| padded_layer(views[layer as usize].image.as_ref(), (iw, ih), halves),
        )?;
        let depths = texture_array(
            gpu,
            "views' depth maps",
            (dw, dh, layers),
            (wgpu::TextureFormat::R32Float, 4),
            |layer| {
                padded_layer(depth_of(layer as usize).map(DepthMap::gd), (dw, dh), |g| {
                    [g]
                })
            },
        )?;
        Ok(GpuViews {
            gpu,
            blender,
            faces: gpu.storage_with("faces", face_bytes),
            views: gpu.storage_with("views", bytemuck::cast_slice(&gpu_views)),
            images,
            depths,
            exclude,
        })
    }

    /// Blends with `settings` from now on: the weighting's per-face table and the shader made
    /// again from `meshes` and `views` (and `depth`), which must be those uploaded; the images
    /// and depth maps stay where they are.
    pub fn reweigh(
        &mut self,
        meshes: &[&Mesh],
        (views, depth): (&[CalibratedView], Option<&[DepthMap]>),
        settings: &BlendSettings,
    ) -> Result<(), DeviceError> {
        check_settings(settings)?;
        self.blender = blender(self.gpu, meshes, (views, depth), settings, self.exclude)?;
        Ok(())
    }

    /// The mesh through `camera`, blended from the views: the image and its pixels' counts, as
    /// [`trompe::views::blend::render`] makes them.
    pub fn render(&self, camera: &Pinhole) -> Result<Blend, GpuError> {
        let source = entries(
            &[(1, &self.faces), (8, &self.views)],
            &[(3, &self.images), (9, &self.depths)],
        );
        self.blender.render(self.gpu, camera, &source)
    }
}

/// The blend of `views` over `meshes` with `settings`: the weighting's per-face table, the
/// views' centres and the whole shader.
fn blender(
    gpu: &Gpu,
    meshes: &[&Mesh],
    (views, depth): (&[CalibratedView], Option<&[DepthMap]>),
    settings: &BlendSettings,
    exclude: Option<usize>,
) -> Result<Blender, DeviceError> {
    let table = match depth {
        Some(depth) => {
            let source = ViewSource::new(views, depth, settings.tolerance, exclude);
            trompe::texturing::face_table(settings.weighting, meshes, &source)
        }
        None => trompe::layers::render::projective_face_table(meshes, views, settings.weighting),
    }
    .map_err(GpuError::from)?;
    let corners: Vec<[glam::Vec3; 3]> = meshes
        .iter()
        .flat_map(|m| (0..m.triangle_count()).map(|t| m.corners(t)))
        .collect();
    let centres: Vec<glam::DVec3> = views.iter().map(|v| v.pose.centre()).collect();
    Ok(Blender::new(
        gpu,
        &corners,
        &centres,
        &table,
        settings,
        ("views.wgsl", &views_source()),
    )?)
}

/// View `view` as the shader reads it: its depth map's pinhole (without one, its whole
/// photograph is projected), its pose and intrinsics, its size; `takes_part` false leaves it
/// out of every blend.
fn gpu_view(view: &CalibratedView, depth: Option<&DepthMap>, takes_part: bool) -> GpuView {
    let (depth_rows, depth_eye) = match depth {
        Some(d) => {
            let camera = d.camera();
            let inverse = camera.mcmillan_inverse();
            let row = |i: usize| v4(inverse.row(i).as_vec3(), 0.0);
            (
                [row(0), row(1), row(2)],
                v4(camera.position().as_vec3(), 0.0),
            )
        }
        None => ([[0.0; 4]; 3], [0.0; 4]),
    };
    let whole = f32::from(u8::from(depth.is_none()));
    let rotation = glam::DMat3::from_quat(view.pose.rotation);
    let row = |i: usize| v4(rotation.row(i).as_vec3(), 0.0);
    let ((fx, fy), (cx, cy)) = (view.intrinsics.focal(), view.intrinsics.principal_point());
    let (iw, ih) = view.image.as_ref().map_or((0, 0), |m| m.size());
    GpuView {
        depth_rows,
        depth_eye,
        rotation: [row(0), row(1), row(2)],
        centre: v4(
            view.pose.centre().as_vec3(),
            f32::from(u8::from(takes_part)),
        ),
        intrinsics: [fx as f32, fy as f32, cx as f32, cy as f32],
        size: [iw as f32, ih as f32, whole, 0.0],
    }
}

/// Renders `mesh` through `camera` textured from `views` (their images loaded) with their depth
/// maps `depth`, on `gpu`, or with the library's [`trompe::views::blend::render_through`] on
/// the CPU without one. On the GPU, a camera with a lens is refused.
pub fn render_through(
    gpu: Option<&Gpu>,
    (camera, lens): (&Pinhole, Option<&Intrinsics>),
    mesh: &Mesh,
    (views, depth): (&[CalibratedView], &[DepthMap]),
    settings: &BlendSettings,
    exclude: Option<usize>,
) -> Result<Blend, DeviceError> {
    let Some(gpu) = gpu else {
        let cpu = trompe::views::blend::render_through(
            camera, lens, mesh, views, depth, settings, exclude,
        )
        .map_err(GpuError::from)?;
        return Ok(cpu);
    };
    crate::master::refuse_lens(lens)?;
    let uploaded = GpuViews::new(gpu, mesh, (views, depth), settings, exclude)?;
    Ok(uploaded.render(camera)?)
}
