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
    // Signed distances (surface fractions) to the nearest target and forbidden region's edge, negative
    // inside; large when there is none. Interpolated: exact along straight edges, rounded at corners.
    @location(3) region: vec2<f32>,
};

// Signed distances from uv to the nearest target and forbidden region's edge (negative inside; 10
// when there is none), over the four regions at once. Branch-free on purpose: the same computation
// written as a loop over the regions, or as one `if` per region, made Mesa's lavapipe 22.3 (software
// Vulkan) keep memory on every draw of the tissue and never give it back: the trainer grew by 5 to
// 8 MB a second there (see the README's "Memory" paragraph and `examples/present_loop.rs`).
fn region_distances(uv: vec2<f32>) -> vec2<f32> {
    let kinds = camera.region_kinds;
    let r0 = camera.regions[0];
    let r1 = camera.regions[1];
    let r2 = camera.regions[2];
    let r3 = camera.regions[3];
    // Rectangles (u0, u1, v0, v1): the larger of the distances outside each edge.
    let rect = vec4<f32>(
        max(max(r0.x - uv.x, uv.x - r0.y), max(r0.z - uv.y, uv.y - r0.w)),
        max(max(r1.x - uv.x, uv.x - r1.y), max(r1.z - uv.y, uv.y - r1.w)),
        max(max(r2.x - uv.x, uv.x - r2.y), max(r2.z - uv.y, uv.y - r2.w)),
        max(max(r3.x - uv.x, uv.x - r3.y), max(r3.z - uv.y, uv.y - r3.w)),
    );
    // Discs (cu, cv, radius).
    let disc = vec4<f32>(
        length(uv - r0.xy) - r0.z,
        length(uv - r1.xy) - r1.z,
        length(uv - r2.xy) - r2.z,
        length(uv - r3.xy) - r3.z,
    );
    let none = vec4<f32>(10.0);
    let d = select(select(rect, disc, kinds > vec4<f32>(2.5)), none, kinds < vec4<f32>(0.5));
    let forbidden = (kinds > vec4<f32>(1.5) & kinds < vec4<f32>(2.5)) | kinds > vec4<f32>(3.5);
    let target_d = select(d, none, forbidden);
    let forbidden_d = select(none, d, forbidden);
    return vec2<f32>(
        min(min(target_d.x, target_d.y), min(target_d.z, target_d.w)),
        min(min(forbidden_d.x, forbidden_d.y), min(forbidden_d.z, forbidden_d.w)),
    );
}

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
    out.region = region_distances(uv);
    return out;
}

