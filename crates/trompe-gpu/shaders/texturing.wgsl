// Projective texturing's blend (src/texturing/mod.rs, the renderer behind views, layers and
// master textures): the mesh's visibility buffer (raster.wgsl, triangles in mesh order) read one
// invocation a pixel; the views that see the pixel's surface weighted and their colours blended.
//
// A source's file goes before this one and gives what the blend asks of it:
// - `struct At`: a surface point as the source answers it;
// - `fn surface_at(face: u32, b1: f32, b2: f32) -> At` and `fn position(at: At) -> vec3<f32>`;
// - `fn sight(view: u32, at: At) -> u32`: 2 seen clearly, 1 at an edge, 0 not at all;
// - `fn lookup(view: u32, at: At) -> vec4<f32>`: the view's colour (w = 1), or w = 0 for none.
//
// The blend follows the CPU step by step:
// - the views that see the point clearly are weighted (ULR, VDTM, or the best-face table); only
//   where none does are the edge views weighted instead;
// - a view that gives no colour is dropped from the blend and the rest renormalized;
// - weights (src/texturing/weights.rs): penalties sorted with ties to the lower view index, a
//   view looking along the eye's ray exactly takes the point alone, ULR's threshold the
//   (k+1)-th penalty (or the worst one's × 1.001 when fewer views see it).
//
// A pixel's state says what it showed: 0 nothing, 1 a colour, 2 a hole (no view sees it).

struct Params {
    // xyz: the eye; w: ULR's β.
    eye: vec4<f32>,
    // Width, height, views, k.
    size: vec4<u32>,
    // x: the weighting (0 ULR, 1 VDTM, 2 best face, 3 view map); y: 1 where holes take `fill`;
    // z: the view map's sample directions a face.
    mode: vec4<u32>,
    // The colour of a hole under a fill policy.
    fill: vec4<f32>,
    // x: the visibility test's relative depth tolerance (sources that test depth).
    extra: vec4<f32>,
}

@group(0) @binding(0) var visibility: texture_2d<u32>;
@group(0) @binding(2) var<storage, read> centres: array<vec4<f32>>;
@group(0) @binding(4) var<uniform> params: Params;
// Per face, the best-face table's view + 1 (0: none); one entry when the weighting is per point.
@group(0) @binding(5) var<storage, read> best: array<u32>;
@group(0) @binding(6) var<storage, read_write> colour_out: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> state_out: array<u32>;
// The view map (src/texturing/view_map.rs): its unit sample directions, its spherical
// triangles (xyz: three directions), and per face and direction the view the sample holds, two
// 16-bit entries a word (0xffff: none). One entry each when the weighting is another.
@group(0) @binding(11) var<storage, read> map_directions: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> map_triangles: array<vec4<u32>>;
@group(0) @binding(13) var<storage, read> map_views: array<u32>;

// The most views a pixel blends (`K_MAX`, the render's k, at most 64) is set before this file
// (crates/trompe-gpu/src/texturing.rs `shader_source`), so a pixel's arrays are no longer than
// the blend needs.
// A penalty this small is a view looking along the eye's ray exactly.
const EXACT: f32 = 1e-9;

// Whether view `view` takes part in the pass that blends clear views (`clearly`) or edge views.
fn takes_part(view: u32, at: At, clearly: bool) -> bool {
    let s = sight(view, at);
    return s == 2u || (!clearly && s == 1u);
}

