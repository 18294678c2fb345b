//! An OBJ and its MTL (`mtllib m.mtl`), separated by the marker.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::parts(data, 2);
    trompe_fuzz::file("m.mtl", p[1]);
    let obj = trompe_fuzz::file("m.obj", p[0]);
    let _ = trompe::geom::io::load(&obj);
});
