//! Section "Non-pinhole impostors" (paper 1 §3–4, Fig. 1, 6–7): pinhole and SPOC impostors of the
//! teapot (colour and `gd`), their fidelity against the BVH on a reflector's rays, against the
//! reflector's distance, and baked as `impostor bake` does on rays from around the viewpoint;
//! then a mirror bunny rendered by the one tracer with its reflected rays answered by the BVH,
//! each impostor or the environment, each frame beside its error map, and crops of what the SPOC
//! holds that the pinhole misses, and of what it misses itself.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, fmt_psnr};
use glam::Vec3;
use std::path::Path;
use trompe::eval::fidelity::{self, ReflectorSetup, check, viewpoint_rays};
use trompe::frame::{FrameError, Image, Rgba, io, metrics};
use trompe::geom::Mesh;
use trompe::impostor::{ImpostorCamera, SurfaceSample, ViewCamera, build};

/// The colour the section bakes into impostors: an orange Lambertian lit from one direction
/// (view-independent, so exact and impostor agree).
fn teapot_color(n: Vec3) -> Vec3 {
    let l = Vec3::new(0.3, 0.8, 0.5).normalize();
    Vec3::new(0.9, 0.45, 0.15) * (0.25 + 0.75 * n.dot(l).max(0.0))
}

/// `gd` as a false-colour image: covered texels from dark (far) to bright (near), empty black.
fn gd_false_color(gd: &Image<f32>) -> Image<Rgba> {
    let covered = gd.pixels().iter().copied().filter(|&g| g > 0.0);
    let (lo, hi) = covered.fold((f32::INFINITY, 0.0f32), |(lo, hi), g| {
        (lo.min(g), hi.max(g))
    });
    let span = (hi - lo).max(f32::MIN_POSITIVE);
    metrics::heat_map(&gd.map(|g| {
        if g > 0.0 {
            0.15 + 0.85 * (g - lo) / span
        } else {
            0.0
        }
    }))
}

pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    let teapot = trompe::geom::io::load(&inputs.assets.join("meshes/teapot.obj"))?.mesh;
    let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let camera_error = |e: trompe::camera::CameraError| {
        ReportError::Frame(FrameError::Codec {
            path: inputs.assets.clone(),
            reason: e.to_string(),
        })
    };
    let mut s = Section::new("impostors", "Non-pinhole impostors (paper 1)");
    s.paragraph("The Utah teapot (largest extent 1) is replaced by a 512² depth image built from the centre of a reflective bunny beside it: a pinhole depth image, and a single-pole occlusion camera (SPOC, `docs/conventions.md` §3) whose strength k = 2Δ/z_O comes from the reflector's size Δ and distance z_O. The SPOC pushes deeper samples away from the pole, so it sees around the silhouette.");
    let color = |s: &SurfaceSample| teapot_color(s.normal);
    let setup = ReflectorSetup::new(&teapot, &bunny, 1.4, 1024).map_err(camera_error)?;
    let exact = trompe::trace::Bvh::build(vec![setup.target.clone()])?;
    let rays = setup.rays()?;
    let mut figures = Vec::new();
    let mut table = Table::new([
        "camera",
        "k",
        "rays",
        "exact hits",
        "agreement",
        "agreement on hits",
        "missed (by the walk)",
        "spurious",
        "error, mean / median (texel footprints)",
        "surface captured (1.5 footprints / 1.5 texel extents)",
        "texel visits / ray",
    ]);
    for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
        let cam = setup.camera(kind, 512).map_err(camera_error)?;
        let k = match &cam {
            ImpostorCamera::Spoc(s) => format!("{:.3}", s.strength()),
            _ => "—".into(),
        };
        let imp = build(cam, &setup.target, 0, &color)?;
        let name = imp.camera().kind();
        let (c, g) = (
            format!("impostor-{name}-color.png"),
            format!("impostor-{name}-gd.png"),
        );
        io::write_png(&out.join(&c), &imp.color_image())?;
        io::write_png(&out.join(&g), &gd_false_color(imp.gd()))?;
        figures.push(Figure::new(c, format!("{name}: colour")));
        figures.push(Figure::new(g, format!("{name}: gd (bright = near)")));
        let r = fidelity::check(&imp, &exact, &rays);
        let captured = fidelity::surface_captured(&imp, &setup.target, 50_000, 1);
        table.row([
            name.to_string(),
            k,
            r.rays.to_string(),
            r.exact_hits.to_string(),
            format!("{:.2} %", r.agreement() * 100.0),
            format!("{:.2} %", r.hit_agreement() * 100.0),
            format!("{} ({})", r.missed, r.missed - r.missed_unheld),
            r.spurious.to_string(),
            format!(
                "{:.2} / {:.1e}",
                r.mean_error_footprints, r.median_error_footprints
            ),
            format!(
                "{:.1} % / {:.1} %",
                captured.within_footprint * 100.0,
                captured.within_texel * 100.0
            ),
            format!("{:.1}", r.texel_visits_per_ray),
        ]);
    }
    s.figures(figures);
    s.heading(
        "Fidelity against the exact BVH (reflected rays of the bunny that enter the teapot's box)",
    );
    s.table(table);
    s.paragraph("A ray agrees when both miss, or both hit within 1.5 texel footprints; trompe's goal is SPOC ≥ 99 %. A missed ray is the walk's (in brackets) when the impostor holds the exact hit — its texel stores a point within 1.5 footprints of it — and the camera's otherwise. The paper reports that its SPOC captures “about half of the teapot”; the surface captured is measured two ways: a surface sample counts when its texel stores a point within 1.5 footprints of it, or within 1.5 times the texel's extent on that surface. From one viewpoint a convex object shows at most half of its surface.");

    s.heading("Agreement against reflector distance");
    let mut by_distance = Table::new([
        "bunny–teapot centre distance",
        "rays",
        "pinhole agreement",
        "SPOC agreement",
    ]);
    for distance in [1.1f32, 1.4, 1.8] {
        let st = ReflectorSetup::new(&teapot, &bunny, distance, 1024).map_err(camera_error)?;
        let exact = trompe::trace::Bvh::build(vec![st.target.clone()])?;
        let rays = st.rays()?;
        let mut cells = Vec::new();
        for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
            let cam = st.camera(kind, 512).map_err(camera_error)?;
            let imp = build(cam, &st.target, 0, &color)?;
            cells.push(fidelity::check(&imp, &exact, &rays).agreement());
        }
        by_distance.row([
            distance.to_string(),
            rays.len().to_string(),
            format!("{:.2} %", cells[0] * 100.0),
            format!("{:.2} %", cells[1] * 100.0),
        ]);
    }
    s.table(by_distance);

    viewpoint_table(&mut s, &teapot, &color)?;
    layers_table(&mut s, inputs)?;
    mirror_frames(&mut s, inputs, out, &teapot, &bunny)?;
    Ok(s)
}

