//! Impostor walks against the exact BVH (paper 1 §3.2 and §3.4: an impostor answers a reflected
//! ray for a cost that does not depend on the mesh behind it). Reflected rays of a teapot
//! mirror beside the bunny are walked through SPOC impostors of the bunny from 128² to 2048² —
//! the reference linear walk, the texel walk, and the texel walk with the pyramid (the default)
//! — each in ns per ray on one thread and texel visits per ray, beside the bunny's BVH on the
//! same rays; then the default walk of the same bunny subdivided twice (16 times the
//! triangles, the same surface) beside its BVH; then the automatic depth layers against one.

use super::{BenchError, Figure, time_pair_median};
use std::time::Duration;
use trompe::eval::fidelity::ReflectorSetup;
use trompe::geom::{Mesh, Ray};
use trompe::impostor::{Impostor, Layers, ViewCamera, WalkMode, albedo_of, build};
use trompe::trace::{Bvh, RayQuery};

/// Impostor sides the walks are measured at.
const SIDES: [u32; 5] = [128, 256, 512, 1024, 2048];
/// The side of the goals on layers and scene size.
const GOAL_SIDE: u32 = 512;

/// Mean ns per ray of `f` over `rays` on this thread, from a total `t`.
fn per_ray(t: Duration, rays: &[Ray]) -> f64 {
    t.as_secs_f64() * 1e9 / rays.len().max(1) as f64
}

/// Every ray's query on this thread, one after the other.
fn query_all(q: &dyn RayQuery, rays: &[Ray]) {
    for r in rays {
        std::hint::black_box(q.closest_hit(r, f32::INFINITY));
    }
}

/// Every ray's walk in `mode` on this thread.
fn walk_all(imp: &Impostor, rays: &[Ray], mode: WalkMode) {
    for r in rays {
        std::hint::black_box(imp.walk_mode(r, f32::INFINITY, mode));
    }
}

/// The walk figures (see the module's text) on the shipped bunny and teapot.
pub fn walks(
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    let load = |name: &str| trompe::geom::io::load(&inputs.assets.join(name)).map(|m| m.mesh);
    let (bunny, teapot) = (load("meshes/bunny.obj")?, load("meshes/teapot.obj")?);
    walks_of(&bunny, &teapot, quick)
}

