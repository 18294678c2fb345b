//! The GPU crate's tests: each runs the GPU path on a real adapter (Mesa's lavapipe runs the same
//! shaders on the CPU) and checks it against the library's CPU answer. Without any adapter a
//! test is *ignored* — counted in the summary, the reason printed above it — or failed where
//! `TROMPE_REQUIRE_SYSTEM` is set, as `.ci/run` sets it.

mod build;
mod bvh;
mod hybrid;
mod layers;
mod master;
mod octahedral;
mod relief;
mod trace;
mod views;
mod walk;

use libtest_mimic::{Arguments, Failed, Trial};
use trompe_gpu::{Gpu, GpuRequest};

/// A test function over an open device as a trial: a panic fails it.
fn on_gpu(name: &str, test: fn(&Gpu)) -> Trial {
    Trial::test(name, move || -> Result<(), Failed> {
        let gpu = GpuRequest::new().open().map_err(|e| e.to_string())?;
        test(&gpu);
        Ok(())
    })
}

/// Every weighting the GPU blends, and the per-point ones again prefiltered to the pixel, with
/// holes filled magenta (so a hole is a pixel to compare on both devices): the settings and their
/// name.
pub fn every_blend() -> Vec<(trompe::texturing::BlendSettings, String)> {
    use trompe::texturing::{BlendSettings, Holes, Weighting};
    let ulr = Weighting::Ulr { beta: 0.1 };
    [
        (ulr, false),
        (Weighting::Vdtm, false),
        (Weighting::ViewMap, false),
        (Weighting::BestFace, false),
        (ulr, true),
        (Weighting::ViewMap, true),
    ]
    .into_iter()
    .map(|(weighting, prefilter)| {
        let settings = BlendSettings {
            weighting,
            prefilter,
            holes: Holes::Fill(glam::Vec4::new(1.0, 0.0, 1.0, 1.0)),
            ..BlendSettings::default()
        };
        let filtered = if prefilter { ", prefiltered" } else { "" };
        (settings, format!("{}{filtered}", weighting.name()))
    })
    .collect()
}

/// The GPU's projective-texturing frame against the CPU's, printed as `what`: mean FLIP ≤ 0.01
/// (the goal), and the pixels covered and the holes each within 0.5 % of the covered pixels
/// (two rasterizers' coverage may differ on a few silhouette pixels).
pub fn blends_agree(what: &str, cpu: &trompe::texturing::Blend, on_gpu: &trompe::texturing::Blend) {
    let f = trompe::frame::metrics::flip(&cpu.image, &on_gpu.image, None).unwrap();
    let worst = (cpu.image.pixels().iter().zip(on_gpu.image.pixels()))
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    println!(
        "{what}: mean FLIP {f:.5}, largest channel difference {worst:.5}; covered {} / {}, \
         holes {} / {}",
        on_gpu.covered, cpu.covered, on_gpu.holes, cpu.holes
    );
    assert!(f <= 0.01, "{what}: FLIP {f}");
    let (covered, holes) = (
        on_gpu.covered.abs_diff(cpu.covered),
        on_gpu.holes.abs_diff(cpu.holes),
    );
    assert!(
        covered * 200 <= cpu.covered,
        "{what}: covered {covered} apart"
    );
    assert!(
        holes * 200 <= cpu.covered.max(1),
        "{what}: holes {holes} apart"
    );
}

/// How closely two frames of one view agree: the share of pixels with the same object id, and
/// the mean FLIP of their colours.
pub fn agreement(cpu: &trompe::frame::Frame, on_gpu: &trompe::frame::Frame) -> (f64, f64) {
    let ids = (cpu.object_id.pixels().iter())
        .zip(on_gpu.object_id.pixels())
        .filter(|(a, b)| a == b)
        .count() as f64
        / cpu.object_id.pixels().len().max(1) as f64;
    let flip = trompe::frame::metrics::compare(&cpu.color, &on_gpu.color, None)
        .unwrap()
        .flip;
    (ids, flip)
}

/// A test that needs no device.
fn plain(name: &str, test: fn()) -> Trial {
    Trial::test(name, move || -> Result<(), Failed> {
        test();
        Ok(())
    })
}

