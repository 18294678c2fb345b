//! Seamless bakes: what a bake that takes each face from one view needs where two views meet
//! (beyond the papers; what mvs-texturing and OpenMVS users expect, after Waechter, Moehrle and
//! Goesele, "Let There Be Color! Large-Scale Texturing of 3D Reconstructions": the
//! photo-consistency check of its view selection, and its seam levelling — implemented here from
//! the description).
//!
//! * [`consistent`] — a face's looks (one mean colour a view that sees it) tested against
//!   their robust centre, so that a view where something passed in front (a person walking
//!   through, a reflection) is left out of that face.
//! * [`gains_and_inliers`] — per view one gain a channel that brings its looks to the faces'
//!   consensus (a view's exposure or white balance), alternating with the consistency test.
//! * [`Seams`] — the mesh edges where faces from two different sources meet (vertices welded
//!   by position, so a mesh split at its UV seams still meets itself).
//! * [`level`] — per vertex and per source meeting there, an additive colour offset, solved
//!   as one sparse least-squares problem (a screened Poisson problem on the mesh's graph):
//!   across every seam the two sides' colours agree, within a source's patch the offsets vary
//!   smoothly, and an offset no seam asks for is zero. A face's texels take its corners'
//!   offsets interpolated across it, so the correction fades away from the seams.
//!
//! Invariants: everything here is sequential and sorted, so a bake is the same on any thread
//! count; a face's offsets are those of its own source at its corners; a mesh without seams
//! gets zero offsets.

use crate::geom::Mesh;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// A look is an outlier when its colour is further from the face's robust centre than this
/// many times the looks' median distance — and than [`OUTLIER_FLOOR`].
pub const OUTLIER_SPREAD: f32 = 3.0;

/// The least relative colour distance ever called an outlier: 25 % of the centre's colour
/// (plus [`DARK`]), so that noise and mild view dependence are never rejected.
pub const OUTLIER_FLOOR: f32 = 0.25;

/// What a colour distance is relative to, added to the centre's length: a dark face's looks
/// are not rejected for a few levels of noise.
pub const DARK: f32 = 0.05;

/// Rounds of gains and consistency tests ([`gains_and_inliers`]).
const GAIN_ROUNDS: usize = 3;

/// What each look adds to both sums of a gain's ratio (linear colour): a channel darker than
/// this in a view's looks keeps a gain near 1.
pub const GAIN_FLOOR: f64 = 0.005;

/// Gains are clamped to `[1 / MAX_GAIN, MAX_GAIN]`.
pub const MAX_GAIN: f32 = 2.0;

/// Weight of the smoothness of a source's offsets along each of its faces' edges, against a
/// seam edge's agreement (weight 1).
pub const SMOOTHNESS: f64 = 0.1;

/// Weight pulling every offset toward zero (fixes what no seam decides).
const SCREEN: f64 = 1e-4;

/// Points sampled along each seam edge.
pub const SEAM_SAMPLES: usize = 8;

/// What making a bake seamless did, for its report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeamReport {
    /// Looks (a view at a face) left out as photometric outliers.
    pub outliers: usize,
    /// Mesh edges where faces from two sources meet.
    pub edges: usize,
    /// The mean colour step across the seams with the views' gains alone, 8-bit sRGB levels
    /// ([`Seams::step`]).
    pub step_gains: f64,
    /// The same after seam levelling.
    pub step_levelled: f64,
}

/// "K looks left out as photometric outliers; seams: N edges, mean step X levels (8-bit
/// sRGB) with the views' gains alone, Y levelled".
impl std::fmt::Display for SeamReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} looks left out as photometric outliers; seams: {} edges, mean step {:.2} levels \
             (8-bit sRGB) with the views' gains alone, {:.2} levelled",
            self.outliers, self.edges, self.step_gains, self.step_levelled
        )
    }
}

/// One view's look at one face: the face's mean colour as that view shows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// The view.
    pub view: u32,
    /// The face's mean colour in it (linear RGB).
    pub colour: Vec3,
    /// Whether the view sees the whole face: only whole looks are compared, since a part of a
    /// face has another mean colour than the whole.
    pub whole: bool,
}

