//! Semantic checks of a deserialized scene. Each check names the offending field by its path, so that
//! the loader can point at its line and column.

use crate::chainmail::{Limits, Material};
use crate::snapshot::CameraSpec;
use crate::training::StepCheck;

use super::error::{FieldPath, Problem, problem};
use super::types::{
    Cameras, Connective, FemParams, LayerTissue, Pinning, Scene, SimulationSettings, Surface, Tissue,
    VolumeModel, VolumeTissue,
};

/// Checks a whole scene; the first problem found.
pub(crate) fn scene(s: &Scene) -> Result<(), Problem> {
    let root = FieldPath::default();
    if s.title.trim().is_empty() {
        return problem(&root.f("title"), "is empty, expected a short name such as \"Meninges\"");
    }
    match &s.tissue {
        Tissue::Layers(l) => layers(l, &root.f("tissue")),
        Tissue::Volume(v) => volume(v, &root.f("tissue")),
    }?;
    let at = root.f("instruments");
    if s.instruments.is_empty() {
        return problem(&at, "is empty, expected at least one of Forceps, Scalpel, Probe");
    }
    for (i, k) in s.instruments.iter().enumerate() {
        if s.instruments[..i].contains(k) {
            return problem(&at.i(i), format!("is {k:?}, listed twice; expected each instrument once"));
        }
    }
    cameras(&s.cameras, &root.f("cameras"))?;
    simulation(&s.simulation, &root.f("simulation"))?;
    instrument_sizes(&s.instrument_sizes, &root.f("instrument_sizes"))?;
    if let Some(g) = &s.goals {
        goals(g, &root.f("goals"))?;
    }
    Ok(())
}

fn goals(g: &crate::training::Goals, at: &FieldPath) -> Result<(), Problem> {
    if let Err(e) = g.target.validate() {
        return problem(&at.f("target"), e);
    }
    for (i, r) in g.forbidden.iter().enumerate() {
        if let Err(e) = r.validate() {
            return problem(&at.f("forbidden").i(i), e);
        }
    }
    if !(g.stretch_limit.is_finite() && g.stretch_limit > 1.0) {
        return problem(&at.f("stretch_limit"), format!("is {}, expected a number above 1", g.stretch_limit));
    }
    if !(g.separation.is_finite() && g.separation > 0.0) {
        return problem(
            &at.f("separation"),
            format!("is {}, expected a positive number of metres", g.separation),
        );
    }
    if !(g.force_limit.is_finite() && g.force_limit > 0.0) {
        return problem(
            &at.f("force_limit"),
            format!("is {}, expected a positive number of newtons", g.force_limit),
        );
    }
    if let Some(t) = g.time_limit_s
        && !(t.is_finite() && t > 0.0)
    {
        return problem(&at.f("time_limit_s"), format!("is {t}, expected a positive number of seconds"));
    }
    if !(g.path_reference_m.is_finite() && g.path_reference_m > 0.0) {
        return problem(
            &at.f("path_reference_m"),
            format!("is {}, expected a positive number of metres", g.path_reference_m),
        );
    }
    if g.incision.len() == 1 {
        return problem(&at.f("incision"), "has one point, expected at least two (a line) or none");
    }
    for (i, &(u, v)) in g.incision.iter().enumerate() {
        for (j, x) in [u, v].into_iter().enumerate() {
            if !(x.is_finite() && (0.0..=1.0).contains(&x)) {
                return problem(
                    &at.f("incision").i(i).i(j),
                    format!("is {x}, expected a fraction in [0, 1]"),
                );
            }
        }
    }
    let pass = at.f("pass");
    if !(g.pass.score.is_finite() && (0.0..=100.0).contains(&g.pass.score)) {
        return problem(&pass.f("score"), format!("is {}, expected a score from 0 to 100", g.pass.score));
    }
    if !(g.pass.completion.is_finite() && (0.0..=1.0).contains(&g.pass.completion)) {
        return problem(
            &pass.f("completion"),
            format!("is {}, expected a share from 0 to 1", g.pass.completion),
        );
    }
    for (i, step) in g.steps.iter().enumerate() {
        let at = at.f("steps").i(i);
        if step.text.trim().is_empty() {
            return problem(&at.f("text"), "is empty, expected what the trainee does in this step");
        }
        let done = at.f("done");
        match step.done {
            StepCheck::Grasp => {}
            StepCheck::Incision(x) | StepCheck::Fibres(x) if !(x.is_finite() && x > 0.0 && x <= 1.0) => {
                return problem(&done.inner(), format!("is {x}, expected a share above 0 and at most 1"));
            }
            StepCheck::Incision(_) if g.incision.is_empty() => {
                return problem(&done, "is Incision, but the goals have no `incision` line to measure it on");
            }
            StepCheck::Separation(x) if !(x.is_finite() && x > 0.0) => {
                return problem(&done.inner(), format!("is {x}, expected a positive number of metres"));
            }
            _ => {}
        }
    }
    Ok(())
}

