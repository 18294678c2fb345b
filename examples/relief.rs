//! Relief impostors: the software shader makes an impostor of a scene's object, it is pre-warped
//! for an eye 10° away and drawn with depth, scored against the true render from that eye — then
//! a short walk through the two-thread pipeline.
//!
//! ```sh
//! cargo run --release --example relief -- [SCENE]
//! ```
//! With no argument, the shipped `scenes/relief-walk.toml`.

use std::error::Error;
use std::path::PathBuf;
use trompe::frame::metrics::psnr;
use trompe::glam::DQuat;
use trompe::relief::prewarp::{Eye, prewarp};
use trompe::relief::texture::draw;
use trompe::relief::{DepthEncoding, PipelineSettings, SoftwareShader, WalkSettings, walk};
use trompe::{Frame, Pinhole, Scene};

fn main() -> Result<(), Box<dyn Error>> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/relief-walk.toml")
        });
    let scene = Scene::load(&path)?;
    let view = scene.view(scene.render.time)?;
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render)?;

    // An impostor of object 0 for the scene's camera, 256² texels, eight-bit depth.
    let eye = scene.camera.position.as_dvec3();
    let impostor = shader
        .impostor(0, eye, 256, DepthEncoding::U8, &|| false)?
        .ok_or("cancelled")?;
    println!(
        "impostor of object 0: {} of {} texels covered, {} KB",
        impostor.covered_count(),
        impostor.color.len(),
        impostor.bytes() / 1024
    );

    // Seen from 10° round the object: pre-warp, texture-map, compare with the true render.
    let centre = impostor.frame.centre();
    let moved = centre + DQuat::from_rotation_y(10f64.to_radians()) * (eye - centre);
    let spec = &scene.camera;
    let camera = Pinhole::look_at(
        moved.as_vec3(),
        spec.look_at,
        spec.up,
        spec.fov_y,
        spec.width,
        spec.height,
    )?;
    let warped = prewarp(&impostor, Eye::Point(moved), true).ok_or("eye behind the impostor")?;
    let truth = shader.render(&camera, &[0])?;
    let mut frame = Frame::new(spec.width, spec.height)?;
    // The same background as the truth where object 0 is absent.
    for (i, c) in frame.color.pixels_mut().iter_mut().enumerate() {
        if truth.object_id.pixels()[i] != 0 {
            *c = truth.color.pixels()[i];
        }
    }
    let drawn = draw(&warped, &impostor.frame, &camera, &mut frame, 0);
    println!(
        "10° away: {:.1} % of texels interpolated, {drawn} pixels drawn, {:.2} dB against the true render",
        warped.interpolated_ratio() * 100.0,
        psnr(&truth.color, &frame.color, None)?
    );

    // A short walk: the rendering thread regenerates impostors as they go stale.
    let settings = WalkSettings {
        frames: 36,
        pipeline: PipelineSettings {
            resolution: 128,
            deterministic: Some(2),
            ..Default::default()
        },
        objects: Vec::new(),
        score: true,
    };
    let report = walk(&scene, &settings, &(), &mut |_, _, _| Ok(()))?;
    println!("{report}");
    Ok(())
}
