//! The ground-truth renderers: agreement on diffuse scenes, determinism across thread counts;
//! and the impostor method against them.

use crate::common;
use std::path::PathBuf;
use trompe::frame::metrics;
use trompe::render::{Method, render};
use trompe::scene::{Scene, Surface};

fn scene(name: &str) -> Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    Scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn raster_and_trace_agree_on_the_diffuse_scene() {
    let s = scene("diffuse.toml");
    let (raster, _) = render(&s, Method::Raster, &()).unwrap();
    let (trace, _) = render(&s, Method::Trace, &()).unwrap();
    let scores = metrics::compare(&trace.color, &raster.color, None).unwrap();
    assert!(scores.psnr >= 45.0, "{scores:?}");
    assert!(scores.flip <= 0.002, "{scores:?}");
    let same = raster
        .object_id
        .pixels()
        .iter()
        .zip(trace.object_id.pixels())
        .filter(|(a, b)| a == b)
        .count();
    let frac = same as f64 / trace.object_id.pixels().len() as f64;
    assert!(frac >= 0.995, "object ids agree on {frac}");
    // Depth agrees wherever both see the same object.
    for ((a, b), (ia, ib)) in raster.depth.pixels().iter().zip(trace.depth.pixels()).zip(
        raster
            .object_id
            .pixels()
            .iter()
            .zip(trace.object_id.pixels()),
    ) {
        if ia == ib && b.is_finite() {
            assert!((a - b).abs() <= 1e-3 * b, "{a} vs {b}");
        }
    }
}

#[test]
fn mirrors_differ_between_methods() {
    // The raster method only looks mirrors up in the panorama: on the reflection scene it must
    // not match the traced image (a renderer that ignored the method would).
    let s = scene("reflections.toml");
    let (raster, _) = render(&s, Method::Raster, &()).unwrap();
    let (trace, _) = render(&s, Method::Trace, &()).unwrap();
    let scores = metrics::compare(&trace.color, &raster.color, None).unwrap();
    assert!(scores.psnr < 35.0, "{scores:?}");
}

#[test]
fn same_pixels_for_one_and_two_threads() {
    for name in ["diffuse.toml", "reflections.toml"] {
        let s = scene(name);
        for method in [Method::Raster, Method::Trace, Method::Impostor(128)] {
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| render(&s, method, &()).unwrap().0)
            };
            let (one, two) = (run(1), run(2));
            assert!(one.color == two.color, "{name} {method}: colour differs");
            assert!(
                one.depth == two.depth && one.object_id == two.object_id,
                "{name} {method}"
            );
        }
    }
}

#[test]
fn impostor_reflections_come_close_to_the_traced_ones() {
    // Paper 1: the rays mirrors and glass send out are answered by impostors of the diffuse
    // objects. Where a primary ray meets a diffuse object nothing changes; on the reflections
    // the method must come far closer to `trace` than environment mapping does.
    let s = scene("reflections.toml");
    let (trace, _) = render(&s, Method::Trace, &()).unwrap();
    let (impostor, _) = render(&s, Method::Impostor(512), &()).unwrap();
    let (raster, _) = render(&s, Method::Raster, &()).unwrap();
    let view = s.view(s.render.time).unwrap();
    let reflectors: Vec<u32> = (0..view.surfaces.len() as u32)
        .filter(|&o| !matches!(view.surfaces[o as usize], Surface::Diffuse(_)))
        .collect();
    assert_eq!(reflectors, [1, 2, 4], "the scene's mirrors and glass");
    let mut diffuse_pixels = 0;
    for ((a, b), id) in trace
        .color
        .pixels()
        .iter()
        .zip(impostor.color.pixels())
        .zip(trace.object_id.pixels())
    {
        if *id != trompe::trace::NO_OBJECT && !reflectors.contains(id) {
            assert_eq!(a, b, "a diffuse pixel of object {id} changed");
            diffuse_pixels += 1;
        }
    }
    assert!(diffuse_pixels > 10_000, "{diffuse_pixels}");
    let near = metrics::compare(&trace.color, &impostor.color, None).unwrap();
    let far = metrics::compare(&trace.color, &raster.color, None).unwrap();
    // Not the traced image: the diffuse objects the mirrors and the glass see are impostors
    // (the mirrors and the glass see one another exactly; without that, 37.4 dB and 0.0019).
    assert!(
        near.psnr.is_finite() && near.psnr >= 45.0 && near.flip <= 0.001,
        "{near:?}"
    );
    assert!(
        near.flip * 10.0 < far.flip,
        "{near:?} against environment mapping {far:?}"
    );
}

