//! Impostors built on the GPU (`trompe_gpu::build`) against the library's own build of the same
//! mesh through the same camera, texel for texel.

use glam::Vec3;
use std::path::Path;
use trompe::geom::{Mesh, Ray};
use trompe::impostor::{Impostor, ImpostorCamera, SurfaceSample, ViewCamera};
use trompe_gpu::Gpu;

fn bunny() -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/bunny.obj");
    trompe::geom::io::load(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .mesh
}

/// A colour that names the triangle a texel stores (its index in the three channels), so equal
/// colours mean the same triangle.
fn triangle_colour(s: &SurfaceSample) -> Vec3 {
    let t = s.triangle;
    Vec3::new(
        (t & 0xff) as f32,
        ((t >> 8) & 0xff) as f32,
        (t >> 16) as f32,
    ) / 255.0
}

/// How two impostors of one mesh through one camera differ: texels covered by one only, texels
/// storing another triangle, the largest depth difference where they store the same — relative
/// to the depth through a projective camera (`gd` is 1 / distance there, so its relative
/// difference is the distance's), and to the depth range through an orthographic one (whose
/// `gd` is affine in depth, 1 on the image plane and 0 as deep as it sees).
fn differences(cpu: &Impostor, gpu: &Impostor) -> (usize, usize, usize, f32) {
    let affine = matches!(cpu.camera(), ImpostorCamera::Orthographic(_));
    let (w, h) = cpu.gd().size();
    let (mut covered, mut one_only, mut other, mut worst) = (0, 0, 0, 0.0f32);
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (cpu.gd().get(x, y), gpu.gd().get(x, y));
            match (a > 0.0, b > 0.0) {
                (true, true) => {
                    covered += 1;
                    if cpu.color_at(x, y) != gpu.color_at(x, y) {
                        other += 1;
                    } else {
                        let scale = if affine { 1.0 } else { a };
                        worst = worst.max((a - b).abs() / scale);
                    }
                }
                (false, false) => {}
                _ => one_only += 1,
            }
        }
    }
    (covered, one_only, other, worst)
}

pub fn gpu_built_impostors_match_the_cpu_built_texel_for_texel(gpu: &Gpu) {
    let mesh = bunny();
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.radius());
    let eye = centre + Vec3::new(0.7, 0.25, 0.6).normalize() * (2.5 * radius);
    let mut cameras: Vec<(String, ImpostorCamera)> = [
        ViewCamera::Pinhole,
        ViewCamera::Orthographic,
        ViewCamera::Spoc(None),
    ]
    .into_iter()
    .map(|kind| {
        let c =
            ImpostorCamera::fitted(kind, eye, centre, radius, 0.1, 256, &mesh.positions).unwrap();
        (c.kind().to_string(), c)
    })
    .collect();
    // A cube-map face from inside the bunny's bounding box, its near plane a hair ahead.
    let inside =
        trompe::camera::Pinhole::look_at(centre, centre + Vec3::Z, Vec3::Y, 90.0, 192, 192)
            .unwrap()
            .with_near(f64::from(radius) * 1e-4);
    cameras.push(("cube face".into(), ImpostorCamera::Pinhole(inside)));
    for (name, camera) in cameras {
        let cpu = trompe::impostor::build(camera.clone(), &mesh, 3, &triangle_colour).unwrap();
        let on_gpu =
            trompe_gpu::build::build_impostor(gpu, camera, (&mesh, 3), &triangle_colour).unwrap();
        let (covered, one_only, other, worst) = differences(&cpu, &on_gpu);
        let texels = cpu.gd().pixels().len();
        println!(
            "{name}: {covered} texels covered by both, {one_only} by one only, {other} store \
             another triangle; depth within {worst:.1e}"
        );
        assert!(covered > texels / 10, "{name}: {covered} covered");
        // Two rasterizers' coverage rules and depth rounding: at most 0.5 % of the covered
        // texels differ, and depths agree to 1e-5.
        assert!(
            one_only + other <= covered / 200,
            "{name}: {one_only} + {other} of {covered}"
        );
        assert!(worst <= 1e-5, "{name}: gd differs by {worst:e}");
        assert_eq!(on_gpu.bounds(), cpu.bounds());
        // Walked by the library, the two answer reflected rays alike.
        let mut rng = trompe::geom::SplitMix64::new(5);
        let rays: Vec<Ray> = (0..4000)
            .map(|_| {
                let origin = eye + rng.unit_vector() * 0.1 * radius;
                let target = centre + rng.unit_vector() * radius * rng.next_f32().cbrt();
                Ray::new(origin, (target - origin).normalize())
            })
            .collect();
        let texel = |imp: &Impostor, r: &Ray| {
            imp.walk(r, f32::INFINITY)
                .0
                .map(|h| (h.uv.x as u32, h.uv.y as u32))
        };
        let same = rays
            .iter()
            .filter(|r| texel(&cpu, r) == texel(&on_gpu, r))
            .count();
        assert!(
            same * 1000 >= 995 * rays.len(),
            "{name}: {same} of {} walks agree",
            rays.len()
        );
    }
}

