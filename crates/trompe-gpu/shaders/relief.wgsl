// The texture-mapping phase of paper 3 ("Relief texture mapping" re-used by 3D image warping,
// §2 and §6) on the graphics hardware, as the library's src/relief/texture.rs draws on the CPU:
// a pre-warped relief texture mapped onto its impostor's base quad (enlarged by the warp's
// margin) and seen through the eye, each pixel taking the depth of the relief point it shows —
// on the eye's line through the base point, at the carried displacement — and drawn only where
// that is nearer than what the frame holds, so the rest of the frame interpenetrates it. One
// dispatch an impostor, over the pixels its quad can cover, in the frame loop's order, into the
// buffers the tracer's raster pass drew the other objects into.

struct Draw {
    // xyz: the eye; w: its height above the base plane.
    eye: vec4<f32>,
    // McMillan's pixel steps and corner vector: a ray through pixel point (u, v) runs along
    // a·u + b·v + c.
    ray_a: vec4<f32>,
    ray_b: vec4<f32>,
    ray_c: vec4<f32>,
    // The base plane: texel (u, v) at displacement d is origin + u·a + v·b + d·f; a and b's w
    // hold 1 / |a|² and 1 / |b|².
    origin: vec4<f32>,
    axis_a: vec4<f32>,
    axis_b: vec4<f32>,
    normal: vec4<f32>,
    // The pixels dispatched: first column and row, columns and rows; then the frame's width.
    rect: vec4<u32>,
    // The image's width and height, its margins, and the object's id.
    image: vec4<u32>,
    frame: vec4<u32>,
}

// The frame as trace.wgsl writes it: colour; depth (x) and object id (y, bits); normal.
@group(0) @binding(0) var<storage, read_write> colour: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> depth_id: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> normals: array<vec4<f32>>;
// The pre-warped colour (sRGB, decoded by the sampler-free load), and per texel its
// displacement (r) and whether anything landed there (g: 1, or 0 where empty).
@group(0) @binding(3) var relief_colour: texture_2d<f32>;
@group(0) @binding(4) var relief_depth: texture_2d<f32>;
@group(0) @binding(5) var<uniform> draw: Draw;

// Bilinear over the non-empty texels at continuous coordinates p: colour and displacement, w
// the weight found (under ½: nothing drawn).
struct Looked {
    colour: vec3<f32>,
    displacement: f32,
    weight: f32,
}

fn look_up(p: vec2<f32>) -> Looked {
    let f = p - vec2<f32>(0.5);
    let corner = floor(f);
    let t = f - corner;
    let size = vec2<i32>(draw.image.xy);
    var found = Looked(vec3<f32>(0.0), 0.0, 0.0);
    for (var k = 0u; k < 4u; k = k + 1u) {
        let dx = k & 1u;
        let dy = k >> 1u;
        let wx = select(1.0 - t.x, t.x, dx == 1u);
        let wy = select(1.0 - t.y, t.y, dy == 1u);
        let w = wx * wy;
        let at = vec2<i32>(corner) + vec2<i32>(i32(dx), i32(dy));
        if (any(at < vec2<i32>(0)) || any(at >= size) || w == 0.0) {
            continue;
        }
        let depth = textureLoad(relief_depth, at, 0);
        if (depth.g == 0.0) {
            continue;
        }
        found.weight = found.weight + w;
        found.colour = found.colour + textureLoad(relief_colour, at, 0).rgb * w;
        found.displacement = found.displacement + depth.r * w;
    }
    return found;
}

@compute @workgroup_size(8, 8)
fn map_relief(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= draw.rect.z || id.y >= draw.rect.w) {
        return;
    }
    let x = draw.rect.x + id.x;
    let y = draw.rect.y + id.y;
    let uv = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let dir = normalize(draw.ray_a.xyz * uv.x + draw.ray_b.xyz * uv.y + draw.ray_c.xyz);
    let f = draw.normal.xyz;
    let along = dot(dir, f);
    if (along >= 0.0) {
        return;
    }
    let eye = draw.eye.xyz;
    let t = dot(draw.origin.xyz - eye, f) / along;
    let r = eye + dir * t - draw.origin.xyz;
    let base = vec2<f32>(dot(r, draw.axis_a.xyz) * draw.axis_a.w, dot(r, draw.axis_b.xyz) * draw.axis_b.w);
    let found = look_up(base + vec2<f32>(draw.image.zw));
    if (found.weight < 0.5) {
        return;
    }
    let d = found.displacement / found.weight;
    // The relief point on the eye's line, d above the plane.
    let s = 1.0 - d / draw.eye.w;
    let distance = s * t;
    let pixel = y * draw.frame.x + x;
    if (s > 0.0 && distance < depth_id[pixel].x) {
        colour[pixel] = vec4<f32>(found.colour / found.weight, 1.0);
        depth_id[pixel] = vec4<f32>(distance, bitcast<f32>(draw.frame.y), 0.0, 0.0);
        normals[pixel] = vec4<f32>(f, 0.0);
    }
}