/// Renders `scene` by `trace` and by the impostor method with `resolution²` impostors, and
/// scores the impostor image on the pixels where `trace` sees `object`: how many, and how well.
fn impostor_against_trace_on(
    scene: &Scene,
    resolution: u32,
    object: u32,
) -> (usize, metrics::Scores) {
    let (trace, _) = render(scene, Method::Trace, &()).unwrap();
    let (impostor, _) = render(scene, Method::Impostor(resolution), &()).unwrap();
    let (w, h) = trace.color.size();
    let on: Vec<bool> = trace
        .object_id
        .pixels()
        .iter()
        .map(|&o| o == object)
        .collect();
    let pixels = on.iter().filter(|&&m| m).count();
    let mask = trompe::frame::Image::from_vec(w, h, on).unwrap();
    let scores = metrics::compare(&trace.color, &impostor.color, Some(&mask)).unwrap();
    (pixels, scores)
}

#[test]
fn a_mirror_in_a_room_sees_the_room_and_the_bunny() {
    // The shipped room scene: the room is around the mirror ball (a cube map of six pinhole
    // impostors, whose big wall triangles are clipped at the near plane and the guard band),
    // the bunny beside it (a SPOC). On the mirror's pixels the method must agree with `trace`.
    let s = scene("room.toml");
    let (pixels, on_mirror) = impostor_against_trace_on(&s, 512, 1);
    assert!(pixels > 5000, "{pixels} mirror pixels");
    assert!(
        on_mirror.psnr >= 34.0 && on_mirror.flip <= 0.01,
        "{on_mirror:?}"
    );
}

#[test]
fn a_reflector_inside_an_object_sees_it_through_a_cube_of_pinholes() {
    // A mirror sphere inside a big diffuse sphere lit from one side: no SPOC sees the big
    // sphere from inside and it is not flat, so its impostor is the six faces of a cube map at
    // the mirror's centre. The mirror's pixels must then agree with the traced ones, which
    // they would not if a face were missing, misplaced, or lost rays starting behind its
    // near plane (the reflected rays start on the mirror, around the cube's centre).
    let dir = common::scratch("impostor-inside");
    let path = dir.join("inside.toml");
    std::fs::write(
        &path,
        "[light]\ndirection = [0.3, 1.0, 0.2]\n\n[camera]\nposition = [0.0, 0.0, 2.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\nresolution = [96, 96]\n\n[[object]]\nshape = \"sphere\"\nscale = 10.0\nmaterial = { type = \"diffuse\", color = [0.5, 0.5, 0.5] }\n\n[[object]]\nshape = \"sphere\"\nscale = 1.0\nmaterial = { type = \"mirror\", tint = [0.9, 0.9, 0.9] }\n",
    )
    .unwrap();
    let s = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let (pixels, on_mirror) = impostor_against_trace_on(&s, 128, 1);
    assert!(pixels > 2000, "{pixels} mirror pixels");
    assert!(
        on_mirror.psnr >= 45.0 && on_mirror.flip <= 0.008,
        "{on_mirror:?}"
    );
    // A size no map can have is said as such.
    for side in [0, 1 << 20] {
        let e = render(&s, Method::Impostor(side), &())
            .unwrap_err()
            .to_string();
        assert!(e.contains("invalid image size"), "{e}");
    }
}

