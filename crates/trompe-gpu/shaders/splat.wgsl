// Paper 2's hybrid reflections on the GPU (the library's src/hybrid/frame.rs, pass for pass):
// the G-buffer of the eye's hits, read from the rasterized visibility buffer, which tells the
// CPU the reflector triangles the eye sees; then,
// over the CPU's plan of cameras and kd-tree nodes, every point projected through its camera's
// cubic (c3rc.wgsl) and splatted where the eye sees that reflector at the image point's depth;
// each pixel resolved to the point nearest the mirror, lit; and the tracer (trace.wgsl),
// whose first reflections off mirrors and glass these splats answer. Compiled after bvh.wgsl,
// trace.wgsl and c3rc.wgsl.
//
// Splats resolve as the CPU's 64-bit atomic minimum over (path length bits, point index), in
// two 32-bit passes: the least path length first, then the least point index among the
// projections that reach it — the same winner for any order of invocations.

// A planned camera's node: its camera (local, in its cloud's space), the cloud, the node's
// first point and count in the frame's numbering, and the stride it is read with.
struct Item {
    camera: u32,
    world: u32,
    cloud: u32,
    first: u32,
    count: u32,
    stride: u32,
    _pad0: u32,
    _pad1: u32,
}

// A cloud: its rows object → world, and its normals' rows, whose w lanes hold its first point
// and object id (bits).
struct Cloud {
    world: array<vec4<f32>, 3>,
    normal: array<vec4<f32>, 3>,
}

struct Splats {
    // Splat side, items, clouds, whether mirrors hide points.
    settings: vec4<u32>,
    // Item workgroups a row of the dispatch covers.
    row: vec4<u32>,
}

// Per pixel: the eye's hit (distance, object bits, or NO_OBJECT) and where it lies.
@group(0) @binding(13) var<storage, read_write> gbuffer: array<vec4<f32>>;
// Per pixel: the lit point's radiance and its distance from the pixel's surface (w < 0: none).
@group(0) @binding(14) var<storage, read_write> splatted: array<vec4<f32>>;
// Counters, then one bit a point: does it project?
@group(0) @binding(15) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(16) var<storage, read> cameras: array<C3rc>;
@group(0) @binding(17) var<storage, read> items: array<Item>;
// Three a point, in object space: position, normal, albedo.
@group(0) @binding(18) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(19) var<storage, read> clouds: array<Cloud>;
// Per pixel: the least path length's bits, then the least point index reaching it.
@group(0) @binding(21) var<storage, read_write> keys: array<atomic<u32>>;
// Per leaf-ordered triangle: 1 where the eye sees it and it reflects.
@group(0) @binding(22) var<storage, read_write> seen_leaves: array<u32>;
@group(0) @binding(23) var<uniform> splats: Splats;

const REFLECTOR_PIXELS: u32 = 0u;
const PROJECTIONS: u32 = 1u;
const SPLATS: u32 = 2u;
const POINTS_SEEN: u32 = 3u;
const PIXELS_SPLATTED: u32 = 4u;
const PIXELS_TRACED: u32 = 5u;
const FIRST_BIT_WORD: u32 = 8u;
const NO_KEY: u32 = 0xffffffffu;
// Relative depth slack between a splat's image point and the surface the eye sees there (the
// library's `hybrid::plan::DEPTH_SLACK`).
const DEPTH_SLACK: f32 = 0.02;
// The class of the mirror and glass triangles in the BVH (trace.rs's `SPECULAR`).
const SPLAT_SPECULAR: u32 = 2u;

fn eye_ray(x: u32, y: u32) -> vec3<f32> {
    let uv = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    return normalize(view.a.xyz * uv.x + view.b.xyz * uv.y + view.c.xyz);
}

