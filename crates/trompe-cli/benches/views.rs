//! Calibrated views: reading a 1 000-view COLMAP text model, and the per-view depth maps of 100
//! views of 720 × 576 of a 102k-triangle mesh — beside the exact BVH casting the same views'
//! primary rays (one view, the peer measured in the same run).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use std::sync::Arc;
use trompe::views::capture::{CaptureSettings, Rig, rig_centres};
use trompe::views::visibility::DepthMap;
use trompe::views::{CalibratedView, Intrinsics, Pose, ViewSet, colmap};

fn rig(count: usize, size: (u32, u32), radius: f64) -> Vec<CalibratedView> {
    let settings = CaptureSettings {
        rig: Rig::Sphere,
        count,
        size,
        ..Default::default()
    };
    let f = size.1 as f64 * 0.5 / (20f64.to_radians()).tan();
    let intrinsics = Intrinsics::pinhole(
        size.0,
        size.1,
        f,
        f,
        size.0 as f64 / 2.0,
        size.1 as f64 / 2.0,
    );
    rig_centres(&settings, DVec3::ZERO, radius)
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            let up = if c.normalize().y.abs() > 0.999 {
                DVec3::Z
            } else {
                DVec3::Y
            };
            CalibratedView {
                name: format!("view{i:04}.png"),
                image_id: i as u32 + 1,
                camera_id: 1,
                intrinsics: intrinsics.clone(),
                pose: Pose::looking_at(c, DVec3::ZERO, up).expect("a pose"),
                image: None,
            }
        })
        .collect()
}

fn views(c: &mut Criterion) {
    let mut group = c.benchmark_group("views");
    let dir = trompe_cli::bench::repo_root().join("target/bench-views");
    std::fs::create_dir_all(&dir).expect("a folder under target/");
    colmap::write_text(&dir, &rig(1000, (720, 576), 1.0)).expect("the model is written");
    group.bench_function("read a 1000-view COLMAP text model", |b| {
        b.iter(|| ViewSet::load(&dir, None).expect("it reads"))
    });

    let mut mesh = trompe::geom::icosphere(6);
    mesh.append(&trompe::geom::icosphere(5));
    let views = rig(100, (720, 576), 3.0);
    group.throughput(Throughput::Elements(100));
    group.bench_function(
        format!(
            "depth maps of 100 views of 720 × 576, {} triangles",
            mesh.triangle_count()
        ),
        |b| b.iter(|| DepthMap::of_all(&views, &mesh).expect("maps")),
    );
    let bvh = trompe::Bvh::build(vec![Arc::new(mesh.clone())]).expect("bvh");
    let camera = views[0].pinhole();
    let rays = trompe_cli::bench::primary_rays(&camera);
    group.throughput(Throughput::Elements(1));
    group.bench_function("peer: exact BVH, one view's primary rays", |b| {
        b.iter(|| trompe_cli::bench::trace_all(&bvh, &rays))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = views
}
criterion_main!(benches);