/// The median of `values` (0 when empty; the mean of the middle two for an even count).
fn median(mut values: Vec<f32>) -> f32 {
    values.sort_by(f32::total_cmp);
    let n = values.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// The channel-wise median of `colours`.
fn centre(colours: &[Vec3]) -> Vec3 {
    let channel = |k: usize| median(colours.iter().map(|c| c[k]).collect());
    Vec3::new(channel(0), channel(1), channel(2))
}

/// Per look at one face, whether it agrees with the others: a whole look within
/// `max(OUTLIER_SPREAD × median distance, OUTLIER_FLOOR)` of the whole looks' channel-wise
/// median, in distance relative to the median's colour. Fewer than three whole looks cannot
/// outvote one another, and a partial look is not judged: they agree.
pub fn consistent(looks: &[Look]) -> Vec<bool> {
    let whole: Vec<Vec3> = looks.iter().filter(|l| l.whole).map(|l| l.colour).collect();
    if whole.len() < 3 {
        return vec![true; looks.len()];
    }
    let mid = centre(&whole);
    let scale = mid.length() + DARK;
    let distance = |c: Vec3| (c - mid).length() / scale;
    let spread = median(whole.iter().map(|&c| distance(c)).collect());
    let limit = (OUTLIER_SPREAD * spread).max(OUTLIER_FLOOR);
    looks
        .iter()
        .map(|l| !l.whole || distance(l.colour) <= limit)
        .collect()
}

/// Per view (of `views`), the gain a channel that brings its looks to the faces' consensus,
/// and per face of `looks`, which of its looks agree ([`consistent`] on the colours as the
/// gains correct them). Gains and the test alternate for a few rounds: each view's gain is its
/// agreeing whole looks' ratio of the faces' robust centres to its own colours (each sum with
/// [`GAIN_FLOOR`] a look added), clamped to
/// `[1 / MAX_GAIN, MAX_GAIN]`.
pub fn gains_and_inliers(looks: &[Vec<Look>], views: usize) -> (Vec<Vec3>, Vec<Vec<bool>>) {
    let mut gains = vec![Vec3::ONE; views];
    let mut inliers = Vec::new();
    for _ in 0..GAIN_ROUNDS {
        // Each look counts GAIN_FLOOR into both sums, so that a channel a view barely has
        // (the blue of a yellow object) keeps a gain near 1 instead of a ratio of noise.
        let mut sums = vec![(DVec3::ZERO, DVec3::ZERO); views];
        inliers = looks
            .iter()
            .map(|face| {
                let corrected: Vec<Look> = face
                    .iter()
                    .map(|l| Look {
                        colour: l.colour * gains[l.view as usize],
                        ..*l
                    })
                    .collect();
                let agree = consistent(&corrected);
                let kept: Vec<Vec3> = corrected
                    .iter()
                    .zip(&agree)
                    .filter(|(l, a)| **a && l.whole)
                    .map(|(l, _)| l.colour)
                    .collect();
                let mid = centre(&kept).as_dvec3();
                let counted = face.iter().zip(&agree).filter(|(l, a)| **a && l.whole);
                for (l, _) in counted {
                    let s = &mut sums[l.view as usize];
                    s.0 += mid + GAIN_FLOOR;
                    s.1 += l.colour.as_dvec3() + GAIN_FLOOR;
                }
                agree
            })
            .collect();
        gains = sums
            .iter()
            .map(|&(mid, own)| {
                let g = mid / own.max(DVec3::splat(1e-9));
                let g = DVec3::select(own.cmpgt(DVec3::splat(1e-9)), g, DVec3::ONE);
                g.as_vec3()
                    .clamp(Vec3::splat(1.0 / MAX_GAIN), Vec3::splat(MAX_GAIN))
            })
            .collect();
    }
    (gains, inliers)
}

/// Per vertex of `mesh`, the first vertex at the same position: the mesh welded, so that faces
/// split apart at UV or normal seams still share their edges.
pub fn welded(mesh: &Mesh) -> Vec<u32> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::new();
    mesh.positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            *first
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(i as u32)
        })
        .collect()
}

/// One edge where two faces from different sources meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Seam {
    /// The two faces.
    pub faces: [u32; 2],
    /// Per face, its local corners (0–2) at the edge's two ends, in the same order for both.
    pub corners: [[u8; 2]; 2],
}

impl Seam {
    /// The barycentric coordinates, in face `side` (0 or 1), of the point `t` along the edge.
    pub fn bary(&self, side: usize, t: f32) -> Vec3 {
        let mut b = Vec3::ZERO;
        let [a, c] = self.corners[side];
        b[a as usize] = 1.0 - t;
        b[c as usize] = t;
        b
    }
}

/// Where faces from different sources meet on a mesh.
#[derive(Clone, Debug)]
pub struct Seams {
    /// Per vertex, its welded index ([`welded`]).
    pub welded: Vec<u32>,
    /// The seam edges, in the order of their welded vertex pairs.
    pub edges: Vec<Seam>,
}