/// A scene object that names a baked impostor renders as the scene that builds one: the
/// impostor baked through the camera the method places, lit by the scene's lights on load.
#[test]
fn a_scene_naming_a_baked_impostor_renders_the_frame_that_builds_it() {
    use trompe::impostor::{albedo_of, build, file};
    let d = common::scratch("render_baked_impostor");
    let teapot = common::asset("meshes/teapot.obj");
    let scene_text = |impostor: &str| {
        format!(
            r#"
[camera]
position = [45.0, 12.0, 50.0]
look_at = [-12.0, 0.0, -40.0]
fov_y = 40.0
resolution = [240, 160]

[light]
direction = [-0.3, 1.0, -0.8]

[[object]]
mesh = "{}"
{impostor}

[[object]]
shape = "plane"
scale = 70.0
rotate = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -40.0]
material = {{ type = "mirror", tint = [0.9, 0.9, 0.9] }}
"#,
            teapot.display()
        )
    };
    let built_path = d.join("built.toml");
    std::fs::write(&built_path, scene_text("")).unwrap();
    let built = Scene::load(&built_path).unwrap();
    // Bake the teapot as the scene places it (no transform) through the method's camera.
    let view = built.view(0.0).unwrap();
    let cameras = trompe::render::placed_cameras(&view.meshes[0], &view.meshes[1], 128).unwrap();
    assert_eq!(
        cameras.len(),
        1,
        "one SPOC for an object outside the reflector"
    );
    let mesh = &view.meshes[0];
    let imp = build(cameras[0].clone(), mesh, 0, &albedo_of(mesh)).unwrap();
    file::save(&imp, &d.join("teapot.json")).unwrap();
    let baked_path = d.join("baked.toml");
    std::fs::write(&baked_path, scene_text("impostor = \"teapot.json\"")).unwrap();
    let baked = Scene::load(&baked_path).unwrap();

    let (a, _) = render(&built, Method::Impostor(128), &()).unwrap();
    let (b, _) = render(&baked, Method::Impostor(128), &()).unwrap();
    assert!(a.object_id == b.object_id && a.depth == b.depth);
    let mirror = a.object_id.map(|id| id == 1);
    let (mut seen, mut worst) = (0, 0.0f32);
    for ((ca, cb), m) in a
        .color
        .pixels()
        .iter()
        .zip(b.color.pixels())
        .zip(mirror.pixels())
    {
        if !*m {
            assert_eq!(ca, cb, "a pixel off the mirror differs");
            continue;
        }
        seen += 1;
        worst = worst.max((*ca - *cb).abs().max_element());
    }
    eprintln!("mirror pixels {seen}, largest channel difference {worst:.2e}");
    assert!(seen > 200, "the mirror covers {seen} pixels");
    // And the teapot is what the mirror shows there: moved far away, most of those pixels change.
    let away = d.join("away.toml");
    let text = scene_text("translate = [0.0, -1000.0, 0.0]");
    std::fs::write(&away, text).unwrap();
    let (c, _) = render(&Scene::load(&away).unwrap(), Method::Impostor(128), &()).unwrap();
    let changed = (a.color.pixels().iter().zip(c.color.pixels()))
        .zip(mirror.pixels())
        .filter(|((x, y), m)| **m && (**x - **y).abs().max_element() > 1e-2)
        .count();
    eprintln!("the teapot shows in {changed} of {seen} mirror pixels");
    assert!(
        changed > 300,
        "the teapot shows in {changed} of {seen} mirror pixels"
    );
    // The baked file stores albedo in half floats and normals in 16-bit octahedral codes, and
    // is lit on load; the built impostor is lit at full precision, then stored: the two differ
    // by that rounding only.
    assert!(worst < 2e-3, "largest channel difference {worst}");
    // A baked impostor of another object is refused, naming both boxes.
    let other = d.join("other.toml");
    let moved = scene_text("impostor = \"teapot.json\"\ntranslate = [0.0, 5.0, 0.0]");
    std::fs::write(&other, moved).unwrap();
    let e = render(&Scene::load(&other).unwrap(), Method::Impostor(128), &())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("teapot.json") && e.contains("was not baked from"),
        "{e}"
    );
}

