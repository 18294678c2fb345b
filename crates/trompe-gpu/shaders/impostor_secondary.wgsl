// What the impostor methods answer the rays mirrors and glass send out into the open with
// (paper 1 §6; the library's src/render/impostor.rs): the impostors of what the object sees,
// each walked (walk.wgsl), and the mirror and glass objects it sees exactly, through the BVH's
// triangles of class SPECULAR; the nearest answer wins, an impostor's on a tie. An impostor's
// hit carries the colour its texel stores. Compiled after trace.wgsl and walk.wgsl.

// Per object o: [2o] its first entry in this array, [2o + 1] how many impostors it sees, with
// the top bit set where it sees the mirror and glass objects exactly; then the lists of
// impostor indices.
@group(0) @binding(18) var<storage, read> reflectors: array<u32>;

const SPECULAR: u32 = 2u;
const SEES_EXACTLY: u32 = 0x80000000u;

fn secondary_hit(source: u32, ray: Ray) -> Answer {
    let first = reflectors[2u * source];
    let word = reflectors[2u * source + 1u];
    let count = word & ~SEES_EXACTLY;
    var best = no_walk_hit();
    for (var i = 0u; i < count; i = i + 1u) {
        let h = walk_impostor(reflectors[first + i], ray.origin, ray.dir, FAR);
        if (h.record != NO_TEXEL && (best.record == NO_TEXEL || h.t < best.t)) {
            best = h;
        }
    }
    var exact = Hit(FAR, MISS, 0.0, 0.0);
    if ((word & SEES_EXACTLY) != 0u) {
        exact = query_classes(ray, false, SPECULAR);
    }
    if (best.record != NO_TEXEL && (exact.triangle == MISS || best.t <= exact.t)) {
        return Answer(Hit(best.t, MISS, 0.0, 0.0), vec4<f32>(walk_looks[2u * best.record + 1u].xyz, 1.0));
    }
    return Answer(exact, vec4<f32>(0.0));
}