// The pixel a point projects into through the eye camera, as (x, y) (negative where behind the
// eye), before flooring.
fn eye_uv(p: vec3<f32>) -> vec3<f32> {
    let r = vec4<f32>(p - view.eye.xyz, 0.0);
    let z = dot(view.row_t, r);
    if (z <= 0.0) {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    return vec3<f32>(dot(view.row_u, r) / z, dot(view.row_v, r) / z, 1.0);
}

// The G-buffer: each pixel's primary hit (distance, object, position) from the visibility
// buffer; the reflector triangles seen flagged for the CPU's plan.
@compute @workgroup_size(8, 8)
fn splat_gbuffer(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = view.size.x;
    if (id.x >= w || id.y >= view.size.y) {
        return;
    }
    let pixel = id.y * w + id.x;
    let eye = view.eye.xyz;
    let d = eye_ray(id.x, id.y);
    // The eye's hit from the rasterized visibility buffer, as the tracer reads it.
    let visible = visible_hit(id.xy, eye, d);
    let hit = visible.hit;
    atomicStore(&keys[2u * pixel], NO_KEY);
    atomicStore(&keys[2u * pixel + 1u], NO_KEY);
    splatted[pixel] = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    if (hit.triangle == MISS) {
        gbuffer[2u * pixel] = vec4<f32>(FAR, bitcast<f32>(NO_OBJECT), 0.0, 0.0);
        gbuffer[2u * pixel + 1u] = vec4<f32>(0.0);
        return;
    }
    let tri = triangles[hit.triangle];
    let object = bitcast<u32>(tri.n1.w);
    gbuffer[2u * pixel] = vec4<f32>(hit.t, bitcast<f32>(object), 0.0, 0.0);
    gbuffer[2u * pixel + 1u] = vec4<f32>(visible.position, 0.0);
    let kind = bitcast<u32>(materials[bitcast<u32>(tri.n0.w)].color.w);
    if (kind != DIFFUSE) {
        seen_leaves[hit.triangle] = 1u;
        atomicAdd(&counters[REFLECTOR_PIXELS], 1u);
    }
}

// A point of the frame's numbering in world space: its cloud's placement applied.
fn world_point(cloud: Cloud, q: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(q, 1.0);
    return vec3<f32>(dot(cloud.world[0], h), dot(cloud.world[1], h), dot(cloud.world[2], h));
}

// Point `global` (object-space `q`, in cloud `cloud`) through item `item`'s camera: every
// projection splatted. In the first pass each accepted splat lowers its pixel's least path
// length and the counters count; in the second, a splat that reaches that least length lowers
// the pixel's least point index.
fn splat_point(item: Item, global: u32, second: bool) {
    let q = points[3u * global].xyz;
    let cam = cameras[item.camera];
    let world = cameras[item.world];
    let lambda_max = world.v[0].w;
    let object = bitcast<u32>(world.v[1].w);
    let found = c3rc_project(cam, q, 0.0, lambda_max);
    if (found.len == 0u) {
        return;
    }
    if (!second) {
        atomicAdd(&counters[PROJECTIONS], found.len);
        let bit = 1u << (global % 32u);
        let old = atomicOr(&counters[FIRST_BIT_WORD + global / 32u], bit);
        if ((old & bit) == 0u) {
            atomicAdd(&counters[POINTS_SEEN], 1u);
        }
    }
    let qw = world_point(clouds[item.cloud], q);
    let eye = view.eye.xyz;
    let size = splats.settings.x;
    let w = view.size.x;
    let h = view.size.y;
    for (var k = 0u; k < found.len; k = k + 1u) {
        let b = found.p[k].bary;
        let p = world.v[0].xyz * b.x + world.v[1].xyz * b.y + world.v[2].xyz * b.z;
        let to_p = length(p - eye);
        let key = bitcast<u32>(to_p + length(qw - p));
        let uv = eye_uv(p);
        if (uv.z < 0.0) {
            continue;
        }
        var corner = floor(uv.xy);
        if (size != 1u) {
            corner = floor(uv.xy - vec2<f32>(0.5));
        }
        for (var dy = 0u; dy < size; dy = dy + 1u) {
            for (var dx = 0u; dx < size; dx = dx + 1u) {
                let x = corner.x + f32(dx);
                let y = corner.y + f32(dy);
                if (x < 0.0 || y < 0.0 || x >= f32(w) || y >= f32(h)) {
                    continue;
                }
                let pixel = u32(y) * w + u32(x);
                let seen = gbuffer[2u * pixel];
                if (bitcast<u32>(seen.y) != object || abs(seen.x - to_p) > DEPTH_SLACK * to_p) {
                    continue;
                }
                if (!second) {
                    atomicAdd(&counters[SPLATS], 1u);
                    atomicMin(&keys[2u * pixel], key);
                } else if (atomicLoad(&keys[2u * pixel]) == key) {
                    atomicMin(&keys[2u * pixel + 1u], global);
                }
            }
        }
    }
}

// One workgroup an item, its invocations striding through the item's points.
fn splat_item(group: vec3<u32>, lane: u32, second: bool) {
    let index = group.x + group.y * splats.row.x;
    if (index >= splats.settings.y) {
        return;
    }
    let item = items[index];
    let step = 64u * item.stride;
    for (var i = lane * item.stride; i < item.count; i = i + step) {
        splat_point(item, item.first + i, second);
    }
}

@compute @workgroup_size(64)
fn splat_lengths(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    splat_item(group, lane, false);
}

@compute @workgroup_size(64)
fn splat_indices(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    splat_item(group, lane, true);
}

// Each pixel's winning point, lit as the library's `render::shading::lambert` lights it, on the
// side the reflector sees it from, shadows traced.
@compute @workgroup_size(8, 8)
fn splat_resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = view.size.x;
    if (id.x >= w || id.y >= view.size.y) {
        return;
    }
    let pixel = id.y * w + id.x;
    let global = atomicLoad(&keys[2u * pixel + 1u]);
    if (global == NO_KEY || atomicLoad(&keys[2u * pixel]) == NO_KEY) {
        return;
    }
    var c = 0u;
    for (var k = 1u; k < splats.settings.z; k = k + 1u) {
        if (bitcast<u32>(clouds[k].normal[0].w) <= global) {
            c = k;
        }
    }
    let cloud = clouds[c];
    let q = world_point(cloud, points[3u * global].xyz);
    let m = points[3u * global + 1u].xyz;
    let albedo = points[3u * global + 2u].xyz;
    var n = vec3<f32>(dot(cloud.normal[0].xyz, m), dot(cloud.normal[1].xyz, m), dot(cloud.normal[2].xyz, m));
    let len = length(n);
    if (len > 0.0 && len <= FAR) {
        n = n / len;
    } else {
        n = vec3<f32>(0.0);
    }
    let surface = gbuffer[2u * pixel + 1u].xyz;
    if (dot(n, surface - q) < 0.0) {
        n = -n;
    }
    var e = ambient(n);
    if (view.size.w != 0u) {
        let l = view.sun_dir.xyz;
        let cos_l = dot(n, l);
        if (cos_l > 0.0) {
            let shadow = query(Ray(q + n * view.eye.w, FAR, l, 0.0), true);
            if (shadow.triangle == MISS) {
                e = e + view.sun.xyz * (cos_l / PI);
            }
        }
    }
    splatted[pixel] = vec4<f32>(albedo * e, length(q - surface));
    atomicAdd(&counters[PIXELS_SPLATTED], 1u);
}