impl Seams {
    /// The seams of `mesh` whose faces come from `labels` (per face: its source; `None` for a
    /// face nothing gave, which has no seam).
    pub fn find(mesh: &Mesh, labels: &[Option<u32>]) -> Seams {
        let welded = welded(mesh);
        // Every labelled face's edges, keyed by their welded ends (smaller first).
        let mut edges: Vec<((u32, u32), u32, [u8; 2])> = Vec::new();
        for (f, tri) in mesh.triangles.iter().enumerate() {
            if labels.get(f).copied().flatten().is_none() {
                continue;
            }
            for k in 0..3u8 {
                let (a, b) = (k, (k + 1) % 3);
                let (wa, wb) = (
                    welded[tri[a as usize] as usize],
                    welded[tri[b as usize] as usize],
                );
                if wa == wb {
                    continue;
                }
                let corners = if wa < wb { [a, b] } else { [b, a] };
                edges.push(((wa.min(wb), wa.max(wb)), f as u32, corners));
            }
        }
        edges.sort_unstable();
        let mut seams = Vec::new();
        for group in edges.chunk_by(|a, b| a.0 == b.0) {
            for (i, &(_, f1, c1)) in group.iter().enumerate() {
                for &(_, f2, c2) in &group[i + 1..] {
                    if labels[f1 as usize] != labels[f2 as usize] {
                        seams.push(Seam {
                            faces: [f1, f2],
                            corners: [c1, c2],
                        });
                    }
                }
            }
        }
        Seams {
            welded,
            edges: seams,
        }
    }

    /// The mean colour step across the seams, in 8-bit sRGB levels (the mean over channels of
    /// the encoded difference): `sample(face, barycentrics)` is the bake's colour there, and the
    /// two sides are compared at [`SEAM_SAMPLES`] points along each edge. 0 without seams.
    pub fn step(&self, sample: impl Fn(usize, Vec3) -> Option<Vec3>) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for s in &self.edges {
            for j in 0..SEAM_SAMPLES {
                let t = (j as f32 + 0.5) / SEAM_SAMPLES as f32;
                let (Some(a), Some(b)) = (
                    sample(s.faces[0] as usize, s.bary(0, t)),
                    sample(s.faces[1] as usize, s.bary(1, t)),
                ) else {
                    continue;
                };
                let encode = |c: Vec3| c.to_array().map(crate::frame::linear_to_srgb);
                let (a, b) = (encode(a), encode(b));
                sum += (0..3).map(|k| f64::from((a[k] - b[k]).abs())).sum::<f64>() * 255.0 / 3.0;
                n += 1;
            }
        }
        if n == 0 { 0.0 } else { sum / n as f64 }
    }
}

/// Per vertex and per source meeting there, the colour offset that levels the seams.
#[derive(Clone, Debug, Default)]
pub struct Offsets {
    /// Per (welded vertex, source), the offset's index.
    index: HashMap<(u32, u32), usize>,
    /// The offsets (linear RGB).
    values: Vec<Vec3>,
}

impl Offsets {
    /// The offset of face `face` of `mesh` (from source `label`) at barycentrics `bary`: its
    /// corners' offsets for that source, interpolated; zero where none was solved.
    pub fn at(&self, mesh: &Mesh, welded: &[u32], face: usize, label: u32, bary: Vec3) -> Vec3 {
        let tri = mesh.triangles[face];
        (0..3)
            .filter_map(|k| {
                let i = self.index.get(&(welded[tri[k] as usize], label))?;
                Some(self.values[*i] * bary[k])
            })
            .sum()
    }

    /// How many offsets were solved.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether none was.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// A symmetric sparse matrix, row by row.
struct Sparse {
    /// Row `i`'s entries are `start[i]..start[i + 1]`.
    start: Vec<usize>,
    column: Vec<u32>,
    value: Vec<f64>,
}

impl Sparse {
    /// The `n × n` matrix summing `entries` `(row, column, value)`.
    fn from_entries(n: usize, mut entries: Vec<(u32, u32, f64)>) -> Sparse {
        entries.sort_unstable_by_key(|e| (e.0, e.1));
        let mut m = Sparse {
            start: vec![0; n + 1],
            column: Vec::new(),
            value: Vec::new(),
        };
        for group in entries.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
            m.column.push(group[0].1);
            m.value.push(group.iter().map(|e| e.2).sum());
            m.start[group[0].0 as usize + 1] += 1;
        }
        for i in 0..n {
            m.start[i + 1] += m.start[i];
        }
        m
    }

