// What the impostor methods answer the rays mirrors and glass send out into the open with
// (paper 1 §6; the library's src/render/impostor.rs): the impostors of what the object sees,
// each walked (walk.wgsl), and the mirror and glass objects it sees exactly through the BVH —
// all of them (the triangles of class SPECULAR), or, where the other mirrors are impostors
// (`--mirrors impostor`), itself and the glass; the nearest answer wins, an impostor's on a tie.
// A diffuse object's impostor answers with the colour its texel stores; a mirror's with the
// surface it stores (where, its normals, its object), which the tracer reflects on. Compiled
// after trace.wgsl and walk.wgsl.

// Per object o: [3o] its first entry in this array, [3o + 1] how many impostors it sees, with
// the top bits saying what it sees exactly, [3o + 2] its first material; then the lists of
// impostor indices.
@group(0) @binding(18) var<storage, read> reflectors: array<u32>;

const SPECULAR: u32 = 2u;
const GLASS_CLASS: u32 = 4u;
const SEES_EXACTLY: u32 = 0x80000000u;
const SEES_GLASS_AND_ITSELF: u32 = 0x40000000u;

// A direction where impostor `imp` was built, now.
fn now_vector(imp: WalkImpostor, v: vec3<f32>) -> vec3<f32> {
    if ((imp.info.w & MOVED) == 0u) {
        return v;
    }
    let m = imp.now_from_built;
    return vec3<f32>(dot(m[0].xyz, v), dot(m[1].xyz, v), dot(m[2].xyz, v));
}

fn secondary_hit(source: u32, ray: Ray) -> Answer {
    let first = reflectors[3u * source];
    let word = reflectors[3u * source + 1u];
    let count = word & ~(SEES_EXACTLY | SEES_GLASS_AND_ITSELF);
    var best = no_walk_hit();
    var best_impostor = 0u;
    for (var i = 0u; i < count; i = i + 1u) {
        let index = reflectors[first + i];
        let h = walk_impostor(index, ray.origin, ray.dir, FAR);
        if (h.record != NO_TEXEL && (best.record == NO_TEXEL || h.t < best.t)) {
            best = h;
            best_impostor = index;
        }
    }
    var exact = Hit(FAR, MISS, 0.0, 0.0);
    if ((word & SEES_EXACTLY) != 0u) {
        exact = query_classes(ray, false, SPECULAR);
    } else if ((word & SEES_GLASS_AND_ITSELF) != 0u) {
        exact = query_selected(ray, false, GLASS_CLASS, source);
    }
    if (best.record != NO_TEXEL && (exact.triangle == MISS || best.t <= exact.t)) {
        let imp = walk_impostors[best_impostor];
        if ((imp.info.w & RADIANCE) != 0u) {
            return Answer(Hit(best.t, MISS, 0.0, 0.0), vec4<f32>(walk_looks[2u * best.record + 1u].xyz, 1.0), no_stored());
        }
        let look = walk_looks[2u * best.record];
        let object = bitcast<u32>(look.w);
        let stored = Stored(
            best.position,
            object,
            now_vector(imp, look.xyz),
            reflectors[3u * object + 2u],
            now_vector(imp, walk_planes[2u * best.record + 1u].xyz),
            1u,
        );
        return Answer(Hit(best.t, MISS, 0.0, 0.0), vec4<f32>(0.0), stored);
    }
    return Answer(exact, vec4<f32>(0.0), no_stored());
}
