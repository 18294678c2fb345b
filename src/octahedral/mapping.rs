//! Octahedral maps of view directions (Engelhardt and Dachsbacher, "Octahedron Environment Maps",
//! 2008; the layout engines' impostor bakers use): a direction is projected onto the octahedron
//! `|x| + |y| + |z| = 1` and the octahedron unfolded onto the unit square — the upper half
//! (`y ≥ 0`) as the inner diamond, the lower half folded out to the corners. The hemi-octahedral
//! map unfolds the upper half alone onto the whole square. An `n × n` grid of frames samples the
//! square at `(i, j)/(n − 1)`, corners and edges included: the sphere's `−y` pole (the corners)
//! and the hemisphere's horizon (the edges) are always frames; the `+y` pole (the centre) and
//! the sphere's horizon (the diamond's edges) are frames when `n` is odd.
//!
//! Invariants: `decode(encode(d)) = d` for unit `d` (of the upper hemisphere for the hemi map);
//! the three frames [`Grid::frames_around`] picks hold weights that sum to 1 and are
//! non-negative; a frame's own direction picks that frame with weight 1.

use glam::{DVec2, DVec3};

/// Which directions the grid covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Coverage {
    /// Every direction (octahedral).
    Sphere,
    /// The upper hemisphere, `y ≥ 0` (hemi-octahedral): for objects seen only from above.
    Hemisphere,
}

/// The unit square point of unit direction `d`.
pub fn encode(d: DVec3, coverage: Coverage) -> DVec2 {
    // The hemi map holds no direction below the horizon: those clamp to it.
    let d = match coverage {
        Coverage::Sphere => d,
        Coverage::Hemisphere => DVec3::new(d.x, d.y.max(0.0), d.z),
    };
    let d = d / (d.x.abs() + d.y.abs() + d.z.abs()).max(f64::MIN_POSITIVE);
    let p = match coverage {
        Coverage::Sphere => {
            if d.y >= 0.0 {
                DVec2::new(d.x, d.z)
            } else {
                // Fold the lower half out to the corners.
                DVec2::new((1.0 - d.z.abs()) * sign(d.x), (1.0 - d.x.abs()) * sign(d.z))
            }
        }
        // The diamond rotated 45° fills the square.
        Coverage::Hemisphere => DVec2::new(d.x + d.z, d.z - d.x),
    };
    (p * 0.5 + DVec2::splat(0.5)).clamp(DVec2::ZERO, DVec2::ONE)
}

/// The unit direction of unit square point `uv`.
pub fn decode(uv: DVec2, coverage: Coverage) -> DVec3 {
    let p = uv * 2.0 - DVec2::ONE;
    let d = match coverage {
        Coverage::Sphere => {
            let y = 1.0 - p.x.abs() - p.y.abs();
            if y >= 0.0 {
                DVec3::new(p.x, y, p.y)
            } else {
                DVec3::new(
                    (1.0 - p.y.abs()) * sign(p.x),
                    y,
                    (1.0 - p.x.abs()) * sign(p.y),
                )
            }
        }
        Coverage::Hemisphere => {
            let (x, z) = ((p.x - p.y) * 0.5, (p.x + p.y) * 0.5);
            DVec3::new(x, 1.0 - x.abs() - z.abs(), z)
        }
    };
    d.normalize()
}

fn sign(v: f64) -> f64 {
    if v >= 0.0 { 1.0 } else { -1.0 }
}

/// An `n × n` grid of frames over the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Grid {
    /// Frames a side.
    pub n: u32,
    /// The directions covered.
    pub coverage: Coverage,
}

/// Fewest and most frames a side.
pub const FRAMES_RANGE: std::ops::RangeInclusive<u32> = 2..=64;

impl Grid {
    /// The view direction (from the object toward the eye) of frame `(i, j)`.
    pub fn direction(&self, i: u32, j: u32) -> DVec3 {
        let s = f64::from(self.n - 1);
        decode(
            DVec2::new(f64::from(i) / s, f64::from(j) / s),
            self.coverage,
        )
    }

