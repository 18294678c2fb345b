//! Evaluation: the experiments that measure one method against another, above every renderer
//! and impostor they measure (data flows into here; nothing below imports it).
//!
//! * [`fidelity`] — an impostor's answers against the exact BVH on reflected, sphere or
//!   viewpoint rays, and how much of the surface it holds (paper 1 §4–6, Fig. 5–7).
//! * [`validate`] — the rasterizer against the BVH's primary hits: depth, ids, coverage.
//! * [`check`] — the whole `trompe impostor check` experiment: build or load an impostor, fire
//!   rays, set a pinhole depth image beside a SPOC, report.
//! * [`misses`] — pictures of where an impostor and the BVH disagree, for `check`.
//! * [`fixtures`] — the cameras and placements those experiments share.

pub mod check;
pub mod fidelity;
pub mod fixtures;
pub mod misses;
pub mod validate;
