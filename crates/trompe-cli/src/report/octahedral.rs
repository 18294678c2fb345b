//! Section "Octahedral impostors" (beyond the papers: what engines' impostor bakers make): the
//! Duck's atlas, renders from it beside the exact render (a side view and straight down), its
//! turntable's FLIP with and without parallax, and the bake's memory.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, draw_line};
use glam::{DVec2, Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::frame::envmap::EnvMap;
use trompe::frame::{Image, Rgba, io, metrics};
use trompe::octahedral::{BakeSettings, Coverage, Grid, TurntableView, bake, turntable};
use trompe::scene::{Light, Lighting, RenderSettings, Surface, View};

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let mesh = trompe::geom::io::load(&inputs.assets.join("gltf/Duck.glb"))?.mesh;
    let surface = Surface::Diffuse(None);
    let settings = BakeSettings::new(
        Grid {
            n: 16,
            coverage: Coverage::Sphere,
        },
        96,
    );
    let start = std::time::Instant::now();
    let atlas = bake(&mesh, &surface, settings)?;
    let bake_time = start.elapsed();
    let grey = Vec4::new(0.25, 0.25, 0.25, 1.0);
    io::write_png(
        &out.join("octahedral-atlas.png"),
        &super::over(grey, &atlas.color),
    )?;
    let lighting = Lighting {
        environment: EnvMap::constant(Vec3::new(0.25, 0.3, 0.35)),
        light: Some(Light {
            direction: Vec3::new(0.4, 1.0, 0.6).normalize(),
            irradiance: Vec3::splat(0.9 * std::f32::consts::PI),
        }),
    };
    io::write_png_data(&out.join("octahedral-orm.png"), &atlas.orm)?;
    let mut figures = vec![
        Figure::new(
            "octahedral-atlas.png",
            "the Duck's 16 × 16 octahedral atlas (base colour)",
        ),
        Figure::new(
            "octahedral-orm.png",
            "its ORM atlas: occlusion traced through the BVH (red), roughness (green), metalness (blue)",
        ),
    ];
    for (name, dir, up) in [
        ("side", Vec3::new(0.8, 0.35, 0.5), Vec3::Y),
        ("top", Vec3::new(0.0, 1.0, 0.0), Vec3::Z),
    ] {
        let eye = atlas.centre + dir.normalize() * atlas.radius * 4.0;
        let camera = Pinhole::look_at(eye, atlas.centre, up, 30.0, 256, 256)?;
        let view = View {
            lens: None,
            camera,
            meshes: vec![Arc::new(mesh.clone())],
            surfaces: vec![surface.clone()],
        };
        let settings = RenderSettings {
            max_depth: 2,
            time: 0.0,
            ray_epsilon: atlas.radius * 1e-4,
        };
        let exact = trompe::octahedral::turntable::exact_unshadowed(&view, &lighting, &settings)?;
        let imp = atlas.render(
            &view.camera,
            &lighting,
            trompe::octahedral::render::PARALLAX_STEPS,
        );
        let flip = metrics::flip(&exact.color, &imp, None)?;
        io::write_png(&out.join(format!("octahedral-{name}.png")), &imp)?;
        io::write_png(
            &out.join(format!("octahedral-{name}-exact.png")),
            &exact.color,
        )?;
        figures.push(Figure::new(
            format!("octahedral-{name}.png"),
            format!("{name}: from the atlas, FLIP {flip:.4}"),
        ));
        figures.push(Figure::new(
            format!("octahedral-{name}-exact.png"),
            format!("{name}: exact"),
        ));
    }
    let views = turntable(&atlas, &mesh, &surface, &lighting, 32, 160)?;
    io::write_png(&out.join("octahedral-turntable.png"), &chart(&views)?)?;
    figures.push(Figure::new(
        "octahedral-turntable.png",
        "FLIP per turntable view: with parallax (orange), without (grey); the last two views look straight down and up",
    ));
    interactive_page(out, &atlas, &mesh, &lighting)?;
    let n = views.len() as f64;
    let mean = |f: fn(&TurntableView) -> f64| views.iter().map(f).sum::<f64>() / n;
    let worst = views.iter().map(|v| v.flip).fold(0.0, f64::max);
    // A whole scene, every object drawn from its atlas, beside the traced frame.
    let mut scene =
        trompe::scene::Scene::load(&inputs.scenes.join("duck-mirror.toml")).map_err(Box::new)?;
    (scene.camera.width, scene.camera.height) = (320, 240);
    let t = scene.render.time;
    let scene_settings = BakeSettings {
        frame_size: 64,
        ..settings
    };
    let mut steps = trompe::progress::Timings::default();
    let drawn = trompe::octahedral::scene::render(&scene, t, scene_settings, &(), &mut steps)?;
    let (traced, _) = trompe::render::render_at(&scene, t, trompe::render::Method::Trace, &())?;
    let scene_flip = metrics::flip(&traced.color, &drawn.color, None)?;
    io::write_png(&out.join("octahedral-scene.png"), &drawn.color)?;
    io::write_png(&out.join("octahedral-scene-traced.png"), &traced.color)?;
    figures.push(Figure::new(
        "octahedral-scene.png",
        format!(
            "scenes/duck-mirror.toml with every object drawn from its 16 × 16 atlas (`trompe render --method octahedral`): FLIP {scene_flip:.4}"
        ),
    ));
    figures.push(Figure::new(
        "octahedral-scene-traced.png",
        "traced: the shadows and the duck in the ball are what no atlas holds",
    ));
    let mut table = Table::new([
        "frames",
        "atlas",
        "bake",
        "memory (colour RGBA8 + normal RGB16F + depth R16F + ORM RGB8)",
        "mean FLIP, parallax",
        "worst view",
        "mean FLIP, no parallax",
    ]);
    let side = u64::from(atlas.side());
    table.row([
        "16 × 16".to_string(),
        format!("{side}²"),
        format!("{:.2} s", bake_time.as_secs_f64()),
        format!("{:.1} MB", (side * side * (4 + 6 + 2 + 3)) as f64 / 1e6),
        format!("{:.4}", mean(|v| v.flip)),
        format!("{worst:.4}"),
        format!("{:.4}", mean(|v| v.flip_flat)),
    ]);
    let mut s = Section::new("octahedral", "Octahedral impostors");
    s.paragraph(
        "What engines' impostor bakers make, baked headless and scored: the object seen from a \
         16 × 16 grid of directions laid out by the octahedral map, each frame an orthographic \
         view with base colour, normal, depth and ORM (occlusion, roughness, metalness), dilated \
         so filtering never bleeds background. \
         Rendering picks the three frames around the view direction, blends them by barycentric \
         weights, corrects each lookup's parallax with its depth and relights with the normals \
         (`trompe impostor bake MESH --octahedral 16`).",
    );
    s.figures(figures);
    s.link(
        PAGE,
        "Turn the baked Duck yourself: its `.glb` drawn in your browser by the three.js runtime \
         (`web/trompe-octahedral.js`), beside the exact turntable",
    );
    s.table(table);
    Ok(s)
}

