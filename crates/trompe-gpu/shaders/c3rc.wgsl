// The continuous 3-ray camera's projection on the GPU (paper 2, "Hybrid backward-forward
// reflection rendering with continuous 3-ray cameras" §3–5; docs/conventions.md §7), as the
// library's src/camera/c3rc/mod.rs projects them: a point q projects where the
// sweeping triangle T(λ) = (vᵢ + λ dᵢ) passes through it, the real roots of the cubic
// n(λ)·(q − v₀ − λ d₀) with n(λ) = n₀ + λ n₁ + λ² n₂, whose barycentrics lie inside the
// triangle — every one of them, up to three.
//
// The arithmetic is in `real`, which the loader (src/hybrid.rs) defines before this file with
// its tolerances: f64 where the adapter has 64-bit floats, as the CPU computes (only the
// trigonometric first guesses are f32, polished by Newton steps in f64), else f32 — where roots
// that nearly coincide, at a fold of the sweep, lose digits. The camera comes as f64 values
// split into two f32 (hi + lo), exact in f64.
//
// Pure functions: a file that includes this one binds its own inputs.

// A camera as uploaded: its vertices, unit construction rays and its sweep normal's three
// terms, computed in f64 on the CPU, each the f32 sum hi + lo (lo: what f32 rounding left
// out); v[0].w is the largest sweep parameter (FAR for none), v[1].w the reflector object's
// id (bits).
struct C3rc {
    v: array<vec4<f32>, 3>,
    d: array<vec4<f32>, 3>,
    n: array<vec4<f32>, 3>,
    v_lo: array<vec4<f32>, 3>,
    d_lo: array<vec4<f32>, 3>,
    n_lo: array<vec4<f32>, 3>,
}

// Tolerance on barycentrics for a projection to count as inside the base triangle.
const C3RC_BARY_EPS: real = 1e-9;
const C3RC_LARGEST: real = 3.4028235e38;

fn c3rc_wide(hi: vec4<f32>, lo: vec4<f32>) -> vec3<real> {
    return vec3<real>(hi.xyz) + vec3<real>(lo.xyz);
}

// At most three roots, in increasing order.
struct C3rcRoots {
    r: array<real, 3>,
    len: u32,
}

// One projection: its sweep parameter and barycentrics.
struct C3rcProjection {
    lambda: f32,
    bary: vec3<f32>,
}

// Up to three projections, nearest sweep first.
struct C3rcProjections {
    p: array<C3rcProjection, 3>,
    len: u32,
}

fn c3rc_push(roots: ptr<function, C3rcRoots>, x: real) {
    // NaN and ±∞ fail both tests.
    if ((*roots).len < 3u && abs(x) <= C3RC_LARGEST) {
        (*roots).r[(*roots).len] = x;
        (*roots).len = (*roots).len + 1u;
    }
}

// Real roots of the monic cubic x³ + a x² + b x + c (trigonometric form for three, Cardano's
// for one).
fn c3rc_monic_roots(a: real, b: real, c: real) -> C3rcRoots {
    var roots = C3rcRoots(array<real, 3>(0.0, 0.0, 0.0), 0u);
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    let shift = a / 3.0;
    let q3 = q * q * q;
    if (r * r < q3) {
        // The angle and cosines in f32 (the only precision they come in): first guesses.
        let theta = acos(f32(clamp(r / sqrt(q3), -1.0, 1.0)));
        let m = -2.0 * sqrt(q);
        for (var k = 0u; k < 3u; k = k + 1u) {
            c3rc_push(&roots, m * real(cos((theta + 6.283185307179586 * f32(k)) / 3.0)) - shift);
        }
    } else {
        let big = abs(r) + sqrt(r * r - q3);
        // The cube root's f32 guess, made exact by two Newton steps on s³ = big.
        var s = real(pow(f32(big), 1.0 / 3.0));
        for (var k = 0u; k < 2u; k = k + 1u) {
            if (s > 0.0) {
                s = s - (s * s * s - big) / (3.0 * s * s);
            }
        }
        if (r > 0.0) {
            s = -s;
        }
        var t: real = 0.0;
        if (s != 0.0) {
            t = q / s;
        }
        c3rc_push(&roots, s + t - shift);
    }
    return roots;
}

