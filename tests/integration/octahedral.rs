//! Octahedral impostors: a frame reproduced from its own direction, dilation, and a turntable
//! against the exact render.

use std::path::Path;
use trompe::frame::envmap::EnvMap;
use trompe::frame::metrics;
use trompe::glam::Vec3;
use trompe::octahedral::{BakeSettings, Coverage, FrameProjection, Grid, bake, turntable};
use trompe::scene::{Light, Lighting, Surface};

fn duck() -> trompe::geom::Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/gltf/Duck.glb");
    trompe::geom::io::load(&path).unwrap().mesh
}

fn lighting() -> Lighting {
    Lighting {
        environment: EnvMap::constant(Vec3::new(0.25, 0.3, 0.35)),
        light: Some(Light {
            direction: Vec3::new(0.4, 1.0, 0.6).normalize(),
            irradiance: Vec3::splat(0.9 * std::f32::consts::PI),
        }),
    }
}

fn settings(n: u32, frame_size: u32, dilation: u32) -> BakeSettings {
    BakeSettings {
        grid: Grid {
            n,
            coverage: Coverage::Sphere,
        },
        frame_size,
        dilation,
        projection: Default::default(),
    }
}

#[test]
fn a_frame_is_reproduced_from_its_own_direction() {
    let mesh = duck();
    let light = lighting();
    let pinhole = FrameProjection::Pinhole { distance: 2.5 };
    for projection in [FrameProjection::Orthographic, pinhole] {
        let atlas = bake(
            &mesh,
            &Surface::Diffuse(None),
            BakeSettings {
                projection,
                ..settings(8, 96, 4)
            },
        )
        .unwrap();
        for (i, j) in [(3, 4), (0, 0), (7, 2), (5, 5)] {
            let camera = atlas.frame_camera(i, j);
            let d = atlas.settings.grid.direction(i, j);
            let s = atlas.settings.frame_size;
            let rendered = atlas.render_rays((s, s), d, |uv| camera.ray(uv), &light, 4);
            // The frame itself, lit as the renderer lights it.
            let mut expected = rendered.clone();
            for y in 0..s {
                for x in 0..s {
                    let c = atlas.color.get(i * s + x, j * s + y);
                    let n = atlas.normal.get(i * s + x, j * s + y);
                    let ray = camera.ray(trompe::glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                    let env = light.environment.radiance(ray.dir);
                    let lit = if c.w > 0.0 {
                        trompe::render::shading::lambert(c.truncate(), n, &light, |_| true) * c.w
                            + env * (1.0 - c.w)
                    } else {
                        env
                    };
                    expected.set(x, y, lit.extend(1.0));
                }
            }
            let psnr = metrics::psnr(&expected, &rendered, None).unwrap();
            println!("{projection:?} frame ({i}, {j}): PSNR {psnr:.1} dB");
            assert!(psnr >= 45.0, "{projection:?} frame ({i}, {j}): {psnr} dB");
        }
    }
}

#[test]
fn dilation_fills_around_the_object_and_keeps_what_it_covers() {
    let mesh = duck();
    let plain = bake(&mesh, &Surface::Diffuse(None), settings(4, 64, 0)).unwrap();
    let grown = bake(&mesh, &Surface::Diffuse(None), settings(4, 64, 3)).unwrap();
    let side = plain.side();
    let (mut covered, mut filled) = (0, 0);
    for y in 0..side {
        for x in 0..side {
            let c = plain.color.get(x, y);
            if c.w > 0.0 {
                covered += 1;
                assert_eq!(grown.color.get(x, y), c);
                assert_eq!(grown.normal.get(x, y), plain.normal.get(x, y));
                assert_eq!(grown.depth.get(x, y), plain.depth.get(x, y));
                continue;
            }
            // Within 3 texels of a covered texel of the same frame: filled, still uncovered.
            let (fx, fy) = (x / 64, y / 64);
            let near = (-3i64..=3).any(|dy| {
                (-3i64..=3).any(|dx| {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    nx >= 0
                        && ny >= 0
                        && (nx as u32) < side
                        && (ny as u32) < side
                        && nx as u32 / 64 == fx
                        && ny as u32 / 64 == fy
                        && plain.color.get(nx as u32, ny as u32).w > 0.0
                })
            });
            if near {
                let g = grown.color.get(x, y);
                assert!(
                    g.w == 0.0 && g.truncate() != Vec3::ZERO,
                    "({x}, {y}) not filled"
                );
                assert!(grown.normal.get(x, y) != Vec3::ZERO);
                filled += 1;
            }
        }
    }
    assert!(covered > 1000 && filled > 500, "{covered} {filled}");
    // Beyond the ring, every texel of every frame holds a colour and a normal of its own frame's
    // object, so coarse mip levels never average in the background.
    for y in 0..side {
        for x in 0..side {
            // (Colours can be black, as the eyes are; a normal is never zero.)
            assert!(
                grown.normal.get(x, y).is_normalized(),
                "({x}, {y}) left empty"
            );
        }
    }
}

#[test]
fn a_turntable_of_the_duck_is_close_to_exact_and_parallax_helps() {
    let mesh = duck();
    let atlas = bake(&mesh, &Surface::Diffuse(None), settings(16, 96, 4)).unwrap();
    let views = turntable(&atlas, &mesh, &Surface::Diffuse(None), &lighting(), 16, 160).unwrap();
    let n = views.len() as f64;
    let with = views.iter().map(|v| v.flip).sum::<f64>() / n;
    let without = views.iter().map(|v| v.flip_flat).sum::<f64>() / n;
    let worst = views.iter().map(|v| v.flip).fold(0.0, f64::max);
    println!(
        "Duck 16 × 16: mean FLIP {with:.4} with parallax (worst {worst:.4}), {without:.4} without"
    );
    assert!(with <= 0.05, "{with}");
    assert!(with < without, "{with} vs {without}");
    // The worst view, with depth-aware blending (0.0539 at these 96² frames and 160² views).
    assert!(worst <= 0.054, "worst view {worst}");
    // Pinhole frames from the turntable's own distance (4 radii).
    let pinhole = BakeSettings {
        projection: FrameProjection::Pinhole { distance: 4.0 },
        ..settings(16, 96, 4)
    };
    let atlas = bake(&mesh, &Surface::Diffuse(None), pinhole).unwrap();
    let views = turntable(&atlas, &mesh, &Surface::Diffuse(None), &lighting(), 16, 160).unwrap();
    let perspective = views.iter().map(|v| v.flip).sum::<f64>() / n;
    println!("Duck 16 × 16, pinhole frames at 4 radii: mean FLIP {perspective:.4}");
    assert!(perspective <= 0.05, "{perspective}");
}

#[test]
fn grids_out_of_range_are_errors() {
    let mesh = trompe::geom::icosphere(1);
    for (n, size) in [(0, 16), (1, 16), (65, 16), (8, 0), (64, u32::MAX / 2)] {
        assert!(
            bake(&mesh, &Surface::Diffuse(None), settings(n, size, 0)).is_err(),
            "{n} {size}"
        );
    }
}

#[test]
fn the_orm_map_holds_traced_occlusion_and_the_materials_roughness_and_metalness() {
    use trompe::geom::{icosphere, plane};
    use trompe::octahedral::bake::vertex_occlusion;
    // A ball of radius ½ resting on a 3 × 3 floor.
    let mut scene = plane(30);
    for p in &mut scene.positions {
        *p *= 3.0;
    }
    let mut ball = icosphere(3);
    for p in &mut ball.positions {
        *p += Vec3::new(0.0, 0.5, 0.0);
    }
    scene.append(&ball);
    let ao = vertex_occlusion(&scene, 2.0).unwrap();
    let at = |q: Vec3| {
        let v = (0..scene.positions.len())
            .min_by(|&a, &b| {
                (scene.positions[a] - q)
                    .length()
                    .total_cmp(&(scene.positions[b] - q).length())
            })
            .unwrap();
        ao[v]
    };
    // Under the ball every upward ray meets it; at the floor's corner almost none does; nothing
    // occludes the top of a convex ball.
    assert!(at(Vec3::ZERO) < 0.1, "contact {}", at(Vec3::ZERO));
    assert!(at(Vec3::new(1.5, 0.0, 1.5)) > 0.9);
    assert_eq!(at(Vec3::new(0.0, 1.0, 0.0)), 1.0);
    let lone = icosphere(2);
    assert!(
        vertex_occlusion(&lone, 1.0)
            .unwrap()
            .iter()
            .all(|&o| o == 1.0)
    );

    // Roughness and metalness come from the material, or from the scene's surface.
    let mut metal = icosphere(2);
    metal.materials[0].roughness = 0.3;
    metal.materials[0].metallic = 0.7;
    let atlas = bake(&metal, &Surface::Diffuse(None), settings(4, 16, 0)).unwrap();
    let covered: Vec<Vec3> = (0..atlas.side() * atlas.side())
        .map(|k| (k % atlas.side(), k / atlas.side()))
        .filter(|&(x, y)| atlas.color.get(x, y).w > 0.0)
        .map(|(x, y)| atlas.orm.get(x, y))
        .collect();
    assert!(covered.len() > 100);
    for o in &covered {
        assert!(
            (*o - Vec3::new(1.0, 0.3, 0.7)).abs().max_element() < 1e-5,
            "{o}"
        );
    }
    let mirror = Surface::Mirror { tint: Vec3::ONE };
    let atlas = bake(&metal, &mirror, settings(4, 16, 0)).unwrap();
    let o = atlas.orm.get(24, 24);
    assert!(
        (o - Vec3::new(1.0, 0.0, 1.0)).abs().max_element() < 1e-5,
        "{o}"
    );
}

#[test]
fn a_scene_drawn_from_octahedral_atlases_comes_close_to_tracing_on_any_thread_count() {
    use trompe::render::{Method, render_at};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/duck-mirror.toml");
    let mut scene = trompe::scene::Scene::load(&path).unwrap();
    (scene.camera.width, scene.camera.height) = (160, 120);
    let t = scene.render.time;
    let draw = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut timings = trompe::progress::Timings::default();
                trompe::octahedral::scene::render(
                    &scene,
                    t,
                    settings(16, 128, 4),
                    &(),
                    &mut timings,
                )
                .unwrap()
            })
    };
    let (one, two) = (draw(1), draw(2));
    assert!(one.color == two.color && one.object_id == two.object_id);
    let (traced, _) = render_at(&scene, t, Method::Trace, &()).unwrap();
    // The same object seen at nearly every pixel (silhouettes differ by a texel or so).
    let same = one
        .object_id
        .pixels()
        .iter()
        .zip(traced.object_id.pixels())
        .filter(|(a, b)| a == b)
        .count();
    let share = same as f64 / (160.0 * 120.0);

    assert!(share > 0.97, "object ids agree on {share}");
    // Colours differ by what an atlas cannot hold: shadows, and the duck in the ball.
    let score = metrics::compare(&traced.color, &one.color, None).unwrap();
    eprintln!("object ids agree on {share}, FLIP {}", score.flip);
    assert!(score.flip < 0.15, "FLIP {}", score.flip);
}

