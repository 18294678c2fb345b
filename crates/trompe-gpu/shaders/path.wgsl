// The image of a ray segment through an impostor's camera, in closed form (paper 1 §3.2,
// §3.4; the library's src/impostor/path.rs, in f32): a projective camera (pinhole,
// orthographic, one frustum of a graph camera) images it as one straight piece; a SPOC as a
// straight piece nearer than z_n and a branch of a hyperbola on its ramp, cut where a
// coordinate turns, so both image coordinates are monotone on every piece. walk.wgsl follows
// these pieces texel by texel; this file is compiled before it.
//
// Invariants: every piece's s is positive; consecutive pieces meet; the world point and gd at
// s are those the camera gives.

// Most pieces a path has: the straight part before the SPOC's ramp, and the ramp cut at the
// turning points of its two coordinates.
const MAX_PIECES: u32 = 4u;

// A stretch of an image path on which both image coordinates are monotone:
// uv(s) = p + r·s + q/s from `start` to `end` (walk order; s may decrease).
struct Piece {
    p: vec2<f32>,
    r: vec2<f32>,
    q: vec2<f32>,
    start: f32,
    end: f32,
}

// A ray's image path (src/impostor/path.rs): its monotone pieces in walk order, the world
// point x0 + x1·s and gd = g.x + g.y·s + g.z/s.
struct Path {
    pieces: array<Piece, MAX_PIECES>,
    count: u32,
    x0: vec3<f32>,
    x1: vec3<f32>,
    g: vec3<f32>,
}

fn piece_uv(pc: Piece, s: f32) -> vec2<f32> {
    return pc.p + pc.r * s + pc.q / s;
}

fn path_gd(path: Path, s: f32) -> f32 {
    return path.g.x + path.g.y * s + path.g.z / s;
}

// The parameter where coordinate `axis` of the piece equals x, clamped onto the piece (y = 1),
// or y = 0 where the piece does not reach it.
fn piece_crossing(pc: Piece, axis: u32, x: f32) -> vec2<f32> {
    let a = pc.r[axis];
    let b = pc.p[axis] - x;
    let c = pc.q[axis];
    let lo = min(pc.start, pc.end);
    let hi = max(pc.start, pc.end);
    let slack = (hi - lo) * 1e-6;
    var roots = vec2<f32>(-1.0);
    if (a == 0.0) {
        // Straight: p + q/s = x.
        if (b == 0.0) {
            return vec2<f32>(0.0);
        }
        roots = vec2<f32>(-c / b, -1.0);
    } else if (c == 0.0) {
        // Affine: p + r·s = x.
        roots = vec2<f32>(-b / a, -1.0);
    } else {
        // Both roots of a·s² + b·s + c without cancellation; no real root: the coordinate
        // turns before reaching x.
        let disc = b * b - 4.0 * a * c;
        if (disc < 0.0) {
            return vec2<f32>(0.0);
        }
        let t = -0.5 * (b + select(sqrt(disc), -sqrt(disc), b < 0.0));
        if (t == 0.0) {
            return vec2<f32>(0.0);
        }
        roots = vec2<f32>(t / a, c / t);
    }
    // (Every piece's s is positive: the −1 of a missing root is never on one.)
    for (var i = 0u; i < 2u; i = i + 1u) {
        let s = roots[i];
        if (s >= lo - slack && s <= hi + slack) {
            return vec2<f32>(clamp(s, lo, hi), 1.0);
        }
    }
    return vec2<f32>(0.0);
}

struct ImagePoint {
    uv: vec2<f32>,
    gd: f32,
    inv_w: f32,
    ok: bool,
}

// A projective camera (pinhole, orthographic, one frustum of a graph camera, a SPOC's
// pinhole) as rows.
struct Projective {
    u: vec4<f32>,
    v: vec4<f32>,
    w: vec4<f32>,
    g: vec4<f32>,
    clip: vec4<f32>,
    ortho: bool,
}

fn camera_of(imp: WalkImpostor) -> Projective {
    return Projective(imp.u_row, imp.v_row, imp.w_row, imp.g_row, imp.clip_row, imp.info.z == ORTHOGRAPHIC);
}

fn project(cam: Projective, p: vec3<f32>) -> ImagePoint {
    let h = vec4<f32>(p, 1.0);
    let u = dot(cam.u, h);
    let v = dot(cam.v, h);
    if (cam.ortho) {
        // The library's orthographic camera refuses points behind its image plane.
        return ImagePoint(vec2<f32>(u, v), dot(cam.g, h), 1.0, dot(cam.clip, h) >= 0.0);
    }
    let w = dot(cam.w, h);
    if (w <= 0.0) {
        return ImagePoint(vec2<f32>(0.0), 0.0, 0.0, false);
    }
    let gd = 1.0 / w;
    return ImagePoint(vec2<f32>(u * gd, v * gd), gd, gd, true);
}

fn one_piece(piece: Piece, x0: vec3<f32>, x1: vec3<f32>, g: vec3<f32>) -> Path {
    var pieces: array<Piece, MAX_PIECES>;
    pieces[0] = piece;
    return Path(pieces, 1u, x0, x1, g);
}

