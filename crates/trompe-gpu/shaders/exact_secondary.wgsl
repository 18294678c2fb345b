// What the `trace` method answers the rays mirrors and glass send out into the open with: the
// exact BVH, as every other ray (compiled after trace.wgsl, which calls it).

fn secondary_hit(source: u32, ray: Ray) -> Answer {
    return Answer(query(ray, false), vec4<f32>(0.0), no_stored());
}
