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
