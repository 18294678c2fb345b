// The `trace` method on the GPU: Whitted ray tracing (Whitted 1980) through the exact BVH of
// bvh.wgsl (this file is compiled after it), one invocation a pixel, shaded as the library's
// src/render/shading.rs shades: Lambert with the environment's irradiance and a sun with hard
// shadows, perfect mirrors, glass with the exact Fresnel weights, a recursion limit past which
// rays take the environment's radiance. Textures and panoramas are looked up as
// src/frame/mod.rs and src/frame/envmap.rs look them up.
//
// Recursion becomes a stack of pending rays, each with the weight its radiance carries to the
// pixel: a mirror passes one ray on, glass two. The pixel is the sum of weight × radiance.
//
// The rays mirrors and glass send out into the open are answered by `secondary_hit`, which the
// file compiled after this one defines: exact_secondary.wgsl (the BVH: the `trace` method) or
// impostor_secondary.wgsl (impostors: paper 1 §6's methods), as the library's
// src/render/trace.rs asks its `SecondaryQuery`.

// A triangle's shading data, in the BVH's leaf order.
struct Triangle {
    // xyz: vertex normal 0; w: its material (bits).
    n0: vec4<f32>,
    // xyz: vertex normal 1; w: its object (bits).
    n1: vec4<f32>,
    // xyz: vertex normal 2; w: Wyman's d_N at corner 0 (glass, under Wyman's refraction).
    n2: vec4<f32>,
    // xyz: the face normal (unit, or zero for a degenerate triangle); w: d_N at corner 1.
    ng: vec4<f32>,
    uv01: vec4<f32>,
    // xy: corner 2's texture coordinates; z: d_N at corner 2.
    uv2: vec4<f32>,
}

const DIFFUSE: u32 = 0u;
const MIRROR: u32 = 1u;
const GLASS: u32 = 2u;

struct Material {
    // rgb: base colour (diffuse) or tint (mirror, glass); w: kind (bits).
    color: vec4<f32>,
    // x: index of refraction (glass).
    ior: vec4<f32>,
    // A texture: first texel, width, height, and 1 where there is one.
    texture: vec4<u32>,
}

struct View {
    // xyz: the eye; w: the ray offset along the normal.
    eye: vec4<f32>,
    // McMillan's pixel steps a, b and the corner vector c: a ray through pixel point (u, v)
    // runs along a·u + b·v + c.
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    // Width, height, recursion limit, whether there is a sun.
    size: vec4<u32>,
    // xyz: toward the sun; w: the panorama's rotation about y.
    sun_dir: vec4<f32>,
    // rgb: the sun's irradiance; w: the panorama's intensity.
    sun: vec4<f32>,
    // The radiance panorama and its irradiance grid: first texel, width, height.
    radiance: vec4<u32>,
    irradiance: vec4<u32>,
    // x: 1 where the primary hits come from the visibility buffer (the raster method); y: 1
    // where the eye's refractions into glass are Wyman's.
    mode: vec4<u32>,
    // The eye camera's rows of M⁻¹: pixel (u, v) = (row_u·r, row_v·r) / row_t·r for r = X − eye.
    row_u: vec4<f32>,
    row_v: vec4<f32>,
    row_t: vec4<f32>,
}

@group(0) @binding(5) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> texels: array<vec4<f32>>;
@group(0) @binding(8) var<uniform> view: View;
// Per pixel: linear colour (alpha 1); (depth, object id bits, 0, 0); the shading normal.
@group(0) @binding(9) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_depth_id: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> out_normal: array<vec4<f32>>;
// The raster method's visibility buffer (raster.wgsl): leaf triangle + 1, b1 and b2 bits.
@group(0) @binding(12) var visibility: texture_2d<u32>;
// Wyman's first pass: the glass objects' back faces drawn through the eye, as `visibility`.
@group(0) @binding(20) var backs: texture_2d<u32>;

const PI: f32 = 3.14159265358979;
// The largest f32: no hit lies beyond it (the CPU's queries ask up to infinity).
const FAR: f32 = 3.4028235e38;
const PENDING: u32 = 24u;
// The object id of a pixel that sees nothing (src/frame/mod.rs's NO_OBJECT).
const NO_OBJECT: u32 = 0xffffffffu;