@vertex
fn vs_solid(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VsOut {
    var out: VsOut;
    let world = object.model * vec4<f32>(position, 1.0);
    out.world = world.xyz;
    out.normal = (object.model * vec4<f32>(normal, 0.0)).xyz;
    out.uv = vec2<f32>(0.0);
    out.region = vec2<f32>(10.0);
    out.clip = camera.view_proj * world;
    return out;
}

// Light from the lamp reaching `p` past one capsule (a = tip and radius, b = end and use flag): 1 in
// the open, down to 0 in the core of the shadow; the penumbra widens with the distance to the caster.
fn capsule_light(p: vec3<f32>, l: vec3<f32>, a: vec4<f32>, b: vec4<f32>) -> f32 {
    // Closest approach between the ray p + t l (t > 0) and the segment a.xyz + s (b.xyz - a.xyz).
    let d = b.xyz - a.xyz;
    let w = p - a.xyz;
    let dl = dot(d, l);
    let wl = dot(w, l);
    let den = max(dot(d, d) - dl * dl, 1e-12);
    let s = clamp((dot(w, d) - dl * wl) / den, 0.0, 1.0);
    let q = w - s * d;
    let t = -dot(q, l);
    let gap = length(q + t * l);
    let r = a.w * 0.5;
    let lit = clamp((gap - r) / (a.w * 0.6 + 0.18 * max(t, 0.0)), 0.0, 1.0);
    return select(1.0, lit, t > 0.0 && b.w > 0.5);
}

fn shadow(p: vec3<f32>) -> f32 {
    if camera.lamp.w <= 0.0 || camera.casters[1].w < 0.5 {
        return 1.0;
    }
    let l = camera.lamp.xyz;
    var lit = capsule_light(p, l, camera.casters[0], camera.casters[1]);
    if camera.casters[3].w > 0.5 {
        lit = lit * capsule_light(p, l, camera.casters[2], camera.casters[3]);
    }
    return mix(1.0, lit, camera.lamp.w);
}

// An outline about two pixels wide along the zero of a signed distance, from its screen derivative.
fn outline(d: f32) -> f32 {
    let px = abs(d) / max(fwidth(d), 1e-9);
    return clamp(2.5 - px, 0.0, 1.0);
}

// x to the powers 16 and 64, by squaring (cheaper than pow on a software rasteriser).
fn pow16(x: f32) -> f32 {
    let x2 = x * x;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    return x8 * x8;
}

// Distance (surface fractions) from p to the segment a-b. Branch-free.
fn segment_distance(p: vec2<f32>, a: vec2<f32>, b: vec2<f32>) -> f32 {
    let ab = b - a;
    let t = clamp(dot(p - a, ab) / max(dot(ab, ab), 1e-12), 0.0, 1.0);
    return length(p - a - t * ab);
}

// Distance from uv to the planned incision (five segments through six points; see `Camera`).
fn incision_distance(uv: vec2<f32>) -> f32 {
    let p0 = camera.incision[0].xy;
    let p1 = camera.incision[0].zw;
    let p2 = camera.incision[1].xy;
    let p3 = camera.incision[1].zw;
    let p4 = camera.incision[2].xy;
    let p5 = camera.incision[2].zw;
    let a = min(segment_distance(uv, p0, p1), segment_distance(uv, p1, p2));
    let b = min(segment_distance(uv, p2, p3), segment_distance(uv, p3, p4));
    return min(min(a, b), segment_distance(uv, p4, p5));
}

@fragment
fn fs_tissue(in: VsOut) -> @location(0) vec4<f32> {
    let v = normalize(camera.eye.xyz - in.world);
    var n = normalize(in.normal);
    let nv = dot(n, v);
    n = select(n, -n, nv < 0.0);

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
    base = base * select(1.0, 0.72, nv < 0.0);

    let shade = shadow(in.world);
    let lamp = camera.lamp.xyz;
    let head = camera.light.xyz;
    // Wrapped diffuse: light bleeds a little past the terminator, as under a thin wet membrane.
    let d_lamp = clamp(dot(n, lamp) * 0.74 + 0.26, 0.0, 1.0);
    let nh = dot(n, head);
    let d_head = clamp(nh * 0.74 + 0.26, 0.0, 1.0);
    // Subsurface tint: light scattered inside comes out redder, most where it grazes the surface.
    let graze = 1.0 - abs(nh);
    let sss = vec3<f32>(0.9, 0.25, 0.18) * (0.1 + 0.16 * graze * graze);
    // Wet: a tight lamp highlight (power 64) over a broad sheen (power 16), and a Fresnel rim.
    let c = 1.0 - abs(nv);
    let c2 = c * c;
    let fres = 0.04 + 0.96 * c2 * c2 * c;
    let hl = max(dot(n, normalize(lamp + v)), 0.0);
    let h16 = pow16(hl);
    let tight = h16 * h16 * h16 * h16 * shade;
    let sheen = pow16(max(nh, 0.0));
    let spec = object.params.x * wet * (tight * 0.8 + sheen * 0.1) + 0.12 * fres;

    var lit = base * (0.16 + 0.62 * d_lamp * shade + 0.34 * d_head + sss) + vec3<f32>(spec);

    // Regions: a tint inside and an outline; the forbidden one hatched.
    let inside = step(in.region, vec2<f32>(0.0));
    let stripe = step(0.5, fract((in.uv.x + in.uv.y) * 60.0));
    lit = mix(lit, vec3<f32>(0.35, 0.9, 0.55), inside.x * 0.1);
    lit = mix(lit, vec3<f32>(0.55, 0.05, 0.6), inside.y * (0.12 + 0.16 * stripe));
    lit = mix(lit, vec3<f32>(0.2, 0.95, 0.5), outline(in.region.x) * 0.85);
    lit = mix(lit, vec3<f32>(0.85, 0.2, 0.95), outline(in.region.y) * 0.85);
    // The planned incision, dashed in a surgeon's violet marker on the upper layer (its outer side).
    let cut_d = incision_distance(in.uv);
    let cut_px = cut_d / max(fwidth(cut_d), 1e-9);
    let dash = step(0.45, fract((in.uv.x + in.uv.y) * 45.0));
    let marker = (1.0 - smoothstep(1.2, 2.4, cut_px)) * dash * object.params.w * select(1.0, 0.0, nv < 0.0);
    lit = mix(lit, vec3<f32>(0.28, 0.12, 0.55), marker * 0.9);
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
