// Rendering from master textures ("Master Texture" §4): the mesh's visibility buffer
// (raster.wgsl, triangles in mesh order) read one invocation a pixel; every view's master
// texture is a layer of one texture array, and every view answers at the one atlas point of the
// pixel's surface — one texture coordinate for all views, as the paper renders.
//
// The CPU twin is src/texturing/mod.rs over src/master/render.rs's source; this shader follows it
// step by step:
// - a view sees the point clearly where its master's nearest texel has alpha 1, at an edge where
//   it has alpha between 0 and 1 (the encoder's EDGE_ALPHA), not at all where 0;
// - the views that see the point clearly are weighted (ULR, VDTM, or the best-face table); only
//   where none does are the edge views weighted instead;
// - a view's colour is a bilinear lookup over the texels that hold a colour (alpha > 0), the
//   weights renormalized; a view with none is dropped from the blend and the rest renormalized;
// - weights (src/texturing/weights.rs): penalties sorted with ties to the lower view index, a
//   view looking along the eye's ray exactly takes the point alone, ULR's threshold the
//   (k+1)-th penalty (or the worst one's × 1.001 when fewer views see it).
//
// A pixel's state says what it showed: 0 nothing, 1 a colour, 2 a hole (no view sees it).

struct Face {
    // The triangle's corners (xyz).
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
    // xy: the atlas point of corner 0; zw: the atlas step to corner 1.
    atlas0: vec4<f32>,
    // xy: the atlas step to corner 2.
    atlas1: vec4<f32>,
}

struct Params {
    // xyz: the eye; w: ULR's β.
    eye: vec4<f32>,
    // Width, height, views, k.
    size: vec4<u32>,
    // x: the weighting (0 ULR, 1 VDTM, 2 best face); y: 1 where holes take `fill`.
    mode: vec4<u32>,
    // The colour of a hole under a fill policy.
    fill: vec4<f32>,
}

@group(0) @binding(0) var visibility: texture_2d<u32>;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read> centres: array<vec4<f32>>;
@group(0) @binding(3) var masters: texture_2d_array<f32>;
@group(0) @binding(4) var<uniform> params: Params;
// Per face, the best-face table's view + 1 (0: none); one entry when the weighting is per point.
@group(0) @binding(5) var<storage, read> best: array<u32>;
@group(0) @binding(6) var<storage, read_write> colour_out: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> state_out: array<u32>;

// The most views a pixel blends, and one more for ULR's threshold.
const K_MAX: u32 = 64u;
// A penalty this small is a view looking along the eye's ray exactly.
const EXACT: f32 = 1e-9;

// How view `view` sees atlas point `p`: 2 clearly, 1 at an edge, 0 not at all.
fn sight(view: u32, p: vec2<f32>) -> u32 {
    let dims = vec2<f32>(textureDimensions(masters));
    let t = floor(p);
    if (!(t.x >= 0.0 && t.y >= 0.0 && t.x < dims.x && t.y < dims.y)) {
        return 0u;
    }
    let a = textureLoad(masters, vec2<i32>(t), i32(view), 0).w;
    if (a >= 1.0) {
        return 2u;
    }
    if (a > 0.0) {
        return 1u;
    }
    return 0u;
}

// Whether view `view` takes part in the pass that blends clear views (`clearly`) or edge views.
fn takes_part(view: u32, p: vec2<f32>, clearly: bool) -> bool {
    let s = sight(view, p);
    return s == 2u || (!clearly && s == 1u);
}

// View `view`'s colour at atlas point `p`: bilinear over the texels with alpha; w = 0 when none.
fn lookup(view: u32, p: vec2<f32>) -> vec4<f32> {
    let dims = vec2<i32>(textureDimensions(masters));
    let f = p - vec2<f32>(0.5);
    let base = floor(f);
    let t = f - base;
    let origin = vec2<i32>(base);
    var sum = vec4<f32>(0.0);
    var weight = 0.0;
    for (var k = 0; k < 4; k++) {
        let d = vec2<i32>(k & 1, k >> 1u);
        let w = select(1.0 - t.x, t.x, d.x == 1) * select(1.0 - t.y, t.y, d.y == 1);
        let q = origin + d;
        if (w <= 0.0 || q.x < 0 || q.y < 0 || q.x >= dims.x || q.y >= dims.y) {
            continue;
        }
        let c = textureLoad(masters, q, i32(view), 0);
        if (c.w > 0.0) {
            sum += c * w;
            weight += w;
        }
    }
    if (weight > 0.0) {
        return vec4<f32>((sum / weight).xyz, 1.0);
    }
    return vec4<f32>(0.0);
}

