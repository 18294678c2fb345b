// Paper 1's ray–impostor intersection in a shader (§3.2, made exact as the library's
// src/impostor/texels.rs makes it; docs/conventions.md §2.3): the ray is clipped to the box of
// the replaced geometry (its exit grown by the impostor's margin), its image through the
// impostor's camera is followed texel by texel, every layer tested at each texel where the ray
// enters and leaves it against the plane of the triangle the texel stores, and pyramid nodes
// the ray passes in front of are stepped over. The acceptance rules are src/impostor/walk.rs's:
// a sign change of the signed distance to a texel plane is a hit only where the ray meets the
// plane within two footprints (stretched by the slant, at most 1/0.3) of the stored point; the
// nearest crossing of any layer wins.
//
// This is the library's walk in f32 rather than f64: the same samples in the same order, so
// the same texel answers but where a path passes within rounding of a grid corner. Every
// impostor camera: pinhole and orthographic (one straight piece), the SPOC (a hyperbola, §3.4,
// cut where its coordinates turn) and the graph camera (the ray cut at the frusta's faces,
// §4.6's algorithm 2); the impostor records say which. The paths are path.wgsl's, compiled
// before this file.

struct WalkImpostor {
    // The camera's rows. Pinhole and SPOC: a point p's homogeneous pinhole image is
    // (u·p̂, v·p̂, w·p̂) with p̂ = (p, 1), its gd 1 / w·p̂; orthographic: the image is (u·p̂, v·p̂)
    // and gd is g·p̂. clip·p̂ ≥ 0 is the camera's domain.
    u_row: vec4<f32>,
    v_row: vec4<f32>,
    w_row: vec4<f32>,
    // Orthographic: the gd row. SPOC: the pole (xy), z_n, the ramp's slope k / (z_f − z_n).
    g_row: vec4<f32>,
    clip_row: vec4<f32>,
    // xyz: the centre of projection (pinhole, SPOC) or the way back along the view
    // (orthographic); w: the world size of a texel at gd 1 (pinhole, SPOC) or anywhere
    // (orthographic).
    eye: vec4<f32>,
    // SPOC: McMillan's a, b, c of its pinhole (xyz); a.w: the focal distance.
    m_a: vec4<f32>,
    m_b: vec4<f32>,
    m_c: vec4<f32>,
    // The box of the replaced geometry; min.w: how far past it a walk goes on.
    box_min: vec4<f32>,
    box_max: vec4<f32>,
    // Width, height, first layer record, layer count.
    size: vec4<u32>,
    // Pyramid levels (the last 1 × 1), its first node past level 0, the camera's kind, flags
    // (RADIANCE, MOVED).
    info: vec4<u32>,
    // Graph camera: its first frustum record, its frustum count.
    graph: vec4<u32>,
    // Rows of the motion from now to where it was built, and back (identity: not moved).
    built_from_now: array<vec4<f32>, 3>,
    now_from_built: array<vec4<f32>, 3>,
}

@group(0) @binding(13) var<storage, read> walk_impostors: array<WalkImpostor>;
// Per layer: its first texel record.
@group(0) @binding(14) var<storage, read> walk_layers: array<u32>;
// Two a texel: (stored point, gd), (face normal turned to the camera, front bound).
@group(0) @binding(15) var<storage, read> walk_planes: array<vec4<f32>>;
// Two a texel: (shading normal, object bits), (colour, 0).
@group(0) @binding(16) var<storage, read> walk_looks: array<vec4<f32>>;
// Every impostor's pyramid of front bounds, levels 1 and up.
@group(0) @binding(17) var<storage, read> walk_pyramid: array<f32>;
// Every graph camera's frusta, FRUSTUM_STRIDE a frustum: (apex, plane count bits), the rows of
// its matrix, the rows of its inverse, its planes (n, e) with n·x + e ≥ 0 inside.
@group(0) @binding(19) var<storage, read> walk_frusta: array<vec4<f32>>;

const WALK_LAYERS: u32 = 8u;
const THICKNESS_FOOTPRINTS: f32 = 2.0;
const MIN_COS: f32 = 0.3;
const WALK_STEPS: u32 = 1048576u;
const WALK_FAR: f32 = 3.4028235e38;
const PINHOLE: u32 = 0u;
const ORTHOGRAPHIC: u32 = 1u;
const SPOC: u32 = 2u;
const GRAPH: u32 = 3u;
const FRUSTUM_STRIDE: u32 = 17u;
const FRUSTUM_PLANES: u32 = 8u;
const MAX_FRUSTA: u32 = 64u;
const NO_TEXEL: u32 = 0xffffffffu;
// Its hits carry the impostor's colour.
const RADIANCE: u32 = 1u;
// Its object has moved since it was built.
const MOVED: u32 = 2u;

