//! Projective texturing's blend on the GPU, shared by the sources that texture a mesh from
//! views ([`crate::views`], [`crate::layers`], [`crate::master`]): the mesh drawn by the GPU
//! rasterizer into a visibility buffer ([`crate::raster`]), then one compute invocation a pixel
//! (`shaders/texturing.wgsl`, after the source's own WGSL) that asks every view how it sees the
//! pixel's surface, weights those that see it and blends their colours — the library's
//! [`trompe::texturing::render`] step by step: the same clear-then-edge passes, the same ULR and
//! VDTM weights with ties to the lower view, the view maps and best-face table the library
//! builds, the same prefilter to the pixel's footprint (found on the face's plane, n × n
//! lookups across it).
//!
//! Not on the GPU (refused before any work, with what to do instead): a seamless best-face bake
//! and more than [`MAX_K`] views a pixel. Holes filled from the nearest seen surface are filled
//! by the library after read-back.
//!
//! Invariant: a frame's pixels depend only on the source, the mesh, the camera and the
//! settings.

use crate::device::{Gpu, GpuError};
use crate::raster::{
    GpuRasterCamera, draw_into_visibility, raster_pipeline_of, v4, visibility_texture,
};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3, Vec4};
use trompe::camera::{Pinhole, Projection};
use trompe::frame::Image;
use trompe::texturing::fill::{Pixel, from_nearest};
use trompe::texturing::{Blend, BlendSettings, FaceTable, Holes, Weighting};

/// The blend's WGSL, which follows a source's.
pub const BLEND_SHADER: &str = include_str!("../shaders/texturing.wgsl");

/// The most views a pixel blends on the GPU (`shaders/texturing.wgsl`'s `K_MAX`).
pub const MAX_K: usize = 64;

/// A source's WGSL followed by the blend of at most `k` views a pixel (1 to [`MAX_K`]): the
/// whole shader.
pub fn shader_source(source: &str, k: usize) -> String {
    let k = k.clamp(1, MAX_K);
    format!("const K_MAX: u32 = {k}u;\n{source}\n{BLEND_SHADER}")
}

/// The shader's `Params`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuParams {
    eye: [f32; 4],
    camera: [[f32; 4]; 3],
    size: [u32; 4],
    mode: [u32; 4],
    fill: [f32; 4],
    extra: [f32; 4],
}

/// The refusal of what the GPU does not blend, pointing at the CPU.
pub(crate) fn unsupported(what: &str) -> GpuError {
    GpuError::Unsupported {
        what: format!("{what} (render it with --device cpu)"),
    }
}

/// Refuses `settings` the GPU does not blend, before any work.
pub(crate) fn check_settings(settings: &BlendSettings) -> Result<(), GpuError> {
    match settings.weighting {
        Weighting::BestFace if settings.seamless => Err(unsupported(
            "a seamless best-face bake is not on the GPU yet",
        )),
        _ if settings.k > MAX_K => Err(unsupported(&format!(
            "k = {} views a pixel: the GPU blends at most {MAX_K}",
            settings.k
        ))),
        _ => Ok(()),
    }
}

/// What every source's frame shares, uploaded once: the mesh's triangles, the views' centres,
/// the weighting's per-face table, the settings and the whole shader.
pub(crate) struct Blender {
    raster: (wgpu::RenderPipeline, wgpu::Buffer, u32),
    centres: wgpu::Buffer,
    best: wgpu::Buffer,
    /// The view map: its directions, its spherical triangles, its views; and its directions a
    /// face.
    view_map: ([wgpu::Buffer; 3], u32),
    views: u32,
    settings: BlendSettings,
    /// The module's label (with its k) and the whole shader.
    shader: (String, String),
}

