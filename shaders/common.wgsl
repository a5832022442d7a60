// Shared by the dissect scene shaders: the per-view camera (group 0) and the per-draw object (group 1).
// Prepended with concat!() to each shader file; keep the structs in step with `src/render/gpu_types.rs`.

struct Camera {
    view_proj: mat4x4<f32>,
    // xyz: eye position, world space.
    eye: vec4<f32>,
    // xyz: unit direction towards the key light (a headlight just above and left of the eye).
    light: vec4<f32>,
    // x, y: viewport size in pixels; z: 1 when the shader must encode sRGB itself (non-sRGB target).
    viewport: vec4<f32>,
};

struct Object {
    model: mat4x4<f32>,
    // Linear RGBA.
    color: vec4<f32>,
    // x: specular strength, y: shininess, z: line width in pixels (lines only).
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<uniform> object: Object;

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

// Final colour for the render target: encodes sRGB when the target format does not.
fn output(c: vec3<f32>, a: f32) -> vec4<f32> {
    let clamped = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    if camera.viewport.z > 0.5 {
        return vec4<f32>(linear_to_srgb(clamped), a);
    }
    return vec4<f32>(clamped, a);
}
