// Thick lines as camera-facing quads: one instance per segment (two world-space end points and a
// stretch), six vertices per instance. Width is in pixels (object.params.z), so fibres stay visible at
// any zoom. Shaded across the width like a thin tube.
//
// Fibres thin and whiten as they stretch: width over the square root of the stretch (a strand keeps its
// volume), colour towards white as the stretch nears the tear stretch (object.params.w). With
// object.params.x = 1 each segment's ends are extended by half the width and the quad is cut to a
// disc: a zero-length segment draws a round dot (the cut-fibre marks, in `fs_overlay`). With
// object.params.y = 1 the line is flat, not shaded as a tube (the planned incision's marker).

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) across: f32,
    @location(1) along: f32,
    @location(2) whiten: f32,
};

@vertex
fn vs_main(
    @builtin(vertex_index) vi: u32,
    @location(0) a: vec3<f32>,
    @location(1) b: vec3<f32>,
    @location(2) stretch: f32,
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
        gone.along = 0.0;
        gone.whiten = 0.0;
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
    let s = max(stretch, 1.0);
    let width = max(object.params.z * camera.viewport.w / sqrt(s), 1.0);
    let dot_mode = object.params.x > 0.5;
    let extend = select(0.0, width, dot_mode) * (t * 2.0 - 1.0);
    p = vec4<f32>(p.xy + (perp * side * width + d * extend) / vp * p.w, p.zw);
    var out: VsOut;
    out.clip = p;
    out.across = side;
    // Along the quad in half-widths from its middle: ±1 at the extended ends of a dot.
    out.along = select(0.0, t * 2.0 - 1.0, dot_mode) * (dl + 2.0 * width) / max(2.0 * width, 1e-6);
    let tear = object.params.w;
    out.whiten = select(0.0, smoothstep(1.0, tear, s), tear > 1.0);
    return out;
}

// Fibres, stubs and flat lines (the planned incision). No `discard` here: a shader that may discard
// makes a software rasteriser shade a pixel before its depth test, and most fibres lie hidden under
// the upper layer.
@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    return line_color(in);
}

fn line_color(in: VsOut) -> vec4<f32> {
    let tube = 1.0 - 0.45 * in.across * in.across;
    let shade = select(tube, 1.0, object.params.y > 0.5);
    let c = mix(object.color.rgb, vec3<f32>(1.0, 0.98, 0.95), in.whiten * 0.85);
    return output(c * shade, object.color.a);
}

// The overlay (cut marks as round dots, the cut path), drawn without a depth test.
@fragment
fn fs_overlay(in: VsOut) -> @location(0) vec4<f32> {
    if object.params.x > 0.5 && in.across * in.across + in.along * in.along > 1.0 {
        discard;
    }
    return line_color(in);
}
