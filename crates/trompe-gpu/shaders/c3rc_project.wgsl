// Every projection of one point through one camera a pair: the C3RC projection alone
// (c3rc.wgsl, compiled before this file), for checking it against the CPU's roots.

struct Pair {
    camera: C3rc,
    // xyz: the point; w: the largest sweep parameter.
    point: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> pairs: array<Pair>;
// Per pair: the projections' count, then three (λ, b₀, b₁, b₂).
@group(0) @binding(1) var<storage, read_write> projections: array<vec4<f32>>;

@compute @workgroup_size(64)
fn project_pairs(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * 65535u * 64u;
    if (i >= arrayLength(&pairs)) {
        return;
    }
    let pair = pairs[i];
    let found = c3rc_project(pair.camera, pair.point.xyz, 0.0, pair.point.w);
    projections[4u * i] = vec4<f32>(f32(found.len), 0.0, 0.0, 0.0);
    for (var k = 0u; k < 3u; k = k + 1u) {
        let p = found.p[k];
        projections[4u * i + 1u + k] = vec4<f32>(p.lambda, p.bary);
    }
}