#[test]
fn a_sphere_shadows_exactly_the_ground_pixels_whose_shadow_ray_the_bvh_blocks() {
    use trompe::geom::Ray;
    use trompe::glam::{DVec2, Vec3};
    use trompe::trace::{Bvh, RayQuery};
    let text = r#"
[camera]
position = [0.0, 2.0, 2.5]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
resolution = [96, 72]
[light]
direction = [0.4, 1.0, 0.2]
intensity = 3.0
[render]
background = [0.0, 0.0, 0.0]
[[object]]
name = "ground"
shape = "plane"
scale = 4.0
material = { type = "diffuse", color = [0.5, 0.5, 0.5] }
[[object]]
name = "ball"
shape = "sphere"
fit = 0.6
translate = [0.0, 0.4, 0.0]
material = { type = "diffuse", color = [0.8, 0.3, 0.2] }
"#;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/shadow-test.toml");
    let s = Scene::from_toml(text, &path).unwrap();
    let view = s.view(0.0).unwrap();
    let bvh = Bvh::build(view.meshes.clone()).unwrap();
    let light = s.lighting.light.as_ref().unwrap();
    let (w, h) = (96, 72);
    for method in [Method::Trace, Method::Raster] {
        let (frame, _) = render(&s, method, &()).unwrap();
        let (mut shadowed, mut agree, mut ground) = (0, 0, 0);
        for y in 0..h {
            for x in 0..w {
                if frame.object_id.get(x, y) != 0 {
                    continue;
                }
                ground += 1;
                let ray = view.camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                let p = ray.at(frame.depth.get(x, y));
                let blocked = bvh.any_hit(
                    &Ray::new(p + Vec3::Y * s.render.ray_epsilon, light.direction),
                    f32::INFINITY,
                );
                // Albedo 0.5, irradiance 3 at cos θ = l·y: 0.5 · 3 · cos θ / π when lit.
                let lit = 0.5 * light.irradiance.x * light.direction.y / std::f32::consts::PI;
                let expected = if blocked { 0.0 } else { lit };
                let c = frame.color.get(x, y).x;
                shadowed += blocked as u32;
                agree += ((c - expected).abs() < 1e-4) as u32;
            }
        }
        assert!(
            shadowed > 100,
            "{method}: the ball casts a shadow ({shadowed} pixels)"
        );
        // Traced: every ground pixel. Rasterized: the same but where a pixel's rasterized
        // position falls on the other side of the shadow's edge.
        let need = if method == Method::Trace {
            ground
        } else {
            ground - ground / 200
        };
        assert!(
            agree >= need,
            "{method}: {agree} of {ground} ground pixels as expected"
        );
    }
}

#[test]
fn wyman_exit_rays_are_exact_on_a_spheres_centre_line_and_close_near_it() {
    use std::sync::Arc;
    use trompe::geom::optics::facing;
    use trompe::glam::{DVec2, Vec3};
    use trompe::render::wyman::{BackFaces, exact_exit, exit_ray};
    use trompe::scene::View;
    use trompe::trace::{Bvh, RayQuery};
    // A unit glass sphere seen from 5 units away, an odd image so the centre pixel's ray is the
    // centre line.
    let sphere = Arc::new(trompe::geom::icosphere(5));
    let ior = 1.5;
    let camera = trompe::camera::Pinhole::look_at(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        Vec3::Y,
        30.0,
        65,
        65,
    )
    .unwrap();
    let view = View {
        lens: None,
        camera: camera.clone(),
        meshes: vec![sphere.clone()],
        surfaces: vec![Surface::Glass {
            ior,
            tint: Vec3::ONE,
        }],
    };
    let backs = BackFaces::build(&view).unwrap();
    let bvh = Bvh::build(vec![sphere.clone()]).unwrap();
    let (mut centre, mut errors) = (None, Vec::new());
    for y in 0..65u32 {
        for x in 0..65u32 {
            let ray = camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
            let Some(hit) = bvh.closest_hit(&ray, f32::INFINITY) else {
                continue;
            };
            let (n1, _, _) = facing(ray.dir, hit.normal, hit.geometric_normal);
            let pixel = (y * 65 + x) as usize;
            let d_v = backs.at(pixel, 0).map_or(0.0, |(t, _)| t - hit.t);
            let d_n = backs.d_n_at(&sphere, 0, hit.triangle, hit.bary);
            let wy = exit_ray(hit.position, n1, ray.dir, ior, d_v, d_n, |p| {
                backs.at_point(p, 0).map(|(_, n)| n)
            })
            .unwrap();
            let ex = exact_exit(&bvh, &hit, ray.dir, ior, 1e-5).unwrap();
            let angle = wy.1.angle_between(ex.1).to_degrees();
            let incidence = (-ray.dir.dot(n1)).acos().to_degrees();
            if (x, y) == (32, 32) {
                centre = Some((angle, wy.0.distance(ex.0)));
            }
            errors.push((incidence, angle));
        }
    }
    let (angle, offset) = centre.expect("the centre pixel sees the sphere");
    assert!(
        angle < 0.05 && offset < 1e-3,
        "centre line: {angle}° apart, exits {offset} apart"
    );
    // Within 30° of normal incidence Wyman's distance estimate stays close.
    let near: Vec<f32> = errors.iter().filter(|e| e.0 < 30.0).map(|e| e.1).collect();
    let mean = near.iter().sum::<f32>() / near.len() as f32;
    let worst = near.iter().cloned().fold(0.0, f32::max);
    println!("Wyman vs exact exit directions, incidence < 30°: mean {mean:.2}°, worst {worst:.2}°");
    assert!(near.len() > 100, "{}", near.len());
    assert!(mean < 1.5 && worst < 3.0, "mean {mean}°, worst {worst}°");
    let all = errors.iter().map(|e| e.1).sum::<f32>() / errors.len() as f32;
    println!(
        "over the whole sphere ({} pixels, grazing included): mean {all:.2}°",
        errors.len()
    );
}