    fn times(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            let r = self.start[i]..self.start[i + 1];
            *yi = self.column[r.clone()]
                .iter()
                .zip(&self.value[r])
                .map(|(&j, &v)| v * x[j as usize])
                .sum();
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        (0..self.start.len() - 1)
            .map(|i| {
                let r = self.start[i]..self.start[i + 1];
                self.column[r.clone()]
                    .iter()
                    .zip(&self.value[r])
                    .find(|(j, _)| **j as usize == i)
                    .map_or(1.0, |(_, v)| *v)
            })
            .collect()
    }

    /// `x` with `self · x = b`, by conjugate gradients preconditioned by the diagonal, to a
    /// residual of `1e-8 |b|` or a bounded number of steps.
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let d = self.diagonal();
        let mut x = vec![0.0; n];
        let mut r = b.to_vec();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let goal = 1e-16 * dot(b, b);
        let mut z: Vec<f64> = r.iter().zip(&d).map(|(r, d)| r / d).collect();
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let mut ap = vec![0.0; n];
        for _ in 0..(4 * n).clamp(64, 4000) {
            if dot(&r, &r) <= goal {
                break;
            }
            self.times(&p, &mut ap);
            let pap = dot(&p, &ap);
            if pap <= 0.0 {
                break;
            }
            let alpha = rz / pap;
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            z = r.iter().zip(&d).map(|(r, d)| r / d).collect();
            let next = dot(&r, &z);
            let beta = next / rz;
            rz = next;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        x
    }
}

