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

pub fn the_shader_parses_and_validates() {
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
    assert_eq!(entries, ["vs_main", "fs_main", "fs_depth"]);
}

pub fn the_shader_constants_are_the_rust_codes() {
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
    assert!(
        src.contains(&format!(
            "const ALPHA_TEST: f32 = {:?};",
            trompe::octahedral::scene::ALPHA_TEST
        )),
        "ALPHA_TEST"
    );
    assert!(
        src.contains(&format!(
            "const DEPTH_AGREEMENT: f32 = {:?};",
            trompe::octahedral::render::DEPTH_AGREEMENT
        )),
        "DEPTH_AGREEMENT"
    );
}

/// A compute entry over the shader's own `frames_around`: each direction in, its three frames
/// and weights out (nine floats).
const PICK: &str = r#"
@compute @workgroup_size(64)
fn run(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= arrayLength(&inputs)) {
        return;
    }
    let f = frames_around(inputs[k].xyz);
    for (var m = 0u; m < 3u; m = m + 1u) {
        outputs[k * 9u + 2u * m] = f32(f.cells[m].x);
        outputs[k * 9u + 2u * m + 1u] = f32(f.cells[m].y);
        outputs[k * 9u + 6u + m] = f.weights[m];
    }
}
"#;

/// Three frames and their weights, as the shader picks them.
type Picked = [((u32, u32), f32); 3];

/// The shader with `entry` (a compute entry point named `run`, reading `inputs` and writing
/// `outputs`) appended, run on a Vulkan device over `input` (four floats an item), with the
/// `Impostor` uniform `uniform`; `per_item` floats out an item. `None` when no Vulkan device
/// is found.
fn run_on_device(entry: &str, uniform: &[u8], input: &[f32], per_item: usize) -> Option<Vec<f32>> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).ok()?;
    eprintln!("running the shader on {}", adapter.get_info().name);
    let (device, queue) =
        pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default())).unwrap();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("octahedral_impostor.wgsl + a compute entry"),
        source: wgpu::ShaderSource::Wgsl((source() + IO + entry).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("run"),
        compilation_options: Default::default(),
        cache: None,
    });
    let buffer = |size: usize, usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: size as u64,
            usage,
            mapped_at_creation: false,
        })
    };
    use wgpu::BufferUsages as U;
    let impostor = buffer(uniform.len(), U::UNIFORM | U::COPY_DST);
    queue.write_buffer(&impostor, 0, uniform);
    let items = input.len() / 4;
    let inputs = buffer(input.len() * 4, U::STORAGE | U::COPY_DST);
    queue.write_buffer(&inputs, 0, &bytes(input));
    let out_size = items * per_item * 4;
    let out = buffer(out_size, U::STORAGE | U::COPY_SRC);
    let read = buffer(out_size, U::MAP_READ | U::COPY_DST);
    let entries =
        [(1, &impostor), (6, &inputs), (7, &out)].map(|(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((items as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, out_size as u64);
    queue.submit([encoder.finish()]);
    read.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let view = read.get_mapped_range(..).unwrap();
    Some(
        view.chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect(),
    )
}

/// The bindings a compute entry reads and writes, beside the shader's own.
const IO: &str = r#"
@group(0) @binding(6) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> outputs: array<f32>;
"#;

fn bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The `Impostor` uniform: centre, radius, frames, frame size, coverage, pinhole distance, and
/// no cross-fade (start and end 0, two floats of padding).
fn uniform(
    centre: [f32; 3],
    radius: f32,
    (frames, frame_size, coverage): (u32, u32, u32),
    distance: f32,
) -> Vec<u8> {
    let mut u = bytes(&[centre[0], centre[1], centre[2], radius]);
    for v in [frames, frame_size, coverage] {
        u.extend(v.to_le_bytes());
    }
    u.extend(distance.to_le_bytes());
    u.extend(bytes(&[0.0; 4]));
    u
}

/// The shader's `frames_around` run on a Vulkan device for `directions`, with `frames` a side
/// and coverage code `coverage`: per direction, the three frames and their weights.
fn shader_frames_around(
    directions: &[[f32; 3]],
    frames: u32,
    coverage: u32,
) -> Option<Vec<Picked>> {
    let input: Vec<f32> = directions
        .iter()
        .flat_map(|d| [d[0], d[1], d[2], 0.0])
        .collect();
    let u = uniform([0.0; 3], 1.0, (frames, 128, coverage), 0.0);
    let floats = run_on_device(PICK, &u, &input, 9)?;
    Some(
        floats
            .chunks_exact(9)
            .map(|p| std::array::from_fn(|m| ((p[2 * m] as u32, p[2 * m + 1] as u32), p[6 + m])))
            .collect(),
    )
}

/// The name of the Vulkan adapter the shader runs on, if there is one.
pub fn vulkan_adapter() -> Option<String> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).ok()?;
    Some(adapter.get_info().name)
}