// The image path of the world segment [c, e] through a projective camera that images its ends
// at pc, pe: one straight piece.
fn projective_path(c: vec3<f32>, e: vec3<f32>, pc: ImagePoint, pe: ImagePoint) -> Path {
    let wc = 1.0 / pc.inv_w;
    let we = 1.0 / pe.inv_w;
    if (abs(we - wc) > 1e-6 * max(abs(wc), abs(we))) {
        // s = w: the homogeneous image w·uv is affine in w.
        let dw = we - wc;
        let x1 = (e - c) / dw;
        let h1 = (pe.uv * we - pc.uv * wc) / dw;
        let piece = Piece(h1, vec2<f32>(0.0), pc.uv * wc - h1 * wc, wc, we);
        return one_piece(piece, c - x1 * wc, x1, vec3<f32>(0.0, 0.0, 1.0));
    }
    // One depth along the segment: s = 1 + λ, image and gd affine in it.
    let d = pe.uv - pc.uv;
    let piece = Piece(pc.uv - d, d, vec2<f32>(0.0), 1.0, 2.0);
    let dg = pe.gd - pc.gd;
    return one_piece(piece, c - (e - c), e - c, vec3<f32>(pc.gd - dg, dg, 0.0));
}

// The SPOC's depth ramp κ(z).
fn kappa(imp: WalkImpostor, z: f32) -> f32 {
    return imp.g_row.w * max(z - imp.g_row.z, 0.0);
}

// The path of [c, e] through a SPOC whose pinhole images its ends at qc, qe: straight nearer
// than z_n, a branch of a hyperbola on the ramp, cut where a coordinate turns
// (src/impostor/path.rs's `ImagePath::spoc`).
fn spoc_path(imp: WalkImpostor, c: vec3<f32>, e: vec3<f32>, qc: ImagePoint, qe: ImagePoint) -> Path {
    let base = projective_path(c, e, qc, qe);
    let p0 = imp.g_row.xy;
    let f = imp.m_a.w;
    let straight = base.pieces[0];
    if (base.g.z == 0.0) {
        // One depth along the whole segment: one scaling about the pole.
        let scale = 1.0 + kappa(imp, f * 0.5 * (1.0 / qc.gd + 1.0 / qe.gd));
        let piece = Piece(p0 + (straight.p - p0) * scale, straight.r * scale, straight.q, straight.start, straight.end);
        return one_piece(piece, base.x0, base.x1, base.g);
    }
    let z_near = imp.g_row.z;
    let slope = imp.g_row.w;
    let alpha = 1.0 - slope * z_near;
    let beta = slope * f;
    let a = straight.p;
    let b = straight.q;
    let ramp = Piece(p0 + (a - p0) * alpha + b * beta, (a - p0) * beta, b * alpha, straight.start, straight.end);
    // The ramp starts at eye depth z_n: s = z_n / f.
    let s_near = z_near / f;
    let lo = min(straight.start, straight.end);
    let hi = max(straight.start, straight.end);
    var parts: array<Piece, 2>;
    var n = 0u;
    if (lo < s_near) {
        parts[n] = Piece(straight.p, straight.r, straight.q, lo, min(hi, s_near));
        n = n + 1u;
    }
    if (hi > s_near) {
        parts[n] = Piece(ramp.p, ramp.r, ramp.q, max(lo, s_near), hi);
        n = n + 1u;
    }
    if (straight.start > straight.end) {
        if (n == 2u) {
            let first = parts[0];
            parts[0] = parts[1];
            parts[1] = first;
        }
        for (var i = 0u; i < n; i = i + 1u) {
            let swap = parts[i].start;
            parts[i].start = parts[i].end;
            parts[i].end = swap;
        }
    }
    // Cut each where a coordinate turns: u′(s) = r − q/s² vanishes at s² = q/r.
    var path: Path;
    path.count = 0u;
    path.x0 = base.x0;
    path.x1 = base.x1;
    path.g = base.g;
    for (var i = 0u; i < n; i = i + 1u) {
        let pc = parts[i];
        let plo = min(pc.start, pc.end);
        let phi = max(pc.start, pc.end);
        let toward = select(-1.0, 1.0, pc.end > pc.start);
        var cuts = vec2<f32>(-1.0);
        for (var k = 0u; k < 2u; k = k + 1u) {
            let ratio = pc.q[k] / pc.r[k];
            if (pc.r[k] != 0.0 && ratio > 0.0 && ratio <= WALK_FAR) {
                let s = sqrt(ratio);
                if (s > plo && s < phi) {
                    cuts[k] = s;
                }
            }
        }
        // In walk order.
        if (cuts.x >= 0.0 && cuts.y >= 0.0 && (cuts.y - pc.start) * toward < (cuts.x - pc.start) * toward) {
            cuts = cuts.yx;
        } else if (cuts.x < 0.0) {
            cuts = cuts.yx;
        }
        var from_s = pc.start;
        for (var k = 0u; k < 3u; k = k + 1u) {
            var cut = pc.end;
            if (k < 2u) {
                if (cuts[k] < 0.0) {
                    continue;
                }
                cut = cuts[k];
            }
            if (cut != from_s && path.count < MAX_PIECES) {
                path.pieces[path.count] = Piece(pc.p, pc.r, pc.q, from_s, cut);
                path.count = path.count + 1u;
                from_s = cut;
            }
        }
    }
    return path;
}
