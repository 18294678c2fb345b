//! The viewer's window on the GPU: each frame, with the viewer's overlay drawn into it, sent to
//! the device once and drawn onto a wgpu surface (`shaders/present.wgsl`), on the device the
//! methods render on. The same pass also draws into a texture kept until the next frame, so what
//! the window was given can be read back (the viewer's screenshots).
//!
//! Invariant: the bytes shown are the bytes sent — the frame is sRGB-encoded, and its texture is
//! read through the encoding of the surface's format, so no colour is converted twice.

use crate::device::{Gpu, GpuError, extent};

/// The window's shader.
pub const SHADER: &str = include_str!("../shaders/present.wgsl");
use trompe::frame::{Image, Rgba};

/// A window's surface on a GPU, and the frame it showed last.
pub struct WindowSurface<'w> {
    surface: wgpu::Surface<'w>,
    config: wgpu::SurfaceConfiguration,
    pipeline: wgpu::RenderPipeline,
    /// The last frame as the surface was given it: its size and texture.
    shown: Option<((u32, u32), wgpu::Texture)>,
}

impl<'w> WindowSurface<'w> {
    /// A surface on `window` (anything wgpu makes a surface of: a winit window behind an `Arc`),
    /// of `size` pixels, on `gpu`.
    ///
    /// # Errors
    /// When the window system offers `gpu`'s adapter no surface, or none in an 8-bit format.
    pub fn new(
        gpu: &Gpu,
        window: impl Into<wgpu::SurfaceTarget<'w>>,
        size: (u32, u32),
    ) -> Result<Self, GpuError> {
        let refused = |reason: String| GpuError::Surface {
            adapter: gpu.name().to_string(),
            reason,
        };
        let surface = gpu
            .instance
            .create_surface(window)
            .map_err(|e| refused(e.to_string()))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let eight_bit = |f: &wgpu::TextureFormat| {
            matches!(
                f.remove_srgb_suffix(),
                wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
            )
        };
        // A format that stores the bytes as sent, else its sRGB twin (read through sRGB too).
        let format = caps
            .formats
            .iter()
            .find(|f| eight_bit(f) && !f.is_srgb())
            .or_else(|| caps.formats.iter().find(|f| eight_bit(f)))
            .copied()
            .ok_or_else(|| {
                refused(format!(
                    "no 8-bit format among the surface's {:?}",
                    caps.formats
                ))
            })?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: Default::default(),
            width: size.0.max(1),
            height: size.1.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        surface.configure(&gpu.device, &config);
        let module = gpu.module("present.wgsl", SHADER);
        let pipeline = gpu
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("present"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("cover"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("shown"),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: None,
            });
        Ok(Self {
            surface,
            config,
            pipeline,
            shown: None,
        })
    }

    /// The surface's format.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.config.format
    }

    /// Shows `pixels` (`size`, row-major, each `0x00RRGGBB` with sRGB-encoded channels, as a
    /// CPU window's buffer holds them). Whether the surface took the frame: `false` when the
    /// window system skipped it (the window hidden, or resized since), to try again next frame.
    ///
    /// # Errors
    /// When `pixels` is not `size`, or the surface reports a failure.
    pub fn present(
        &mut self,
        gpu: &Gpu,
        pixels: &[u32],
        (w, h): (u32, u32),
    ) -> Result<bool, GpuError> {
        if pixels.len() as u64 != u64::from(w) * u64::from(h) || w == 0 || h == 0 {
            return Err(GpuError::Surface {
                adapter: gpu.name().to_string(),
                reason: format!("a frame of {} pixels shown as {w} × {h}", pixels.len()),
            });
        }
        gpu.check_texture("the window's frame", w, h)?;
        if (self.config.width, self.config.height) != (w, h) {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&gpu.device, &self.config);
        }
        let target = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&gpu.device, &self.config);
                return Ok(false);
            }
            other => {
                return Err(GpuError::Surface {
                    adapter: gpu.name().to_string(),
                    reason: format!("the surface gave no texture: {other:?}"),
                });
            }
        };
        // 0x00RRGGBB little-endian is the bytes B, G, R, 0.
        let sent = if self.config.format.is_srgb() {
            wgpu::TextureFormat::Bgra8UnormSrgb
        } else {
            wgpu::TextureFormat::Bgra8Unorm
        };
        let frame = gpu.texture(
            "the window's frame",
            (w, h),
            sent,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &frame,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(pixels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            extent((w, h)),
        );
        let shown = gpu.texture(
            "the window's frame as shown",
            (w, h),
            self.config.format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let view = frame.create_view(&Default::default());
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("present"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            }],
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let on_surface = target.texture.create_view(&Default::default());
        let kept = shown.create_view(&Default::default());
        for into in [&on_surface, &kept] {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: into,
                    resolve_target: None,
                    depth_slice: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..3, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.queue.present(target);
        self.shown = Some(((w, h), shown));
        Ok(true)
    }

    /// The last frame the surface was given, read back from the device (`None` before the
    /// first): linear colour, as the frame's images hold it.
    ///
    /// # Errors
    /// When the read back fails.
    pub fn read_shown(&self, gpu: &Gpu) -> Result<Option<Image<Rgba>>, GpuError> {
        let Some(((w, h), shown)) = &self.shown else {
            return Ok(None);
        };
        let (w, h) = (*w, *h);
        let encoder = gpu.device.create_command_encoder(&Default::default());
        let bytes = gpu.read_texture_bytes(encoder, shown, ((w, h), 4), "the shown frame")?;
        let bgra = matches!(
            self.config.format.remove_srgb_suffix(),
            wgpu::TextureFormat::Bgra8Unorm
        );
        let mut image = Image::new(w, h, Rgba::ZERO).map_err(|e| GpuError::Surface {
            adapter: gpu.name().to_string(),
            reason: e.to_string(),
        })?;
        for y in 0..h {
            for x in 0..w {
                let i = 4 * (y as usize * w as usize + x as usize);
                let [a, g, b] = [bytes[i], bytes[i + 1], bytes[i + 2]];
                let (r, b) = if bgra { (b, a) } else { (a, b) };
                let linear = [r, g, b].map(|c| trompe::frame::srgb_to_linear(f32::from(c) / 255.0));
                image.set(x, y, Rgba::new(linear[0], linear[1], linear[2], 1.0));
            }
        }
        Ok(Some(image))
    }
}
