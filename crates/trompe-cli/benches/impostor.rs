//! Impostor construction and ray walks: a SPOC impostor of the bunny beside a pinhole
//! impostor, a plain rasterization and a raster-method render of the same mesh, framed on its
//! bounding sphere and, as `trompe impostor bake` frames them, on the mesh; walks of reflected
//! rays through SPOC impostors of the bunny per resolution, beside the bunny's BVH; a SPOC impostor of a textured mesh (the Duck) beside the same build
//! without its texture; the graph-camera impostor of the demo maze with four bunnies beside a
//! rasterization through its root.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use trompe::camera::Spoc;
use trompe::eval::fidelity::ReflectorSetup;
use trompe::impostor::{ImpostorCamera, ViewCamera, albedo_of, build};
use trompe::raster::NoAttributes;
use trompe_cli::bench::{framed_pinhole, plain_raster, raster_view, render_raster_once};

fn impostor(c: &mut Criterion) {
    let assets = trompe_cli::bench::repo_root().join("assets");
    let bunny = trompe::geom::io::load(&assets.join("meshes/bunny.obj"))
        .expect("shipped bunny")
        .mesh;
    let teapot = trompe::geom::io::load(&assets.join("meshes/teapot.obj"))
        .expect("shipped teapot")
        .mesh;
    let b = bunny.bounds();
    let eye = b.center() + Vec3::new(0.3, 0.2, 1.0).normalize() * b.radius() * 3.0;
    let spoc = Spoc::around(eye, b.center(), b.radius(), 0.8, 512).expect("valid SPOC");
    let color = albedo_of(&bunny);
    let mut group = c.benchmark_group("impostor build, bunny 512²");
    group.bench_function("SPOC impostor", |bch| {
        bch.iter_with_large_drop(|| {
            build(ImpostorCamera::Spoc(spoc.clone()), &bunny, 0, &color).expect("valid")
        })
    });
    group.bench_function("peer: pinhole impostor (same maps)", |bch| {
        bch.iter_with_large_drop(|| {
            build(
                ImpostorCamera::Pinhole(spoc.pinhole().clone()),
                &bunny,
                0,
                &color,
            )
            .expect("valid")
        })
    });
    let mut builder = trompe::impostor::ImpostorBuilder::new();
    let mut again = build(ImpostorCamera::Spoc(spoc.clone()), &bunny, 0, &color).expect("valid");
    group.bench_function("SPOC impostor rebuilt, memory reused", |bch| {
        bch.iter(|| {
            builder
                .rebuild(&mut again, &bunny, 0, &color)
                .expect("valid")
        })
    });
    let mut target = trompe::raster::rasterize(spoc.pinhole(), &[&bunny], &NoAttributes, ())
        .expect("valid")
        .0;
    group.bench_function("peer: plain rasterization into a reused target", |bch| {
        bch.iter(|| {
            trompe::raster::rasterize_into(
                spoc.pinhole(),
                &[&bunny],
                &NoAttributes,
                (),
                &mut target,
            )
            .expect("valid")
        })
    });
    group.bench_function("peer: plain rasterization (depth + ids)", |bch| {
        bch.iter_with_large_drop(|| plain_raster(spoc.pinhole(), &bunny))
    });
    // The SPOC's reference pinhole is wider by (1 + k)·1.05 than one framing the bunny's
    // bounding sphere, as a pinhole impostor's camera does: the bunny is smaller there.
    if let Some(framed) = framed_pinhole(eye, b.center(), b.radius(), 512) {
        group.bench_function(
            "peer: plain rasterization through a pinhole framing the sphere",
            |bch| bch.iter_with_large_drop(|| plain_raster(&framed, &bunny)),
        );
    }
    // The cameras `trompe impostor bake` places at the same eye, framed on the mesh's vertices:
    // the bunny fills their images (47.6 % and 44.2 % of the texels, against 12.2 % above).
    let bake_framed = |kind| {
        let (center, radius) = (b.center(), b.radius());
        ImpostorCamera::fitted(
            kind,
            eye,
            center,
            radius,
            radius as f64,
            512,
            &bunny.positions,
        )
    };
    if let Ok(ImpostorCamera::Spoc(fitted)) = bake_framed(ViewCamera::Spoc(Some(0.8))) {
        group.bench_function("SPOC impostor framed on the mesh (as bake)", |bch| {
            bch.iter_with_large_drop(|| {
                build(ImpostorCamera::Spoc(fitted.clone()), &bunny, 0, &color).expect("valid")
            })
        });
        group.bench_function(
            "peer: plain rasterization through that SPOC's reference pinhole",
            |bch| bch.iter_with_large_drop(|| plain_raster(fitted.pinhole(), &bunny)),
        );
    }
    if let Ok(pinhole) = bake_framed(ViewCamera::Pinhole) {
        group.bench_function(
            "peer: pinhole impostor framed on the mesh (as bake)",
            |bch| {
                bch.iter_with_large_drop(|| {
                    build(pinhole.clone(), &bunny, 0, &color).expect("valid")
                })
            },
        );
    }
    let render_peer = raster_view(spoc.pinhole(), &bunny);
    group.bench_function(
        "peer: raster render method (colour, distance, normals, ids)",
        |bch| bch.iter_with_large_drop(|| render_raster_once(&render_peer)),
    );
    group.finish();

    // A textured mesh (`trompe bench`'s `bench::textured_impostor`): its texture sampled at
    // every covered texel, beside the goal's peer and the same build without the texture.
    let duck = trompe::geom::io::load(&assets.join("gltf/Duck.glb"))
        .expect("shipped duck")
        .mesh;
    let (_, duck_spoc) = trompe_cli::bench::goal_spoc(&duck);
    let untextured = trompe_cli::bench::without_textures(&duck);
    let (sampled, flat) = (albedo_of(&duck), albedo_of(&untextured));
    let camera = ImpostorCamera::Spoc(duck_spoc.clone());
    let mut group = c.benchmark_group("impostor build, textured Duck 512²");
    group.bench_function("SPOC impostor", |bch| {
        bch.iter_with_large_drop(|| build(camera.clone(), &duck, 0, &sampled).expect("valid"))
    });
    group.bench_function("peer: the same build, texture left out", |bch| {
        bch.iter_with_large_drop(|| build(camera.clone(), &untextured, 0, &flat).expect("valid"))
    });
    group.bench_function("peer: plain rasterization (depth + ids)", |bch| {
        bch.iter_with_large_drop(|| plain_raster(duck_spoc.pinhole(), &duck))
    });
    group.finish();

    // As `trompe bench walks`: reflected rays of a teapot mirror that enter the bunny's box,
    // walked through SPOC impostors of the bunny, beside the bunny's BVH on the same rays.
    let setup = ReflectorSetup::new(&bunny, &teapot, 1.4, 512).expect("valid setup");
    let rays = setup.rays().expect("reflected rays");
    let mut group = c.benchmark_group("SPOC walk, reflected rays");
    group.throughput(Throughput::Elements(rays.len() as u64));
    for res in [128u32, 256, 512, 1024, 2048] {
        let imp = build(
            setup.camera(ViewCamera::Spoc(None), res).expect("camera"),
            &setup.target,
            0,
            &albedo_of(&setup.target),
        )
        .expect("valid");
        imp.prepare_walks();
        group.bench_function(format!("{res}²"), |bch| {
            bch.iter(|| {
                rays.iter()
                    .filter(|r| imp.walk(r, f32::INFINITY).0.is_some())
                    .count()
            })
        });
    }
    let exact = trompe::trace::Bvh::build(vec![setup.target.clone()]).expect("bvh");
    group.bench_function("peer: the bunny's BVH", |bch| {
        bch.iter(|| {
            rays.iter()
                .filter(|r| {
                    trompe::trace::RayQuery::closest_hit(&exact, r, f32::INFINITY).is_some()
                })
                .count()
        })
    });
    group.finish();

    // Paper 1 §4.5 / §6: the maze with four bunnies, through its graph camera.
    let maze_path = trompe_cli::bench::repo_root().join("scenes/maze.maze");
    let maze = trompe::scene::maze::Maze::load(&maze_path).expect("shipped maze");
    let graph = maze.graph_camera(512, &maze_path).expect("maze camera");
    let scene = maze.with_objects(&bunny, 4);
    let color = albedo_of(&scene);
    let mut group = c.benchmark_group("graph-camera impostor, maze + 4 bunnies 512²");
    group.bench_function("graph impostor", |bch| {
        bch.iter_with_large_drop(|| {
            build(ImpostorCamera::Graph(graph.clone()), &scene, 0, &color).expect("valid")
        })
    });
    group.bench_function(
        "peer: depth + id rasterization through its root pinhole",
        |bch| bch.iter_with_large_drop(|| plain_raster(graph.root(), &scene)),
    );
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = impostor
}
criterion_main!(benches);
