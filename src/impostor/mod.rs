//! Impostors: depth images built through any camera, answering rays (paper 1 §3–4;
//! docs/conventions.md §2–3).
//!
//! An [`Impostor`] is a camera plus per-texel maps — colour, generalized depth `gd`, normal,
//! world position and object id — and the bounding box of what it replaces. [`build`] makes one
//! by rasterizing a mesh through the camera (tessellating adaptively for curved cameras, §2.2);
//! the impostor implements [`crate::trace::RayQuery`] by walking the ray's projection across the
//! image (§2.3, `walk`), over what it derives from its maps on the first walk — a pyramid of
//! front bounds (`pyramid`, `front`) and the texels packed as the walk reads them (`planes`);
//! [`file`](mod@file) saves and loads it (OpenEXR channels + JSON sidecar).
//!
//! Invariants: texel `gd` follows docs/conventions.md §1.2 (0 = empty, larger = nearer); every non-empty
//! texel gives the world position of the surface point it shows ([`Impostor::position_at`]: the
//! point of the texel's ray at its `gd`, on the plane of the stored triangle; a graph camera
//! stores it), so a hit's position is exact up to the texel's footprint; the maps are compact
//! (colour in half floats, normals in octahedral codes, `frame::packed`); the impostor never
//! consults the mesh after it is built.

mod bake;
mod billboard;
mod builder;
mod camera;
pub mod file;
mod front;
pub mod gltf;
mod maps;
mod path;
mod peel;
mod planes;
mod pyramid;
mod settings;
mod strength;
mod subject;
mod texels;
mod walk;

/// Bytes one texel of an impostor costs, for the memory budget ([`crate::memory`]): its maps
/// (24: half-float colour, `gd`, two packed normals, object id), the walks' index (about 22: the
/// texel's plane and its share of the max pyramid) and the rasterizer's scratch while it builds.
pub const BYTES_PER_TEXEL: u64 = 64;

pub use bake::{BakeError, BakeReport, BakeSettings, bake};
pub use billboard::Billboard;
pub use builder::{
    DrawnError, DrawnImage, DrawnTexel, ImpostorBuilder, SourceTriangle, SurfaceSample,
    Tessellation, albedo_of, build, graph_pieces, resolve_drawn, tessellate,
};
pub use camera::{ImpostorCamera, ViewCamera};
pub use front::front_bounds;
pub use maps::{AGREEMENT_FOOTPRINTS, Impostor, ImpostorSummary};
pub use peel::{AUTO_SHARE, LayerError, Layers, MAX_LAYERS, PEEL_GAP};
pub use planes::TexelPlane;
pub use pyramid::MaxPyramid;
pub use settings::{ImpostorError, ImpostorSettings};
pub use strength::{
    STRENGTH_MARGIN, STRENGTH_RAYS, StrengthChoice, StrengthError, choose_strength, region_rays,
};
pub use subject::{CameraChoice, Paired, Subject, SubjectError, is_maze};
pub use walk::{WalkMode, WalkStats};
