//! BVH build time and rays per second (primary and incoherent reflected rays) on the bunny,
//! beside brute force over every triangle on a sample of the same rays.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::sync::Arc;
use trompe::geom::Ray;
use trompe::trace::{BruteForce, Bvh};
use trompe_cli::bench::{framing_camera, primary_rays, reflected_rays, trace_all};

fn trace(c: &mut Criterion) {
    let path = trompe_cli::bench::repo_root().join("assets/meshes/bunny.obj");
    let mesh = Arc::new(trompe::geom::io::load(&path).expect("shipped bunny").mesh);
    let mut group = c.benchmark_group("trace");
    group.bench_function("BVH build, bunny", |b| {
        b.iter(|| Bvh::build(vec![mesh.clone()]))
    });
    let bvh = Bvh::build(vec![mesh.clone()]).expect("the bunny fits the budget");
    let brute = BruteForce::new(vec![mesh.clone()]);
    let primary = primary_rays(&framing_camera(&mesh, 512));
    let reflected = reflected_rays(&bvh, &primary, mesh.bounds().radius() * 1e-4);
    for (name, rays) in [("primary", &primary), ("reflected", &reflected)] {
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(format!("BVH, {name} rays"), |b| {
            b.iter(|| trace_all(&bvh, rays))
        });
        let sample: Vec<Ray> = rays.iter().step_by(rays.len() / 128).copied().collect();
        group.throughput(Throughput::Elements(sample.len() as u64));
        group.bench_function(format!("peer: brute force, {name} rays"), |b| {
            b.iter(|| trace_all(&brute, &sample))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = trace
}
criterion_main!(benches);