// One sample of one layer's run (src/impostor/texels.rs's `Mark`): where on the path, which
// texel (x < 0: none), the stored gd there (< 0: the last texel of a stepped-over node, read
// only if needed), the signed distance to the texel's plane (+∞ over empty texels).
struct Mark {
    s: f32,
    piece: u32,
    texel: vec2<i32>,
    stored: f32,
    delta: f32,
    valid: bool,
}

// A hit of a walk: distance, where, the texel record it stores and the layer.
struct WalkHit {
    t: f32,
    record: u32,
    layer: u32,
    position: vec3<f32>,
}

fn no_walk_hit() -> WalkHit {
    return WalkHit(WALK_FAR, NO_TEXEL, 0u, vec3<f32>(0.0));
}

fn record_of(imp: WalkImpostor, layer: u32, texel: vec2<i32>) -> u32 {
    return walk_layers[imp.size.z + layer] + u32(texel.y) * imp.size.x + u32(texel.x);
}

// Frustum j's record.
fn frustum_at(imp: WalkImpostor, j: u32) -> u32 {
    return (imp.graph.x + j) * FRUSTUM_STRIDE;
}

// Whether x lies in frustum record f (its planes, within tol).
fn frustum_contains(f: u32, x: vec3<f32>, tol: f32) -> bool {
    let planes = bitcast<u32>(walk_frusta[f].w);
    for (var i = 0u; i < planes; i = i + 1u) {
        let p = walk_frusta[f + 9u + i];
        if (dot(p.xyz, x) + p.w < -tol) {
            return false;
        }
    }
    return true;
}

// The first frustum holding x (src/camera/graph.rs's `locate`), or the root.
fn locate(imp: WalkImpostor, x: vec3<f32>) -> u32 {
    for (var j = 0u; j < imp.graph.y; j = j + 1u) {
        if (frustum_contains(frustum_at(imp, j), x, 1e-12)) {
            return j;
        }
    }
    return 0u;
}

// Frustum record f's unprojection of (uv, gd): its inverse matrix, then the homogeneous divide.
fn frustum_unproject(f: u32, uv: vec2<f32>, gd: f32) -> vec3<f32> {
    let w = 1.0 / gd;
    let h = vec4<f32>(uv.x * w, uv.y * w, 1.0, w);
    let x = vec4<f32>(dot(walk_frusta[f + 5u], h), dot(walk_frusta[f + 6u], h), dot(walk_frusta[f + 7u], h), dot(walk_frusta[f + 8u], h));
    return x.xyz / x.w;
}

// The graph camera's unprojection: the frustum whose inverse lands inside it, else the root's.
fn graph_unproject(imp: WalkImpostor, uv: vec2<f32>, gd: f32) -> vec3<f32> {
    for (var j = 0u; j < imp.graph.y; j = j + 1u) {
        let f = frustum_at(imp, j);
        let x = frustum_unproject(f, uv, gd);
        if (frustum_contains(f, x, 1e-9 * (1.0 + length(x)))) {
            return x;
        }
    }
    return frustum_unproject(frustum_at(imp, 0u), uv, gd);
}

