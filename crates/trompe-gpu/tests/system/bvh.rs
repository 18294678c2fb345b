//! The GPU walk of the BVH (`shaders/bvh.wgsl`) against the library's CPU walk of the same BVH.

use glam::Vec3;
use std::path::Path;
use std::sync::Arc;
use trompe::geom::{Mesh, Ray};
use trompe::trace::{Bvh, RayQuery};
use trompe_gpu::{Gpu, GpuBvh};

pub fn the_shaders_parse_and_validate() {
    validate(trompe_gpu::bvh::SHADER);
    validate(&trompe_gpu::trace::shader_source());
    validate(trompe_gpu::raster::RASTER_SHADER);
    validate(&trompe_gpu::walk::shader_source());
    validate(&trompe_gpu::trace::impostor_shader_source());
    validate(trompe_gpu::present::SHADER);
    for k in [1, 4, trompe_gpu::texturing::MAX_K] {
        use trompe_gpu::texturing::shader_source;
        validate(&shader_source(trompe_gpu::master::MASTER_SHADER, k));
        validate(&shader_source(&trompe_gpu::views::views_source(), k));
        validate(&shader_source(&trompe_gpu::layers::layers_source(), k));
    }
    // The tracer's stack holds one pending ray more than the recursion limit it accepts.
    let pending = format!(
        "const PENDING: u32 = {}u;",
        trompe_gpu::trace::MAX_DEPTH + 1
    );
    assert!(
        trompe_gpu::trace::shader_source().contains(&pending),
        "{pending}"
    );
}

/// Parses and validates WGSL with naga, as wgpu would before compiling it.
fn validate(source: &str) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{e:?}"));
}

/// The bunny (0.6 units across) and a teapot of its size beside it: two objects, 73k triangles.
fn scene() -> Bvh {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let load = |name: &str, scale: f32, offset: Vec3| -> Arc<Mesh> {
        let path = root.join("assets/meshes").join(name);
        let mut mesh = trompe::geom::io::load(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .mesh;
        mesh.positions
            .iter_mut()
            .for_each(|p| *p = *p * scale + offset);
        Arc::new(mesh)
    };
    Bvh::build(vec![
        load("bunny.obj", 1.0, Vec3::ZERO),
        load("teapot.obj", 0.02, Vec3::new(1.0, 0.25, 0.25)),
    ])
    .expect("two small meshes fit the budget")
}

/// `n` incoherent rays: origins spread through (and around) the scene, directions uniform.
fn incoherent_rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = trompe::geom::SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let s = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let origin = Vec3::new(1.5, 0.7, 0.7) * s - Vec3::splat(0.1);
            Ray::new(origin, rng.unit_vector())
        })
        .collect()
}

pub fn the_gpu_walk_hits_the_cpu_bvhs_triangles_on_ten_thousand_incoherent_rays(gpu: &Gpu) {
    let bvh = scene();
    let on_gpu = GpuBvh::upload(gpu, &bvh).unwrap();
    let rays = incoherent_rays(20_000, 3);
    let gpu_hits = on_gpu.closest_hits(&rays, f32::INFINITY).unwrap();
    let (mut hits, mut other_triangle, mut hit_and_miss, mut worst_t) = (0, 0, 0, 0.0f32);
    for (ray, g) in rays.iter().zip(&gpu_hits) {
        let c = bvh.closest_hit(ray, f32::INFINITY);
        match (&c, g) {
            (Some(c), Some(g)) => {
                hits += 1;
                if (c.object, c.triangle) != (g.object, g.triangle) {
                    other_triangle += 1;
                    eprintln!(
                        "{ray:?}: CPU {:?} at {}, GPU {:?} at {}",
                        (c.object, c.triangle),
                        c.t,
                        (g.object, g.triangle),
                        g.t
                    );
                } else {
                    worst_t = worst_t.max((c.t - g.t).abs() / c.t);
                }
            }
            (None, None) => {}
            _ => {
                hit_and_miss += 1;
                eprintln!(
                    "{ray:?}: CPU {:?}, GPU {:?}",
                    c.map(|h| h.t),
                    g.map(|h| h.t)
                );
            }
        }
    }
    eprintln!(
        "{} rays on {}: {hits} hits, {other_triangle} on another triangle, {hit_and_miss} hit on \
         one side only, largest relative distance difference {worst_t:.1e}",
        rays.len(),
        gpu.name()
    );
    // Both answers are exercised: the test's rays are not all hits, nor all misses.
    assert!((2_000..18_000).contains(&hits), "{hits} of 20000 rays hit");
    assert_eq!((other_triangle, hit_and_miss), (0, 0));
    assert!(worst_t <= 1e-4, "{worst_t}");
}

pub fn shadow_rays_agree_with_the_cpu_any_hit(gpu: &Gpu) {
    let bvh = scene();
    let on_gpu = GpuBvh::upload(gpu, &bvh).unwrap();
    let rays = incoherent_rays(10_000, 8);
    for t_max in [0.1, f32::INFINITY] {
        let gpu_any = on_gpu.any_hits(&rays, t_max).unwrap();
        let differ = rays
            .iter()
            .zip(&gpu_any)
            .filter(|(r, g)| bvh.any_hit(r, t_max) != **g)
            .count();
        let blocked = gpu_any.iter().filter(|b| **b).count();
        eprintln!(
            "t_max {t_max}: {blocked} of {} blocked, {differ} differ",
            rays.len()
        );
        assert!(blocked > 500 && blocked < rays.len() - 500);
        assert_eq!(differ, 0);
    }
}

pub fn the_same_rays_give_the_same_bits_on_repeated_runs(gpu: &Gpu) {
    let bvh = scene();
    let on_gpu = GpuBvh::upload(gpu, &bvh).unwrap();
    let rays = incoherent_rays(10_000, 21);
    let first = on_gpu.leaf_hits(&rays, f32::INFINITY, false).unwrap();
    let second = on_gpu.leaf_hits(&rays, f32::INFINITY, false).unwrap();
    let bits = |h: &[trompe_gpu::bvh::LeafHit]| -> Vec<u8> { bytemuck::cast_slice(h).to_vec() };
    assert!(bits(&first) == bits(&second));
}

pub fn an_empty_scene_misses_and_no_rays_is_no_work(gpu: &Gpu) {
    let empty = Bvh::build(Vec::new()).unwrap();
    let on_gpu = GpuBvh::upload(gpu, &empty).unwrap();
    let rays = incoherent_rays(100, 1);
    assert!(
        on_gpu
            .closest_hits(&rays, f32::INFINITY)
            .unwrap()
            .iter()
            .all(Option::is_none)
    );
    assert!(
        on_gpu
            .any_hits(&rays, f32::INFINITY)
            .unwrap()
            .iter()
            .all(|b| !b)
    );
    let bvh = scene();
    let on_gpu = GpuBvh::upload(gpu, &bvh).unwrap();
    assert!(on_gpu.closest_hits(&[], 1.0).unwrap().is_empty());
}
