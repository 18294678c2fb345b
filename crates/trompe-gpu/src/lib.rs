//! trompe on the GPU: a device layer on wgpu and the library's methods run where their papers
//! ran them, each checked against its CPU twin in the library.
//!
//! - [`device`]: which adapter, found by backend, name and kind; its report; a clear error when
//!   there is none.
//! - [`bvh`]: the exact ray query (the library's BVH walked by a compute shader), the GPU's
//!   ground truth and the peer every GPU method is timed against.
//! - [`methods`]: the library's list of methods with a device: the GPU path where there is
//!   one, the CPU renderer otherwise.
//! - [`trace`]: the `trace` method (Whitted ray tracing, hard shadows) as one compute shader,
//!   and the impostor methods: the same tracer with what mirrors and glass send out answered
//!   by walking impostors.
//! - [`walk`]: paper 1's ray–impostor walk as a shader, over impostors the library built.
//! - [`c3rc`]: paper 2's continuous 3-ray camera — a point's every projection through the cubic,
//!   in f64 where the adapter has it.
//! - [`hybrid`]: paper 2's hybrid reflections — points projected through continuous 3-ray
//!   cameras in a compute shader and splatted, the tracer shading with them.
//! - [`relief`]: paper 3's texture-mapping phase — the library's pre-warped relief textures
//!   mapped with per-pixel depth onto their base quads, uploads double-buffered.
//! - [`raster`]: the visibility pass — triangles drawn by the GPU rasterizer through any
//!   impostor camera or the eye, under a depth-peeling ceiling if asked.
//! - [`build`]: paper 1's impostors drawn by the GPU rasterizer, resolved by the library.
//! - [`texturing`]: projective texturing's blend — the views that see a pixel's surface
//!   weighted and blended in a compute shader, shared by the sources below.
//! - [`views`]: calibrated views — photographs with depth maps — blended on a new camera.
//! - [`layers`]: image layers, each object through its layer's sub-frustum (paper 4 §5).
//! - [`master`]: paper 5's rendering path — every master texture a layer of one texture
//!   array, the mesh's one atlas point a pixel, the views blended in a compute shader.
//! - [`textured`]: a mesh textured from views or masters, uploaded once, blended with any
//!   weighting through any camera (the viewer's photograph modes).
//! - [`octahedral`]: engines' octahedral impostors drawn by their shader, instanced, and shaded.
//! - [`present`]: the viewer's window shown through a wgpu surface on the same device.
//!
//! Data flows one way, as in the library: the library builds (meshes, BVH, cameras), this crate
//! uploads and runs, and answers come back as the library's types.
//!
//! ```no_run
//! use trompe_gpu::GpuRequest;
//! let gpu = GpuRequest::new().open()?;
//! println!("{}", gpu.report());
//! # Ok::<(), trompe_gpu::GpuError>(())
//! ```

pub mod build;
pub mod bvh;
pub mod c3rc;
pub mod device;
pub mod hybrid;
pub mod layers;
pub mod master;
pub mod methods;
pub mod octahedral;
pub mod present;
pub mod raster;
pub mod relief;
pub mod textured;
pub mod texturing;
pub mod trace;
pub mod views;
pub mod walk;

pub use bvh::GpuBvh;
pub use device::{AdapterReport, Backends, Gpu, GpuError, GpuRequest, adapters};
pub use methods::{
    Device, DeviceError, DeviceRenderer, check_device, has_gpu_path, open, open_for,
};
pub use present::WindowSurface;
pub use textured::{PhotoSource, TexturedMesh};