// The world size of a texel at (uv, gd) divided by the cosine (at least MIN_COS) between the
// stored plane's normal n and the way back to the camera from the stored point p
// (src/impostor/maps.rs's `footprint`, src/impostor/camera.rs's `toward_camera_along_ray`).
fn slanted_footprint(imp: WalkImpostor, uv: vec2<f32>, gd: f32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let kind = imp.info.z;
    var view = imp.eye.xyz - p;
    var footprint = imp.eye.w / gd;
    if (kind == ORTHOGRAPHIC) {
        view = imp.eye.xyz;
        footprint = imp.eye.w;
    } else if (kind == SPOC) {
        // X(g) = C + M·(q(g), 1)/g with q = p0 + (uv − p0)/σ(g), σ = 1 + κ(f/g): the way
        // along the SPOC's ray is dX/dg.
        let f = imp.m_a.w;
        let z = f / gd;
        let sigma = 1.0 + kappa(imp, z);
        let r = uv - imp.g_row.xy;
        let q = imp.g_row.xy + r / sigma;
        var d_sigma = 0.0;
        if (z > imp.g_row.z) {
            d_sigma = -imp.g_row.w * f / (gd * gd);
        }
        let dq = -r * d_sigma / (sigma * sigma);
        let mq = imp.m_a.xyz * q.x + imp.m_b.xyz * q.y + imp.m_c.xyz;
        view = -mq / (gd * gd) + (imp.m_a.xyz * dq.x + imp.m_b.xyz * dq.y) / gd;
        footprint = imp.eye.w / (sigma * gd);
    } else if (kind == GRAPH) {
        let f = frustum_at(imp, locate(imp, graph_unproject(imp, uv, gd)));
        let x = frustum_unproject(f, uv, gd);
        let dx = frustum_unproject(f, uv + vec2<f32>(1.0, 0.0), gd) - x;
        let dy = frustum_unproject(f, uv + vec2<f32>(0.0, 1.0), gd) - x;
        footprint = max(length(dx), length(dy));
        view = walk_frusta[frustum_at(imp, locate(imp, p))].xyz - p;
    }
    let lv = length(view);
    var cos_v = MIN_COS;
    if (lv > 0.0) {
        cos_v = max(abs(dot(n, view / lv)), MIN_COS);
    }
    return footprint / cos_v;
}

// The crossing of the ray with the plane of m's texel when it lies within the thickness of
// the stored point (src/impostor/walk.rs's `accept`, one candidate): w = 1, or w = 0.
fn plane_crossing(imp: WalkImpostor, path: Path, layer: u32, o: vec3<f32>, d: vec3<f32>, m: Mark) -> vec4<f32> {
    let record = record_of(imp, layer, m.texel);
    let a = walk_planes[2u * record];
    let stored_point = a.xyz;
    let n = walk_planes[2u * record + 1u].xyz;
    let denom = dot(d, n);
    if (abs(denom) < 1e-9) {
        return vec4<f32>(0.0);
    }
    let x = o + d * (dot(stored_point - o, n) / denom);
    let uv = piece_uv(path.pieces[m.piece], m.s);
    if (length(x - stored_point) <= THICKNESS_FOOTPRINTS * slanted_footprint(imp, uv, a.w, stored_point, n)) {
        return vec4<f32>(x, 1.0);
    }
    return vec4<f32>(0.0);
}

// A layer's verdict on a sign change from a to b: b's plane, then a's.
fn crossing(imp: WalkImpostor, path: Path, layer: u32, o: vec3<f32>, d: vec3<f32>, a: Mark, b: Mark) -> WalkHit {
    if (a.texel.x < 0 || b.texel.x < 0) {
        return no_walk_hit();
    }
    var a_stored = a.stored;
    if (a_stored < 0.0) {
        a_stored = walk_planes[2u * record_of(imp, layer, a.texel)].w;
    }
    var b_stored = b.stored;
    if (b_stored < 0.0) {
        b_stored = walk_planes[2u * record_of(imp, layer, b.texel)].w;
    }
    if (a_stored <= 0.0 || b_stored <= 0.0) {
        return no_walk_hit();
    }
    let at_b = plane_crossing(imp, path, layer, o, d, b);
    if (at_b.w != 0.0) {
        return WalkHit(dot(at_b.xyz - o, d), record_of(imp, layer, b.texel), layer, at_b.xyz);
    }
    let at_a = plane_crossing(imp, path, layer, o, d, a);
    if (at_a.w != 0.0) {
        return WalkHit(dot(at_a.xyz - o, d), record_of(imp, layer, a.texel), layer, at_a.xyz);
    }
    return no_walk_hit();
}

// The largest front bound under node (x, y) of pyramid level `level` ≥ 1.
fn pyramid_node(imp: WalkImpostor, level: u32, x: u32, y: u32) -> f32 {
    var offset = imp.info.y;
    for (var l = 1u; l < level; l = l + 1u) {
        let lw = (imp.size.x + (1u << l) - 1u) >> l;
        let lh = (imp.size.y + (1u << l) - 1u) >> l;
        offset = offset + lw * lh;
    }
    let lw = (imp.size.x + (1u << level) - 1u) >> level;
    return walk_pyramid[offset + y * lw + x];
}