impl Blender {
    /// The mesh's triangles `corners` (its objects' one after another, as its faces are
    /// numbered), the views' `centres`, the weighting's per-face `table` (the library's, over
    /// the same objects), and the source's WGSL named `label`. The settings must have passed
    /// [`check_settings`].
    pub(crate) fn new(
        gpu: &Gpu,
        corners: &[[Vec3; 3]],
        centres: &[DVec3],
        table: &FaceTable,
        settings: &BlendSettings,
        (label, source): (&'static str, &str),
    ) -> Result<Self, GpuError> {
        check_settings(settings)?;
        let raster = raster_pipeline_of(gpu, corners)?;
        let centres: Vec<[f32; 4]> = centres.iter().map(|c| v4(c.as_vec3(), 0.0)).collect();
        let best: Vec<u32> = match table {
            FaceTable::BestFace(tables) => tables
                .iter()
                .flatten()
                .map(|v| v.map_or(0, |i| i as u32 + 1))
                .collect(),
            _ => vec![0],
        };
        gpu.check_storage("the best-face table", best.len() as u64 * 4)?;
        Ok(Blender {
            raster,
            centres: gpu.storage_with("view centres", bytemuck::cast_slice(&centres)),
            best: gpu.storage_with("best faces", bytemuck::cast_slice(&best)),
            view_map: upload_view_maps(gpu, table)?,
            views: centres.len() as u32,
            settings: *settings,
            shader: (
                format!("{label}, k = {}", settings.k),
                shader_source(source, settings.k),
            ),
        })
    }

    /// The mesh through `camera`, blended from the source whose bindings are `source`
    /// (bindings 1, 3 and from 8 up; the blend holds 0, 2 and 4 to 7): the image and its pixels'
    /// counts, as the library's render makes them.
    pub(crate) fn render(
        &self,
        gpu: &Gpu,
        camera: &Pinhole,
        source: &[wgpu::BindGroupEntry],
    ) -> Result<Blend, GpuError> {
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
        let (mode, beta) = match s.weighting {
            Weighting::Ulr { beta } => (0, beta as f32),
            Weighting::Vdtm => (1, 0.0),
            Weighting::BestFace => (2, 0.0),
            Weighting::ViewMap => (3, 0.0),
        };
        let params = GpuParams {
            eye: v4(camera.position().as_vec3(), beta),
            camera: {
                let (a, b, c) = camera.mcmillan();
                [a, b, c].map(|v| v4(v.as_vec3(), 0.0))
            },
            size: [w, h, self.views, s.k as u32],
            mode: [
                mode,
                u32::from(matches!(s.holes, Holes::Fill(_))),
                self.view_map.1,
                u32::from(s.prefilter),
            ],
            fill: match s.holes {
                Holes::Fill(c) => c.to_array(),
                _ => [0.0; 4],
            },
            extra: [s.tolerance as f32, 0.0, 0.0, 0.0],
        };
        let uniform = gpu.uniform_with("blend params", bytemuck::bytes_of(&params));
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let colour = gpu.buffer("colour", pixels * 16, storage);
        let state = gpu.buffer("pixel state", pixels * 4, storage);
        let pipeline = gpu.compute_pipeline(&self.shader.0, &self.shader.1, "blend_views");
        let visibility_view = visibility.create_view(&Default::default());
        let [directions, triangles, views] = &self.view_map.0;
        let buffers = [
            (2, &self.centres),
            (4, &uniform),
            (5, &self.best),
            (6, &colour),
            (7, &state),
            (11, directions),
            (12, triangles),
            (13, views),
        ];
        let mut all = entries(&buffers, &[(0, &visibility_view)]);
        all.extend(source.iter().cloned());
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.shader.0),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &all,
        });
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        let read = gpu.read_back(encoder, &[colour, state], "the blended frame")?;
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

