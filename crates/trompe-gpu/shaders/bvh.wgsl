// The exact ray query on the GPU: obvhs's compressed wide BVH (8 children a node, child boxes
// quantized to 8 bits in the node's frame; Ylitie, Karras and Laine 2017, "Efficient Incoherent
// Ray Traversal on GPUs Through Compressed Wide BVHs") walked front to back in the ray's octant
// order, with the watertight triangle test of src/geom/mod.rs (Woop, Benthin and Wald 2013).
//
// The node layout is obvhs's `CwBvhNode`, 80 bytes read as five vec4<u32>, each loaded once:
//   q0: p (the node's box minimum, f32 bits) and e[0..3] exponents + imask (bytes)
//   q1: first child node, first primitive, child_meta[8]
//   q2, q3, q4: child min x, max x; min y, max y; min z, max z (8 bytes each)
// Triangles are the BVH's leaf order, three corners a triangle.
//
// One invocation answers one ray: its closest hit below `t_max`, or (in any-hit mode) whether
// anything at all lies below it.

struct Ray {
    origin: vec3<f32>,
    t_max: f32,
    dir: vec3<f32>,
    _pad: f32,
}

// A hit: distance, leaf-ordered triangle (MISS where none), barycentrics of corners 1 and 2.
struct Hit {
    t: f32,
    triangle: u32,
    b1: f32,
    b2: f32,
}

struct Params {
    rays: u32,
    any_hit: u32,
    _pad: u32,
    // Rays a row of workgroups covers, for dispatches wider than one dimension allows.
    row: u32,
}

// The hierarchy (bindings 0 and 1) is all `query` reads: a shader that includes this file binds
// its own inputs from binding 5 on.
@group(0) @binding(0) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> corners: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> rays: array<Ray>;
@group(0) @binding(3) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(4) var<uniform> params: Params;

const NODE_QUADS: u32 = 5u;
const EVERY_TRIANGLE: u32 = 1u;
const MISS: u32 = 0xffffffffu;
// obvhs's nearest box entry (its `EPSILON`): a child box that ends before it is skipped.
const BOX_EPSILON: f32 = 0.0001;
// f32::EPSILON: directions below it are inverted as ±1/ε, as obvhs's `safe_inverse` does.
const DIR_EPSILON: f32 = 1.1920929e-7;
const STACK: u32 = 32u;