pub(crate) fn finite(at: &FieldPath, x: f32) -> Result<f32, Problem> {
    if x.is_finite() { Ok(x) } else { problem(at, format!("is {x}, expected a finite number")) }
}

/// Largest length or coordinate in a scene, script or recording, metres: sizes, offsets, camera and
/// instrument positions all lie within ±100 m, so that no sum or square of them overflows.
pub const MAX_METRES: f32 = 100.0;

/// Smallest distance between neighbouring elements at rest, metres (a micrometre): closer elements
/// would make links of no length.
pub const MIN_SPACING: f32 = 1e-6;

/// A finite coordinate or length within ±[`MAX_METRES`].
pub(crate) fn within(at: &FieldPath, x: f32) -> Result<f32, Problem> {
    finite(at, x)?;
    if x.abs() <= MAX_METRES {
        Ok(x)
    } else {
        problem(at, format!("is {x}, expected at most {MAX_METRES} metres either way"))
    }
}

fn positive(at: &FieldPath, x: f32, unit: &str) -> Result<f32, Problem> {
    within(at, x)?;
    if x > 0.0 { Ok(x) } else { problem(at, format!("is {x}, expected a positive length in {unit}")) }
}

fn color(at: &FieldPath, c: [f32; 4]) -> Result<(), Problem> {
    for (i, x) in c.into_iter().enumerate() {
        finite(&at.i(i), x)?;
        if !(0.0..=1.0).contains(&x) {
            return problem(
                &at.i(i),
                format!("is {x}, expected a colour channel in [0, 1] (red, green, blue, alpha)"),
            );
        }
    }
    Ok(())
}

/// Most elements a scene may have, in all its layers (a 1024 × 1024 sheet): about 700 MiB of
/// simulation state, a renderer's largest buffer (24 bytes an element, the triangle indices) at 24 MiB,
/// well inside the 256 MiB every device offers, and built, stepped and drawn in CI (the engine itself
/// takes up to [`crate::chainmail::MAX_ELEMENTS`]).
pub const MAX_SCENE_ELEMENTS: usize = 1 << 20;

fn element_limit(at: &FieldPath, count: u128, what: String) -> Result<(), Problem> {
    const MAX: usize = MAX_SCENE_ELEMENTS;
    if count > MAX as u128 {
        let mib = (MAX / (1 << 20) * crate::chainmail::BYTES_PER_ELEMENT) as u128;
        return problem(
            at,
            format!(
                "is {what}: {count} elements, more than the limit of {MAX} elements (about {mib} MiB of \
                 simulation state); expected at most {MAX} elements in all"
            ),
        );
    }
    Ok(())
}