#[test]
fn a_planar_mirror_answered_by_a_pinhole_impostor_from_the_mirrored_eye_matches_trace() {
    use std::sync::Arc;
    use trompe::glam::{Mat4, Vec3};
    use trompe::impostor::{ImpostorCamera, build};
    use trompe::render::shading::{albedo, lambert, lit};
    use trompe::render::{ReflectorImpostors, Tracer, render_trace};
    use trompe::scene::View;
    use trompe::trace::{Bvh, Exact};
    // A vertical mirror in the z = 0 plane facing +z, the Duck between it and the eye.
    let s = scene("reflections.toml");
    let duck = trompe::geom::io::load(&common::asset("gltf/Duck.glb"))
        .unwrap()
        .mesh;
    let b = duck.bounds();
    let fit = Mat4::from_translation(Vec3::new(0.0, 0.0, 1.2))
        * Mat4::from_scale(Vec3::splat(0.5 / b.extent().max_element()))
        * Mat4::from_translation(-Vec3::new(b.center().x, b.min.y, b.center().z));
    let duck = Arc::new(duck.transformed(&fit));
    let mirror = Arc::new(trompe::geom::plane(1).transformed(
        &(Mat4::from_translation(Vec3::new(0.0, 0.75, 0.0))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(2.0))),
    ));
    let eye = Vec3::new(0.35, 0.9, 3.0);
    let camera =
        trompe::camera::Pinhole::look_at(eye, Vec3::new(0.0, 0.5, 0.0), Vec3::Y, 40.0, 160, 120)
            .unwrap();
    let surfaces = vec![Surface::Diffuse(None), Surface::Mirror { tint: Vec3::ONE }];
    let view = View {
        lens: None,
        camera,
        meshes: vec![duck.clone(), mirror],
        surfaces: surfaces.clone(),
    };
    let bvh = Bvh::build(view.meshes.clone()).unwrap();
    // Every ray the mirror reflects passes through the eye mirrored in its plane: a pinhole
    // there sees exactly what those rays meet.
    let mirrored = Vec3::new(eye.x, eye.y, -eye.z);
    let target = duck.bounds().center();
    let half = duck.bounds().radius() / mirrored.distance(target);
    let fov = 2.0 * half.atan().to_degrees() * 1.1;
    let pinhole =
        trompe::camera::Pinhole::look_at(mirrored, target, Vec3::Y, fov as f64, 1024, 1024)
            .unwrap()
            .with_near(0.01);
    let eps = 1e-4;
    let color = |p: &trompe::impostor::SurfaceSample| {
        let n = if p.normal.dot(mirrored - p.position) < 0.0 {
            -p.normal
        } else {
            p.normal
        };
        lambert(
            albedo(&duck, &surfaces[0], p.triangle, p.uv),
            n,
            &s.lighting,
            |l| lit(&bvh, p.position, n, l, eps),
        )
    };
    let imp = build(ImpostorCamera::Pinhole(pinhole), &duck, 0, &color).unwrap();
    let answers = ReflectorImpostors::from_impostors(&view, vec![Vec::new(), vec![imp]]).unwrap();
    let settings = trompe::scene::RenderSettings {
        max_depth: 4,
        time: 0.0,
        ray_epsilon: eps,
    };
    let frame = |secondary: &dyn trompe::trace::SecondaryQuery| {
        let tracer = Tracer {
            view: &view,
            primary: &bvh,
            secondary,
            lighting: &s.lighting,
            settings: &settings,
        };
        render_trace(&tracer, &()).unwrap()
    };
    let exact = frame(&Exact(&bvh));
    let imposted = frame(&answers);
    // Over the mirror's pixels (the Duck's reflection and the panorama's).
    let mask = exact.object_id.map(|id| id == 1);
    let flip = metrics::flip(&exact.color, &imposted.color, Some(&mask)).unwrap();
    let seen = mask.pixels().iter().filter(|&&m| m).count();
    println!(
        "planar mirror, pinhole impostor from the mirrored eye: FLIP {flip:.5} over {seen} px"
    );
    assert!(seen > 2000, "the mirror covers {seen} pixels");
    assert!(flip <= 0.01, "FLIP {flip} over the mirror");
    // The Duck is in the mirror: the panorama alone misses it.
    let env = frame(&trompe::trace::EnvironmentOnly);
    let without = metrics::flip(&exact.color, &env.color, Some(&mask)).unwrap();
    assert!(without > 10.0 * flip, "the panorama alone: FLIP {without}");
}

