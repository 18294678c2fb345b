//! Graph-camera impostors (paper 1 §5; docs/conventions.md §4): an L-shaped corridor seen around its
//! corner.

use crate::common;

use glam::{DVec3, Mat4, Vec3};
use std::sync::Arc;
use trompe::camera::GraphCamera;
use trompe::geom::{Mesh, Ray, SplitMix64, cube};
use trompe::impostor::{ImpostorCamera, WalkMode, albedo_of, build};
use trompe::trace::{Bvh, RayQuery};
use trompe::{Pinhole, Projection};

fn boxed(min: Vec3, max: Vec3) -> Mesh {
    let c = cube();
    c.transformed(&(Mat4::from_translation((min + max) * 0.5) * Mat4::from_scale(max - min)))
}

/// Walls of a corridor along −z (x ∈ [−1, 1], z ∈ [0, −4]) that turns toward −x
/// (z ∈ [−4, −2]), and a cube at its far end.
fn corridor() -> (Mesh, Mesh) {
    let mut walls = boxed(Vec3::new(-1.2, 0.0, -2.0), Vec3::new(-1.0, 2.0, 0.0));
    for (min, max) in [
        (Vec3::new(1.0, 0.0, -4.2), Vec3::new(1.2, 2.0, 0.0)),
        (Vec3::new(-7.0, 0.0, -4.2), Vec3::new(1.2, 2.0, -4.0)),
        (Vec3::new(-7.0, 0.0, -2.0), Vec3::new(-1.0, 2.0, -1.8)),
        (Vec3::new(-7.0, -0.1, -4.2), Vec3::new(1.2, 0.0, 0.0)),
    ] {
        walls.append(&boxed(min, max));
    }
    let target = boxed(Vec3::new(-5.5, 0.0, -3.5), Vec3::new(-4.5, 1.0, -2.5));
    (walls, target)
}

fn camera() -> (GraphCamera, Pinhole) {
    let root = Pinhole::look_at(
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, -1.0),
        Vec3::Y,
        70.0,
        256,
        256,
    )
    .unwrap()
    .with_near(0.05);
    let mut g = GraphCamera::new(root.clone());
    // Bend at the corner: the diagonal plane through (0, ·, −3), the apex turned 90° about it.
    let corner = DVec3::new(0.0, 1.0, -3.0);
    g.bend(
        0,
        corner,
        DVec3::new(1.0, 0.0, 1.0),
        corner + DVec3::new(4.0, 0.0, 0.0),
        100.0,
    )
    .unwrap();
    (g, root)
}

fn scene() -> Mesh {
    let (mut m, t) = corridor();
    m.append(&t);
    m
}

#[test]
fn the_graph_impostor_sees_around_the_corner_and_is_self_consistent() {
    let (g, root) = camera();
    let mesh = scene();
    let (_, target) = corridor();
    let tb = target.bounds();
    let graph = build(
        ImpostorCamera::Graph(g.clone()),
        &mesh,
        0,
        &albedo_of(&mesh),
    )
    .unwrap();
    let pinhole = build(ImpostorCamera::Pinhole(root), &mesh, 0, &albedo_of(&mesh)).unwrap();
    let sees_target = |imp: &trompe::impostor::Impostor| {
        imp.position_image()
            .pixels()
            .iter()
            .zip(imp.gd().pixels())
            .filter(|(p, g)| {
                **g > 0.0 && p.cmpge(tb.min - 1e-4).all() && p.cmple(tb.max + 1e-4).all()
            })
            .count()
    };
    assert_eq!(sees_target(&pinhole), 0, "the cube is around the corner");
    assert!(sees_target(&graph) > 200, "{}", sees_target(&graph));
    // Every stored point projects back into its own texel with its own gd.
    let mut checked = 0;
    for y in 0..256u32 {
        for x in 0..256u32 {
            let gd = graph.gd().get(x, y);
            if gd <= 0.0 {
                continue;
            }
            let p = graph.position_at(x, y).as_dvec3();
            let q = g
                .project(p)
                .unwrap_or_else(|| panic!("texel ({x}, {y}) stores an unprojectable point"));
            let centre = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            assert!(
                (q.uv - centre).abs().max_element() <= 0.51,
                "({x}, {y}): {}",
                q.uv
            );
            assert!(
                (q.gd - gd as f64).abs() <= 1e-3 * gd as f64,
                "({x}, {y}): {} vs {gd}",
                q.gd
            );
            checked += 1;
        }
    }
    assert!(checked > 30_000, "{checked}");
}