/// The view maps of `table` (one an object, their faces one after another) as the shader reads
/// them: the sample directions, the spherical triangles, the views two to a word; and the
/// directions a face. One entry each when the table is not a view map.
fn upload_view_maps(gpu: &Gpu, table: &FaceTable) -> Result<([wgpu::Buffer; 3], u32), GpuError> {
    let (directions, triangles, views, per_face) = match table {
        FaceTable::ViewMap(maps) if !maps.is_empty() => {
            let first = &maps[0];
            let directions: Vec<[f32; 4]> = first
                .directions()
                .iter()
                .map(|d| v4(d.as_vec3(), 0.0))
                .collect();
            let triangles: Vec<[u32; 4]> = first
                .sphere_faces()
                .iter()
                .map(|t| [t[0], t[1], t[2], 0])
                .collect();
            let entries: Vec<u16> = maps
                .iter()
                .flat_map(|m| m.table().iter().copied())
                .collect();
            let views: Vec<u32> = entries
                .chunks(2)
                .map(|pair| u32::from(pair[0]) | (u32::from(*pair.get(1).unwrap_or(&0)) << 16))
                .collect();
            (
                directions,
                triangles,
                views,
                first.directions().len() as u32,
            )
        }
        _ => (vec![[0.0; 4]], vec![[0; 4]], vec![0], 0),
    };
    gpu.check_storage("the view maps", views.len() as u64 * 4)?;
    Ok((
        [
            gpu.storage_with("view-map directions", bytemuck::cast_slice(&directions)),
            gpu.storage_with("view-map triangles", bytemuck::cast_slice(&triangles)),
            gpu.storage_with("view-map views", bytemuck::cast_slice(&views)),
        ],
        per_face,
    ))
}

/// Bind-group entries: storage buffers and texture views, by binding.
pub(crate) fn entries<'b>(
    buffers: &[(u32, &'b wgpu::Buffer)],
    textures: &[(u32, &'b wgpu::TextureView)],
) -> Vec<wgpu::BindGroupEntry<'b>> {
    let buffers = buffers.iter().map(|&(binding, b)| wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    });
    let textures = textures.iter().map(|&(binding, t)| wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(t),
    });
    buffers.chain(textures).collect()
}

/// `image`'s texels, each as `N` values `texel` gives, row by row into a layer `w` wide and `h`
/// tall (at least the image's size), zero beyond the image or without one: a texture array's
/// layer as `texture_array` uploads it.
pub(crate) fn padded_layer<T: Copy, U: Pod, const N: usize>(
    image: Option<&Image<T>>,
    (w, h): (u32, u32),
    texel: impl Fn(T) -> [U; N],
) -> Vec<u8> {
    let mut out = vec![U::zeroed(); w as usize * h as usize * N];
    if let Some(img) = image {
        for (y, row) in img.pixels().chunks(img.width() as usize).enumerate() {
            for (x, &t) in row.iter().enumerate() {
                let at = (y * w as usize + x) * N;
                out[at..at + N].copy_from_slice(&texel(t));
            }
        }
    }
    bytemuck::cast_slice(&out).to_vec()
}

/// A colour as the half floats of an `Rgba16Float` texel.
pub(crate) fn halves(c: trompe::frame::Rgba) -> [half::f16; 4] {
    c.to_array().map(half::f16::from_f32)
}

/// `layers` images of `w × h`, each given by `texels(layer)` (row-major, `w × h` of them), as
/// the layers of one texture array of `format`, `texel` bytes a texel.
pub(crate) fn texture_array(
    gpu: &Gpu,
    label: &'static str,
    (w, h, layers): (u32, u32, u32),
    (format, texel): (wgpu::TextureFormat, u32),
    texels: impl Fn(u32) -> Vec<u8>,
) -> Result<wgpu::TextureView, GpuError> {
    gpu.check_texture(label, w, h)?;
    let limit = gpu.limits().max_texture_array_layers;
    if layers > limit {
        return Err(unsupported(&format!(
            "{layers} {label}: {} holds at most {limit} in one texture array",
            gpu.name()
        )));
    }
    let bytes = u64::from(w) * u64::from(h) * u64::from(texel) * u64::from(layers.max(1));
    let what = format!("{layers} {label} of {w} × {h}");
    trompe::memory::check(|| what.clone(), bytes)?;
    let texture = gpu.allocating((&what, bytes), || {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: layers.max(1),
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    })?;
    for layer in 0..layers {
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            &texels(layer),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * texel),
                rows_per_image: Some(h),
            },
            crate::device::extent((w, h)),
        );
    }
    Ok(texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    }))
}