/// The offsets that level `seams` of `mesh`, whose faces come from `labels`:
/// `sample(face, barycentrics)` is the bake's colour (before levelling) there. Minimizes, per
/// channel, the squared disagreement of the two sides at [`SEAM_SAMPLES`] points along every
/// seam edge (each edge weight 1), plus [`SMOOTHNESS`] times the squared difference of a
/// source's offsets along each edge of its faces, plus a small pull of every offset to zero.
pub fn level(
    mesh: &Mesh,
    labels: &[Option<u32>],
    seams: &Seams,
    sample: impl Fn(usize, Vec3) -> Option<Vec3>,
) -> Offsets {
    let mut offsets = Offsets::default();
    if seams.edges.is_empty() {
        return offsets;
    }
    let welded = &seams.welded;
    let mut key = |face: usize, k: usize, label: u32| {
        let v = welded[mesh.triangles[face][k] as usize];
        let n = offsets.index.len();
        *offsets.index.entry((v, label)).or_insert(n) as u32
    };
    let mut entries: Vec<(u32, u32, f64)> = Vec::new();
    let mut rhs: Vec<(u32, DVec3)> = Vec::new();
    // Smoothness within each source's faces; the keys are made in face order.
    for (f, label) in labels.iter().take(mesh.triangle_count()).enumerate() {
        let Some(label) = *label else { continue };
        let k = [0, 1, 2].map(|c| key(f, c, label));
        for c in 0..3 {
            let (a, b) = (k[c], k[(c + 1) % 3]);
            if a == b {
                continue;
            }
            entries.extend([
                (a, a, SMOOTHNESS),
                (b, b, SMOOTHNESS),
                (a, b, -SMOOTHNESS),
                (b, a, -SMOOTHNESS),
            ]);
        }
    }
    // Agreement across each seam: (1 - t) g(a) + t g(b) on one side minus the same on the
    // other equals the other side's colour minus this side's.
    let weight = 1.0 / SEAM_SAMPLES as f64;
    for s in &seams.edges {
        let [f0, f1] = s.faces.map(|f| f as usize);
        let label = |f: usize| labels.get(f).copied().flatten();
        let (Some(l0), Some(l1)) = (label(f0), label(f1)) else {
            continue;
        };
        // The offsets at the edge's ends on each side (seams found for other labels have none).
        let ends = |f: usize, side: usize, label: u32| -> Option<[u32; 2]> {
            let [a, b] = s.corners[side].map(|c| {
                let v = welded[mesh.triangles[f][c as usize] as usize];
                offsets.index.get(&(v, label)).map(|&i| i as u32)
            });
            Some([a?, b?])
        };
        let (Some(e0), Some(e1)) = (ends(f0, 0, l0), ends(f1, 1, l1)) else {
            continue;
        };
        for j in 0..SEAM_SAMPLES {
            let t = (j as f32 + 0.5) / SEAM_SAMPLES as f32;
            let (Some(c0), Some(c1)) = (sample(f0, s.bary(0, t)), sample(f1, s.bary(1, t))) else {
                continue;
            };
            let t = f64::from(t);
            let row = [(e0[0], 1.0 - t), (e0[1], t), (e1[0], t - 1.0), (e1[1], -t)];
            for &(i, a) in &row {
                for &(j, b) in &row {
                    entries.push((i, j, weight * a * b));
                }
                rhs.push((i, weight * a * (c1 - c0).as_dvec3()));
            }
        }
    }
    let n = offsets.index.len();
    entries.extend((0..n as u32).map(|i| (i, i, SCREEN)));
    let matrix = Sparse::from_entries(n, entries);
    let mut b = vec![DVec3::ZERO; n];
    for (i, v) in rhs {
        b[i as usize] += v;
    }
    let channels: Vec<Vec<f64>> = (0..3)
        .map(|k| matrix.solve(&b.iter().map(|v| v[k]).collect::<Vec<f64>>()))
        .collect();
    offsets.values = (0..n)
        .map(|i| DVec3::new(channels[0][i], channels[1][i], channels[2][i]).as_vec3())
        .collect();
    offsets
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_look_unlike_the_others_is_an_outlier_and_two_looks_always_agree() {
        let grey = Vec3::splat(0.4);
        let colours = [
            grey,
            grey * 1.05,
            grey * 0.97,
            Vec3::new(0.9, 0.1, 0.1),
            grey,
        ];
        let mut looks: Vec<Look> = (colours.iter().enumerate())
            .map(|(v, &colour)| Look {
                view: v as u32,
                colour,
                whole: true,
            })
            .collect();
        assert_eq!(consistent(&looks), [true, true, true, false, true]);
        assert_eq!(consistent(&looks[2..4]), [true, true]);
        // A partial look is not judged, nor does it judge.
        looks[3].whole = false;
        looks[4].colour = Vec3::new(0.1, 0.1, 0.9);
        assert_eq!(consistent(&looks), [true, true, true, true, false]);
        // Two whole looks cannot outvote each other.
        looks[0].whole = false;
        looks[1].whole = false;
        assert_eq!(consistent(&looks), [true; 5]);
    }

    #[test]
    fn gains_take_out_a_views_exposure() {
        // Three views of ten faces; view 1 is 50 % too bright, and view 2 sees something in
        // front of face 4.
        let looks: Vec<Vec<Look>> = (0..10)
            .map(|f| {
                let c = Vec3::new(0.1 + 0.05 * f as f32, 0.3, 0.2);
                (0..3)
                    .map(|v| Look {
                        view: v,
                        whole: true,
                        colour: match (v, f) {
                            (1, _) => c * 1.5,
                            (2, 4) => Vec3::new(0.9, 0.9, 0.0),
                            _ => c,
                        },
                    })
                    .collect()
            })
            .collect();
        let (gains, inliers) = gains_and_inliers(&looks, 3);
        assert!(
            (gains[1] * 1.5 - gains[0]).abs().max_element() < 0.01,
            "{gains:?}"
        );
        assert!(
            (gains[2] - gains[0]).abs().max_element() < 0.01,
            "{gains:?}"
        );
        assert_eq!(inliers[4], [true, true, false]);
        assert!(
            inliers
                .iter()
                .enumerate()
                .all(|(f, i)| f == 4 || i.iter().all(|&a| a))
        );
    }

    /// Two triangles sharing an edge (0–2), split apart like a UV seam (vertices repeated).
    fn square() -> Mesh {
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let mut mesh = Mesh {
            positions: p.to_vec(),
            triangles: vec![[0, 1, 2], [3, 4, 5]],
            ..Mesh::default()
        };
        mesh.compute_normals();
        mesh
    }

    #[test]
    fn a_seam_between_two_sources_is_levelled_and_one_source_has_none() {
        let mesh = square();
        let same = Seams::find(&mesh, &[Some(0), Some(0)]);
        assert!(same.edges.is_empty());
        let labels = [Some(0), Some(1)];
        let seams = Seams::find(&mesh, &labels);
        assert_eq!(seams.edges.len(), 1);
        // The two sides differ by a step that grows along the seam.
        let colour = |f: usize, b: Vec3| {
            let along = b.x + b.y;
            Some(
                Vec3::splat(0.3)
                    + if f == 1 {
                        Vec3::splat(0.1 * along)
                    } else {
                        Vec3::ZERO
                    },
            )
        };
        let before = seams.step(colour);
        let offsets = level(&mesh, &labels, &seams, colour);
        let levelled = |f: usize, b: Vec3| {
            Some(colour(f, b)? + offsets.at(&mesh, &seams.welded, f, labels[f]?, b))
        };
        let after = seams.step(levelled);
        println!("seam step {before:.2} → {after:.2} levels");
        assert!(before > 5.0 && after < 0.05 * before, "{before} → {after}");
    }
}
