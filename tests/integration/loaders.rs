//! Loading the shared models gives the counts listed in ../shared/data/SOURCES.md.

use crate::common;
use common::shared;
use trompe::geom::io::load;

#[track_caller]
fn check(rel: &str, vertices: usize, triangles: usize) -> trompe::geom::io::LoadedMesh {
    let loaded = load(&shared(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    assert_eq!(loaded.source.vertices, vertices, "{rel}: vertices");
    assert_eq!(loaded.source.triangles, triangles, "{rel}: triangles");
    let m = &loaded.mesh;
    assert!(
        m.normals
            .iter()
            .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-4),
        "{rel}: normals"
    );
    loaded
}

#[test]
fn obj_counts_match_sources() {
    let bunny = check("meshes/bunny.obj", 28088, 56172);
    assert_eq!(bunny.mesh.triangle_count(), 56172);
    let b = bunny.mesh.bounds();
    assert!(
        (b.max.x - 0.6238).abs() < 1e-3 && (b.min.y + 0.06646).abs() < 1e-4,
        "{b:?}"
    );
    check("meshes/bunny_lowres.obj", 1839, 3674);
    check("meshes/teapot.obj", 792, 992);
    check("meshes/dragon_res4.obj", 5205, 11102);
    let tex = check("meshes/bunny10k_textured/bunny10k_textured.obj", 5051, 9999);
    assert!(tex.mesh.uvs.is_some());
    assert!(
        tex.mesh.materials.iter().any(|m| m.texture.is_some()),
        "texture from map_Kd"
    );
}

#[test]
fn gltf_counts_match_sources() {
    let duck = check("gltf/Duck.glb", 2399, 4212);
    assert!(duck.mesh.materials.iter().any(|m| m.texture.is_some()));
    // Root node scale 0.01 is applied: the bounds are those of SOURCES.md.
    let b = duck.mesh.bounds();
    assert!((b.max.y - 1.64).abs() < 1e-2, "{b:?}");
    // The truck's wheels are instanced twice: counts are per instance.
    let truck = check("gltf/CesiumMilkTruck/CesiumMilkTruck.gltf", 3564, 3624);
    assert!(truck.mesh.materials.iter().any(|m| m.texture.is_some()));
    check("gltf/BoxTextured.glb", 24, 12);
    check("gltf/Suzanne.glb", 7503, 14842);
}

#[test]
fn teapot_normals_are_smooth_across_its_duplicated_seams() {
    let t = load(&shared("meshes/teapot.obj")).unwrap().mesh;
    // Vertices at the same position get the same (welded) normal.
    let mut by_pos = std::collections::HashMap::new();
    for (p, n) in t.positions.iter().zip(&t.normals) {
        let e = by_pos.entry(p.to_array().map(f32::to_bits)).or_insert(*n);
        assert!((*e - *n).length() < 1e-6);
    }
    assert_eq!(by_pos.len(), 529);
}

#[test]
fn binary_ply_of_the_bunny_loads_like_the_obj() {
    // Write the Stanford bunny as binary little-endian PLY (its native format) and read it back.
    let obj = load(&shared("meshes/bunny.obj")).unwrap().mesh;
    let dir = common::scratch("ply_bunny");
    let path = dir.join("bunny.ply");
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by a trompe test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        obj.positions.len(),
        obj.triangles.len()
    )
    .into_bytes();
    for p in &obj.positions {
        for c in p.to_array() {
            bytes.extend(c.to_le_bytes());
        }
    }
    for t in &obj.triangles {
        bytes.push(3);
        for i in t {
            bytes.extend((*i as i32).to_le_bytes());
        }
    }
    std::fs::write(&path, bytes).unwrap();
    let ply = load(&path).unwrap();
    assert_eq!(ply.source.vertices, 28088);
    assert_eq!(ply.source.triangles, 56172);
    assert_eq!(ply.mesh.positions, obj.positions);
    assert_eq!(ply.mesh.triangles, obj.triangles);
}

#[test]
fn panoramas_load_with_their_published_statistics() {
    // SOURCES.md: the courtyard EXR is 1024 × 512, radiance max 55.56, mean 0.5579.
    let exr =
        trompe::frame::io::read_exr_rgba(&shared("envmaps/blender_courtyard_1k.exr")).unwrap();
    assert_eq!(exr.size(), (1024, 512));
    let rgb: Vec<f32> = exr.pixels().iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let mean = rgb.iter().map(|&v| v as f64).sum::<f64>() / rgb.len() as f64;
    let max = rgb.iter().copied().fold(f32::MIN, f32::max);
    assert!((mean - 0.5579).abs() < 0.001, "mean {mean}");
    assert!((max - 55.56).abs() < 0.01, "max {max}");
    for name in ["studio", "city", "forest", "apartment", "sunset", "night"] {
        let hdr = trompe::frame::io::read_hdr(&shared(&format!("envmaps/{name}.hdr"))).unwrap();
        assert_eq!(hdr.size(), (512, 256), "{name}");
        assert!(
            hdr.pixels()
                .iter()
                .all(|p| p.is_finite() && p.min_element() >= 0.0),
            "{name}"
        );
    }
}
