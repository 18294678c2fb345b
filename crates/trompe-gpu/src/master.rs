//! Rendering from master textures on the GPU ("Master Texture" §4, the paper's rendering path):
//! every view's master texture is one layer of a texture array, the mesh carries one atlas
//! point a corner, and a frame is the mesh drawn by the GPU rasterizer into a visibility buffer
//! ([`crate::raster`]), then one compute invocation a pixel (`shaders/master.wgsl`) that asks
//! every view at the pixel's one texture coordinate and blends those that see it.
//!
//! The CPU twin is [`trompe::master::render`] over [`trompe::texturing::render`]: the same
//! sight by the master's alpha, the same clear-then-edge passes, the same ULR and VDTM weights
//! and the same bilinear lookup over texels with a colour; the best-face table is the library's
//! own ([`trompe::master::render::best_faces`]), built once on the CPU. Holes filled from the
//! nearest seen surface are filled by the library after the frame is read back.
//!
//! Not on the GPU (refused before any work, with what to do instead): the view map, a seamless
//! best-face bake, prefiltering to the pixel's footprint, and a camera with a lens.
//!
//! Invariant: a frame's pixels depend only on the masters, the mesh, the camera and the
//! settings; the masters are uploaded once and every frame reuses them.

use crate::device::{Gpu, GpuError, extent};
use crate::methods::DeviceError;
use crate::raster::{
    GpuRasterCamera, draw_into_visibility, raster_pipeline_of, v4, visibility_texture,
};
use bytemuck::{Pod, Zeroable};
use glam::{DVec2, Vec4};
use trompe::camera::{Pinhole, Projection};
use trompe::frame::{Image, Rgba};
use trompe::geom::Mesh;
use trompe::master::layout::Layout;
use trompe::texturing::fill::{Pixel, from_nearest};
use trompe::texturing::{Blend, BlendSettings, Holes, Weighting};

/// The master-texture renderer's source.
pub const MASTER_SHADER: &str = include_str!("../shaders/master.wgsl");

/// The most views a pixel blends on the GPU (`shaders/master.wgsl`'s `K_MAX`).
pub const MAX_K: usize = 64;

/// A face as the shader reads it: its corners, and its atlas point and steps.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuFace {
    corners: [[f32; 4]; 3],
    atlas0: [f32; 4],
    atlas1: [f32; 4],
}

/// The shader's `Params`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuParams {
    eye: [f32; 4],
    size: [u32; 4],
    mode: [u32; 4],
    fill: [f32; 4],
}

