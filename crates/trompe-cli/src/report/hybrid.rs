//! Section "Hybrid reflections" (paper 2, "Hybrid backward-forward reflection rendering with
//! continuous 3-ray cameras"): the shipped mirror teapot reflecting the bunny — splatted through
//! C3RCs, with and without the level of detail, beside the exact frame and its FLIP map (paper
//! Fig. 1 and 5) — the construction rays drawn on the reflector (Fig. 3), and the demo's
//! reflection scene, mirror ball, glass ball and teapot over a ground, by both methods (Fig. 2).

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, draw_line};
use glam::Vec4;
use std::path::Path;
use std::time::Instant;
use trompe::camera::{C3rc, Projection};
use trompe::frame::{Image, Rgba, io, metrics};
use trompe::hybrid::{FrameStats, HybridReflections, HybridSettings};
use trompe::render::{Method, render_at};
use trompe::scene::{Scene, Surface};

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let mut table = Table::new([
        "scene",
        "method",
        "points",
        "C3RCs",
        "culling",
        "projection",
        "valid projections",
        "projections a point",
        "frame",
        "exact frame",
        "FLIP vs exact",
    ]);
    let mut figures = Vec::new();
    for (file, name) in [
        ("c3rc-bunny.toml", "teapot and bunny"),
        ("reflections.toml", "reflections"),
    ] {
        let scene = Scene::load(&inputs.scenes.join(file)).map_err(Box::new)?;
        let t = scene.render.time;
        let start = Instant::now();
        let (exact, _) = render_at(&scene, t, Method::Trace, &())?;
        let exact_time = start.elapsed();
        let stem = file.trim_end_matches(".toml");
        io::write_png(&out.join(format!("hybrid-{stem}-exact.png")), &exact.color)?;
        let variants: &[(bool, &str)] = if stem == "c3rc-bunny" {
            &[
                (true, "C3RC, level of detail"),
                (false, "C3RC, paper's algorithm"),
            ]
        } else {
            &[(true, "C3RC, level of detail")]
        };
        for &(lod, method) in variants {
            let settings = HybridSettings {
                level_of_detail: lod,
                mirrors_occlude: lod,
                ..HybridSettings::default()
            };
            let clouds = HybridReflections::prepare(&scene, settings)?;
            let start = Instant::now();
            let hybrid = clouds.render_at(&scene, t, &())?;
            let frame_time = start.elapsed();
            let flip = metrics::flip(&exact.color, &hybrid.frame.color, None)?;
            row(
                &mut table,
                name,
                method,
                clouds.point_count(),
                &hybrid.stats,
                frame_time,
                exact_time,
                flip,
            );
            let tag = if lod { "lod" } else { "paper" };
            let image = format!("hybrid-{stem}-{tag}.png");
            io::write_png(&out.join(&image), &hybrid.frame.color)?;
            figures.push(Figure::new(image, format!("{name}: {method}")));
            if lod {
                let heat = format!("hybrid-{stem}-flip.png");
                io::write_png(
                    &out.join(&heat),
                    &metrics::heat_map(&metrics::flip_map(&exact.color, &hybrid.frame.color)?),
                )?;
                figures.push(Figure::heat_map(
                    heat,
                    format!("{name}: FLIP against the exact frame"),
                ));
            }
        }
        figures.push(Figure::new(
            format!("hybrid-{stem}-exact.png"),
            format!("{name}: exact reflections (BVH)"),
        ));
        if stem == "c3rc-bunny" {
            let rays = format!("hybrid-{stem}-rays.png");
            io::write_png(&out.join(&rays), &construction_rays(&scene, &exact.color)?)?;
            figures.push(Figure::new(
                rays,
                "construction rays of every 40th reflector triangle (paper Fig. 3)",
            ));
        }
    }
    let mut s = Section::new("hybrid", "Hybrid reflections (continuous 3-ray cameras)");
    s.paragraph(
        "Paper 2: the diffuse objects are sampled once as points in an eight-way kd-tree; every \
         frame, each mirror triangle the eye sees becomes a continuous 3-ray camera whose rays \
         are the reflected rays at its vertices, the tree is culled against its view volume and \
         the surviving points are projected (every valid root of a cubic) and splatted where the \
         mirror is seen, nearest the mirror winning. The level of detail reads each camera's \
         leaves thinned to what its magnification needs, and a splatted pixel whose reflected \
         ray meets a mirror first is traced; the paper's algorithm reads every point and lets \
         points show through mirrors. Primary rays, shading and refraction are the exact \
         tracer's; mirrors do not show one another in splatted reflections.",
    );
    s.figures(figures);
    s.table(table);
    s.paragraph(
        "Regenerate the paper's tables with `trompe bench c3rc` (docs/hybrid.md holds the \
         current figures).",
    );
    Ok(s)
}

#[allow(clippy::too_many_arguments)]
fn row(
    table: &mut Table,
    scene: &str,
    method: &str,
    points: usize,
    st: &FrameStats,
    frame: std::time::Duration,
    exact: std::time::Duration,
    flip: f64,
) {
    let ms = |d: std::time::Duration| format!("{:.1} ms", d.as_secs_f64() * 1e3);
    table.row([
        scene.to_string(),
        method.to_string(),
        points.to_string(),
        st.c3rcs.to_string(),
        ms(st.cull),
        ms(st.project),
        format!("{:.0} %", 100.0 * st.valid_ratio()),
        format!("{:.2}", st.projections_per_point()),
        ms(frame),
        ms(exact),
        format!("{flip:.4}"),
    ]);
}

/// The exact frame with the base edges (grey) and construction rays (yellow, 0.15 long) of
/// every 40th triangle of the mirrors drawn over it.
fn construction_rays(scene: &Scene, under: &Image<Rgba>) -> Result<Image<Rgba>, ReportError> {
    let view = scene.view(scene.render.time)?;
    let mut img = under.clone();
    let eye = view.camera.position();
    let screen = |p: glam::DVec3| view.camera.project(p).map(|ip| ip.uv);
    for (o, mesh) in view.meshes.iter().enumerate() {
        if !matches!(view.surfaces[o], Surface::Mirror { .. }) {
            continue;
        }
        for t in (0..mesh.triangle_count()).step_by(40) {
            let idx = mesh.triangles[t];
            let v = idx.map(|i| mesh.positions[i as usize].as_dvec3());
            let n = idx.map(|i| mesh.normals[i as usize].as_dvec3());
            // Only triangles facing the eye.
            if (v[1] - v[0]).cross(v[2] - v[0]).dot(eye - v[0]) <= 0.0 {
                continue;
            }
            let Some(c) = C3rc::reflector(v, n, eye) else {
                continue;
            };
            for k in 0..3 {
                if let (Some(a), Some(b)) = (screen(v[k]), screen(v[(k + 1) % 3])) {
                    draw_line(&mut img, a, b, Vec4::new(0.5, 0.5, 0.5, 1.0));
                }
                if let (Some(a), Some(b)) = (screen(v[k]), screen(v[k] + c.d[k] * 0.15)) {
                    draw_line(&mut img, a, b, Vec4::new(1.0, 0.85, 0.1, 1.0));
                }
            }
        }
    }
    Ok(img)
}
