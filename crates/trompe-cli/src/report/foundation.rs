//! Section "Ground-truth renderers": every shipped scene by every method, each image beside its
//! FLIP error map against the trace method, scores and per-step timings; the shipped models;
//! the rasterizer against the exact BVH.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, RenderRow, ReportError, fmt_psnr};
use std::path::Path;
use trompe::frame::{io, metrics};
use trompe::methods::{MethodKind, MethodSettings, Renderer};
use trompe::render::Progress;
use trompe::scene::Scene;

/// Renders the shipped scenes; returns the section and a row per render.
pub(super) fn section(
    inputs: &DemoInputs,
    out: &Path,
    progress: &dyn Fn(&str, u64) -> Box<dyn Progress>,
) -> Result<(Section, Vec<RenderRow>), ReportError> {
    let mut s = Section::new(
        "renderers",
        "Ground-truth renderers and the impostor method",
    );
    s.paragraph("**raster** rasterizes through the pinhole camera and shades each pixel once (mirrors and glass are looked up in the panorama); **trace** is a Whitted ray tracer through the exact BVH (mirror reflection, refraction with Fresnel). On the diffuse scene the two must agree: they share one shading model and differ only at silhouette pixels. **impostor** is paper 1's method: primary rays as **trace**, and what mirrors and glass send out answered by 512² impostors of the diffuse objects built from each one's centre — a SPOC of an object beside it, a parallel depth image of a floor, a cube map of a room around it — or by the panorama (`trompe render scenes/reflections.toml --method impostor`). Each image stands beside its FLIP error map against the trace image. The last five scenes are paper 1's: a teapot in a mirror bunny (Fig. 1), a mirror ball passing through a teapot (Fig. 2; `--frames` plays it), inter-reflecting teapots and a glass bunny (Fig. 3, 11), a large mirror ball whose rays reach the lid and bottom a pinhole depth image misses (Fig. 6), and a mirror ball in the maze with four bunnies (Fig. 4–5). Paper 1's Tables 1 and 2, second-order mirrors and dynamic scenes: `docs/reflections.md` and `trompe bench reflect`.");
    let mut scores = Table::new([
        "scene",
        "method",
        "time",
        "PSNR (dB)",
        "SSIM",
        "FLIP",
        "object ids equal",
    ]);
    let mut steps = Table::new(["scene", "method", "steps (ms)"]);
    let mut rows = Vec::new();
    // The shipped scenes, then paper 1's: Fig. 1, 2, 3 and 11, 6, 4–5.
    for name in [
        "diffuse",
        "reflections",
        "room",
        "teapot-in-bunny",
        "intersecting",
        "teapots",
        "pinhole-misses",
        "maze",
    ] {
        let path = inputs.scenes.join(format!("{name}.toml"));
        let scene = Scene::load(&path).map_err(Box::new)?;
        let h = scene.camera.height;
        let mut methods = vec![MethodKind::Trace, MethodKind::Raster];
        if name != "diffuse" {
            methods.extend([
                MethodKind::Impostor,
                MethodKind::PinholeImpostor,
                MethodKind::EnvMap,
            ]);
        }
        let mut frames = Vec::new();
        for method in methods {
            let bar = progress(&format!("{name} ({method})"), h as u64);
            let start = std::time::Instant::now();
            let mut renderer = Renderer::new(&scene, method, MethodSettings::default())?;
            let out = renderer.frame(scene.render.time, None, bar.as_ref())?;
            frames.push((method, out.frame, start.elapsed(), out.timings));
        }
        let reference = frames[0].1.clone();
        s.heading(format!("Scene `{name}.toml`"));
        let mut figures = Vec::new();
        for (method, frame, time, timings) in &frames {
            let file = format!("{name}-{method}.png");
            io::write_png(&out.join(&file), &frame.color)?;
            figures.push(Figure::new(
                &file,
                format!("{method}, {:.0} ms", time.as_secs_f64() * 1e3),
            ));
            if *method != MethodKind::Trace {
                let heat = metrics::heat_map(&metrics::flip_map(&reference.color, &frame.color)?);
                let heat_file = format!("{name}-{method}-flip.png");
                io::write_png(&out.join(&heat_file), &heat)?;
                figures.push(Figure::heat_map(
                    heat_file,
                    format!("FLIP error, {method} against trace"),
                ));
            }
            let sc = metrics::compare(&reference.color, &frame.color, None)?;
            let same = frame
                .object_id
                .pixels()
                .iter()
                .zip(reference.object_id.pixels())
                .filter(|(a, b)| a == b)
                .count() as f64
                / reference.object_id.pixels().len() as f64;
            scores.row([
                name.to_string(),
                method.to_string(),
                format!("{:.0} ms", time.as_secs_f64() * 1e3),
                fmt_psnr(sc.psnr),
                format!("{:.4}", sc.ssim),
                format!("{:.4}", sc.flip),
                format!("{:.2} %", same * 100.0),
            ]);
            let listed: Vec<String> = timings
                .0
                .iter()
                .map(|(step, d)| format!("{step} {:.1}", d.as_secs_f64() * 1e3))
                .collect();
            steps.row([name.to_string(), method.to_string(), listed.join(" · ")]);
            rows.push(RenderRow {
                scene: name.to_string(),
                method: *method,
                time: *time,
                scores: sc,
                id_agreement: same,
            });
        }
        s.figures(figures);
    }
    s.heading("Scores against the trace image");
    s.table(scores);
    s.heading("Per-step timings");
    s.table(steps);
    paper_tables(&mut s, inputs)?;

    s.heading("Shipped models");
    let mut models = Table::new([
        "file",
        "vertices (file)",
        "triangles (file)",
        "triangles kept",
        "materials",
        "textured",
    ]);
    for rel in ["meshes/bunny.obj", "meshes/teapot.obj", "gltf/Duck.glb"] {
        let loaded = trompe::geom::io::load(&inputs.assets.join(rel))?;
        let m = &loaded.mesh;
        let textured = m.materials.iter().any(|x| x.texture.is_some());
        models.row([
            format!("`{rel}`"),
            loaded.source.vertices.to_string(),
            loaded.source.triangles.to_string(),
            m.triangle_count().to_string(),
            m.materials.len().to_string(),
            if textured { "yes" } else { "no" }.to_string(),
        ]);
    }
    s.table(models);

    let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let a = trompe::eval::validate::raster_vs_bvh(&bunny, 256)?;
    s.heading("The rasterizer against the exact BVH (bunny, 256²)");
    let mut t = Table::new([
        "covered pixels",
        "max relative depth error",
        "item ids equal",
        "coverage equal",
    ]);
    t.row([
        a.covered.to_string(),
        format!("{:.2e}", a.max_relative_depth_error),
        format!("{:.3} %", a.id_agreement * 100.0),
        format!("{:.3} %", a.coverage_agreement * 100.0),
    ]);
    s.table(t);
    Ok((s, rows))
}

