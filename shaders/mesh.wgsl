// Lit triangle meshes. Both sides of a sheet are drawn (cull none); the normal is turned towards the
// viewer, and the side facing away from the given normal (the inner side of a layer) is shaded darker.
//
// Tissue (layers): `vs_tissue` lights each vertex: a wrapped diffuse from the overhead lamp and the
// headlight, a reddish tint where light grazes (light scattered under the surface), a broad sheen, a
// Fresnel rim, the instruments' soft shadows from the lamp, and the cosine of the wet highlight.
// `fs_tissue` adds per pixel what is finer than the vertices: the layer's pattern (group 2, in the
// surface's rest coordinates), the highlight's sharp power-64 falloff and the exercise's regions.
// Why per vertex: a software rasteriser pays for every operation of the fragment shader at every
// pixel, two or three times over along the edges of small triangles (it shades 4 × 4 blocks), while
// the sheets are smooth at their vertex spacing; the golden images of the dissection differ from
// per-pixel lighting in under 0.1 % of pixels. `fs_solid` (instruments, cut edges): plain or polished
// steel, lit per pixel.
// Everything stays within WebGL2: uniforms, one 2D texture, no storage buffers.

@group(2) @binding(0) var tissue_texture: texture_2d<f32>;
@group(2) @binding(1) var tissue_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

struct TissueOut {
    @builtin(position) clip: vec4<f32>,
    // Surface coordinates (fractions of the surface's rest extent).
    @location(0) uv: vec2<f32>,
    // Signed distances (surface fractions) to the nearest target and forbidden region's edge, negative
    // inside; large when there is none. Interpolated: exact along straight edges, rounded at corners.
    @location(1) region: vec2<f32>,
    // What multiplies the layer's colour: ambient, both diffuse terms (the lamp's past the shadows),
    // the subsurface tint, and the inner side's darkening.
    @location(2) light: vec3<f32>,
    // x: the broad sheen, y: the Fresnel rim (both added), z: the lamp's light past the shadows, w: the
    // cosine between the normal and the lamp's half vector (the highlight's).
    @location(3) gloss: vec4<f32>,
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
) -> TissueOut {
    var out: TissueOut;
    out.clip = camera.view_proj * vec4<f32>(position, 1.0);
    out.uv = uv;
    out.region = region_distances(uv);
    let v = normalize(camera.eye.xyz - position);
    var n = normalize(normal);
    let nv = dot(n, v);
    n = select(n, -n, nv < 0.0);
    let lamp = camera.lamp.xyz;
    let head = camera.light.xyz;
    let shade = shadow(position);
    // Wrapped diffuse: light bleeds a little past the terminator, as under a thin wet membrane.
    let d_lamp = clamp(dot(n, lamp) * 0.74 + 0.26, 0.0, 1.0);
    let nh = dot(n, head);
    let d_head = clamp(nh * 0.74 + 0.26, 0.0, 1.0);
    // Subsurface tint: light scattered inside comes out redder, most where it grazes the surface.
    let graze = 1.0 - abs(nh);
    let sss = vec3<f32>(0.9, 0.25, 0.18) * (0.1 + 0.16 * graze * graze);
    // The inner side of a layer is darker.
    let side = select(1.0, 0.72, nv < 0.0);
    out.light = (vec3<f32>(0.16 + 0.62 * d_lamp * shade + 0.34 * d_head) + sss) * side;
    // Wet: a broad sheen (power 16), a Fresnel rim, and the tight highlight's cosine (its power is
    // taken per pixel, so the highlight keeps its sharp edge between vertices).
    let c = 1.0 - abs(nv);
    let c2 = c * c;
    let fres = 0.04 + 0.96 * c2 * c2 * c;
    let hl = max(dot(n, normalize(lamp + v)), 0.0);
    out.gloss = vec4<f32>(0.1 * pow16(max(nh, 0.0)), 0.12 * fres, shade, hl);
    return out;
}

@vertex
fn vs_solid(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VsOut {
    var out: VsOut;
    let world = object.model * vec4<f32>(position, 1.0);
    out.world = world.xyz;
    out.normal = (object.model * vec4<f32>(normal, 0.0)).xyz;
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

// The lamp's light at `p` past both casters (an unused caster lets all light through). Branch-free,
// like `region_distances`: lavapipe runs a vertex shader's branches at a high cost (with an `if` on
// the casters here the frame cost about as much as with the shadow computed at every pixel).
fn shadow(p: vec3<f32>) -> f32 {
    let l = camera.lamp.xyz;
    let lit = capsule_light(p, l, camera.casters[0], camera.casters[1])
        * capsule_light(p, l, camera.casters[2], camera.casters[3]);
    return mix(1.0, lit, max(camera.lamp.w, 0.0));
}

// x to the power 16, by squaring (cheaper than pow on a software rasteriser).
fn pow16(x: f32) -> f32 {
    let x2 = x * x;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    return x8 * x8;
}

@fragment
fn fs_tissue(in: TissueOut) -> @location(0) vec4<f32> {
    // The layer's pattern (see `render::texture`): r the colour's factor over 1.2, g the weight of the
    // pattern's vessel colour (object.detail), b the extra wetness over vessels.
    let tex = textureSample(tissue_texture, tissue_sampler, in.uv * object.extra.xy);
    let base = object.color.rgb * (tex.r * 1.2) + object.detail.rgb * tex.g;
    let wet = 1.0 + 0.5 * tex.b;
    // Wet: the tight lamp highlight (power 64), dimmed in the instruments' shadows.
    let h16 = pow16(in.gloss.w);
    let tight = h16 * h16 * h16 * h16 * in.gloss.z;
    let spec = object.params.x * wet * (tight * 0.8 + in.gloss.x) + in.gloss.y;
    var lit = base * in.light + vec3<f32>(spec);

    // Regions: a tint inside and an outline about two pixels wide (from the distance's screen
    // derivative); the forbidden one hatched. Regions do not overlap, so a pixel takes the nearer one's
    // (the distance to their union is continuous, so its derivative is sound). Pixels away from every
    // region skip the rest: the rasteriser skips a branch no pixel of its block takes.
    let d = min(in.region.x, in.region.y);
    let px = max(fwidth(d), 1e-9);
    if d < 2.5 * px {
        let forbidden = in.region.y < in.region.x;
        let stripe = step(0.5, fract((in.uv.x + in.uv.y) * 60.0));
        let tint = select(0.1, 0.12 + 0.16 * stripe, forbidden) * step(d, 0.0);
        let edge = clamp(2.5 - abs(d) / px, 0.0, 1.0) * 0.85;
        lit = mix(lit, select(vec3<f32>(0.35, 0.9, 0.55), vec3<f32>(0.55, 0.05, 0.6), forbidden), tint);
        lit = mix(lit, select(vec3<f32>(0.2, 0.95, 0.5), vec3<f32>(0.85, 0.2, 0.95), forbidden), edge);
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