// The stretch [s_a, s_b] of the piece inside the w × h image (x = s_a, y = s_b, z = 1), or z = 0.
fn inside(pc: Piece, w: f32, h: f32) -> vec3<f32> {
    let forward = pc.end > pc.start;
    let a = piece_uv(pc, pc.start);
    let b = piece_uv(pc, pc.end);
    var s_a = pc.start;
    var s_b = pc.end;
    let size = vec2<f32>(w, h);
    for (var k = 0u; k < 2u; k = k + 1u) {
        let lo = min(a[k], b[k]);
        let hi = max(a[k], b[k]);
        if (hi < 0.0 || lo >= size[k]) {
            return vec3<f32>(0.0);
        }
        let rising = b[k] > a[k];
        let first = select(size[k], 0.0, rising);
        let last = select(0.0, size[k], rising);
        let out_at_start = select(a[k] > first, a[k] < first, rising);
        if (out_at_start) {
            let c = piece_crossing(pc, k, first);
            if (c.y != 0.0) {
                s_a = select(min(s_a, c.x), max(s_a, c.x), forward);
            }
        }
        let out_at_end = select(b[k] < last, b[k] > last, rising);
        if (out_at_end) {
            let c = piece_crossing(pc, k, last);
            if (c.y != 0.0) {
                s_b = select(max(s_b, c.x), min(s_b, c.x), forward);
            }
        }
    }
    let empty = select(s_a <= s_b, s_a >= s_b, forward);
    if (empty) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(s_a, s_b, 1.0);
}

fn before(a: f32, b: f32, forward: bool) -> bool {
    return select(a > b, a < b, forward);
}