/// The checks of [`Material::validate`], naming the field.
pub(crate) fn material(at: &FieldPath, m: &Material) -> Result<(), Problem> {
    let lim = at.f("limits");
    match m.limits {
        Limits::Relative { max_stretch, min_compress, max_shear } => {
            let a = lim.f("max_stretch");
            if finite(&a, max_stretch)? < 1.0 {
                return problem(
                    &a,
                    format!(
                        "is {max_stretch}, expected at least 1 (a link may stretch to max_stretch times its rest \
                         length; below 1 it could not even rest)"
                    ),
                );
            }
            let a = lim.f("min_compress");
            if !(finite(&a, min_compress)? > 0.0 && min_compress <= 1.0) {
                return problem(
                    &a,
                    format!(
                        "is {min_compress}, expected a value in (0, 1] (shortest length as a share of the rest length)"
                    ),
                );
            }
            let a = lim.f("max_shear");
            if finite(&a, max_shear)? < 0.0 {
                return problem(&a, format!("is {max_shear}, expected 0 or more"));
            }
        }
        Limits::Absolute { min_dist, max_dist, max_shear } => {
            let a = lim.f("min_dist");
            if within(&a, min_dist)? <= 0.0 {
                return problem(&a, format!("is {min_dist}, expected a positive length in metres"));
            }
            let b = lim.f("max_dist");
            if within(&b, max_dist)? < min_dist {
                return problem(&b, format!("is {max_dist}, expected at least min_dist ({min_dist})"));
            }
            let a = lim.f("max_shear");
            if finite(&a, max_shear)? < 0.0 {
                return problem(&a, format!("is {max_shear}, expected 0 or more"));
            }
        }
    }
    let a = at.f("stiffness");
    if finite(&a, m.stiffness)? <= 0.0 {
        return problem(
            &a,
            format!("is {}, expected a positive number (1 is the usual weight)", m.stiffness),
        );
    }
    for (name, x, what) in [
        ("young_modulus", m.young_modulus, "pascals (dura: about 1e6 to 6e7)"),
        ("thickness", m.thickness, "metres (dura: about 0.0005)"),
        ("toughness", m.toughness, "joules per square metre (soft tissue: about 100 to 5000)"),
    ] {
        let a = at.f(name);
        if finite(&a, x)? <= 0.0 {
            return problem(&a, format!("is {x}, expected a positive number of {what}"));
        }
    }
    if let Some(t) = m.tear_ratio {
        let a = at.f("tear_ratio");
        if finite(&a, t)? <= 1.0 {
            return problem(
                &a,
                format!("is {t}, expected more than 1 (at 1 or less, links would tear at rest)"),
            );
        }
        if let Limits::Relative { max_stretch, .. } = m.limits
            && t < max_stretch
        {
            return problem(
                &a,
                format!(
                    "is {t}, expected at least max_stretch ({max_stretch}): a link would tear before it may \
                     stretch that far"
                ),
            );
        }
    }
    if let Some(nu) = m.poisson_ratio {
        let a = at.f("poisson_ratio");
        if !(finite(&a, nu)? > -1.0 && nu < 0.5) {
            return problem(
                &a,
                format!(
                    "is {nu}, expected a value in (-1, 0.5) (soft tissue: about 0.45; 0.5 would be incompressible)"
                ),
            );
        }
    }
    // Backstop: the engine's own check must agree.
    if let Err(e) = m.validate() {
        return problem(at, format!("is not usable: {e}"));
    }
    Ok(())
}

/// A material of something without cells (a layer, connective fibres) has no Poisson's ratio.
fn cellless(at: &FieldPath, m: &Material, what: &str) -> Result<(), Problem> {
    match m.poisson_ratio {
        Some(nu) => problem(
            &at.f("poisson_ratio"),
            format!(
                "is Some({nu}), expected None: the Poisson's ratio relaxes a Volume's cells, and {what} has none"
            ),
        ),
        None => Ok(()),
    }
}

fn surface(at: &FieldPath, s: &Surface) -> Result<(), Problem> {
    match *s {
        Surface::Plane { width, depth } => {
            positive(&at.f("width"), width, "metres")?;
            positive(&at.f("depth"), depth, "metres")?;
        }
        Surface::Box { width, depth, height } => {
            positive(&at.f("width"), width, "metres")?;
            positive(&at.f("depth"), depth, "metres")?;
            positive(&at.f("height"), height, "metres")?;
        }
        Surface::Cylinder { radius, length } => {
            positive(&at.f("radius"), radius, "metres")?;
            positive(&at.f("length"), length, "metres")?;
        }
        Surface::Sphere { radius } => {
            positive(&at.f("radius"), radius, "metres")?;
        }
    }
    Ok(())
}