// What the tracer's rays into the open meet: where the ray is the eye's first reflection off
// `source` at a pixel, the splat there (the environment where no point landed; traced exactly
// where a mirror or glass lies nearer than the point and mirrors hide points); the exact BVH
// for every other ray. One traversal call site: lavapipe pays for each inlined copy of the walk
// in every invocation.
fn secondary_hit(source: u32, ray: Ray) -> Answer {
    let uv = eye_uv(ray.origin);
    let x = floor(uv.x);
    let y = floor(uv.y);
    // Whether the nearer mirrors are asked first, the splat's answer waiting on them.
    var mirrors_first = false;
    var found = vec4<f32>(0.0);
    if (uv.z >= 0.0 && x >= 0.0 && y >= 0.0 && x < f32(view.size.x) && y < f32(view.size.y)) {
        let pixel = u32(y) * view.size.x + u32(x);
        let seen = gbuffer[2u * pixel];
        let position = gbuffer[2u * pixel + 1u].xyz;
        let near = 2.0 * view.eye.w + 1e-6 * (1.0 + length(position));
        if (bitcast<u32>(seen.y) == source && length(position - ray.origin) <= near) {
            found = splatted[pixel];
            if (found.w < 0.0) {
                return Answer(Hit(FAR, MISS, 0.0, 0.0), vec4<f32>(0.0), no_stored());
            }
            if (splats.settings.w == 0u) {
                return Answer(Hit(FAR, MISS, 0.0, 0.0), vec4<f32>(found.xyz, 1.0), no_stored());
            }
            mirrors_first = true;
        }
    }
    var query_ray = ray;
    var classes = EVERY_TRIANGLE;
    if (mirrors_first) {
        query_ray.t_max = found.w;
        classes = SPLAT_SPECULAR;
    }
    var answer = Answer(Hit(FAR, MISS, 0.0, 0.0), vec4<f32>(0.0), no_stored());
    for (var round = 0u; round < 2u; round = round + 1u) {
        let hit = query_classes(query_ray, false, classes);
        if (!mirrors_first) {
            answer = Answer(hit, vec4<f32>(0.0), no_stored());
            break;
        }
        if (hit.triangle == MISS) {
            answer = Answer(Hit(FAR, MISS, 0.0, 0.0), vec4<f32>(found.xyz, 1.0), no_stored());
            break;
        }
        // A mirror hides the point: the ray traced exactly.
        atomicAdd(&counters[PIXELS_TRACED], 1u);
        mirrors_first = false;
        query_ray = ray;
        classes = EVERY_TRIANGLE;
    }
    return answer;
}
