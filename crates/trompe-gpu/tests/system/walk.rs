//! Paper 1's walk on the GPU (`shaders/walk.wgsl`) against the library's walk of the same
//! impostors (`Impostor::walk`): the same hit texel, every difference counted.

use glam::{Mat4, Vec3};
use std::path::Path;
use trompe::geom::{Mesh, Ray};
use trompe::impostor::{ImpostorCamera, Layers, ViewCamera};
use trompe_gpu::Gpu;
use trompe_gpu::walk::WalkSet;

/// The bunny, as shipped (about 0.15 units across, resting on y = 0.03).
fn bunny() -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/bunny.obj");
    trompe::geom::io::load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .mesh
}

/// `n` rays as a mirror ball of radius `region` at `eye` reflects them toward the bunny: origins
/// on the ball, directions spread over the bunny's bounding sphere.
fn reflected_rays(mesh: &Mesh, eye: Vec3, region: f32, n: usize, seed: u64) -> Vec<Ray> {
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.radius());
    let mut rng = trompe::geom::SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let origin = eye + rng.unit_vector() * region;
            let target = centre + rng.unit_vector() * (radius * 1.2 * rng.next_f32().cbrt());
            Ray::new(origin, (target - origin).normalize())
        })
        .collect()
}

/// What the two walks of `rays` disagree on, or the failure naming each count.
fn compare(
    gpu: &Gpu,
    name: &str,
    set: &WalkSet,
    index: u32,
    impostor: &trompe::impostor::Impostor,
    rays: &[Ray],
) {
    let uploaded = set.upload(gpu).unwrap();
    let on_gpu = uploaded.walk(gpu, index, rays, f32::INFINITY).unwrap();
    impostor.prepare_walks();
    let (mut hits, mut same, mut other_texel, mut hit_and_miss) = (0usize, 0usize, 0usize, 0usize);
    let mut worst_t = 0.0f32;
    for (ray, g) in rays.iter().zip(&on_gpu) {
        let c = impostor
            .walk(ray, f32::INFINITY)
            .0
            .filter(|h| h.t > 0.0 && h.t < f32::INFINITY);
        match (c, g) {
            (Some(c), Some(g)) => {
                hits += 1;
                let texel = (c.uv.x as u32, c.uv.y as u32);
                if texel == g.texel {
                    same += 1;
                    worst_t = worst_t.max((c.t - g.t).abs() / c.t.max(1e-6));
                } else {
                    other_texel += 1;
                }
            }
            (None, None) => same += 1,
            _ => hit_and_miss += 1,
        }
    }
    let agreement = same as f64 / rays.len() as f64;
    println!(
        "{name}: {} rays, {hits} hit on both; same answer {:.3} %, {other_texel} another texel, \
         {hit_and_miss} hit on one device only; worst t {worst_t:.2e} relative",
        rays.len(),
        agreement * 100.0
    );
    assert!(hits > rays.len() / 5, "{name}: only {hits} hits");
    assert!(
        agreement >= 0.999,
        "{name}: {:.3} % agree",
        agreement * 100.0
    );
    assert!(worst_t <= 1e-4, "{name}: t differs by {worst_t:e}");
}

pub fn the_gpu_walk_answers_as_the_cpu_walk_on_reflected_rays(gpu: &Gpu) {
    let mesh = bunny();
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.radius());
    let eye = centre + Vec3::new(0.7, 0.25, 0.6).normalize() * (2.5 * radius);
    let region = radius as f64 * 0.3;
    let color = |s: &trompe::impostor::SurfaceSample| Vec3::new(s.uv.x, s.uv.y, 0.5);
    for (name, kind, layers) in [
        ("pinhole", ViewCamera::Pinhole, Layers::ONE),
        ("pinhole, 3 layers", ViewCamera::Pinhole, Layers::Count(3)),
        ("orthographic", ViewCamera::Orthographic, Layers::ONE),
        ("SPOC", ViewCamera::Spoc(None), Layers::ONE),
        ("SPOC, 3 layers", ViewCamera::Spoc(None), Layers::Count(3)),
    ] {
        let camera =
            ImpostorCamera::fitted(kind, eye, centre, radius, region, 256, &mesh.positions)
                .unwrap();
        let mut impostor = trompe::impostor::build(camera, &mesh, 0, &color).unwrap();
        impostor.peel(&mesh, 0, &color, layers).unwrap();
        let mut set = WalkSet::new();
        let index = set.push(&impostor, Mat4::IDENTITY, true).unwrap();
        let rays = reflected_rays(&mesh, eye, region as f32, 12_000, 7);
        compare(gpu, name, &set, index, &impostor, &rays);
    }
}