// The angle between two vectors, well conditioned near 0.
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// The blend of the views that take part in one pass, by the per-point weights; w = 0 when no
// view gives a colour.
fn blend_per_point(x: vec3<f32>, p: vec2<f32>, clearly: bool) -> vec4<f32> {
    let eye = params.eye.xyz;
    let v2 = x - eye;
    let k = min(params.size.w, K_MAX);
    let ulr = params.mode.x == 0u;
    // The k + 1 smallest penalties, sorted, ties to the lower index (a later view enters only
    // before a strictly larger penalty).
    var pen: array<f32, 65>;
    var idx: array<u32, 65>;
    var n = 0u;
    var worst = 0.0;
    for (var i = 0u; i < params.size.z; i++) {
        if (!takes_part(i, p, clearly)) {
            continue;
        }
        let v1 = x - centres[i].xyz;
        var penalty = angle_between(v1, v2);
        if (ulr) {
            let l1 = length(v1);
            penalty += params.eye.w * max((l1 - length(v2)) / l1, 0.0);
        }
        worst = max(worst, penalty);
        var slot = min(n, k + 1u);
        while (slot > 0u && penalty < pen[slot - 1u]) {
            if (slot <= k) {
                pen[slot] = pen[slot - 1u];
                idx[slot] = idx[slot - 1u];
            }
            slot -= 1u;
        }
        if (slot <= k) {
            pen[slot] = penalty;
            idx[slot] = i;
        }
        n += 1u;
    }
    if (n == 0u || k == 0u) {
        return vec4<f32>(0.0);
    }
    if (pen[0] <= EXACT) {
        return lookup(idx[0], p);
    }
    let taken = min(n, k);
    var threshold = worst * (1.0 + 1e-3);
    if (n > k) {
        threshold = pen[k];
    }
    var raw: array<f32, 64>;
    var total = 0.0;
    for (var j = 0u; j < taken; j++) {
        var w = 1.0 / pen[j];
        if (ulr) {
            w = max(1.0 - pen[j] / threshold, 0.0);
        }
        raw[j] = w;
        total += w;
    }
    if (!(total > 0.0) || total != total) {
        return lookup(idx[0], p);
    }
    // The weighted colours; a view with none is dropped and the others renormalized.
    var sum = vec3<f32>(0.0);
    var kept = 0.0;
    var dropped = false;
    for (var j = 0u; j < taken; j++) {
        let w = raw[j] / total;
        if (w <= 0.0) {
            continue;
        }
        let c = lookup(idx[j], p);
        if (c.w > 0.0) {
            sum += c.xyz * w;
            kept += w;
        } else {
            dropped = true;
        }
    }
    if (kept <= 0.0) {
        return vec4<f32>(0.0);
    }
    if (dropped) {
        return vec4<f32>(sum / kept, 1.0);
    }
    return vec4<f32>(sum, 1.0);
}

@compute @workgroup_size(8, 8)
fn render_masters(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.size.x;
    if (id.x >= w || id.y >= params.size.y) {
        return;
    }
    let i = id.y * w + id.x;
    let v = textureLoad(visibility, vec2<i32>(id.xy), 0);
    if (v.x == 0u) {
        colour_out[i] = vec4<f32>(0.0);
        state_out[i] = 0u;
        return;
    }
    let face = faces[v.x - 1u];
    let b1 = bitcast<f32>(v.y);
    let b2 = bitcast<f32>(v.z);
    let b0 = 1.0 - b1 - b2;
    let x = face.c0.xyz * b0 + face.c1.xyz * b1 + face.c2.xyz * b2;
    let p = face.atlas0.xy + face.atlas0.zw * b1 + face.atlas1.xy * b2;
    var c = vec4<f32>(0.0);
    for (var round = 0u; round < 2u; round++) {
        let clearly = round == 0u;
        if (params.mode.x == 2u) {
            // The table's view alone, where it takes part in this pass.
            let entry = best[v.x - 1u];
            if (entry > 0u && takes_part(entry - 1u, p, clearly)) {
                c = lookup(entry - 1u, p);
            }
        } else {
            c = blend_per_point(x, p, clearly);
        }
        if (c.w > 0.0) {
            break;
        }
    }
    if (c.w > 0.0) {
        colour_out[i] = c;
        state_out[i] = 1u;
    } else {
        colour_out[i] = select(vec4<f32>(0.0), params.fill, params.mode.y == 1u);
        state_out[i] = 2u;
    }
}