/// Two facing planar mirrors and the Duck between them, seen obliquely: the view, and the
/// pixels whose reflected ray meets the other mirror (second-bounce pixels).
fn facing_mirrors(size: (u32, u32)) -> (trompe::scene::View, trompe::Image<bool>) {
    use std::sync::Arc;
    use trompe::geom::optics::{facing, reflect};
    use trompe::glam::{DVec2, Mat4, Vec3};
    use trompe::trace::{Bvh, RayQuery};
    let duck = trompe::geom::io::load(&common::asset("gltf/Duck.glb"))
        .unwrap()
        .mesh;
    let b = duck.bounds();
    let fit = Mat4::from_translation(Vec3::new(0.3, 0.0, 1.2))
        * Mat4::from_scale(Vec3::splat(0.6 / b.extent().max_element()))
        * Mat4::from_translation(-Vec3::new(b.center().x, b.min.y, b.center().z));
    let floor = trompe::geom::plane(1).transformed(&Mat4::from_scale(Vec3::splat(3.0)));
    let wall = |z: f32, turn: f32| {
        Arc::new(trompe::geom::plane(1).transformed(
            &(Mat4::from_translation(Vec3::new(0.0, 0.8, z))
                * Mat4::from_rotation_x(turn)
                * Mat4::from_scale(Vec3::new(2.4, 1.0, 1.4))),
        ))
    };
    let half_pi = std::f32::consts::FRAC_PI_2;
    let camera = trompe::camera::Pinhole::look_at(
        Vec3::new(-0.5, 1.3, 2.0),
        Vec3::new(0.2, 0.6, 0.0),
        Vec3::Y,
        45.0,
        size.0,
        size.1,
    )
    .unwrap();
    let view = trompe::scene::View {
        lens: None,
        camera,
        meshes: vec![
            Arc::new(duck.transformed(&fit)),
            Arc::new(floor),
            wall(0.0, half_pi),
            wall(2.4, -half_pi),
        ],
        surfaces: vec![
            Surface::Diffuse(None),
            Surface::Diffuse(None),
            Surface::Mirror {
                tint: Vec3::splat(0.9),
            },
            Surface::Mirror {
                tint: Vec3::splat(0.9),
            },
        ],
    };
    let bvh = Bvh::build(view.meshes.clone()).unwrap();
    let mut second = trompe::Image::new(size.0, size.1, false).unwrap();
    for (x, y) in (0..size.1).flat_map(|y| (0..size.0).map(move |x| (x, y))) {
        let v = {
            let ray = view.camera.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
            bvh.closest_hit(&ray, f32::INFINITY)
                .filter(|h| h.object >= 2)
                .is_some_and(|h| {
                    let (n, ng, _) = facing(ray.dir, h.normal, h.geometric_normal);
                    let out = trompe::Ray::new(h.position + ng * 1e-4, reflect(ray.dir, n));
                    bvh.closest_hit(&out, f32::INFINITY)
                        .is_some_and(|g| g.object >= 2 && g.object != h.object)
                })
        };
        second.set(x, y, v);
    }
    (view, second)
}