/// An impostor whose object has moved: the GPU takes the ray into the frame it was built in, as
/// the library's impostor method does, and agrees with the CPU walk of the moved ray.
pub fn a_moved_impostor_is_walked_where_it_was_built(gpu: &Gpu) {
    let mesh = bunny();
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.radius());
    let eye = centre + Vec3::new(-0.6, 0.2, 0.7).normalize() * (2.5 * radius);
    let color = |_: &trompe::impostor::SurfaceSample| Vec3::ONE;
    let camera = ImpostorCamera::fitted(
        ViewCamera::Pinhole,
        eye,
        centre,
        radius,
        0.1 * radius as f64,
        192,
        &mesh.positions,
    )
    .unwrap();
    let impostor = trompe::impostor::build(camera, &mesh, 0, &color).unwrap();
    let motion =
        Mat4::from_translation(Vec3::new(2.0, 0.0, -0.8) * radius) * Mat4::from_rotation_y(0.4);
    let mut set = WalkSet::new();
    set.push(&impostor, Mat4::IDENTITY, true).unwrap();
    let moved = set.push(&impostor, motion, true).unwrap();
    let uploaded = set.upload(gpu).unwrap();
    // Rays aimed at the moved object, and the same rays taken back to where it was built.
    let rays: Vec<Ray> = reflected_rays(&mesh, eye, 0.1 * radius, 4_000, 11)
        .iter()
        .map(|r| {
            Ray::new(
                motion.transform_point3(r.origin),
                motion.transform_vector3(r.dir),
            )
        })
        .collect();
    let there: Vec<Ray> = rays
        .iter()
        .map(|r| {
            let back = motion.inverse();
            Ray::new(
                back.transform_point3(r.origin),
                back.transform_vector3(r.dir),
            )
        })
        .collect();
    let a = uploaded.walk(gpu, moved, &rays, f32::INFINITY).unwrap();
    let b = uploaded.walk(gpu, 0, &there, f32::INFINITY).unwrap();
    let hits = a.iter().filter(|h| h.is_some()).count();
    let same = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| match (x, y) {
            (Some(x), Some(y)) => x.texel == y.texel && (x.t - y.t).abs() <= 1e-4 * x.t,
            (None, None) => true,
            _ => false,
        })
        .count();
    assert!(hits > 1000, "{hits} hits");
    assert!(
        same as f64 >= 0.999 * rays.len() as f64,
        "{same} of {} agree",
        rays.len()
    );
}

/// The same rays give the same bits on repeated runs.
pub fn the_same_walks_give_the_same_bits_on_repeated_runs(gpu: &Gpu) {
    let mesh = bunny();
    let b = mesh.bounds();
    let eye = b.center() + Vec3::new(0.3, 0.2, 0.3).normalize() * (3.0 * b.radius());
    let color = |_: &trompe::impostor::SurfaceSample| Vec3::ONE;
    let camera = ImpostorCamera::fitted(
        ViewCamera::Pinhole,
        eye,
        b.center(),
        b.radius(),
        0.1 * b.radius() as f64,
        128,
        &mesh.positions,
    )
    .unwrap();
    let impostor = trompe::impostor::build(camera, &mesh, 0, &color).unwrap();
    let mut set = WalkSet::new();
    set.push(&impostor, Mat4::IDENTITY, true).unwrap();
    let uploaded = set.upload(gpu).unwrap();
    let rays = reflected_rays(&mesh, eye, 0.1 * b.radius(), 5_000, 5);
    let first = uploaded.walk(gpu, 0, &rays, f32::INFINITY).unwrap();
    let again = uploaded.walk(gpu, 0, &rays, f32::INFINITY).unwrap();
    let bits = |v: &[Option<trompe_gpu::walk::WalkHit>]| -> Vec<(u32, (u32, u32))> {
        v.iter()
            .map(|h| h.map_or((u32::MAX, (0, 0)), |h| (h.t.to_bits(), h.texel)))
            .collect()
    };
    assert_eq!(bits(&first), bits(&again));
}
