// The viewer's window on the GPU (crates/trompe-gpu/src/present.rs): the frame, its overlay
// already drawn into it, copied texel for texel onto the surface by one triangle that covers
// the screen. The frame arrives sRGB-encoded, as the CPU window shows it; its texture is read
// through the view that matches the surface's encoding, so the bytes shown are the bytes sent.

@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn cover(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (−1, −1), (3, −1), (−1, 3): one triangle over the whole screen.
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn shown(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(textureLoad(frame, vec2<i32>(at.xy), 0).rgb, 1.0);
}