/// A scene of teapots (and a mirror ball), the teapots written as one object with `instances`
/// or as objects of their own.
fn teapots(as_field: bool) -> trompe::scene::Scene {
    let at = [[-0.9, 0.0, 0.0], [0.0, 0.0, -0.6], [0.9, 0.0, 0.2]];
    let mut text = String::from(
        "[camera]\nposition = [0.0, 1.2, 3.0]\nlook_at = [0.0, 0.3, 0.0]\nfov_y = 40.0\n\
         resolution = [96, 64]\n[light]\ndirection = [0.4, 1.0, 0.6]\nintensity = 2.5\n",
    );
    let teapot = "[[object]]\nname = \"teapot\"\nmesh = \"../assets/meshes/teapot.obj\"\n\
                  fit = 0.6\nrotate = [0.0, 30.0, 0.0]\n";
    if as_field {
        text += teapot;
        text += &format!("instances = {at:?}\n");
    } else {
        for (k, a) in at.iter().enumerate() {
            text += &teapot.replace("\"teapot\"", &format!("\"teapot#{k}\""));
            text += &format!("translate = {a:?}\n");
        }
    }
    text += "[[object]]\nshape = \"sphere\"\nscale = 0.5\ntranslate = [0.0, 0.25, 0.8]\n\
             material = { type = \"mirror\" }\n";
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/teapot-field.toml");
    trompe::scene::Scene::from_toml(&text, &path).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn a_field_of_instances_is_one_atlas_drawn_as_its_copies_would_be_one_by_one() {
    use trompe::octahedral::scene::SceneAtlases;
    let (field, apart) = (teapots(true), teapots(false));
    let names: Vec<&str> = field.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["teapot#0", "teapot#1", "teapot#2", "sphere"]);
    let copy = field.objects[2].field.unwrap();
    assert_eq!((copy.first, copy.offset), (0, Vec3::new(1.8, 0.0, 0.2)));
    let t = field.render.time;
    let small = settings(8, 48, 4);
    let baked = SceneAtlases::bake(&field, t, small, &()).unwrap();
    let one_by_one = SceneAtlases::bake(&apart, t, small, &()).unwrap();
    assert_eq!((baked.atlases().count(), baked.placed().len()), (2, 4));
    assert_eq!(one_by_one.atlases().count(), 4);
    assert!(baked.report(8, true).contains("drawing 4 objects"));
    // Each method sees the copies as objects: traced, the two scenes are one picture.
    let (traced_field, _) =
        trompe::render::render(&field, trompe::render::Method::Trace, &()).unwrap();
    let (traced_apart, _) =
        trompe::render::render(&apart, trompe::render::Method::Trace, &()).unwrap();
    let same = |a: &trompe::frame::Frame, b: &trompe::frame::Frame| {
        let n = a.object_id.pixels().len() as f64;
        let same = (a.object_id.pixels().iter())
            .zip(b.object_id.pixels())
            .filter(|(x, y)| x == y)
            .count();
        (
            same as f64 / n,
            metrics::compare(&a.color, &b.color, None).unwrap().flip,
        )
    };
    let (ids, flip) = same(&traced_field, &traced_apart);
    assert!(
        ids >= 0.999 && flip < 1e-3,
        "traced: ids {ids}, FLIP {flip}"
    );
    for copy in 0..3 {
        assert!(
            traced_field.object_id.pixels().contains(&copy),
            "copy {copy} unseen"
        );
    }
    // Drawn from atlases: one atlas moved to each copy draws what three bakes draw.
    let camera = field.camera.at(t).unwrap();
    let drawn = baked.render_through(&camera, &field.lighting, &()).unwrap();
    let drawn_apart = one_by_one
        .render_through(&camera, &apart.lighting, &())
        .unwrap();
    let (ids, flip) = same(&drawn, &drawn_apart);
    eprintln!("a field drawn from one atlas against three bakes: ids {ids}, FLIP {flip}");
    assert!(ids >= 0.995 && flip < 0.01, "drawn: ids {ids}, FLIP {flip}");
}