/// A compute entry over the shader's `frame_texel`: each input `(x, y, z, frame)` (frame as
/// `i + j·n`) to its texel coordinates in that frame.
const TEXEL: &str = r#"
@compute @workgroup_size(64)
fn run(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= arrayLength(&inputs)) {
        return;
    }
    let f = u32(inputs[k].w);
    let frame = vec2<u32>(f % impostor.frames, f / impostor.frames);
    let d = frame_direction(frame);
    let right = frame_right(d);
    let up = cross(d, right);
    let t = frame_texel(inputs[k].xyz, impostor.centre, d, right, up);
    outputs[k * 2u] = t.x;
    outputs[k * 2u + 1u] = t.y;
}
"#;

pub fn the_shaders_frame_texels_are_the_cpu_references_for_both_projections() {
    use glam::DVec3;
    use trompe::octahedral::render::frame_texel;
    use trompe::octahedral::{BakeSettings, Coverage, FrameProjection, Grid};
    let (centre, radius) = ([0.3f32, -0.2, 0.5], 1.5f32);
    let mut seed = 5u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let n = 12;
    // Points inside the bounding sphere, each with a frame.
    let items: Vec<([f32; 3], u32)> = (0..10_000)
        .map(|_| {
            let p = DVec3::new(next(), next(), next()) * 2.0 - DVec3::ONE;
            let p = glam::Vec3::from(centre) + (p * 0.57 * f64::from(radius)).as_vec3();
            (p.to_array(), (next() * f64::from(n * n)) as u32 % (n * n))
        })
        .collect();
    let input: Vec<f32> = items
        .iter()
        .flat_map(|(p, f)| [p[0], p[1], p[2], *f as f32])
        .collect();
    for (projection, distance) in [
        (FrameProjection::Orthographic, 0.0),
        (FrameProjection::Pinhole { distance: 3.0 }, 3.0),
    ] {
        let settings = BakeSettings {
            grid: Grid {
                n,
                coverage: Coverage::Sphere,
            },
            frame_size: 96,
            dilation: 0,
            projection,
        };
        let u = uniform(centre, radius, (n, 96, 0), distance);
        let shader = run_on_device(TEXEL, &u, &input, 2).expect("the Vulkan device found before");
        let sphere = (glam::Vec3::from(centre).as_dvec3(), f64::from(radius));
        let mut worst = 0.0f64;
        for (k, (p, f)) in items.iter().enumerate() {
            let p = glam::Vec3::from(*p).as_dvec3();
            let cpu = frame_texel(&settings, sphere, (f % n, f / n), p);
            let gpu = glam::DVec2::new(shader[2 * k].into(), shader[2 * k + 1].into());
            worst = worst.max((cpu - gpu).length());
        }
        eprintln!("{projection:?}: largest texel difference {worst:.2e}");
        // f32 against f64, over a 96-texel frame.
        assert!(worst < 1e-3, "{projection:?}: {worst} texels apart");
    }
}

pub fn the_shaders_frame_selection_is_the_cpu_references_on_ten_thousand_directions() {
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
            let shader =
                shader_frames_around(&single, n, code).expect("the Vulkan device found before");
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
