//! # trompe — impostor-based and image-based rendering on the CPU
//!
//! trompe replaces geometry by images that carry depth (impostors) and renders with them what a
//! plain rasterizer cannot do cheaply: reflections and refractions on curved objects, distant
//! objects re-rendered only now and then, photo-textured models seen from new viewpoints. It runs
//! on the CPU, on every core, and gives the same pixels for any thread count.
//!
//! Data flows one way: **scene → impostors → ray queries → frame**.
//!
//! * [`geom`] — rays, boxes, triangles, meshes; loaders for OBJ + MTL, PLY, glTF.
//! * [`frame`] — image buffers, PNG / EXR / HDR files, environment maps, PSNR / SSIM / FLIP.
//! * [`camera`] — the [`Projection`] trait (world point → `(u, v, gd)`) and its cameras.
//! * [`raster`] — a watertight rasterizer generic over any [`Projection`].
//! * [`trace`] — the [`RayQuery`] trait, the exact BVH (ground truth), the environment at infinity.
//! * [`scene`] — TOML scene files, camera paths, animation.
//! * [`render`] — the ground-truth renderers: raster and Whitted ray tracing.
//! * [`report`], [`validate`], [`bench`](mod@bench) — the demo report, cross-method checks, benchmarks.
//!
//! ## Conventions (said once, here)
//!
//! * World space is right-handed, `y` up, in metres.
//! * Images have their origin top-left; pixel `(i, j)` covers `[i, i+1) × [j, j+1)` and is
//!   sampled at its centre `(i + 0.5, j + 0.5)` ([`frame::PIXEL_CENTER`]).
//! * Colours are linear `f32` inside trompe; sRGB exists only in PNG files ([`frame::io`]).
//! * Depth in images built through a camera is **generalized depth** `gd = 1/t`
//!   (algorithms.md §1.2): larger is nearer, empty is `0`, and the z-test keeps the larger.
//!   Renderers' [`Frame::depth`] is Euclidean distance along the pixel's ray.
//! * Cameras take a vertical field of view (full angle, degrees), a position, a look-at point and
//!   an up vector. Equirectangular maps use Mitsuba's mapping ([`frame::envmap`]).
//! * Texture coordinates follow the image convention: `(0, 0)` is the top-left texel.

// Safe Rust everywhere but one audited function, `prefetch` (a cache hint; see its module).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bench;
pub mod camera;
pub mod eval;
pub mod frame;
pub mod geom;
pub mod raster;
pub mod render;
pub mod report;
pub mod scene;
pub mod trace;

pub use camera::{ImagePoint, Pinhole, Projection};
pub use frame::{Frame, Image, Rgba};
pub use geom::{Aabb, Mesh, Ray};
pub use raster::{Fragment, FragmentShader, ItemId, rasterize};
pub use scene::Scene;
pub use trace::{Bvh, Hit, RayQuery};
pub mod impostor;
mod prefetch;
pub mod progress;
#[cfg(test)]
mod test_scratch;
