//! A COLMAP model: `cameras` then (after the marker) `images`, loaded as a text model and as a
//! binary one.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::parts(data, 2);
    for (dir, ext) in [("text", "txt"), ("binary", "bin")] {
        let d = trompe_fuzz::scratch().join(dir);
        std::fs::create_dir_all(&d).expect("a scratch folder");
        std::fs::write(d.join(format!("cameras.{ext}")), p[0]).expect("writable");
        std::fs::write(d.join(format!("images.{ext}")), p[1]).expect("writable");
        let _ = trompe::views::ViewSet::load(&d, None);
    }
});
