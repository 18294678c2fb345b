//! Section "Calibrated views" (the input of papers 4 and 5, "Layered view-dependent projective
//! textures" and "Master Texture Space"): a synthetic ring capture of a textured model, each of
//! some views left out and rebuilt from the others, and novel viewpoints off the ring scored
//! against the exact render — for ULR, VDTM and a best-view-per-face baseline.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, over};
use glam::{DVec3, Vec4};
use std::path::Path;
use trompe::frame::{io, metrics};
use trompe::texturing::{BlendSettings, Weighting};
use trompe::views::blend;
use trompe::views::capture::{CaptureSettings, capture, capture_scene};
use trompe::views::score::{leave_one_out, name};
use trompe::views::visibility::DepthMap;

/// The capture's background radiance (capture scenes escape to a uniform grey).
const BACKGROUND: Vec4 = Vec4::new(0.5, 0.5, 0.5, 1.0);

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let model = inputs.assets.join("gltf/Duck.glb");
    let settings = CaptureSettings {
        count: 36,
        size: (256, 192),
        ..Default::default()
    };
    let set = capture(&model, &settings, &())?;
    let mesh = trompe::geom::io::load(&model)?.mesh;
    let weightings = [
        Weighting::Ulr { beta: 0.1 },
        Weighting::Vdtm,
        Weighting::BestFace,
    ];
    let base = BlendSettings::default();
    let which: Vec<usize> = (0..set.views.len()).step_by(6).collect();
    let reports = leave_one_out(&set, &mesh, &base, &weightings, &which, &())?;
    let mut loo = Table::new([
        "weights",
        "views left out",
        "PSNR (dB)",
        "SSIM",
        "FLIP",
        "holes",
    ]);
    for r in &reports {
        let (psnr, ssim, flip, holes) = r.mean();
        loo.row([
            name(r.weighting).to_string(),
            r.views.len().to_string(),
            format!("{psnr:.2}"),
            format!("{ssim:.4}"),
            format!("{flip:.4}"),
            format!("{:.2} %", holes * 100.0),
        ]);
    }

    // A left-out view beside its rebuildings.
    let depth = DepthMap::of_all(&set.views, &mesh)?;
    let left = 0;
    let view = &set.views[left];
    // A capture holds every view's image.
    let truth = view
        .image
        .clone()
        .ok_or_else(|| trompe::views::ViewsError::Empty(model.clone()))?;
    io::write_png(&out.join("views-left-out-truth.png"), &truth)?;
    let mut figures = vec![Figure::new(
        "views-left-out-truth.png",
        format!("{}: the captured view", view.name),
    )];
    for w in [Weighting::Ulr { beta: 0.1 }, Weighting::BestFace] {
        let s = BlendSettings {
            weighting: w,
            ..base
        };
        let b = blend::render(&view.pinhole(), &mesh, &set.views, &depth, &s, Some(left))?;
        let file = format!("views-left-out-{}.png", name(w).replace(' ', "-"));
        io::write_png(&out.join(&file), &over(BACKGROUND, &b.image))?;
        figures.push(Figure::new(
            file,
            format!("left out, rebuilt by {}", name(w)),
        ));
        if matches!(w, Weighting::Ulr { .. }) {
            let heat = metrics::heat_map(&metrics::flip_map(&truth, &over(BACKGROUND, &b.image))?);
            io::write_png(&out.join("views-left-out-flip.png"), &heat)?;
            figures.push(Figure::heat_map(
                "views-left-out-flip.png",
                "FLIP of the ULR rebuild",
            ));
        }
    }

    // Novel viewpoints above the ring, between its cameras: the exact render is the truth.
    let mut scene = capture_scene(&model).map_err(|e| ReportError::Scene(Box::new(e)))?;
    let b = scene.objects[0].mesh.bounds();
    let centre = ((b.min + b.max) * 0.5).as_dvec3();
    let radius = (b.extent().length() * 0.5) as f64;
    let mut novel = Table::new(["viewpoint", "weights", "PSNR (dB)", "SSIM", "FLIP", "holes"]);
    let mut novel_figures = Vec::new();
    for (k, (azimuth, elevation)) in [(5.0f64, 35.0f64), (95.0, 50.0), (185.0, 25.0)]
        .into_iter()
        .enumerate()
    {
        let (a, e) = (azimuth.to_radians(), elevation.to_radians());
        let eye = centre
            + DVec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
                * radius
                * settings.distance;
        scene.camera.position = eye.as_vec3();
        scene.camera.look_at = centre.as_vec3();
        scene.camera.fov_y = settings.fov_y;
        (scene.camera.width, scene.camera.height) = settings.size;
        scene.camera.near = radius * 1e-3;
        let (frame, _) = trompe::render::render(&scene, trompe::render::Method::Trace, &())?;
        let camera = scene
            .view(0.0)
            .map_err(trompe::render::RenderError::from)?
            .camera;
        for w in weightings {
            let s = BlendSettings {
                weighting: w,
                ..base
            };
            let bl = blend::render(&camera, &mesh, &set.views, &depth, &s, None)?;
            let mask = bl.image.map(|c| c.w > 0.0);
            let sc = metrics::compare(&frame.color, &bl.image, Some(&mask))?;
            novel.row([
                format!("azimuth {azimuth}°, elevation {elevation}°"),
                name(w).to_string(),
                format!("{:.2}", sc.psnr),
                format!("{:.4}", sc.ssim),
                format!("{:.4}", sc.flip),
                format!("{:.2} %", 100.0 * bl.unseen_share()),
            ]);
            if k == 0 && matches!(w, Weighting::Ulr { .. }) {
                io::write_png(&out.join("views-novel-exact.png"), &frame.color)?;
                io::write_png(
                    &out.join("views-novel-ulr.png"),
                    &over(BACKGROUND, &bl.image),
                )?;
                let heat = metrics::heat_map(&metrics::flip_map(
                    &frame.color,
                    &over(BACKGROUND, &bl.image),
                )?);
                io::write_png(&out.join("views-novel-flip.png"), &heat)?;
                novel_figures = vec![
                    Figure::new("views-novel-exact.png", "exact render (ground truth)"),
                    Figure::new("views-novel-ulr.png", "textured from the 36 views (ULR)"),
                    Figure::heat_map("views-novel-flip.png", "FLIP"),
                ];
            }
        }
    }

    let mut s = Section::new("views", "Calibrated views and view-dependent texturing");
    s.paragraph(format!(
        "The glTF duck captured by {} cameras on a ring 15° up, {} × {} pixels, rendered by the \
         exact tracer and written as a COLMAP model (`trompe views capture`). A surface point seen \
         from a new camera takes the colour of the views that see it (per-view depth maps, 1 % \
         tolerance), weighted by the Unstructured Lumigraph (k = 4), by VDTM's inverse angle, by \
         Debevec's view map, or \
         — the baseline a single-texture bake gives — by the one view a face that sees it largest.",
        settings.count, settings.size.0, settings.size.1
    ));
    s.heading("Leave one out");
    s.paragraph(
        "Each of these views is rendered from the other 35 and compared with its own image, on the \
         pixels the blend covers (`trompe views score`).",
    );
    s.table(loo);
    s.figures(figures);
    s.heading("Novel viewpoints");
    s.paragraph(
        "Above the ring, where no camera stood, against the exact render of the same camera.",
    );
    s.table(novel);
    s.figures(novel_figures);
    Ok(s)
}
