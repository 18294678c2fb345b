//! What the experiments, benchmarks and tests share: the framing camera — one place says how a
//! mesh is framed, so a figure in `docs/` and the test beside it measure the same view — and
//! where the repository's shipped scenes and models are.

use crate::camera::Pinhole;
use crate::geom::Mesh;
use glam::Vec3;
use std::path::PathBuf;

/// A camera framing `mesh` from the front-right (along `(0.5, 0.35, 1)` from its centre, 2.6
/// bounding radii away, 45° vertical field of view), `size × size` pixels. A flat or point-like
/// mesh still gets a camera (its radius is taken as at least 10⁻³); `None` only for a mesh whose
/// box is not finite or a size of 0.
pub fn framing_camera(mesh: &Mesh, size: u32) -> Option<Pinhole> {
    let b = mesh.bounds();
    let r = b.radius().max(1e-3);
    let eye = b.center() + Vec3::new(0.5, 0.35, 1.0).normalize() * r * 2.6;
    Pinhole::look_at(eye, b.center(), Vec3::Y, 45.0, size, size)
        .ok()
        .map(|c| c.with_near(r as f64 * 1e-3))
}

/// What the repository ships for the demo, the benchmarks and the examples: its `scenes/` and
/// `assets/`.
#[derive(Clone, Debug)]
pub struct Shipped {
    /// Directory holding the demo scenes.
    pub scenes: PathBuf,
    /// Directory holding the shipped models.
    pub assets: PathBuf,
}

impl Shipped {
    /// `scenes/` and `assets/` in the current directory if present, else beside this crate's
    /// manifest (so `cargo run -- demo` works from anywhere in the checkout).
    pub fn locate() -> Shipped {
        let here = PathBuf::from(".");
        let root = if here.join("scenes/diffuse.toml").is_file() {
            here
        } else {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        };
        Shipped {
            scenes: root.join("scenes"),
            assets: root.join("assets"),
        }
    }
}
