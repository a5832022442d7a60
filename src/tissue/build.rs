//! Building a tissue from its description: the `(u, v, h)` lattice of one or two layers with their
//! connective fibres, or a volume; pins; render triangles.

use glam::Vec3;
use thiserror::Error;

use super::spec::{ConnectiveSpec, Edge, LayerSpec, Pinning};
use super::{Damage, Geometry, Layer, LinkKind, Tissue};
use crate::chainmail::{
    Body, ChainMailError, ElementId, GridSpec, Lattice, LinkId, LinkSpec, MAX_ELEMENTS, Material, NormalPair,
    Workspace,
};
use crate::surface::Surface;

/// Why a tissue could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TissueError {
    /// The engine refused the lattice or a material.
    #[error(transparent)]
    Engine(#[from] ChainMailError),
    /// A parameter that cannot work.
    #[error("{field}: {reason}")]
    Invalid {
        /// The parameter, as named in scenes.
        field: String,
        /// What is wrong and what is expected.
        reason: String,
    },
}

fn invalid(field: &str, reason: impl Into<String>) -> TissueError {
    TissueError::Invalid { field: field.into(), reason: reason.into() }
}

/// Layers on a parametric surface.
#[derive(Clone, Debug, PartialEq)]
pub struct LayeredSpec {
    /// The base surface.
    pub surface: Surface,
    /// Elements along `u` and `v`.
    pub resolution: [usize; 2],
    /// Optional non-uniform `u` positions, fractions in `[0, 1]`.
    pub u_coords: Option<Vec<f32>>,
    /// Optional non-uniform `v` positions, fractions in `[0, 1]`.
    pub v_coords: Option<Vec<f32>>,
    /// One or two layers, upper first.
    pub layers: Vec<LayerSpec>,
    /// Fibres between two layers.
    pub connective: Option<ConnectiveSpec>,
    /// Pinned elements.
    pub pinned: Pinning,
}

/// A ChainMail volume: a box of elements, world coordinates, base at `y = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeSpec {
    /// Size along x, y, z, metres.
    pub size: [f32; 3],
    /// Elements along x, y, z.
    pub resolution: [usize; 3],
    /// Material.
    pub material: Material,
    /// Colour of its surface.
    pub color: [f32; 4],
    /// Pin the base.
    pub pinned: Pinning,
    /// Drive the volume with the finite-element model instead of ChainMail (base clamped).
    pub fem: Option<super::FemSpec>,
}

/// What to build.
#[derive(Clone, Debug, PartialEq)]
pub enum TissueSpec {
    /// SurfaceChainMail layers.
    Layered(LayeredSpec),
    /// A 3D ChainMail volume.
    Volume(VolumeSpec),
}

impl Tissue {
    /// Builds a tissue to be stepped at the default 1000 steps per second. Nothing is half-built: any
    /// error leaves no tissue.
    pub fn build(spec: &TissueSpec) -> Result<Self, TissueError> {
        Self::build_stepped(spec, 1e-3)
    }

    /// Builds a tissue to be stepped every `step_seconds` (what a dynamic finite-element model
    /// integrates over; the world passes its own step, see `World::build`).
    pub fn build_stepped(spec: &TissueSpec, step_seconds: f32) -> Result<Self, TissueError> {
        match spec {
            TissueSpec::Layered(s) => build_layered(s),
            TissueSpec::Volume(s) => build_volume(s, step_seconds),
        }
    }
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    Vec3::from(a).distance(Vec3::from(b))
}

fn check_fracs(field: &str, f: &Option<Vec<f32>>, n: usize, wrapped: bool) -> Result<(), TissueError> {
    let Some(f) = f else { return Ok(()) };
    if f.len() != n {
        return Err(invalid(field, format!("has {} values, expected one per element ({n})", f.len())));
    }
    if f.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > 1.0 || (wrapped && *x >= 1.0)) {
        return Err(invalid(field, "expected fractions in [0, 1] (below 1 around a wrapped surface)"));
    }
    if f.windows(2).any(|w| w[1] <= w[0]) {
        return Err(invalid(field, "expected strictly increasing fractions"));
    }
    Ok(())
}

