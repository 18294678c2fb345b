//! A Radiance `.hdr` panorama, read as a colour image and as an environment map.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::file("e.hdr", data);
    let _ = trompe::frame::envmap::EnvMap::load(&p, 0.0, 1.0);
});