#[test]
fn graph_walks_agree_with_the_bvh_and_with_each_other() {
    let (g, _) = camera();
    let mesh = scene();
    let (_, target) = corridor();
    let imp = build(ImpostorCamera::Graph(g), &mesh, 0, &albedo_of(&mesh)).unwrap();
    let exact = Bvh::build(vec![Arc::new(mesh)]).unwrap();
    // Rays from near the bent frustum's apex region toward the cube around the corner.
    let tb = target.bounds();
    let mut rng = SplitMix64::new(5);
    let (mut agree2, mut agree12, mut hits, n) = (0, 0, 0, 4000);
    for _ in 0..n {
        let o = Vec3::new(
            -0.5 + 0.5 * rng.next_f32(),
            0.8 + 0.4 * rng.next_f32(),
            -3.4 + 0.8 * rng.next_f32(),
        );
        let aim = tb.min + tb.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let ray = Ray::new(o, (aim - o).normalize());
        let e = exact.closest_hit(&ray, f32::INFINITY);
        let a2 = imp.walk_mode(&ray, f32::INFINITY, WalkMode::Exact).0;
        let a1 = imp.walk_mode(&ray, f32::INFINITY, WalkMode::Linear).0;
        hits += e.is_some() as usize;
        let close = |a: Option<trompe::trace::Hit>, b: Option<trompe::trace::Hit>| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => a.position.distance(b.position) < 0.05,
            _ => false,
        };
        agree2 += close(e, a2) as usize;
        agree12 += close(a1, a2) as usize;
    }
    eprintln!(
        "rays {n}, exact hits {hits}, algorithm 2 agrees with the BVH on {agree2}, with algorithm 1 on {agree12}"
    );
    assert!(hits > n * 9 / 10);
    assert!(agree2 as f64 >= 0.95 * n as f64, "{agree2}");
    assert!(agree12 as f64 >= 0.95 * n as f64, "{agree12}");
}

#[test]
fn graph_texel_walks_return_the_linear_walks_hits() {
    // Algorithm 2 walked texel by texel, frustum by frustum, against algorithm 1's uniform
    // steps: rays from around the bend, half aimed at the cube beyond the corner and half
    // anywhere down the corridor.
    let (g, _) = camera();
    let mesh = scene();
    let (walls, target) = corridor();
    let imp = build(ImpostorCamera::Graph(g), &mesh, 0, &albedo_of(&mesh)).unwrap();
    let exact = Bvh::build(vec![Arc::new(mesh)]).unwrap();
    let (tb, wb) = (target.bounds(), walls.bounds());
    let mut rng = SplitMix64::new(17);
    let rays: Vec<Ray> = (0..100_000)
        .map(|i| {
            let o = Vec3::new(
                -0.5 + 0.5 * rng.next_f32(),
                0.8 + 0.4 * rng.next_f32(),
                -3.4 + 1.4 * rng.next_f32(),
            );
            let b = if i % 2 == 0 { tb } else { wb };
            let aim =
                b.min + b.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            Ray::new(o, (aim - o).normalize())
        })
        .collect();
    let c = common::compare_walks(&imp, &exact, &rays);
    eprintln!("graph: {c:?}");
    c.holds();
    assert!(c.hits > 50_000, "{c:?}");
}

