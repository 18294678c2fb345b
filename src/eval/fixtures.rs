//! What the experiments, benchmarks and tests share: the framing camera — one place says how a
//! mesh is framed, so a figure in `docs/` and the test beside it measure the same view — where
//! the repository's shipped scenes and models are, and the model kinds they lack ([`kinds`]).

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

/// Model kinds the shipped models leave out, made from boxes and quads so a test or a table can
/// hold the papers' claims on them (`docs/fidelity.md`): a thin slab with raised letters, an
/// assembly of thin parts with gaps between them, and a bush of thin leaves. Each is Y-up,
/// about one unit across, and the same on every call.
pub mod kinds {
    use crate::geom::{Mesh, SplitMix64, cube, plane};
    use glam::{Mat4, Quat, Vec3};

    /// `mesh` moved by `m`, appended to `into` (started when empty).
    fn add(into: &mut Option<Mesh>, mesh: &Mesh, m: Mat4) {
        let moved = mesh.transformed(&m);
        match into {
            Some(all) => all.append(&moved),
            None => *into = Some(moved),
        }
    }

    /// A box of `size` centred at `at`.
    fn boxed(into: &mut Option<Mesh>, at: Vec3, size: Vec3) {
        add(
            into,
            &cube(),
            Mat4::from_translation(at) * Mat4::from_scale(size),
        );
    }

    /// Five-by-seven glyphs of the letters of "TROMPE", one row of five bits a line, top first.
    const GLYPHS: [[u8; 7]; 6] = [
        [0x1f, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        [0x1e, 0x11, 0x11, 0x1e, 0x14, 0x12, 0x11],
        [0x0e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e],
        [0x11, 0x1b, 0x15, 0x15, 0x11, 0x11, 0x11],
        [0x1e, 0x11, 0x11, 0x1e, 0x10, 0x10, 0x10],
        [0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f],
    ];

    /// A logo slab: a plate 1 × 0.4 and 0.04 thick, lying in the xy plane facing +z, with the
    /// letters TROMPE raised 0.02 on its face, one box a glyph cell.
    pub fn slab_with_letters() -> Mesh {
        let mut all = None;
        boxed(&mut all, Vec3::ZERO, Vec3::new(1.0, 0.4, 0.04));
        let cell = 0.025;
        for (i, glyph) in GLYPHS.iter().enumerate() {
            let left = -0.45 + i as f32 * 0.155;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        let at = Vec3::new(
                            left + (col as f32 + 0.5) * cell,
                            0.0875 - row as f32 * cell,
                            0.03,
                        );
                        boxed(&mut all, at, Vec3::new(cell, cell, 0.02));
                    }
                }
            }
        }
        all.unwrap_or_else(cube)
    }

    /// A mechanical assembly: a base plate, a comb of thin upright fins with narrow gaps, a row
    /// of thin rods through them and two side brackets — many thin parts that hide each other.
    pub fn assembly() -> Mesh {
        let mut all = None;
        boxed(
            &mut all,
            Vec3::new(0.0, -0.3, 0.0),
            Vec3::new(1.0, 0.03, 0.6),
        );
        for i in 0..12 {
            let x = -0.44 + i as f32 * 0.08;
            boxed(
                &mut all,
                Vec3::new(x, -0.05, 0.0),
                Vec3::new(0.012, 0.47, 0.5),
            );
        }
        for j in 0..4 {
            let (y, z) = (-0.15 + j as f32 * 0.1, -0.18 + j as f32 * 0.12);
            boxed(
                &mut all,
                Vec3::new(0.0, y, z),
                Vec3::new(1.05, 0.015, 0.015),
            );
        }
        for x in [-0.52, 0.52] {
            boxed(
                &mut all,
                Vec3::new(x, -0.1, 0.0),
                Vec3::new(0.02, 0.42, 0.3),
            );
        }
        all.unwrap_or_else(cube)
    }

    /// A bush: 240 leaves, thin quads 0.12 × 0.06 (two triangles a side, both sides), turned at
    /// random about a stem, filling a sphere of radius 0.45 more densely near its surface.
    pub fn foliage() -> Mesh {
        let mut all = None;
        boxed(
            &mut all,
            Vec3::new(0.0, -0.25, 0.0),
            Vec3::new(0.04, 0.5, 0.04),
        );
        let mut rng = SplitMix64::new(11);
        let leaf = {
            let mut front = plane(1);
            let back = front.transformed(&Mat4::from_rotation_x(std::f32::consts::PI));
            front.append(&back);
            front
        };
        for _ in 0..240 {
            let at = rng.unit_vector() * 0.45 * rng.next_f32().sqrt();
            let turn =
                Quat::from_axis_angle(rng.unit_vector(), rng.next_f32() * std::f32::consts::TAU);
            let m = Mat4::from_scale_rotation_translation(Vec3::new(0.12, 1.0, 0.06), turn, at);
            add(&mut all, &leaf, m);
        }
        all.unwrap_or_else(cube)
    }
}
