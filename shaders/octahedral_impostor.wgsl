// Octahedral impostor, as trompe bakes it (`trompe impostor bake MESH --octahedral N`):
// a camera-facing card whose fragments blend the three atlas frames around the view direction,
// each lookup parallax-corrected with the frame's depth, keep what has coverage ≥ ½ (the alpha
// test) and write the base colour, normal, object id and depth of the surface they found. The
// CPU reference is src/octahedral/render.rs, and src/octahedral/scene.rs draws a scene by the
// same rules; the layout is src/octahedral/mapping.rs (docs/conventions.md §8). The constants
// below are checked against the Rust code by the tests.
//
// Instanced: each instance is one copy of the baked object, moved by its own translation, with
// its own object id (two per-instance vertex attributes); one copy drawn at the bake's place has
// offset zero.
//
// Bindings: the atlas's three maps as the bake writes them (NAME.png as an sRGB texture,
// NAME-normal.exr and NAME-depth.exr as float textures), a linear sampler, and two uniforms.

const PARALLAX_STEPS: u32 = 4u;
const COVERAGE_SPHERE: u32 = 0u;
const COVERAGE_HEMISPHERE: u32 = 1u;
const ALPHA_TEST: f32 = 0.5;

struct Camera {
    // World to clip space; depth is compared as the pipeline says (trompe's renderer: reversed).
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // The near plane's distance along the view direction.
    near: f32,
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

// Frame texel coordinates of world point p in the frame looking along -d, the sphere centred
// on `centre` (mapping.rs `frame_basis`; render.rs `frame_texel`): orthographic, or through the
// frame's pinhole.
fn frame_texel(p: vec3<f32>, centre: vec3<f32>, d: vec3<f32>, right: vec3<f32>, up: vec3<f32>) -> vec2<f32> {
    let r = impostor.radius;
    let fs = f32(impostor.frame_size);
    var q = p - centre;
    var scale = r;
    if (impostor.distance > 0.0) {
        q = p - (centre + d * (r * impostor.distance));
        let z = max(-dot(q, d), 1e-12 * r);
        scale = z / sqrt(max(impostor.distance * impostor.distance - 1.0, 1e-12));
    }
    return vec2<f32>((dot(q, right) / scale + 1.0) * 0.5 * fs, (1.0 - dot(q, up) / scale) * 0.5 * fs);
}

struct Lookup {
    color: vec4<f32>,
    normal: vec3<f32>,
    position: vec3<f32>,
    // 0 where the point found falls more than a texel outside the frame (render.rs: no sample).
    inside: f32,
};

// Frame `frame` along the ray o + t·dir, parallax-corrected, the sphere centred on `centre`
// (render.rs `lookup`).
fn lookup(frame: vec2<u32>, centre: vec3<f32>, o: vec3<f32>, dir: vec3<f32>) -> Lookup {
    let d = frame_direction(frame);
    let right = frame_right(d);
    let up = cross(d, right);
    let r = impostor.radius;
    let facing = min(dot(dir, d), -1e-6);
    var offset = 0.0;
    var p = o + dir * (dot(centre + d * offset - o, d) / facing);
    var t = frame_texel(p, centre, d, right, up);
    for (var k = 0u; k < PARALLAX_STEPS; k = k + 1u) {
        let depth = textureSampleLevel(atlas_depth, atlas_sampler, atlas_uv(frame, t), 0.0).r;
        offset = r - 2.0 * r * depth;
        p = o + dir * (dot(centre + d * offset - o, d) / facing);
        t = frame_texel(p, centre, d, right, up);
    }
    let fs = f32(impostor.frame_size);
    var out: Lookup;
    out.color = textureSampleLevel(atlas_color, atlas_sampler, atlas_uv(frame, t), 0.0);
    out.normal = textureSampleLevel(atlas_normal, atlas_sampler, atlas_uv(frame, t), 0.0).xyz;
    out.position = p;
    out.inside = select(0.0, 1.0, all(t >= vec2<f32>(-1.0)) && all(t <= vec2<f32>(fs + 1.0)));
    return out;
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    // The instance's bounding sphere centre, and its object id.
    @location(1) @interpolate(flat) centre: vec3<f32>,
    @location(2) @interpolate(flat) object: u32,
};

// A camera-facing card of the bounding sphere's diameter; `corner` in [-1, 1]²; per instance,
// its translation from the bake's place and its object id.
@vertex
fn vs_main(
    @location(0) corner: vec2<f32>,
    @location(1) offset: vec3<f32>,
    @location(2) object: u32,
) -> VertexOut {
    let centre = impostor.centre + offset;
    let r = impostor.radius;
    let to_eye = normalize(camera.eye - centre);
    var world: vec3<f32>;
    if (length(camera.eye - centre) - r > 4.0 * camera.near) {
        // The card stands in front of the sphere so no surface point is clipped by it, and
        // covers its silhouette.
        let right = frame_right(to_eye);
        let up = cross(to_eye, right);
        world = centre + to_eye * r + (right * corner.x + up * corner.y) * r;
    } else {
        // The eye in the sphere or at it: a card across the whole view just past the near
        // plane (the view direction is clip w's row), every pixel's ray through it.
        let m = camera.view_proj;
        let forward = normalize(vec3<f32>(m[0][3], m[1][3], m[2][3]));
        let right = frame_right(-forward);
        let up = cross(-forward, right);
        let d = 4.0 * camera.near;
        world = camera.eye + forward * d + (right * corner.x + up * corner.y) * (100.0 * d);
    }
    var out: VertexOut;
    out.clip = camera.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.centre = centre;
    out.object = object;
    return out;
}

struct FragmentOut {
    // Base colour (alpha 1: the surface is kept whole).
    @location(0) color: vec4<f32>,
    // The blended unit normal (toward the eye where the frames' normals cancel).
    @location(1) normal: vec4<f32>,
    @location(2) object: u32,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let o = camera.eye;
    let dir = normalize(in.world - o);
    let centre = in.centre;
    // Only rays through the bounding sphere meet the object.
    let oc = o - centre;
    let b = dot(oc, dir);
    if (b * b - (dot(oc, oc) - impostor.radius * impostor.radius) < 0.0) {
        discard;
    }
    let frames = frames_around(normalize(camera.eye - centre));
    var color = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var alpha = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let w = frames.weights[k];
        if (w <= 0.0) {
            continue;
        }
        let s = lookup(frames.cells[k], centre, o, dir);
        let a = s.color.a * s.inside * w;
        color += s.color.rgb * a;
        normal += s.normal * a;
        position += s.position * a;
        alpha += a;
    }
    // The alpha test; and only what lies ahead of the eye.
    if (alpha < ALPHA_TEST || dot(position / alpha - o, dir) <= 0.0) {
        discard;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(color / alpha, 1.0);
    let n = length(normal);
    out.normal = vec4<f32>(select(-dir, normal / n, n > 1e-20), 0.0);
    out.object = in.object;
    // Pixel depth offset: the depth of the surface found, not of the card.
    let clip = camera.view_proj * vec4<f32>(position / alpha, 1.0);
    out.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    return out;
}