// The slab test of src/geom/mod.rs's `Aabb::intersect`: (t0, t1, 1) or z = 0.
fn box_span(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> vec3<f32> {
    let inv = 1.0 / d;
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let near = min(ta, tb);
    let far = max(ta, tb);
    let t0 = max(max(max(near.x, near.y), near.z), 0.0);
    let t1 = min(min(min(far.x, far.y), far.z), t_max);
    return vec3<f32>(t0, t1, select(0.0, 1.0, t0 <= t1));
}

// The part of [c, e] in a camera's domain (src/impostor/walk.rs's `clip_to_domain`).
struct Clipped {
    c: vec3<f32>,
    e: vec3<f32>,
    ok: bool,
}

fn clip_to_domain(clip: vec4<f32>, c: vec3<f32>, e: vec3<f32>) -> Clipped {
    let dc = dot(clip, vec4<f32>(c, 1.0));
    let de = dot(clip, vec4<f32>(e, 1.0));
    if (dc >= 0.0 && de >= 0.0) {
        return Clipped(c, e, true);
    }
    if (!(dc >= 0.0 || de >= 0.0)) {
        return Clipped(c, e, false);
    }
    let s = clamp(dc / (dc - de), 0.0, 1.0);
    let cut = c + (e - c) * s;
    var inward = c - cut;
    if (dc < 0.0) {
        inward = e - cut;
    }
    let nudged = cut + inward * 1e-6;
    if (dc < 0.0) {
        return Clipped(nudged, e, true);
    }
    return Clipped(c, nudged, true);
}

// The texel of the level-`level` node holding `cell` where the path leaves it at `s_out`.
fn last_texel(pc: Piece, cell: vec2<i32>, level: u32, s_out: f32, crossed: vec2<bool>, dir: vec2<i32>, size: vec2<i32>) -> vec2<i32> {
    let at = piece_uv(pc, s_out);
    var texel = vec2<i32>(0);
    for (var k = 0u; k < 2u; k = k + 1u) {
        let lo = (cell[k] >> level) << level;
        let hi = min(lo + (1 << level) - 1, size[k] - 1);
        if (crossed[k]) {
            texel[k] = select(lo, hi, dir[k] > 0);
        } else {
            texel[k] = clamp(i32(at[k]), lo, hi);
        }
    }
    return texel;
}

// Where the path leaves, along axis k, the level-`level` node holding `cell`.
fn leave(pc: Piece, k: u32, cell: vec2<i32>, level: u32, s_in: f32, s_b: f32, dir: vec2<i32>, forward: bool) -> f32 {
    if (dir[k] == 0) {
        return s_b;
    }
    let node = cell[k] >> level;
    var line = node << level;
    if (dir[k] > 0) {
        line = (node + 1) << level;
    }
    let c = piece_crossing(pc, k, f32(line));
    let s = select(s_b, c.x, c.y != 0.0);
    if (before(s, s_in, forward)) {
        return s_in;
    }
    if (before(s, s_b, forward)) {
        return s;
    }
    return s_b;
}

// The texel walk of `path` (part of the ray o + t·d) through every layer, stepping over pyramid
// nodes the ray passes in front of when `skip`: the nearest accepted crossing
// (src/impostor/texels.rs's `walk_texels`).
fn walk_path(imp: WalkImpostor, path: Path, o: vec3<f32>, d: vec3<f32>, skip: bool) -> WalkHit {
    var best = no_walk_hit();
    let along = vec2<f32>(dot(path.x0 - o, d), dot(path.x1, d));
    let layers = min(imp.size.w, WALK_LAYERS);
    var prev: array<Mark, WALK_LAYERS>;
    var done: array<bool, WALK_LAYERS>;
    for (var l = 0u; l < WALK_LAYERS; l = l + 1u) {
        prev[l] = Mark(0.0, 0u, vec2<i32>(-1), 0.0, WALK_FAR, false);
        done[l] = false;
    }
    var walking = layers;
    let w = i32(imp.size.x);
    let h = i32(imp.size.y);
    let size = vec2<i32>(w, h);
    let top = imp.info.x - 1u;
    var steps = 0u;
    var started = false;
    for (var index = 0u; index < path.count; index = index + 1u) {
        let piece = path.pieces[index];
        let span = inside(piece, f32(w), f32(h));
        if (span.z == 0.0) {
            continue;
        }
        let s_a = span.x;
        let s_b = span.y;
        if (started && s_a != piece.start) {
            // The path left the image and comes back: outside, everything is empty.
            for (var l = 0u; l < layers; l = l + 1u) {
                if (!done[l]) {
                    prev[l] = Mark(s_a, index, vec2<i32>(-1), 0.0, WALK_FAR, true);
                }
            }
        }
        started = true;
        let forward = piece.end > piece.start;
        let ends = piece_uv(piece, s_b) - piece_uv(piece, s_a);
        let dir = vec2<i32>(i32(sign(ends.x)), i32(sign(ends.y)));
        let start = piece_uv(piece, s_a + (s_b - s_a) * 1e-6);
        var cell = vec2<i32>(clamp(i32(start.x), 0, w - 1), clamp(i32(start.y), 0, h - 1));
        var s_in = s_a;
        var level = 0u;
        var exits = vec2<f32>(0.0);
        var known = vec2<bool>(false);
        // The level-1 node where climbing last failed.
        var failed = vec2<i32>(-1);
        loop {
            steps = steps + 1u;
            let finished = walking == 0u || (best.record != NO_TEXEL && along.x + along.y * s_in > best.t);
            if (steps > WALK_STEPS || finished) {
                return best;
            }
            var ex = exits.x;
            if (!known.x) {
                ex = leave(piece, 0u, cell, level, s_in, s_b, dir, forward);
            }
            var ey = exits.y;
            if (!known.y) {
                ey = leave(piece, 1u, cell, level, s_in, s_b, dir, forward);
            }
            let s_out = select(ex, ey, before(ey, ex, forward));
            let crossed = vec2<bool>(dir.x != 0 && ex == s_out && s_out != s_b, dir.y != 0 && ey == s_out && s_out != s_b);
            if (level > 0u) {
                let bound = pyramid_node(imp, level, u32(cell.x >> level), u32(cell.y >> level));
                if (min(path_gd(path, s_in), path_gd(path, s_out)) > bound) {
                    // The whole stretch is in front of every plane: step over the node.
                    let last = last_texel(piece, cell, level, s_out, crossed, dir, size);
                    for (var l = 0u; l < layers; l = l + 1u) {
                        if (!done[l]) {
                            prev[l] = Mark(s_out, index, last, -1.0, WALK_FAR, true);
                        }
                    }
                    if (!(crossed.x || crossed.y)) {
                        break;
                    }
                    let at = piece_uv(piece, s_out);
                    for (var k = 0u; k < 2u; k = k + 1u) {
                        let lo = (cell[k] >> level) << level;
                        if (crossed[k]) {
                            cell[k] = select(lo - 1, lo + (1 << level), dir[k] > 0);
                        } else {
                            let hi = min(lo + (1 << level) - 1, size[k] - 1);
                            cell[k] = clamp(i32(at[k]), lo, hi);
                        }
                    }
                    if (cell.x < 0 || cell.y < 0 || cell.x >= w || cell.y >= h) {
                        break;
                    }
                    s_in = s_out;
                    level = min(level + 1u, top);
                } else {
                    if (level == 1u) {
                        failed = cell >> vec2<u32>(1u);
                    } else {
                        failed = vec2<i32>(-1);
                    }
                    level = level - 1u;
                }
                known = vec2<bool>(false);
                continue;
            }
            // Texel `cell` of every layer still walking, from s_in to s_out.
            var in_front = true;
            let g_out = path_gd(path, s_out);
            for (var l = 0u; l < layers; l = l + 1u) {
                if (done[l]) {
                    continue;
                }
                let record = record_of(imp, l, cell);
                let plane = walk_planes[2u * record];
                let gd = plane.w;
                var d_in = WALK_FAR;
                var d_out = WALK_FAR;
                var front = 0.0;
                if (gd > 0.0) {
                    let normal = walk_planes[2u * record + 1u];
                    let base = dot(path.x0 - plane.xyz, normal.xyz);
                    let rate = dot(path.x1, normal.xyz);
                    d_in = base + rate * s_in;
                    d_out = base + rate * s_out;
                    front = normal.w;
                }
                for (var k = 0u; k < 2u; k = k + 1u) {
                    let s = select(s_out, s_in, k == 0u);
                    let delta = select(d_out, d_in, k == 0u);
                    let cur = Mark(s, index, cell, gd, delta, true);
                    let p = prev[l];
                    if (p.valid && p.delta > 0.0 && delta <= 0.0) {
                        let hit = crossing(imp, path, l, o, d, p, cur);
                        if (hit.record != NO_TEXEL) {
                            done[l] = true;
                            walking = walking - 1u;
                            if (best.record == NO_TEXEL || hit.t < best.t) {
                                best = hit;
                            }
                            break;
                        }
                    }
                    prev[l] = cur;
                }
                if (!done[l] && gd > 0.0 && !(g_out > front)) {
                    in_front = false;
                }
            }
            if (!(crossed.x || crossed.y)) {
                break;
            }
            let climb = skip && top > 0u && in_front && any(failed != (cell >> vec2<u32>(1u)));
            for (var k = 0u; k < 2u; k = k + 1u) {
                if (crossed[k]) {
                    cell[k] = cell[k] + dir[k];
                }
            }
            if (cell.x < 0 || cell.y < 0 || cell.x >= w || cell.y >= h) {
                break;
            }
            s_in = s_out;
            if (climb) {
                level = 1u;
                known = vec2<bool>(false);
            } else {
                exits = vec2<f32>(ex, ey);
                known = !crossed;
            }
        }
    }
    return best;
}

// The texel walk of [c, e] (part of the ray o + t·d) through a projective camera.
fn walk_projective(imp: WalkImpostor, cam: Projective, o: vec3<f32>, d: vec3<f32>, c: vec3<f32>, e: vec3<f32>, skip: bool) -> WalkHit {
    let clipped = clip_to_domain(cam.clip, c, e);
    if (!clipped.ok) {
        return no_walk_hit();
    }
    let pc = project(cam, clipped.c);
    let pe = project(cam, clipped.e);
    if (!pc.ok || !pe.ok) {
        return no_walk_hit();
    }
    return walk_path(imp, projective_path(clipped.c, clipped.e, pc, pe), o, d, skip);
}

// §4.6's algorithm 2: the ray clipped to every frustum (Cyrus–Beck), the pieces walked in order
// along it, each with its frustum's matrix; the first piece with a hit answers. No node is
// stepped over.
fn walk_graph(imp: WalkImpostor, o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> WalkHit {
    var pieces: array<vec3<f32>, MAX_FRUSTA>;
    var count = 0u;
    for (var j = 0u; j < min(imp.graph.y, MAX_FRUSTA); j = j + 1u) {
        let f = frustum_at(imp, j);
        let planes = bitcast<u32>(walk_frusta[f].w);
        var lo = t0;
        var hi = t1;
        var outside = false;
        for (var i = 0u; i < planes; i = i + 1u) {
            let p = walk_frusta[f + 9u + i];
            let num = dot(p.xyz, o) + p.w;
            let den = dot(p.xyz, d);
            if (den == 0.0) {
                if (num < 0.0) {
                    outside = true;
                }
            } else {
                let t = -num / den;
                if (den > 0.0) {
                    lo = max(lo, t);
                } else {
                    hi = min(hi, t);
                }
            }
        }
        if (outside || !(lo < hi)) {
            continue;
        }
        // Insertion by (entry, frustum).
        var k = count;
        while (k > 0u && pieces[k - 1u].x > lo) {
            pieces[k] = pieces[k - 1u];
            k = k - 1u;
        }
        pieces[k] = vec3<f32>(lo, hi, bitcast<f32>(j));
        count = count + 1u;
    }
    for (var i = 0u; i < count; i = i + 1u) {
        let f = frustum_at(imp, bitcast<u32>(pieces[i].z));
        let w_row = walk_frusta[f + 4u];
        let cam = Projective(walk_frusta[f + 1u], walk_frusta[f + 2u], w_row, vec4<f32>(0.0), w_row - vec4<f32>(0.0, 0.0, 0.0, 1e-9), false);
        let hit = walk_projective(imp, cam, o, d, o + d * pieces[i].x, o + d * pieces[i].y, false);
        if (hit.record != NO_TEXEL) {
            return hit;
        }
    }
    return no_walk_hit();
}

// The walk of impostor `index` by the ray origin + t·dir: every layer, the nearest crossing
// with 0 < t < t_max (src/impostor/walk.rs's `closest_hit`), where its object is now.
fn walk_impostor(index: u32, origin: vec3<f32>, dir_in: vec3<f32>, t_max: f32) -> WalkHit {
    let imp = walk_impostors[index];
    var o = origin;
    var d = dir_in;
    // Into the frame the impostor was built in.
    let moved = (imp.info.w & MOVED) != 0u;
    if (moved) {
        let m = imp.built_from_now;
        o = vec3<f32>(dot(m[0], vec4<f32>(origin, 1.0)), dot(m[1], vec4<f32>(origin, 1.0)), dot(m[2], vec4<f32>(origin, 1.0)));
        d = vec3<f32>(dot(m[0].xyz, dir_in), dot(m[1].xyz, dir_in), dot(m[2].xyz, dir_in));
    }
    let entry = box_span(imp.box_min.xyz, imp.box_max.xyz, o, d, t_max);
    if (entry.z == 0.0) {
        return no_walk_hit();
    }
    let margin = vec3<f32>(imp.box_min.w);
    let reach = box_span(imp.box_min.xyz - margin, imp.box_max.xyz + margin, o, d, t_max);
    if (reach.z == 0.0) {
        return no_walk_hit();
    }
    let kind = imp.info.z;
    var best = no_walk_hit();
    if (kind == GRAPH) {
        best = walk_graph(imp, o, d, entry.x, reach.y);
    } else if (kind == SPOC) {
        let cam = camera_of(imp);
        let clipped = clip_to_domain(cam.clip, o + d * entry.x, o + d * reach.y);
        if (clipped.ok) {
            let qc = project(cam, clipped.c);
            let qe = project(cam, clipped.e);
            if (qc.ok && qe.ok) {
                best = walk_path(imp, spoc_path(imp, clipped.c, clipped.e, qc, qe), o, d, true);
            }
        }
    } else {
        best = walk_projective(imp, camera_of(imp), o, d, o + d * entry.x, o + d * reach.y, true);
    }
    // What src/impostor/walk.rs's `closest_hit` keeps.
    if (!(best.t > 0.0 && best.t < t_max)) {
        return no_walk_hit();
    }
    if (moved) {
        // Back to where the object is now.
        let m = imp.now_from_built;
        let p = best.position;
        best.position = vec3<f32>(dot(m[0], vec4<f32>(p, 1.0)), dot(m[1], vec4<f32>(p, 1.0)), dot(m[2], vec4<f32>(p, 1.0)));
    }
    return best;
}

// One ray a thread against impostor `params.any_hit` (the walk's test and bench): (t, texel
// record, layer bits, 0), or record NO_TEXEL.
@compute @workgroup_size(64)
fn walk_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.rays) {
        return;
    }
    let ray = rays[i];
    let hit = walk_impostor(params.any_hit, ray.origin, ray.dir, ray.t_max);
    hits[i] = Hit(hit.t, hit.record, bitcast<f32>(hit.layer), 0.0);
}