fn coords(at: &FieldPath, c: &[f32], n: u32, wraps: bool, axis: &str) -> Result<(), Problem> {
    if c.len() as u128 != u128::from(n) {
        return problem(
            at,
            format!("has {} fractions, expected {n}, one per element along {axis} (the resolution)", c.len()),
        );
    }
    for (i, &x) in c.iter().enumerate() {
        let a = at.i(i);
        finite(&a, x)?;
        let ok = if wraps { (0.0..1.0).contains(&x) } else { (0.0..=1.0).contains(&x) };
        if !ok {
            let range = if wraps { "[0, 1) (this axis wraps around: 1 is 0 again)" } else { "[0, 1]" };
            return problem(&a, format!("is {x}, expected a fraction in {range}"));
        }
        if i > 0 && x <= c[i - 1] {
            return problem(
                &a,
                format!("is {x}, expected more than the one before ({}): strictly increasing", c[i - 1]),
            );
        }
    }
    Ok(())
}

fn layers(l: &LayerTissue, at: &FieldPath) -> Result<(), Problem> {
    surface(&at.f("surface"), &l.surface)?;
    let wraps = l.surface.wraps_u();
    let res = at.f("resolution");
    let min_u = if wraps { 3 } else { 2 };
    if l.resolution[0] < min_u {
        let why = if wraps { " (u wraps around, so at least 3)" } else { "" };
        return problem(
            &res.i(0),
            format!("is {}, expected at least {min_u} elements along u{why}", l.resolution[0]),
        );
    }
    if l.resolution[1] < 2 {
        return problem(&res.i(1), format!("is {}, expected at least 2 elements along v", l.resolution[1]));
    }
    let nl = at.f("layers");
    if l.layers.is_empty() || l.layers.len() > 2 {
        return problem(&nl, format!("has {} layers, expected 1 or 2 (upper first)", l.layers.len()));
    }
    let count = l.layers.len() as u128 * u128::from(l.resolution[0]) * u128::from(l.resolution[1]);
    element_limit(
        &res,
        count,
        format!("({}, {}) with {} layer(s)", l.resolution[0], l.resolution[1], l.layers.len()),
    )?;
    if let Some(c) = &l.u_coords {
        coords(&at.f("u_coords").inner(), c, l.resolution[0], wraps, "u")?;
    }
    if let Some(c) = &l.v_coords {
        coords(&at.f("v_coords").inner(), c, l.resolution[1], false, "v")?;
    }
    for (i, layer) in l.layers.iter().enumerate() {
        let a = nl.i(i);
        if layer.name.trim().is_empty() {
            return problem(&a.f("name"), "is empty, expected a name such as \"dura\"");
        }
        if l.layers[..i].iter().any(|o| o.name == layer.name) {
            return problem(
                &a.f("name"),
                format!("is \"{}\", used twice; expected a different name per layer", layer.name),
            );
        }
        color(&a.f("color"), layer.color)?;
        let off = a.f("offset");
        within(&off, layer.offset)?;
        match l.surface {
            Surface::Cylinder { radius, .. } | Surface::Sphere { radius } if layer.offset <= -radius => {
                return problem(
                    &off,
                    format!("is {}, expected more than -{radius} (the surface's radius)", layer.offset),
                );
            }
            Surface::Box { .. } if layer.offset < 0.0 => {
                return problem(
                    &off,
                    format!("is {}, expected 0 or more: the layers lie on top of the block", layer.offset),
                );
            }
            _ => {}
        }
        material(&a.f("material"), &layer.material)?;
        cellless(&a.f("material"), &layer.material, "a layer")?;
    }
    if let [upper, lower] = l.layers.as_slice()
        && upper.offset <= lower.offset
    {
        return problem(
            &nl.i(0).f("offset"),
            format!(
                "is {}, expected more than the lower layer's offset ({}): the upper layer (listed first) lies \
                 above the lower",
                upper.offset, lower.offset
            ),
        );
    }
    spacing(l, at)?;
    if let Some(c) = &l.connective {
        connective(&at.f("connective"), c, l)?;
    }
    pinning(&at.f("pinned"), &l.pinned, wraps)
}

