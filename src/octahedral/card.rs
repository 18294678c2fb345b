//! The card an octahedral impostor is drawn on, cut to the object's outline (the "cut-out card"
//! of engines' impostor bakers): a convex polygon of at most [`MAX_VERTICES`] vertices in the
//! card's own axes, in units of the bounding radius, that a runtime draws instead of the square
//! of the sphere's diameter, to spare the pixels where no frame can find the object.
//!
//! The runtimes turn the card to face the eye, its axes those [`super::mapping::frame_basis`]
//! gives the direction to the eye, and place it tangent to the bounding sphere on the eye's side.
//! Every point of the object then projects, from the eye, onto the card no farther from its
//! centre than its orthographic projection along that direction, and in the same direction: a
//! convex outline round the card's centre that holds every orthographic silhouette holds every
//! perspective one. Those axes turn through every angle as the view goes round the pole, so the
//! outline is made of edges at [`MAX_VERTICES`] fixed angles θ, each pushed out to the object's
//! extent over all the 3-D directions its normal takes: `cos θ · right + sin θ · up` over every
//! view is the unit vectors whose vertical part lies between 0 and `sin θ`, widened by the pole
//! cap where `frame_basis` changes reference. The extent over that band is exact per vertex (the
//! band's best direction is the vertex's own direction, clamped into the band), plus a margin of
//! [`MARGIN_TEXELS`] frame texels for coverage that the frames' filtering spreads past the true
//! silhouette. docs/conventions.md §8.5.
//!
//! Invariants: the outline is convex, counter-clockwise, holds the card's centre, and lies in the
//! square `[-1, 1]²` the whole card spans.

use crate::geom::clip_polygon;
use glam::{DVec2, Vec3};

/// Most vertices of an outline (the number of edge directions tried).
pub const MAX_VERTICES: usize = 8;

/// Frame texels of margin round the silhouette: bilinear coverage reaches half a texel past the
/// mesh, and the three frames' parallax-corrected lookups about as much again.
pub const MARGIN_TEXELS: f64 = 1.0;

/// The vertical extent of `frame_basis`'s pole cap, where the card's axes take their reference
/// from `z` instead of `y`: `sin(acos(0.999))`.
const CAP: f64 = 0.044_710_2;

/// A card outline: convex, counter-clockwise, in units of the bounding radius.
#[derive(Clone, Debug, PartialEq)]
pub struct Card {
    outline: Vec<[f32; 2]>,
}

impl Default for Card {
    /// The whole square of the sphere's diameter.
    fn default() -> Self {
        Self {
            outline: vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]],
        }
    }
}

impl Card {
    /// The outline round `points` (the object's vertices, in the bake's space) for a bounding
    /// sphere `(centre, radius)` and frames of `frame_size` texels a side.
    pub fn around(
        points: impl Iterator<Item = Vec3> + Clone,
        centre: Vec3,
        radius: f32,
        frame_size: u32,
    ) -> Self {
        let r = f64::from(radius).max(1e-30);
        let margin = MARGIN_TEXELS * 2.0 / f64::from(frame_size.max(1));
        let mut polygon: Vec<DVec2> = Card::default()
            .outline
            .iter()
            .map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])))
            .collect();
        for k in 0..MAX_VERTICES {
            let theta = std::f64::consts::TAU * k as f64 / MAX_VERTICES as f64;
            let band = band(theta.sin());
            let extent = points
                .clone()
                .map(|p| reach((p - centre).as_dvec3() / r, band))
                .fold(0.0f64, f64::max);
            // Keep x·cos θ + y·sin θ ≤ extent + margin.
            let (c, s) = (theta.cos(), theta.sin());
            polygon = clip_polygon(
                &polygon,
                |p| extent + margin - (p.x * c + p.y * s),
                |a, b, t| a.lerp(*b, t),
            );
        }
        let outline: Vec<[f32; 2]> = polygon.iter().map(|p| [p.x as f32, p.y as f32]).collect();
        if outline.len() < 3 {
            return Self::default();
        }
        Self { outline }
    }

    /// An outline as a file holds it, checked: 3 to [`MAX_VERTICES`] finite points in
    /// `[-1, 1]²`, convex, counter-clockwise, round the centre. `None` otherwise.
    pub fn from_outline(outline: Vec<[f32; 2]>) -> Option<Self> {
        let n = outline.len();
        if !(3..=MAX_VERTICES).contains(&n)
            || outline
                .iter()
                .any(|p| p.iter().any(|c| !c.is_finite() || c.abs() > 1.0 + 1e-5))
        {
            return None;
        }
        // The centre lies left of (or on) every edge: convex, counter-clockwise, round it.
        let holds_centre = (0..n).all(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0] >= -1e-6
        });
        let convex = (0..n).all(|i| {
            let (a, b, c) = (outline[i], outline[(i + 1) % n], outline[(i + 2) % n]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) >= -1e-6
        });
        (holds_centre && convex).then_some(Self { outline })
    }

    /// The vertices, counter-clockwise.
    pub fn outline(&self) -> &[[f32; 2]] {
        &self.outline
    }

    /// The vertices in triangle-strip order (0, 1, n−1, 2, n−2, …): one strip draws the
    /// convex polygon.
    pub fn strip(&self) -> Vec<[f32; 2]> {
        let n = self.outline.len();
        let (mut lo, mut hi) = (1, n - 1);
        let mut out = vec![self.outline[0]];
        while lo <= hi {
            out.push(self.outline[lo]);
            if lo != hi {
                out.push(self.outline[hi]);
            }
            (lo, hi) = (lo + 1, hi - 1);
        }
        out
    }

    /// The share of the whole square's area the outline covers (1 for the square).
    pub fn area_share(&self) -> f64 {
        let n = self.outline.len();
        let twice: f64 = (0..n)
            .map(|i| {
                let (a, b) = (self.outline[i], self.outline[(i + 1) % n]);
                f64::from(a[0]) * f64::from(b[1]) - f64::from(a[1]) * f64::from(b[0])
            })
            .sum();
        twice / 2.0 / 4.0
    }

    /// Whether the card point `(x, y)` (units of the radius, the card's axes) is inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let n = self.outline.len();
        (0..n).all(|i| {
            let (a, b) = (self.outline[i], self.outline[(i + 1) % n]);
            let (ax, ay) = (f64::from(a[0]), f64::from(a[1]));
            (f64::from(b[0]) - ax) * (y - ay) - (f64::from(b[1]) - ay) * (x - ax) >= 0.0
        })
    }
}