// The real roots of c.x + c.y x + c.z x² + c.w x³, falling back to lower degrees where leading
// coefficients vanish relative to the largest, each polished by Newton steps; sorted,
// duplicates merged.
fn c3rc_roots(c_in: vec4<real>) -> C3rcRoots {
    var out = C3rcRoots(array<real, 3>(0.0, 0.0, 0.0), 0u);
    let scale = max(max(abs(c_in.x), abs(c_in.y)), max(abs(c_in.z), abs(c_in.w)));
    if (!(scale > 0.0 && scale <= C3RC_LARGEST)) {
        return out;
    }
    let c = c_in / scale;
    var roots = C3rcRoots(array<real, 3>(0.0, 0.0, 0.0), 0u);
    if (abs(c.w) > C3RC_TINY) {
        roots = c3rc_monic_roots(c.z / c.w, c.y / c.w, c.x / c.w);
    } else if (abs(c.z) > C3RC_TINY) {
        let disc = c.y * c.y - 4.0 * c.z * c.x;
        if (disc >= 0.0) {
            // The stable form: no cancellation between −b and √disc.
            var sign: real = 1.0;
            if (c.y < 0.0) {
                sign = -1.0;
            }
            let s = -0.5 * (c.y + sign * sqrt(disc));
            if (s == 0.0) {
                c3rc_push(&roots, 0.0);
            } else {
                c3rc_push(&roots, s / c.z);
                c3rc_push(&roots, c.x / s);
            }
        }
    } else if (abs(c.y) > C3RC_TINY) {
        c3rc_push(&roots, -c.x / c.y);
    }
    // Newton steps, on the cubic whatever the degree used.
    var polished = C3rcRoots(array<real, 3>(0.0, 0.0, 0.0), 0u);
    for (var i = 0u; i < roots.len; i = i + 1u) {
        var x = roots.r[i];
        for (var k = 0u; k < 3u; k = k + 1u) {
            let f = ((c.w * x + c.z) * x + c.y) * x + c.x;
            let df = (3.0 * c.w * x + 2.0 * c.z) * x + c.y;
            if (abs(df) > 1e-30) {
                let next = x - f / df;
                if (abs(next) <= C3RC_LARGEST) {
                    x = next;
                }
            }
        }
        c3rc_push(&polished, x);
    }
    // Sorted (three at most), then duplicates merged.
    for (var i = 1u; i < polished.len; i = i + 1u) {
        for (var j = i; j > 0u && polished.r[j - 1u] > polished.r[j]; j = j - 1u) {
            let t = polished.r[j];
            polished.r[j] = polished.r[j - 1u];
            polished.r[j - 1u] = t;
        }
    }
    for (var i = 0u; i < polished.len; i = i + 1u) {
        let x = polished.r[i];
        if (out.len == 0u || abs(x - out.r[out.len - 1u]) > C3RC_MERGE * (1.0 + abs(out.r[out.len - 1u]))) {
            c3rc_push(&out, x);
        }
    }
    return out;
}

// Every projection of q through `cam` with lambda_min ≤ λ ≤ lambda_max, nearest sweep first.
fn c3rc_project(cam: C3rc, q: vec3<f32>, lambda_min: f32, lambda_max: f32) -> C3rcProjections {
    var out = C3rcProjections(array<C3rcProjection, 3>(
        C3rcProjection(0.0, vec3<f32>(0.0)),
        C3rcProjection(0.0, vec3<f32>(0.0)),
        C3rcProjection(0.0, vec3<f32>(0.0)),
    ), 0u);
    let v0 = c3rc_wide(cam.v[0], cam.v_lo[0]);
    let v1 = c3rc_wide(cam.v[1], cam.v_lo[1]);
    let v2 = c3rc_wide(cam.v[2], cam.v_lo[2]);
    let d0 = c3rc_wide(cam.d[0], cam.d_lo[0]);
    let d1 = c3rc_wide(cam.d[1], cam.d_lo[1]);
    let d2 = c3rc_wide(cam.d[2], cam.d_lo[2]);
    let n0 = c3rc_wide(cam.n[0], cam.n_lo[0]);
    let n1 = c3rc_wide(cam.n[1], cam.n_lo[1]);
    let n2 = c3rc_wide(cam.n[2], cam.n_lo[2]);
    let wq = vec3<real>(q);
    let r = wq - v0;
    let coefficients = vec4<real>(
        dot(n0, r),
        dot(n1, r) - dot(n0, d0),
        dot(n2, r) - dot(n1, d0),
        -dot(n2, d0),
    );
    let roots = c3rc_roots(coefficients);
    for (var i = 0u; i < roots.len; i = i + 1u) {
        var lambda = roots.r[i];
        // A root a rounding error below 0 is the base itself.
        if (lambda < 0.0 && lambda > -C3RC_SNAP) {
            lambda = 0.0;
        }
        if (!(lambda >= real(lambda_min) && lambda <= real(lambda_max))) {
            continue;
        }
        let t0 = v0 + d0 * lambda;
        let a = v1 + d1 * lambda - t0;
        let b = v2 + d2 * lambda - t0;
        let w = wq - t0;
        let n = cross(a, b);
        let nn = dot(n, n);
        if (!(nn > 1.1754944e-38)) {
            continue;
        }
        let b2 = dot(cross(w, b), n) / nn;
        let b3 = dot(cross(a, w), n) / nn;
        let bary = vec3<real>(1.0 - b2 - b3, b2, b3);
        if (min(bary.x, min(bary.y, bary.z)) < -C3RC_BARY_EPS) {
            continue;
        }
        out.p[out.len] = C3rcProjection(f32(lambda), vec3<f32>(bary));
        out.len = out.len + 1u;
    }
    return out;
}
