//! Rasterizer properties: watertightness under the top-left rule, depth and barycentrics.

use super::*;
use crate::camera::ImagePoint;
use crate::geom::Material;
use glam::{DVec2, DVec3, Vec2};

/// Image space as a camera: world `(x, y)` is pixel `(u, v)`, `gd = 1/z`.
struct ScreenSpace(u32, u32);

impl Projection for ScreenSpace {
    fn resolution(&self) -> (u32, u32) {
        (self.0, self.1)
    }
    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        (p.z > 0.0).then(|| ImagePoint {
            uv: p.truncate(),
            gd: 1.0 / p.z,
            inv_w: 1.0 / p.z,
        })
    }
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        uv.extend(1.0 / gd)
    }
    fn clip_distance(&self, p: DVec3) -> f64 {
        p.z - 1e-3
    }
    fn midpoint_deviation_bound(&self, _: &[ImagePoint]) -> f64 {
        0.0
    }
}

fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    let n = triangles.len();
    Mesh {
        normals: vec![Vec3::Z; positions.len()],
        positions,
        uvs: None,
        triangles,
        face_material: vec![0; n],
        materials: vec![Material::default()],
    }
}

/// Per-pixel coverage counts, each triangle rasterized on its own so the depth test hides nothing.
fn coverage(cam: &ScreenSpace, m: &Mesh) -> Vec<u32> {
    let mut count = vec![0u32; (cam.0 * cam.1) as usize];
    for t in 0..m.triangles.len() {
        let single = mesh(m.positions.clone(), vec![m.triangles[t]]);
        let (target, _) = rasterize(cam, &[&single], &NoAttributes, ()).unwrap();
        for (c, id) in count.iter_mut().zip(target.item.pixels()) {
            *c += (!id.is_none()) as u32;
        }
    }
    count
}

