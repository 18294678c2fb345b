//! Deterministic random numbers and surface sampling, for replayable tests and measurements.

use super::{Mesh, Ray};
use glam::Vec3;

/// SplitMix64 (Steele, Lea and Flood 2014): a small, fast, seedable generator.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator with this seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[0, 1)`.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3 {
        let z = 2.0 * self.next_f32() - 1.0;
        let phi = std::f32::consts::TAU * self.next_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// `count` points spread uniformly by area over the mesh's surface.
pub fn sample_surface(mesh: &Mesh, count: usize, seed: u64) -> Vec<Vec3> {
    let mut cdf = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0f64;
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(t);
        total += ((b - a).cross(c - a).length() * 0.5) as f64;
        cdf.push(total);
    }
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .filter_map(|_| {
            let x = rng.next_u64() as f64 / u64::MAX as f64 * total;
            let t = cdf
                .partition_point(|&c| c < x)
                .min(cdf.len().checked_sub(1)?);
            let [a, b, c] = mesh.corners(t);
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            Some(a + (b - a) * u + (c - a) * v)
        })
        .collect()
}

/// `count` rays from points spread over a sphere (`center`, `radius`), each aimed at a point of
/// the box `target` (deterministic for a given `seed`).
pub fn sphere_rays(
    center: Vec3,
    radius: f32,
    target: super::Aabb,
    count: usize,
    seed: u64,
) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let o = center + rng.unit_vector() * radius;
            let aim = target.min
                + target.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            Ray::new(o, (aim - o).normalize_or(Vec3::Y))
        })
        .collect()
}
