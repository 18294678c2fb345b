// Images with depth, as the sources that keep to a surface read them (views.wgsl, layers.wgsl;
// this file goes before the source's own): colour images in one texture array, their
// generalized depth (1/z, 0 where nothing was seen) in another, layer for layer; and the
// mesh's triangles those sources share.
//
// The CPU's rules, in f32: src/views/visibility.rs (`sight_in`: seen, at an edge, hidden) and
// the lookups that keep to a surface (src/views/blend.rs `sample_on_surface` and
// `nearest_where`, src/layers/render.rs `sample_layer` and `edge_colour`).

@group(0) @binding(3) var images: texture_2d_array<f32>;
@group(0) @binding(9) var depths: texture_2d_array<f32>;

// The mesh's triangles, as the sources that read images with depth keep them.
struct Face {
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> faces: array<Face>;

fn corners(face: u32) -> array<vec3<f32>, 3> {
    let f = faces[face];
    return array<vec3<f32>, 3>(f.c0.xyz, f.c1.xyz, f.c2.xyz);
}

// One image with depth: its layer, its size in texels, and whether a texel counts only where
// the image holds it (alpha ≥ ½: an image layer's texels).
struct DepthImage {
    layer: i32,
    size: vec2<f32>,
    alpha_gated: bool,
}

// The generalized depth `d` holds at texel `q`: 0 beyond its size, where it saw nothing, or
// (alpha-gated) where the image does not hold the texel.
fn known_gd(d: DepthImage, q: vec2<i32>) -> f32 {
    if (q.x < 0 || q.y < 0 || f32(q.x) >= d.size.x || f32(q.y) >= d.size.y) {
        return 0.0;
    }
    if (d.alpha_gated && textureLoad(images, q, d.layer, 0).w < 0.5) {
        return 0.0;
    }
    return textureLoad(depths, q, d.layer, 0).x;
}

// Whether texel `q` of `d` is the surface at depth `z`, within `tolerance` relative to `z`.
fn on_surface_at(d: DepthImage, q: vec2<i32>, z: f32, tolerance: f32) -> bool {
    let g = known_gd(d, q);
    return g > 0.0 && abs(1.0 / g - z) <= tolerance * z;
}

// How `d` sees a point of depth `z` at texel point `uv`: 2 seen (the texel under it does not
// hide it by more than `tolerance`), 1 at an edge (not behind all four texels of its bilinear
// footprint, an empty one being infinitely far but one at least not empty, by more than the
// tolerance plus half their depth range), 0 hidden.
fn sight_rule(d: DepthImage, uv: vec2<f32>, z: f32, tolerance: f32) -> u32 {
    let size = d.size;
    if (!(uv.x > -1.0 && uv.y > -1.0 && uv.x < size.x + 1.0 && uv.y < size.y + 1.0)) {
        return 0u;
    }
    if (uv.x >= 0.0 && uv.y >= 0.0 && uv.x < size.x && uv.y < size.y) {
        let stored = known_gd(d, vec2<i32>(floor(uv)));
        if (stored > 0.0 && z <= (1.0 / stored) * (1.0 + tolerance)) {
            return 2u;
        }
    }
    let f = uv - vec2<f32>(0.5);
    let base = floor(f);
    let t = f - base;
    let origin = vec2<i32>(base);
    var nearest = 0.0;
    var farthest = 0.0;
    var seen_any = false;
    var empty_any = false;
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let weight = select(1.0 - t.x, t.x, o.x == 1) * select(1.0 - t.y, t.y, o.y == 1);
        if (weight <= 0.0) {
            continue;
        }
        let g = known_gd(d, origin + o);
        if (g > 0.0) {
            let depth = 1.0 / g;
            nearest = select(depth, min(nearest, depth), seen_any);
            farthest = select(depth, max(farthest, depth), seen_any);
            seen_any = true;
        } else {
            empty_any = true;
        }
    }
    if (seen_any && (empty_any || z <= farthest * (1.0 + tolerance) + 0.5 * (farthest - nearest))) {
        return 1u;
    }
    return 0u;
}

// A bilinear lookup of `d`'s image at texel point `px` over the taps that are the surface at
// depth `z` (within `tolerance`), their weights renormalized; w = 0 when no tap is.
fn bilinear_on_surface(d: DepthImage, px: vec2<f32>, z: f32, tolerance: f32) -> vec4<f32> {
    let f = px - vec2<f32>(0.5);
    let base = floor(f);
    let t = f - base;
    let origin = vec2<i32>(base);
    var sum = vec4<f32>(0.0);
    var weight = 0.0;
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let w = select(1.0 - t.x, t.x, o.x == 1) * select(1.0 - t.y, t.y, o.y == 1);
        let q = origin + o;
        if (w <= 0.0 || !on_surface_at(d, q, z, tolerance)) {
            continue;
        }
        sum += textureLoad(images, q, d.layer, 0) * w;
        weight += w;
    }
    if (weight > 0.0) {
        return vec4<f32>((sum / weight).xyz, 1.0);
    }
    return vec4<f32>(0.0);
}

// The colour of the texel nearest `px`, among the 3 × 3 around the texel under it, that is the
// surface at depth `z` (within `tolerance`), ties to the first in row order; w = 0 for none.
fn nearest_on_surface(d: DepthImage, px: vec2<f32>, z: f32, tolerance: f32) -> vec4<f32> {
    let size = d.size;
    if (!(px.x > -2.0 && px.y > -2.0 && px.x < size.x + 2.0 && px.y < size.y + 2.0)) {
        return vec4<f32>(0.0);
    }
    let c = vec2<i32>(floor(px));
    var best = -1.0;
    var colour = vec4<f32>(0.0);
    for (var y = c.y - 1; y <= c.y + 1; y++) {
        for (var x = c.x - 1; x <= c.x + 1; x++) {
            let q = vec2<i32>(x, y);
            if (!on_surface_at(d, q, z, tolerance)) {
                continue;
            }
            let e = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) - px;
            let dist = dot(e, e);
            if (best < 0.0 || dist < best) {
                best = dist;
                colour = vec4<f32>(textureLoad(images, q, d.layer, 0).xyz, 1.0);
            }
        }
    }
    return colour;
}
