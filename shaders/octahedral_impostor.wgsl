// Octahedral impostor, as trompe bakes it (`trompe impostor bake MESH --octahedral N`):
// a camera-facing card whose fragments blend the three atlas frames around the view direction,
// each lookup parallax-corrected with the frame's depth, keep what has coverage ≥ ½ (the alpha
// test) and write the base colour, normal, object id and depth of the surface they found. The
// CPU reference is src/octahedral/render.rs, and src/octahedral/scene.rs draws a scene by the
// same rules; the layout is src/octahedral/mapping.rs (docs/conventions.md §8). The constants
// below are checked against the Rust code by the tests.
//
// Instanced: each instance is one copy of the baked object placed by its own similarity —
// world = rotation · (scale · p) + offset, p in the bake's space — with its own object id
// (per-instance vertex attributes 1–4); a copy drawn at the bake's place has offset zero, the
// identity rotation (0, 0, 0, 1) and scale 1.
//
// Entry points: `vs_main` with `fs_main` (colour, normal, object id and depth: a G-buffer), and
// `vs_main` with `fs_depth` (the depth alone: a shadow map seen from a light's eye, or a depth
// pre-pass), which keeps exactly the pixels fs_main keeps, at the same depth.
//
// Cross-fade: between the layout's `cross_fade` distances the impostor keeps a 4 × 4 dithered share
// of its pixels (`lod_impostor_draws`, which an engine's mesh shader calls to keep the others).
//
// Bindings: the colour atlas (NAME.png, an sRGB texture: coverage in alpha) and the normal-depth
// atlas (NAME-normal-depth.png, linear: rgb = n·½ + ½, a = depth), as the .glb embeds them, with
// or without mip levels; a linear sampler; two uniforms. Mip levels are chosen from each pixel's
// footprint and kept inside their frame (trompe fills every frame whole, so a power-of-two
// frame's box-filtered levels never mix frames).

const PARALLAX_STEPS: u32 = 4u;
const COVERAGE_SPHERE: u32 = 0u;
const COVERAGE_HEMISPHERE: u32 = 1u;
const ALPHA_TEST: f32 = 0.5;
const DEPTH_AGREEMENT: f32 = 0.125;

struct Camera {
    // World to clip space; depth is compared as the pipeline says (trompe's renderer: reversed).
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // The near plane's distance along the view direction.
    near: f32,
};

struct Impostor {
    // The bounding sphere's centre and radius in the bake's own space.
    centre: vec3<f32>,
    radius: f32,
    // Frames a side, texels a frame side, COVERAGE_*.
    frames: u32,
    frame_size: u32,
    coverage: u32,
    // 0 for orthographic frames; else pinhole frames, the eye this many radii from the centre
    // (the sidecar's `projection`).
    distance: f32,
    // The layout's `cross_fade` (start, end): the impostor draws a dithered share of the pixels
    // between the two distances, all of them past the end (0, 0: always all).
    fade_start: f32,
    fade_end: f32,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> impostor: Impostor;
@group(0) @binding(2) var atlas_color: texture_2d<f32>;
@group(0) @binding(3) var atlas_normal_depth: texture_2d<f32>;
@group(0) @binding(4) var atlas_sampler: sampler;

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

// Atlas coordinates of frame texel coordinates t (texel centres at +0.5), kept half a texel of
// mip level lod inside the frame.
fn atlas_uv(frame: vec2<u32>, t: vec2<f32>, lod: f32) -> vec2<f32> {
    let fs = f32(impostor.frame_size);
    let side = fs * f32(impostor.frames);
    let margin = 0.5 * exp2(lod);
    let inside = clamp(t, vec2<f32>(margin), vec2<f32>(fs - margin));
    return (vec2<f32>(frame) * fs + inside) / side;
}

// Frame texel coordinates of point p (the bake's space) in the frame looking along -d, the
// sphere centred on `centre` (mapping.rs `frame_basis`; render.rs `frame_texel`): orthographic,
// or through the frame's pinhole.
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

// Frame `frame` along the ray o + t·dir (the bake's space), parallax-corrected, sampled at
// mip level lod (render.rs `lookup`).
fn lookup(frame: vec2<u32>, o: vec3<f32>, dir: vec3<f32>, lod: f32) -> Lookup {
    let centre = impostor.centre;
    let d = frame_direction(frame);
    let right = frame_right(d);
    let up = cross(d, right);
    let r = impostor.radius;
    let facing = min(dot(dir, d), -1e-6);
    var offset = 0.0;
    var p = o + dir * (dot(centre + d * offset - o, d) / facing);
    var t = frame_texel(p, centre, d, right, up);
    for (var k = 0u; k < PARALLAX_STEPS; k = k + 1u) {
        let depth = textureSampleLevel(atlas_normal_depth, atlas_sampler, atlas_uv(frame, t, lod), lod).a;
        offset = r - 2.0 * r * depth;
        p = o + dir * (dot(centre + d * offset - o, d) / facing);
        t = frame_texel(p, centre, d, right, up);
    }
    let fs = f32(impostor.frame_size);
    let uv = atlas_uv(frame, t, lod);
    var out: Lookup;
    out.color = textureSampleLevel(atlas_color, atlas_sampler, uv, lod);
    out.normal = textureSampleLevel(atlas_normal_depth, atlas_sampler, uv, lod).xyz * 2.0 - vec3<f32>(1.0);
    out.position = p;
    out.inside = select(0.0, 1.0, all(t >= vec2<f32>(-1.0)) && all(t <= vec2<f32>(fs + 1.0)));
    return out;
}

// The share of pixels the impostor draws `distance` from the eye (the bake's units: a world
// distance over the instance's scale) — src/octahedral/lod.rs `impostor_share`.
fn lod_share(distance: f32) -> f32 {
    if (impostor.fade_end <= impostor.fade_start) {
        return select(0.0, 1.0, distance >= impostor.fade_start);
    }
    return clamp((distance - impostor.fade_start) / (impostor.fade_end - impostor.fade_start), 0.0, 1.0);
}

// Whether the impostor draws the fragment at `frag` (its @builtin(position).xy) `distance` from
// the eye: its 4 × 4 Bayer threshold below the share. An engine's mesh shader for the same object
// discards exactly where this is true, so every pixel is drawn once across the fade.
fn lod_impostor_draws(frag: vec2<f32>, distance: f32) -> bool {
    let bayer = array<u32, 16>(0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);
    let p = vec2<u32>(floor(frag)) % vec2<u32>(4u);
    let threshold = (f32(bayer[p.y * 4u + p.x]) + 0.5) / 16.0;
    return threshold < lod_share(distance);
}

// Unit quaternion q (x, y, z, w) applied to v.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let u = cross(q.xyz, v) + q.w * v;
    return v + 2.0 * cross(q.xyz, u);
}

