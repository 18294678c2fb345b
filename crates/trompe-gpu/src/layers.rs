//! Layered projective rendering on the GPU ("Layered view-dependent projective textures" §5, as
//! the paper ran it on graphics hardware): every object textured through the image layer that
//! holds its triangle in each view, each layer projected through its own asymmetric
//! sub-frustum (its texture matrix); every layer's image one layer of a texture array and its
//! depth a layer of another; a frame the blend of [`crate::texturing`] over that source
//! (`shaders/layers.wgsl`).
//!
//! The CPU twin is [`trompe::layers::render`]: the same sight (a layer's texels it holds on the
//! point's surface, else its edge) and the same lookups; holes as the CPU leaves them.
//!
//! Invariant: the layers are uploaded once and every frame reuses them; a frame's pixels depend
//! only on the layer set, the camera and the settings.

use crate::device::{Gpu, GpuError};
use crate::methods::DeviceError;
use crate::raster::v4;
use crate::texturing::{
    Blender, check_settings, entries, halves, padded_layer, texture_array, unsupported,
};
use bytemuck::{Pod, Zeroable};
use trompe::camera::{Intrinsics, Pinhole};
use trompe::layers::LayerSet;
use trompe::texturing::{Blend, BlendSettings};

/// The layers' source WGSL (the rules of images with depth go before it, the blend after).
pub const LAYERS_SHADER: &str = include_str!("../shaders/layers.wgsl");

/// The layers' whole source: the rules of images with depth, then the layers'.
pub fn layers_source() -> String {
    format!("{}\n{LAYERS_SHADER}", crate::views::DEPTH_IMAGES_SHADER)
}

/// An image layer as the shader reads it (`shaders/layers.wgsl`'s `Layer`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuLayer {
    rows: [[f32; 4]; 4],
    size: [f32; 4],
}

/// A layer set uploaded once, rendered through any pinhole.
pub struct GpuLayers<'a> {
    gpu: &'a Gpu,
    blender: Blender,
    faces: wgpu::Buffer,
    layers: wgpu::Buffer,
    holders: wgpu::Buffer,
    images: wgpu::TextureView,
    depths: wgpu::TextureView,
}

impl<'a> GpuLayers<'a> {
    /// Uploads `set` (its meshes, every view's image layers, their depth and projectors, which
    /// layer holds each triangle) to `gpu`, to be rendered with `settings`.
    pub fn new(
        gpu: &'a Gpu,
        set: &LayerSet,
        settings: &BlendSettings,
    ) -> Result<Self, DeviceError> {
        check_settings(settings)?;
        if set.layers.len() != set.views.len() {
            let what = format!(
                "{} views but {} views' layers",
                set.views.len(),
                set.layers.len()
            );
            return Err(GpuError::Unsupported { what }.into());
        }
        // The objects' triangles, one after another: a face's number in the frame.
        let corners: Vec<[glam::Vec3; 3]> = set
            .meshes
            .iter()
            .flat_map(|m| (0..m.triangle_count()).map(|t| m.corners(t)))
            .collect();
        let table = trompe::layers::render::face_table(set, settings).map_err(GpuError::from)?;
        let centres: Vec<glam::DVec3> = set.views.iter().map(|v| v.pose.centre()).collect();
        let blender = Blender::new(
            gpu,
            &corners,
            &centres,
            &table,
            settings,
            ("layers.wgsl", &layers_source()),
        )?;
        // Every view's layers, one after another; per view and face, the layer holding it.
        let mut gpu_layers = Vec::new();
        let mut holders = Vec::with_capacity(set.views.len() * corners.len());
        let mut largest = (1u32, 1u32);
        let mut images = Vec::new();
        for (view, vl) in set.layers.iter().enumerate() {
            let first = gpu_layers.len() as u32;
            for (l, layer) in vl.layers.iter().enumerate() {
                let projector =
                    set.projectors
                        .get(view)
                        .and_then(|p| p.get(l))
                        .ok_or_else(|| {
                            unsupported(&format!("view {view}'s layer {l} has no projector"))
                        })?;
                let m = projector.texture_matrix.transpose();
                let (w, h) = layer.image.size();
                if projector.size != (w, h) || vl.depth.get(l).map(|d| d.size()) != Some((w, h)) {
                    let what = format!(
                        "view {view}'s layer {l}: its image, depth and projector differ in size"
                    );
                    return Err(GpuError::Unsupported { what }.into());
                }
                gpu_layers.push(GpuLayer {
                    rows: [0, 1, 2, 3].map(|i| m.col(i).as_vec4().to_array()),
                    size: [w as f32, h as f32, 0.0, 0.0],
                });
                largest = (largest.0.max(w), largest.1.max(h));
                images.push((&layer.image, &vl.depth[l]));
            }
            for (object, mesh) in set.meshes.iter().enumerate() {
                let assignment = vl.assignment.get(object);
                holders.extend((0..mesh.triangle_count()).map(|t| {
                    assignment
                        .and_then(|a| a.layer(t))
                        .filter(|&l| (l as usize) < vl.layers.len())
                        .map_or(0, |l| first + l + 1)
                }));
            }
        }
        let layer_count = images.len() as u32;
        let (lw, lh) = largest;
        let image_array = texture_array(
            gpu,
            "image layers",
            (lw, lh, layer_count),
            (wgpu::TextureFormat::Rgba16Float, 8),
            |layer| padded_layer(Some(images[layer as usize].0), (lw, lh), halves),
        )?;
        let depth_array = texture_array(
            gpu,
            "image layers' depth",
            (lw, lh, layer_count),
            (wgpu::TextureFormat::R32Float, 4),
            |layer| padded_layer(Some(images[layer as usize].1), (lw, lh), |g| [g]),
        )?;
        let faces: Vec<[[f32; 4]; 3]> = corners.iter().map(|c| c.map(|p| v4(p, 1.0))).collect();
        let face_bytes: &[u8] = bytemuck::cast_slice(&faces);
        gpu.check_storage("the meshes' faces", face_bytes.len() as u64)?;
        gpu.check_storage("the layers holding each face", holders.len() as u64 * 4)?;
        Ok(GpuLayers {
            gpu,
            blender,
            faces: gpu.storage_with("faces", face_bytes),
            layers: gpu.storage_with("image layers", bytemuck::cast_slice(&gpu_layers)),
            holders: gpu.storage_with("layer of each face", bytemuck::cast_slice(&holders)),
            images: image_array,
            depths: depth_array,
        })
    }

