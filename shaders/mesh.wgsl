// Lit triangle meshes: tissue layers and instrument parts. Both sides of a sheet are drawn (cull none);
// the normal is turned towards the viewer, and the side facing away from the given normal (the inner side
// of a layer) is shaded a little darker so an undercut edge reads.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VsOut {
    var out: VsOut;
    let world = object.model * vec4<f32>(position, 1.0);
    out.world = world.xyz;
    out.normal = (object.model * vec4<f32>(normal, 0.0)).xyz;
    out.clip = camera.view_proj * world;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let v = normalize(camera.eye.xyz - in.world);
    var n = in.normal;
    let len = length(n);
    n = select(v, n / len, len > 1e-6);
    // Back side: flip the normal towards the viewer and darken slightly.
    let back = dot(n, v) < 0.0;
    n = select(n, -n, back);
    let side = select(1.0, 0.78, back);
    let l = camera.light.xyz;
    let diffuse = max(dot(n, l), 0.0);
    let h = normalize(l + v);
    let spec = object.params.x * pow(max(dot(n, h), 0.0), max(object.params.y, 1.0));
    // Soft fill from above so surfaces turned away from the key light are not flat black.
    let fill = 0.12 * max(n.y, 0.0);
    let base = object.color.rgb * side;
    let lit = base * (0.22 + 0.70 * diffuse + fill) + vec3<f32>(spec);
    return output(lit, object.color.a);
}
