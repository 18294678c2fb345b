//! A PLY file, ASCII or binary.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let _ = trompe::geom::io::load(&trompe_fuzz::file("m.ply", data));
});