/// Replayable jitter in `[-0.5, 0.5)`.
fn jitter(i: u32) -> f32 {
    (i.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32 - 0.5
}

#[test]
fn grid_sharing_edges_covers_each_pixel_exactly_once() {
    // An 8 × 8 grid of quads over [4.5, 59.5]²: the outer corners sit on pixel centres, interior
    // vertices are jittered (some land exactly on centres too), and every quad is split in two.
    let cam = ScreenSpace(64, 64);
    let n = 8;
    let step = 55.0 / n as f32;
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let mut v = Vec3::new(4.5 + i as f32 * step, 4.5 + j as f32 * step, 1.0);
            if i > 0 && i < n && j > 0 && j < n {
                let k = j * (n + 1) + i;
                v.x += if k % 3 == 0 {
                    0.0
                } else {
                    jitter(k) * step * 0.6
                };
                v.y += if k % 3 == 0 {
                    0.0
                } else {
                    jitter(k + 1000) * step * 0.6
                };
                if k % 3 == 0 {
                    v.x = v.x.floor() + 0.5;
                    v.y = v.y.floor() + 0.5;
                }
            }
            p.push(v);
        }
    }
    let idx = |i: u32, j: u32| j * (n + 1) + i;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            tris.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
            tris.push([idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)]); // opposite winding on purpose
        }
    }
    let count = coverage(&cam, &mesh(p, tris));
    for y in 0..64 {
        for x in 0..64 {
            // Left and top borders (on pixel centres) are owned; right and bottom are not.
            let inside = (4..59).contains(&x) && (4..59).contains(&y);
            assert_eq!(count[y * 64 + x], inside as u32, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn fan_around_a_pixel_centre_covers_each_pixel_exactly_once() {
    let cam = ScreenSpace(64, 64);
    let c = Vec3::new(32.5, 32.5, 1.0);
    let k = 13;
    let mut p = vec![c];
    for i in 0..k {
        let a = i as f32 / k as f32 * std::f32::consts::TAU;
        p.push(c + Vec3::new(a.cos(), a.sin(), 0.0) * 25.0);
    }
    let tris = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
    let m = mesh(p.clone(), tris);
    let count = coverage(&cam, &m);
    for y in 0..64u32 {
        for x in 0..64u32 {
            let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            // Signed distance to the outer polygon (negative inside).
            let mut dist = f32::NEG_INFINITY;
            for i in 0..k as usize {
                let (a, b) = (p[1 + i].truncate(), p[1 + (i + 1) % k as usize].truncate());
                let n = Vec2::new(b.y - a.y, a.x - b.x).normalize();
                let n = if n.dot(c.truncate() - a) > 0.0 { -n } else { n };
                dist = dist.max(n.dot(q - a));
            }
            let got = count[(y * 64 + x) as usize];
            assert!(got <= 1, "pixel ({x}, {y}) covered {got} times");
            if dist < -1e-3 {
                assert_eq!(got, 1, "pixel ({x}, {y}) missed");
            } else if dist > 1e-3 {
                assert_eq!(got, 0, "pixel ({x}, {y}) outside covered");
            }
        }
    }
}

#[test]
fn depth_test_keeps_the_nearer_triangle_and_ties_keep_the_first() {
    let cam = ScreenSpace(16, 16);
    let quad = |z: f32| {
        vec![
            Vec3::new(0.0, 0.0, z),
            Vec3::new(16.0, 0.0, z),
            Vec3::new(0.0, 16.0, z),
        ]
    };
    let far = mesh(quad(2.0), vec![[0, 1, 2]]);
    let near = mesh(quad(1.0), vec![[0, 1, 2]]);
    let (t, _) = rasterize(&cam, &[&far, &near, &near], &NoAttributes, ()).unwrap();
    assert_eq!(
        t.item.get(2, 2),
        ItemId {
            object: 1,
            triangle: 0
        }
    );
    assert_eq!(t.gd.get(2, 2), 1.0);
    assert_eq!(t.gd.get(15, 15), 0.0);
}

/// A 32 × 32 perspective camera at the origin looking along +z, with unit focal length and no
/// image offset (a world point (x, y, z) images at (x/z, y/z)), its near plane at z = 10⁻³.
struct Persp;

impl Projection for Persp {
    fn resolution(&self) -> (u32, u32) {
        (32, 32)
    }
    fn project(&self, p: DVec3) -> Option<ImagePoint> {
        (p.z > 0.0).then(|| ImagePoint {
            uv: DVec2::new(p.x / p.z, p.y / p.z),
            gd: 1.0 / p.z,
            inv_w: 1.0 / p.z,
        })
    }
    fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        uv.extend(1.0) / gd
    }
    fn clip_distance(&self, p: DVec3) -> f64 {
        p.z - 1e-3
    }
    fn midpoint_deviation_bound(&self, _: &[ImagePoint]) -> f64 {
        0.0
    }
}

#[test]
fn barycentrics_are_perspective_correct() {
    // A tilted triangle: interpolating world positions with the fragment barycentrics must land
    // on the point the pixel's ray meets, i.e. unproject(uv, gd).
    let p = [
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(31.0, 2.0, 4.0),
        Vec3::new(3.0, 30.0, 9.0),
    ];
    // In ScreenSpace, a world point (x, y, z) projects to (x, y): make the corners' image
    // positions differ from their x, y by storing world = (u·z, v·z, z) (a true perspective).
    let world: Vec<Vec3> = p
        .iter()
        .map(|v| Vec3::new(v.x * v.z, v.y * v.z, v.z))
        .collect();
    let m = mesh(world.clone(), vec![[0, 1, 2]]);
    let (t, stats) = rasterize(&Persp, &[&m], &StoreFragment, None).unwrap();
    assert!(stats.written > 100);
    let error = largest_position_error(&world, &t.attributes);
    assert!(error < 1e-4, "{error}");
    for f in t.attributes.pixels().iter().flatten() {
        assert!((f.bary.element_sum() - 1.0).abs() < 1e-5);
    }
}

/// The largest distance, relative to the point's distance from the camera, between a stored
/// fragment's barycentric blend of `world` (the drawn triangle's corners) and the point its
/// pixel's ray meets at its `gd` through [`Persp`].
fn largest_position_error(world: &[Vec3], fragments: &Image<Option<Fragment>>) -> f32 {
    fragments
        .pixels()
        .iter()
        .flatten()
        .map(|f| {
            let interp = world[0] * f.bary.x + world[1] * f.bary.y + world[2] * f.bary.z;
            let uv = crate::frame::pixel_centre(f.x as f64, f.y as f64);
            let exact = Persp.unproject(uv, f.gd as f64).as_vec3();
            (interp - exact).length() / exact.length()
        })
        .fold(0.0, f32::max)
}

#[test]
fn barycentrics_stay_perspective_correct_through_near_and_guard_band_clipping() {
    // A corner behind the camera: clipped at the near plane, the triangle's new corners project
    // millions of pixels away and are clipped again to the guard band. Every corner made on the
    // way must carry its own 1/w, or the barycentrics — hence positions, normals and texture
    // coordinates — go wrong while the depth stays right (an impostor of a room, seen from
    // inside, stored its floor's points metres away).
    let world = vec![
        Vec3::new(2.0, 2.0, 2.0),
        Vec3::new(90.0, 6.0, 3.0),
        Vec3::new(5000.0, 3000.0, -1.0),
    ];
    let near_corner = Persp
        .project(DVec3::new(2.0 + 4998.0 * 0.666, 2.0 + 2998.0 * 0.666, 1e-3))
        .unwrap();
    assert!(
        near_corner.uv.x > 2.0 * setup::GUARD,
        "the test must reach the guard band"
    );
    let m = mesh(world.clone(), vec![[0, 1, 2]]);
    let (t, stats) = rasterize(&Persp, &[&m], &StoreFragment, None).unwrap();
    assert!(stats.written > 100, "{stats:?}");
    let error = largest_position_error(&world, &t.attributes);
    assert!(error < 1e-3, "{error}");
}

#[test]
fn triangles_crossing_the_near_plane_are_clipped_not_dropped() {
    let cam = ScreenSpace(16, 16);
    // One corner behind the camera: the visible part still covers pixels, with positive gd.
    let m = mesh(
        vec![
            Vec3::new(2.0, 2.0, 1.0),
            Vec3::new(14.0, 2.0, 1.0),
            Vec3::new(2.0, 14.0, -1.0),
        ],
        vec![[0, 1, 2]],
    );
    let (t, stats) = rasterize(&cam, &[&m], &NoAttributes, ()).unwrap();
    assert!(stats.written > 10);
    assert!(t.gd.pixels().iter().all(|&g| g >= 0.0 && g.is_finite()));
    // Entirely behind: nothing.
    let behind = mesh(
        vec![
            Vec3::new(2.0, 2.0, -1.0),
            Vec3::new(14.0, 2.0, -1.0),
            Vec3::new(2.0, 14.0, -1.0),
        ],
        vec![[0, 1, 2]],
    );
    let (_, stats) = rasterize(&cam, &[&behind], &NoAttributes, ()).unwrap();
    assert_eq!(stats.written, 0);
}

#[test]
fn huge_triangles_are_guard_band_clipped() {
    // Corners millions of pixels away must neither overflow nor lose the on-screen part.
    let cam = ScreenSpace(16, 16);
    let m = mesh(
        vec![
            Vec3::new(-1e8, -1e8, 1.0),
            Vec3::new(1e8, -1e8, 1.0),
            Vec3::new(0.0, 1e8, 1.0),
        ],
        vec![[0, 1, 2]],
    );
    let (t, _) = rasterize(&cam, &[&m], &NoAttributes, ()).unwrap();
    assert!(t.item.pixels().iter().all(|id| !id.is_none()));
}

#[test]
fn rasterizing_into_a_used_target_equals_a_fresh_rasterization() {
    let cam = ScreenSpace(64, 64);
    let big = mesh(
        vec![
            Vec3::new(2.0, 2.0, 1.0),
            Vec3::new(62.0, 3.0, 1.0),
            Vec3::new(30.0, 61.0, 1.0),
        ],
        vec![[0, 1, 2]],
    );
    let small = mesh(
        vec![
            Vec3::new(20.0, 20.0, 2.0),
            Vec3::new(40.0, 22.0, 2.0),
            Vec3::new(30.0, 35.0, 2.0),
        ],
        vec![[0, 1, 2]],
    );
    let (mut target, _) = rasterize(&cam, &[&big], &StoreFragment, None).unwrap();
    rasterize_into(&cam, &[&small], &StoreFragment, None, &mut target).unwrap();
    let (fresh, _) = rasterize(&cam, &[&small], &StoreFragment, None).unwrap();
    assert!(target.gd == fresh.gd && target.item == fresh.item);
    assert!(target.attributes == fresh.attributes);
}

/// Small random triangles at random depths, in `count` triangles.
fn scattered_triangles(count: u32, seed: u64) -> Mesh {
    let mut rng = crate::geom::SplitMix64::new(seed);
    let mut positions = Vec::new();
    for _ in 0..count {
        let c = Vec3::new(rng.next_f32() * 64.0, rng.next_f32() * 64.0, 1.0);
        let z = 1.0 + rng.next_f32() * 4.0;
        for _ in 0..3 {
            let d = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 0.0) * 24.0;
            positions.push(Vec3::new(c.x + d.x, c.y + d.y, z));
        }
    }
    mesh(
        positions,
        (0..count).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
    )
}

#[test]
fn binning_across_chunks_and_objects_keeps_input_order() {
    // Two objects whose triangles span several setup chunks and bands: the result must equal
    // drawing every triangle alone and compositing in input order (strictly nearer wins, so
    // the earlier of two equal depths stays).
    let cam = ScreenSpace(64, 64);
    let (a, b) = (scattered_triangles(700, 1), scattered_triangles(450, 2));
    let (both, stats) = rasterize(&cam, &[&a, &b], &NoAttributes, ()).unwrap();
    assert_eq!(stats.triangles_in, 1150);
    let mut gd = vec![0.0f32; 64 * 64];
    let mut item = vec![ItemId::NONE; 64 * 64];
    for (o, m) in [&a, &b].into_iter().enumerate() {
        for t in 0..m.triangles.len() {
            let one = mesh(m.corners(t).to_vec(), vec![[0, 1, 2]]);
            let (alone, _) = rasterize(&cam, &[&one], &NoAttributes, ()).unwrap();
            for (i, &g) in alone.gd.pixels().iter().enumerate() {
                if g > gd[i] {
                    gd[i] = g;
                    item[i] = ItemId {
                        object: o as u32,
                        triangle: t as u32,
                    };
                }
            }
        }
    }
    assert!(both.gd.pixels() == gd.as_slice());
    assert!(both.item.pixels() == item.as_slice());
}

#[test]
fn each_band_is_finished_with_its_own_output() {
    // Drawing into a depth image alone, the finishing callback sees every band once, with its
    // own output and the final pixels a whole-image rasterization holds there (scratch rows
    // reused from band to band, and from one rasterization to the next, hold nothing stale).
    let cam = ScreenSpace(64, 40);
    let m = scattered_triangles(300, 3);
    let bands = 40u32.div_ceil(BAND_ROWS) as usize;
    let (whole, _) = rasterize(&cam, &[&m], &StoreFragment, None).unwrap();
    let mut memory = RasterMemory::default();
    let mut gd = Image::new(64, 40, 0.5f32).unwrap();
    for (last, mesh) in [(false, scattered_triangles(200, 5)), (true, m.clone())] {
        let mut copy = vec![(0.0f32, ItemId::NONE, None); 64 * 40];
        let outputs: Vec<_> = copy.chunks_mut((BAND_ROWS * 64) as usize).collect();
        assert_eq!(outputs.len(), bands);
        let target = DepthTarget {
            gd: &mut gd,
            zeroed: false,
        };
        draw_depth_then(
            set_up(&cam, &[&mesh], &mut memory).unwrap(),
            &StoreFragment,
            None,
            target,
            outputs,
            |band: FinishedBand<'_, Option<Fragment>>, out: &mut &mut [_]| {
                assert_eq!(band.first_pixel % (BAND_ROWS * 64) as usize, 0);
                for (i, o) in out.iter_mut().enumerate() {
                    *o = (band.gd[i], band.item[i], band.attributes[i]);
                }
            },
        )
        .unwrap();
        if last {
            let got: Vec<_> = copy.iter().map(|c| c.1).collect();
            assert!(gd == whole.gd && got.as_slice() == whole.item.pixels());
            assert!(
                copy.iter()
                    .map(|c| c.2)
                    .eq(whole.attributes.pixels().iter().copied())
            );
            assert!(
                copy.iter()
                    .map(|c| c.0)
                    .eq(whole.gd.pixels().iter().copied())
            );
        }
    }
    // A zeroed depth image is drawn without clearing: the same result.
    let mut fresh = Image::zeroed(64, 40).unwrap();
    let target = DepthTarget {
        gd: &mut fresh,
        zeroed: true,
    };
    let outputs = vec![(); bands];
    draw_depth_then(
        set_up(&cam, &[&m], &mut memory).unwrap(),
        &StoreFragment,
        None,
        target,
        outputs,
        |_, _| {},
    )
    .unwrap();
    assert!(fresh == whole.gd);
    // A depth image of another size is an error, not a panic.
    let mut small = Image::new(8, 8, 0.0f32).unwrap();
    let target = DepthTarget {
        gd: &mut small,
        zeroed: false,
    };
    let outputs = vec![(); bands];
    let mut memory = RasterMemory::default();
    let setup = set_up(&cam, &[&m], &mut memory).unwrap();
    assert!(draw_depth_then(setup, &NoAttributes, (), target, outputs, |_, _| {}).is_err());
}