/// A graph camera's impostor (paper 1 §4.5): the demo maze with four bunnies, each frustum's
/// clipped triangles drawn by the GPU through its own matrix over one image, against the
/// library's build; and an image that does not say which frustum drew each texel, or names one
/// the camera lacks, refused with the reason.
pub fn gpu_built_graph_impostors_match_the_cpu_built(gpu: &Gpu) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let plan = root.join("scenes/maze.maze");
    let maze = trompe::scene::maze::Maze::load(&plan).unwrap();
    let g = maze.graph_camera(256, &plan).unwrap();
    let mesh = trompe::scene::maze::Maze::with_objects(&maze, &bunny(), 4);
    let camera = ImpostorCamera::Graph(g);
    let cpu = trompe::impostor::build(camera.clone(), &mesh, 3, &triangle_colour).unwrap();
    let drawn = trompe_gpu::build::draw(gpu, &camera, &mesh).unwrap();
    let on_gpu =
        trompe::impostor::resolve_drawn(camera.clone(), (&mesh, 3), &triangle_colour, &drawn)
            .unwrap();
    let (covered, one_only, other, worst) = differences(&cpu, &on_gpu);
    let texels = cpu.gd().pixels().len();
    let frusta = drawn.frusta.as_ref().map_or(0, |f| {
        f.iter().collect::<std::collections::BTreeSet<_>>().len()
    });
    println!(
        "graph camera: {covered} texels covered by both, {one_only} by one only, {other} store \
         another triangle; gd within {worst:.1e} relative; drawn by {frusta} frusta"
    );
    assert!(covered > texels / 4, "{covered} covered");
    assert!(frusta > 1, "the maze's image is drawn by several frusta");
    assert!(
        one_only + other <= covered / 200,
        "{one_only} + {other} of {covered}"
    );
    // The depth of the point a texel's barycentrics name: the GPU interpolates them in f32
    // through frustum matrices concatenated along the corridors (the CPU's in f64), over
    // depths from the entrance to the far end of the maze; 3e-5 relative (measured 1.5e-5).
    assert!(worst <= 3e-5, "gd differs by {worst:e}");
    assert_eq!(on_gpu.bounds(), cpu.bounds());
    let without = trompe::impostor::DrawnImage {
        frusta: None,
        ..drawn.clone()
    };
    let e = trompe::impostor::resolve_drawn(camera.clone(), (&mesh, 3), &triangle_colour, &without)
        .unwrap_err();
    assert!(e.to_string().contains("graph camera"), "{e}");
    let mut wrong = drawn;
    if let Some(f) = wrong.frusta.as_mut() {
        f[0] = 99;
    }
    let e =
        trompe::impostor::resolve_drawn(camera, (&mesh, 3), &triangle_colour, &wrong).unwrap_err();
    assert!(e.to_string().contains("frustum 99"), "{e}");
}

/// Depth layers peeled by the GPU (`trompe_gpu::build::peel`: each layer drawn under the one
/// before's depth as a ceiling) against the library's peel of the same impostor, layer by layer,
/// through a pinhole, an orthographic camera and a SPOC of 256² (as above); and a graph camera
/// refused as the library refuses it.
pub fn gpu_peeled_layers_match_the_cpu_peeled(gpu: &Gpu) {
    use trompe::impostor::Layers;
    let mesh = bunny();
    let b = mesh.bounds();
    let (centre, radius) = (b.center(), b.radius());
    let eye = centre + Vec3::new(0.7, 0.25, 0.6).normalize() * (2.5 * radius);
    for kind in [
        ViewCamera::Pinhole,
        ViewCamera::Orthographic,
        ViewCamera::Spoc(None),
    ] {
        let camera =
            ImpostorCamera::fitted(kind, eye, centre, radius, 0.1, 256, &mesh.positions).unwrap();
        let name = camera.kind();
        for layers in [Layers::Count(4), Layers::Auto] {
            let mut cpu =
                trompe::impostor::build(camera.clone(), &mesh, 3, &triangle_colour).unwrap();
            cpu.peel(&mesh, 3, &triangle_colour, layers).unwrap();
            let mut on_gpu = trompe_gpu::build::build_impostor(
                gpu,
                camera.clone(),
                (&mesh, 3),
                &triangle_colour,
            )
            .unwrap();
            trompe_gpu::build::peel(gpu, &mut on_gpu, (&mesh, 3), &triangle_colour, layers)
                .unwrap();
            assert_eq!(
                on_gpu.layer_count(),
                cpu.layer_count(),
                "{name}, {layers} layers"
            );
            assert!(cpu.layer_count() > 1, "{name}: the bunny has depth layers");
            for (l, (c, g)) in cpu.layers().zip(on_gpu.layers()).enumerate() {
                let (covered, one_only, other, worst) = differences(c, g);
                println!(
                    "{name}, {layers} layers, layer {}: {covered} texels covered by both, \
                     {one_only} by one only, {other} store another triangle; depth within \
                     {worst:.1e}",
                    l + 1
                );
                assert!(covered > 0, "{name}: layer {} is empty", l + 1);
                // As for the first layer: two rasterizers' coverage rules and depth rounding,
                // here also at the ceiling, where a surface lies within the peeling gap of the
                // layer before.
                assert!(
                    one_only + other <= covered / 200,
                    "{name}, layer {}: {one_only} + {other} of {covered}",
                    l + 1
                );
                assert!(worst <= 1e-5, "{name}, layer {}: gd {worst:e}", l + 1);
            }
        }
    }
    // A graph camera holds one layer, on either device.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let plan = root.join("scenes/maze.maze");
    let maze = trompe::scene::maze::Maze::load(&plan).unwrap();
    let camera = ImpostorCamera::Graph(maze.graph_camera(64, &plan).unwrap());
    let maze_mesh = trompe::scene::maze::Maze::with_objects(&maze, &mesh, 1);
    let mut imp =
        trompe_gpu::build::build_impostor(gpu, camera, (&maze_mesh, 3), &triangle_colour).unwrap();
    let e = trompe_gpu::build::peel(
        gpu,
        &mut imp,
        (&maze_mesh, 3),
        &triangle_colour,
        Layers::Count(2),
    )
    .unwrap_err();
    assert!(e.to_string().contains("--layers 1"), "{e}");
}
