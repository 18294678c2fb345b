//! The library's tests that need a system package: the octahedral shader run on a Vulkan device
//! (Mesa's lavapipe runs it on the CPU) and Krita opening the layers (under Xvfb). A package
//! that is missing makes its tests *ignored* — counted in the summary, the reason printed above
//! it — or failed where `TROMPE_REQUIRE_SYSTEM` is set, as `.ci/run` sets it.

#[path = "../integration/common/mod.rs"]
mod common;
mod krita;
mod shader;

use common::needs;
use libtest_mimic::{Arguments, Failed, Trial};

/// A test function as a trial: a panic fails it.
fn trial(name: &str, test: fn()) -> Trial {
    Trial::test(name, move || -> Result<(), Failed> {
        test();
        Ok(())
    })
}

fn main() {
    let args = Arguments::from_args();
    let vulkan = shader::vulkan_adapter();
    if let Some(name) = &vulkan {
        println!("the shader runs on {name}");
    }
    const VULKAN: &str = "a Vulkan device (Mesa's lavapipe, package mesa-vulkan-drivers)";
    const KRITA: &str = "krita or xvfb-run (packages krita, xvfb)";
    let trials = vec![
        trial(
            "shader::the_shader_parses_and_validates",
            shader::the_shader_parses_and_validates,
        ),
        trial(
            "shader::the_shader_constants_are_the_rust_codes",
            shader::the_shader_constants_are_the_rust_codes,
        ),
        needs(
            trial(
                "shader::the_shaders_frame_texels_are_the_cpu_references_for_both_projections",
                shader::the_shaders_frame_texels_are_the_cpu_references_for_both_projections,
            ),
            vulkan.is_some(),
            VULKAN,
        ),
        needs(
            trial(
                "shader::the_shaders_frame_selection_is_the_cpu_references_on_ten_thousand_directions",
                shader::the_shaders_frame_selection_is_the_cpu_references_on_ten_thousand_directions,
            ),
            vulkan.is_some(),
            VULKAN,
        ),
        needs(
            trial(
                "krita::krita_opens_the_layers_as_written_and_what_it_saves_renders_the_same",
                krita::krita_opens_the_layers_as_written_and_what_it_saves_renders_the_same,
            ),
            krita::installed(),
            KRITA,
        ),
    ];
    libtest_mimic::run(&args, trials).exit();
}