/// The interactive page's file.
const PAGE: &str = "octahedral-turn.html";

/// The bake as a self-contained `.glb` in a page of its own, turned by the reader with the
/// three.js runtime, beside the exact renders of 8 views round the Duck.
fn interactive_page(
    out: &Path,
    atlas: &trompe::octahedral::OctahedralAtlas,
    mesh: &trompe::geom::Mesh,
    lighting: &Lighting,
) -> Result<(), ReportError> {
    let page = out.join(PAGE);
    let png = trompe::octahedral::gltf::TextureFormat::Png;
    let (bytes, _) =
        trompe::octahedral::gltf::encode(atlas, png, &page).map_err(|e| ReportError::Io {
            path: page.clone(),
            source: std::io::Error::other(e.to_string()),
        })?;
    let settings = RenderSettings {
        max_depth: 2,
        time: 0.0,
        ray_epsilon: atlas.radius * 1e-4,
    };
    let mut turntable = Vec::new();
    for k in 0..8 {
        let azimuth = 45.0 * k as f32;
        let (a, e) = (azimuth.to_radians(), 20f32.to_radians());
        let dir = Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
        let eye = atlas.centre + dir * atlas.radius * 4.0;
        let view = View {
            lens: None,
            camera: Pinhole::look_at(eye, atlas.centre, Vec3::Y, 30.0, 192, 192)?,
            meshes: vec![Arc::new(mesh.clone())],
            surfaces: vec![Surface::Diffuse(None)],
        };
        let exact = trompe::octahedral::turntable::exact_unshadowed(&view, lighting, &settings)?;
        let file = format!("octahedral-turn-{k}.png");
        io::write_png(&out.join(&file), &exact.color)?;
        turntable.push((file, format!("azimuth {azimuth}°, exact")));
    }
    let sun = lighting.light.unwrap_or(Light {
        direction: Vec3::Y,
        irradiance: Vec3::ZERO,
    });
    let eye = atlas.centre + Vec3::new(0.8, 0.35, 0.5).normalize() * atlas.radius * 4.0;
    super::turn::write_page(
        out,
        PAGE,
        &bytes,
        (eye.to_array(), atlas.centre.to_array()),
        &super::turn::PageLighting {
            sky: lighting.environment.radiance(Vec3::Y).to_array(),
            sun_direction: sun.direction.to_array(),
            sun_irradiance: sun.irradiance.to_array(),
        },
        &turntable,
    )
}

/// One score of a turntable view.
type Score = fn(&TurntableView) -> f64;

/// FLIP per view: parallax in orange, flat in grey, over a 0–0.2 scale.
fn chart(views: &[TurntableView]) -> Result<Image<Rgba>, trompe::frame::FrameError> {
    let (w, h) = (480u32, 160u32);
    let mut img = Image::new(w, h, Vec4::ONE)?;
    let x = |k: usize| 10.0 + k as f64 * (f64::from(w) - 20.0) / (views.len().max(2) - 1) as f64;
    let y = |f: f64| f64::from(h) - 10.0 - (f / 0.2).min(1.0) * (f64::from(h) - 20.0);
    for k in 1..views.len() {
        let series: [(Score, Vec4); 2] = [
            (|v| v.flip_flat, Vec4::new(0.5, 0.5, 0.5, 1.0)),
            (|v| v.flip, Vec4::new(1.0, 0.5, 0.05, 1.0)),
        ];
        for (value, color) in series {
            draw_line(
                &mut img,
                DVec2::new(x(k - 1), y(value(&views[k - 1]))),
                DVec2::new(x(k), y(value(&views[k]))),
                color,
            );
        }
    }
    // The 0.05 goal.
    draw_line(
        &mut img,
        DVec2::new(10.0, y(0.05)),
        DVec2::new(f64::from(w) - 10.0, y(0.05)),
        Vec4::new(0.2, 0.6, 0.2, 1.0),
    );
    Ok(img)
}
