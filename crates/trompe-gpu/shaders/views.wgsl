// Calibrated views as a projective-texturing source (view-dependent texture mapping from
// photographs with depth maps; texturing.wgsl follows this file and blends): every view's image
// is a layer of one texture array and its depth map a layer of another, each padded to the
// largest view.
//
// The CPU twin is src/views/blend.rs with src/views/visibility.rs:
// - a view sees a point clearly where the depth map's texel under it does not hide it (the
//   point at most a relative tolerance behind the stored surface); at an edge where it is not
//   behind all four texels of its bilinear footprint (an empty texel, or one beyond the image,
//   being infinitely far, but one at least not empty) by more than the tolerance plus half
//   their depth range;
// - a view's colour is a bilinear lookup over the texels whose depth says they are the point's
//   surface (within SAME_SURFACE); failing that, the nearest such texel of the 3 × 3 around it;
//   failing that, the nearest texel, clamped.

struct Face {
    // The triangle's corners (xyz).
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
}

struct View {
    // The depth map's pinhole: the rows of M⁻¹ (applied to a point less `depth_eye`).
    depth_u: vec4<f32>,
    depth_v: vec4<f32>,
    depth_t: vec4<f32>,
    // xyz: the depth map's centre; w: 1 where the view takes part (an image, not left out).
    depth_eye: vec4<f32>,
    // The view's rotation, world to camera, by rows; and its centre (xyz).
    rot0: vec4<f32>,
    rot1: vec4<f32>,
    rot2: vec4<f32>,
    centre: vec4<f32>,
    // fx, fy, cx, cy.
    intrinsics: vec4<f32>,
    // The image's width and height, then the depth map's.
    size: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(3) var images: texture_2d_array<f32>;
@group(0) @binding(8) var<storage, read> views: array<View>;
@group(0) @binding(9) var depths: texture_2d_array<f32>;

// How far (relative depth) a texel's surface may be from the sampled point and still be the
// same surface (src/views/blend.rs's SAME_SURFACE).
const SAME_SURFACE: f32 = 0.05;

struct At {
    x: vec3<f32>,
}

fn surface_at(face: u32, b1: f32, b2: f32) -> At {
    let f = faces[face];
    return At(f.c0.xyz * (1.0 - b1 - b2) + f.c1.xyz * b1 + f.c2.xyz * b2);
}

fn position(at: At) -> vec3<f32> {
    return at.x;
}

// The depth map's generalized depth at texel `q` of view `view`, 0 beyond its size.
fn stored_gd(view: u32, q: vec2<i32>) -> f32 {
    let size = views[view].size.zw;
    if (q.x < 0 || q.y < 0 || f32(q.x) >= size.x || f32(q.y) >= size.y) {
        return 0.0;
    }
    return textureLoad(depths, q, i32(view), 0).x;
}

fn sight(view: u32, at: At) -> u32 {
    let v = views[view];
    if (v.depth_eye.w == 0.0) {
        return 0u;
    }
    let r = at.x - v.depth_eye.xyz;
    let w = vec3<f32>(dot(v.depth_u.xyz, r), dot(v.depth_v.xyz, r), dot(v.depth_t.xyz, r));
    if (w.z <= 0.0) {
        return 0u;
    }
    let uv = w.xy / w.z;
    let z = w.z;
    let size = v.size.zw;
    let tolerance = params.extra.x;
    let near_image = uv.x > -1.0 && uv.y > -1.0 && uv.x < size.x + 1.0 && uv.y < size.y + 1.0;
    if (!near_image) {
        return 0u;
    }
    if (uv.x >= 0.0 && uv.y >= 0.0 && uv.x < size.x && uv.y < size.y) {
        let stored = stored_gd(view, vec2<i32>(floor(uv)));
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
        let d = vec2<i32>(k & 1, k >> 1u);
        let weight = select(1.0 - t.x, t.x, d.x == 1) * select(1.0 - t.y, t.y, d.y == 1);
        if (weight <= 0.0) {
            continue;
        }
        let g = stored_gd(view, origin + d);
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

// Whether the stored generalized depth `g` is the surface at depth `z`.
fn on_surface(g: f32, z: f32) -> bool {
    return g > 0.0 && abs(1.0 / g - z) <= SAME_SURFACE * z;
}

fn lookup(view: u32, at: At) -> vec4<f32> {
    let v = views[view];
    let r = at.x - v.centre.xyz;
    let p = vec3<f32>(dot(v.rot0.xyz, r), dot(v.rot1.xyz, r), dot(v.rot2.xyz, r));
    if (p.z <= 1e-9) {
        return vec4<f32>(0.0);
    }
    let px = v.intrinsics.xy * (p.xy / p.z) + v.intrinsics.zw;
    let z = p.z;
    let size = v.size.xy;
    let dims = vec2<i32>(size);
    // Bilinear over the texels on the point's surface.
    let f = px - vec2<f32>(0.5);
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
        if (on_surface(stored_gd(view, q), z)) {
            sum += textureLoad(images, q, i32(view), 0) * w;
            weight += w;
        }
    }
    if (weight > 0.0) {
        return vec4<f32>((sum / weight).xyz, 1.0);
    }
    // The nearest texel on the surface of the 3 × 3 around the point, ties to the first in row
    // order.
    if (px.x > -2.0 && px.y > -2.0 && px.x < size.x + 2.0 && px.y < size.y + 2.0) {
        let c = vec2<i32>(floor(px));
        var best = -1.0;
        var colour = vec4<f32>(0.0);
        for (var y = c.y - 1; y <= c.y + 1; y++) {
            for (var x = c.x - 1; x <= c.x + 1; x++) {
                if (x < 0 || y < 0 || x >= dims.x || y >= dims.y) {
                    continue;
                }
                if (!on_surface(stored_gd(view, vec2<i32>(x, y)), z)) {
                    continue;
                }
                let e = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) - px;
                let d = dot(e, e);
                if (best < 0.0 || d < best) {
                    best = d;
                    colour = textureLoad(images, vec2<i32>(x, y), i32(view), 0);
                }
            }
        }
        if (best >= 0.0) {
            return vec4<f32>(colour.xyz, 1.0);
        }
    }
    // The nearest texel, clamped to the image.
    let q = clamp(vec2<i32>(floor(px)), vec2<i32>(0), dims - vec2<i32>(1));
    return vec4<f32>(textureLoad(images, q, i32(view), 0).xyz, 1.0);
}
