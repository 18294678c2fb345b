//! Section "Relief impostors" (paper 3, "Software Shaders in Interactive Environments Using
//! Relief Impostors"): an impostor made by the software shader (Fig. 2), where it stays valid
//! (Fig. 3), a walk around the shipped relief scene through the two-thread pipeline — frames
//! beside the true render and direct rasterization, a chart of PSNR and states per frame — and
//! the heuristic against the brute force.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError};
use glam::{DVec3, Vec4};
use std::path::Path;
use trompe::frame::{Image, Rgba, io, metrics};
use trompe::relief::ObjectState;
use trompe::relief::validity::{RATIO_THRESHOLD, validity_map};
use trompe::relief::walk::{path, true_frame, verdicts_along};
use trompe::relief::{DepthEncoding, PipelineSettings, ReliefError, WalkSettings, walk};
use trompe::scene::Scene;

impl From<ReliefError> for ReportError {
    fn from(e: ReliefError) -> Self {
        ReportError::Relief(Box::new(e))
    }
}

/// Frames of the walk shown as images.
const SHOWN: [usize; 3] = [20, 50, 95];

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let scene = Scene::load(&inputs.scenes.join("relief-walk.toml")).map_err(Box::new)?;
    let frames = 120;
    let settings = WalkSettings {
        frames,
        pipeline: PipelineSettings {
            deterministic: Some(2),
            ..Default::default()
        },
        objects: Vec::new(),
        score: true,
    };
    let cameras = path(&scene, frames)?;
    let mut shown = Vec::new();
    let report = walk(&scene, &settings, &(), &mut |i, frame, truth| {
        if SHOWN.contains(&i)
            && let Some(t) = truth
        {
            shown.push((i, frame.color.clone(), t.color.clone()));
        }
        Ok(())
    })?;

    // The impostor of the bunny the walk starts with, and where it stays valid.
    let view = scene.view(scene.render.time)?;
    let shader = trompe::relief::SoftwareShader::new(&view, &scene.lighting, &scene.render)?;
    let eye = cameras
        .first()
        .map_or(scene.camera.position.as_dvec3(), |(_, c)| c.position());
    let imp = shader
        .impostor(0, eye, 256, DepthEncoding::U8, &|| false)?
        .ok_or(ReliefError::Worker("cancelled"))?;
    io::write_png(&out.join("relief-impostor-color.png"), &imp.color_image()?)?;
    io::write_png(&out.join("relief-impostor-depth.png"), &imp.depth_image()?)?;
    let (centre, radius) = shader.bounds(0)?;
    let level = DVec3::new(centre.x, eye.y, centre.z);
    let (map, valid) = validity_map(
        &imp,
        level,
        DVec3::X,
        -DVec3::Z,
        9.0,
        radius * 1.5,
        48,
        RATIO_THRESHOLD,
    )?;
    io::write_png(&out.join("relief-validity.png"), &upscale(&map, 4)?)?;

    // Frames: relief, truth, direct rasterization, FLIP of the relief frame.
    let mut figures = Vec::new();
    for (i, frame, truth) in &shown {
        let (_, camera) = &cameras[*i];
        let raster = trompe::relief::raster::raster_subset(
            &view,
            &scene.lighting,
            camera,
            &[0, 1],
            &mut trompe::render::Timings::default(),
        )?;
        let states: Vec<String> = report.frames[*i]
            .objects
            .iter()
            .map(|o| o.state.to_string())
            .collect();
        io::write_png(&out.join(format!("relief-frame-{i}.png")), frame)?;
        io::write_png(&out.join(format!("relief-truth-{i}.png")), truth)?;
        io::write_png(&out.join(format!("relief-raster-{i}.png")), &raster.color)?;
        let heat = metrics::heat_map(&metrics::flip_map(truth, frame)?);
        io::write_png(&out.join(format!("relief-flip-{i}.png")), &heat)?;
        figures.push(Figure::new(
            format!("relief-frame-{i}.png"),
            format!(
                "frame {i}: relief impostors ({}), {:.1} dB",
                states.join(", "),
                report.frames[*i].psnr.unwrap_or(f64::NAN)
            ),
        ));
        figures.push(Figure::new(
            format!("relief-truth-{i}.png"),
            "the software shader's true render (shadows)",
        ));
        figures.push(Figure::new(
            format!("relief-raster-{i}.png"),
            format!(
                "direct rasterization, {:.1} dB",
                report.frames[*i].raster_psnr.unwrap_or(f64::NAN)
            ),
        ));
        figures.push(Figure::heat_map(
            format!("relief-flip-{i}.png"),
            "FLIP, relief against the truth",
        ));
    }
    io::write_png(&out.join("relief-chart.png"), &chart(&report)?)?;

    // The walk in numbers.
    let (relief_time, raster_time) = report.mean_times();
    let traced = {
        let (_, camera) = &cameras[cameras.len() / 2];
        let t = std::time::Instant::now();
        true_frame(&shader, camera, &[0, 1], &[])?;
        t.elapsed()
    };
    let (agree, judged) = report.agreement();
    let mut numbers = Table::new(["", "this walk", "paper"]);
    let per_object = report.regenerations as f64 / report.frames[0].objects.len().max(1) as f64;
    for (what, ours, paper) in [
        (
            "impostors made per object, one orbit".to_string(),
            format!("{per_object:.0}"),
            "17",
        ),
        (
            "frames warped / valid without a warp / stale / fallback".into(),
            format!(
                "{} / {} / {} / {}",
                report.count(ObjectState::Warping),
                report.count(ObjectState::Valid),
                report.count(ObjectState::Stale),
                report.count(ObjectState::Fallback)
            ),
            "—",
        ),
        ("cache hits".into(), report.cache_hits().to_string(), "—"),
        (
            "mean PSNR against the true render, relief / direct rasterization".into(),
            format!(
                "{:.2} / {:.2} dB",
                report.mean_psnr().unwrap_or(f64::NAN),
                report.mean_raster_psnr().unwrap_or(f64::NAN)
            ),
            "—",
        ),
        (
            "frame time: relief / direct rasterization / ray traced".into(),
            format!(
                "{:.1} / {:.1} / {:.1} ms",
                relief_time.as_secs_f64() * 1e3,
                raster_time.as_secs_f64() * 1e3,
                traced.as_secs_f64() * 1e3
            ),
            "131 / 124 fps (GPU)",
        ),
        (
            "heuristic and brute force agree (frames showing an impostor)".into(),
            format!("{:.1} % of {judged}", agree * 100.0),
            "—",
        ),
        (
            "camera positions where the first impostor stays valid (map)".into(),
            format!("{:.1} %", valid * 100.0),
            "Fig. 3",
        ),
        (
            "impostor memory held at the end (in use and cached)".into(),
            format!("{:.1} MB", report.bytes as f64 / 1e6),
            "—",
        ),
    ] {
        numbers.row([what, ours, paper.to_string()]);
    }

    // The heuristic against the brute force, no pipeline: impostors made every 15° of an
    // orbit, judged over the 45° that follow.
    let eyes: Vec<glam::Vec3> = cameras
        .iter()
        .map(|(_, c)| c.position().as_vec3())
        .collect();
    let mut judged_table = Table::new([
        "object",
        "eyes judged",
        "obsolete by the brute force",
        "agreement",
    ]);
    for (object, name) in [(0, "bunny"), (1, "teapot")] {
        let v = verdicts_along(&shader, object, &eyes, 5, 15, 256, 4)?;
        let obsolete = v.iter().filter(|(_, r)| *r > RATIO_THRESHOLD).count();
        let agree = v
            .iter()
            .filter(|(p, r)| (*p > RATIO_THRESHOLD) == (*r > RATIO_THRESHOLD))
            .count();
        judged_table.row([
            name.to_string(),
            v.len().to_string(),
            format!("{:.0} %", 100.0 * obsolete as f64 / v.len().max(1) as f64),
            format!("{:.1} %", 100.0 * agree as f64 / v.len().max(1) as f64),
        ]);
    }

    let mut s = Section::new("relief", "Relief impostors and the software shader");
    s.paragraph(
        "An object drawn as a **relief impostor**: an orthographic colour + depth image made by \
         the software shader — trompe's ray tracer, with the hard shadows a rasterizer lacks — \
         pre-warped for each new eye in two 1-D passes and texture-mapped on its base quad with \
         per-pixel depth. The rendering thread makes a new impostor when the critical-point \
         heuristic predicts that more than 20 % of the warped texels would be interpolated; the \
         frame loop never waits for it (`trompe relief scenes/relief-walk.toml`).",
    );
    s.figures(vec![
        Figure::new(
            "relief-impostor-color.png",
            "impostor of the bunny, 256², colour (paper Fig. 2)",
        ),
        Figure::new(
            "relief-impostor-depth.png",
            "its depth, 8 bits (white: the base plane)",
        ),
        Figure::new(
            "relief-validity.png",
            "where it stays valid: eyes at its height, green ≤ 20 % interpolated, red above, white its own eye (paper Fig. 3)",
        ),
    ]);
    s.heading("A walk around the scene");
    s.paragraph(format!(
        "{frames} frames on one orbit, deterministic mode (a new impostor is used two frames \
         after it is requested, for the eye predicted two frames ahead)."
    ));
    s.table(numbers);
    s.figures(vec![Figure::new(
        "relief-chart.png",
        "per frame: PSNR of the relief frame (orange) and of direct rasterization (grey) against the truth; below, each object's state (green warped, blue valid, yellow stale, red fallback) and a tick where a new impostor came in",
    )]);
    s.figures(figures);
    s.heading("The heuristic against the brute force");
    s.paragraph(
        "Impostors made every 15° of the orbit, each judged at the 15 eyes that follow, by the \
         heuristic's predicted share and by the share the warp actually interpolates.",
    );
    s.table(judged_table);
    Ok(s)
}

