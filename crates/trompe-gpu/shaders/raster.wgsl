// The primary pass by rasterization (paper 1 §6 rasterizes it): every triangle drawn by the GPU
// rasterizer through the pinhole's McMillan matrix into a visibility buffer — per pixel the
// BVH-leaf-ordered triangle + 1 (0 where nothing is drawn), the perspective-correct
// barycentrics of its corners 1 and 2 and the depth drawn — which trace.wgsl shades as the
// raster method.
//
// Depth is reversed: a point t = (M⁻¹(X − C)).z along the image-plane normal (in focal units)
// has depth t_near / t, 1 on the near plane and 0 at infinity, the nearest kept.
//
// The same pass draws impostors (paper 1 §3.1, crates/trompe-gpu/src/build.rs): through a
// pinhole as above; through a graph camera (§4.5), frustum by frustum over one image, each
// frustum's matrix in the pinhole's form about its apex and its depth `near · gd`, so the largest
// gd wins across frusta; through a SPOC (§3), each corner of the tessellated mesh pushed from the pole
// by 1 + κ(z) after its pinhole projection, depth and barycentrics as the pinhole's; or through
// an orthographic camera, whose image coordinates and gd are affine in the point (depth = gd: 1
// on the image plane, 0 as deep as it sees; nothing behind it).

struct Camera {
    // Rows of M⁻¹ (orthographic: the affine rows of u, v and gd, times (X, 1)).
    row_u: vec4<f32>,
    row_v: vec4<f32>,
    row_t: vec4<f32>,
    // xyz: the eye; w: the near plane's t.
    eye: vec4<f32>,
    // Width and height in pixels; z: 1 for an orthographic camera, 2 for a SPOC; w: the SPOC's
    // focal distance.
    size: vec4<f32>,
    // The SPOC's pole (xy), z_n, and its ramp's slope k / (z_f − z_n).
    spoc: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct Corner {
    @builtin(position) clip: vec4<f32>,
    @location(0) bary: vec3<f32>,
    @location(1) @interpolate(flat) leaf: u32,
}

@vertex
fn draw_corner(@location(0) position: vec3<f32>, @location(1) corner_leaf: vec2<u32>) -> Corner {
    var out: Corner;
    if (camera.size.z == 1.0) {
        let p = vec4<f32>(position, 1.0);
        let u = dot(camera.row_u, p);
        let v = dot(camera.row_v, p);
        out.clip = vec4<f32>(2.0 * u / camera.size.x - 1.0, 1.0 - 2.0 * v / camera.size.y, dot(camera.row_t, p), 1.0);
    } else {
        // About the eye (a graph camera's frustum: its apex, where its rows' w terms vanish up
        // to rounding; a pinhole's are 0).
        let r = vec4<f32>(position - camera.eye.xyz, 1.0);
        var w = vec3<f32>(dot(camera.row_u, r), dot(camera.row_v, r), dot(camera.row_t, r));
        if (camera.size.z == 2.0 && w.z > 0.0) {
            // The SPOC: q = w.xy / w.z pushed from the pole by 1 + κ(f·w.z).
            let pole = camera.spoc.xy;
            let push = 1.0 + camera.spoc.w * max(camera.size.w * w.z - camera.spoc.z, 0.0);
            w = vec3<f32>((pole + (w.xy / w.z - pole) * push) * w.z, w.z);
        }
        // Pixel (u, v) = (w.x, w.y) / w.z, v down the image: x_ndc = 2u/W − 1, y_ndc = 1 − 2v/H.
        out.clip = vec4<f32>(
            2.0 * w.x / camera.size.x - w.z,
            w.z - 2.0 * w.y / camera.size.y,
            camera.eye.w,
            w.z,
        );
    }
    out.bary = vec3<f32>(
        select(0.0, 1.0, corner_leaf.x == 0u),
        select(0.0, 1.0, corner_leaf.x == 1u),
        select(0.0, 1.0, corner_leaf.x == 2u),
    );
    out.leaf = corner_leaf.y;
    return out;
}

// What a texel records: the leaf + 1, the barycentrics of corners 1 and 2, and the depth drawn.
fn record(in: Corner) -> vec4<u32> {
    return vec4<u32>(in.leaf + 1u, bitcast<u32>(in.bary.y), bitcast<u32>(in.bary.z), bitcast<u32>(in.clip.z));
}

@fragment
fn visible(in: Corner) -> @location(0) vec4<u32> {
    return record(in);
}

// Depth peeling (layered impostors, src/impostor/peel.rs): per texel the bits of a ceiling
// depth — the layer drawn before's, moved PEEL_GAP nearer the camera; 0 where it holds nothing.
@group(1) @binding(0) var ceiling: texture_2d<u32>;

// A fragment is drawn only strictly behind the ceiling (reversed depth: a smaller depth), so
// each texel keeps the nearest surface behind the layer before.
@fragment
fn visible_behind(in: Corner) -> @location(0) vec4<u32> {
    let under = bitcast<f32>(textureLoad(ceiling, vec2<i32>(in.clip.xy), 0).x);
    if (in.clip.z >= under) {
        discard;
    }
    return record(in);
}