#[test]
fn graph_impostors_save_and_load_exactly() {
    use trompe::impostor::file;
    let (g, _) = camera();
    let mesh = scene();
    let imp = build(ImpostorCamera::Graph(g), &mesh, 2, &albedo_of(&mesh)).unwrap();
    let dir = common::scratch("graph-file");
    let path = dir.join("corridor.json");
    file::save(&imp, &path).unwrap();
    let back = file::load(&path).unwrap();
    let (ImpostorCamera::Graph(a), ImpostorCamera::Graph(b)) = (&back.camera(), &imp.camera())
    else {
        panic!("the camera comes back as a graph camera");
    };
    assert_eq!(a.frusta().len(), b.frusta().len());
    for (fa, fb) in a.frusta().iter().zip(b.frusta()) {
        assert!(fa.matrix.abs_diff_eq(fb.matrix, 1e-9));
    }
    assert!(
        back.gd() == imp.gd()
            && back.color() == imp.color()
            && back.position_image() == imp.position_image()
    );
    // The reloaded impostor answers rays as the original does, with both algorithms.
    let mut rng = SplitMix64::new(5);
    for _ in 0..500 {
        let mut range = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
        let o = Vec3::new(range(-0.8, 0.8), range(0.2, 1.8), range(-1.0, 0.5));
        let d = Vec3::new(range(-1.0, 1.0), range(-0.5, 0.5), range(-1.0, 0.2));
        let r = Ray::new(o, d.normalize());
        for mode in [WalkMode::Exact, WalkMode::Linear] {
            assert_eq!(
                back.walk_mode(&r, f32::INFINITY, mode).0,
                imp.walk_mode(&r, f32::INFINITY, mode).0
            );
        }
    }
    // A frustum whose parent comes after it is refused with the file's name.
    let json = std::fs::read_to_string(&path).unwrap();
    let bad = json.replacen("\"parent\": 0", "\"parent\": 7", 1);
    assert_ne!(bad, json);
    let bad_path = dir.join("bad.json");
    std::fs::write(&bad_path, bad).unwrap();
    let e = file::load(&bad_path).unwrap_err().to_string();
    assert!(e.contains("bad.json") && e.contains("parent"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The paper's Fig. 5 setting on the shipped maze: a mirror bunny in the first corridor, its
/// reflected rays answered by the maze's graph-camera impostor (algorithm 2) and by the BVH.
#[test]
fn the_maze_impostor_agrees_with_the_bvh_on_reflected_rays() {
    use trompe::eval::fidelity::{ReflectorSetup, check, check_with};
    use trompe::scene::maze::Maze;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("scenes/maze.maze");
    let maze = Maze::load(&path).unwrap();
    let bunny = trompe::geom::io::load(&root.join("assets/meshes/bunny.obj"))
        .unwrap()
        .mesh;
    let setup = ReflectorSetup::in_maze(&maze, &bunny, 256).unwrap();
    let g = maze.graph_camera(512, &path).unwrap();
    assert!(
        g.frusta().iter().any(|f| f.children.len() >= 2),
        "the walk splits at a junction"
    );
    let imp = build(
        ImpostorCamera::Graph(g),
        &setup.target,
        0,
        &albedo_of(&setup.target),
    )
    .unwrap();
    let exact = Bvh::build(vec![setup.target.clone()]).unwrap();
    let rays = setup.rays().unwrap();
    assert!(rays.len() > 1000, "{}", rays.len());
    let r = check(&imp, &exact, &rays);
    assert!(r.exact_hits > rays.len() / 2, "{} hits", r.exact_hits);
    assert!(r.agreement() >= 0.99, "algorithm 2: {:.4}", r.agreement());
    // The exact walk loses no hit the image holds: what it misses, the camera did not capture.
    assert_eq!(r.missed, r.missed_unheld, "algorithm 2: {r:?}");
    // Algorithm 1 samples the bent image path uniformly in 3-D.
    let r1 = check_with(&imp, &exact, &rays, WalkMode::Linear);
    assert!(r1.agreement() >= 0.99, "algorithm 1: {:.4}", r1.agreement());
}

/// Paper 1 Fig. 4: the graph camera captures the entire maze. Walked from the entrance, it
/// reaches every corridor, and every floor cell shows in the image — the deepest ones with a
/// few texels of a 1024² image, as the paper's Fig. 12 warns.
#[test]
fn the_maze_graph_camera_shows_every_floor_cell() {
    use trompe::scene::maze::Maze;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("scenes/maze.maze");
    let maze = Maze::load(&path).unwrap();
    let g = maze.graph_camera(1024, &path).unwrap();
    let mesh = maze.mesh();
    let imp = build(ImpostorCamera::Graph(g), &mesh, 0, &albedo_of(&mesh)).unwrap();
    let (w, h) = (maze.width(), maze.height());
    let mut floor_texels = vec![0usize; w * h];
    let (position, normal) = (imp.position_image(), imp.normal_image());
    for ((p, n), &gd) in position
        .pixels()
        .iter()
        .zip(normal.pixels())
        .zip(imp.gd().pixels())
    {
        let (c, r) = (p.x.floor(), p.z.floor());
        if gd > 0.0 && p.y.abs() < 1e-3 && n.y > 0.5 && c >= 0.0 && r >= 0.0 {
            let (c, r) = (c as usize, r as usize);
            if c < w && r < h {
                floor_texels[r * w + c] += 1;
            }
        }
    }
    let unseen: Vec<(usize, usize)> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .filter(|&(c, r)| !maze.walls[r][c] && floor_texels[r * w + c] == 0)
        .collect();
    assert!(
        unseen.is_empty(),
        "floor cells not in the image: {unseen:?}"
    );
    // The entrance is seen best (paper 1 §6: reflections are of highest quality there).
    let (c0, r0) = maze.entrance;
    let most = floor_texels.iter().max().copied().unwrap_or(0);
    assert_eq!(floor_texels[r0 * w + c0], most);
}

/// A graph-camera impostor rebuilt in place (a dynamic scene: objects come and go in the
/// maze) equals a fresh build of the scene as it now is, map for map.
#[test]
fn a_rebuilt_graph_impostor_equals_a_fresh_build() {
    use trompe::impostor::ImpostorBuilder;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/maze.maze");
    let maze = trompe::scene::maze::Maze::load(&path).unwrap();
    let g = maze.graph_camera(128, &path).unwrap();
    let with = maze.with_objects(&trompe::geom::icosphere(2), 4);
    let without = maze.mesh();
    let camera = ImpostorCamera::Graph(g);
    let mut builder = ImpostorBuilder::new();
    let mut imp = builder
        .build(camera.clone(), &with, 1, &albedo_of(&with))
        .unwrap();
    for scene in [&without, &with] {
        builder
            .rebuild(&mut imp, scene, 1, &albedo_of(scene))
            .unwrap();
        let fresh = build(camera.clone(), scene, 1, &albedo_of(scene)).unwrap();
        assert!(
            imp.gd() == fresh.gd()
                && imp.color() == fresh.color()
                && imp.position_image() == fresh.position_image()
        );
        assert!(imp.normal() == fresh.normal() && imp.face_normal() == fresh.face_normal());
        assert!(imp.object() == fresh.object() && imp.bounds() == fresh.bounds());
    }
    // The spheres show, so the rebuilds had texels to clear and to fill again.
    let bare = build(camera, &without, 1, &albedo_of(&without)).unwrap();
    assert!(imp.gd() != bare.gd(), "the spheres are not seen");
}

#[test]
fn every_impostor_camera_clips_and_projects_in_one_call_as_in_two() {
    // The rasterizer asks each vertex for both in one call: the answer must be exactly the two
    // separate calls', for every camera the rasterizer draws through — pinhole, orthographic,
    // SPOC, and each frustum of a graph camera — on both sides of each one's near boundary.
    use trompe::impostor::ViewCamera;
    fn one_as_two<P: Projection>(camera: &P, eye: Vec3, rng: &mut SplitMix64) {
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..2000 {
            let p = (eye + rng.unit_vector() * 4.0 * rng.next_f32()).as_dvec3();
            let clip = camera.clip_distance(p);
            let expected = (clip, (clip >= 0.0).then(|| camera.project(p)).flatten());
            assert_eq!(camera.clip_and_project(p), expected, "{p}");
            if clip >= 0.0 {
                inside += 1
            } else {
                outside += 1
            }
        }
        assert!(inside > 100 && outside > 100, "{inside} / {outside}");
    }
    let (g, _) = camera();
    let (eye, center) = (Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.0, 1.0, -1.0));
    let mut rng = SplitMix64::new(11);
    one_as_two(&g.frustum(0), eye, &mut rng);
    for kind in [
        ViewCamera::Pinhole,
        ViewCamera::Orthographic,
        ViewCamera::Spoc(Some(0.6)),
    ] {
        match ImpostorCamera::around(kind, eye, center, 1.0, 0.5, 64).unwrap() {
            ImpostorCamera::Pinhole(c) => one_as_two(&c, eye, &mut rng),
            ImpostorCamera::Orthographic(c) => one_as_two(&c, eye, &mut rng),
            ImpostorCamera::Spoc(c) => one_as_two(&c, eye, &mut rng),
            ImpostorCamera::Graph(_) => unreachable!("a placed camera"),
        }
    }
}