/// Nearest-neighbour enlargement (for small maps).
fn upscale(image: &Image<Rgba>, k: u32) -> Result<Image<Rgba>, trompe::frame::FrameError> {
    let (w, h) = image.size();
    let mut out = Image::new(w * k, h * k, Rgba::ZERO)?;
    for y in 0..h * k {
        for x in 0..w * k {
            out.set(x, y, image.get(x / k, y / k));
        }
    }
    Ok(out)
}

/// The walk's chart: PSNR per frame (relief and direct rasterization) above a strip of states
/// per object.
fn chart(report: &trompe::relief::WalkReport) -> Result<Image<Rgba>, trompe::frame::FrameError> {
    let n = report.frames.len().max(1);
    let objects = report.frames.first().map_or(0, |f| f.objects.len());
    let (cw, plot_h, strip) = (4u32, 160u32, 10u32);
    let (w, h) = (n as u32 * cw, plot_h + strip * objects as u32 + 4);
    let mut img = Image::new(w, h, Vec4::new(1.0, 1.0, 1.0, 1.0))?;
    let (lo, hi) = (20.0, 50.0);
    let y_of = |p: f64| {
        let t = ((p.min(hi) - lo) / (hi - lo)).clamp(0.0, 1.0);
        ((1.0 - t) * (plot_h - 1) as f64) as u32
    };
    // Grid lines every 10 dB.
    for db in [20.0, 30.0, 40.0, 50.0] {
        let y = y_of(db);
        for x in 0..w {
            img.set(x, y, Vec4::new(0.85, 0.85, 0.85, 1.0));
        }
    }
    let mut line = |values: Vec<Option<f64>>, colour: Vec4| {
        let mut prev: Option<(u32, u32)> = None;
        for (i, v) in values.into_iter().enumerate() {
            let x = i as u32 * cw + cw / 2;
            let Some(p) = v else {
                prev = None;
                continue;
            };
            let y = y_of(p);
            if let Some((px, py)) = prev {
                let steps = (x - px).max(py.abs_diff(y)).max(1);
                for s in 0..=steps {
                    let t = s as f64 / steps as f64;
                    let xx = (px as f64 + (x - px) as f64 * t) as u32;
                    let yy = (py as f64 + (y as f64 - py as f64) * t) as u32;
                    img.set(xx.min(w - 1), yy.min(plot_h - 1), colour);
                    img.set(xx.min(w - 1), (yy + 1).min(plot_h - 1), colour);
                }
            }
            prev = Some((x, y));
        }
    };
    line(
        report.frames.iter().map(|f| f.raster_psnr).collect(),
        Vec4::new(0.55, 0.55, 0.55, 1.0),
    );
    line(
        report.frames.iter().map(|f| f.psnr).collect(),
        Vec4::new(0.95, 0.45, 0.1, 1.0),
    );
    for (i, f) in report.frames.iter().enumerate() {
        for (o, of) in f.objects.iter().enumerate() {
            let colour = match of.state {
                ObjectState::Warping => Vec4::new(0.2, 0.65, 0.25, 1.0),
                ObjectState::Valid => Vec4::new(0.2, 0.4, 0.85, 1.0),
                ObjectState::Stale => Vec4::new(0.95, 0.8, 0.2, 1.0),
                ObjectState::Fallback => Vec4::new(0.8, 0.15, 0.1, 1.0),
            };
            let y0 = plot_h + 2 + o as u32 * strip;
            for y in y0..y0 + strip - 1 {
                for x in i as u32 * cw..(i as u32 + 1) * cw {
                    let tick = (of.regenerated || of.cache_hit) && x == i as u32 * cw;
                    img.set(
                        x,
                        y,
                        if tick {
                            Vec4::new(0.0, 0.0, 0.0, 1.0)
                        } else {
                            colour
                        },
                    );
                }
            }
        }
    }
    Ok(img)
}