/// The closest two neighbouring elements may be at rest, metres: a micrometre, and at least a
/// millionth of the tissue's size (single-precision coordinates resolve about a ten-millionth).
fn min_spacing(extent: f64) -> f64 {
    f64::from(MIN_SPACING).max(1e-6 * extent)
}

/// Neighbouring elements far enough apart to make links: what building the tissue needs, checked here
/// so that `dissect check` finds it (at `u_coords` / `v_coords`, or at `resolution` when evenly spaced).
fn spacing(l: &LayerTissue, at: &FieldPath) -> Result<(), Problem> {
    use std::f64::consts::PI;
    let gap = |f: &[f32], wraps: bool| -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for (i, w) in f.windows(2).enumerate() {
            let d = f64::from(w[1]) - f64::from(w[0]);
            if d < best.0 {
                best = (d, i + 1);
            }
        }
        if wraps && let (Some(&a), Some(&b)) = (f.first(), f.last()) {
            let d = 1.0 + f64::from(a) - f64::from(b);
            if d < best.0 {
                best = (d, 0);
            }
        }
        best
    };
    let (fu, fv) = (l.u_fractions(), l.v_fractions());
    let (du, iu) = gap(&fu, l.surface.wraps_u());
    let (dv, iv) = gap(&fv, false);
    let low = l.layers.iter().map(|x| f64::from(x.offset)).fold(f64::INFINITY, f64::min).min(0.0);
    let (span_u, span_v, extent) = match l.surface {
        Surface::Plane { width, depth } | Surface::Box { width, depth, .. } => {
            (f64::from(width), f64::from(depth), f64::from(width.max(depth)))
        }
        Surface::Cylinder { radius, length } => {
            let r = f64::from(radius) + low;
            (2.0 * PI * r, f64::from(length), (2.0 * PI * f64::from(radius)).max(f64::from(length)))
        }
        Surface::Sphere { radius } => {
            let r = f64::from(radius) + low;
            // The shortest ring is the one nearest a pole.
            let ring = fv.iter().map(|&v| (PI * f64::from(v)).sin()).fold(f64::INFINITY, f64::min);
            (2.0 * PI * r * ring, PI * r, 2.0 * PI * f64::from(radius))
        }
    };
    let least = min_spacing(extent);
    for (d, span, i, name, coords) in [
        (du * span_u, span_u, iu, "u_coords", &l.u_coords),
        (dv * span_v, span_v, iv, "v_coords", &l.v_coords),
    ] {
        if d < least {
            let field = if coords.is_some() { at.f(name).inner().i(i) } else { at.f("resolution") };
            let axis = &name[..1];
            return problem(
                &field,
                format!(
                    "puts neighbouring elements {d:.3e} m apart along {axis} (over {span:.3e} m), expected at \
                     least {least:.1e} m: closer elements make links of no length"
                ),
            );
        }
    }
    Ok(())
}

fn connective(at: &FieldPath, c: &Connective, l: &LayerTissue) -> Result<(), Problem> {
    let Some(gap) = l.gap() else {
        return problem(
            at,
            "is given, but connective fibres join two layers and this tissue has one; expected `None` or a second layer",
        );
    };
    material(&at.f("material"), &c.material)?;
    cellless(&at.f("material"), &c.material, "connective fibres")?;
    let d = at.f("density");
    if !(finite(&d, c.density)? > 0.0 && c.density <= 1.0) {
        return problem(&d, format!("is {}, expected a share of the fibres' sites in (0, 1]", c.density));
    }
    let g = at.f("min_gap");
    if !(finite(&g, c.min_gap)? >= 0.0 && c.min_gap < gap) {
        return problem(
            &g,
            format!(
                "is {}, expected at least 0 and less than the gap between the layers ({gap} m)",
                c.min_gap
            ),
        );
    }
    let s = at.f("spacing");
    if finite(&s, c.spacing)? < 0.0 {
        return problem(
            &s,
            format!("is {}, expected at least 0 metres between the fibres' sites", c.spacing),
        );
    }
    Ok(())
}

