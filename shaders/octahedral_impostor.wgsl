// Octahedral impostor, as trompe bakes it (`trompe impostor bake MESH --octahedral N`):
// a camera-facing card whose fragments blend the three atlas frames around the view direction,
// each lookup parallax-corrected with the frame's depth, and write the depth of the surface they
// found. The CPU reference is src/octahedral/render.rs; the layout is src/octahedral/mapping.rs
// (docs/conventions.md §8). The constants below are checked against the Rust code by the tests.
//
// Bindings: the atlas's three maps as the bake writes them (NAME.png as an sRGB texture,
// NAME-normal.exr and NAME-depth.exr as float textures), a linear sampler, and two uniforms.

const PARALLAX_STEPS: u32 = 4u;
const COVERAGE_SPHERE: u32 = 0u;
const COVERAGE_HEMISPHERE: u32 = 1u;

struct Camera {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    _pad: f32,
};

struct Impostor {
    // World position of the bounding sphere's centre, and its radius (the object's own space
    // placed by the engine without rotation or scale).
    centre: vec3<f32>,
    radius: f32,
    // Frames a side, texels a frame side, COVERAGE_*.
    frames: u32,
    frame_size: u32,
    coverage: u32,
    // 0 for orthographic frames; else pinhole frames, the eye this many radii from the centre
    // (the sidecar's `projection`).
    distance: f32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> impostor: Impostor;
@group(0) @binding(2) var atlas_color: texture_2d<f32>;
@group(0) @binding(3) var atlas_normal: texture_2d<f32>;
@group(0) @binding(4) var atlas_depth: texture_2d<f32>;
@group(0) @binding(5) var atlas_sampler: sampler;

fn sign_nonzero(v: f32) -> f32 {
    return select(-1.0, 1.0, v >= 0.0);
}

// The unit square point of unit direction d (mapping.rs `encode`).
fn oct_encode(dir: vec3<f32>, coverage: u32) -> vec2<f32> {
    var d = dir;
    if (coverage == COVERAGE_HEMISPHERE) {
        d.y = max(d.y, 0.0);
    }
    d = d / max(abs(d.x) + abs(d.y) + abs(d.z), 1e-30);
    var p: vec2<f32>;
    if (coverage == COVERAGE_SPHERE) {
        if (d.y >= 0.0) {
            p = vec2<f32>(d.x, d.z);
        } else {
            p = vec2<f32>((1.0 - abs(d.z)) * sign_nonzero(d.x), (1.0 - abs(d.x)) * sign_nonzero(d.z));
        }
    } else {
        p = vec2<f32>(d.x + d.z, d.z - d.x);
    }
    return clamp(p * 0.5 + vec2<f32>(0.5), vec2<f32>(0.0), vec2<f32>(1.0));
}

// The unit direction of unit square point uv (mapping.rs `decode`).
fn oct_decode(uv: vec2<f32>, coverage: u32) -> vec3<f32> {
    let p = uv * 2.0 - vec2<f32>(1.0);
    var d: vec3<f32>;
    if (coverage == COVERAGE_SPHERE) {
        let y = 1.0 - abs(p.x) - abs(p.y);
        if (y >= 0.0) {
            d = vec3<f32>(p.x, y, p.y);
        } else {
            d = vec3<f32>((1.0 - abs(p.y)) * sign_nonzero(p.x), y, (1.0 - abs(p.x)) * sign_nonzero(p.y));
        }
    } else {
        let x = (p.x - p.y) * 0.5;
        let z = (p.x + p.y) * 0.5;
        d = vec3<f32>(x, 1.0 - abs(x) - abs(z), z);
    }
    return normalize(d);
}

// The view direction of frame (i, j) (mapping.rs `Grid::direction`).
fn frame_direction(frame: vec2<u32>) -> vec3<f32> {
    let s = f32(impostor.frames - 1u);
    return oct_decode(vec2<f32>(frame) / s, impostor.coverage);
}

// A frame's image axes: right, up (mapping.rs `frame_basis`).
fn frame_right(d: vec3<f32>) -> vec3<f32> {
    var reference = vec3<f32>(0.0, 1.0, 0.0);
    if (abs(d.y) > 0.999) {
        reference = vec3<f32>(0.0, 0.0, -sign(d.y));
    }
    return normalize(cross(reference, d));
}

struct Frames {
    cells: array<vec2<u32>, 3>,
    weights: vec3<f32>,
};

// The three frames around view direction v and their weights (mapping.rs `frames_around`).
fn frames_around(v: vec3<f32>) -> Frames {
    let s = f32(impostor.frames - 1u);
    let p = oct_encode(v, impostor.coverage) * s;
    let cell = max(min(floor(p), vec2<f32>(s - 1.0)), vec2<f32>(0.0));
    let f = p - cell;
    let c = vec2<u32>(cell);
    var out: Frames;
    if (f.x + f.y <= 1.0) {
        out.cells = array<vec2<u32>, 3>(c, c + vec2<u32>(1u, 0u), c + vec2<u32>(0u, 1u));
        out.weights = vec3<f32>(1.0 - f.x - f.y, f.x, f.y);
    } else {
        out.cells = array<vec2<u32>, 3>(c + vec2<u32>(1u, 1u), c + vec2<u32>(0u, 1u), c + vec2<u32>(1u, 0u));
        out.weights = vec3<f32>(f.x + f.y - 1.0, 1.0 - f.x, 1.0 - f.y);
    }
    return out;
}

// Atlas coordinates of frame texel coordinates t (texel centres at +0.5), clamped to the frame.
fn atlas_uv(frame: vec2<u32>, t: vec2<f32>) -> vec2<f32> {
    let fs = f32(impostor.frame_size);
    let side = fs * f32(impostor.frames);
    let inside = clamp(t, vec2<f32>(0.5), vec2<f32>(fs - 0.5));
    return (vec2<f32>(frame) * fs + inside) / side;
}

// Frame texel coordinates of world point p in the frame looking along -d (mapping.rs
// `frame_basis`; render.rs `frame_texel`): orthographic, or through the frame's pinhole.
fn frame_texel(p: vec3<f32>, d: vec3<f32>, right: vec3<f32>, up: vec3<f32>) -> vec2<f32> {
    let r = impostor.radius;
    let fs = f32(impostor.frame_size);
    var q = p - impostor.centre;
    var scale = r;
    if (impostor.distance > 0.0) {
        q = p - (impostor.centre + d * (r * impostor.distance));
        let z = max(-dot(q, d), 1e-12 * r);
        scale = z / sqrt(max(impostor.distance * impostor.distance - 1.0, 1e-12));
    }
    return vec2<f32>((dot(q, right) / scale + 1.0) * 0.5 * fs, (1.0 - dot(q, up) / scale) * 0.5 * fs);
}

struct Lookup {
    color: vec4<f32>,
    normal: vec3<f32>,
    position: vec3<f32>,
};

// Frame `frame` along the ray o + t·dir, parallax-corrected (render.rs `lookup`).
fn lookup(frame: vec2<u32>, o: vec3<f32>, dir: vec3<f32>) -> Lookup {
    let d = frame_direction(frame);
    let right = frame_right(d);
    let up = cross(d, right);
    let r = impostor.radius;
    let facing = min(dot(dir, d), -1e-6);
    var offset = 0.0;
    var p = o + dir * (dot(impostor.centre + d * offset - o, d) / facing);
    var t = frame_texel(p, d, right, up);
    for (var k = 0u; k < PARALLAX_STEPS; k = k + 1u) {
        let depth = textureSampleLevel(atlas_depth, atlas_sampler, atlas_uv(frame, t), 0.0).r;
        offset = r - 2.0 * r * depth;
        p = o + dir * (dot(impostor.centre + d * offset - o, d) / facing);
        t = frame_texel(p, d, right, up);
    }
    var out: Lookup;
    out.color = textureSampleLevel(atlas_color, atlas_sampler, atlas_uv(frame, t), 0.0);
    out.normal = textureSampleLevel(atlas_normal, atlas_sampler, atlas_uv(frame, t), 0.0).xyz;
    out.position = p;
    return out;
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

// A camera-facing card of the bounding sphere's diameter; `corner` in [-1, 1]².
@vertex
fn vs_main(@location(0) corner: vec2<f32>) -> VertexOut {
    let to_eye = normalize(camera.eye - impostor.centre);
    let right = frame_right(to_eye);
    let up = cross(to_eye, right);
    // The card stands in front of the sphere so no surface point is clipped by it.
    let world = impostor.centre + to_eye * impostor.radius
        + (right * corner.x + up * corner.y) * impostor.radius;
    var out: VertexOut;
    out.clip = camera.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let o = camera.eye;
    let dir = normalize(in.world - o);
    let frames = frames_around(normalize(camera.eye - impostor.centre));
    var color = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var alpha = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let w = frames.weights[k];
        if (w <= 0.0) {
            continue;
        }
        let s = lookup(frames.cells[k], o, dir);
        color += s.color.rgb * s.color.a * w;
        normal += s.normal * s.color.a * w;
        position += s.position * s.color.a * w;
        alpha += s.color.a * w;
    }
    if (alpha < 0.5) {
        discard;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(color / alpha, 1.0);
    out.normal = vec4<f32>(normalize(normal), 0.0);
    // Pixel depth offset: the depth of the surface found, not of the card.
    let clip = camera.view_proj * vec4<f32>(position / alpha, 1.0);
    out.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    return out;
}
