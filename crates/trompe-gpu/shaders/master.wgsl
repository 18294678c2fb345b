// Master textures as a projective-texturing source ("Master Texture" §4, the paper's rendering
// path; texturing.wgsl follows this file and blends): every view's master texture is a layer of
// one texture array, and every view answers at the one atlas point of the pixel's surface — one
// texture coordinate for all views.
//
// The CPU twin is src/master/render.rs: a view sees the point clearly where its master's
// nearest texel has alpha 1, at an edge where it has alpha between 0 and 1 (the encoder's
// EDGE_ALPHA), not at all where 0; its colour is a bilinear lookup over the texels that hold a
// colour (alpha > 0), the weights renormalized.

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

@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(3) var masters: texture_2d_array<f32>;

fn corners(face: u32) -> array<vec3<f32>, 3> {
    let f = faces[face];
    return array<vec3<f32>, 3>(f.c0.xyz, f.c1.xyz, f.c2.xyz);
}

// The atlas point of barycentrics `b` on face `face` (one texture coordinate for every view).
fn atlas_point(face: u32, b: vec3<f32>) -> vec2<f32> {
    let f = faces[face];
    return f.atlas0.xy + f.atlas0.zw * b.y + f.atlas1.xy * b.z;
}

fn texel(view: u32, at: At) -> vec3<f32> {
    return vec3<f32>(atlas_point(at.face, at.bary), 1.0);
}

fn sight(view: u32, at: At) -> u32 {
    let dims = vec2<f32>(textureDimensions(masters));
    let t = floor(atlas_point(at.face, at.bary));
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

// A point across the footprint may leave the triangle, and its texel the face's part of the
// atlas: it is looked up at the nearest point of the triangle (its barycentrics clamped).
fn lookup(view: u32, at: At) -> vec4<f32> {
    let dims = vec2<i32>(textureDimensions(masters));
    let b = max(at.bary, vec3<f32>(0.0));
    let f = atlas_point(at.face, b / (b.x + b.y + b.z)) - vec2<f32>(0.5);
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