fn pinning(at: &FieldPath, p: &Pinning, wraps: bool) -> Result<(), Problem> {
    use super::types::Edge;
    match p {
        Pinning::None | Pinning::Boundary => Ok(()),
        Pinning::Edges(edges) => {
            let list = at.inner();
            if edges.is_empty() {
                return problem(at, "lists no edges, expected some of UMin, UMax, VMin, VMax (or `None`)");
            }
            for (i, e) in edges.iter().enumerate() {
                if wraps && matches!(e, Edge::UMin | Edge::UMax) {
                    return problem(
                        &list.i(i),
                        format!(
                            "is {e:?}, but u wraps around this surface so it has no edge; expected VMin or VMax"
                        ),
                    );
                }
            }
            Ok(())
        }
        Pinning::Patch { u, v } => {
            for (name, (lo, hi)) in [("u", u), ("v", v)] {
                let a = at.f(if name == "u" { "u" } else { "v" });
                finite(&a.i(0), *lo)?;
                finite(&a.i(1), *hi)?;
                if !(0.0 <= *lo && lo <= hi && *hi <= 1.0) {
                    return problem(
                        &a,
                        format!("is ({lo}, {hi}), expected (lo, hi) with 0 <= lo <= hi <= 1"),
                    );
                }
            }
            Ok(())
        }
    }
}

fn volume(v: &VolumeTissue, at: &FieldPath) -> Result<(), Problem> {
    let size = at.f("size");
    for (i, x) in v.size.into_iter().enumerate() {
        positive(&size.i(i), x, "metres")?;
    }
    let res = at.f("resolution");
    for (i, n) in v.resolution.into_iter().enumerate() {
        if n < 2 {
            return problem(&res.i(i), format!("is {n}, expected at least 2 elements along each axis"));
        }
    }
    let [x, y, z] = v.resolution;
    element_limit(&res, v.resolution.iter().map(|&n| u128::from(n)).product(), format!("({x}, {y}, {z})"))?;
    let h: Vec<f64> = (0..3).map(|k| f64::from(v.size[k]) / f64::from(v.resolution[k] - 1)).collect();
    let least = min_spacing(v.size.iter().map(|&s| f64::from(s)).fold(0.0, f64::max));
    for (k, &d) in h.iter().enumerate() {
        if d < least {
            return problem(
                &res.i(k),
                format!("puts neighbouring elements {d:.3e} m apart, expected at least {least:.1e} m"),
            );
        }
    }
    material(&at.f("material"), &v.material)?;
    color(&at.f("color"), v.color)?;
    if let VolumeModel::Fem(f) = &v.model {
        // What loading the model needs: one spacing along every axis, and its dense matrices within
        // the memory limit.
        if h.iter().any(|x| (x - h[0]).abs() > 1e-4 * h[0]) {
            return problem(
                &size,
                format!(
                    "gives the elements spacings ({:.4}, {:.4}, {:.4}) m along x, y and z, expected one spacing \
                     (size over resolution − 1 equal along every axis) for a finite-element block",
                    h[0], h[1], h[2]
                ),
            );
        }
        let bytes = fem_bytes(v.resolution, matches!(f.mode, super::types::FemMode::Dynamic));
        let limit = crate::fem::DEFAULT_MEMORY_LIMIT as f64;
        if bytes > limit {
            return problem(
                &res,
                format!(
                    "is ({x}, {y}, {z}): a finite-element block this fine needs about {:.0} MiB of dense matrices, \
                     more than the limit of {:.0} MiB; expected fewer nodes (16 along each axis need about 165 MiB)",
                    bytes / f64::from(1u32 << 20),
                    limit / f64::from(1u32 << 20)
                ),
            );
        }
        fem(&at.f("model").inner(), f)?;
    }
    Ok(())
}

