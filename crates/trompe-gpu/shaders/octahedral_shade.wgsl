// The `octahedral` method's shading on the GPU: what shaders/octahedral_impostor.wgsl drew
// through the eye (base colour, blended normal and object id a pixel, the nearest surface the
// alpha test kept) shaded as the library's src/octahedral/scene.rs shades it — the one shading
// path of every method with the blended normal, unshadowed (an atlas holds no occluder), every
// bounce of a mirror or glass the environment's. Compiled after bvh.wgsl, trace.wgsl and
// exact_secondary.wgsl, whose view, materials (here one an object) and lighting it reads.

@group(0) @binding(21) var drawn_color: texture_2d<f32>;
@group(0) @binding(22) var drawn_normal: texture_2d<f32>;
@group(0) @binding(23) var drawn_object: texture_2d<u32>;

@compute @workgroup_size(8, 8)
fn shade_atlases(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = view.size.x;
    let h = view.size.y;
    if (id.x >= w || id.y >= h) {
        return;
    }
    let pixel = id.y * w + id.x;
    let uv = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    let d = normalize(view.a.xyz * uv.x + view.b.xyz * uv.y + view.c.xyz);
    let object = textureLoad(drawn_object, id.xy, 0).r;
    out_depth_id[pixel] = vec4<f32>(0.0, bitcast<f32>(object), 0.0, 0.0);
    if (object == NO_OBJECT) {
        out_color[pixel] = vec4<f32>(environment(d), 1.0);
        return;
    }
    let albedo = textureLoad(drawn_color, id.xy, 0).xyz;
    let blended = normalize(textureLoad(drawn_normal, id.xy, 0).xyz);
    // src/geom/optics.rs's `facing`, the blended normal both shading and geometric.
    let front = dot(d, blended) < 0.0;
    let n = select(-blended, blended, front);
    let material = materials[object];
    let kind = bitcast<u32>(material.color.w);
    var radiance: vec3<f32>;
    if (kind == DIFFUSE) {
        var e = ambient(n);
        if (view.size.w != 0u) {
            let cos_l = dot(n, view.sun_dir.xyz);
            if (cos_l > 0.0) {
                e = e + view.sun.xyz * (cos_l / PI);
            }
        }
        radiance = albedo * e;
    } else if (kind == MIRROR) {
        radiance = material.color.xyz * environment(reflect_about(d, n));
    } else {
        let ior = material.ior.x;
        let eta = select(ior, 1.0 / ior, front);
        let kr = fresnel(max(-dot(d, n), 0.0), eta);
        let t = refract_through(d, n, eta);
        var transmitted = vec3<f32>(0.0);
        if (t.w != 0.0 && kr < 1.0) {
            transmitted = material.color.xyz * environment(t.xyz);
        }
        radiance = kr * environment(reflect_about(d, n)) + (1.0 - kr) * transmitted;
    }
    out_color[pixel] = vec4<f32>(radiance, 1.0);
}
