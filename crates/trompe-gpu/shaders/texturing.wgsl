// Projective texturing's blend (src/texturing/mod.rs, the renderer behind views, layers and
// master textures): the mesh's visibility buffer (raster.wgsl, triangles in mesh order) read one
// invocation a pixel; the views that see the pixel's surface weighted and their colours blended.
//
// A source's file goes before this one and gives what the blend asks of it, of a surface point
// `At` (below):
// - `fn corners(face: u32) -> array<vec3<f32>, 3>`: the face's triangle;
// - `fn sight(view: u32, at: At) -> u32`: 2 seen clearly, 1 at an edge, 0 not at all;
// - `fn lookup(view: u32, at: At) -> vec4<f32>`: the view's colour (w = 1), or w = 0 for none;
// - `fn texel(view: u32, at: At) -> vec3<f32>`: where the point lands in the image the view
//   samples (xy; z = 0 where it lands nowhere), for the prefilter.
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
    // The camera's McMillan vectors: pixel (u, v) looks along a·u + b·v + c.
    cam_a: vec4<f32>,
    cam_b: vec4<f32>,
    cam_c: vec4<f32>,
    // Width, height, views, k.
    size: vec4<u32>,
    // x: the weighting (0 ULR, 1 VDTM, 2 best face, 3 view map); y: 1 where holes take `fill`;
    // z: the view map's sample directions a face; w: 1 where each view's image is prefiltered
    // to the pixel's footprint.
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

// A point of a rendered surface (src/texturing/mod.rs `SurfacePoint`): its face, barycentrics
// and world position, and the pixel's footprint on the face's plane — the world and barycentric
// steps to the next pixel right and down (zero where not prefiltered, or seen edge-on).
struct At {
    face: u32,
    bary: vec3<f32>,
    x: vec3<f32>,
    dx: vec3<f32>,
    dy: vec3<f32>,
    dbx: vec3<f32>,
    dby: vec3<f32>,
}

fn position(at: At) -> vec3<f32> {
    return at.x;
}

// The point `(s, t)` pixel steps from `at` along its footprint (it may leave the triangle).
fn offset(at: At, s: f32, t: f32) -> At {
    let zero = vec3<f32>(0.0);
    let bary = at.bary + at.dbx * s + at.dby * t;
    return At(at.face, bary, at.x + at.dx * s + at.dy * t, zero, zero, zero, zero);
}

// The change of barycentric coordinates on triangle `c` along the in-plane step `d`.
fn bary_step(c: array<vec3<f32>, 3>, d: vec3<f32>) -> vec3<f32> {
    let e1 = c[1] - c[0];
    let e2 = c[2] - c[0];
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let d20 = dot(d, e1);
    let d21 = dot(d, e2);
    let det = d00 * d11 - d01 * d01;
    if (det == 0.0) {
        return vec3<f32>(0.0);
    }
    let b = (d11 * d20 - d01 * d21) / det;
    let g = (d00 * d21 - d01 * d20) / det;
    return vec3<f32>(-(b + g), b, g);
}

// The surface point of pixel `pixel` on face `face` at barycentrics (1 − b1 − b2, b1, b2), with
// the pixel's footprint when prefiltering: the steps to where the rays of the next pixel's
// centre right and down meet the face's plane (zero where the plane is seen edge-on).
fn surface_at(pixel: vec2<u32>, face: u32, b1: f32, b2: f32) -> At {
    let c = corners(face);
    let bary = vec3<f32>(1.0 - b1 - b2, b1, b2);
    let x = c[0] * bary.x + c[1] * bary.y + c[2] * bary.z;
    var at = At(face, bary, x, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    if (params.mode.w == 0u) {
        return at;
    }
    let eye = params.eye.xyz;
    let n = cross(c[1] - c[0], c[2] - c[0]);
    let along = dot(n, x - eye);
    let centre = vec2<f32>(pixel) + vec2<f32>(0.5);
    var steps: array<vec3<f32>, 2>;
    for (var k = 0u; k < 2u; k++) {
        let uv = centre + select(vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), k == 0u);
        let ray = params.cam_a.xyz * uv.x + params.cam_b.xyz * uv.y + params.cam_c.xyz;
        let t = along / dot(n, ray);
        let q = eye + ray * t;
        // Finite and in front: `t == t` and `abs(t) < 3e38` refuse NaN and infinity.
        if (!(t > 0.0 && abs(t) < 3e38 && all(abs(q) < vec3<f32>(3e38)))) {
            return at;
        }
        steps[k] = q - x;
    }
    at.dx = steps[0];
    at.dy = steps[1];
    at.dbx = bary_step(c, steps[0]);
    at.dby = bary_step(c, steps[1]);
    return at;
}

// Most lookups along each side of a pixel's footprint (src/texturing/mod.rs MAX_FOOTPRINT_TAPS).
const MAX_FOOTPRINT_TAPS: u32 = 8u;

