//! Section "Master Texture Space" (paper 5): a ring capture of the Duck encoded into master
//! textures (paper Fig. 4), renders from a new camera from the masters beside the same renderer
//! from the exemplars, two edits propagated to every view (paper Fig. 6–7: a disc painted into
//! one exemplar; the shadow of an added sphere seen from a new camera, rendered by the relief
//! module's software shader), and the storage table (paper Table 1).

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, over};
use glam::{Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba, io, metrics};
use trompe::master::edit::{Apply, delta, delta_from_camera, propagate};
use trompe::master::job::{EDIT_THRESHOLD, storage};
use trompe::master::render::render;
use trompe::master::{Encoding, MasterError, encode, encode_views};
use trompe::views::BlendSettings;
use trompe::views::capture::{CaptureSettings, capture};
use trompe::views::visibility::DepthMap;

impl From<MasterError> for ReportError {
    fn from(e: MasterError) -> Self {
        ReportError::Master(Box::new(e))
    }
}

/// What a texel or pixel no view sees shows in the figures: a light grey.
const GREY: Vec4 = Vec4::new(0.8, 0.8, 0.8, 1.0);

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let model = inputs.assets.join("gltf/Duck.glb");
    let settings = CaptureSettings {
        count: 36,
        size: (256, 192),
        ..Default::default()
    };
    let set = capture(&model, &settings, &())?;
    let mesh = trompe::geom::io::load(&model)?.mesh;
    let t = std::time::Instant::now();
    let enc = encode_views(&mesh, &set.views, trompe::master::DEFAULT_SCALE, &())?;
    let encode_time = t.elapsed();
    let cameras = enc.pinholes();
    let blend = BlendSettings::default();

    // An exemplar, its master texture, the bake.
    let exemplar = set.views[0]
        .image
        .clone()
        .ok_or_else(|| trompe::views::ViewsError::Empty(model.clone()))?;
    io::write_png(&out.join("master-exemplar.png"), &exemplar)?;
    io::write_png(
        &out.join("master-texture.png"),
        &over(GREY, &enc.masters[0]),
    )?;

    // A new camera above the ring: from the masters and from the exemplars.
    let b = mesh.bounds();
    let centre = b.center();
    let radius = b.extent().length() * 0.5;
    let novel = |dir: Vec3| -> Result<Pinhole, ReportError> {
        Ok(Pinhole::look_at(
            centre + dir.normalize() * radius * 3.2,
            centre,
            Vec3::Y,
            40.0,
            256,
            192,
        )?)
    };
    let camera = novel(Vec3::new(0.5, 0.7, 1.0))?;
    let t = std::time::Instant::now();
    let from_masters = render(
        &camera,
        &mesh,
        &enc.atlas.layout,
        &cameras,
        &enc.masters,
        &blend,
    )?;
    let masters_time = t.elapsed();
    let depth = DepthMap::of_all(&set.views, &mesh)?;
    let t = std::time::Instant::now();
    let from_exemplars =
        trompe::views::blend::render(&camera, &mesh, &set.views, &depth, &blend, None)?;
    let exemplars_time = t.elapsed();
    let mask = from_exemplars.image.map(|c| c.w > 0.0);
    let agreement = metrics::psnr(&from_exemplars.image, &from_masters.image, Some(&mask))?;
    io::write_png(
        &out.join("master-novel.png"),
        &over(GREY, &from_masters.image),
    )?;
    io::write_png(
        &out.join("master-novel-exemplars.png"),
        &over(GREY, &from_exemplars.image),
    )?;

    // Edit (a): a disc painted into exemplar 0, propagated, seen from the new camera.
    let mut painted = exemplar.clone();
    let (w, h) = painted.size();
    let (cx, cy, r) = (w as f32 * 0.42, h as f32 * 0.38, h as f32 * 0.09);
    for y in 0..h {
        for x in 0..w {
            let c = trompe::frame::pixel_centre(f64::from(x), f64::from(y)).as_vec2();
            let (dx, dy) = (c.x - cx, c.y - cy);
            if dx * dx + dy * dy < r * r && painted.get(x, y).w > 0.0 {
                painted.set(x, y, Vec4::new(0.05, 0.15, 0.85, 1.0));
            }
        }
    }
    io::write_png(&out.join("master-painted.png"), &painted)?;
    let (_, cam0) = &enc.cameras[0];
    let after = encode(&enc.atlas, cam0, &painted, &DepthMap::through(cam0, &mesh)?)?;
    let d = delta(&enc.masters[0], &after, EDIT_THRESHOLD)?;
    let mut edited = enc.masters.clone();
    let changed_a = propagate(&mut edited, &d, &after, Apply::Add)?;
    let edited_view = render(&camera, &mesh, &enc.atlas.layout, &cameras, &edited, &blend)?;
    io::write_png(
        &out.join("master-edit-a.png"),
        &over(GREY, &edited_view.image),
    )?;

    // Edit (b): the shadow of a sphere added above the Duck, seen from a new camera and
    // rendered with and without it by the software shader (hard shadows).
    let (shadow_file, changed_b) = shadow_edit(&model, &mesh, &enc, &cameras, &blend, out)?;

    // Storage, paper Table 1: exemplars + per-view UVs against masters + one UV set.
    let mut table = Table::new([
        "model",
        "faces",
        "views",
        "texels a pixel",
        "atlas",
        "exemplars + their UVs",
        "masters + one UV set",
        "exemplars : masters",
    ]);
    let teapot = inputs.assets.join("meshes/teapot.obj");
    for (path, name) in [(&model, "Duck"), (&teapot, "teapot")] {
        let m = trompe::geom::io::load(path)?.mesh;
        for count in [12usize, 36] {
            let s = CaptureSettings {
                count,
                size: (256, 192),
                ..Default::default()
            };
            let views = capture(path, &s, &())?;
            for scale in [1.0, 2.0] {
                let e = encode_views(&m, &views.views, scale, &())?;
                let sizes: Vec<(u32, u32)> =
                    views.views.iter().map(|v| v.intrinsics.size()).collect();
                let ((ex, exuv), (ma, mauv)) = storage(&e.atlas, &sizes);
                let mb = |b: u64| format!("{:.2} MB", b as f64 / 1e6);
                table.row([
                    name.to_string(),
                    m.triangle_count().to_string(),
                    count.to_string(),
                    format!("{scale}"),
                    format!("{} × {}", e.atlas.size().0, e.atlas.size().1),
                    mb(ex + exuv),
                    mb(ma + mauv),
                    format!("{:.2} : 1", (ex + exuv) as f64 / (ma + mauv) as f64),
                ]);
            }
        }
    }

    let mut s = Section::new("master", "Master Texture Space");
    s.paragraph(format!(
        "The Duck's 36-view ring capture (256 × 192) encoded into 36 pixel-aligned master \
         textures of {} × {} texels ({:.1} s): every face warped to a right triangle of one size \
         for all views, faces paired two to a box with a gutter, boxes packed largest first; \
         texels a view does not see are marked, not copied (grey below). One packing map, one \
         UV set (`trompe master encode`).",
        enc.atlas.size().0,
        enc.atlas.size().1,
        encode_time.as_secs_f64()
    ));
    s.figures(vec![
        Figure::new("master-exemplar.png", "an exemplar (view 0)"),
        Figure::new("master-texture.png", "its master texture (paper Fig. 4)"),
    ]);
    s.heading("Rendering from the master textures");
    s.paragraph(format!(
        "A camera above the ring, ULR weights (k = 4) from the masters against the same blend \
         from the exemplars: {agreement:.2} dB between the two (goal 45 dB); {:.1} ms from the \
         masters, {:.1} ms from the exemplars.",
        masters_time.as_secs_f64() * 1e3,
        exemplars_time.as_secs_f64() * 1e3
    ));
    s.figures(vec![
        Figure::new("master-novel.png", "from the master textures"),
        Figure::new("master-novel-exemplars.png", "from the exemplars"),
    ]);
    s.heading("Edits propagated to every view");
    s.paragraph(format!(
        "Left: a disc painted into exemplar 0, encoded, its difference added to all 36 master \
         textures ({changed_a} texels); the new camera sees it. Right: a sphere added above the \
         Duck, rendered from a new camera with and without it by the relief module's software \
         shader; the difference of their encodings — the sphere's shadow — added to every \
         master texture ({changed_b} texels) (paper Fig. 6–7)."
    ));
    s.figures(vec![
        Figure::new("master-painted.png", "exemplar 0 as painted"),
        Figure::new(
            "master-edit-a.png",
            "the new camera, from the edited masters",
        ),
        Figure::new(shadow_file, "the shadow propagated, from the new camera"),
    ]);
    s.heading("Storage");
    s.paragraph(
        "Bytes as 8-bit RGB images and f32 texture coordinates. Master textures hold every face \
         at its largest view's resolution for every view, so on ring captures where each view \
         sees about half the object they are larger than the exemplars; the paper reports \
         1 : 2.4 to 3 : 1 on its captures.",
    );
    s.table(table);
    Ok(s)
}