fn build_layered(s: &LayeredSpec) -> Result<Tissue, TissueError> {
    s.surface.validate().map_err(|r| invalid("surface", r))?;
    let [nu, nv] = s.resolution;
    if nu < 2 || nv < 2 {
        return Err(invalid(
            "resolution",
            format!("{nu} x {nv}: expected at least 2 elements along u and v"),
        ));
    }
    let nl = s.layers.len();
    if !(1..=2).contains(&nl) {
        return Err(invalid("layers", format!("{nl} layers: expected 1 or 2")));
    }
    let total = (nu as u128) * (nv as u128) * (nl as u128);
    if total > MAX_ELEMENTS as u128 {
        return Err(invalid(
            "resolution",
            format!("{nu} x {nv} x {nl} layers = {total} elements, more than the limit of {MAX_ELEMENTS}"),
        ));
    }
    let wrapped = s.surface.u_period().is_some();
    if wrapped && nu < 3 {
        return Err(invalid("resolution", "a wrapped surface needs at least 3 elements around"));
    }
    check_fracs("u_coords", &s.u_coords, nu, wrapped)?;
    check_fracs("v_coords", &s.v_coords, nv, false)?;
    for (i, l) in s.layers.iter().enumerate() {
        l.material.validate().map_err(|e| invalid(&format!("layers[{i}].material"), e.to_string()))?;
        if !l.offset.is_finite() {
            return Err(invalid(&format!("layers[{i}].offset"), "expected a finite number of metres"));
        }
    }
    // Lattice order: lowest offset first. The scene lists the upper layer first.
    let mut order: Vec<usize> = (0..nl).collect();
    order.sort_by(|&a, &b| s.layers[a].offset.total_cmp(&s.layers[b].offset));
    let offsets: Vec<f32> = order.iter().map(|&i| s.layers[i].offset).collect();
    let gap = if nl == 2 { offsets[1] - offsets[0] } else { 0.0 };
    if nl == 2 && gap <= 0.0 {
        return Err(invalid("layers", "the two layers have the same offset: expected the upper one above"));
    }
    let connective = if nl == 2 { s.connective } else { None };
    if let Some(c) = &connective {
        c.material.validate().map_err(|e| invalid("connective.material", e.to_string()))?;
        if !(c.density > 0.0 && c.density <= 1.0) {
            return Err(invalid("connective.density", format!("{}: expected a share in (0, 1]", c.density)));
        }
        if !(c.spacing.is_finite() && c.spacing >= 0.0) {
            return Err(invalid("connective.spacing", format!("{}: expected at least 0 metres", c.spacing)));
        }
        if !(c.min_gap >= 0.0 && c.min_gap < gap) {
            return Err(invalid(
                "connective.min_gap",
                format!("{}: expected at least 0 and below the gap between the layers ({gap})", c.min_gap),
            ));
        }
    }

    let sampling = s.surface.sample(nu, nv, s.u_coords.as_deref(), s.v_coords.as_deref());
    let sheet = nu * nv;
    let mut rest = Vec::with_capacity(sheet * nl);
    for &h in &offsets {
        for j in 0..nv {
            for i in 0..nu {
                rest.push([sampling.u[i], sampling.v[j], h]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| ElementId((i + nu * (j + nv * k)) as u32);
    let world = |p: [f32; 3]| s.surface.to_world(p);
    let mut links = Vec::new();
    let mut kinds = Vec::new();
    let mut rest_len = Vec::new();
    // The mean world length of the lowest layer's links along u and along v, with their counts: the
    // element spacing the fibres' stride is measured against.
    let mut along = [(0.0f64, 0u32); 2];
    for k in 0..nl {
        for j in 0..nv {
            for i in 0..nu {
                // Along u (wrapping), then along v.
                let last_u = i + 1 == nu;
                if !last_u || wrapped {
                    let (i2, du) = if last_u {
                        (0, sampling.u_period.unwrap_or(0.0) - (sampling.u[nu - 1] - sampling.u[0]))
                    } else {
                        (i + 1, sampling.u[i + 1] - sampling.u[i])
                    };
                    let (a, b) = (id(i, j, k), id(i2, j, k));
                    let d3 = dist(world(rest[a.index()]), world(rest[b.index()]));
                    links.push(LinkSpec { a, b, rest: [du, 0.0, 0.0], scale: [du, du, d3] });
                    kinds.push(LinkKind::Layer((nl - 1 - k) as u8));
                    rest_len.push(d3);
                    if k == 0 {
                        along[0] = (along[0].0 + f64::from(d3), along[0].1 + 1);
                    }
                }
                if j + 1 < nv {
                    let dv = sampling.v[j + 1] - sampling.v[j];
                    let (a, b) = (id(i, j, k), id(i, j + 1, k));
                    let d3 = dist(world(rest[a.index()]), world(rest[b.index()]));
                    links.push(LinkSpec { a, b, rest: [0.0, dv, 0.0], scale: [dv, dv, d3] });
                    kinds.push(LinkKind::Layer((nl - 1 - k) as u8));
                    rest_len.push(d3);
                    if k == 0 {
                        along[1] = (along[1].0 + f64::from(d3), along[1].1 + 1);
                    }
                }
            }
        }
    }
    // One element in `stride` along each axis is a fibre's site (the same sites per square millimetre
    // at every resolution finer than the fibres' spacing).
    let mean = |(sum, n): (f64, u32)| if n > 0 { (sum / f64::from(n)) as f32 } else { f32::INFINITY };
    let fibre_stride = connective.as_ref().map_or([1, 1], |c| c.stride(mean(along[0]), mean(along[1])));
    if let Some(c) = &connective {
        for j in 0..nv {
            for i in 0..nu {
                if !c.joins_at(i as u32, j as u32, fibre_stride) {
                    continue;
                }
                links.push(LinkSpec {
                    a: id(i, j, 0),
                    b: id(i, j, 1),
                    rest: [0.0, 0.0, gap],
                    scale: [gap; 3],
                });
                kinds.push(LinkKind::Connective);
                rest_len.push(gap);
            }
        }
    }
    let mut lattice = Lattice::from_links(rest, &links)?;
    lattice.dims = Some([nu, nv, nl]);
    // Material 0 is the lowest layer's; the others follow.
    let mut body = Body::new(lattice, s.layers[order[0]].material)?;
    let mut layer_material = vec![crate::chainmail::MaterialId(0)];
    if nl == 2 {
        layer_material.push(body.add_material(s.layers[order[1]].material)?);
    }
    let connective_material = match &connective {
        Some(c) => Some(body.add_material(c.material)?),
        None => None,
    };
    for (l, kind) in kinds.iter().enumerate() {
        let m = match kind {
            LinkKind::Layer(k) => layer_material[nl - 1 - *k as usize],
            LinkKind::Connective => connective_material.unwrap_or(layer_material[0]),
        };
        body.set_link_material(LinkId(l as u32), m)?;
    }
    // Pins.
    let (edges, patch): (Vec<Edge>, Option<FractionBox>) = match &s.pinned {
        Pinning::None => (vec![], None),
        Pinning::Boundary if wrapped => (vec![Edge::VMin, Edge::VMax], None),
        Pinning::Boundary => (vec![Edge::UMin, Edge::UMax, Edge::VMin, Edge::VMax], None),
        Pinning::Edges(e) => (e.clone(), None),
        Pinning::Patch { u, v } => (vec![], Some((*u, *v))),
    };
    let (lo, span) = fraction_extent(&Geometry::Surface(s.surface), body.lattice().rest_positions());
    let uf: Vec<f32> = sampling.u.iter().map(|u| (u - lo[0]) / span[0]).collect();
    let vf: Vec<f32> = sampling.v.iter().map(|v| (v - lo[1]) / span[1]).collect();
    for k in 0..nl {
        for (j, &fv) in vf.iter().enumerate() {
            for (i, &fu) in uf.iter().enumerate() {
                let in_patch = patch.is_some_and(|((u0, u1), (v0, v1))| {
                    fu >= u0 - 1e-6 && fu <= u1 + 1e-6 && fv >= v0 - 1e-6 && fv <= v1 + 1e-6
                });
                let on = in_patch
                    || edges.iter().any(|e| match e {
                        Edge::UMin => i == 0,
                        Edge::UMax => i + 1 == nu,
                        Edge::VMin => j == 0,
                        Edge::VMax => j + 1 == nv,
                    });
                if on {
                    body.set_pinned(id(i, j, k), true)?;
                }
            }
        }
    }
    // Render triangles per layer: each grid quad as two triangles, oriented along the outward normal.
    let mut layers = Vec::with_capacity(nl);
    let link_of = |a: ElementId, b: ElementId, body: &Body| -> u32 {
        body.lattice().neighbours(a).find(|&(n, _)| n == b).map(|(_, l)| l.0).unwrap_or(u32::MAX)
    };
    let mut pairs = Vec::new();
    for (k, &src) in order.iter().enumerate() {
        let spec = &s.layers[src];
        let mut triangles = Vec::new();
        let cols = if wrapped { nu } else { nu - 1 };
        for j in 0..nv - 1 {
            for i in 0..cols {
                let i2 = (i + 1) % nu;
                let (a, b, c, d) = (id(i, j, k), id(i2, j, k), id(i2, j + 1, k), id(i, j + 1, k));
                let (ab, bc, dc, ad) =
                    (link_of(a, b, &body), link_of(b, c, &body), link_of(d, c, &body), link_of(a, d, &body));
                // Orientation: the triangle normal should agree with the surface normal at rest.
                let (pa, pb, pc) = (
                    world(body.positions()[a.index()]),
                    world(body.positions()[b.index()]),
                    world(body.positions()[c.index()]),
                );
                let (pa, pb, pc) = (Vec3::from(pa), Vec3::from(pb), Vec3::from(pc));
                let n = (pb - pa).cross(pc - pa);
                let r = body.positions()[a.index()];
                let flip = n.dot(Vec3::from(s.surface.normal(r[0], r[1]))) < 0.0;
                let (t1, t2) = if flip {
                    ([a.0, c.0, b.0], [a.0, d.0, c.0])
                } else {
                    ([a.0, b.0, c.0], [a.0, c.0, d.0])
                };
                triangles.push((t1, [ab, bc]));
                triangles.push((t2, [dc, ad]));
                // The cell's diagonals bound the normal offset as its sides do (see
                // `chainmail::NormalPair`): the tent of a point lift is then round, not a pyramid.
                if [ab, bc, dc, ad].iter().all(|&l| l != u32::MAX) {
                    let [ab, bc, dc, ad] = [ab, bc, dc, ad].map(LinkId);
                    pairs.push(NormalPair { a, b: c, paths: [[ab, bc], [ad, dc]] });
                    pairs.push(NormalPair { a: b, b: d, paths: [[ab, ad], [bc, dc]] });
                }
            }
        }
        // A sphere's pole rings are closed by fans round their poles, for drawing only.
        let mut caps = Vec::new();
        if matches!(s.surface, Surface::Sphere { .. }) {
            for (j, south) in [(0, true), (nv - 1, false)] {
                let ring: Vec<u32> = (0..nu).map(|i| id(i, j, k).0).collect();
                let links = (0..nu).map(|i| link_of(id(i, j, k), id((i + 1) % nu, j, k), &body)).collect();
                // Fan (pole, ring[i], ring[i + 1]) faces outwards when its normal points away from the
                // sphere's centre, like the pole itself.
                let (p0, p1) =
                    (world(body.positions()[ring[0] as usize]), world(body.positions()[ring[1] as usize]));
                let (p0, p1) = (Vec3::from(p0), Vec3::from(p1));
                let r = p0.length();
                let pole = Vec3::new(0.0, if south { -r } else { r }, 0.0);
                let n = (p0 - pole).cross(p1 - pole);
                caps.push(super::Cap { ring, links, flip: n.dot(pole) < 0.0 });
            }
        }
        layers.push(Layer {
            caps,
            name: spec.name.clone(),
            color: spec.color,
            first: (k * sheet) as u32,
            count: sheet as u32,
            material: layer_material[k],
            triangles,
            grid: Some([nu as u32, nv as u32]),
            version: crate::chainmail::fresh_number(),
        });
    }
    body.set_normal_pairs(&pairs)?;
    // The tissue lists its layers upper first, as the scene does.
    layers.reverse();
    let spacing = {
        let du = (sampling.u[nu - 1] - sampling.u[0]) / (nu - 1) as f32;
        let dv = (sampling.v[nv - 1] - sampling.v[0]) / (nv - 1) as f32;
        du.min(dv)
    };
    let n = body.element_count();
    Ok(Tissue::assemble(
        body,
        Geometry::Surface(s.surface),
        layers,
        kinds,
        rest_len,
        if nl == 2 { sheet as u32 } else { 0 },
        connective.as_ref().map(|c| c.min_gap).unwrap_or(0.0),
        spacing,
        fibre_stride,
        super::Model::ChainMail,
        vec![true; n],
    ))
}

fn build_volume(s: &VolumeSpec, step_seconds: f32) -> Result<Tissue, TissueError> {
    for (k, &x) in s.size.iter().enumerate() {
        if !(x.is_finite() && x > 0.0) {
            return Err(invalid(&format!("size[{k}]"), format!("{x}: expected a positive number of metres")));
        }
    }
    let [nx, ny, nz] = s.resolution;
    if nx < 2 || ny < 2 || nz < 2 {
        return Err(invalid("resolution", "expected at least 2 elements along each axis"));
    }
    let total = (nx as u128) * (ny as u128) * (nz as u128);
    if total > MAX_ELEMENTS as u128 {
        return Err(invalid(
            "resolution",
            format!("{total} elements, more than the limit of {MAX_ELEMENTS}"),
        ));
    }
    s.material.validate().map_err(|e| invalid("material", e.to_string()))?;
    let axis = |n: usize, len: f32, lo: f32| (0..n).map(|i| lo + len * i as f32 / (n - 1) as f32).collect();
    let spec = GridSpec {
        coords: [
            axis(nx, s.size[0], -0.5 * s.size[0]),
            axis(ny, s.size[1], 0.0),
            axis(nz, s.size[2], -0.5 * s.size[2]),
        ],
        wrap: [None; 3],
        scale: [1.0; 3],
    };
    let lattice = Lattice::grid(&spec)?;
    let mut body = Body::new(lattice, s.material)?;
    let id = |i: usize, j: usize, k: usize| ElementId((i + nx * (j + ny * k)) as u32);
    if s.pinned != Pinning::None {
        for k in 0..nz {
            for i in 0..nx {
                body.set_pinned(id(i, 0, k), true)?;
            }
        }
    }
    let m = body.link_count();
    let rest_len: Vec<f32> = (0..m)
        .map(|l| body.lattice().link_rest(LinkId(l as u32)).map(|r| dist(r, [0.0; 3])).unwrap_or(1.0))
        .collect();
    let link_of = |a: ElementId, b: ElementId, body: &Body| -> u32 {
        body.lattice().neighbours(a).find(|&(n, _)| n == b).map(|(_, l)| l.0).unwrap_or(u32::MAX)
    };
    // The outer surface: the quads of the six faces, oriented outwards.
    let mut triangles = Vec::new();
    let dims = [nx, ny, nz];
    for axis in 0..3 {
        let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, dims[axis] - 1] {
            for b in 0..dims[q] - 1 {
                for a in 0..dims[p] - 1 {
                    let at = |da: usize, db: usize| {
                        let mut c = [0usize; 3];
                        c[axis] = side;
                        c[p] = a + da;
                        c[q] = b + db;
                        id(c[0], c[1], c[2])
                    };
                    let (e00, e10, e11, e01) = (at(0, 0), at(1, 0), at(1, 1), at(0, 1));
                    let l = |x, y| link_of(x, y, &body);
                    let outward = side != 0;
                    let (t1, t2) = if outward {
                        ([e00.0, e10.0, e11.0], [e00.0, e11.0, e01.0])
                    } else {
                        ([e00.0, e11.0, e10.0], [e00.0, e01.0, e11.0])
                    };
                    triangles.push((t1, [l(e00, e10), l(e10, e11)]));
                    triangles.push((t2, [l(e01, e11), l(e00, e01)]));
                }
            }
        }
    }
    let n = body.element_count();
    let mut on_surface = vec![false; n];
    for (t, _) in &triangles {
        for &v in t {
            on_surface[v as usize] = true;
        }
    }
    let layers = vec![Layer {
        caps: Vec::new(),
        name: "volume".into(),
        color: s.color,
        first: 0,
        count: n as u32,
        material: crate::chainmail::MaterialId(0),
        triangles,
        grid: None,
        version: crate::chainmail::fresh_number(),
    }];
    let spacing = (0..3).map(|k| s.size[k] / (dims[k] - 1) as f32).fold(f32::MAX, f32::min);
    let model = match &s.fem {
        None => super::Model::ChainMail,
        Some(f) => {
            let h: Vec<f32> = (0..3).map(|k| s.size[k] / (dims[k] - 1) as f32).collect();
            if h.iter().any(|x| (x - h[0]).abs() > 1e-4 * h[0]) {
                return Err(invalid(
                    "tissue.size",
                    format!(
                        "element spacing {h:?} differs between axes; a finite-element block needs one spacing"
                    ),
                ));
            }
            let mut last = -1.0f32;
            let drive = super::FemDrive::load(dims, h[0], f, step_seconds, |p| {
                if p >= last + 0.25 || p >= 1.0 {
                    log::info!("finite-element model: {:.0}% precomputed", 100.0 * p);
                    last = p;
                }
            })
            .map_err(|e| invalid("tissue.model", e.to_string()))?;
            super::Model::Fem(Box::new(drive))
        }
    };
    Ok(Tissue::assemble(
        body,
        Geometry::Volume,
        layers,
        vec![LinkKind::Layer(0); m],
        rest_len,
        0,
        0.0,
        spacing,
        [1, 1],
        model,
        on_surface,
    ))
}

impl Tissue {
    /// A tissue at rest around a built body, with empty scratch and counters.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        body: Body,
        geometry: Geometry,
        layers: Vec<Layer>,
        link_kind: Vec<LinkKind>,
        rest_len: Vec<f32>,
        sheet: u32,
        min_gap: f32,
        spacing: f32,
        fibre_stride: [u32; 2],
        model: super::Model,
        on_surface: Vec<bool>,
    ) -> Self {
        let n = body.element_count();
        let (extent_lo, extent_span) = fraction_extent(&geometry, body.lattice().rest_positions());
        let mut by_kind: Vec<(LinkKind, Vec<u32>)> = Vec::new();
        for (l, &kind) in link_kind.iter().enumerate() {
            match by_kind.iter_mut().find(|(k, _)| *k == kind) {
                Some((_, ids)) => ids.push(l as u32),
                None => by_kind.push((kind, vec![l as u32])),
            }
        }
        let wrapped = match geometry {
            Geometry::Surface(s) => s.u_period().is_some(),
            Geometry::Volume => true,
        };
        let kind_links = by_kind
            .into_iter()
            .map(|(kind, ids)| (kind, super::link_grid::LinkGrid::new(&body, &ids, wrapped)))
            .collect();
        // Each layer's surface elements where they rest, on a flat surface (the nearest element's search).
        let layer_elements = match geometry {
            Geometry::Surface(s) if s.is_flat() => layers
                .iter()
                .map(|l| {
                    let ids: Vec<u32> = (l.first..l.first + l.count)
                        .filter(|&e| on_surface.get(e as usize) == Some(&true))
                        .collect();
                    super::link_grid::LinkGrid::of_elements(&body, &ids, false)
                })
                .collect(),
            _ => Vec::new(),
        };
        // Only a flat surface's tear scan reads the table (see `scan.rs`).
        let scan_table = match geometry {
            Geometry::Surface(s) if s.is_flat() => super::scan::ScanTable::new(&body, &link_kind, &rest_len),
            _ => super::scan::ScanTable::default(),
        };
        let mut tissue = Tissue {
            mesh_recipe: std::sync::Arc::new(super::MeshRecipe::empty(geometry)),
            scan_table,
            scan_spare: Default::default(),
            growth: Default::default(),
            coarse: Default::default(),
            settling: false,
            settle_steps: 0,
            // (Written now, so that a release meets no page the system has yet to give.)
            fill_bits: crate::chainmail::touched(n.div_ceil(64), 0),
            fill_stack: touched_empty(n),
            fill_found: touched_empty(n),
            kind_links,
            cut_candidates: Vec::new(),
            layer_elements,
            drift_max: 0.0,
            drift_at: None,
            tear_scratch: Vec::new(),
            tear_hits: Vec::new(),
            region_scan: None,
            scan_keep: Vec::with_capacity(n),
            wide_scratch: Vec::new(),
            ws: {
                // A lift's taut tent rises a block at a time (`chainmail/reaction/lift.rs`).
                let mut ws = Workspace::new(&body);
                ws.set_rigid_blocks(true);
                ws
            },
            extent_lo,
            extent_span,
            geometry,
            layers,
            link_kind,
            rest_len,
            fibre_sites: Vec::new(),
            fibre_stride,
            sheet,
            min_gap,
            active: Vec::with_capacity(n),
            in_active: crate::chainmail::touched(n, false),
            last_move: crate::chainmail::touched(n, 0.0),
            region_scratch: Vec::with_capacity(n),
            #[cfg(test)]
            stepped_region: Vec::new(),
            region_bits: super::bits::Bits::new(n),
            moved_bits: super::bits::Bits::new(n),
            moved_pending: false,
            relax_cursor: 0,
            swept: None,
            swept_checks: 0,
            step_moved: 0,
            settled: false,
            cut_queue: Vec::new(),
            events: Vec::new(),
            topology_version: 0,
            damage: Damage::default(),
            max_stretch: 1.0,
            spacing,
            body,
            model,
            notice: None,
            jaws: Default::default(),
            blade_half_width: 0.5 * crate::instrument::BLADE_WIDTH,
            on_surface,
            forces: Default::default(),
            cut_energy: 0.0,
            probe: super::press::Probe::new(),
            repair: Default::default(),
        };
        tissue.forces = super::force::LinkFactors::of(&tissue);
        tissue.growth.fit(tissue.body.lattice());
        tissue.fit_coarse();
        tissue.repair.fit(n);
        tissue.fibre_sites = tissue.rest_fibre_sites();
        tissue.mesh_recipe = std::sync::Arc::new(super::MeshRecipe::new(&tissue));
        // What the first step would otherwise do over the whole body: measure the drift from rest
        // and size a lift's cone (a step then touches only what moves).
        tissue.drift();
        tissue.jaws.cone.fit_body(&tissue.body);
        if matches!(tissue.geometry, Geometry::Surface(_)) {
            tissue.probe.cone.fit_body(&tissue.body);
        }
        tissue
    }
}

/// An empty vector with room for `n` elements, its memory written.
fn touched_empty(n: usize) -> Vec<u32> {
    let mut v = crate::chainmail::touched(n, 0);
    v.clear();
    v
}

/// A range of `u` and a range of `v`, as fractions.
type FractionBox = ((f32, f32), (f32, f32));

/// Where the fractions that scenes and goals use start and how far they span, per lattice axis: a
/// wrapped `u` spans its whole period, a sphere's `v` runs from pole to pole (its rows are cell centres),
/// anything else spans its rest positions.
pub(crate) fn fraction_extent(geometry: &Geometry, rest: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in rest {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mut span = [0, 1, 2].map(|k| hi[k] - lo[k]);
    if let Geometry::Surface(surface) = geometry {
        if let Some(period) = surface.u_period() {
            lo[0] = 0.0;
            span[0] = period;
        }
        if let Surface::Sphere { radius } = *surface {
            lo[1] = 0.0;
            span[1] = std::f32::consts::PI * radius;
        }
    }
    (lo, span.map(|x| x.max(f32::MIN_POSITIVE)))
}
