//! Paper 2's `c3rc` method on the GPU against its CPU twin: the projection through continuous
//! 3-ray cameras alone, root by root, and whole frames of the shipped scenes with mirrors.

use glam::DVec3;
use trompe::camera::C3rc;
use trompe::frame::NO_OBJECT;
use trompe::hybrid::{HybridReflections, HybridSettings};
use trompe::methods::{MethodKind, MethodSettings};
use trompe_gpu::Gpu;
use trompe_gpu::c3rc::project_pairs;
use trompe_gpu::hybrid::GpuHybrid;

fn rng(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

/// A reflector triangle seen from an eye, its vertex normals tilted apart by up to `tilt`
/// (positive: the mirror bulges, its rays diverge; negative: it is concave and they cross).
fn camera(seed: &mut u64, tilt: f64) -> C3rc {
    let v = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.1 * rng(seed), 0.0),
        DVec3::new(0.2 * rng(seed), 1.0, 0.1 * rng(seed)),
    ];
    let centre = (v[0] + v[1] + v[2]) / 3.0;
    let n = v.map(|p| {
        let out = (p - centre) * tilt * (0.5 + rng(seed));
        DVec3::new(out.x, out.y, 1.0)
    });
    let eye = DVec3::new(0.3 * rng(seed), 0.3 * rng(seed), 3.0 + rng(seed));
    C3rc::reflector(v, n, eye).expect("a camera")
}

/// 24 000 points through random cameras, convex and concave (whose sweeps fold, so points
/// project two or three times): the GPU's f32 projection finds the CPU's f64 roots, every one,
/// its sweep parameter and barycentrics within 1e-4.
pub fn the_gpu_projects_points_through_c3rcs_as_the_cpu(gpu: &Gpu) {
    let mut seed = 7;
    let mut pairs = Vec::new();
    for case in 0..240 {
        let tilt = if case % 2 == 0 { 0.6 } else { -0.9 };
        let c = camera(&mut seed, tilt);
        let lambda_max = if case % 3 == 0 { f64::INFINITY } else { 6.0 };
        for k in 0..100 {
            // Points in the view volume (at least one projection) and anywhere near it.
            let q = if k % 2 == 0 {
                let (b1, b2) = (rng(&mut seed), rng(&mut seed));
                let (b1, b2) = if b1 + b2 > 1.0 {
                    (1.0 - b1, 1.0 - b2)
                } else {
                    (b1, b2)
                };
                c.at(DVec3::new(1.0 - b1 - b2, b1, b2), 5.0 * rng(&mut seed))
            } else {
                DVec3::new(
                    4.0 * rng(&mut seed) - 1.5,
                    4.0 * rng(&mut seed) - 1.5,
                    6.0 * rng(&mut seed) - 1.0,
                )
            };
            pairs.push((c, q, lambda_max));
        }
    }
    let on_gpu = project_pairs(gpu, &pairs).unwrap();
    let (mut roots, mut multiple, mut worst) = (0usize, 0usize, 0.0f64);
    let mut mismatches = Vec::new();
    for (i, ((c, q, lambda_max), g)) in pairs.iter().zip(&on_gpu).enumerate() {
        let cpu = c.project(*q, *lambda_max);
        roots += cpu.len();
        multiple += usize::from(cpu.len() > 1);
        if cpu.len() != g.len() {
            mismatches.push(format!(
                "pair {i}: CPU {} roots, GPU {}",
                cpu.len(),
                g.len()
            ));
            continue;
        }
        for (p, (lambda, bary)) in cpu.iter().zip(g) {
            let apart = (p.lambda - lambda)
                .abs()
                .max((p.bary - *bary).abs().max_element());
            worst = worst.max(apart);
            if apart > 1e-4 {
                mismatches.push(format!("pair {i}: {p:?} against ({lambda}, {bary})"));
            }
        }
    }
    println!(
        "{} points, {roots} projections ({multiple} points with several); largest difference \
         {worst:.2e}; {} mismatches",
        pairs.len(),
        mismatches.len()
    );
    for m in mismatches.iter().take(30) {
        println!("{m}");
    }
    assert!(multiple > 200, "the concave cameras fold: {multiple}");
    assert!(mismatches.is_empty(), "{mismatches:#?}");
}

