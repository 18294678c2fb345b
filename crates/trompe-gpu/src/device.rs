//! The GPU device: which adapter trompe runs on, found by backend, name and kind, and the
//! report `trompe info --gpu` prints.
//!
//! An adapter is picked from every adapter the chosen backends list, hardware first (discrete,
//! integrated, virtual, other), a software rasterizer (Mesa's lavapipe, WARP, SwiftShader)
//! last. Invariant: a [`Gpu`] holds an open device and queue on the adapter its report names,
//! with that adapter's own limits, so the largest buffers it allows are usable.

use std::collections::HashMap;
use std::fmt;
use std::sync::Mutex;
use thiserror::Error;

/// Why no GPU device could be opened.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter matched the request.
    #[error("no GPU adapter found: looked for {looked_for}{}", found_list(.found))]
    NoAdapter {
        /// What was asked for, in words.
        looked_for: String,
        /// Every adapter the backends listed, by name and backend.
        found: Vec<String>,
    },
    /// The adapter refused to open a device.
    #[error("the adapter {adapter} refused a device: {reason}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// The driver's answer.
        reason: String,
    },
    /// A buffer the work needs is larger than the device allows.
    #[error("{what} needs {bytes} bytes in one buffer; {adapter} allows {limit}")]
    TooLarge {
        /// What the buffer holds.
        what: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's limit.
        limit: u64,
        /// The adapter's name.
        adapter: String,
    },
    /// The GPU path does not do what was asked.
    #[error("the GPU cannot render this: {what}")]
    Unsupported {
        /// What it cannot do, and its limit.
        what: String,
    },
    /// The frame's size is not a valid image size.
    #[error(transparent)]
    Frame(#[from] trompe::frame::FrameError),
    /// What the work holds on the CPU side (the BVH it uploads) would pass the memory budget.
    #[error(transparent)]
    Memory(#[from] trompe::memory::OverBudget),
    /// A texture the work needs is wider or taller than the device allows.
    #[error("{what} needs a texture {side} texels a side; {adapter} allows {limit}")]
    TextureTooLarge {
        /// What the texture holds.
        what: &'static str,
        /// Its longer side.
        side: u32,
        /// The device's limit.
        limit: u32,
        /// The adapter's name.
        adapter: String,
    },
    /// The device could not hold what the work needs.
    #[error("{adapter} could not hold {what}, {bytes} bytes: {reason}")]
    OutOfMemory {
        /// What it holds.
        what: String,
        /// Its size.
        bytes: u64,
        /// The adapter's name.
        adapter: String,
        /// The driver's answer.
        reason: String,
    },
    /// A window's surface could not be made or shown on the adapter.
    #[error("showing a window on {adapter}: {reason}")]
    Surface {
        /// The adapter's name.
        adapter: String,
        /// Why.
        reason: String,
    },
    /// Reading results back from the device failed.
    #[error("reading {what} back from {adapter} failed: {reason}")]
    Readback {
        /// What was being read.
        what: &'static str,
        /// The adapter's name.
        adapter: String,
        /// The driver's answer.
        reason: String,
    },
}

fn found_list(found: &[String]) -> String {
    if found.is_empty() {
        " (the backends listed no adapter at all; on Linux without a GPU, install Mesa's \
         lavapipe: package mesa-vulkan-drivers)"
            .to_string()
    } else {
        format!(" (found: {})", found.join("; "))
    }
}

/// Which graphics APIs to look on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backends {
    /// Every backend this build has (Vulkan, Metal, DX12, GL).
    #[default]
    All,
    /// Vulkan only (where lavapipe lives).
    Vulkan,
    /// Metal only.
    Metal,
    /// DirectX 12 only.
    Dx12,
    /// OpenGL / GLES only.
    Gl,
}

impl Backends {
    fn wgpu(self) -> wgpu::Backends {
        match self {
            Backends::All => wgpu::Backends::all(),
            Backends::Vulkan => wgpu::Backends::VULKAN,
            Backends::Metal => wgpu::Backends::METAL,
            Backends::Dx12 => wgpu::Backends::DX12,
            Backends::Gl => wgpu::Backends::GL,
        }
    }
}

/// Which adapter to open: the backends to look on, an optional name, and whether a software
/// rasterizer will do.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpuRequest {
    backends: Backends,
    name: Option<String>,
    software: bool,
}

impl Default for GpuRequest {
    fn default() -> Self {
        GpuRequest {
            backends: Backends::All,
            name: None,
            software: true,
        }
    }
}

impl GpuRequest {
    /// Any adapter on any backend, hardware first, software if nothing else.
    pub fn new() -> Self {
        Self::default()
    }