/// The walk figures with `bunny` the replaced object and `teapot` the mirror.
pub fn walks_of(bunny: &Mesh, teapot: &Mesh, quick: bool) -> Result<Vec<Figure>, BenchError> {
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let mut out = Vec::new();
    let setup = ReflectorSetup::new(bunny, teapot, 1.4, 512)?;
    let rays = setup.rays()?;
    let exact = Bvh::build(vec![setup.target.clone()])?;
    out.push(Figure {
        name: format!(
            "impostor walks below: reflected rays of a teapot mirror that enter the box of the \
             bunny ({} triangles), one thread",
            setup.target.triangle_count()
        ),
        value: rays.len() as f64,
        unit: "rays",
        versus: None,
    });
    let color = albedo_of(&setup.target);
    let mut at_goal = None;
    for side in SIDES {
        let imp = build(
            setup.camera(ViewCamera::Spoc(None), side)?,
            &setup.target,
            0,
            &color,
        )?;
        imp.prepare_walks();
        let modes = [
            (WalkMode::Linear, "linear (paper 1 §3.2)"),
            (WalkMode::Exact, "texel walk"),
            (WalkMode::Pyramid, "texel walk + pyramid (default)"),
        ];
        let visits = modes.map(|(mode, _)| {
            rays.iter()
                .map(|r| imp.walk_mode(r, f32::INFINITY, mode).1.texel_visits as f64)
                .sum::<f64>()
                / rays.len().max(1) as f64
        });
        let (t_linear, t_default) = time_pair_median(
            min,
            || walk_all(&imp, &rays, WalkMode::Linear),
            || walk_all(&imp, &rays, WalkMode::Pyramid),
        );
        let (t_exact, t_default_2) = time_pair_median(
            min,
            || walk_all(&imp, &rays, WalkMode::Exact),
            || walk_all(&imp, &rays, WalkMode::Pyramid),
        );
        let (t_walk, t_bvh) =
            time_pair_median(min, || query_all(&imp, &rays), || query_all(&exact, &rays));
        let ns = |t| per_ray(t, &rays);
        for (k, (_, label)) in modes.iter().enumerate() {
            let versus = match k {
                0 => Some((
                    ns(t_linear) / ns(t_default),
                    "× the default walk (timed alternately)".to_string(),
                )),
                1 => Some((
                    ns(t_exact) / ns(t_default_2),
                    "× the default walk (timed alternately)".to_string(),
                )),
                _ => Some((
                    ns(t_walk) / ns(t_bvh),
                    format!("× the BVH's {:.0} ns a ray (timed alternately)", ns(t_bvh)),
                )),
            };
            let t = [t_linear, t_exact, t_walk][k];
            out.push(Figure {
                name: format!("SPOC walk {side}², {label}: time per ray"),
                value: ns(t),
                unit: "ns",
                versus,
            });
            out.push(Figure {
                name: format!("SPOC walk {side}², {label}: texel visits per ray"),
                value: visits[k],
                unit: "texels",
                versus: None,
            });
        }
        let lengths: Vec<f64> = rays
            .iter()
            .map(|r| imp.walk(r, f32::INFINITY).1.projection_length as f64)
            .collect();
        out.push(Figure {
            name: format!("SPOC walk {side}²: ray image path, max / mean"),
            value: lengths.iter().copied().fold(0.0, f64::max),
            unit: "px",
            versus: Some((
                lengths.iter().sum::<f64>() / lengths.len().max(1) as f64,
                "px mean".into(),
            )),
        });
        if side == GOAL_SIDE {
            at_goal = Some(imp);
        }
    }
    let Some(imp) = at_goal else {
        return Ok(out);
    };
    // Scene size: the same surface in 16 times the triangles, through the same camera.
    let big = setup.target.subdivided().subdivided();
    {
        let big_imp = build(imp.camera().clone(), &big, 0, &albedo_of(&big))?;
        big_imp.prepare_walks();
        let big_exact = Bvh::build(vec![std::sync::Arc::new(big.clone())])?;
        let (t_big, t_small) = time_pair_median(
            min,
            || query_all(&big_imp, &rays),
            || query_all(&imp, &rays),
        );
        let (t_big_bvh, t_small_bvh) = time_pair_median(
            min,
            || query_all(&big_exact, &rays),
            || query_all(&exact, &rays),
        );
        out.push(Figure {
            name: format!(
                "SPOC walk {GOAL_SIDE}², default, of the bunny subdivided twice ({} triangles)",
                big.triangle_count()
            ),
            value: per_ray(t_big, &rays),
            unit: "ns",
            versus: Some((
                t_big.as_secs_f64() / t_small.as_secs_f64(),
                "× the walk of the bunny (timed alternately; goal ≤ 1.10)".into(),
            )),
        });
        out.push(Figure {
            name: "  its BVH on the same rays".into(),
            value: per_ray(t_big_bvh, &rays),
            unit: "ns",
            versus: Some((
                t_big_bvh.as_secs_f64() / t_small_bvh.as_secs_f64(),
                "× the bunny's BVH (timed alternately)".into(),
            )),
        });
    }
    // Depth layers: the automatic count against one, on the same rays.
    let mut layered = imp.clone();
    {
        layered.peel(&setup.target, 0, &color, Layers::Auto)?;
        layered.prepare_walks();
        let (t_layered, t_one) = time_pair_median(
            min,
            || query_all(&layered, &rays),
            || query_all(&imp, &rays),
        );
        out.push(Figure {
            name: format!(
                "SPOC walk {GOAL_SIDE}², default, {} depth layers (auto)",
                layered.layer_count()
            ),
            value: per_ray(t_layered, &rays),
            unit: "ns",
            versus: Some((
                t_layered.as_secs_f64() / t_one.as_secs_f64(),
                "× one layer (timed alternately)".into(),
            )),
        });
    }
    Ok(out)
}