/// Bytes of the dense matrices a finite-element block of `dims` nodes needs, base clamped (as
/// `FemModel::load` counts them, the larger of the static and the dynamic inverse).
fn fem_bytes(dims: [u32; 3], dynamic: bool) -> f64 {
    let [x, y, z] = dims.map(f64::from);
    let interior = (x - 2.0).max(0.0) * (y - 2.0).max(0.0) * (z - 2.0).max(0.0);
    let boundary = x * y * z - interior;
    let free_surface = 3.0 * (boundary - x * z);
    let load = 2.0 * free_surface * free_surface * 8.0 + 3.0 * interior * 64.0 * 8.0;
    let dynamic_inverse = free_surface * free_surface * 8.0;
    if dynamic { load.max(dynamic_inverse) } else { load }
}

fn fem(at: &FieldPath, f: &FemParams) -> Result<(), Problem> {
    let a = at.f("young_modulus");
    if finite(&a, f.young_modulus)? <= 0.0 {
        return problem(
            &a,
            format!(
                "is {}, expected a positive stiffness in pascals (soft tissue: ~1000 to 10000)",
                f.young_modulus
            ),
        );
    }
    let a = at.f("poisson_ratio");
    if !(finite(&a, f.poisson_ratio)? > -1.0 && f.poisson_ratio < 0.5) {
        return problem(
            &a,
            format!("is {}, expected a value in (-1, 0.5) (soft tissue: about 0.45)", f.poisson_ratio),
        );
    }
    let a = at.f("density");
    if finite(&a, f.density)? <= 0.0 {
        return problem(
            &a,
            format!("is {}, expected a positive density in kg/m³ (tissue: about 1000)", f.density),
        );
    }
    let a = at.f("damping");
    if finite(&a, f.damping)? < 0.0 {
        return problem(&a, format!("is {}, expected 0 or more (per second)", f.damping));
    }
    Ok(())
}

/// A camera: eye and target finite and within reach, apart, a field of view in (1, 179) degrees.
pub(crate) fn camera(at: &FieldPath, c: &CameraSpec) -> Result<(), Problem> {
    for (name, p) in [("eye", c.eye), ("target", c.target)] {
        let a = at.f(if name == "eye" { "eye" } else { "target" });
        for (i, x) in p.into_iter().enumerate() {
            within(&a.i(i), x)?;
        }
    }
    if c.eye == c.target {
        return problem(
            &at.f("target"),
            "is the same point as the eye, expected a point the camera looks at",
        );
    }
    let a = at.f("fov_y_deg");
    if !(finite(&a, c.fov_y_deg)? > 1.0 && c.fov_y_deg < 179.0) {
        return problem(
            &a,
            format!("is {}, expected a vertical field of view in degrees, in (1, 179)", c.fov_y_deg),
        );
    }
    Ok(())
}

fn cameras(c: &Cameras, at: &FieldPath) -> Result<(), Problem> {
    if let Some(t) = &c.trainee {
        camera(&at.f("trainee"), t)?;
    }
    if let Some(o) = &c.observer {
        camera(&at.f("observer"), o)?;
    }
    Ok(())
}

fn simulation(s: &SimulationSettings, at: &FieldPath) -> Result<(), Problem> {
    if !(50..=20_000).contains(&s.rate_hz) {
        return problem(
            &at.f("rate_hz"),
            format!("is {}, expected steps per second in [50, 20000]", s.rate_hz),
        );
    }
    if s.relax_sweeps > 1000 {
        return problem(
            &at.f("relax_sweeps"),
            format!("is {}, expected at most 1000 sweeps per step", s.relax_sweeps),
        );
    }
    if s.relax_budget_us > 1_000_000 {
        return problem(
            &at.f("relax_budget_us"),
            format!("is {}, expected at most 1000000 microseconds per step", s.relax_budget_us),
        );
    }
    Ok(())
}

/// Instrument sizes: positive lengths up to 5 cm (a jaw or blade wider than the exercise is a typo).
fn instrument_sizes(s: &crate::instrument::InstrumentSizes, at: &FieldPath) -> Result<(), Problem> {
    for (name, x) in
        [("jaw_width", s.jaw_width), ("blade_width", s.blade_width), ("probe_radius", s.probe_radius)]
    {
        let at = at.f(name);
        positive(&at, x, "metres")?;
        if x > 0.05 {
            return problem(&at, format!("is {x}, expected at most 0.05 metres (5 cm)"));
        }
    }
    Ok(())
}