/// The shipped scenes with mirrors or glass, at 320 × 240: the GPU's `c3rc` frame against the
/// CPU's through the library's one interface, object ids equal on ≥ 99.9 % of the pixels and
/// mean FLIP ≤ 0.02; the reflector pixels a point reached within 1 % of the CPU's, and the share
/// of them won by the same point printed (splat keys computed in f32 on the GPU may order two
/// nearly equal path lengths differently).
pub fn c3rc_frames_on_the_gpu_are_the_cpus(gpu: &Gpu) {
    let mut compared = 0;
    for (path, scene) in crate::trace::shipped_scenes() {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let view = scene.view(scene.render.time).unwrap();
        let reflects = view
            .surfaces
            .iter()
            .any(|s| !matches!(s, trompe::scene::Surface::Diffuse(_)));
        if !reflects || scene.camera.lens.is_some() {
            continue;
        }
        let t = scene.render.time;
        let clouds = HybridReflections::prepare(&scene, HybridSettings::default()).unwrap();
        let cpu = trompe::hybrid::render_frame(&clouds, &scene, t, &()).unwrap();
        let uploaded = GpuHybrid::new(gpu, &view, &scene.lighting, &scene.render, &clouds).unwrap();
        let started = std::time::Instant::now();
        let g = uploaded.frame(&clouds, &scene, &view, t).unwrap();
        let took = started.elapsed();
        let (ids, flip) = crate::agreement(&cpu.frame, &g.frame);
        let (cpu_reached, gpu_reached) = (cpu.stats.pixels_splatted, g.stats.pixels_splatted);
        let both = (cpu.winners.pixels().iter())
            .zip(g.winners.pixels())
            .filter(|(a, b)| **a != NO_OBJECT && **b != NO_OBJECT);
        let (mut shared, mut same) = (0usize, 0usize);
        for (a, b) in both {
            shared += 1;
            same += usize::from(a == b);
        }
        println!(
            "c3rc {name:>16}: ids {:.3} % equal, mean FLIP {flip:.5}; pixels reached {gpu_reached} \
             / {cpu_reached}, the same point winning {:.2} % of those both reach; C3RCs {} / {}, \
             projections {} / {} ({} ms on the GPU)",
            100.0 * ids,
            100.0 * same as f64 / shared.max(1) as f64,
            g.stats.c3rcs,
            cpu.stats.c3rcs,
            g.stats.projections,
            cpu.stats.projections,
            took.as_millis()
        );
        assert!(ids >= 0.999, "{name}: ids {ids}");
        assert!(flip <= 0.02, "{name}: FLIP {flip}");
        assert!(
            gpu_reached.abs_diff(cpu_reached) * 100 <= cpu_reached.max(1),
            "{name}: {gpu_reached} pixels reached against {cpu_reached}"
        );
        compared += 1;
    }
    assert!(compared >= 3, "{compared} scenes with mirrors");
}

/// The same frame twice gives the same bits, and `--device gpu` runs the method through the
/// library's one interface, reporting the adapter; a scene without mirrors renders as on the
/// CPU.
pub fn a_c3rc_frame_on_the_gpu_is_the_same_twice(gpu: &Gpu) {
    let (_, scene) = crate::trace::shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("c3rc-bunny.toml"))
        .expect("scenes/c3rc-bunny.toml");
    let mut renderer = trompe_gpu::DeviceRenderer::new(
        &scene,
        MethodKind::C3rc,
        MethodSettings::default(),
        Some(gpu),
    )
    .unwrap();
    let t = scene.render.time;
    let first = renderer.frame(t, None, &()).unwrap();
    let second = renderer.frame(t, None, &()).unwrap();
    println!("{}", second.report);
    assert!(first.report.contains("scene uploaded"), "{}", first.report);
    assert!(second.report.contains("scene kept"), "{}", second.report);
    assert!(first.frame.color.pixels() == second.frame.color.pixels());
    assert!(first.frame.object_id.pixels() == second.frame.object_id.pixels());
    // A scene without mirrors has no points and no cameras: the tracer's frame, on both devices.
    let (_, scene) = crate::trace::shipped_scenes()
        .into_iter()
        .find(|(p, _)| p.ends_with("diffuse.toml"))
        .expect("scenes/diffuse.toml");
    let frame = |device| {
        trompe_gpu::DeviceRenderer::new(&scene, MethodKind::C3rc, MethodSettings::default(), device)
            .and_then(|mut r| r.frame(scene.render.time, None, &()))
            .unwrap()
            .frame
    };
    let (ids, flip) = crate::agreement(&frame(None), &frame(Some(gpu)));
    assert!(
        ids >= 0.999 && flip <= 0.01,
        "no mirrors: ids {ids}, FLIP {flip}"
    );
}
