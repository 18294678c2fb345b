//! Relief impostors on real models: the validity heuristic against the brute force along a walk,
//! the pipeline's walk of a shipped scene, and the `trompe relief` command.

use std::path::Path;
use trompe::glam::Vec3;
use trompe::relief::ObjectState;
use trompe::relief::shader::SoftwareShader;
use trompe::relief::walk::verdicts_along;
use trompe::relief::{PipelineSettings, WalkSettings, walk};
use trompe::scene::Scene;

fn walk_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/relief-walk.toml");
    let mut scene = Scene::load(&path).expect("the shipped relief scene");
    scene.camera.width = 160;
    scene.camera.height = 120;
    scene
}

/// Eyes on a horizontal orbit around `centre`, `step` degrees apart.
fn orbit(centre: Vec3, radius: f32, height: f32, step: f32, n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let a = (i as f32 * step).to_radians();
            centre + Vec3::new(radius * a.sin(), height, radius * a.cos())
        })
        .collect()
}

#[test]
fn the_heuristic_and_the_brute_force_agree_along_walks() {
    let scene = walk_scene();
    let view = scene.view(0.0).unwrap();
    let shader = SoftwareShader::new(&view, &scene.lighting, &scene.render).unwrap();
    let mut judged = Vec::new();
    for object in 0..2 {
        // Impostors made every 15°, each judged over the 45° that follow: young ones valid,
        // old ones obsolete.
        let eyes = orbit(Vec3::new(0.0, 0.3, 0.0), 6.5, 1.2, 3.0, 60);
        judged.extend(verdicts_along(&shader, object, &eyes, 5, 15, 128, 4).unwrap());
    }
    let threshold = trompe::relief::validity::RATIO_THRESHOLD;
    let obsolete = judged.iter().filter(|(_, r)| *r > threshold).count();
    let agree = judged
        .iter()
        .filter(|(p, r)| (*p > threshold) == (*r > threshold))
        .count() as f64
        / judged.len() as f64;
    println!(
        "agreement {:.1} % on {} eyes ({obsolete} obsolete by the brute force)",
        agree * 100.0,
        judged.len()
    );
    // Both verdicts are common, so that a heuristic that always says one thing scores at most
    // the larger share — below the bound.
    let share = obsolete as f64 / judged.len() as f64;
    assert!((0.25..=0.75).contains(&share), "obsolete share {share}");
    assert!(agree >= 0.9, "agreement {agree}");
}

#[test]
fn a_walk_regenerates_warps_and_scores_every_frame() {
    let scene = walk_scene();
    let settings = WalkSettings {
        frames: 72,
        pipeline: PipelineSettings {
            resolution: 128,
            first_resolution: Some(32),
            deterministic: Some(1),
            predict: 1,
            ..Default::default()
        },
        objects: Vec::new(),
        score: true,
    };
    let mut seen = 0;
    let report = walk(&scene, &settings, &(), &mut |_, frame, truth| {
        assert_eq!(frame.color.size(), (160, 120));
        assert!(truth.is_some());
        seen += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!(seen, 72);
    println!("{report}");
    // Five degrees a frame around the scene: impostors are made along the way (the paper's
    // walk needs 17 an object) and most frames are warped from a valid one.
    assert!(report.regenerations >= 12, "{}", report.regenerations);
    assert!(report.count(ObjectState::Warping) >= 36);
    // Warped frames stay close to the truth (the background dominates: a loose bound that
    // an empty or misplaced impostor fails).
    let warped: Vec<f64> = report
        .frames
        .iter()
        .filter(|f| f.objects.iter().all(|o| o.state == ObjectState::Warping))
        .filter_map(|f| f.psnr)
        .collect();
    assert!(!warped.is_empty());
    let mean = warped.iter().sum::<f64>() / warped.len() as f64;
    assert!(mean > 25.0, "{mean}");
    // The same walk again: the same decisions (deterministic mode).
    let again = walk(&scene, &settings, &(), &mut |_, _, _| Ok(())).unwrap();
    let states = |r: &trompe::relief::WalkReport| -> Vec<_> {
        r.frames.iter().map(|f| f.objects.clone()).collect()
    };
    let (a, b) = (states(&report), states(&again));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        for (p, q) in x.iter().zip(y) {
            assert_eq!(
                (p.state, p.regenerated, p.cache_hit),
                (q.state, q.regenerated, q.cache_hit)
            );
            assert_eq!(p.ratio, q.ratio);
        }
    }
}