#[test]
fn two_facing_mirrors_seen_through_impostors_agree_with_tracing_on_the_second_bounce() {
    use trompe::render::{Mirrors, RenderOptions, render_view};
    let s = scene("reflections.toml");
    let (view, second) = facing_mirrors((200, 150));
    let settings = trompe::scene::RenderSettings {
        max_depth: 6,
        ..s.render
    };
    let frame = |options: RenderOptions| {
        render_view(
            &view,
            (&s.lighting, &settings),
            options,
            &Default::default(),
            &(),
            &mut Default::default(),
        )
        .unwrap()
    };
    let exact = frame(RenderOptions::new(Method::Trace));
    let imposted = frame(RenderOptions::new(Method::Impostor(512)).mirrors(Mirrors::Impostor));
    let pixels: Vec<_> = (0..150)
        .flat_map(|y| (0..200).map(move |x| (x, y)))
        .filter(|&(x, y)| second.get(x, y))
        .collect();
    assert!(pixels.len() > 3000, "{} second-bounce pixels", pixels.len());
    // Agreement: every channel within 0.02 + 5 % of the traced radiance.
    let agree = pixels
        .iter()
        .filter(|&&(x, y)| {
            let (e, i) = (exact.color.get(x, y), imposted.color.get(x, y));
            (e - i).truncate().abs().max_element() <= 0.02 + 0.05 * e.truncate().max_element()
        })
        .count();
    let share = agree as f64 / pixels.len() as f64;
    eprintln!(
        "{agree} of {} second-bounce pixels agree ({:.2} %)",
        pixels.len(),
        100.0 * share
    );
    assert!(share >= 0.99, "{:.2} % agree", 100.0 * share);
}

#[test]
fn a_rasterized_primary_pass_differs_from_the_traced_one_on_silhouettes_only() {
    use trompe::render::{Primary, RenderOptions, render_with};
    let s = scene("reflections.toml");
    let t = s.render.time;
    let options = RenderOptions::new(Method::Impostor(128));
    let traced = render_with(&s, t, options, &()).unwrap().0;
    let rasterized = render_with(&s, t, options.primary(Primary::Rasterized), &())
        .unwrap()
        .0;
    let (w, h) = traced.color.size();
    let differ = traced
        .object_id
        .pixels()
        .iter()
        .zip(rasterized.object_id.pixels())
        .filter(|(a, b)| a != b)
        .count();
    // Different surfaces on under 1 % of pixels (where coverage rules meet edges).
    assert!(
        differ * 100 < (w * h) as usize,
        "{differ} pixels see another object"
    );
    let score = metrics::compare(&traced.color, &rasterized.color, None).unwrap();
    assert!(score.flip < 0.01, "FLIP {}", score.flip);
}

#[test]
fn a_scene_object_can_be_a_maze_floor_plan() {
    let s = scene("maze.toml");
    let maze = &s.objects[0];
    assert_eq!(maze.name, "maze");
    // scenes/maze.maze: 11 × 11 cells, 68 of them walls, a unit cube (12 triangles) each, and
    // the two triangles of the floor.
    assert_eq!(maze.mesh.triangle_count(), 68 * 12 + 2);
    assert!(s.files.iter().any(|f| f.ends_with("maze.maze")));
}

#[test]
fn a_mirror_ball_in_the_maze_sees_it_through_its_graph_camera_and_keeps_it_as_it_rolls() {
    use trompe::render::{RenderOptions, Sequence};
    let mut s = scene("maze.toml");
    (s.camera.width, s.camera.height) = (160, 120);
    let t = s.render.time;
    let (truth, _) = trompe::render::render_at(&s, t, Method::Trace, &()).unwrap();
    let mut sequence = Sequence::new(&s, RenderOptions::new(Method::Impostor(256)));
    let (frame, _, first) = sequence.frame(t, &()).unwrap();
    // One graph-camera impostor of the maze, one SPOC a bunny.
    assert_eq!(first.built, 5, "{first}");
    let mask = truth.object_id.map(|id| id == 1);
    let score = metrics::compare(&truth.color, &frame.color, Some(&mask)).unwrap();
    assert!(score.flip < 0.02, "FLIP over the ball {}", score.flip);
    // The ball rolls half a metre: the bunnies' SPOCs are rebuilt, the maze's is kept.
    let (_, _, later) = sequence.frame(t + 0.5, &()).unwrap();
    assert_eq!((later.built, later.reused), (4, 1), "{later}");
}

