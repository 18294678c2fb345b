//! The rasterizer against the exact BVH: depth at every covered pixel and item ids; and the BVH
//! against brute force.

use crate::common;
use common::shared;
use glam::Vec3;
use std::sync::Arc;
use trompe::eval::validate::raster_vs_bvh;
use trompe::geom::Ray;
use trompe::geom::io::load;
use trompe::trace::{BruteForce, Bvh, RayQuery};

#[track_caller]
fn check(rel: &str) {
    let mesh = load(&shared(rel)).unwrap().mesh;
    let a = raster_vs_bvh(&mesh, 256).unwrap();
    assert!(a.covered > 5000, "{rel}: {a:?}");
    assert!(a.max_relative_depth_error <= 1e-4, "{rel}: {a:?}");
    assert!(a.id_agreement >= 0.995, "{rel}: {a:?}");
}

#[test]
fn bunny_raster_depth_and_ids_match_bvh() {
    check("meshes/bunny.obj");
}

#[test]
fn teapot_raster_depth_and_ids_match_bvh() {
    check("meshes/teapot.obj");
}

#[test]
fn bvh_hits_equal_brute_force_hits() {
    let mesh = Arc::new(load(&shared("meshes/dragon_res4.obj")).unwrap().mesh);
    let bvh = Bvh::build(vec![mesh.clone()]).unwrap();
    let brute = BruteForce::new(vec![mesh.clone()]);
    let b = mesh.bounds();
    let mut hits = 0;
    for i in 0..3000u32 {
        // Replayable rays from a sphere around the dragon toward random points in its box.
        let h = |k: u32| {
            ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(2_246_822_519)) % 100_003) as f32
                / 100_003.0
        };
        let dir = Vec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5).normalize_or(Vec3::X);
        let origin = b.center() + dir * b.radius() * 2.0;
        let target = b.min + b.extent() * Vec3::new(h(4), h(5), h(6));
        let ray = Ray::new(origin, (target - origin).normalize());
        let (x, y) = (
            bvh.closest_hit(&ray, f32::INFINITY),
            brute.closest_hit(&ray, f32::INFINITY),
        );
        assert_eq!(x.is_some(), y.is_some(), "ray {i}");
        if let (Some(x), Some(y)) = (x, y) {
            hits += 1;
            assert!(
                (x.t - y.t).abs() <= 1e-6 * y.t,
                "ray {i}: {} vs {}",
                x.t,
                y.t
            );
            assert!(bvh.any_hit(&ray, x.t * 1.01), "ray {i}");
            assert!(!bvh.any_hit(&ray, x.t * 0.99), "ray {i}");
        }
    }
    assert!(hits > 1000, "{hits}");
    // Axis-aligned rays, negative zeros included (`-Vec3::Z` is (−0, −0, −1)).
    for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        let ray = Ray::new(b.center() - axis * b.radius() * 3.0, axis);
        let (x, y) = (
            bvh.closest_hit(&ray, f32::INFINITY),
            brute.closest_hit(&ray, f32::INFINITY),
        );
        assert_eq!(x.map(|h| h.t), y.map(|h| h.t), "axis {axis}");
    }
}
