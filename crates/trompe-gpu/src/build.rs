//! Paper 1's impostors built where the paper built them (§3.1): the mesh drawn by the GPU
//! rasterizer through the impostor's camera into a visibility image — per texel the triangle
//! its centre sees and the perspective-correct barycentrics there (`shaders/raster.wgsl`, the
//! primary pass's shader) — read back and resolved into the maps by the library
//! ([`trompe::impostor::resolve_drawn`]), exactly as it resolves its own rasterizer's image.
//!
//! Pinhole and orthographic cameras (a cube map is six pinholes), the SPOC — the mesh
//! tessellated by the library's rule (§3.1: an edge splits while its image strays half a pixel
//! from its chord), each corner projected through the SPOC in the vertex shader, each texel
//! named by its source triangle — and the graph camera (§4.5): the library clips the triangles
//! to each frustum ([`trompe::impostor::graph_pieces`]), and the GPU draws every frustum's
//! pieces through its own matrix over one image, the largest `gd` kept. Depth layers are
//! peeled by the GPU too ([`peel`]): each layer drawn again under the one before's depth as a
//! ceiling, the library choosing the triangles, the stop and the resolve
//! ([`Impostor::peel_drawn`]).
//!
//! Invariant: a GPU-built impostor differs from the CPU-built one only where the two
//! rasterizers' coverage rules or depth rounding pick another triangle for a texel
//! (`tests/system/build.rs` states the bound).

use crate::device::{Gpu, GpuError};
use crate::raster::{
    GpuRasterCamera, RasterDraw, draw_ranges_into_visibility, raster_pipeline_of,
    visibility_pipeline, visibility_texture,
};
use glam::{Vec2, Vec3};
use trompe::geom::Mesh;
use trompe::impostor::{
    DrawnImage, DrawnTexel, Impostor, ImpostorCamera, LayerError, Layers, PEEL_GAP, SurfaceSample,
};

/// Why an impostor could not be built on the GPU.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The device's.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The library's, resolving the image.
    #[error(transparent)]
    Drawn(#[from] trompe::impostor::DrawnError),
    /// The library's, peeling layers.
    #[error(transparent)]
    Layers(#[from] LayerError),
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

/// Peels `impostor`'s depth layers on `gpu` ([`Impostor::peel`] drawn by the GPU): `mesh`
/// (object id `object`, coloured by `color`) is the mesh it was built from. The first layer's
/// depth is drawn once more; then each layer is the facing triangles drawn under the one
/// before's depth, [`PEEL_GAP`] nearer the camera, as the library's ceiling.
///
/// # Errors
/// What [`Impostor::peel`] refuses (a graph camera, a count out of range), and the device's.
pub fn peel<F: Fn(&SurfaceSample) -> Vec3 + Sync>(
    gpu: &Gpu,
    impostor: &mut Impostor,
    (mesh, object): (&Mesh, u32),
    color: &F,
    layers: Layers,
) -> Result<(), BuildError> {
    let camera = impostor.camera().clone();
    // The depth drawn at each texel by the layer before, as the device writes it.
    let mut above: Option<Vec<f32>> = None;
    let mut draw = |facing: &Mesh| -> Result<DrawnImage, String> {
        let depth = match above.take() {
            Some(depth) => depth,
            None => {
                draw_under(gpu, &camera, mesh, None)
                    .map_err(|e| e.to_string())?
                    .1
            }
        };
        let ceiling: Vec<f32> = depth.iter().map(|d| d * (1.0 - PEEL_GAP)).collect();
        let (image, depth) =
            draw_under(gpu, &camera, facing, Some(&ceiling)).map_err(|e| e.to_string())?;
        above = Some(depth);
        Ok(image)
    };
    impostor.peel_drawn((mesh, object), color, layers, &mut draw)?;
    Ok(())
}

/// The GPU as the impostor methods' drawer ([`trompe::render::ImpostorDrawer`]): it draws every
/// impostor the methods build (cube maps, floors, SPOCs, pinhole-impostor's planar images, the
/// maze's graph cameras).
pub struct GpuDrawer<'a>(pub &'a Gpu);

impl trompe::render::ImpostorDrawer for GpuDrawer<'_> {
    fn draw(&self, camera: &ImpostorCamera, mesh: &Mesh) -> Option<Result<DrawnImage, String>> {
        Some(draw(self.0, camera, mesh).map_err(|e| e.to_string()))
    }
}

