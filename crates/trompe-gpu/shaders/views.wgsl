// Calibrated views as a projective-texturing source (view-dependent texture mapping from
// photographs with depth maps; depth_images.wgsl goes before this file, texturing.wgsl after
// it): every view's image is a layer of one texture array and its depth map the same layer of
// another, each padded to the largest view.
//
// The CPU twin is src/views/blend.rs with src/views/visibility.rs: a view sees a point by the
// depth map's rule (depth_images.wgsl's `sight_rule`); its colour is a bilinear lookup over
// the texels whose depth says they are the point's surface (within SAME_SURFACE), failing that
// the nearest such texel of the 3 × 3 around it, failing that the nearest texel, clamped.
//
// Projected whole (paper 4's baseline, src/layers/render.rs `Photographs`), a view has no depth
// map: it sees every point in front of it that lands in its frame, and colours it by a plain
// bilinear lookup, clamped at the edges.

struct View {
    // The depth map's pinhole: the rows of M⁻¹ (applied to a point less `depth_eye`).
    depth_u: vec4<f32>,
    depth_v: vec4<f32>,
    depth_t: vec4<f32>,
    // xyz: the depth map's centre.
    depth_eye: vec4<f32>,
    // The view's rotation, world to camera, by rows; and its centre (xyz), w: 1 where the view
    // takes part (an image, not left out).
    rot0: vec4<f32>,
    rot1: vec4<f32>,
    rot2: vec4<f32>,
    centre: vec4<f32>,
    // fx, fy, cx, cy.
    intrinsics: vec4<f32>,
    // xy: the image's width and height (its depth map's are the same); z: 1 where the whole
    // photograph is projected, without a depth map.
    size: vec4<f32>,
}

@group(0) @binding(8) var<storage, read> views: array<View>;

// How far (relative depth) a texel's surface may be from the sampled point and still be the
// same surface (src/views/blend.rs's SAME_SURFACE).
const SAME_SURFACE: f32 = 0.05;

// Where `at` lands in view `view`'s image (through its intrinsics, no lens): xy the pixel, z its
// depth along the camera's z (0: behind it).
fn project(view: u32, at: At) -> vec3<f32> {
    let v = views[view];
    let r = at.x - v.centre.xyz;
    let p = vec3<f32>(dot(v.rot0.xyz, r), dot(v.rot1.xyz, r), dot(v.rot2.xyz, r));
    if (p.z <= 1e-9) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(v.intrinsics.xy * (p.xy / p.z) + v.intrinsics.zw, p.z);
}

fn texel(view: u32, at: At) -> vec3<f32> {
    // A whole photograph is looked up once, unfiltered, as on the CPU.
    let p = project(view, at);
    return vec3<f32>(p.xy, select(0.0, 1.0, p.z > 0.0 && views[view].size.z != 1.0));
}

// A bilinear lookup of view `view`'s image at `px`, clamped at its edges.
fn bilinear_clamped(view: u32, px: vec2<f32>) -> vec4<f32> {
    let last = vec2<i32>(views[view].size.xy) - vec2<i32>(1);
    let f = px - vec2<f32>(0.5);
    let base = floor(f);
    let t = f - base;
    let a = clamp(vec2<i32>(base), vec2<i32>(0), last);
    let b = clamp(vec2<i32>(base) + vec2<i32>(1), vec2<i32>(0), last);
    let top = mix(textureLoad(images, a, view, 0), textureLoad(images, vec2<i32>(b.x, a.y), view, 0), t.x);
    let bottom = mix(textureLoad(images, vec2<i32>(a.x, b.y), view, 0), textureLoad(images, b, view, 0), t.x);
    return vec4<f32>(mix(top, bottom, t.y).xyz, 1.0);
}

fn depth_image(view: u32) -> DepthImage {
    return DepthImage(i32(view), views[view].size.xy, false);
}

// Whether pixel point `px` lies in view `view`'s frame.
fn in_frame(view: u32, px: vec2<f32>) -> bool {
    let size = views[view].size.xy;
    return px.x >= 0.0 && px.y >= 0.0 && px.x < size.x && px.y < size.y;
}

fn sight(view: u32, at: At) -> u32 {
    let v = views[view];
    if (v.centre.w == 0.0) {
        return 0u;
    }
    if (v.size.z == 1.0) {
        let p = project(view, at);
        return select(0u, 2u, p.z > 0.0 && in_frame(view, p.xy));
    }
    let r = at.x - v.depth_eye.xyz;
    let w = vec3<f32>(dot(v.depth_u.xyz, r), dot(v.depth_v.xyz, r), dot(v.depth_t.xyz, r));
    if (w.z <= 0.0) {
        return 0u;
    }
    return sight_rule(depth_image(view), w.xy / w.z, w.z, params.extra.x);
}

fn lookup(view: u32, at: At) -> vec4<f32> {
    let p = project(view, at);
    if (p.z <= 0.0) {
        return vec4<f32>(0.0);
    }
    let px = p.xy;
    if (views[view].size.z == 1.0) {
        if (!in_frame(view, px)) {
            return vec4<f32>(0.0);
        }
        return bilinear_clamped(view, px);
    }
    let d = depth_image(view);
    let on = bilinear_on_surface(d, px, p.z, SAME_SURFACE);
    if (on.w > 0.0) {
        return on;
    }
    let near = nearest_on_surface(d, px, p.z, SAME_SURFACE);
    if (near.w > 0.0) {
        return near;
    }
    // The nearest texel, clamped to the image.
    let q = clamp(vec2<i32>(floor(px)), vec2<i32>(0), vec2<i32>(d.size) - vec2<i32>(1));
    return vec4<f32>(textureLoad(images, q, d.layer, 0).xyz, 1.0);
}
