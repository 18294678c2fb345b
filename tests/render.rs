//! The two ground-truth renderers: agreement on diffuse scenes, determinism across thread counts.

mod common;
use std::path::PathBuf;
use trompe::frame::metrics;
use trompe::render::{Method, render};
use trompe::scene::Scene;

fn scene(name: &str) -> Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    Scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn raster_and_trace_agree_on_the_diffuse_scene() {
    let s = scene("diffuse.toml");
    let (raster, _) = render(&s, Method::Raster, &()).unwrap();
    let (trace, _) = render(&s, Method::Trace, &()).unwrap();
    let scores = metrics::compare(&trace.color, &raster.color, None).unwrap();
    assert!(scores.psnr >= 45.0, "{scores:?}");
    assert!(scores.flip <= 0.002, "{scores:?}");
    let same = raster
        .object_id
        .pixels()
        .iter()
        .zip(trace.object_id.pixels())
        .filter(|(a, b)| a == b)
        .count();
    let frac = same as f64 / trace.object_id.pixels().len() as f64;
    assert!(frac >= 0.995, "object ids agree on {frac}");
    // Depth agrees wherever both see the same object.
    for ((a, b), (ia, ib)) in raster.depth.pixels().iter().zip(trace.depth.pixels()).zip(
        raster
            .object_id
            .pixels()
            .iter()
            .zip(trace.object_id.pixels()),
    ) {
        if ia == ib && b.is_finite() {
            assert!((a - b).abs() <= 1e-3 * b, "{a} vs {b}");
        }
    }
}

#[test]
fn mirrors_differ_between_methods() {
    // The raster method only looks mirrors up in the panorama: on the reflection scene it must
    // not match the traced image (a renderer that ignored the method would).
    let s = scene("reflections.toml");
    let (raster, _) = render(&s, Method::Raster, &()).unwrap();
    let (trace, _) = render(&s, Method::Trace, &()).unwrap();
    let scores = metrics::compare(&trace.color, &raster.color, None).unwrap();
    assert!(scores.psnr < 35.0, "{scores:?}");
}

#[test]
fn same_pixels_for_one_and_two_threads() {
    for name in ["diffuse.toml", "reflections.toml"] {
        let s = scene(name);
        for method in [Method::Raster, Method::Trace] {
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| render(&s, method, &()).unwrap().0)
            };
            let (one, two) = (run(1), run(2));
            assert!(one.color == two.color, "{name} {method}: colour differs");
            assert!(
                one.depth == two.depth && one.object_id == two.object_id,
                "{name} {method}"
            );
        }
    }
}
