//! An OpenEXR file, read as every channel and as RGBA.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::file("e.exr", data);
    let _ = trompe::frame::io::read_exr_channels(&p);
    let _ = trompe::frame::io::read_exr_rgba(&p);
});
