//! Leave-one-out scoring of view-dependent texturing: each chosen view is rendered from the
//! others and compared with its own image on the pixels the blend covers — the figure a capture
//! gives without any ground truth beyond itself.
//!
//! Invariant: the view scored never contributes to its own rendering.

use super::blend;
use super::visibility::DepthMap;
use super::{ViewSet, ViewsError};
use crate::frame::metrics::{self, Scores};
use crate::geom::Mesh;
use crate::progress::Progress;
use crate::texturing::{BlendSettings, Weighting};

/// One view's scores.
#[derive(Clone, Debug)]
pub struct ViewScore {
    /// The view's name.
    pub name: String,
    /// PSNR / SSIM / FLIP against its image, on covered pixels.
    pub scores: Scores,
    /// Covered pixels no other view sees (holes), as a fraction.
    pub holes: f64,
}

/// The scores of one weighting over the views left out.
#[derive(Clone, Debug)]
pub struct LeaveOneOut {
    /// What weighted the views.
    pub weighting: Weighting,
    /// Per view left out.
    pub views: Vec<ViewScore>,
}

impl LeaveOneOut {
    /// Mean PSNR, SSIM, FLIP and hole fraction.
    pub fn mean(&self) -> (f64, f64, f64, f64) {
        let n = self.views.len().max(1) as f64;
        let sum = self.views.iter().fold((0.0, 0.0, 0.0, 0.0), |a, v| {
            (
                a.0 + v.scores.psnr,
                a.1 + v.scores.ssim,
                a.2 + v.scores.flip,
                a.3 + v.holes,
            )
        });
        (sum.0 / n, sum.1 / n, sum.2 / n, sum.3 / n)
    }
}

/// As JSON: the weighting, the means the text shows, and every view's scores.
impl serde::Serialize for LeaveOneOut {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (psnr, ssim, flip, holes) = self.mean();
        let views: Vec<_> = (self.views.iter())
            .map(|v| serde_json::json!({ "name": v.name, "scores": v.scores, "holes": v.holes }))
            .collect();
        serde_json::json!({
            "weighting": name(self.weighting),
            "mean": { "psnr": psnr, "ssim": ssim, "flip": flip, "holes": holes },
            "views": views,
        })
        .serialize(s)
    }
}

impl std::fmt::Display for LeaveOneOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (psnr, ssim, flip, holes) = self.mean();
        write!(
            f,
            "{:<22} PSNR {psnr:6.2} dB  SSIM {ssim:.4}  FLIP {flip:.4}  holes {:.2} %  ({} views left out)",
            name(self.weighting),
            holes * 100.0,
            self.views.len()
        )
    }
}

/// A weighting's name as the command line spells it.
pub fn name(w: Weighting) -> &'static str {
    match w {
        Weighting::Vdtm => "vdtm",
        Weighting::ViewMap => "view map",
        Weighting::Ulr { .. } => "ulr",
        Weighting::BestFace => "best view per face",
    }
}

/// Leaves out each view in `which` (indices into `set.views`, images loaded) and scores its
/// rendering from the others, for each weighting in `weightings`.
pub fn leave_one_out(
    set: &ViewSet,
    mesh: &Mesh,
    base: &BlendSettings,
    weightings: &[Weighting],
    which: &[usize],
    progress: &dyn Progress,
) -> Result<Vec<LeaveOneOut>, ViewsError> {
    let depth = DepthMap::of_all(&set.views, mesh).map_err(ViewsError::DepthMaps)?;
    let mut out: Vec<LeaveOneOut> = weightings
        .iter()
        .map(|&weighting| LeaveOneOut {
            weighting,
            views: Vec::new(),
        })
        .collect();
    for &v in which {
        let view = &set.views[v];
        let Some(truth) = blend::undistorted_image(view) else {
            continue;
        };
        let camera = view.pinhole();
        for report in &mut out {
            let settings = BlendSettings {
                weighting: report.weighting,
                ..*base
            };
            let err = |source| ViewsError::Image {
                name: view.name.clone(),
                source,
            };
            let b = blend::render(&camera, mesh, &set.views, &depth, &settings, Some(v))
                .map_err(err)?;
            // Scored where the blend shows the mesh and some other view saw it.
            let mask = b.image.map(|c| c.w > 0.0);
            let scores = metrics::compare(&truth, &b.image, Some(&mask)).map_err(err)?;
            report.views.push(ViewScore {
                name: view.name.clone(),
                scores,
                holes: b.unseen_share(),
            });
        }
        progress.advance(1);
    }
    Ok(out)
}
