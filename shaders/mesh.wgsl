// Lit triangle meshes. Both sides of a sheet are drawn (cull none); the normal is turned towards the
// viewer, and the side facing away from the given normal (the inner side of a layer) is shaded darker.
//
// `fs_tissue` (layers): the procedural texture (group 2) in the surface's rest coordinates, a wrapped
// diffuse with a reddish tint where light grazes (light scattered under the surface), a sharp wet
// highlight over a broad sheen, the instruments' soft shadows from the overhead lamp, and the
// exercise's regions drawn on the surface. `fs_solid` (instruments, cut edges): plain or polished steel.
// Everything stays within WebGL2: uniforms, one 2D texture, no storage buffers.

@group(2) @binding(0) var tissue_texture: texture_2d<f32>;
@group(2) @binding(1) var tissue_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

@vertex
fn vs_tissue(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
) -> VsOut {
    var out: VsOut;
    out.world = position;
    out.normal = normal;
    out.uv = uv;
    out.clip = camera.view_proj * vec4<f32>(position, 1.0);
    return out;
}

@vertex
fn vs_solid(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VsOut {
    var out: VsOut;
    let world = object.model * vec4<f32>(position, 1.0);
    out.world = world.xyz;
    out.normal = (object.model * vec4<f32>(normal, 0.0)).xyz;
    out.uv = vec2<f32>(0.0);
    out.clip = camera.view_proj * world;
    return out;
}

// Light from the lamp reaching `p` past one capsule (a = tip and radius, b = end and use flag): 1 in
// the open, down to 0 in the core of the shadow; the penumbra widens with the distance to the caster.
fn capsule_light(p: vec3<f32>, l: vec3<f32>, a: vec4<f32>, b: vec4<f32>) -> f32 {
    if b.w < 0.5 {
        return 1.0;
    }
    // Closest approach between the ray p + t l (t > 0) and the segment a.xyz + s (b.xyz - a.xyz).
    let d = b.xyz - a.xyz;
    let w = p - a.xyz;
    let dd = dot(d, d);
    let dl = dot(d, l);
    let wd = dot(w, d);
    let wl = dot(w, l);
    let den = max(dd - dl * dl, 1e-12);
    let s = clamp((wd - dl * wl) / den, 0.0, 1.0);
    let q = a.xyz + s * d;
    let t = dot(q - p, l);
    if t <= 0.0 {
        return 1.0;
    }
    let gap = length(p + t * l - q);
    let soft = a.w * 0.6 + 0.18 * t;
    return smoothstep(a.w * 0.5, a.w * 0.5 + soft, gap);
}

fn shadow(p: vec3<f32>) -> f32 {
    let l = camera.lamp.xyz;
    let lit = capsule_light(p, l, camera.casters[0], camera.casters[1])
        * capsule_light(p, l, camera.casters[2], camera.casters[3]);
    return mix(1.0, lit, camera.lamp.w);
}

// 1 inside an outline band `width` pixels wide along the edge of region k, 0 elsewhere; `inside` is set
// to whether uv lies in it.
fn region_edge(k: i32, uv: vec2<f32>, px: vec2<f32>) -> vec2<f32> {
    let r = camera.regions[k];
    let kind = camera.region_kinds[k];
    var dist = 0.0;
    if kind > 2.5 {
        // Disc: signed distance in pixels through the uv derivative.
        let e = (length(uv - r.xy) - r.z) / max(length(px), 1e-9);
        dist = e;
    } else {
        let du = max(r.x - uv.x, uv.x - r.y) / max(px.x, 1e-9);
        let dv = max(r.z - uv.y, uv.y - r.w) / max(px.y, 1e-9);
        dist = max(du, dv);
    }
    let band = 1.0 - smoothstep(1.0, 2.2, abs(dist + 1.5));
    return vec2<f32>(band, select(0.0, 1.0, dist < 0.0));
}

@fragment
fn fs_tissue(in: VsOut) -> @location(0) vec4<f32> {
    let v = normalize(camera.eye.xyz - in.world);
    var n = in.normal;
    let len = length(n);
    n = select(v, n / len, len > 1e-6);
    let back = dot(n, v) < 0.0;
    n = select(n, -n, back);

    // Texture: grain (r), vessels (g), capillaries (b), mottle (a).
    let tex = textureSample(tissue_texture, tissue_sampler, in.uv * object.extra.xy);
    let pattern = object.params.z;
    var base = object.color.rgb * (0.9 + 0.2 * tex.a);
    var wet = 1.0;
    if pattern < 0.5 {
        // Dura: fine collagen grain, and the meningeal vessels faint through it.
        base = base * (0.9 + 0.16 * tex.r);
        base = mix(base, vec3<f32>(0.55, 0.12, 0.12), tex.g * 0.18);
    } else if pattern < 1.5 {
        // Arachnoid: red vessels on a translucent pink film, capillaries fainter.
        let vessel = max(tex.g, 0.45 * tex.b);
        base = mix(base, vec3<f32>(0.42, 0.03, 0.05), vessel * 0.85);
        wet = 1.0 + 0.5 * tex.g;
    }
    base = base * select(1.0, 0.72, back);

    let shade = shadow(in.world);
    let lamp = camera.lamp.xyz;
    let head = camera.light.xyz;
    // Wrapped diffuse: light bleeds a little past the terminator, as under a thin wet membrane.
    let wrap = 0.35;
    let d_lamp = max((dot(n, lamp) + wrap) / (1.0 + wrap), 0.0);
    let d_head = max((dot(n, head) + wrap) / (1.0 + wrap), 0.0);
    // Subsurface tint: light scattered inside comes out redder, most where it grazes the surface.
    let graze = 1.0 - abs(dot(n, head));
    let sss = vec3<f32>(0.9, 0.25, 0.18) * (0.1 + 0.16 * graze * graze);
    // Wet: a tight highlight over a broad sheen, both stronger at grazing angles (Fresnel).
    let fres = 0.04 + 0.96 * pow(1.0 - max(dot(n, v), 0.0), 5.0);
    let h_lamp = normalize(lamp + v);
    let h_head = normalize(head + v);
    let tight = pow(max(dot(n, h_lamp), 0.0), 90.0) * shade + pow(max(dot(n, h_head), 0.0), 120.0) * 0.7;
    let sheen = pow(max(dot(n, h_head), 0.0), 14.0);
    let spec = object.params.x * wet * (tight * 0.8 + sheen * 0.08) + 0.12 * fres;

    var lit = base * (0.16 + 0.62 * d_lamp * shade + 0.34 * d_head) + base * sss + vec3<f32>(spec);

    // Regions: a tint inside and an outline a few pixels wide (pixel widths from the uv derivatives).
    let px = fwidth(in.uv);
    for (var k = 0; k < 4; k = k + 1) {
        let kind = camera.region_kinds[k];
        if kind < 0.5 {
            continue;
        }
        let e = region_edge(k, in.uv, px);
        let forbidden = kind > 1.5 && kind < 2.5 || kind > 3.5;
        if forbidden {
            // Hatched: diagonal stripes in surface fractions, pixel-independent.
            let stripe = step(0.5, fract((in.uv.x + in.uv.y) * 60.0));
            lit = mix(lit, vec3<f32>(0.55, 0.05, 0.6), e.y * (0.12 + 0.16 * stripe));
            lit = mix(lit, vec3<f32>(0.85, 0.2, 0.95), e.x * 0.85);
        } else {
            lit = mix(lit, vec3<f32>(0.35, 0.9, 0.55), e.y * 0.1);
            lit = mix(lit, vec3<f32>(0.2, 0.95, 0.5), e.x * 0.85);
        }
    }
    return output(lit, 1.0);
}

@fragment
fn fs_solid(in: VsOut) -> @location(0) vec4<f32> {
    let v = normalize(camera.eye.xyz - in.world);
    var n = in.normal;
    let len = length(n);
    n = select(v, n / len, len > 1e-6);
    let back = dot(n, v) < 0.0;
    n = select(n, -n, back);
    let lamp = camera.lamp.xyz;
    let head = camera.light.xyz;
    let diffuse = 0.6 * max(dot(n, lamp), 0.0) + 0.4 * max(dot(n, head), 0.0);
    let spec = object.params.x * (pow(max(dot(n, normalize(lamp + v)), 0.0), object.params.y)
        + 0.6 * pow(max(dot(n, normalize(head + v)), 0.0), object.params.y));
    var lit = object.color.rgb * (0.2 + 0.75 * diffuse) + vec3<f32>(spec);
    if object.params.z > 0.5 {
        // Polished steel: reflects a bright overhead and a dark floor.
        let r = reflect(-v, n);
        let env = mix(vec3<f32>(0.08, 0.1, 0.11), vec3<f32>(0.95, 0.97, 1.0), smoothstep(-0.3, 0.7, r.y));
        lit = mix(lit, env * object.color.rgb * 1.25, 0.55);
    }
    return output(lit, 1.0);
}