fn main() {
    let args = Arguments::from_args();
    let adapters = trompe_gpu::adapters(trompe_gpu::Backends::All);
    match adapters.first() {
        Some(a) => println!("the GPU tests run on {} ({})", a.name, a.backend),
        None => println!("no GPU adapter found"),
    }
    let device_trials = [
        on_gpu(
            "bvh::the_gpu_walk_hits_the_cpu_bvhs_triangles_on_ten_thousand_incoherent_rays",
            bvh::the_gpu_walk_hits_the_cpu_bvhs_triangles_on_ten_thousand_incoherent_rays,
        ),
        on_gpu(
            "bvh::shadow_rays_agree_with_the_cpu_any_hit",
            bvh::shadow_rays_agree_with_the_cpu_any_hit,
        ),
        on_gpu(
            "bvh::the_same_rays_give_the_same_bits_on_repeated_runs",
            bvh::the_same_rays_give_the_same_bits_on_repeated_runs,
        ),
        on_gpu(
            "bvh::an_empty_scene_misses_and_no_rays_is_no_work",
            bvh::an_empty_scene_misses_and_no_rays_is_no_work,
        ),
        on_gpu(
            "hybrid::the_gpu_projects_points_through_c3rcs_as_the_cpu",
            hybrid::the_gpu_projects_points_through_c3rcs_as_the_cpu,
        ),
        on_gpu(
            "hybrid::c3rc_frames_on_the_gpu_are_the_cpus",
            hybrid::c3rc_frames_on_the_gpu_are_the_cpus,
        ),
        on_gpu(
            "hybrid::a_c3rc_frame_on_the_gpu_is_the_same_twice",
            hybrid::a_c3rc_frame_on_the_gpu_is_the_same_twice,
        ),
        on_gpu(
            "relief::relief_frames_on_the_gpu_are_the_cpus",
            relief::relief_frames_on_the_gpu_are_the_cpus,
        ),
        on_gpu(
            "relief::a_relief_frame_where_no_impostor_changes_draws_identically_twice",
            relief::a_relief_frame_where_no_impostor_changes_draws_identically_twice,
        ),
        on_gpu(
            "relief::the_relief_method_on_the_gpu_is_the_cpus",
            relief::the_relief_method_on_the_gpu_is_the_cpus,
        ),
        on_gpu(
            "relief::a_new_pre_warp_is_never_drawn_half_written",
            relief::a_new_pre_warp_is_never_drawn_half_written,
        ),
        on_gpu(
            "build::gpu_built_impostors_match_the_cpu_built_texel_for_texel",
            build::gpu_built_impostors_match_the_cpu_built_texel_for_texel,
        ),
        on_gpu(
            "build::gpu_built_graph_impostors_match_the_cpu_built",
            build::gpu_built_graph_impostors_match_the_cpu_built,
        ),
        on_gpu(
            "trace::wymans_refraction_runs_on_the_gpu_as_on_the_cpu",
            trace::wymans_refraction_runs_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "trace::mirrors_seen_as_impostors_run_on_the_gpu_as_on_the_cpu",
            trace::mirrors_seen_as_impostors_run_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "build::gpu_peeled_layers_match_the_cpu_peeled",
            build::gpu_peeled_layers_match_the_cpu_peeled,
        ),
        on_gpu(
            "walk::the_gpu_walk_answers_as_the_cpu_walk_on_reflected_rays",
            walk::the_gpu_walk_answers_as_the_cpu_walk_on_reflected_rays,
        ),
        on_gpu(
            "walk::a_moved_impostor_is_walked_where_it_was_built",
            walk::a_moved_impostor_is_walked_where_it_was_built,
        ),
        on_gpu(
            "walk::the_same_walks_give_the_same_bits_on_repeated_runs",
            walk::the_same_walks_give_the_same_bits_on_repeated_runs,
        ),
        on_gpu(
            "octahedral::every_shipped_scene_draws_octahedral_impostors_on_the_gpu_as_on_the_cpu",
            octahedral::every_shipped_scene_draws_octahedral_impostors_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "octahedral::a_field_of_instances_is_one_atlas_drawn_once_a_copy_on_the_gpu",
            octahedral::a_field_of_instances_is_one_atlas_drawn_once_a_copy_on_the_gpu,
        ),
        on_gpu(
            "octahedral::instances_moved_turned_and_scaled_and_the_depth_only_entry_draw_what_the_scene_draws",
            octahedral::instances_moved_turned_and_scaled_and_the_depth_only_entry_draw_what_the_scene_draws,
        ),
        on_gpu(
            "octahedral::the_cross_fade_draws_each_copys_share_of_the_bayer_pattern",
            octahedral::the_cross_fade_draws_each_copys_share_of_the_bayer_pattern,
        ),
        on_gpu(
            "trace::every_shipped_scene_traces_on_the_gpu_as_on_the_cpu",
            trace::every_shipped_scene_traces_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "trace::every_shipped_scene_renders_through_impostors_on_the_gpu_as_on_the_cpu",
            trace::every_shipped_scene_renders_through_impostors_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "trace::every_shipped_scene_renders_through_pinhole_impostors_on_the_gpu_as_on_the_cpu",
            trace::every_shipped_scene_renders_through_pinhole_impostors_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "trace::impostors_are_kept_across_frames_on_the_gpu_as_on_the_cpu",
            trace::impostors_are_kept_across_frames_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "trace::what_the_gpu_does_not_run_is_refused_before_any_work",
            trace::what_the_gpu_does_not_run_is_refused_before_any_work,
        ),
        on_gpu(
            "trace::every_shipped_scene_rasterizes_on_the_gpu_as_on_the_cpu",
            trace::every_shipped_scene_rasterizes_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "master::master_textures_render_on_the_gpu_as_on_the_cpu",
            master::master_textures_render_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "master::the_same_masters_render_the_same_bits_on_repeated_runs",
            master::the_same_masters_render_the_same_bits_on_repeated_runs,
        ),
        on_gpu(
            "master::what_the_gpu_does_not_blend_is_refused_before_any_work",
            master::what_the_gpu_does_not_blend_is_refused_before_any_work,
        ),
        on_gpu(
            "views::calibrated_views_render_on_the_gpu_as_on_the_cpu",
            views::calibrated_views_render_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "views::the_gpu_prefilters_as_the_cpu_where_a_pixel_spans_texels",
            views::the_gpu_prefilters_as_the_cpu_where_a_pixel_spans_texels,
        ),
        on_gpu(
            "views::the_same_views_render_the_same_bits_on_repeated_runs",
            views::the_same_views_render_the_same_bits_on_repeated_runs,
        ),
        on_gpu(
            "layers::the_layered_method_runs_on_the_gpu_as_on_the_cpu",
            layers::the_layered_method_runs_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "layers::the_projective_method_runs_on_the_gpu_as_on_the_cpu",
            layers::the_projective_method_runs_on_the_gpu_as_on_the_cpu,
        ),
        on_gpu(
            "layers::image_layers_render_on_the_gpu_as_on_the_cpu",
            layers::image_layers_render_on_the_gpu_as_on_the_cpu,
        ),
    ];
    let mut trials = vec![
        plain(
            "bvh::the_shaders_parse_and_validate",
            bvh::the_shaders_parse_and_validate,
        ),
        plain(
            "device::an_adapter_that_cannot_be_had_is_an_error_naming_what_was_looked_for",
            an_adapter_that_cannot_be_had_is_an_error_naming_what_was_looked_for,
        ),
    ];
    trials.extend(
        device_trials
            .into_iter()
            .map(|t| needs_adapter(t, !adapters.is_empty())),
    );
    libtest_mimic::run(&args, trials).exit();
}