/// The visibility image of `mesh` through `camera`, drawn on `gpu`: per texel, row-major, the
/// triangle of `mesh` its centre sees and the barycentrics of its corners 1 and 2 there, and
/// through a graph camera the frustum that drew it.
pub fn draw(gpu: &Gpu, camera: &ImpostorCamera, mesh: &Mesh) -> Result<DrawnImage, GpuError> {
    if let ImpostorCamera::Graph(g) = camera {
        return draw_graph(gpu, g, mesh);
    }
    Ok(draw_under(gpu, camera, mesh, None)?.0)
}

/// [`draw`] through a pinhole, orthographic or SPOC camera, under a `ceiling` if given (per
/// texel, row-major, a depth as the device writes it: only fragments strictly behind it are
/// drawn), and the depth drawn at each texel (0 where nothing is).
fn draw_under(
    gpu: &Gpu,
    camera: &ImpostorCamera,
    mesh: &Mesh,
    ceiling: Option<&[f32]>,
) -> Result<(DrawnImage, Vec<f32>), GpuError> {
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
    let draws = [(uniform, 0..3 * corners.len() as u32)];
    let texels = draw_and_read(gpu, &corners, (&draws, ceiling), (w, h))?;
    let source = tessellation.as_ref().map(|t| t.source.as_slice());
    let depth = texels.iter().map(|t| f32::from_bits(t[3])).collect();
    let image = DrawnImage {
        texels: texels
            .iter()
            .map(|t| {
                let triangle = t[0].checked_sub(1)?;
                let b = Vec2::new(f32::from_bits(t[1]), f32::from_bits(t[2]));
                match source {
                    None => Some((triangle, b)),
                    Some(source) => in_source(source.get(triangle as usize)?, b),
                }
            })
            .collect(),
        frusta: None,
    };
    Ok((image, depth))
}

/// A sub-triangle's point at barycentrics `b` (of its corners 1 and 2), named in its source
/// triangle.
fn in_source(&(s, c): &trompe::impostor::SourceTriangle, b: Vec2) -> DrawnTexel {
    let w = c[0] * (1.0 - b.x - b.y) + c[1] * b.x + c[2] * b.y;
    Some((s, Vec2::new(w.y, w.z)))
}