/// Paper 1's Tables 1 and 2 on `teapot-in-bunny.toml`: frame time against output resolution
/// and against impostor resolution (`trompe bench reflect` prints every row).
fn paper_tables(s: &mut Section, inputs: &DemoInputs) -> Result<(), ReportError> {
    use crate::bench::reflect::{Selection, tables};
    let t =
        tables(inputs, &Selection::paper_tables()).map_err(|e| ReportError::Bench(Box::new(e)))?;
    let ms = |d: std::time::Duration| format!("{:.1}", d.as_secs_f64() * 1e3);
    s.heading(
        "Paper 1, Table 1: frame time against output resolution (teapot-in-bunny, 512² impostors)",
    );
    s.paragraph("The first frame builds the impostors; later frames of a sequence keep them (nothing deforms), with the primary pass traced or rasterized; `trace` is the exact frame with its BVH kept. Goal: 30 frames/s at 640×480.");
    let mut one = Table::new([
        "pixels",
        "first frame (ms)",
        "later frame (ms)",
        "rasterized primary (ms)",
        "frames/s",
        "trace (ms)",
    ]);
    for r in &t.by_output {
        one.row([
            format!("{}×{}", r.size.0, r.size.1),
            ms(r.first),
            ms(r.kept),
            ms(r.rasterized),
            format!("{:.1}", 1.0 / r.rasterized.as_secs_f64().max(1e-9)),
            ms(r.trace),
        ]);
    }
    s.table(one);
    s.heading("Paper 1, Table 2: frame time against impostor resolution (640×480)");
    let mut two = Table::new([
        "texels a side",
        "build and light (ms)",
        "later frame (ms)",
        "longest ray projection (texels)",
        "FLIP vs trace",
    ]);
    for r in &t.by_impostor {
        two.row([
            r.side.to_string(),
            ms(r.build),
            ms(r.kept),
            r.max_projection.to_string(),
            format!("{:.4}", r.flip),
        ]);
    }
    s.table(two);
    Ok(())
}