    /// The layer set's meshes through `camera`: the image and its pixels' counts, as
    /// [`trompe::layers::render::render`] makes them.
    pub fn render(&self, camera: &Pinhole) -> Result<Blend, GpuError> {
        let source = entries(
            &[(1, &self.faces), (8, &self.layers), (10, &self.holders)],
            &[(3, &self.images), (9, &self.depths)],
        );
        self.blender.render(self.gpu, camera, &source)
    }
}

/// Renders `set`'s meshes through `camera` on `gpu`, or with the library's
/// [`trompe::layers::render::render_through`] on the CPU without one. On the GPU, a camera with
/// a lens is refused.
pub fn render_through(
    gpu: Option<&Gpu>,
    (camera, lens): (&Pinhole, Option<&Intrinsics>),
    set: &LayerSet,
    settings: &BlendSettings,
) -> Result<Blend, DeviceError> {
    let Some(gpu) = gpu else {
        let cpu = trompe::layers::render::render_through((camera, lens), set, settings)
            .map_err(GpuError::from)?;
        return Ok(cpu);
    };
    crate::master::refuse_lens(lens)?;
    let uploaded = GpuLayers::new(gpu, set, settings)?;
    Ok(uploaded.render(camera)?)
}

/// Plain projective texturing of `meshes` from `views`' whole photographs through `camera` on
/// `gpu` ([`crate::views::GpuViews::photographs`]), or with the library's
/// [`trompe::layers::render::render_projective_through`] on the CPU without one. On the GPU, a
/// camera with a lens is refused.
pub fn render_projective_through(
    gpu: Option<&Gpu>,
    (camera, lens): (&Pinhole, Option<&Intrinsics>),
    meshes: &[&trompe::geom::Mesh],
    views: &[trompe::views::CalibratedView],
    settings: &BlendSettings,
) -> Result<Blend, DeviceError> {
    let Some(gpu) = gpu else {
        let cpu = trompe::layers::render::render_projective_through(
            (camera, lens),
            meshes,
            views,
            settings,
        )
        .map_err(GpuError::from)?;
        return Ok(cpu);
    };
    crate::master::refuse_lens(lens)?;
    let uploaded = crate::views::GpuViews::photographs(gpu, meshes, views, settings)?;
    Ok(uploaded.render(camera)?)
}
