//! Relief impostors (paper 3 §5–6): the pre-warp of a 256² impostor of the bunny on one core —
//! by lookup tables and direct — beside a copy of its texel buffers, and ray-traced impostor
//! generation of the ~1000-triangle teapot beside rasterizing its image.

use criterion::{Criterion, criterion_group, criterion_main};
use trompe::relief::prewarp::{Eye, prewarp};
use trompe::relief::{DepthEncoding, SoftwareShader};
use trompe_cli::bench::relief::{SIDE, copy_texels, lone_shader, turned_eye};

fn relief(c: &mut Criterion) {
    let root = trompe_cli::bench::repo_root();
    let scene = trompe::Scene::load(&root.join("scenes/relief-walk.toml")).expect("scene");
    let view = scene.view(0.0).expect("view");
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render).expect("shader");
    let eye = scene.camera.position.as_dvec3();
    let imp = shader
        .impostor(0, eye, SIDE, DepthEncoding::U8, &|| false)
        .expect("impostor")
        .expect("not cancelled");
    let target = turned_eye(&imp);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut g = c.benchmark_group("relief pre-warp 256², 1 core");
    g.bench_function("lookup tables", |b| {
        one.install(|| b.iter(|| prewarp(&imp, Eye::Point(target), true)))
    });
    g.bench_function("direct", |b| {
        one.install(|| b.iter(|| prewarp(&imp, Eye::Point(target), false)))
    });
    let mut copy = (imp.color.clone(), vec![0u8; imp.color.len()]);
    g.bench_function("peer: copy of its texel buffers", |b| {
        b.iter(|| copy_texels(&imp, &mut copy))
    });
    g.finish();

    let teapot = trompe::geom::io::load(&root.join("assets/meshes/teapot.obj"))
        .expect("teapot")
        .mesh;
    let lone = lone_shader(&teapot).expect("shader");
    let (centre, radius) = lone.bounds(0).expect("bounds");
    let from = centre + trompe::glam::DVec3::new(0.3, 0.4, 1.0).normalize() * radius * 4.0;
    let camera = trompe_cli::bench::framing_camera(&teapot, SIDE);
    let raster = trompe_cli::bench::raster_view(&camera, &teapot);
    let mut g = c.benchmark_group("relief impostor 256², teapot, 1 thread");
    g.sample_size(20);
    g.bench_function("ray traced by the software shader", |b| {
        one.install(|| b.iter(|| lone.impostor(0, from, SIDE, DepthEncoding::U8, &|| false)))
    });
    g.bench_function("peer: rasterizing its image", |b| {
        one.install(|| b.iter(|| trompe_cli::bench::render_raster_once(&raster)))
    });
    g.finish();
}

criterion_group!(benches, relief);
criterion_main!(benches);