    /// Look only on `backends`.
    pub fn backends(mut self, backends: Backends) -> Self {
        self.backends = backends;
        self
    }

    /// Only an adapter whose name contains `name` (case-insensitive).
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Whether a software rasterizer (lavapipe, WARP) is acceptable: `false` for "a hardware
    /// GPU or nothing", as `--device auto` asks.
    pub fn software(mut self, allowed: bool) -> Self {
        self.software = allowed;
        self
    }

    fn describe(&self) -> String {
        let mut s = match self.backends {
            Backends::All => "an adapter on any backend".to_string(),
            b => format!("an adapter on {b:?}"),
        };
        if let Some(n) = &self.name {
            s += &format!(" named like \"{n}\"");
        }
        if !self.software {
            s += ", hardware only";
        }
        s
    }

    /// Opens the best adapter this request allows.
    pub fn open(&self) -> Result<Gpu, GpuError> {
        let adapters = list_adapters(self.backends);
        let found: Vec<String> = adapters
            .iter()
            .map(|(_, a)| {
                let i = a.get_info();
                format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
            })
            .collect();
        let wanted = self.name.as_ref().map(|n| n.to_lowercase());
        let (instance, adapter) = adapters
            .into_iter()
            .filter(|(_, a)| {
                let info = a.get_info();
                let named = wanted
                    .as_ref()
                    .is_none_or(|n| info.name.to_lowercase().contains(n));
                named && (self.software || !is_software(&info))
            })
            .min_by_key(|(_, a)| rank(&a.get_info()))
            .ok_or_else(|| GpuError::NoAdapter {
                looked_for: self.describe(),
                found,
            })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        // 64-bit floats where the adapter has them: the C3RC projection's roots in the CPU's
        // precision (`crate::hybrid`).
        let features = adapter.features() & wgpu::Features::SHADER_F64;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("trompe"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
            limits,
            compute: Mutex::default(),
            render: Mutex::default(),
        })
    }
}

/// Whether an adapter is a software rasterizer.
fn is_software(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
}

/// Preference order: hardware kinds first, software last.
fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// An open GPU device and its queue.
pub struct Gpu {
    /// What found the adapter, and the adapter: a window's surface is made and configured
    /// through them.
    pub(crate) instance: wgpu::Instance,
    pub(crate) adapter: wgpu::Adapter,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    /// Pipelines compiled on this device, by entry point: a shader is compiled once however
    /// many scenes and frames use it.
    /// By (module label, entry point): two modules may share an entry point's name.
    compute: Mutex<HashMap<(String, &'static str), wgpu::ComputePipeline>>,
    render: Mutex<HashMap<&'static str, wgpu::RenderPipeline>>,
}

impl Gpu {
    /// What the adapter is, for reports and every table of figures.
    pub fn report(&self) -> AdapterReport {
        AdapterReport::of(&self.info, &self.limits)
    }

    /// The adapter's name.
    pub fn name(&self) -> &str {
        &self.info.name
    }

    /// Whether shaders on this device compute in 64-bit floats.
    pub fn has_f64(&self) -> bool {
        self.device.features().contains(wgpu::Features::SHADER_F64)
    }

    /// The limits the device was opened with (the adapter's own).
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }

    /// Whether the adapter is a software rasterizer (lavapipe).
    pub fn is_software(&self) -> bool {
        is_software(&self.info)
    }

