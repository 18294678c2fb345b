//! Layered projective textures (paper 4): the layers of the 100k-triangle street scene from two
//! 640 × 480 views, beside drawing the same views' depth and item buffers alone; a layered frame
//! beside plain projective texturing.

use criterion::{Criterion, criterion_group, criterion_main};
use trompe::layers::{self, BuildSettings};
use trompe::raster::{NoAttributes, rasterize};
use trompe::texturing::BlendSettings;

fn layers(c: &mut Criterion) {
    let root = trompe_cli::bench::repo_root();
    let scene = trompe::Scene::load(&root.join("scenes/street-100k.toml")).expect("scene");
    let views = trompe_cli::bench::layers::ring_views(&scene, 2, (640, 480)).expect("views");
    let (meshes, names) = layers::scene_objects(&scene).expect("objects");
    let refs: Vec<&trompe::geom::Mesh> = meshes.iter().collect();
    let mut g = c.benchmark_group("street-100k, 2 views 640 × 480");
    g.sample_size(10);
    g.bench_function("visibility and image layers", |b| {
        b.iter(|| {
            layers::build(
                meshes.clone(),
                names.clone(),
                &views,
                &BuildSettings::default(),
                &(),
            )
        })
    });
    g.bench_function("peer: depth and item buffers of the views", |b| {
        b.iter(|| {
            for v in &views {
                std::hint::black_box(rasterize(&v.pinhole(), &refs, &NoAttributes, ()).ok());
            }
        })
    });
    let set = layers::build(
        meshes.clone(),
        names.clone(),
        &views,
        &BuildSettings::default(),
        &(),
    )
    .expect("layers");
    let camera = scene.camera.at(0.0).expect("camera");
    g.bench_function("layered frame", |b| {
        b.iter(|| layers::render::render(&camera, &set, &BlendSettings::default()))
    });
    g.bench_function("plain projective frame", |b| {
        b.iter(|| {
            layers::render::render_projective(&camera, &refs, &set.views, &BlendSettings::default())
        })
    });
    g.finish();
}

criterion_group!(benches, layers);
criterion_main!(benches);