// The inverse rotation.
fn unrotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    return rotate(vec4<f32>(-q.xyz, q.w), v);
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // The card's point in the bake's space.
    @location(0) local: vec3<f32>,
    // The eye in the bake's space, and the instance's similarity and object id.
    @location(1) @interpolate(flat) eye: vec3<f32>,
    @location(2) @interpolate(flat) object: u32,
    @location(3) @interpolate(flat) rotation: vec4<f32>,
    @location(4) @interpolate(flat) offset_scale: vec4<f32>,
};

// A camera-facing card within the bounding sphere's diameter: `corner` in [-1, 1]², the card's
// outline (the layout's `card`, counter-clockwise, drawn as a triangle strip in the order
// 0, 1, n−1, 2, n−2, …; the square's four corners without one) in units of the radius; per
// instance, its offset, object id, rotation (a unit quaternion) and scale.
@vertex
fn vs_main(
    @location(0) corner: vec2<f32>,
    @location(1) offset: vec3<f32>,
    @location(2) object: u32,
    @location(3) rotation: vec4<f32>,
    @location(4) scale: f32,
) -> VertexOut {
    let centre = impostor.centre;
    let r = impostor.radius;
    let eye = unrotate(rotation, camera.eye - offset) / scale;
    let to_eye = normalize(eye - centre);
    var local: vec3<f32>;
    if ((length(eye - centre) - r) * scale > 4.0 * camera.near) {
        // The card stands in front of the sphere so no surface point is clipped by it, and
        // covers its silhouette.
        let right = frame_right(to_eye);
        let up = cross(to_eye, right);
        local = centre + to_eye * r + (right * corner.x + up * corner.y) * r;
    } else {
        // The eye in the sphere or at it: a card across the whole view just past the near
        // plane (the view direction is clip w's row), every pixel's ray through it.
        let m = camera.view_proj;
        let forward = normalize(vec3<f32>(m[0][3], m[1][3], m[2][3]));
        let right = frame_right(-forward);
        let up = cross(-forward, right);
        let d = 4.0 * camera.near;
        // The outline's corners pushed onto the square's edge: wide enough whatever its shape.
        let c = corner / max(max(abs(corner.x), abs(corner.y)), 1e-6);
        let world = camera.eye + forward * d + (right * c.x + up * c.y) * (100.0 * d);
        local = unrotate(rotation, world - offset) / scale;
    }
    var out: VertexOut;
    out.clip = camera.view_proj * vec4<f32>(rotate(rotation, local * scale) + offset, 1.0);
    out.local = local;
    out.eye = eye;
    out.object = object;
    out.rotation = rotation;
    out.offset_scale = vec4<f32>(offset, scale);
    return out;
}

