//! Rendering from master textures (paper 5 §4): the mesh drawn through a new camera, each
//! surface point's colour blended from the views that see it — the views module's VDTM / ULR
//! weights ([`crate::views::blend::weights`]) — reading each view's master texture at the
//! point's one texture coordinate. A view sees a point where its master texture's texel there
//! has alpha (the encoder marked occlusion), so no depth map is needed at render time — and the
//! per-face weightings, which need every view's depth map, are refused.
//!
//! Invariant: the same camera, masters and settings give the same pixels on any thread count.

use super::MasterError;
use super::layout::Layout;
use crate::camera::{Pinhole, Projection};
use crate::frame::{Image, Rgba};
use crate::raster::{StoreFragment, rasterize};
use crate::views::blend::{Blend, BlendSettings, Holes, weights};
use glam::{DVec2, DVec3, Vec4};
use rayon::prelude::*;

/// Colour of `master` at atlas point `p`, bilinear over the texels that hold a colour (alpha),
/// or `None` when none of the four does.
pub fn lookup(master: &Image<Rgba>, p: DVec2) -> Option<Rgba> {
    master.sample_bilinear_where(p, |_, _, c| c.w > 0.0)
}

/// Whether `master` holds the surface at atlas point `p` (its nearest texel has alpha).
fn sees(master: &Image<Rgba>, p: DVec2) -> bool {
    let (w, h) = master.size();
    let (x, y) = (p.x.floor(), p.y.floor());
    x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64 && master.get(x as u32, y as u32).w > 0.0
}

/// Renders `mesh` through `camera` from `masters` (one a view, laid out by `layout`; the views'
/// centres of projection `centres`, for the weights).
pub fn render(
    camera: &Pinhole,
    mesh: &crate::geom::Mesh,
    layout: &Layout,
    centres: &[DVec3],
    masters: &[Image<Rgba>],
    settings: &BlendSettings,
) -> Result<Blend, MasterError> {
    if layout.faces.len() != mesh.triangle_count() {
        return Err(MasterError::Faces {
            mesh: mesh.triangle_count(),
            map: layout.faces.len(),
        });
    }
    if !settings.weighting.per_point() {
        return Err(MasterError::Weighting(settings.weighting.name()));
    }
    let (target, _) = rasterize(camera, &[mesh], &StoreFragment, None)?;
    let (w, h) = camera.resolution();
    let eye = camera.position();
    let fragments = target.attributes.pixels();
    let faces = &layout.faces;
    let mut image = Image::new(w, h, Vec4::ZERO)?;
    let counts: Vec<(usize, usize)> = image
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .map(|(y, row)| {
            let (mut covered, mut holes) = (0, 0);
            for (x, out) in row.iter_mut().enumerate() {
                let Some(f) = fragments[y * w as usize + x] else {
                    continue;
                };
                covered += 1;
                let t = f.item.triangle as usize;
                let c = mesh.corners(t);
                let p = (c[0] * f.bary.x + c[1] * f.bary.y + c[2] * f.bary.z).as_dvec3();
                let at = faces[t].at(f.bary.y as f64, f.bary.z as f64);
                let sees = |i| sees(&masters[i], at);
                let ws = weights(p, eye, centres, sees, settings.weighting, settings.k);
                let mut colour = Vec4::ZERO;
                let mut total = 0.0;
                for (i, wgt) in ws {
                    if let Some(s) = lookup(&masters[i], at) {
                        colour += s * wgt as f32;
                        total += wgt;
                    }
                }
                if total <= 0.0 {
                    holes += 1;
                    *out = match settings.holes {
                        Holes::Transparent => Vec4::ZERO,
                        Holes::Fill(c) => c,
                    };
                    continue;
                }
                *out = (colour / total as f32).truncate().extend(1.0);
            }
            (covered, holes)
        })
        .collect();
    let (covered, holes) = counts
        .into_iter()
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    Ok(Blend {
        image,
        covered,
        holes,
    })
}

#[cfg(test)]
mod tests {
    use super::super::tests::duck_capture;
    use super::super::{DEFAULT_SCALE, encode_views};
    use super::*;
    use crate::frame::metrics::psnr;
    use crate::views::visibility::DepthMap;

    #[test]
    fn rendering_at_an_exemplars_viewpoint_reproduces_it() {
        let (mesh, set) = duck_capture(8);
        let settings = BlendSettings::default();
        let enc = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
        for v in [0, 3] {
            let view = &set.views[v];
            let out = render(
                &view.pinhole(),
                &mesh,
                &enc.atlas.layout,
                &enc.centres(),
                &enc.masters,
                &settings,
            )
            .unwrap();
            let truth = view.image.as_ref().unwrap();
            let mask = out.image.map(|c| c.w > 0.0);
            let p = psnr(truth, &out.image, Some(&mask)).unwrap();
            println!(
                "view {v}: {p:.2} dB over {} px, {} holes",
                out.covered, out.holes
            );
            // Two bilinear resamplings (view to master, master to frame) of a textured model:
            // measured 34.9 and 32.3 dB.
            assert!(p >= 31.0, "view {v}: {p:.2} dB");
            assert!(out.holes * 100 <= out.covered, "{} holes", out.holes);
        }
    }

    #[test]
    fn masters_render_as_the_exemplars_do() {
        let (mesh, set) = duck_capture(12);
        let depth = DepthMap::of_all(&set.views, &mesh).unwrap();
        let settings = BlendSettings::default();
        // A camera between two of the ring's, a little higher.
        let (a, b) = (set.views[0].pose.centre(), set.views[1].pose.centre());
        let eye = (a + b) * 0.5 + DVec3::Y * 0.05 * a.length();
        let target = mesh.bounds().center();
        let camera =
            Pinhole::look_at(eye.as_vec3(), target, glam::Vec3::Y, 40.0, 160, 120).unwrap();
        let from_exemplars =
            crate::views::blend::render(&camera, &mesh, &set.views, &depth, &settings, None)
                .unwrap();
        let mask = from_exemplars.image.map(|c| c.w > 0.0);
        let enc = encode_views(&mesh, &set.views, DEFAULT_SCALE, &()).unwrap();
        let from_masters = render(
            &camera,
            &mesh,
            &enc.atlas.layout,
            &enc.centres(),
            &enc.masters,
            &settings,
        )
        .unwrap();
        let p = psnr(&from_exemplars.image, &from_masters.image, Some(&mask)).unwrap();
        println!(
            "masters against exemplars: {p:.2} dB, atlas {:?}",
            enc.atlas.size()
        );
        // Measured 40.95 dB (the paper's "same fidelity" goal of 45 dB is not reached).
        assert!(p >= 39.0, "{p:.2} dB");
    }
}
