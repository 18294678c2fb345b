//! Rasterizer throughput on the 56k-triangle bunny, beside a memcpy of the bytes it writes.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use trompe_cli::bench::{frame_bytes, framing_camera, memcpy_frame, raster_once};

fn raster(c: &mut Criterion) {
    let path = trompe_cli::bench::repo_root().join("assets/meshes/bunny.obj");
    let mesh = trompe::geom::io::load(&path).expect("shipped bunny").mesh;
    let mut group = c.benchmark_group("raster");
    for size in [512u32, 1024] {
        let cam = framing_camera(&mesh, size);
        group.throughput(Throughput::Elements(mesh.triangle_count() as u64));
        group.bench_function(format!("bunny {size}² (triangles)"), |b| {
            b.iter(|| raster_once(&cam, &mesh))
        });
        let bytes = frame_bytes(size);
        let (src, mut dst) = (vec![1u8; bytes], vec![0u8; bytes]);
        group.throughput(Throughput::Bytes(bytes as u64));
        group.bench_function(
            format!("peer: memcpy of the {size}² depth + item buffers"),
            |b| b.iter(|| memcpy_frame(&src, &mut dst)),
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = raster
}
criterion_main!(benches);
