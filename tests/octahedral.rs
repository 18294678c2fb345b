//! Octahedral impostors: a frame reproduced from its own direction, dilation, and a turntable
//! against the exact render.

use std::path::Path;
use trompe::frame::envmap::EnvMap;
use trompe::frame::metrics;
use trompe::glam::Vec3;
use trompe::octahedral::{BakeSettings, Coverage, Grid, bake, turntable};
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
            radiance: Vec3::splat(0.9),
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
    }
}

#[test]
fn a_frame_is_reproduced_from_its_own_direction() {
    let mesh = duck();
    let atlas = bake(&mesh, &Surface::Diffuse(None), settings(8, 96, 4)).unwrap();
    let light = lighting();
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
                    trompe::render::shading::lambert(c.truncate(), n, &light) * c.w
                        + env * (1.0 - c.w)
                } else {
                    env
                };
                expected.set(x, y, lit.extend(1.0));
            }
        }
        let psnr = metrics::psnr(&expected, &rendered, None).unwrap();
        println!("frame ({i}, {j}): PSNR {psnr:.1} dB");
        assert!(psnr >= 45.0, "frame ({i}, {j}): {psnr} dB");
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