/// The range of vertical parts of the directions an edge at angle θ faces over every view.
fn band(sin_theta: f64) -> (f64, f64) {
    (
        (sin_theta.min(0.0) - CAP).max(-1.0),
        (sin_theta.max(0.0) + CAP).min(1.0),
    )
}

/// The farthest `q` reaches along a unit direction whose vertical part lies in `band`: the
/// direction nearest `q`'s own (the reach, `ρ·√(1−y²) + q_y·y`, is concave in `y`).
fn reach(q: glam::DVec3, (lo, hi): (f64, f64)) -> f64 {
    let length = q.length();
    if length <= 0.0 {
        return 0.0;
    }
    let y = (q.y / length).clamp(lo, hi);
    let rho = (q.x * q.x + q.z * q.z).sqrt();
    rho * (1.0 - y * y).max(0.0).sqrt() + q.y * y
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octahedral::mapping::frame_basis;
    use glam::DVec3;

    /// A tall thin box: the outline is a narrow upright shape, not the square.
    fn pole() -> Vec<Vec3> {
        let mut v = Vec::new();
        for x in [-0.1, 0.1] {
            for y in [-1.0, 1.0] {
                for z in [-0.1, 0.1] {
                    v.push(Vec3::new(x, y, z));
                }
            }
        }
        v
    }

    #[test]
    fn every_view_of_the_object_lies_inside_the_outline() {
        let points = pole();
        let radius = points.iter().map(|p| p.length()).fold(0.0, f32::max);
        let card = Card::around(points.iter().copied(), Vec3::ZERO, radius, 64);
        assert!(card.outline().len() <= MAX_VERTICES);
        assert!(card.area_share() < 0.5, "{}", card.area_share());
        assert_eq!(
            Card::from_outline(card.outline().to_vec()),
            Some(card.clone())
        );
        // Views all round, the poles and their caps included.
        let mut views = vec![DVec3::Y, -DVec3::Y];
        for e in -90..=90 {
            for a in 0..72 {
                let (e, a) = ((e as f64).to_radians(), (a as f64 * 5.0).to_radians());
                views.push(DVec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin()));
            }
        }
        for v in views {
            let (right, up) = frame_basis(v);
            for p in &points {
                let q = p.as_dvec3() / f64::from(radius);
                let (x, y) = (q.dot(right), q.dot(up));
                assert!(card.contains(x, y), "{p} from {v}: ({x}, {y}) outside");
            }
        }
    }

    #[test]
    fn the_strip_draws_the_polygon() {
        let card = Card::default();
        assert_eq!(
            card.strip(),
            vec![[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [1.0, 1.0]]
        );
        assert_eq!(card.area_share(), 1.0);
        assert!(Card::from_outline(vec![[1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]]).is_none());
    }
}
