//! What the relief pipeline ([`super::pipeline`], paper 3 §4–6) hands back for a frame: what it
//! did for each object (valid, warping, stale, fallback) and its line of state, the frame, and —
//! before the texture-mapping phase — the objects to rasterize and the pre-warped impostors to
//! map over them.
//!
//! Invariant: a [`ReliefDraw`]'s image is the pre-warp of its object's impostor for this frame's
//! eye, or the same `Arc` as the last frame's while Schaufler's test holds.

use super::prewarp::Prewarped;
use crate::frame::Frame;
use crate::progress::Timings;
use std::sync::Arc;

/// What the pipeline did for one object in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ObjectState {
    /// The last pre-warp still fits (Schaufler's test): texture mapping only.
    Valid,
    /// Pre-warped for this eye.
    Warping,
    /// Obsolete by the heuristic; warped anyway while a new impostor is made.
    Stale,
    /// Rasterized directly: no impostor good enough.
    Fallback,
}

impl std::fmt::Display for ObjectState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ObjectState::Valid => "valid",
            ObjectState::Warping => "warping",
            ObjectState::Stale => "stale",
            ObjectState::Fallback => "fallback",
        })
    }
}

/// One object in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectFrame {
    /// The object (scene id).
    pub object: usize,
    /// What was done.
    pub state: ObjectState,
    /// The heuristic's error for this eye: mean stretch of the critical pairs, texels
    /// (`INFINITY` without an impostor).
    pub error: f64,
    /// The interpolated share the heuristic predicts from it.
    pub predicted: f64,
    /// Interpolated over direct texels of the pre-warp shown (`None` if none was shown).
    pub ratio: Option<f64>,
    /// A new impostor from the rendering thread came into use this frame.
    pub regenerated: bool,
    /// A cached impostor came back into use this frame.
    pub cache_hit: bool,
    /// A new impostor of the object is being made (a request is in flight after this frame).
    pub regenerating: bool,
    /// Resolution of the impostor shown (0 in fallback).
    pub resolution: u32,
}

impl ObjectFrame {
    /// The object's line of state, `name` its name: what was done (valid, warping, stale or
    /// fallback, and whether a new impostor is being made), the impostor's resolution, and the
    /// validity measure — the interpolated share of the pre-warp the critical-point heuristic
    /// predicts, against `threshold`, past which the impostor is obsolete.
    pub fn line(&self, name: &str, threshold: f64) -> String {
        let mut line = format!("  {name}: {}", self.state);
        if self.regenerating {
            line.push_str(" + regenerating");
        }
        if self.resolution > 0 {
            line.push_str(&format!(" {}^2", self.resolution));
        }
        if self.predicted.is_finite() {
            line.push_str(&format!(
                "  predicted {:.3} of limit {threshold:.3}",
                self.predicted
            ));
        }
        if let Some(ratio) = self.ratio {
            line.push_str(&format!("  interpolated {ratio:.3}"));
        }
        if self.cache_hit {
            line.push_str("  from cache");
        }
        line
    }
}

/// One frame of the pipeline.
#[derive(Clone, Debug)]
pub struct FrameOutput {
    /// The frame.
    pub frame: Frame,
    /// Per relief object.
    pub objects: Vec<ObjectFrame>,
    /// Step timings of this frame.
    pub timings: Timings,
}

/// A frame before its texture-mapping phase ([`Pipeline::prepare`](super::Pipeline::prepare)): what the frame loop decided
/// and pre-warped, the objects rasterized, and the impostors to map over them — the split paper
/// 3 §6 makes between the CPU, which pre-warps, and the graphics hardware, which maps.
#[derive(Clone, Debug)]
pub struct PreparedFrame {
    /// The objects drawn directly (those without relief, and the fallbacks), with their depth.
    pub background: Frame,
    /// The impostors to texture-map over it, in order.
    pub draws: Vec<ReliefDraw>,
    /// Per relief object.
    pub objects: Vec<ObjectFrame>,
    /// Step timings so far.
    pub timings: Timings,
}

/// A frame's decisions and pre-warps, before anything is drawn ([`Pipeline::prepare_draws`](super::Pipeline::prepare_draws)):
/// the objects to draw directly, and the impostors to map over them.
#[derive(Clone, Debug)]
pub struct PreparedDraws {
    /// The objects to draw directly: those without relief, and the fallbacks.
    pub rasterized: Vec<usize>,
    /// The impostors to texture-map over them, in order.
    pub draws: Vec<ReliefDraw>,
    /// Per relief object.
    pub objects: Vec<ObjectFrame>,
    /// Step timings so far.
    pub timings: Timings,
}

/// One pre-warped impostor to texture-map ([`super::texture::draw`]).
#[derive(Clone, Debug)]
pub struct ReliefDraw {
    /// Its object's id.
    pub object: u32,
    /// The pre-warped image: the same `Arc` while the pre-warp stands (Schaufler's test), a new
    /// one when the frame loop pre-warped again.
    pub image: Arc<Prewarped>,
    /// Its base plane.
    pub frame: super::ReliefFrame,
}