// The angle between two vectors, well conditioned near 0.
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// The blend of the views that take part in one pass, by the per-point weights; w = 0 when no
// view gives a colour.
fn blend_per_point(at: At, clearly: bool) -> vec4<f32> {
    let x = position(at);
    let v2 = x - params.eye.xyz;
    let k = min(params.size.w, K_MAX);
    let ulr = params.mode.x == 0u;
    // The k + 1 smallest penalties, sorted, ties to the lower index (a later view enters only
    // before a strictly larger penalty).
    var pen: array<f32, K_MAX + 1u>;
    var idx: array<u32, K_MAX + 1u>;
    var n = 0u;
    var worst = 0.0;
    for (var i = 0u; i < params.size.z; i++) {
        if (!takes_part(i, at, clearly)) {
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
        return lookup(idx[0], at);
    }
    let taken = min(n, k);
    var threshold = worst * (1.0 + 1e-3);
    if (n > k) {
        threshold = pen[k];
    }
    var raw: array<f32, K_MAX>;
    var total = 0.0;
    for (var j = 0u; j < taken; j++) {
        var w = 1.0 / pen[j];
        if (ulr) {
            w = max(1.0 - pen[j] / threshold, 0.0);
        }
        raw[j] = w;
        total += w;
    }
    if (!(total > 0.0)) {
        return lookup(idx[0], at);
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
        let c = lookup(idx[j], at);
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

// The view sample `sample` of face `face`'s view map holds (0xffff: none).
fn map_view(face: u32, sample: u32) -> u32 {
    let i = face * params.mode.z + sample;
    return (map_views[i / 2u] >> (16u * (i % 2u))) & 0xffffu;
}

// The view-map blend of the views that take part in one pass: the (at most three) views of
// the spherical triangle the direction to the eye falls in, by its barycentric coordinates,
// those that take part renormalized; w = 0 when none gives a colour.
fn blend_view_map(at: At, face: u32, clearly: bool) -> vec4<f32> {
    let omega = normalize(params.eye.xyz - position(at));
    var views: array<u32, 3>;
    var weights: array<f32, 3>;
    var n = 0u;
    for (var f = 0u; f < arrayLength(&map_triangles); f++) {
        let tri = map_triangles[f];
        let a = map_directions[tri.x].xyz;
        let b = map_directions[tri.y].xyz;
        let c = map_directions[tri.z].xyz;
        let w = vec3<f32>(dot(omega, cross(b, c)), dot(omega, cross(c, a)), dot(omega, cross(a, b)));
        let total = w.x + w.y + w.z;
        let inside = all(w >= vec3<f32>(0.0)) || all(w <= vec3<f32>(0.0));
        if (!inside || total == 0.0 || dot(omega, a + b + c) <= 0.0) {
            continue;
        }
        let corners = vec3<u32>(tri.x, tri.y, tri.z);
        for (var k = 0u; k < 3u; k++) {
            let v = map_view(face, corners[k]);
            let weight = w[k] / total;
            if (v == 0xffffu || weight <= 0.0) {
                continue;
            }
            var merged = false;
            for (var e = 0u; e < n; e++) {
                if (views[e] == v) {
                    weights[e] += weight;
                    merged = true;
                }
            }
            if (!merged) {
                views[n] = v;
                weights[n] = weight;
                n += 1u;
            }
        }
        break;
    }
    // The views that take part, renormalized; a view with no colour dropped as in the blend.
    var kept_weight = 0.0;
    for (var e = 0u; e < n; e++) {
        if (!takes_part(views[e], at, clearly)) {
            weights[e] = 0.0;
        }
        kept_weight += weights[e];
    }
    if (kept_weight <= 0.0) {
        return vec4<f32>(0.0);
    }
    var sum = vec3<f32>(0.0);
    var kept = 0.0;
    var dropped = false;
    for (var e = 0u; e < n; e++) {
        if (weights[e] <= 0.0) {
            continue;
        }
        let w = weights[e] / kept_weight;
        let c = lookup(views[e], at);
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
fn blend_views(@builtin(global_invocation_id) id: vec3<u32>) {
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
    let at = surface_at(v.x - 1u, bitcast<f32>(v.y), bitcast<f32>(v.z));
    var c = vec4<f32>(0.0);
    for (var round = 0u; round < 2u; round++) {
        let clearly = round == 0u;
        if (params.mode.x == 2u) {
            // The table's view alone, where it takes part in this pass.
            let entry = best[v.x - 1u];
            if (entry > 0u && takes_part(entry - 1u, at, clearly)) {
                c = lookup(entry - 1u, at);
            }
        } else if (params.mode.x == 3u) {
            c = blend_view_map(at, v.x - 1u, clearly);
        } else {
            c = blend_per_point(at, clearly);
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
