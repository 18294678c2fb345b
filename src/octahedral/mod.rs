//! Octahedral impostors (beyond the papers: what Unreal's ImpostorBaker, Amplify Impostors and
//! Godot's octahedral impostors bake): an object seen from an `n × n` grid of directions laid out
//! by the octahedral map of the sphere (or hemi-octahedral map of the upper hemisphere), each
//! frame an orthographic view framed on its bounding sphere, with base colour and coverage, normal
//! and depth ([`bake`](mod@bake)); and the renderer that blends the three frames around a view direction
//! with parallax correction and relighting ([`render`]). Layout: conventions §8.
//!
//! Invariants: the atlas is in the object's own space; [`mapping`] is the one place the frame
//! layout is defined.

pub mod bake;
pub mod batch;
pub mod card;
pub mod file;
pub mod gltf;
pub mod lod;
pub mod mapping;
pub mod mips;
pub mod packing;
pub mod render;
pub mod scene;
pub mod turntable;

pub use bake::{
    BakeError, BakeSettings, DEFAULT_DILATION, FrameCamera, FrameProjection, OctahedralAtlas, bake,
};
pub use card::Card;
pub use lod::CrossFade;
pub use mapping::{Coverage, Grid};
pub use turntable::{TurntableView, turntable};
