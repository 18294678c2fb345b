//! Layered impostors (depth peeling through one camera) and batched ray queries.

use crate::common;
use glam::Vec3;
use std::path::Path;
use trompe::eval::check::{CheckSettings, check_built};
use trompe::geom::Mesh;
use trompe::geom::io::load;
use trompe::impostor::{ImpostorCamera, Layers, Subject, ViewCamera, albedo_of, build, file};
use trompe::{Ray, RayQuery};

/// Three squares facing `+z` at z = 0, −1, −2, each sized so the camera at z = 3 sees them
/// cover the same image square: every texel that sees one sees all three.
fn three_squares() -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (k, z) in [0.0f32, -1.0, -2.0].into_iter().enumerate() {
        let half = 0.1 * (3.0 - z);
        let base = 4 * k as u32;
        positions.extend([
            Vec3::new(-half, -half, z),
            Vec3::new(half, -half, z),
            Vec3::new(half, half, z),
            Vec3::new(-half, half, z),
        ]);
        triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    let n = positions.len();
    let mut warnings = Vec::new();
    Mesh::from_parts(
        Path::new("three-squares"),
        positions,
        Some(vec![Vec3::Z; n]),
        None,
        triangles,
        vec![0; 6],
        Vec::new(),
        &mut warnings,
    )
    .unwrap()
}

#[test]
fn peeled_layers_hold_the_squares_in_depth_order_and_a_walk_from_behind_the_first_meets_the_second()
{
    let mesh = three_squares();
    let eye = Vec3::new(0.0, 0.0, 3.0);
    for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(Some(0.1))] {
        let camera =
            ImpostorCamera::around(kind, eye, Vec3::new(0.0, 0.0, -1.0), 0.8, 0.8, 96).unwrap();
        let mut imp = build(camera, &mesh, 0, &albedo_of(&mesh)).unwrap();
        let single = imp.clone();
        // Four asked, three held: peeling stops at a layer that would hold nothing.
        imp.peel(&mesh, 0, &albedo_of(&mesh), Layers::Count(4))
            .unwrap();
        assert_eq!(imp.layer_count(), 3, "{kind:?}");
        let (w, h) = imp.gd().size();
        let covered = |l: usize| {
            let layer = imp.layer(l).unwrap();
            (0..w * h)
                .filter(|i| layer.gd().pixels()[*i as usize] > 0.0)
                .count()
        };
        let first = covered(0);
        assert!(first > 500, "{kind:?}: {first}");
        // Through the pinhole the three squares cover the same texels, up to the rasterizer's
        // edge rule at their borders; the SPOC pushes deeper surface outward from its pole (what
        // it is for), so its first layer shows the deeper squares' rims.
        let through_pinhole = kind == ViewCamera::Pinhole;
        for l in 1..3 {
            if through_pinhole {
                assert!(
                    covered(l).abs_diff(first) * 50 < first,
                    "layer {l}: {} texels against {first}",
                    covered(l)
                );
            } else {
                assert!(
                    covered(l) * 2 > first,
                    "{kind:?} layer {l}: {} of {first}",
                    covered(l)
                );
            }
        }
        let mut all_three = 0;
        for y in 0..h {
            for x in 0..w {
                let held: Vec<f32> = imp
                    .layers()
                    .filter(|layer| layer.gd().get(x, y) > 0.0)
                    .map(|layer| layer.position_at(x, y).z)
                    .collect();
                // Every texel a deeper layer covers, the layer before covers; each layer holds
                // one of the squares, farther than the layer before.
                for l in 0..held.len() {
                    assert!(imp.layer(l).unwrap().gd().get(x, y) > 0.0);
                    let square = (-held[l]).round();
                    assert!(
                        (held[l] + square).abs() < 2e-3,
                        "{kind:?} layer {l} texel ({x}, {y}) holds z = {}",
                        held[l]
                    );
                    if l > 0 {
                        assert!(held[l] < held[l - 1] - 0.5, "{kind:?} ({x}, {y}): {held:?}");
                    }
                }
                // Where all three are held, layer l holds square l.
                if held.len() == 3 {
                    all_three += 1;
                    for (l, z) in held.iter().enumerate() {
                        assert!((z + l as f32).abs() < 2e-3, "{kind:?} ({x}, {y}): {held:?}");
                    }
                }
            }
        }
        assert!(all_three * 2 > first, "{kind:?}: {all_three} of {first}");
        // From between the first and the second square, away from the camera.
        let ray = Ray::new(Vec3::new(0.05, 0.02, -0.5), -Vec3::Z);
        let hit = imp
            .closest_hit(&ray, f32::INFINITY)
            .expect("the second square");
        assert!(
            (hit.position.z + 1.0).abs() < 2e-3 && (hit.t - 0.5).abs() < 2e-3,
            "{kind:?}: {hit:?}"
        );
        // One layer holds only the first square: the ray, behind it, meets nothing.
        assert!(
            single.closest_hit(&ray, f32::INFINITY).is_none(),
            "{kind:?}"
        );
        // From in front, the first square.
        let front = Ray::new(Vec3::new(0.05, 0.02, 1.0), -Vec3::Z);
        let hit = imp.closest_hit(&front, f32::INFINITY).unwrap();
        assert!(hit.position.z.abs() < 2e-3, "{kind:?}: {hit:?}");
    }
}

