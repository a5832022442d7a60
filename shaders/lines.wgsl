// Thick lines as camera-facing quads: one instance per segment (two world-space end points), six vertices
// per instance. Width is in pixels (object.params.z), so fibres stay visible at any zoom. Shaded across
// the width like a thin tube.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) across: f32,
};

@vertex
fn vs_main(
    @builtin(vertex_index) vi: u32,
    @location(0) a: vec3<f32>,
    @location(1) b: vec3<f32>,
) -> VsOut {
    // Two triangles: (0,-) (1,-) (1,+)  (0,-) (1,+) (0,+)
    var ends = array<f32, 6>(0.0, 1.0, 1.0, 0.0, 1.0, 0.0);
    var sides = array<f32, 6>(-1.0, -1.0, 1.0, -1.0, 1.0, 1.0);
    let t = ends[vi];
    let side = sides[vi];
    var ca = camera.view_proj * vec4<f32>(a, 1.0);
    var cb = camera.view_proj * vec4<f32>(b, 1.0);
    // Clip the segment against a plane just in front of the eye so an end behind the camera does not
    // flip the quad across the screen; a segment wholly behind collapses to nothing.
    let eps = 1e-5;
    if ca.w < eps && cb.w < eps {
        var gone: VsOut;
        gone.clip = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        gone.across = 0.0;
        return gone;
    }
    if ca.w < eps {
        ca = mix(ca, cb, (eps - ca.w) / (cb.w - ca.w));
    } else if cb.w < eps {
        cb = mix(cb, ca, (eps - cb.w) / (ca.w - cb.w));
    }
    let vp = camera.viewport.xy;
    let sa = ca.xy / max(ca.w, 1e-6) * vp;
    let sb = cb.xy / max(cb.w, 1e-6) * vp;
    var d = sb - sa;
    let dl = length(d);
    d = select(vec2<f32>(1.0, 0.0), d / dl, dl > 1e-4);
    let perp = vec2<f32>(-d.y, d.x);
    var p = select(ca, cb, t > 0.5);
    // Width in pixels, scaled for the view height (camera.viewport.w), never under one pixel. NDC spans
    // 2 units per viewport, so one pixel is 2 / vp: offsetting by width / vp puts half on each side.
    let width = max(object.params.z * camera.viewport.w, 1.0);
    p = vec4<f32>(p.xy + perp * side * width / vp * p.w, p.zw);
    var out: VsOut;
    out.clip = p;
    out.across = side;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let shade = 1.0 - 0.45 * in.across * in.across;
    return output(object.color.rgb * shade, object.color.a);
}
