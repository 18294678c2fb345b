//! The memory budget: every allocation sized by input is refused past the limit, before it is
//! made. One test in this binary, because the limit is process-wide.

#[path = "integration/common/mod.rs"]
mod common;
use std::path::Path;
use trompe::memory::{self, OverBudget};

/// The process's peak resident memory so far (Linux), in bytes.
fn peak_resident() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[test]
fn input_sized_allocations_are_refused_past_the_budget_before_they_are_made() {
    let d = common::scratch("memory_budget");
    // Inputs are made before the budget is lowered.
    // 40 levels: a few kilobytes that instance one triangle 2⁴⁰ times.
    let dag = common::instanced_triangle(&d, "dag.gltf", 40);
    // A 4096² grey PNG (a few kilobytes compressed; 448 MiB decoded), as an OBJ's texture.
    let big = d.join("big.png");
    image::GrayImage::new(4096, 4096).save(&big).unwrap();
    std::fs::write(d.join("m.mtl"), "newmtl a\nmap_Kd big.png\n").unwrap();
    let obj = d.join("textured.obj");
    std::fs::write(
        &obj,
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    // Sixteen 1024² textures of one OBJ (28 MiB each while decoded, 16 MiB held): each fits
    // the budget below, their sum does not.
    let mut mtl = String::new();
    let mut faces =
        String::from("mtllib many.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n");
    for i in 0..16 {
        image::GrayImage::new(1024, 1024)
            .save(d.join(format!("t{i}.png")))
            .unwrap();
        mtl += &format!("newmtl m{i}\nmap_Kd t{i}.png\n");
        faces += &format!("usemtl m{i}\nf 1/1 2/2 3/3\n");
    }
    std::fs::write(d.join("many.mtl"), mtl).unwrap();
    let many = d.join("many.obj");
    std::fs::write(&many, faces).unwrap();
    let mesh = trompe::geom::icosphere(2);
    let mut scene = trompe::Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/turntable.toml"
    )))
    .unwrap();
    scene.camera.width = 8192;
    scene.camera.height = 8192;
    // 327 680 triangles: 90 MiB while their BVH is built.
    let dense = std::sync::Arc::new(trompe::geom::icosphere(7));
    let sparse = std::sync::Arc::new(trompe::geom::icosphere(5));

    // 64 MiB on top of what the inputs made above hold (the scene's images).
    let before = peak_resident();
    let base = memory::held();
    let limit = base + (64 << 20);
    memory::set_limit(limit);
    assert_eq!(memory::limit(), limit);
    let limit_text = format!("memory limit is {}", memory::Bytes(limit));

    let over = |e: &dyn std::error::Error| {
        let text = e.to_string();
        assert!(
            text.contains(&limit_text) && text.contains("--memory-limit"),
            "{text}"
        );
        text
    };
    let e = trompe::geom::io::load(&dag).unwrap_err();
    assert!(over(&e).contains("dag.gltf"));
    assert!(matches!(e, trompe::geom::MeshError::Memory { .. }), "{e:?}");

    let e = trompe::geom::io::load(&obj).unwrap_err();
    assert!(over(&e).contains("4096 × 4096"));

    let e = trompe::geom::io::load(&many).unwrap_err();
    let text = over(&e);
    assert!(
        text.contains("t3.png") && text.contains("already held"),
        "{text}"
    );
    assert_eq!(
        memory::held(),
        base,
        "the refused load's textures are returned"
    );
    // Two images compared: each alone fits (64 MiB), the two together do not.
    let (a, b) = (d.join("t0.png"), d.join("t1.png"));
    let e = trompe::frame::metrics::budget_compare(&[&a]);
    assert!(e.is_ok(), "{e:?}");
    let e = trompe::frame::metrics::budget_compare(&[&a, &b]).unwrap_err();
    assert!(over(&e).contains("comparing") && over(&e).contains("t1.png (1024 × 1024)"));

    let e = trompe::Impostor::spoc(&mesh)
        .resolution(4096)
        .build()
        .unwrap_err();
    assert!(over(&e).contains("4096 × 4096 impostor"));

    let e = trompe::render(&scene, trompe::Method::Trace, &()).unwrap_err();
    assert!(over(&e).contains("8192 × 8192 render"));

    let e = trompe::Image::new(8192, 8192, 0u32).unwrap_err();
    let source: Option<&OverBudget> = match &e {
        trompe::frame::FrameError::Memory(b) => Some(b),
        _ => None,
    };
    assert_eq!(source.map(|b| b.needed), Some(base + (256 << 20)), "{e}");

    // A BVH is refused by its build's peak, and holds its arrays while it is alive.
    let e = trompe::Bvh::build(vec![dense.clone()]).err().unwrap();
    assert!(over(&e).contains("a BVH of 327680 triangles"), "{e}");
    let kept = trompe::Bvh::build(vec![sparse.clone()]).unwrap();
    let resident = 20_480 * trompe::trace::BVH_RESIDENT_BYTES_PER_TRIANGLE;
    assert_eq!(memory::held(), base + resident);
    drop(kept);
    assert_eq!(memory::held(), base);
    // So is the rasterizer's set-up of it (vertices seen through the camera, screen triangles).
    let camera = trompe::eval::fixtures::framing_camera(&dense, 64).unwrap();
    let e = trompe::raster::rasterize(&camera, &[&*dense], &trompe::raster::NoAttributes, ())
        .err()
        .unwrap();
    assert!(over(&e).contains("rasterizing 327680 triangles"), "{e}");
    assert_eq!(memory::held(), base);

    // What fits still runs under the same budget.
    let small = trompe::Impostor::spoc(&mesh).resolution(64).build();
    assert!(small.is_ok());

    if let (Some(before), Some(after)) = (before, peak_resident()) {
        assert!(
            after < before + (64 << 20),
            "refusals raised the peak from {before} to {after} bytes"
        );
    }
}