/// Five models, each beside a mirror sphere (`trompe impostor check MESH --layers auto --view
/// 512`): the pinhole depth image, the SPOC with 1, 2 and 4 layers and the automatic count.
fn layers_table(s: &mut Section, inputs: &DemoInputs) -> Result<(), ReportError> {
    use trompe::eval::check::{CheckSettings, check_built};
    s.heading("Depth layers: what one layer hides");
    s.paragraph("One depth image holds only what its camera sees first; a reflected ray that passes behind an occluding edge meets surface it does not hold. A layered impostor peels the surfaces behind, facing the camera, through the same camera (`docs/conventions.md` §2.5), and the walk takes the nearest crossing of any layer. Each model stands beside a mirror sphere whose reflected rays (a 512² view) are fired at its 512² impostor, as `trompe impostor check MESH --layers auto --view 512` does. Missed rays are split as above: surface the impostor does not hold / the walk's.");
    let mut t = Table::new([
        "model",
        "rays",
        "pinhole",
        "SPOC, 1 layer",
        "2 layers",
        "4 layers",
        "auto",
        "missed (1 → auto)",
        "maps (1 → auto)",
    ]);
    for model in [
        "meshes/teapot.obj",
        "meshes/bunny.obj",
        "meshes/dragon_res4.obj",
        "gltf/Suzanne.glb",
        "gltf/Duck.glb",
    ] {
        let path = inputs.assets.join(model);
        let failed = |reason: String| {
            ReportError::Frame(FrameError::Codec {
                path: path.clone(),
                reason,
            })
        };
        let (subject, _) =
            trompe::impostor::Subject::load(&path).map_err(|e| failed(e.to_string()))?;
        let settings = CheckSettings {
            layers: trompe::impostor::Layers::Auto,
            view: 512,
            ..CheckSettings::default()
        };
        let report = check_built(&subject, &settings).map_err(|e| failed(e.to_string()))?;
        let rows = &report.layers_beside;
        let (Some(one), Some(auto)) = (rows.first(), rows.last()) else {
            return Err(failed("no layer rows".into()));
        };
        let pct =
            |r: &trompe::eval::fidelity::FidelityReport| format!("{:.2} %", r.agreement() * 100.0);
        let missed = |r: &trompe::eval::fidelity::FidelityReport| {
            format!(
                "{} ({} / {})",
                r.missed,
                r.missed_unheld,
                r.missed - r.missed_unheld
            )
        };
        t.row([
            model.rsplit('/').next().unwrap_or(model).to_string(),
            one.fidelity.rays.to_string(),
            report
                .pinhole_beside
                .as_ref()
                .map_or("—".into(), |(r, _)| pct(r)),
            pct(&one.fidelity),
            rows.get(1).map_or("—".into(), |r| pct(&r.fidelity)),
            rows.get(2).map_or("—".into(), |r| pct(&r.fidelity)),
            format!("{} ({} layers)", pct(&auto.fidelity), auto.layers),
            format!("{} → {}", missed(&one.fidelity), missed(&auto.fidelity)),
            format!(
                "{:.1} → {:.1} MB",
                one.map_bytes as f64 / 1e6,
                auto.map_bytes as f64 / 1e6
            ),
        ]);
    }
    s.table(t);
    Ok(())
}

/// The teapot in its own coordinates, baked as `trompe impostor bake` does by default (3 radii
/// away along (0, 0.3, 1)) through a pinhole and a SPOC, checked on 20 000 rays from the sphere
/// of 1/4, 1/2 and 1 bounding radius around the viewpoint (`trompe impostor check --impostor`).
fn viewpoint_table<F>(s: &mut Section, teapot: &Mesh, color: &F) -> Result<(), ReportError>
where
    F: Fn(&SurfaceSample) -> Vec3 + Sync,
{
    let from = Vec3::new(0.0, 0.3, 1.0);
    let mut impostors = Vec::new();
    for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
        let camera = ImpostorCamera::facing_mesh(kind, teapot, from, 3.0, 512).map_err(|e| {
            ReportError::Frame(FrameError::Codec {
                path: "teapot".into(),
                reason: e.to_string(),
            })
        })?;
        impostors.push(build(camera, teapot, 0, color)?);
    }
    let exact = trompe::trace::Bvh::build(vec![std::sync::Arc::new(teapot.clone())])?;
    let b = teapot.bounds();
    s.heading("A baked impostor on rays from around its viewpoint");
    s.paragraph("The teapot baked as `trompe impostor bake` does by default — 3 bounding radii away, the SPOC's strength chosen for rays from within one radius of its viewpoint — then checked as `trompe impostor check MESH --impostor FILE` does: 20 000 rays from points on a sphere around the viewpoint, aimed at points of the teapot's box.");
    let mut t = Table::new([
        "sphere radius (bounding radii)",
        "rays",
        "exact hits",
        "pinhole: agreement, missed, spurious",
        "SPOC: agreement, missed (by the walk), spurious",
    ]);
    for region in [0.25f32, 0.5, 1.0] {
        let rays = viewpoint_rays(&impostors[1], region * b.radius(), b, 20_000, 1);
        let [p, q] = [&impostors[0], &impostors[1]].map(|imp| check(imp, &exact, &rays));
        t.row([
            region.to_string(),
            q.rays.to_string(),
            q.exact_hits.to_string(),
            format!(
                "{:.2} %, {}, {}",
                p.agreement() * 100.0,
                p.missed,
                p.spurious
            ),
            format!(
                "{:.2} %, {} ({}), {}",
                q.agreement() * 100.0,
                q.missed,
                q.missed - q.missed_unheld,
                q.spurious
            ),
        ]);
    }
    s.table(t);
    Ok(())
}