#[test]
fn layers_raise_the_dragons_agreement_with_the_bvh_well_above_one_layer() {
    let (subject, _) = Subject::load(&common::asset("meshes/dragon_res4.obj")).unwrap();
    let settings = CheckSettings {
        layers: Layers::Auto,
        view: 512,
        ..CheckSettings::default()
    };
    let report = check_built(&subject, &settings).unwrap();
    let rows = &report.layers_beside;
    assert_eq!(rows.len(), 4);
    let (one, auto) = (&rows[0], &rows[3]);
    assert_eq!(one.layers, 1);
    assert!(auto.layers >= 2 && auto.layers <= 8, "{}", auto.layers);
    // Measured: 94.3 % with one layer, 98.3 % with the automatic five. A peel that copied the
    // first layer, or held back faces the walk takes for the surface it passed, gains nothing.
    let (a1, aa) = (one.fidelity.agreement(), auto.fidelity.agreement());
    assert!(aa > a1 + 0.025, "one layer {a1}, auto {aa}");
    assert!(
        auto.fidelity.missed * 5 < one.fidelity.missed,
        "missed: one layer {}, auto {}",
        one.fidelity.missed,
        auto.fidelity.missed
    );
    // Each layer costs the maps of one.
    assert_eq!(auto.map_bytes, one.map_bytes * auto.layers as u64);
    assert_eq!(report.impostor.layer_count(), auto.layers);
}

#[test]
fn the_layered_texel_walk_returns_the_layer_by_layer_linear_walks_hits() {
    // One texel walk through every layer at once, under one pyramid bounding them all, against
    // paper 1's linear walk run layer by layer (nearest wins), on the dragon's automatic
    // layers: random rays around it.
    let mesh = load(&common::asset("meshes/dragon_res4.obj")).unwrap().mesh;
    let imp = trompe::Impostor::spoc(&mesh)
        .resolution(256)
        .layers(Layers::Auto)
        .build()
        .unwrap();
    assert!(imp.layer_count() >= 3, "{}", imp.layer_count());
    let bvh = trompe::Bvh::build(vec![std::sync::Arc::new(mesh.clone())]).unwrap();
    let b = mesh.bounds();
    let rays = trompe::eval::fidelity::sphere_rays(b.center(), b.radius() * 3.0, b, 100_000, 5);
    let c = common::compare_walks(&imp, &bvh, &rays);
    eprintln!("{} layers: {c:?}", imp.layer_count());
    c.holds();
    assert!(c.hits > 20_000, "{c:?}");
}

#[test]
fn a_layered_impostor_saves_and_loads_exactly_and_a_wrong_layer_count_is_refused() {
    let mesh = load(&common::asset("meshes/dragon_res4.obj")).unwrap().mesh;
    let mut imp = trompe::Impostor::spoc(&mesh)
        .resolution(128)
        .layers(Layers::Count(3))
        .build()
        .unwrap();
    assert_eq!(imp.layer_count(), 3);
    imp.set_object_id(5);
    let dir = common::scratch("layered_impostor");
    let path = dir.join("dragon.json");
    file::save(&imp, &path).unwrap();
    let back = file::load(&path).unwrap();
    assert_eq!(back.layer_count(), 3);
    for (a, b) in imp.layers().zip(back.layers()) {
        assert!(a.gd() == b.gd() && a.color() == b.color() && a.object() == b.object());
        assert!(a.normal() == b.normal() && a.face_normal() == b.face_normal());
    }
    let b = mesh.bounds();
    let rays = trompe::eval::fidelity::sphere_rays(b.center(), b.radius() * 2.5, b, 3000, 7);
    let mut hits = 0;
    for r in &rays {
        let (x, y) = (imp.walk(r, f32::INFINITY).0, back.walk(r, f32::INFINITY).0);
        assert_eq!(x, y);
        hits += x.is_some() as usize;
    }
    assert!(hits > 300, "{hits}");
    // The sidecar says two layers; the EXR holds three.
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"layers\": 3"), "{text}");
    std::fs::write(&path, text.replace("\"layers\": 3", "\"layers\": 2")).unwrap();
    let err = file::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("says 2 layers") && err.contains("channels of 3"),
        "{err}"
    );
    // And one layer (the field removed) against three.
    let single = text.replace("\"layers\": 3,", "");
    assert!(!single.contains("layers"));
    std::fs::write(&path, single).unwrap();
    let err = file::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("says 1 layer ") && err.contains("channels of 3"),
        "{err}"
    );
}

#[test]
fn batched_queries_return_the_one_ray_answers_on_one_and_two_threads() {
    let mesh = load(&common::asset("meshes/teapot.obj")).unwrap().mesh;
    let imp = trompe::Impostor::spoc(&mesh)
        .resolution(256)
        .layers(Layers::Count(2))
        .build()
        .unwrap();
    let bvh = trompe::Bvh::build(vec![std::sync::Arc::new(mesh.clone())]).unwrap();
    let b = mesh.bounds();
    let rays: Vec<(Ray, f32)> =
        trompe::eval::fidelity::sphere_rays(b.center(), b.radius() * 2.0, b, 5000, 3)
            .into_iter()
            .enumerate()
            .map(|(i, r)| {
                (
                    r,
                    if i % 7 == 0 {
                        b.radius()
                    } else {
                        f32::INFINITY
                    },
                )
            })
            .collect();
    for query in [&imp as &dyn RayQuery, &bvh as &dyn RayQuery] {
        let one: Vec<_> = rays.iter().map(|(r, t)| query.closest_hit(r, *t)).collect();
        assert!(one.iter().filter(|h| h.is_some()).count() > 1000);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut batch = vec![None; 3];
            pool.install(|| query.closest_hits(&rays, &mut batch));
            assert!(batch == one, "{threads} threads");
        }
    }
}
