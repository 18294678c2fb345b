//! A baked impostor: its JSON sidecar and the EXR it names (`i.exr`), separated by the marker.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::parts(data, 2);
    trompe_fuzz::file("i.exr", p[1]);
    let json = trompe_fuzz::file("i.json", p[0]);
    if let Ok(imp) = trompe::impostor::file::load(&json) {
        let b = imp.bounds();
        let centre = (b.min + b.max) * 0.5;
        let origin = centre + trompe::glam::Vec3::splat(b.extent().length().max(1.0));
        let direction = (centre - origin).normalize_or(trompe::glam::Vec3::Z);
        let ray = trompe::Ray::new(origin, direction);
        let _ = trompe::RayQuery::closest_hit(&imp, &ray, f32::INFINITY);
    }
});