/// `trial` as it is where an adapter is present; otherwise ignored (counted), or failed under
/// `TROMPE_REQUIRE_SYSTEM`.
fn needs_adapter(trial: Trial, present: bool) -> Trial {
    const WHAT: &str =
        "a GPU adapter (without a GPU: Mesa's lavapipe, package mesa-vulkan-drivers)";
    if present {
        return trial;
    }
    let name = trial.name().to_string();
    // `.ci/run` sets TROMPE_REQUIRE_SYSTEM; TROMPE_REQUIRE_VULKAN asks the same of the GPU
    // tests alone.
    let required = ["TROMPE_REQUIRE_SYSTEM", "TROMPE_REQUIRE_VULKAN"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    if required {
        return Trial::test(name, move || {
            Err(format!(
                "{WHAT} is missing, and TROMPE_REQUIRE_SYSTEM or TROMPE_REQUIRE_VULKAN is set (.ci/run installs it)"
            )
            .into())
        });
    }
    println!("ignored {name}: {WHAT} is missing (.ci/run installs it)");
    trial.with_ignored_flag(true)
}

/// Asking for an adapter nobody has is an error (not a panic) that says what was looked for
/// and what was found.
fn an_adapter_that_cannot_be_had_is_an_error_naming_what_was_looked_for() {
    let error = match GpuRequest::new().named("no such adapter 7f3a").open() {
        Ok(gpu) => panic!("opened {}", gpu.name()),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("no such adapter 7f3a"), "{error}");
    assert!(error.starts_with("no GPU adapter found"), "{error}");
}