// View `view`'s colour at `at`: prefiltered to the pixel's footprint where it spans two or more
// of the image's texels (the mean of n × n lookups across it, n the footprint's longer side in
// texels, at most MAX_FOOTPRINT_TAPS; `at`'s own lookup where none gives a colour), one lookup
// otherwise (src/texturing/mod.rs `prefiltered`).
fn colour(view: u32, at: At) -> vec4<f32> {
    // The taps across the footprint: n × n of them where it spans n ≥ 2 texels, else none.
    var n = 0u;
    let p = texel(view, at);
    if (params.mode.w != 0u && p.z != 0.0) {
        var texels = 0.0;
        for (var k = 0u; k < 2u; k++) {
            let q = texel(view, offset(at, select(0.0, 1.0, k == 0u), select(1.0, 0.0, k == 0u)));
            if (q.z != 0.0) {
                texels = max(texels, length(q.xy - p.xy));
            }
        }
        if (texels >= 2.0 && texels < 3e38) {
            n = min(u32(floor(texels)), MAX_FOOTPRINT_TAPS);
        }
    }
    // One lookup a tap, then `at`'s own where no tap gave a colour (the only one without taps):
    // a single place that looks up, so the shader holds one copy of the source's lookup.
    let taps = n * n;
    var sum = vec4<f32>(0.0);
    var count = 0u;
    for (var k = 0u; k <= taps; k++) {
        if (k == taps && count > 0u) {
            break;
        }
        var q = at;
        if (k < taps) {
            let s = (f32(k % n) + 0.5) / f32(n) - 0.5;
            let t = (f32(k / n) + 0.5) / f32(n) - 0.5;
            q = offset(at, s, t);
        }
        let c = lookup(view, q);
        if (k == taps) {
            return c;
        }
        if (c.w > 0.0) {
            sum += c;
            count += 1u;
        }
    }
    return vec4<f32>((sum / f32(count)).xyz, 1.0);
}

// Whether view `view` takes part in the pass that blends clear views (`clearly`) or edge views.
fn takes_part(view: u32, at: At, clearly: bool) -> bool {
    let s = sight(view, at);
    return s == 2u || (!clearly && s == 1u);
}

// The angle between two vectors, well conditioned near 0.
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// The views a blend weighs and their weights, chosen by one weighting for one pass
// (`choose_per_point`, `choose_view_map`, the best-face table) and blended by `blend_chosen`.
var<private> chosen_views: array<u32, BLEND_MAX>;
var<private> chosen_weights: array<f32, BLEND_MAX>;

// The per-point weights of the views that take part in one pass, into `chosen_*`: how many.
fn choose_per_point(at: At, clearly: bool) -> u32 {
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
        return 0u;
    }
    // A view looking along the eye's ray exactly takes the point alone.
    chosen_views[0] = idx[0];
    chosen_weights[0] = 1.0;
    if (pen[0] <= EXACT) {
        return 1u;
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
    // Weights that do not sum to a positive number: the best view alone (chosen above).
    if (!(total > 0.0)) {
        return 1u;
    }
    for (var j = 0u; j < taken; j++) {
        chosen_views[j] = idx[j];
        chosen_weights[j] = raw[j] / total;
    }
    return taken;
}

// The most views one blend weighs: the per-point weightings' k, or the view map's three.
const BLEND_MAX: u32 = max(K_MAX, 3u);

// The colours the chosen views `chosen_views[0..n]` give `at`, weighted by `chosen_weights` (a
// view of weight 0 left out): a view that gives none is dropped and the others renormalized
// (src/texturing/mod.rs `blend`); w = 0 when none gives a colour. The shader's one call of it
// holds its one copy of `colour`.
fn blend_chosen(n: u32, at: At) -> vec4<f32> {
    var sum = vec3<f32>(0.0);
    var kept = 0.0;
    var dropped = false;
    for (var j = 0u; j < n; j++) {
        let w = chosen_weights[j];
        if (w <= 0.0) {
            continue;
        }
        let c = colour(chosen_views[j], at);
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

// The view-map weights of the views that take part in one pass, into `chosen_*`: the (at most
// three) views of the spherical triangle the direction to the eye falls in, by its barycentric
// coordinates, those that take part renormalized; how many.
fn choose_view_map(at: At, face: u32, clearly: bool) -> u32 {
    let omega = normalize(params.eye.xyz - position(at));
    var views: array<u32, BLEND_MAX>;
    var weights: array<f32, BLEND_MAX>;
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
    // The views that take part, renormalized.
    var kept_weight = 0.0;
    for (var e = 0u; e < n; e++) {
        if (!takes_part(views[e], at, clearly)) {
            weights[e] = 0.0;
        }
        kept_weight += weights[e];
    }
    if (kept_weight <= 0.0) {
        return 0u;
    }
    for (var e = 0u; e < n; e++) {
        chosen_views[e] = views[e];
        chosen_weights[e] = weights[e] / kept_weight;
    }
    return n;
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
    let at = surface_at(id.xy, v.x - 1u, bitcast<f32>(v.y), bitcast<f32>(v.z));
    var c = vec4<f32>(0.0);
    for (var round = 0u; round < 2u; round++) {
        let clearly = round == 0u;
        var n = 0u;
        if (params.mode.x == 2u) {
            // The table's view alone, where it takes part in this pass.
            let entry = best[v.x - 1u];
            if (entry > 0u && takes_part(entry - 1u, at, clearly)) {
                chosen_views[0] = entry - 1u;
                chosen_weights[0] = 1.0;
                n = 1u;
            }
        } else if (params.mode.x == 3u) {
            n = choose_view_map(at, v.x - 1u, clearly);
        } else {
            n = choose_per_point(at, clearly);
        }
        c = blend_chosen(n, at);
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
