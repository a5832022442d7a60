// Full-screen vertical gradient behind the scene: one triangle covering the viewport, no vertex buffer.
// Dark teal like surgical drapes, so tan and pink tissue reads against it.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) height: f32,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let x = f32((vi << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vi & 2u) * 2.0 - 1.0;
    var out: VsOut;
    out.clip = vec4<f32>(x, y, 1.0, 1.0);
    out.height = y * 0.5 + 0.5;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let top = vec3<f32>(0.055, 0.11, 0.12);
    let bottom = vec3<f32>(0.008, 0.018, 0.022);
    return output(mix(bottom, top, clamp(in.height, 0.0, 1.0)), 1.0);
}
