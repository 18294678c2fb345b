//! # trompe — impostor-based and image-based rendering on the CPU
//!
//! trompe replaces geometry by images that carry depth (impostors) and renders with them what a
//! plain rasterizer cannot do cheaply: reflections and refractions on curved objects, distant
//! objects re-rendered only now and then, photo-textured models seen from new viewpoints. It runs
//! on the CPU, on every core, and gives the same pixels for any thread count.
//!
//! ```
//! use trompe::{Bvh, Impostor, Ray, RayQuery, glam::Vec3};
//! use std::sync::Arc;
//!
//! // A SPOC impostor of a mesh, seen from a point, and a ray answered by it and by the exact BVH.
//! let mesh = trompe::geom::icosphere(3);
//! let eye = Vec3::new(0.0, 0.4, 2.0);
//! let impostor = Impostor::spoc(&mesh).from(eye).resolution(128).build()?;
//! let ray = Ray::new(eye, (Vec3::ZERO - eye).normalize());
//! let exact = Bvh::build(vec![Arc::new(mesh)])?;
//! let (a, b) = (impostor.closest_hit(&ray, f32::INFINITY), exact.closest_hit(&ray, f32::INFINITY));
//! assert!((a.unwrap().position - b.unwrap().position).length() < 0.01);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Data flows one way: **scene → impostors → ray queries → frame**.
//!
//! * [`geom`] — rays, boxes, triangles, meshes, optics; loaders for OBJ + MTL, PLY, glTF.
//! * [`frame`] — image buffers, PNG / EXR / HDR files, environment maps, PSNR / SSIM / FLIP.
//! * [`camera`] — the [`Projection`] trait (world point → `(u, v, gd)`) and its cameras.
//! * [`raster`] — a watertight rasterizer generic over any [`Projection`].
//! * [`trace`] — the [`RayQuery`] and [`SecondaryQuery`] traits, the exact BVH (ground truth),
//!   the environment at infinity.
//! * [`scene`] — TOML scene files, camera paths, animation, maze floor plans.
//! * [`impostor`] — impostors through pinhole, orthographic, SPOC and graph cameras: build,
//!   walk, bake, save and load.
//! * [`render`](mod@render) — one Whitted tracer generic over what answers primary and secondary rays, and
//!   the raster, trace and impostor methods built on it.
//! * [`hybrid`] — hybrid reflections: diffuse objects as points, splatted through one continuous
//!   3-ray camera per mirror triangle.
//! * [`relief`] — relief impostors: a software shader, 3-D image warping, validity, the
//!   two-thread pipeline.
//! * [`texturing`] — projective texturing, the one renderer of views, layers and master
//!   textures: weights (VDTM, ULR, view map, best face), one hole policy.
//! * [`views`] — calibrated views: COLMAP models, capture rigs, per-view visibility, the views
//!   as a texturing source.
//! * [`layers`] — layered view-dependent projective textures: visibility layers per view,
//!   editable OpenRaster image layers, rendering through each layer's sub-frustum.
//! * [`master`] — Master Texture Space: many views of a mesh encoded in pixel-aligned atlases
//!   with one UV set, rendered view-dependently, edited once for every view.
//! * [`methods`] — the one list of methods: every way trompe makes a frame, prepared once
//!   over a scene, then a frame at a time and a camera.
//! * [`eval`] — experiments: an impostor against the exact BVH, the rasterizer against the BVH.
//! * [`progress`] — progress reports and step timings of long work.
//! * [`sidecar`] — which kind of impostor a JSON sidecar describes.
//! * [`memory`] — the memory budget every input-sized allocation is checked against.
//!
//! ## Conventions (said once, here)
//!
//! * World space is right-handed, `y` up, in metres.
//! * Images have their origin top-left; pixel `(i, j)` covers `[i, i+1) × [j, j+1)` and is
//!   sampled at its centre `(i + 0.5, j + 0.5)` ([`frame::PIXEL_CENTER`]).
//! * Colours are linear `f32` inside trompe; sRGB exists only in PNG files ([`frame::io`]).
//! * Depth in images built through a camera is **generalized depth** `gd = 1/t`
//!   (`docs/conventions.md`): larger is nearer, empty is `0`, and the z-test keeps the larger.
//!   Renderers' [`Frame::depth`] is Euclidean distance along the pixel's ray.
//! * Cameras take a vertical field of view (full angle, degrees), a position, a look-at point and
//!   an up vector. Equirectangular maps use Mitsuba's mapping ([`frame::envmap`]).
//! * Texture coordinates follow the image convention: `(0, 0)` is the top-left texel.

// Safe Rust everywhere but one audited function, `prefetch` (a cache hint; see its module).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod camera;
pub mod eval;
pub mod files;
pub mod frame;
pub mod geom;
pub mod hybrid;
pub mod impostor;
pub mod layers;
pub mod master;
pub mod memory;
pub mod methods;
pub mod octahedral;
pub mod progress;
pub mod raster;
pub mod relief;
pub mod render;
pub mod scene;
pub mod sidecar;
pub mod texturing;
pub mod trace;
pub mod views;

mod prefetch;
#[cfg(test)]
mod test_scratch;

/// The vector maths trompe speaks (points, directions, matrices): the `glam` crate, re-exported
/// so a user's versions match.
pub use glam;

pub use camera::{ImagePoint, Orthographic, Pinhole, Projection, Spoc};
pub use frame::{Frame, Image, Rgba};
pub use geom::{Aabb, Mesh, Ray};
pub use impostor::{Impostor, ImpostorCamera, ImpostorSettings, ViewCamera};
pub use progress::{Progress, Timings};
pub use raster::{Fragment, FragmentShader, ItemId, rasterize};
pub use render::{Method, Tracer, render, render_trace};
pub use scene::{Scene, View};
pub use trace::{Bvh, EnvironmentOnly, Exact, Hit, RayQuery, SecondaryQuery};