// Texel (x, y) of the image whose first texel, width and height are `img`.
fn texel(img: vec4<u32>, x: u32, y: u32) -> vec3<f32> {
    return texels[img.x + y * img.y + x].xyz;
}

// The texels i and i + 1 of a row of n, repeated or clamped.
fn pair(i: i32, n: u32, repeat: bool) -> vec2<u32> {
    let m = i32(n);
    if (repeat) {
        let a = ((i % m) + m) % m;
        return vec2<u32>(u32(a), select(u32(a) + 1u, 0u, a + 1 == m));
    }
    return vec2<u32>(u32(clamp(i, 0, m - 1)), u32(clamp(i + 1, 0, m - 1)));
}

// Bilinear lookup at pixel coordinates `p` (texel centres at +½).
fn bilinear(img: vec4<u32>, p: vec2<f32>, repeat_x: bool, repeat_y: bool) -> vec3<f32> {
    let q = clamp(p - vec2<f32>(0.5), vec2<f32>(-1073741824.0), vec2<f32>(1073741824.0));
    let f = floor(q);
    let t = q - f;
    let xs = pair(i32(f.x), img.y, repeat_x);
    let ys = pair(i32(f.y), img.z, repeat_y);
    let top = texel(img, xs.x, ys.x) * (1.0 - t.x) + texel(img, xs.y, ys.x) * t.x;
    let bottom = texel(img, xs.x, ys.y) * (1.0 - t.x) + texel(img, xs.y, ys.y) * t.x;
    return top * (1.0 - t.y) + bottom * t.y;
}

fn rem_euclid_one(x: f32) -> f32 {
    let r = x - trunc(x);
    return select(r, r + 1.0, r < 0.0);
}

// atan2 with IEEE 754's answers where both arguments are zero (±0 for x = +0, ±π for x = −0),
// as the CPU's: a normal along ±y looks the panorama's pole up at the same longitude.
fn atan2_signed_zeros(y: f32, x: f32) -> f32 {
    if (y == 0.0 && x == 0.0) {
        let negative_x = (bitcast<u32>(x) >> 31u) != 0u;
        let negative_y = (bitcast<u32>(y) >> 31u) != 0u;
        let angle = select(0.0, PI, negative_x);
        return select(angle, -angle, negative_y);
    }
    return atan2(y, x);
}