#[test]
fn a_depth_pass_set_up_first_draws_nothing_when_the_caller_declines() {
    // One triangle crosses the near plane (set-up clips it), the other does not; the caller
    // reads set-up's counters and draws only when set-up clipped nothing (or always, when it
    // does not ask).
    let cam = ScreenSpace(16, 16);
    let m = mesh(
        vec![
            Vec3::new(2.0, 2.0, 1.0),
            Vec3::new(14.0, 2.0, 1.0),
            Vec3::new(2.0, 14.0, -1.0),
            Vec3::new(3.0, 3.0, 2.0),
            Vec3::new(12.0, 3.0, 2.0),
            Vec3::new(3.0, 12.0, 2.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    let bands = 16u32.div_ceil(BAND_ROWS) as usize;
    let mut memory = RasterMemory::default();
    let unclipped = mesh(m.positions.clone(), vec![[3, 4, 5]]);
    for (objects, ask) in [(&m, true), (&m, false), (&unclipped, true)] {
        let mut gd = Image::new(16, 16, 0.25f32).unwrap();
        let finished = std::sync::atomic::AtomicUsize::new(0);
        let setup = set_up(&cam, &[objects], &mut memory).unwrap();
        let counted = setup.stats();
        let stats = if ask && counted.has_curved_or_clipped() {
            // Declined: the set-up is dropped, nothing is drawn.
            counted
        } else {
            let target = DepthTarget {
                gd: &mut gd,
                zeroed: false,
            };
            let finish = |_: FinishedBand<'_, ()>, _: &mut ()| {
                finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            };
            let stats =
                draw_depth_then(setup, &NoAttributes, (), target, vec![(); bands], finish).unwrap();
            // Drawing keeps set-up's counters.
            assert_eq!(counted.clipped, stats.clipped);
            assert_eq!(counted.screen_triangles, stats.screen_triangles);
            stats
        };
        let finished = finished.into_inner();
        let untouched = gd.pixels().iter().all(|&g| g == 0.25);
        if ask && stats.has_curved_or_clipped() {
            // Counted by set-up, then left: nothing drawn, nothing finished.
            assert_eq!(stats.clipped, 1, "{stats:?}");
            assert_eq!((stats.fragments, finished), (0, 0), "{stats:?}");
            assert!(untouched);
        } else {
            // Nothing to refuse, or nobody asked: every band drawn and finished.
            assert!(stats.written > 10, "{stats:?}");
            assert_eq!(finished, bands);
            assert!(!untouched);
        }
    }
}
