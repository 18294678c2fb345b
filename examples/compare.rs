//! Compare two images as `trompe compare` does: PSNR, SSIM and FLIP, and a FLIP heat map.
//!
//! ```sh
//! cargo run --release --example compare -- REFERENCE TEST [HEATMAP.png]
//! ```
//! With no arguments, compares two renders of `scenes/diffuse.toml`: the traced frame against the
//! rasterized one.

use std::error::Error;
use std::path::PathBuf;
use trompe::frame::{io, metrics};
use trompe::{Method, Scene, render};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (reference, test) = match args.as_slice() {
        [a, b, ..] => (io::read_color(a.as_ref())?, io::read_color(b.as_ref())?),
        _ => {
            let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/diffuse.toml");
            let scene = Scene::load(&path)?;
            let (exact, _) = render(&scene, Method::Trace, &())?;
            let (raster, _) = render(&scene, Method::Raster, &())?;
            (exact.color, raster.color)
        }
    };
    let s = metrics::compare(&reference, &test, None)?;
    println!(
        "PSNR {:.3} dB\nSSIM {:.5}\nFLIP {:.5}",
        s.psnr, s.ssim, s.flip
    );
    if let Some(heat) = args.get(2) {
        io::write_png(
            heat.as_ref(),
            &metrics::heat_map(&metrics::flip_map(&reference, &test)?),
        )?;
        println!("wrote {heat}");
    }
    Ok(())
}