/// A graph camera's image (§4.5): every frustum's pieces ([`trompe::impostor::graph_pieces`])
/// drawn through its matrix, in order, over one image and one depth buffer.
fn draw_graph(
    gpu: &Gpu,
    g: &trompe::camera::GraphCamera,
    mesh: &Mesh,
) -> Result<DrawnImage, GpuError> {
    let (w, h) = g.resolution();
    gpu.check_texture("the impostor's visibility image", w, h)?;
    let pieces = trompe::impostor::graph_pieces(g, mesh);
    // Every frustum's pieces in one vertex buffer, frustum after frustum; `first[j]` is the
    // index of frustum j's first piece.
    let mut corners: Vec<[Vec3; 3]> = Vec::new();
    let mut first = Vec::with_capacity(pieces.len() + 1);
    // Depth is near · gd: near the smallest w (1/gd) of anything drawn keeps it within 1.
    let mut near = f64::INFINITY;
    for (j, piece) in pieces.iter().enumerate() {
        first.push(corners.len() as u32);
        let m = &g.frusta()[j].matrix;
        for t in &piece.mesh.triangles {
            let c = t.map(|i| piece.mesh.positions[i as usize]);
            for p in c {
                let w = (*m * p.as_dvec3().extend(1.0)).w;
                if w > 0.0 {
                    near = near.min(w);
                }
            }
            corners.push(c);
        }
    }
    first.push(corners.len() as u32);
    let near = if near.is_finite() { near } else { 1.0 };
    let empty = || DrawnImage {
        texels: vec![None; w as usize * h as usize],
        frusta: Some(vec![0; w as usize * h as usize]),
    };
    if corners.is_empty() {
        return Ok(empty());
    }
    let draws: Vec<_> = (0..pieces.len())
        .filter(|&j| first[j] < first[j + 1])
        .map(|j| {
            let camera = GpuRasterCamera::frustum(g, j, near);
            (camera, 3 * first[j]..3 * first[j + 1])
        })
        .collect();
    let texels = draw_and_read(gpu, &corners, (&draws, None), (w, h))?;
    let mut image = empty();
    for (i, t) in texels.iter().enumerate() {
        let Some(leaf) = t[0].checked_sub(1) else {
            continue;
        };
        // The frustum whose range holds the piece.
        let j = first.partition_point(|&f| f <= leaf).saturating_sub(1);
        let Some(source) = pieces
            .get(j)
            .and_then(|p| p.source.get((leaf - first[j]) as usize))
        else {
            continue;
        };
        let b = Vec2::new(f32::from_bits(t[1]), f32::from_bits(t[2]));
        image.texels[i] = in_source(source, b);
        if let Some(f) = image.frusta.as_mut() {
            f[i] = j as u32;
        }
    }
    Ok(image)
}

/// The `w × h` visibility image of `triangles`, each range of their corners drawn through its
/// camera in order ([`draw_ranges_into_visibility`]) under `ceiling` if given, read back
/// row-major.
fn draw_and_read(
    gpu: &Gpu,
    triangles: &[[Vec3; 3]],
    (draws, ceiling): (&[RasterDraw], Option<&[f32]>),
    (w, h): (u32, u32),
) -> Result<Vec<[u32; 4]>, GpuError> {
    let (mut pipeline, vertices, _) = raster_pipeline_of(gpu, triangles)?;
    let ceiling = match ceiling {
        None => None,
        Some(depth) => {
            pipeline = visibility_pipeline(gpu, true);
            Some(ceiling_group(gpu, &pipeline, depth, (w, h))?)
        }
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let visibility = visibility_texture(gpu, w, h);
    draw_ranges_into_visibility(
        gpu,
        &mut encoder,
        (&pipeline, &vertices),
        (draws, ceiling.as_ref()),
        &visibility,
        (w, h),
    );
    gpu.read_texture(
        encoder,
        &visibility,
        (w, h),
        "the impostor's visibility image",
    )
}

/// The bind group of a `w × h` depth-peeling ceiling for `pipeline` (drawing behind one):
/// `depth`'s bits in a one-channel integer texture, read texel by texel.
fn ceiling_group(
    gpu: &Gpu,
    pipeline: &wgpu::RenderPipeline,
    depth: &[f32],
    (w, h): (u32, u32),
) -> Result<wgpu::BindGroup, GpuError> {
    if depth.len() as u64 != u64::from(w) * u64::from(h) {
        return Err(GpuError::Unsupported {
            what: format!(
                "a ceiling of {} texels for an image of {w} × {h}",
                depth.len()
            ),
        });
    }
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let ceiling = gpu.texture("ceiling", (w, h), wgpu::TextureFormat::R32Uint, usage);
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &ceiling,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(depth),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * w),
            rows_per_image: Some(h),
        },
        crate::device::extent((w, h)),
    );
    let view = ceiling.create_view(&Default::default());
    Ok(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("ceiling"),
        layout: &pipeline.get_bind_group_layout(1),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&view),
        }],
    }))
}
