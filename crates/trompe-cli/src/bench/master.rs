//! Master Texture workloads (paper 5 §5: 436 polygons and 360 views of 720 × 576 in 8 minutes
//! on a 1.7 GHz Pentium 4, 8020 polygons in 26): encoding every view of a mesh, streamed (one
//! view and one master texture in memory), beside drawing the same views' depth maps alone.

use super::{BenchError, Figure};
use glam::{DVec3, Vec4};
use std::time::Instant;
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba};
use trompe::geom::Mesh;
use trompe::master::{MasterError, encode_stream};
use trompe::views::capture::{CaptureSettings, Rig, rig_centres};
use trompe::views::visibility::DepthMap;

/// `count` pinholes of `w × h` on a sphere around `mesh`, looking at its centre.
pub fn sphere_cameras(mesh: &Mesh, count: usize, (w, h): (u32, u32)) -> Vec<(String, Pinhole)> {
    let b = mesh.bounds();
    let centre = b.center().as_dvec3();
    let radius = (b.extent().length() * 0.5) as f64;
    let settings = CaptureSettings {
        rig: Rig::Sphere,
        count,
        size: (w, h),
        ..Default::default()
    };
    rig_centres(&settings, centre, radius)
        .into_iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let up = if (c - centre).normalize().y.abs() > 0.999 {
                DVec3::Z
            } else {
                DVec3::Y
            };
            let cam = Pinhole::look_at(
                c.as_vec3(),
                centre.as_vec3(),
                up.as_vec3(),
                settings.fov_y,
                w,
                h,
            )
            .ok()?;
            Some((format!("view{i:04}"), cam))
        })
        .collect()
}

/// A `w × h` image with a gradient (what the encoder reads costs the same as a photograph).
pub fn gradient(w: u32, h: u32) -> Result<Image<Rgba>, trompe::frame::FrameError> {
    let mut img = Image::new(w, h, Vec4::ONE)?;
    for y in 0..h {
        for x in 0..w {
            img.set(
                x,
                y,
                Vec4::new(x as f32 / w as f32, y as f32 / h as f32, 0.5, 1.0),
            );
        }
    }
    Ok(img)
}

/// The master figures: 360 views of 720 × 576 of the teapot (992 faces) and the Duck (4212).
pub fn master(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let views = if quick { 36 } else { 360 };
    let size = (720, 576);
    let image = gradient(size.0, size.1)?;
    let mut out = Vec::new();
    for (file, name) in [("meshes/teapot.obj", "teapot"), ("gltf/Duck.glb", "Duck")] {
        let mesh = trompe::geom::io::load(&inputs.assets.join(file))?.mesh;
        let cameras = sphere_cameras(&mesh, views, size);
        let t = Instant::now();
        let mut texels = 0usize;
        let (atlas, _) = encode_stream(
            &mesh,
            &cameras,
            1.0,
            &mut |_| Ok::<_, MasterError>(image.clone()),
            &mut |_, m| {
                texels += m.pixels().iter().filter(|c| c.w > 0.0).count();
                Ok(())
            },
            &(),
        )?;
        let encode = t.elapsed();
        let t = Instant::now();
        for (_, cam) in &cameras {
            std::hint::black_box(DepthMap::through(cam, &mesh)?);
        }
        let depth = t.elapsed();
        let (aw, ah) = atlas.size();
        out.push(
            Figure::millis(
                format!(
                    "master encode, {name} ({} faces), {views} views 720×576, atlas {aw}×{ah}",
                    mesh.triangle_count()
                ),
                encode,
            )
            .versus((encode, depth), "× drawing the views' depth maps alone"),
        );
        std::hint::black_box(texels);
    }
    Ok(out)
}

/// Paper 5 §4's rendering path on each device: the teapot's masters of `views` sphere views of
/// 720 × 576, rendered through a new camera at 1920 × 1080 (640 × 360 when `quick`) — on the
/// GPU from one texture array (the masters uploaded once), beside the library's CPU render of
/// the same masters, ULR and best face.
pub fn gpu_renders(
    gpu: &trompe_gpu::Gpu,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    use trompe::texturing::{BlendSettings, Weighting};
    let views = if quick { 36 } else { 360 };
    let (w, h) = if quick { (640, 360) } else { (1920, 1080) };
    let mesh = trompe::geom::io::load(&inputs.assets.join("meshes/teapot.obj"))?.mesh;
    let cameras = sphere_cameras(&mesh, views, (720, 576));
    let image = gradient(720, 576)?;
    let mut masters = Vec::with_capacity(views);
    let (atlas, _) = encode_stream(
        &mesh,
        &cameras,
        1.0,
        &mut |_| Ok::<_, MasterError>(image.clone()),
        &mut |_, m| {
            masters.push(m.clone());
            Ok(())
        },
        &(),
    )?;
    let pinholes: Vec<Pinhole> = cameras.into_iter().map(|(_, c)| c).collect();
    // Between the first two views, a little nearer.
    let b = mesh.bounds();
    let (p0, p1) = (pinholes[0].position(), pinholes[1].position());
    let centre = b.center().as_dvec3();
    let eye = centre + ((p0 + p1) * 0.5 - centre) * 0.9;
    let camera = Pinhole::look_at(eye.as_vec3(), b.center(), glam::Vec3::Y, 40.0, w, h)?;
    let (aw, ah) = atlas.size();
    let mut out = Vec::new();
    for weighting in [Weighting::Ulr { beta: 0.1 }, Weighting::BestFace] {
        let settings = BlendSettings {
            weighting,
            ..BlendSettings::default()
        };
        let layout = &atlas.layout;
        let t = Instant::now();
        let cpu =
            trompe::master::render::render(&camera, &mesh, layout, &pinholes, &masters, &settings)?;
        let cpu_time = t.elapsed();
        let uploaded = trompe_gpu::master::GpuMasters::new(
            gpu,
            &mesh,
            (layout, &pinholes, &masters),
            &settings,
        )?;
        // The first frame compiles the pipeline; then the mean of a few.
        uploaded.render(&camera)?;
        const FRAMES: u32 = 3;
        let t = Instant::now();
        for _ in 0..FRAMES {
            std::hint::black_box(uploaded.render(&camera)?);
        }
        let gpu_time = t.elapsed() / FRAMES;
        std::hint::black_box(cpu);
        out.push(
            Figure::millis(
                format!(
                    "master render, {}, teapot ({} faces), {views} masters {aw}×{ah}, {w}×{h}: \
                     GPU frame (with read-back)",
                    weighting.name(),
                    mesh.triangle_count()
                ),
                gpu_time,
            )
            .versus((gpu_time, cpu_time), "CPU"),
        );
    }
    Ok(out)
}