    /// The three frames around view direction `d` and their weights: the grid cell holding
    /// `d`'s map point, split along its diagonal, and the barycentric weights in that half.
    pub fn frames_around(&self, d: DVec3) -> [((u32, u32), f64); 3] {
        let s = f64::from(self.n - 1);
        let p = encode(d, self.coverage) * s;
        let cell = p.floor().min(DVec2::splat(s - 1.0)).max(DVec2::ZERO);
        let f = p - cell;
        let (i, j) = (cell.x as u32, cell.y as u32);
        if f.x + f.y <= 1.0 {
            [
                ((i, j), 1.0 - f.x - f.y),
                ((i + 1, j), f.x),
                ((i, j + 1), f.y),
            ]
        } else {
            [
                ((i + 1, j + 1), f.x + f.y - 1.0),
                ((i, j + 1), 1.0 - f.x),
                ((i + 1, j), 1.0 - f.y),
            ]
        }
    }
}

/// A frame's image axes for view direction `d` (toward the eye): `right`, `up`, with `up` as
/// close to `+y` as `d` allows (`−z` at the poles, so the basis turns smoothly near them).
pub fn frame_basis(d: DVec3) -> (DVec3, DVec3) {
    let reference = if d.y.abs() > 0.999 {
        -DVec3::Z * d.y.signum()
    } else {
        DVec3::Y
    };
    let right = reference.cross(d).normalize();
    (right, d.cross(right))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_and_decode_are_inverse_on_frame_centres_and_random_directions() {
        for coverage in [Coverage::Sphere, Coverage::Hemisphere] {
            let grid = Grid { n: 16, coverage };
            for i in 0..16 {
                for j in 0..16 {
                    let d = grid.direction(i, j);
                    let uv = encode(d, coverage);
                    let back = uv * 15.0;
                    // Folded edges of the sphere map meet themselves: the same direction.
                    let again = decode(uv, coverage);
                    assert!((again - d).length() < 1e-9, "{i},{j}: {d} → {again}");
                    if coverage == Coverage::Hemisphere || (i > 0 && i < 15 && j > 0 && j < 15) {
                        assert!(
                            (back - DVec2::new(f64::from(i), f64::from(j))).length() < 1e-9,
                            "{i},{j}: {back}"
                        );
                    }
                    // A frame's own direction picks it alone.
                    let around = grid.frames_around(d);
                    let own = around
                        .iter()
                        .filter(|(f, _)| grid.direction(f.0, f.1).dot(d) > 1.0 - 1e-9)
                        .map(|(_, w)| w)
                        .sum::<f64>();
                    assert!((own - 1.0).abs() < 1e-9, "{i},{j}: {around:?}");
                }
            }
            let mut seed = 3u64;
            for _ in 0..10_000 {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                let a = (seed >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
                let z = (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                let r = (1.0 - z * z).sqrt();
                let mut d = DVec3::new(r * a.cos(), z, r * a.sin());
                if coverage == Coverage::Hemisphere {
                    d.y = d.y.abs();
                }
                let back = decode(encode(d, coverage), coverage);
                assert!((back - d).length() < 1e-9, "{d} → {back}");
                let w = grid.frames_around(d);
                assert!(w.iter().all(|(_, w)| *w >= -1e-12));
                assert!((w.iter().map(|(_, w)| w).sum::<f64>() - 1.0).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn the_hemi_map_covers_the_upper_hemisphere_only() {
        for i in 0..=20 {
            for j in 0..=20 {
                let d = decode(
                    DVec2::new(f64::from(i) / 20.0, f64::from(j) / 20.0),
                    Coverage::Hemisphere,
                );
                assert!(d.y >= -1e-12, "{d}");
            }
        }
        // Below the horizon clamps to it.
        let below = decode(
            encode(DVec3::new(0.6, -0.8, 0.0), Coverage::Hemisphere),
            Coverage::Hemisphere,
        );
        assert!(below.y.abs() < 1e-9 && below.x > 0.99, "{below}");
    }
}