/// The mirror view (paper 1 Fig. 1): one renderer, reflected rays answered four ways; each frame
/// beside its error map; crops of where the SPOC and the pinhole differ most.
fn mirror_frames(
    s: &mut Section,
    inputs: &DemoInputs,
    out: &Path,
    teapot: &Mesh,
    bunny: &Mesh,
) -> Result<(), ReportError> {
    use trompe::scene::{DiffuseOverride, Light, Lighting, RenderSettings, Surface, View};
    let camera_error = |e: trompe::camera::CameraError| {
        ReportError::Frame(FrameError::Codec {
            path: inputs.assets.clone(),
            reason: e.to_string(),
        })
    };
    let setup = ReflectorSetup::new(teapot, bunny, 1.4, 400).map_err(camera_error)?;
    let env =
        trompe::frame::envmap::EnvMap::load(&inputs.assets.join("envmaps/studio.hdr"), 0.0, 0.6)?;
    let lighting = Lighting {
        environment: env,
        light: Some(Light {
            direction: Vec3::new(0.3, 0.8, 0.5).normalize(),
            irradiance: Vec3::splat(0.75 * std::f32::consts::PI),
        }),
    };
    let albedo = Vec3::new(0.9, 0.45, 0.15);
    let orange = Surface::Diffuse(Some(DiffuseOverride {
        color: albedo,
        texture: None,
    }));
    let view = View {
        lens: None,
        camera: setup.view.clone(),
        meshes: vec![setup.target.clone(), setup.reflector.clone()],
        surfaces: vec![orange, Surface::Mirror { tint: Vec3::ONE }],
    };
    let settings = RenderSettings {
        max_depth: 4,
        time: 0.0,
        ray_epsilon: 1e-4,
    };
    let primary = trompe::trace::Bvh::build(view.meshes.clone())?;
    let render_with = |secondary: &dyn trompe::trace::SecondaryQuery| {
        let tracer = trompe::render::Tracer {
            view: &view,
            primary: &primary,
            secondary,
            lighting: &lighting,
            settings: &settings,
        };
        trompe::render::render_trace(&tracer, &())
    };
    let exact_frame = render_with(&trompe::trace::Exact(&primary))?;
    let reference = exact_frame.color.clone();
    let mask = exact_frame.object_id.map(|id| id == 1);
    io::write_png(&out.join("mirror-exact.png"), &reference)?;
    // The tracer's diffuse shading baked into each impostor, as `render --method impostor` does.
    let eye = setup.reflector.bounds().center();
    let shaded = |p: &SurfaceSample| {
        let n = if p.normal.dot(eye - p.position) < 0.0 {
            -p.normal
        } else {
            p.normal
        };
        trompe::render::shading::lambert(albedo, n, &lighting, |l| {
            trompe::render::shading::lit(&primary, p.position, n, l, settings.ray_epsilon)
        })
    };
    let mut answers = Vec::new();
    for kind in [ViewCamera::Spoc(None), ViewCamera::Pinhole] {
        let cam = setup.camera(kind, 512).map_err(camera_error)?;
        let imp = build(cam, &setup.target, 0, &shaded)?;
        answers.push(trompe::render::ReflectorImpostors::from_impostors(
            &view,
            vec![Vec::new(), vec![imp]],
        )?);
    }
    s.heading("The bunny as a mirror (paper 1, Fig. 1)");
    s.paragraph("One tracer renders every frame: primary rays see the exact scene, and only what answers the rays the bunny reflects changes — the exact BVH, the SPOC impostor, the pinhole impostor, or the environment alone. Scores compare each frame with the exact one over the bunny's pixels.");
    let mut figures = vec![Figure::new(
        "mirror-exact.png",
        "reflected rays traced in the exact BVH",
    )];
    let mut scores = Table::new(["reflected rays answered by", "PSNR (dB)", "SSIM", "FLIP"]);
    let mut images = Vec::new();
    for (i, label) in ["SPOC impostor", "pinhole impostor", "environment map only"]
        .into_iter()
        .enumerate()
    {
        let frame = match answers.get(i) {
            Some(a) => render_with(a)?,
            None => render_with(&trompe::trace::EnvironmentOnly)?,
        };
        let img = frame.color;
        let (file, heat) = (format!("mirror-{i}.png"), format!("mirror-{i}-flip.png"));
        io::write_png(&out.join(&file), &img)?;
        let flip = metrics::flip_map(&reference, &img)?;
        io::write_png(&out.join(&heat), &metrics::heat_map(&flip))?;
        let sc = metrics::compare(&reference, &img, Some(&mask))?;
        figures.push(Figure::new(file, label));
        figures.push(Figure::heat_map(heat, format!("FLIP error, {label}")));
        scores.row([
            label.to_string(),
            fmt_psnr(sc.psnr),
            format!("{:.4}", sc.ssim),
            format!("{:.4}", sc.flip),
        ]);
        images.push((img, flip));
    }
    s.figures(figures);
    s.table(scores);

    // Crops: where the pinhole errs and the SPOC does not (what the SPOC holds that the
    // pinhole misses), and where the SPOC errs most (what it misses).
    let (spoc_err, pin_err) = (&images[0].1, &images[1].1);
    let on_mirror = |f: &dyn Fn(u32, u32) -> f32| -> Result<Image<f32>, FrameError> {
        let (w, h) = mask.size();
        let mut img = Image::new(w, h, 0.0f32)?;
        for y in 0..h {
            for x in 0..w {
                if mask.get(x, y) {
                    img.set(x, y, f(x, y));
                }
            }
        }
        Ok(img)
    };
    let gain = on_mirror(&|x, y| pin_err.get(x, y) - spoc_err.get(x, y))?;
    let loss = on_mirror(&|x, y| spoc_err.get(x, y))?;
    let mut crops = Vec::new();
    for (what, score) in [("holds", &gain), ("misses", &loss)] {
        let (x0, y0) = busiest_window(score, CROP);
        for (name, img) in [
            ("exact", &reference),
            ("SPOC", &images[0].0),
            ("pinhole", &images[1].0),
        ] {
            let file = format!("mirror-crop-{what}-{}.png", name.to_lowercase());
            io::write_png(&out.join(&file), &crop(img, x0, y0, CROP, 4)?)?;
            crops.push(Figure::new(
                file,
                format!("{name}, {CROP}² px at ({x0}, {y0}): where the SPOC {what} most"),
            ));
        }
    }
    s.heading("Crops: what the SPOC holds that the pinhole misses, and what it misses");
    s.paragraph("Each window is the 48² pixels of the bunny where the FLIP error of the pinhole-answered frame exceeds the SPOC's the most (first row), then where the SPOC's own error is largest (second row), enlarged four times.");
    s.figures(crops[..3].to_vec());
    s.figures(crops[3..].to_vec());
    Ok(())
}