    /// A storage buffer of `bytes` for `what`, refused with [`GpuError::TooLarge`] past the
    /// device's binding limit (instead of wgpu's validation panic).
    pub(crate) fn check_storage(&self, what: &'static str, bytes: u64) -> Result<(), GpuError> {
        let limit = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what,
                bytes,
                limit,
                adapter: self.info.name.clone(),
            });
        }
        Ok(())
    }

    /// An uninitialised buffer of `bytes` (at least 16: a binding is never empty).
    pub(crate) fn buffer(
        &self,
        label: &str,
        bytes: u64,
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(16).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
            usage,
            mapped_at_creation: false,
        })
    }

    /// A buffer holding `data` with `usage` (and room for at least 16 bytes).
    fn buffer_with(&self, label: &str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let buffer = self.buffer(
            label,
            data.len() as u64,
            usage | wgpu::BufferUsages::COPY_DST,
        );
        if !data.is_empty() {
            let whole = data
                .len()
                .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT as usize);
            let mut padded = data.to_vec();
            padded.resize(whole, 0);
            self.queue.write_buffer(&buffer, 0, &padded);
        }
        buffer
    }

    /// A read-only storage buffer holding `data`.
    pub(crate) fn storage_with(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        self.buffer_with(label, data, wgpu::BufferUsages::STORAGE)
    }

    /// A vertex buffer holding `data`.
    pub(crate) fn vertices_with(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        self.buffer_with(label, data, wgpu::BufferUsages::VERTEX)
    }

    /// A uniform buffer holding `data`.
    pub(crate) fn uniform_with(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        self.buffer_with(label, data, wgpu::BufferUsages::UNIFORM)
    }

    /// The `w × h` texels of `texture` (its first level), each `texel` bytes, read back after
    /// `encoder`'s work, row-major and unpadded.
    pub(crate) fn read_texture_bytes(
        &self,
        mut encoder: wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        ((w, h), texel): ((u32, u32), u32),
        what: &'static str,
    ) -> Result<Vec<u8>, GpuError> {
        let tight = u64::from(w) * u64::from(texel);
        let row = tight.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
        let buffer = self.buffer(
            "texture read back",
            row * u64::from(h),
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row as u32),
                    rows_per_image: Some(h),
                },
            },
            extent((w, h)),
        );
        let bytes = self.read_back(encoder, &[buffer], what)?;
        Ok(bytes[0]
            .chunks(row as usize)
            .take(h as usize)
            .flat_map(|r| r[..tight as usize].iter().copied())
            .collect())
    }

    /// [`Gpu::read_texture_bytes`] of a texture of four 32-bit channels a texel.
    pub(crate) fn read_texture(
        &self,
        encoder: wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        size: (u32, u32),
        what: &'static str,
    ) -> Result<Vec<[u32; 4]>, GpuError> {
        let bytes = self.read_texture_bytes(encoder, texture, (size, 16), what)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// A `w × h` 2-D texture of one level.
    pub(crate) fn texture(
        &self,
        label: &str,
        size: (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(size),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// Submits `encoder`, then copies each of `sources` back and waits for them (one
    /// submission, one wait).
    pub(crate) fn read_back(
        &self,
        mut encoder: wgpu::CommandEncoder,
        sources: &[wgpu::Buffer],
        what: &'static str,
    ) -> Result<Vec<Vec<u8>>, GpuError> {
        let staging: Vec<wgpu::Buffer> = sources
            .iter()
            .map(|source| {
                let staging = self.buffer(
                    "read back",
                    source.size(),
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                );
                encoder.copy_buffer_to_buffer(source, 0, &staging, 0, source.size());
                staging
            })
            .collect();
        self.queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        for s in &staging {
            let sender = sender.clone();
            s.map_async(wgpu::MapMode::Read, .., move |r| {
                // The receiver waits below; a send fails only if it is gone.
                let _ = sender.send(r);
            });
        }
        let failed = |reason: String| GpuError::Readback {
            what,
            adapter: self.info.name.clone(),
            reason,
        };
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| failed(e.to_string()))?;
        for _ in &staging {
            receiver
                .recv()
                .map_err(|e| failed(e.to_string()))?
                .map_err(|e| failed(e.to_string()))?;
        }
        staging
            .iter()
            .map(|s| {
                let bytes = s
                    .get_mapped_range(..)
                    .map_err(|e| failed(e.to_string()))?
                    .to_vec();
                s.unmap();
                Ok(bytes)
            })
            .collect()
    }

    /// The compute pipeline of entry point `entry` of WGSL `source` (its module named `label`),
    /// compiled on first use.
    pub(crate) fn compute_pipeline(
        &self,
        label: &str,
        source: &str,
        entry: &'static str,
    ) -> wgpu::ComputePipeline {
        let mut cache = self.compute.lock().unwrap_or_else(|e| e.into_inner());
        cache
            .entry((label.to_string(), entry))
            .or_insert_with(|| {
                let module = self.module(label, source);
                self.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: None,
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
            })
            .clone()
    }

    /// The render pipeline `name`, made by `make` on first use.
    pub(crate) fn render_pipeline(
        &self,
        name: &'static str,
        make: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        let mut cache = self.render.lock().unwrap_or_else(|e| e.into_inner());
        cache.entry(name).or_insert_with(make).clone()
    }

    /// WGSL `source` as a shader module.
    pub(crate) fn module(&self, label: &str, source: &str) -> wgpu::ShaderModule {
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
    }

    /// A `w × h` 2-D texture for `what`, refused with [`GpuError::TextureTooLarge`] past the device's
    /// side limit (instead of wgpu's validation panic).
    pub(crate) fn check_texture(&self, what: &'static str, w: u32, h: u32) -> Result<(), GpuError> {
        let limit = self.limits.max_texture_dimension_2d;
        if w.max(h) > limit {
            return Err(GpuError::TextureTooLarge {
                what,
                side: w.max(h),
                limit,
                adapter: self.info.name.clone(),
            });
        }
        Ok(())
    }

    /// `make`'s work (the creation of a resource of `bytes` for `what`), refused with
    /// [`GpuError::OutOfMemory`] where the device cannot hold it (instead of wgpu's panic).
    pub(crate) fn allocating<T>(
        &self,
        (what, bytes): (&str, u64),
        make: impl FnOnce() -> T,
    ) -> Result<T, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let made = make();
        match pollster::block_on(scope.pop()) {
            None => Ok(made),
            Some(e) => Err(GpuError::OutOfMemory {
                what: what.to_string(),
                bytes,
                adapter: self.info.name.clone(),
                reason: e.to_string(),
            }),
        }
    }

    /// The largest number of workgroups one dispatch may have along x.
    pub(crate) fn max_groups(&self) -> u32 {
        self.limits.max_compute_workgroups_per_dimension
    }
}