/// Master textures uploaded once, rendered through any pinhole.
pub struct GpuMasters<'a> {
    gpu: &'a Gpu,
    raster: (wgpu::RenderPipeline, wgpu::Buffer, u32),
    faces: wgpu::Buffer,
    centres: wgpu::Buffer,
    best: wgpu::Buffer,
    masters: wgpu::TextureView,
    views: u32,
    settings: BlendSettings,
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
        let unsupported = |what: &str| GpuError::Unsupported {
            what: format!("{what} (render it with --device cpu)"),
        };
        let mode = match settings.weighting {
            Weighting::Ulr { .. } => 0,
            Weighting::Vdtm => 1,
            Weighting::BestFace if settings.seamless => {
                return Err(unsupported("a seamless best-face bake is not on the GPU yet").into());
            }
            Weighting::BestFace => 2,
            Weighting::ViewMap => {
                return Err(unsupported("the view-map weighting is not on the GPU yet").into());
            }
        };
        if settings.prefilter {
            let what = "prefiltering to the pixel's footprint is not on the GPU yet";
            return Err(unsupported(what).into());
        }
        if settings.k > MAX_K {
            let what = format!(
                "k = {} views a pixel: the GPU blends at most {MAX_K}",
                settings.k
            );
            return Err(unsupported(&what).into());
        }
        // The library's own checks (faces, pairing) and, for best face, its table.
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
        gpu.check_texture("the master textures", w, h)?;
        let views = masters.len() as u32;
        let layers = gpu.limits().max_texture_array_layers;
        if views > layers {
            let what = format!(
                "{views} master textures: {} holds at most {layers} in one texture array",
                gpu.name()
            );
            return Err(unsupported(&what).into());
        }
        let corners: Vec<[glam::Vec3; 3]> = (0..mesh.triangle_count())
            .map(|t| mesh.corners(t))
            .collect();
        let raster = raster_pipeline_of(gpu, &corners)?;
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
        let centres: Vec<[f32; 4]> = cameras
            .iter()
            .map(|c| v4(c.position().as_vec3(), 0.0))
            .collect();
        let best: Vec<u32> = match mode {
            2 => trompe::master::render::best_faces(mesh, layout, cameras, masters)?
                .iter()
                .map(|v| v.map_or(0, |i| i as u32 + 1))
                .collect(),
            _ => vec![0],
        };
        Ok(GpuMasters {
            gpu,
            raster,
            faces: gpu.storage_with("faces", face_bytes),
            centres: gpu.storage_with("view centres", bytemuck::cast_slice(&centres)),
            best: gpu.storage_with("best faces", bytemuck::cast_slice(&best)),
            masters: upload_masters(gpu, masters, (w, h))?,
            views,
            settings: *settings,
        })
    }

    /// The mesh through `camera`, blended from the masters: the image and its pixels' counts,
    /// as [`trompe::master::render::render`] makes them.
    pub fn render(&self, camera: &Pinhole) -> Result<Blend, GpuError> {
        let gpu = self.gpu;
        let (w, h) = camera.resolution();
        gpu.check_texture("the frame", w, h)?;
        let pixels = u64::from(w) * u64::from(h);
        gpu.check_storage("the frame", pixels * 16)?;
        let visibility = visibility_texture(gpu, w, h);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        draw_into_visibility(
            gpu,
            &mut encoder,
            &self.raster,
            &GpuRasterCamera::pinhole(camera),
            &visibility,
            (w, h),
        );
        let s = &self.settings;
        let params = GpuParams {
            eye: v4(
                camera.position().as_vec3(),
                match s.weighting {
                    Weighting::Ulr { beta } => beta as f32,
                    _ => 0.0,
                },
            ),
            size: [w, h, self.views, s.k as u32],
            mode: [
                match s.weighting {
                    Weighting::Ulr { .. } => 0,
                    Weighting::Vdtm => 1,
                    _ => 2,
                },
                u32::from(matches!(s.holes, Holes::Fill(_))),
                0,
                0,
            ],
            fill: match s.holes {
                Holes::Fill(c) => c.to_array(),
                _ => [0.0; 4],
            },
        };
        let uniform = gpu.uniform_with("master params", bytemuck::bytes_of(&params));
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let colour = gpu.buffer("colour", pixels * 16, storage);
        let state = gpu.buffer("pixel state", pixels * 4, storage);
        let pipeline = gpu.compute_pipeline("master.wgsl", MASTER_SHADER, "render_masters");
        let visibility_view = visibility.create_view(&Default::default());
        let buffers = [
            (1, &self.faces),
            (2, &self.centres),
            (4, &uniform),
            (5, &self.best),
            (6, &colour),
            (7, &state),
        ];
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("master textures"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &buffers
                .into_iter()
                .map(|(binding, b)| wgpu::BindGroupEntry {
                    binding,
                    resource: b.as_entire_binding(),
                })
                .chain([
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&visibility_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&self.masters),
                    },
                ])
                .collect::<Vec<_>>(),
        });
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        let read = gpu.read_back(encoder, &[colour, state], "the master-texture frame")?;
        let colours: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read[0][..pixels as usize * 16]);
        let states: Vec<u32> = bytemuck::pod_collect_to_vec(&read[1][..pixels as usize * 4]);
        let mut image = Image::new(w, h, Vec4::ZERO)?;
        for (out, c) in image.pixels_mut().iter_mut().zip(&colours) {
            *out = Vec4::from_array(*c);
        }
        let shown: Vec<Pixel> = states
            .iter()
            .map(|s| match s {
                1 => Pixel::Seen,
                2 => Pixel::Hole,
                _ => Pixel::Background,
            })
            .collect();
        let covered = shown.iter().filter(|p| **p != Pixel::Background).count();
        let holes = shown.iter().filter(|p| **p == Pixel::Hole).count();
        let filled = match s.holes {
            Holes::Nearest if holes > 0 => from_nearest(&mut image, &shown),
            _ => 0,
        };
        Ok(Blend {
            image,
            covered,
            holes,
            filled,
            seams: None,
        })
    }
}

/// `masters` (each `w × h`) as the layers of one half-float texture array.
fn upload_masters(
    gpu: &Gpu,
    masters: &[Image<Rgba>],
    (w, h): (u32, u32),
) -> Result<wgpu::TextureView, GpuError> {
    let layers = masters.len().max(1) as u32;
    let bytes = u64::from(w) * u64::from(h) * 8 * u64::from(layers);
    trompe::memory::check(
        || format!("{layers} master textures of {w} × {h} as half floats"),
        bytes,
    )?;
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("master textures"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (layer, master) in masters.iter().enumerate() {
        let halves: Vec<half::f16> = master
            .pixels()
            .iter()
            .flat_map(|c| c.to_array().map(half::f16::from_f32))
            .collect();
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer as u32,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&halves),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 8),
                rows_per_image: Some(h),
            },
            extent((w, h)),
        );
    }
    Ok(texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    }))
}

/// Renders `mesh` through `camera` from the encoding `trompe master encode` wrote in `dir`, on
/// `gpu`: [`trompe::master::job::render_folder`] on the GPU. A camera with a lens is refused
/// (the GPU rasterizer draws through a pinhole).
pub fn render_folder(
    gpu: &Gpu,
    dir: &std::path::Path,
    mesh: &Mesh,
    (camera, lens): (&Pinhole, Option<&trompe::camera::Intrinsics>),
    settings: &BlendSettings,
) -> Result<Blend, DeviceError> {
    if let Some(lens) = lens {
        let what = format!(
            "a camera with a {} lens (render it with --device cpu)",
            lens.model().name()
        );
        return Err(GpuError::Unsupported { what }.into());
    }
    let (manifest, masters) = trompe::master::file::load(dir)?;
    let cameras: Vec<Pinhole> = manifest.views.iter().map(|v| v.pinhole()).collect();
    let uploaded = GpuMasters::new(gpu, mesh, (&manifest.layout, &cameras, &masters), settings)?;
    Ok(uploaded.render(camera)?)
}
