//! Hybrid reflections (paper 2): one frame of the shipped mirror teapot reflecting the bunny —
//! with the level of detail and with the paper's algorithm — beside the same frame ray traced
//! exactly through the BVH.

use criterion::{Criterion, criterion_group, criterion_main};
use trompe::hybrid::{HybridReflections, HybridSettings};
use trompe::render::{Method, render_at};

fn hybrid(c: &mut Criterion) {
    let root = trompe_cli::bench::repo_root();
    let scene = trompe::Scene::load(&root.join("scenes/c3rc-bunny.toml")).expect("scene");
    let clouds = HybridReflections::prepare(&scene, HybridSettings::default()).expect("points");
    let paper = HybridReflections::prepare(
        &scene,
        HybridSettings {
            level_of_detail: false,
            mirrors_occlude: false,
            ..HybridSettings::default()
        },
    )
    .expect("points");
    let mut g = c.benchmark_group("teapot reflecting the bunny, 480 × 320");
    g.sample_size(10);
    g.bench_function("hybrid frame (C3RC splatting)", |b| {
        b.iter(|| clouds.render_at(&scene, 0.0, &()))
    });
    g.bench_function("hybrid frame, paper's algorithm", |b| {
        b.iter(|| paper.render_at(&scene, 0.0, &()))
    });
    g.bench_function("peer: exact frame (BVH)", |b| {
        b.iter(|| render_at(&scene, 0.0, Method::Trace, &()))
    });
    g.finish();
}

criterion_group!(benches, hybrid);
criterion_main!(benches);