/// The shadow edit: returns the figure's file and the texels changed.
fn shadow_edit(
    model: &Path,
    mesh: &trompe::geom::Mesh,
    enc: &Encoding,
    cameras: &[Pinhole],
    blend: &BlendSettings,
    out: &Path,
) -> Result<(String, usize), ReportError> {
    let scene = trompe::views::capture::capture_scene(model).map_err(Box::new)?;
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.extent().length() * 0.5);
    let sun = scene
        .lighting
        .light
        .as_ref()
        .map_or(Vec3::Y, |l| l.direction.normalize());
    let sphere = trompe::geom::icosphere(3).transformed(
        &(glam::Mat4::from_translation(centre + sun * radius * 1.3)
            * glam::Mat4::from_scale(Vec3::splat(radius * 0.7))),
    );
    let camera = Pinhole::look_at(
        centre + Vec3::new(-0.9, 0.8, 0.6).normalize() * radius * 3.2,
        centre,
        Vec3::Y,
        40.0,
        256,
        192,
    )?;
    let view = |with: bool| trompe::scene::View {
        lens: None,
        camera: camera.clone(),
        meshes: if with {
            vec![Arc::new(mesh.clone()), Arc::new(sphere.clone())]
        } else {
            vec![Arc::new(mesh.clone())]
        },
        surfaces: if with {
            vec![
                trompe::scene::Surface::Diffuse(None),
                trompe::scene::Surface::Diffuse(None),
            ]
        } else {
            vec![trompe::scene::Surface::Diffuse(None)]
        },
    };
    let render_with = |with: bool| -> Result<Image<Rgba>, ReportError> {
        let shader =
            trompe::relief::SoftwareShader::new(&view(with), &scene.lighting, &scene.render)?;
        Ok(shader.render(&camera, &[0])?.color)
    };
    let (without, with) = (render_with(false)?, render_with(true)?);
    let (d, after) = delta_from_camera(&enc.atlas, mesh, &camera, &without, &with, EDIT_THRESHOLD)?;
    let mut edited = enc.masters.clone();
    let changed = propagate(&mut edited, &d, &after, Apply::Add)?;
    let seen_from = Pinhole::look_at(
        centre + Vec3::new(0.5, 0.9, 0.9).normalize() * radius * 3.2,
        centre,
        Vec3::Y,
        40.0,
        256,
        192,
    )?;
    let shown = render(&seen_from, mesh, &enc.atlas.layout, cameras, &edited, blend)?;
    io::write_png(&out.join("master-edit-b.png"), &over(GREY, &shown.image))?;
    Ok(("master-edit-b.png".into(), changed))
}