#[test]
fn rasterized_and_traced_primaries_shade_a_degenerate_normal_triangle_the_same() {
    use std::sync::Arc;
    use trompe::glam::Vec3;
    use trompe::render::{Primary, RenderOptions, StandIns, render_view};
    let s = scene("diffuse.toml");
    let mut view = s.view(s.render.time).unwrap();
    // One large triangle in front of the camera whose vertex normals are zero (a file may say
    // so): the interpolated normal is zero everywhere, so both primaries must fall back to the
    // face normal.
    let camera = view.camera.clone();
    let eye = camera.position().as_vec3();
    let ahead = camera.forward().as_vec3();
    let side = ahead.cross(Vec3::Y).normalize();
    let up = side.cross(ahead);
    let centre = eye + ahead * 3.0;
    let mut mesh = view.meshes[0].as_ref().clone();
    mesh.positions = vec![
        centre - side * 2.0 - up * 1.5,
        centre + side * 2.0 - up * 1.5,
        centre + up * 2.0,
    ];
    mesh.normals = vec![Vec3::ZERO; 3];
    mesh.uvs = None;
    mesh.triangles = vec![[0, 1, 2]];
    mesh.face_material = vec![0];
    view.meshes = vec![Arc::new(mesh)];
    view.surfaces = vec![Surface::Diffuse(None)];
    let shade = |options: RenderOptions| {
        let lighting = (&s.lighting, &s.render);
        let mut timings = trompe::Timings::default();
        render_view(
            &view,
            lighting,
            options,
            &StandIns::default(),
            &(),
            &mut timings,
        )
        .unwrap()
    };
    let trace = RenderOptions::new(Method::Trace);
    let traced = shade(trace.primary(Primary::Traced));
    // The rasterized primary pass of the tracing methods, and the raster method (the same
    // tracer at depth 1): one shading path.
    for rasterized in [
        shade(trace.primary(Primary::Rasterized)),
        shade(RenderOptions::new(Method::Raster)),
    ] {
        let (w, h) = traced.color.size();
        let (mut both, mut same) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                if traced.object_id.get(x, y) != 0 || rasterized.object_id.get(x, y) != 0 {
                    continue;
                }
                both += 1;
                let (a, b) = (traced.color.get(x, y), rasterized.color.get(x, y));
                let (na, nb) = (traced.normal.get(x, y), rasterized.normal.get(x, y));
                if (a - b).abs().max_element() <= 1e-5 && (na - nb).length() <= 1e-5 {
                    same += 1;
                }
            }
        }
        assert!(
            both > (w * h) as usize / 10,
            "{both} pixels see the triangle"
        );
        assert_eq!(
            same,
            both,
            "{} of {both} pixels shaded differently",
            both - same
        );
    }
}

/// A radiance past f32's range (an environment 3e38 times as bright) makes no picture: every
/// method refuses the frame, naming its first pixel that is not a number, rather than writing it.
#[test]
fn a_frame_whose_radiance_overflows_is_refused() {
    let path = common::root().join("scenes/diffuse.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("intensity = 0.55", "intensity = 3e38")
        .replace("resolution = [480, 320]", "resolution = [24, 16]");
    let scene = Scene::from_toml(&text, &path).unwrap();
    let e = render(&scene, Method::Trace, &()).unwrap_err();
    assert!(
        matches!(e, trompe::render::RenderError::Radiance { .. }),
        "{e}"
    );
    assert!(e.to_string().contains("passes f32's range"), "{e}");
    for kind in [
        trompe::methods::MethodKind::Raster,
        trompe::methods::MethodKind::C3rc,
    ] {
        let mut r = trompe::methods::Renderer::new(&scene, kind, Default::default()).unwrap();
        let e = r.frame(0.0, None, &()).map(|_| ()).unwrap_err();
        assert!(
            e.to_string().contains("passes f32's range"),
            "{}: {e}",
            kind.name()
        );
    }
}
