//! The octahedral impostor's WGSL shader (shaders/octahedral_impostor.wgsl): it parses and
//! validates with naga, its constants are the Rust code's, and run on a Vulkan device (Mesa's
//! lavapipe on the CPU) it picks the frames the Rust code picks.

use std::path::Path;

fn source() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/octahedral_impostor.wgsl"),
    )
    .unwrap()
}

#[test]
fn the_shader_parses_and_validates() {
    let module = naga::front::wgsl::parse_str(&source()).unwrap_or_else(|e| {
        panic!("{}", e.emit_to_string(&source()));
    });
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap();
    let entries: Vec<&str> = module
        .entry_points
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(entries, ["vs_main", "fs_main"]);
}

#[test]
fn the_shader_constants_are_the_rust_codes() {
    let src = source();
    assert!(
        src.contains(&format!(
            "const PARALLAX_STEPS: u32 = {}u;",
            trompe::octahedral::render::PARALLAX_STEPS
        )),
        "PARALLAX_STEPS"
    );
    // The coverage codes name the sidecar's values in order.
    let names = [
        trompe::octahedral::Coverage::Sphere,
        trompe::octahedral::Coverage::Hemisphere,
    ]
    .map(|c| serde_json::to_string(&c).unwrap());
    assert_eq!(names, ["\"sphere\"", "\"hemisphere\""]);
    assert!(src.contains("const COVERAGE_SPHERE: u32 = 0u;"));
    assert!(src.contains("const COVERAGE_HEMISPHERE: u32 = 1u;"));
}

/// A compute entry over the shader's own `frames_around`, appended to its source: each
/// direction in, its three frames and weights out (nine floats).
const PICK: &str = r#"
@group(0) @binding(6) var<storage, read> directions: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> picked: array<f32>;

@compute @workgroup_size(64)
fn pick(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= arrayLength(&directions)) {
        return;
    }
    let f = frames_around(directions[k].xyz);
    for (var m = 0u; m < 3u; m = m + 1u) {
        picked[k * 9u + 2u * m] = f32(f.cells[m].x);
        picked[k * 9u + 2u * m + 1u] = f32(f.cells[m].y);
        picked[k * 9u + 6u + m] = f.weights[m];
    }
}
"#;

/// Three frames and their weights, as the shader picks them.
type Picked = [((u32, u32), f32); 3];

/// The shader's `frames_around` run on a Vulkan device for `directions`, with `frames` a side
/// and coverage code `coverage`: per direction, the three frames and their weights. `None`
/// when no Vulkan device is found.
fn shader_frames_around(
    directions: &[[f32; 3]],
    frames: u32,
    coverage: u32,
) -> Option<Vec<Picked>> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        force_fallback_adapter: false,
        ..Default::default()
    }))
    .ok()?;
    eprintln!("running the shader on {}", adapter.get_info().name);
    let (device, queue) =
        pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default())).unwrap();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("octahedral_impostor.wgsl + pick"),
        source: wgpu::ShaderSource::Wgsl((source() + PICK).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("pick"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let buffer = |size: usize, usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: size as u64,
            usage,
            mapped_at_creation: false,
        })
    };
    use wgpu::BufferUsages as U;
    // struct Impostor: centre, radius, frames, frame_size, coverage, padding.
    let mut uniform = bytes(&[0.0, 0.0, 0.0, 1.0]);
    for u in [frames, 128, coverage, 0] {
        uniform.extend(u.to_le_bytes());
    }
    let impostor = buffer(uniform.len(), U::UNIFORM | U::COPY_DST);
    queue.write_buffer(&impostor, 0, &uniform);
    let input: Vec<f32> = directions
        .iter()
        .flat_map(|d| [d[0], d[1], d[2], 0.0])
        .collect();
    let dirs = buffer(input.len() * 4, U::STORAGE | U::COPY_DST);
    queue.write_buffer(&dirs, 0, &bytes(&input));
    let out_size = directions.len() * 9 * 4;
    let out = buffer(out_size, U::STORAGE | U::COPY_SRC);
    let read = buffer(out_size, U::MAP_READ | U::COPY_DST);
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 1,
                resource: impostor.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: dirs.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 7,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((directions.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, out_size as u64);
    queue.submit([encoder.finish()]);
    read.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let view = read.get_mapped_range(..).unwrap();
    let floats: Vec<f32> = view
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Some(
        floats
            .chunks_exact(9)
            .map(|p| std::array::from_fn(|m| ((p[2 * m] as u32, p[2 * m + 1] as u32), p[6 + m])))
            .collect(),
    )
}

#[test]
fn the_shaders_frame_selection_is_the_cpu_references_on_ten_thousand_directions() {
    use glam::DVec3;
    use trompe::octahedral::{Coverage, Grid};
    // Uniform directions on the sphere, from a fixed generator.
    let mut seed = 11u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let directions: Vec<DVec3> = (0..10_000)
        .map(|_| {
            let (a, z) = (next() * std::f64::consts::TAU, next() * 2.0 - 1.0);
            let r = (1.0 - z * z).sqrt();
            DVec3::new(r * a.cos(), z, r * a.sin())
        })
        .collect();
    let single: Vec<[f32; 3]> = directions.iter().map(|d| d.as_vec3().to_array()).collect();
    for (coverage, code) in [(Coverage::Sphere, 0), (Coverage::Hemisphere, 1)] {
        for n in [8, 16, 31] {
            let Some(shader) = shader_frames_around(&single, n, code) else {
                if std::env::var_os("TROMPE_REQUIRE_VULKAN").is_some() {
                    panic!("no Vulkan device, and TROMPE_REQUIRE_VULKAN is set (.ci/run sets it)");
                }
                eprintln!("skipped: no Vulkan device (Mesa's lavapipe runs it on the CPU)");
                return;
            };
            let grid = Grid { n, coverage };
            let mut on_an_edge = 0;
            for (k, d) in directions.iter().enumerate() {
                // The reference, in f64, of the direction the shader was given in f32.
                let cpu = grid.frames_around(single[k].map(f64::from).into());
                let gpu = shader[k];
                let same_frames = cpu.iter().zip(&gpu).all(|(c, g)| c.0 == g.0);
                if !same_frames {
                    // Only where the map point lies within f32 rounding of a cell edge or
                    // diagonal may the two pick different (and then equally weighted) frames.
                    let p = trompe::octahedral::mapping::encode(*d, coverage) * f64::from(n - 1);
                    let f = p - p.floor();
                    let edge = [f.x, 1.0 - f.x, f.y, 1.0 - f.y, (f.x + f.y - 1.0).abs()]
                        .into_iter()
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        edge < 1e-4,
                        "{coverage:?} n {n}, direction {d}: CPU {cpu:?}, shader {gpu:?}"
                    );
                    on_an_edge += 1;
                    continue;
                }
                for (c, g) in cpu.iter().zip(&gpu) {
                    assert!(
                        (c.1 - f64::from(g.1)).abs() < 1e-4,
                        "{coverage:?} n {n}, direction {d}: weights CPU {cpu:?}, shader {gpu:?}"
                    );
                }
            }
            eprintln!("{coverage:?} {n}²: {on_an_edge} of 10000 directions on a cell edge");
            assert!(
                on_an_edge <= 10,
                "{on_an_edge} directions pick other frames"
            );
        }
    }
}