// −0.0 counts as positive, as the CPU query makes it (`dir + 0.0`).
fn sign_of(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

fn safe_inverse(x: f32) -> f32 {
    if (abs(x) <= DIR_EPSILON) {
        return sign_of(x) / DIR_EPSILON;
    }
    return 1.0 / x;
}

// Byte `i` (0-7) of the 8-byte field held in words `lo` (bytes 0-3) and `hi` (4-7).
fn byte8(lo: u32, hi: u32, i: u32) -> u32 {
    return (select(lo, hi, i >= 4u) >> ((i % 4u) * 8u)) & 0xffu;
}

// The node's hit mask: for every child box the ray enters before `t_max`, an inner child's bit
// (high byte, at its octant-ordered slot) or a leaf's primitive bits (low 24 bits).
fn intersect_node(q0: vec4<u32>, q1: vec4<u32>, base: u32, origin: vec3<f32>, inv: vec3<f32>, t_max: f32, oct_inv4: u32) -> u32 {
    let q2 = nodes[base + 2u];
    let q3 = nodes[base + 3u];
    let q4 = nodes[base + 4u];
    let p = bitcast<vec3<f32>>(q0.xyz);
    let w3 = q0.w;
    let extent = vec3<f32>(
        bitcast<f32>((w3 & 0xffu) << 23u),
        bitcast<f32>(((w3 >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((w3 >> 16u) & 0xffu) << 23u),
    );
    let scaled_inv = extent * inv;
    let shifted = (p - origin) * inv;
    let negative = inv < vec3<f32>(0.0);
    var mask = 0u;
    for (var c = 0u; c < 8u; c = c + 1u) {
        let info = byte8(q1.z, q1.w, c);
        if (info == 0u) {
            continue;
        }
        let lo = vec3<f32>(f32(byte8(q2.x, q2.y, c)), f32(byte8(q3.x, q3.y, c)), f32(byte8(q4.x, q4.y, c)));
        let hi = vec3<f32>(f32(byte8(q2.z, q2.w, c)), f32(byte8(q3.z, q3.w, c)), f32(byte8(q4.z, q4.w, c)));
        let near = select(lo, hi, negative) * scaled_inv + shifted;
        let far = select(hi, lo, negative) * scaled_inv + shifted;
        let t_in = max(max(near.x, near.y), max(near.z, BOX_EPSILON));
        let t_out = min(min(far.x, far.y), min(far.z, t_max));
        if (t_in <= t_out) {
            // Inner children hold 0b001_11xxx: their slot is reordered by the ray's octant.
            let inner = ((info & (info << 1u)) & 0x10u) != 0u;
            let bit_index = (info ^ select(0u, oct_inv4 & 0xffu, inner)) & 0x1fu;
            let child_bits = (info >> 5u) & 7u;
            mask = mask | (child_bits << bit_index);
        }
    }
    return mask;
}

// The watertight ray-triangle test, two-sided, for hits with 0 < t < t_max: (t, b1, b2, 1) or
// w = 0 for a miss. Without f64 here, the edge functions are not recomputed when one is zero.
fn intersect_triangle(origin: vec3<f32>, d: vec3<f32>, k: u32, t_max: f32) -> vec4<f32> {
    let ad = abs(d);
    var kz = 2u;
    if (ad.x >= ad.y && ad.x >= ad.z) {
        kz = 0u;
    } else if (ad.y >= ad.z) {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kz + 2u) % 3u;
    if (d[kz] < 0.0) {
        let s = kx;
        kx = ky;
        ky = s;
    }
    if (d[kz] == 0.0) {
        return vec4<f32>(0.0);
    }
    let sx = d[kx] / d[kz];
    let sy = d[ky] / d[kz];
    let sz = 1.0 / d[kz];
    let a = corners[3u * k].xyz - origin;
    let b = corners[3u * k + 1u].xyz - origin;
    let c = corners[3u * k + 2u].xyz - origin;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return vec4<f32>(0.0);
    }
    let det = u + v + w;
    if (det == 0.0) {
        return vec4<f32>(0.0);
    }
    let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
    if (!(t > 0.0 && t < t_max)) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(t, v / det, w / det, 1.0);
}

// The closest hit along `ray` below its t_max (any hit, the first found, when `any_hit`).
fn query(ray: Ray, any_hit: bool) -> Hit {
    return query_classes(ray, any_hit, EVERY_TRIANGLE);
}

// `query` over the triangles in one of `classes` (bits; the first corner's w holds a
// triangle's, and every triangle is in EVERY_TRIANGLE).
fn query_classes(ray: Ray, any_hit: bool, classes: u32) -> Hit {
    return query_selected(ray, any_hit, classes, NO_SELECTED_OBJECT);
}

// No object: the second corner's w (an object's id, as f32) never converts to it.
const NO_SELECTED_OBJECT: u32 = 0xffffffffu;

// `query` over the triangles in one of `classes` and those of object `object` (the second
// corner's w holds a triangle's object).
fn query_selected(ray: Ray, any_hit: bool, classes: u32, object: u32) -> Hit {
    var best = Hit(ray.t_max, MISS, 0.0, 0.0);
    // An empty hierarchy is bound as one padding word short of a node.
    if (arrayLength(&nodes) < NODE_QUADS) {
        return best;
    }
    let dir = ray.dir;
    let inv = vec3<f32>(safe_inverse(dir.x), safe_inverse(dir.y), safe_inverse(dir.z));
    let oct_inv4 = select(0x04040404u, 0u, dir.x < 0.0)
        | select(0x02020202u, 0u, dir.y < 0.0)
        | select(0x01010101u, 0u, dir.z < 0.0);
    var stack: array<vec2<u32>, STACK>;
    var depth = 0u;
    // (first child node, hit bits << 24 | imask); the root stands as the one inner hit.
    var group = vec2<u32>(0u, 0x80000000u);
    var prims = vec2<u32>(0u, 0u);
    loop {
        while (prims.y != 0u) {
            let local = firstLeadingBit(prims.y);
            prims.y = prims.y & ~(1u << local);
            let k = prims.x + local;
            if ((bitcast<u32>(corners[3u * k].w) & classes) == 0u
                && u32(corners[3u * k + 1u].w) != object) {
                continue;
            }
            let h = intersect_triangle(ray.origin, dir, k, best.t);
            if (h.w != 0.0) {
                best = Hit(h.x, k, h.y, h.z);
                if (any_hit) {
                    return best;
                }
            }
        }
        prims = vec2<u32>(0u, 0u);
        if ((group.y & 0xff000000u) != 0u) {
            let hits_imask = group.y;
            let offset = firstLeadingBit(hits_imask);
            group.y = group.y & ~(1u << offset);
            if ((group.y & 0xff000000u) != 0u) {
                if (depth < STACK) {
                    stack[depth] = group;
                    depth = depth + 1u;
                }
            }
            let slot = (offset - 24u) ^ (oct_inv4 & 0xffu);
            let relative = countOneBits(hits_imask & ~(0xffffffffu << slot));
            let node = (group.x + relative) * NODE_QUADS;
            let q0 = nodes[node];
            let q1 = nodes[node + 1u];
            let mask = intersect_node(q0, q1, node, ray.origin, inv, best.t, oct_inv4);
            group = vec2<u32>(q1.x, (mask & 0xff000000u) | (q0.w >> 24u));
            prims = vec2<u32>(q1.y, mask & 0x00ffffffu);
        } else {
            group = vec2<u32>(0u, 0u);
        }
        if (prims.y == 0u && (group.y & 0xff000000u) == 0u) {
            if (depth == 0u) {
                break;
            }
            depth = depth - 1u;
            group = stack[depth];
        }
    }
    return best;
}

@compute @workgroup_size(64)
fn trace_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.rays) {
        return;
    }
    hits[i] = query(rays[i], params.any_hit != 0u);
}