#[test]
fn a_field_that_cannot_be_is_refused_by_its_key() {
    let base = "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\
                resolution = [32, 32]\n[[object]]\nshape = \"cube\"\n";
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bad-field.toml");
    let error = |extra: &str| {
        trompe::scene::Scene::from_toml(&format!("{base}{extra}"), &path)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let many = format!("instances = [{}]\n", vec!["[0, 0, 0]"; 4097].join(", "));
    let e = error(&many);
    assert!(
        e.contains("object[0].instances") && e.contains("4096"),
        "{e}"
    );
    let e = error("instances = [[0, 0, 0], [nan, 0, 0]]\n");
    assert!(
        e.contains("object[0].instances") && e.contains("finite"),
        "{e}"
    );
    let e = error("impostor = \"cube.json\"\ninstances = [[0, 0, 0], [1, 0, 0]]\n");
    assert!(
        e.contains("object[0].instances") && e.contains("no copies"),
        "{e}"
    );
}

/// The cut-out card spares pixels without losing any: from every side, the poles and their
/// neighbourhoods included, near and far, with orthographic and pinhole frames, over the sphere
/// and the upper hemisphere, the atlas drawn on its outline keeps exactly the pixels it keeps
/// on the whole square.
#[test]
fn the_cut_out_card_loses_no_pixel_the_square_card_draws() {
    use trompe::camera::Pinhole;
    use trompe::glam::{Mat4, Quat};
    use trompe::octahedral::Card;
    // The Duck, and a tall thin post leaning over (its outline far from the square).
    let post = trompe::geom::cube().transformed(
        &(Mat4::from_quat(Quat::from_rotation_z(0.4))
            * Mat4::from_scale(Vec3::new(0.1, 1.0, 0.15))),
    );
    let cases = [
        (
            "duck",
            duck(),
            Coverage::Sphere,
            FrameProjection::Orthographic,
        ),
        (
            "post",
            post.clone(),
            Coverage::Sphere,
            FrameProjection::Orthographic,
        ),
        (
            "post, hemisphere",
            post.clone(),
            Coverage::Hemisphere,
            FrameProjection::Orthographic,
        ),
        (
            "post, pinhole frames",
            post,
            Coverage::Sphere,
            FrameProjection::Pinhole { distance: 3.0 },
        ),
    ];
    for (name, mesh, coverage, projection) in cases {
        let settings = BakeSettings {
            grid: Grid { n: 8, coverage },
            projection,
            ..settings(8, 64, 2)
        };
        let cut = bake(&mesh, &Surface::Diffuse(None), settings).unwrap();
        let mut square = cut.clone();
        square.card = Card::default();
        let share = cut.card.area_share();
        let (mut pixels, mut drawn) = (0usize, 0usize);
        let lowest = if coverage == Coverage::Sphere { -90 } else { 0 };
        for elevation in [
            -90.0, -89.5, -88.0, -60.0, -20.0, 0.0, 20.0, 60.0, 88.0, 89.5, 90.0f32,
        ] {
            if elevation < lowest as f32 {
                continue;
            }
            for azimuth in (0..16).map(|k| k as f32 * 22.5 + 3.0) {
                for (distance, fov) in [(1.6f32, 90.0f64), (4.0, 32.0)] {
                    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
                    let d = Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
                    let up = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
                    let eye = cut.centre + d * (distance * cut.radius);
                    let camera = Pinhole::look_at(eye, cut.centre, up, fov, 48, 48).unwrap();
                    let light = lighting();
                    let a = cut.render_cutout(&camera, &light, 4);
                    let b = square.render_cutout(&camera, &light, 4);
                    let background = light.environment.radiance(Vec3::Y).extend(1.0);
                    for (p, q) in a.pixels().iter().zip(b.pixels()) {
                        pixels += 1;
                        drawn += usize::from(*q != background);
                        assert_eq!(
                            p, q,
                            "{name}: a pixel lost from ({azimuth}°, {elevation}°) at {distance} radii"
                        );
                    }
                }
            }
        }
        println!(
            "{name}: the outline has {} vertices, {:.0} % of the square's area; {drawn} of {pixels} pixels drawn, none lost",
            cut.card.outline().len(),
            100.0 * share
        );
        assert!(share < 1.0, "{name}: {share}");
    }
}