// A direction's equirectangular (u, v), the panorama's rotation undone.
fn panorama_uv(d_in: vec3<f32>) -> vec2<f32> {
    // glam's normalize_or(+y): times the reciprocal length, where it is finite and positive.
    var d = vec3<f32>(0.0, 1.0, 0.0);
    let rcp = 1.0 / length(d_in);
    if (rcp > 0.0 && rcp <= FAR) {
        d = d_in * rcp;
    }
    let angle = -view.sun_dir.w;
    if (angle != 0.0) {
        let s = sin(angle);
        let c = cos(angle);
        d = vec3<f32>(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
    }
    return vec2<f32>(rem_euclid_one(atan2_signed_zeros(d.x, -d.z) / (2.0 * PI)), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

// Radiance arriving from direction d (Mitsuba's texel placement: rows at v·(H − 1)).
fn environment(d: vec3<f32>) -> vec3<f32> {
    let st = panorama_uv(d);
    let img = view.radiance;
    let p = vec2<f32>(st.x * f32(img.y), st.y * f32(img.z - 1u) + 0.5);
    return bilinear(img, p, true, false) * view.sun.w;
}

// Irradiance / π around n, from the convolved grid.
fn ambient(n: vec3<f32>) -> vec3<f32> {
    let st = panorama_uv(n);
    let img = view.irradiance;
    return bilinear(img, st * vec2<f32>(f32(img.y), f32(img.z)), true, false) * view.sun.w;
}

fn reflect_about(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(d, n) * n;
}

// The refracted direction (w = 1), or w = 0 under total internal reflection.
fn refract_through(d: vec3<f32>, n: vec3<f32>, eta: f32) -> vec4<f32> {
    let cos_i = -dot(d, n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k < 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(normalize(eta * d + (eta * cos_i - sqrt(k)) * n), 1.0);
}

fn fresnel(cos_i: f32, eta: f32) -> f32 {
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if (sin_t2 >= 1.0) {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin_t2);
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// A ray still to follow: origin, direction, the weight its radiance carries, its depth, and
// the object it leaves into the open (NO_OBJECT for the eye's rays and rays into glass).
struct Pending {
    origin: vec3<f32>,
    depth: u32,
    dir: vec3<f32>,
    source: u32,
    weight: vec3<f32>,
}

// A surface an impostor stores (a mirror's, under `--mirrors impostor`), met by a ray: where,
// its object, its shading normal, the object's material, its face normal; `found` 1 when met.
struct Stored {
    position: vec3<f32>,
    object: u32,
    normal: vec3<f32>,
    material: u32,
    face: vec3<f32>,
    found: u32,
}

fn no_stored() -> Stored {
    return Stored(vec3<f32>(0.0), 0u, vec3<f32>(0.0), 0u, vec3<f32>(0.0), 0u);
}

// The answer to a ray an object sends out into the open (`secondary_hit`, defined by the file
// compiled after this one): a hit on the scene's triangles to shade, (w = 1) the radiance
// the ray carries (a diffuse object's impostor texel), or a surface an impostor stores, shaded
// as the triangles are.
struct Answer {
    hit: Hit,
    radiance: vec4<f32>,
    stored: Stored,
}

// The rasterized primary hit at `pixel`: where it lies (the corners interpolated, as the CPU's
// raster method places it) and its distance along the ray.
struct Visible {
    hit: Hit,
    position: vec3<f32>,
}

fn visible_hit(pixel: vec2<u32>, origin: vec3<f32>, d: vec3<f32>) -> Visible {
    let texel = textureLoad(visibility, vec2<i32>(pixel), 0);
    if (texel.x == 0u) {
        return Visible(Hit(FAR, MISS, 0.0, 0.0), vec3<f32>(0.0));
    }
    let k = texel.x - 1u;
    let b1 = bitcast<f32>(texel.y);
    let b2 = bitcast<f32>(texel.z);
    let position = corners[3u * k].xyz * (1.0 - b1 - b2) + corners[3u * k + 1u].xyz * b1
        + corners[3u * k + 2u].xyz * b2;
    return Visible(Hit(dot(position - origin, d), k, b1, b2), position);
}

// The back face of glass object `object` drawn at `pixel` in Wyman's first pass: its outward
// normal, its distance from the eye, and whether one was found — as src/render/wyman.rs's
// `BackFaces` holds it.
struct Back {
    normal: vec3<f32>,
    t: f32,
    found: bool,
}

fn back_at(pixel: vec2<u32>, object: u32) -> Back {
    let none = Back(vec3<f32>(0.0), 0.0, false);
    let texel = textureLoad(backs, vec2<i32>(pixel), 0);
    if (texel.x == 0u) {
        return none;
    }
    let k = texel.x - 1u;
    let tri = triangles[k];
    if (bitcast<u32>(tri.n1.w) != object) {
        return none;
    }
    let b1 = bitcast<f32>(texel.y);
    let b2 = bitcast<f32>(texel.z);
    let b0 = 1.0 - b1 - b2;
    let position = corners[3u * k].xyz * b0 + corners[3u * k + 1u].xyz * b1
        + corners[3u * k + 2u].xyz * b2;
    let interpolated = tri.n0.xyz * b0 + tri.n1.xyz * b1 + tri.n2.xyz * b2;
    let rcp = 1.0 / length(interpolated);
    var normal = tri.ng.xyz;
    if (rcp > 0.0 && rcp <= FAR) {
        normal = interpolated * rcp;
    }
    return Back(normal, length(position - view.eye.xyz), true);
}

// The back face of `object` at the pixel `p` projects to (none off the image or behind the eye).
fn back_at_point(p: vec3<f32>, object: u32) -> Back {
    let r = vec4<f32>(p - view.eye.xyz, 0.0);
    let z = dot(view.row_t, r);
    if (z <= 0.0) {
        return Back(vec3<f32>(0.0), 0.0, false);
    }
    let uv = floor(vec2<f32>(dot(view.row_u, r), dot(view.row_v, r)) / z);
    if (uv.x < 0.0 || uv.y < 0.0 || uv.x >= f32(view.size.x) || uv.y >= f32(view.size.y)) {
        return Back(vec3<f32>(0.0), 0.0, false);
    }
    return back_at(vec2<u32>(uv), object);
}

// Wyman's leaving ray (src/render/wyman.rs's `exit_ray`) for an eye ray of direction `v` entering
// glass of index `ior` at `p1` (normal `n1` facing the eye), `d_v` the distance to the back face
// along `v` and `d_n` the interpolated per-vertex distance: the exit point and direction.
struct Exit {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

fn wyman_exit(object: u32, p1: vec3<f32>, n1: vec3<f32>, v: vec3<f32>, ior: f32, d_v: f32, d_n: f32) -> Exit {
    // Entering from outside, the ray always refracts.
    let t1 = refract_through(v, n1, 1.0 / ior).xyz;
    let theta_i = acos(clamp(-dot(v, n1), -1.0, 1.0));
    let theta_t = acos(clamp(-dot(t1, n1), -1.0, 1.0));
    var r = 1.0 / ior;
    if (theta_i > 1e-4) {
        r = theta_t / theta_i;
    }
    let p2 = p1 + t1 * (r * d_v + (1.0 - r) * d_n);
    let back = back_at_point(p2, object);
    if (!back.found) {
        return Exit(p2, t1);
    }
    let t2 = refract_through(t1, -back.normal, ior);
    if (t2.w == 0.0) {
        return Exit(p2, reflect_about(t1, -back.normal));
    }
    return Exit(p2, t2.xyz);
}

// What a primary hit leaves in the pixel's buffers.
struct Surface {
    t: f32,
    object: u32,
    normal: vec3<f32>,
}

@compute @workgroup_size(8, 8)
fn trace_pixels(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = view.size.x;
    let h = view.size.y;
    if (id.x >= w || id.y >= h) {
        return;
    }
    let pixel = id.y * w + id.x;
    let uv = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    let eye = view.eye.xyz;
    let eps = view.eye.w;
    let max_depth = view.size.z;
    var stack: array<Pending, PENDING>;
    stack[0] = Pending(eye, 0u, normalize(view.a.xyz * uv.x + view.b.xyz * uv.y + view.c.xyz), NO_OBJECT, vec3<f32>(1.0));
    var count = 1u;
    var sum = vec3<f32>(0.0);
    var first = Surface(FAR, NO_OBJECT, vec3<f32>(0.0));
    // Whether the ray being followed is the pixel's primary ray (the first popped).
    var primary = true;
    while (count > 0u) {
        count = count - 1u;
        let ray = stack[count];
        let d = ray.dir;
        let is_primary = primary;
        primary = false;
        var hit: Hit;
        var position: vec3<f32>;
        var stored = no_stored();
        if (is_primary && view.mode.x != 0u) {
            let v = visible_hit(id.xy, ray.origin, d);
            hit = v.hit;
            position = v.position;
        } else if (ray.source != NO_OBJECT) {
            let answer = secondary_hit(ray.source, Ray(ray.origin, FAR, d, 0.0));
            if (answer.radiance.w != 0.0) {
                sum = sum + ray.weight * answer.radiance.xyz;
                continue;
            }
            hit = answer.hit;
            stored = answer.stored;
            position = ray.origin + d * hit.t;
        } else {
            hit = query(Ray(ray.origin, FAR, d, 0.0), false);
            position = ray.origin + d * hit.t;
        }
        if (hit.triangle == MISS && stored.found == 0u) {
            sum = sum + ray.weight * environment(d);
            continue;
        }
        // The hit: its shading normal — on a triangle interpolated (the face's where it
        // cancels), on a stored surface as stored — turned to face the ray as
        // src/geom/optics.rs's `facing` turns it.
        var tri: Triangle;
        var b0 = 0.0;
        var normal: vec3<f32>;
        var face: vec3<f32>;
        var object: u32;
        var material_index: u32;
        if (stored.found != 0u) {
            position = stored.position;
            normal = stored.normal;
            face = stored.face;
            object = stored.object;
            material_index = stored.material;
        } else {
            tri = triangles[hit.triangle];
            b0 = 1.0 - hit.b1 - hit.b2;
            let interpolated = tri.n0.xyz * b0 + tri.n1.xyz * hit.b1 + tri.n2.xyz * hit.b2;
            let rcp = 1.0 / length(interpolated);
            normal = tri.ng.xyz;
            if (rcp > 0.0 && rcp <= FAR) {
                normal = interpolated * rcp;
            }
            face = tri.ng.xyz;
            object = bitcast<u32>(tri.n1.w);
            material_index = bitcast<u32>(tri.n0.w);
        }
        let front = dot(d, face) < 0.0;
        let ng = select(-face, face, front);
        let n = select(normal, -normal, dot(normal, ng) < 0.0);
        if (is_primary) {
            first = Surface(hit.t, object, n);
        }
        let material = materials[material_index];
        let kind = bitcast<u32>(material.color.w);
        let last = ray.depth + 1u >= max_depth;
        if (kind == DIFFUSE) {
            var albedo = material.color.xyz;
            if (material.texture.w != 0u) {
                let st = tri.uv01.xy * b0 + tri.uv01.zw * hit.b1 + tri.uv2.xy * hit.b2;
                let img = material.texture;
                albedo = albedo * bilinear(img, st * vec2<f32>(f32(img.y), f32(img.z)), true, true);
            }
            var e = ambient(n);
            if (view.size.w != 0u) {
                let l = view.sun_dir.xyz;
                let cos_l = dot(n, l);
                if (cos_l > 0.0) {
                    let shadow = query(Ray(position + ng * eps, FAR, l, 0.0), true);
                    if (shadow.triangle == MISS) {
                        e = e + view.sun.xyz * (cos_l / PI);
                    }
                }
            }
            sum = sum + ray.weight * albedo * e;
            continue;
        }
        // Mirror and glass: what they send out, followed (or the environment's at the limit).
        let tint = material.color.xyz;
        var reflected_weight = ray.weight * tint;
        if (kind == GLASS) {
            let ior = material.ior.x;
            let eta = select(ior, 1.0 / ior, front);
            let kr = fresnel(max(-dot(d, n), 0.0), eta);
            reflected_weight = ray.weight * kr;
            let t = refract_through(d, n, eta);
            if (is_primary && front && view.mode.y != 0u) {
                // Wyman's refraction: the second interface found in images, the ray leaving
                // from it into the open.
                var d_v = 0.0;
                let back = back_at(id.xy, object);
                if (back.found) {
                    d_v = max(back.t - hit.t, 0.0);
                }
                let d_n = tri.n2.w * b0 + tri.ng.w * hit.b1 + tri.uv2.z * hit.b2;
                let exit = wyman_exit(object, position, n, d, ior, d_v, d_n);
                let weight = ray.weight * (1.0 - kr) * tint * tint;
                if (last) {
                    sum = sum + weight * environment(exit.dir);
                } else if (count < PENDING) {
                    stack[count] = Pending(exit.origin + exit.dir * eps, ray.depth + 1u, exit.dir, object, weight);
                    count = count + 1u;
                }
            } else if (t.w != 0.0 && kr < 1.0) {
                let weight = ray.weight * (1.0 - kr) * tint;
                if (last) {
                    sum = sum + weight * environment(t.xyz);
                } else if (count < PENDING) {
                    // Out of the glass (into the open) when the ray met its back.
                    let source = select(object, NO_OBJECT, front);
                    stack[count] = Pending(position - ng * eps, ray.depth + 1u, t.xyz, source, weight);
                    count = count + 1u;
                }
            }
        }
        let r = reflect_about(d, n);
        if (last) {
            sum = sum + reflected_weight * environment(r);
        } else if (count < PENDING) {
            // A mirror's reflection goes into the open, and so does glass's from outside.
            let source = select(NO_OBJECT, object, kind == MIRROR || front);
            stack[count] = Pending(position + ng * eps, ray.depth + 1u, r, source, reflected_weight);
            count = count + 1u;
        }
    }
    out_color[pixel] = vec4<f32>(sum, 1.0);
    out_depth_id[pixel] = vec4<f32>(first.t, bitcast<f32>(first.object), 0.0, 0.0);
    out_normal[pixel] = vec4<f32>(first.normal, 0.0);
}
