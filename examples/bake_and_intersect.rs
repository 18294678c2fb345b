//! Bake a SPOC impostor of a glTF model, save it, load it back, and answer rays with it beside
//! the exact BVH.
//!
//! ```sh
//! cargo run --release --example bake_and_intersect -- [MODEL.glb] [RESOLUTION]
//! ```
//! Default: the Khronos Duck shipped in `assets/gltf/Duck.glb`, 256².

use std::error::Error;
use std::path::PathBuf;
use std::sync::Arc;
use trompe::eval::fidelity::{check, viewpoint_rays};
use trompe::glam::Vec3;
use trompe::{Bvh, Impostor, Ray, RayQuery};

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let model = args.next().map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/gltf/Duck.glb"),
        PathBuf::from,
    );
    let resolution: u32 = args.next().map_or(Ok(256), |a| a.parse())?;

    // Load the mesh (its textures come along) and bake: the camera 3 bounding radii away, the
    // SPOC's strength chosen for rays from within one radius of it.
    let mesh = trompe::geom::io::load(&model)?.mesh;
    let b = mesh.bounds();
    let eye = b.center() + Vec3::new(0.3, 0.4, 1.0).normalize() * 3.0 * b.radius();
    let impostor = Impostor::spoc(&mesh)
        .from(eye)
        .resolution(resolution)
        .build()?;
    println!(
        "{}: {} impostor {resolution}², {:.1} % of texels covered",
        model.display(),
        impostor.camera().kind(),
        impostor.coverage() * 100.0
    );

    // Save and load it back: a JSON sidecar and the EXR of its maps.
    let out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/examples");
    std::fs::create_dir_all(&out)?;
    let sidecar = out.join("baked.json");
    trompe::impostor::file::save(&impostor, &sidecar)?;
    let impostor = trompe::impostor::file::load(&sidecar)?;
    println!("saved and loaded {}", sidecar.display());

    // One ray from the eye to the centre, answered by the impostor and by the exact BVH.
    let exact = Bvh::build(vec![Arc::new(mesh)])?;
    let ray = Ray::new(eye, (b.center() - eye).normalize());
    let (a, e) = (
        impostor.closest_hit(&ray, f32::INFINITY),
        exact.closest_hit(&ray, f32::INFINITY),
    );
    if let (Some(a), Some(e)) = (a, e) {
        println!(
            "central ray: impostor t = {:.4}, exact t = {:.4}, colour {:?}",
            a.t,
            e.t,
            a.radiance.unwrap_or_default()
        );
    }

    // Many rays from around the viewpoint, scored against the BVH.
    let rays = viewpoint_rays(&impostor, b.radius(), b, 5_000, 1);
    let r = check(&impostor, &exact, &rays);
    println!(
        "{} rays from within one radius of the eye: {:.2} % agree with the BVH ({} missed, {} spurious)",
        r.rays,
        r.agreement() * 100.0,
        r.missed,
        r.spurious
    );
    Ok(())
}