// What a fragment found: the blended colour, normal (the bake's space) and point.
struct Found {
    keep: bool,
    color: vec3<f32>,
    normal: vec3<f32>,
    // In the world.
    position: vec3<f32>,
    depth: f32,
};

// The mip level of a pixel's footprint on the card (in uniform control flow: derivatives): a
// bilinear tap of level L spans 2^(L+1) texels, so a footprint of w texels takes log2(w) - 1.
fn footprint_lod(local: vec3<f32>) -> f32 {
    let footprint = max(length(dpdx(local)), length(dpdy(local)));
    let texels = footprint * f32(impostor.frame_size) / (2.0 * impostor.radius);
    let levels = f32(textureNumLevels(atlas_color)) - 1.0;
    // Down to two texels a frame at most.
    let coarsest = min(levels, max(log2(f32(impostor.frame_size)) - 1.0, 0.0));
    return clamp(log2(max(texels, 1e-8)) - 1.0, 0.0, coarsest);
}

fn find(in: VertexOut, lod: f32) -> Found {
    var found: Found;
    found.keep = false;
    let o = in.eye;
    let dir = normalize(in.local - o);
    let centre = impostor.centre;
    // Only rays through the bounding sphere meet the object.
    let oc = o - centre;
    let b = dot(oc, dir);
    if (b * b - (dot(oc, oc) - impostor.radius * impostor.radius) < 0.0) {
        return found;
    }
    let frames = frames_around(normalize(o - centre));
    var looks: array<Lookup, 3>;
    // The nearest surface a covered frame finds along the ray.
    var front = 3.0e38;
    for (var k = 0u; k < 3u; k = k + 1u) {
        if (frames.weights[k] > 0.0) {
            looks[k] = lookup(frames.cells[k], o, dir, lod);
            if (looks[k].color.a * looks[k].inside >= ALPHA_TEST) {
                front = min(front, dot(looks[k].position - o, dir));
            }
        }
    }
    var color = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var alpha = 0.0;
    var total = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        var w = frames.weights[k];
        if (w <= 0.0) {
            continue;
        }
        let s = looks[k];
        let coverage = s.color.a * s.inside;
        // Depth-aware blending (render.rs `blend`): a frame that sees past the nearest surface
        // fades out. At mip level L a lookup's depth is the mean of 2^L texels, which shrinks
        // the gaps a level-0 blend sees; the tolerance shrinks with it (docs/octahedral.md).
        if (coverage >= ALPHA_TEST) {
            let tolerance = DEPTH_AGREEMENT * impostor.radius * exp2(-lod);
            let behind = (dot(s.position - o, dir) - front) / tolerance;
            w = w * exp(-behind * behind);
        }
        total += w;
        let a = coverage * w;
        color += s.color.rgb * a;
        normal += s.normal * a;
        position += s.position * a;
        alpha += a;
    }
    // The alpha test; and only what lies ahead of the eye.
    if (total <= 0.0 || alpha < ALPHA_TEST * total || dot(position / alpha - o, dir) <= 0.0) {
        return found;
    }
    let n = length(normal);
    let rotation = in.rotation;
    let offset = in.offset_scale.xyz;
    let scale = in.offset_scale.w;
    found.keep = true;
    found.color = color / alpha;
    found.normal = rotate(rotation, select(-dir, normal / n, n > 1e-20));
    found.position = rotate(rotation, position / alpha * scale) + offset;
    // Pixel depth offset: the depth of the surface found, not of the card.
    let clip = camera.view_proj * vec4<f32>(found.position, 1.0);
    found.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    return found;
}

struct FragmentOut {
    // Base colour (alpha 1: the surface is kept whole).
    @location(0) color: vec4<f32>,
    // The blended unit normal in the world (toward the eye where the frames' normals cancel).
    @location(1) normal: vec4<f32>,
    @location(2) object: u32,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let lod = footprint_lod(in.local);
    if (!lod_impostor_draws(in.clip.xy, length(in.eye - impostor.centre))) {
        discard;
    }
    let found = find(in, lod);
    if (!found.keep) {
        discard;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(found.color, 1.0);
    out.normal = vec4<f32>(found.normal, 0.0);
    out.object = in.object;
    out.depth = found.depth;
    return out;
}

// The depth alone: a shadow map or a depth pre-pass (no colour target).
@fragment
fn fs_depth(in: VertexOut) -> @builtin(frag_depth) f32 {
    let lod = footprint_lod(in.local);
    if (!lod_impostor_draws(in.clip.xy, length(in.eye - impostor.centre))) {
        discard;
    }
    let found = find(in, lod);
    if (!found.keep) {
        discard;
    }
    return found.depth;
}
