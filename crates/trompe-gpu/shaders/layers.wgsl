// Image layers as a projective-texturing source ("Layered view-dependent projective textures"
// §5; depth_images.wgsl goes before this file, texturing.wgsl after it): every object textured
// through the image layer that holds its triangle in each view, each through its layer's
// asymmetric sub-frustum (its texture matrix). Every layer's image is a layer of one texture
// array and its depth the same layer of another, each padded to the largest layer.
//
// The CPU twin is src/layers/render.rs: a view sees a point clearly where its layer's bilinear
// lookup over the texels it holds (alpha ≥ ½) at the point's depth (within the tolerance) has
// a tap; at an edge where the depth rule over the texels it holds says so and its edge lookup
// (texels it holds on the point's surface, within SAME_SURFACE, bilinear, else the nearest of
// the 3 × 3) finds one; its colour is the first lookup, else the edge lookup.

struct Layer {
    // The rows of its texture matrix (Bias · Frustum(layer window) · View).
    m0: vec4<f32>,
    m1: vec4<f32>,
    m2: vec4<f32>,
    m3: vec4<f32>,
    // Its width and height in texels.
    size: vec4<f32>,
}

@group(0) @binding(8) var<storage, read> layers: array<Layer>;
// Per view and face (view × faces + face): the layer (index into `layers`) + 1 that holds the
// face in that view, 0 where none does.
@group(0) @binding(10) var<storage, read> holders: array<u32>;

// src/views/blend.rs's SAME_SURFACE.
const SAME_SURFACE: f32 = 0.05;

// Where `at` lands in the layer of `view` that holds it: xy the texel point, z the eye depth,
// w the layer + 1 (0: no layer holds it, or it is behind the view).
fn layer_texel(view: u32, at: At) -> vec4<f32> {
    let holder = holders[view * arrayLength(&faces) + at.face];
    if (holder == 0u) {
        return vec4<f32>(0.0);
    }
    let l = layers[holder - 1u];
    let p = vec4<f32>(at.x, 1.0);
    let q = vec4<f32>(dot(l.m0, p), dot(l.m1, p), dot(l.m2, p), dot(l.m3, p));
    if (q.w <= 1e-12) {
        return vec4<f32>(0.0);
    }
    let st = q.xy / q.w;
    return vec4<f32>(st.x * l.size.x, (1.0 - st.y) * l.size.y, q.w, f32(holder));
}

fn depth_image(holder: u32) -> DepthImage {
    return DepthImage(i32(holder - 1u), layers[holder - 1u].size.xy, true);
}

// The layer's colour at the point's texel: on its surface within the tolerance, else its edge
// lookup; w = 0 for none.
fn layer_colour(d: DepthImage, t: vec4<f32>, edge_only: bool) -> vec4<f32> {
    if (!edge_only) {
        let on = bilinear_on_surface(d, t.xy, t.z, params.extra.x);
        if (on.w > 0.0) {
            return on;
        }
    }
    let edge = bilinear_on_surface(d, t.xy, t.z, SAME_SURFACE);
    if (edge.w > 0.0) {
        return edge;
    }
    return nearest_on_surface(d, t.xy, t.z, SAME_SURFACE);
}

fn sight(view: u32, at: At) -> u32 {
    let t = layer_texel(view, at);
    if (t.w == 0.0) {
        return 0u;
    }
    let d = depth_image(u32(t.w));
    if (bilinear_on_surface(d, t.xy, t.z, params.extra.x).w > 0.0) {
        return 2u;
    }
    if (sight_rule(d, t.xy, t.z, params.extra.x) != 0u && layer_colour(d, t, true).w > 0.0) {
        return 1u;
    }
    return 0u;
}

fn texel(view: u32, at: At) -> vec3<f32> {
    let t = layer_texel(view, at);
    return vec3<f32>(t.xy, select(0.0, 1.0, t.w > 0.0));
}

fn lookup(view: u32, at: At) -> vec4<f32> {
    let t = layer_texel(view, at);
    if (t.w == 0.0) {
        return vec4<f32>(0.0);
    }
    return layer_colour(depth_image(u32(t.w)), t, false);
}