/// The adapter a [`Gpu`] runs on, as `trompe info --gpu` prints it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterReport {
    /// The adapter's name ("NVIDIA H100", "llvmpipe (LLVM 15.0.7, 256 bits)").
    pub name: String,
    /// The graphics API.
    pub backend: String,
    /// Discrete, integrated, virtual, CPU or other.
    pub kind: String,
    /// Whether it is a software rasterizer.
    pub software: bool,
    /// The driver's name.
    pub driver: String,
    /// The driver's version text.
    pub driver_info: String,
    /// The largest storage buffer one binding may hold, in bytes.
    pub max_storage_buffer: u64,
    /// The largest buffer, in bytes.
    pub max_buffer: u64,
    /// The most compute workgroups along one dimension of a dispatch.
    pub max_workgroups_per_dimension: u32,
    /// The largest 2-D texture side.
    pub max_texture_2d: u32,
}

impl fmt::Display for AdapterReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let software = if self.software { ", software" } else { "" };
        writeln!(
            f,
            "adapter  {} ({}, {}{software})",
            self.name, self.backend, self.kind
        )?;
        writeln!(f, "driver   {} {}", self.driver, self.driver_info)?;
        writeln!(
            f,
            "limits   storage buffer {} MiB, buffer {} MiB, {} workgroups a dimension, 2-D texture {}",
            self.max_storage_buffer >> 20,
            self.max_buffer >> 20,
            self.max_workgroups_per_dimension,
            self.max_texture_2d
        )
    }
}

/// Every adapter the backends list, as reports (without opening a device), hardware first.
pub fn adapters(backends: Backends) -> Vec<AdapterReport> {
    let mut list = list_adapters(backends);
    list.sort_by_key(|(_, a)| rank(&a.get_info()));
    list.iter()
        .map(|(_, a)| AdapterReport::of(&a.get_info(), &a.limits()))
        .collect()
}

/// The adapters on `backends`, each with the instance that found it. [`Backends::All`] asks GL
/// only where Vulkan, Metal and DX12 list nothing: GL's adapter is the same device seen through
/// an older API, and opening it probes the window system.
fn list_adapters(backends: Backends) -> Vec<(wgpu::Instance, wgpu::Adapter)> {
    let on = |b: wgpu::Backends| {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: b,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        pollster::block_on(instance.enumerate_adapters(b))
            .into_iter()
            .map(|a| (instance.clone(), a))
            .collect::<Vec<_>>()
    };
    match backends {
        Backends::All => {
            let primary = on(wgpu::Backends::PRIMARY);
            if primary.is_empty() {
                on(wgpu::Backends::GL)
            } else {
                primary
            }
        }
        b => on(b.wgpu()),
    }
}

impl AdapterReport {
    fn of(i: &wgpu::AdapterInfo, l: &wgpu::Limits) -> AdapterReport {
        AdapterReport {
            name: i.name.clone(),
            backend: format!("{:?}", i.backend),
            kind: format!("{:?}", i.device_type),
            software: is_software(i),
            driver: i.driver.clone(),
            driver_info: i.driver_info.clone(),
            max_storage_buffer: l.max_storage_buffer_binding_size,
            max_buffer: l.max_buffer_size,
            max_workgroups_per_dimension: l.max_compute_workgroups_per_dimension,
            max_texture_2d: l.max_texture_dimension_2d,
        }
    }
}

/// The extent of a `w × h` 2-D image.
pub(crate) fn extent((w, h): (u32, u32)) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    }
}
