//! Every method of the library's one list (`trompe::methods`) on one scene, through the one
//! interface every command uses: the first frame (what a method prepares, made then) and the
//! mean of the frames after it (what it keeps, reused), each beside the `trace` method measured
//! in the same run. The scene is paper 1's Fig. 2 (`scenes/intersecting.toml`: a mirror ball
//! moving through a teapot), so the impostor methods keep their impostors across rigid motion.

use super::{BenchError, Figure};
use std::time::{Duration, Instant};
use trompe::methods::{MethodKind, MethodSettings, Renderer};
use trompe::scene::Scene;

/// Frames after the first that each method renders.
const FRAMES: u32 = 8;

/// The first frame and the mean of the next frames of `kind`, 1/30 s apart.
fn time_method(scene: &Scene, kind: MethodKind) -> Result<(Duration, Duration), BenchError> {
    let mut renderer = Renderer::new(scene, kind, MethodSettings::default())?;
    let t0 = scene.render.time;
    let start = Instant::now();
    renderer.frame(t0, None, &())?;
    let first = start.elapsed();
    let start = Instant::now();
    for i in 1..=FRAMES {
        renderer.frame(t0 + i as f32 / 30.0, None, &())?;
    }
    Ok((first, start.elapsed() / FRAMES))
}

/// The figures (see the module's text); `quick` renders at a quarter of the pixels.
pub fn methods(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let path = inputs.scenes.join("intersecting.toml");
    let mut scene = Scene::load(&path).map_err(Box::new)?;
    if quick {
        scene.camera.width /= 2;
        scene.camera.height /= 2;
    }
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (trace_first, trace_next) = time_method(&scene, MethodKind::Trace)?;
    let mut out = Vec::new();
    for kind in MethodKind::for_scenes() {
        let (first, next) = if kind == MethodKind::Trace {
            (trace_first, trace_next)
        } else {
            time_method(&scene, kind)?
        };
        let ratio = |t: Duration, peer: Duration| {
            Some((
                t.as_secs_f64() / peer.as_secs_f64().max(1e-12),
                "trace".to_string(),
            ))
        };
        out.push(Figure {
            name: format!("{kind}: first frame, {w} × {h} (prepares)"),
            value: first.as_secs_f64() * 1e3,
            unit: "ms",
            versus: ratio(first, trace_first),
        });
        out.push(Figure {
            name: format!("{kind}: a frame after it, mean of {FRAMES}"),
            value: next.as_secs_f64() * 1e3,
            unit: "ms",
            versus: ratio(next, trace_next),
        });
    }
    Ok(out)
}