/// Side of a crop, in pixels.
const CROP: u32 = 48;

/// The top-left corner of the `size²` window (on an 8-pixel grid) with the largest sum of
/// `score`.
fn busiest_window(score: &Image<f32>, size: u32) -> (u32, u32) {
    let (w, h) = score.size();
    let mut best = (0.0f32, (0, 0));
    for y0 in (0..h.saturating_sub(size)).step_by(8) {
        for x0 in (0..w.saturating_sub(size)).step_by(8) {
            let mut sum = 0.0;
            for y in y0..y0 + size {
                for x in x0..x0 + size {
                    sum += score.get(x, y);
                }
            }
            if sum > best.0 {
                best = (sum, (x0, y0));
            }
        }
    }
    best.1
}

/// The `size²` window of `img` at `(x0, y0)`, each pixel repeated `scale` times a side.
fn crop(
    img: &Image<Rgba>,
    x0: u32,
    y0: u32,
    size: u32,
    scale: u32,
) -> Result<Image<Rgba>, FrameError> {
    let (w, h) = img.size();
    let side = size * scale;
    let mut out = Image::new(side, side, Rgba::ZERO)?;
    for y in 0..side {
        for x in 0..side {
            let (sx, sy) = ((x0 + x / scale).min(w - 1), (y0 + y / scale).min(h - 1));
            out.set(x, y, img.get(sx, sy));
        }
    }
    Ok(out)
}
