// Shared by the dissect scene shaders: the per-view camera (group 0) and the per-draw object (group 1).
// Prepended with concat!() to each shader file; keep the structs in step with
// `CameraUniform` and `ObjectUniform` in `src/render/scene.rs`.

struct Camera {
    view_proj: mat4x4<f32>,
    // xyz: eye position, world space.
    eye: vec4<f32>,
    // xyz: unit direction towards the key light (a headlight just above and left of the eye).
    light: vec4<f32>,
    // x, y: viewport size in pixels; z: 1 when the shader must encode sRGB itself (non-sRGB target);
    // w: line width scale for this view's height.
    viewport: vec4<f32>,
    // xyz: unit direction towards the overhead lamp, which casts the instruments' shadows; w: shadow
    // strength (0 turns shadows off).
    lamp: vec4<f32>,
    // Up to two shadow casters as capsules: [2k] = (tip xyz, radius), [2k + 1] = (end xyz, 1 if used).
    casters: array<vec4<f32>, 4>,
    // Up to four regions in surface fractions: rect (u0, u1, v0, v1) or disc (cu, cv, radius, 0).
    regions: array<vec4<f32>, 4>,
    // Per region: 0 unused, 1 target rect, 2 forbidden rect, 3 target disc, 4 forbidden disc.
    region_kinds: vec4<f32>,
};

struct Object {
    model: mat4x4<f32>,
    // Linear RGBA.
    color: vec4<f32>,
    // Meshes: x specular strength, y shininess, z (solids) 1 for polished steel. Lines: z width in
    // pixels, w stretch at which fibres tear (0: none), x 1 for round dots, y 1 for a flat (untubed)
    // line.
    params: vec4<f32>,
    // Tissue: xy texture repeats per unit of surface fraction along u and v.
    extra: vec4<f32>,
    // Tissue: rgb the colour of the pattern's vessels (linear).
    detail: vec4<f32>,
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
