//! Forces in newtons: each link is a spring whose constant comes from its material's Young's modulus
//! (and a layer's thickness) and from the rest geometry around it, so that what the tissue exerts on an
//! instrument (the forceps' pull on what they hold, the probe's contact force, the scalpel's cutting
//! resistance) is in newtons and does not depend on the element spacing.
//!
//! - A layer's link of rest length `L` and width `w` (half the perpendicular links at each end, the
//!   tributary width of a spring network) stands for a strip of membrane `w` wide and `t` thick: a
//!   spring of `E·t·w/L` N/m, which is `E·t` on a square grid at any spacing. Membranes buckle rather
//!   than push: only tension counts.
//! - A connective fibre of length `L` stands for the connective tissue over its elements' area `A`
//!   (divided by the fibres' density): `E·A/L`, tension only.
//! - A volume's link stands for the cross-section `A` around it and is the spring of the energy
//!   relaxation minimises: `k·(Δx − ΔX)`, the change of its offset from rest, in every direction
//!   (compression and shear too), with `k = c·A/L` (`A` the square of the mean perpendicular link:
//!   `a²` on a cubic lattice, faces included) and `c = E / (2(1 − ν²))`
//!   ([`ElasticMaterial::lattice_modulus`]: the lattice's surface response is then Boussinesq's),
//!   ν = [`VOLUME_POISSON`]. Relaxed, every free element is balanced by these springs, so the force on
//!   what an instrument holds is the whole body's reaction; `dissect compare` checks it against the
//!   finite-element reference on the same block.
//!
//! The force on a set of elements is the sum of their links' forces (links between two elements of the
//! set cancel), read only from those elements: nothing here walks the body. Cutting a link costs its
//! material's toughness times the area the blade cuts through: `t·w` in a layer (a stroke cuts the
//! links it crosses), `A` in a volume, and for a fibre `L·k²s²/b`, its length times the area its site
//! stands for (`k × k` cells of side `s`, one element in `k` along each axis being a site: see
//! `ConnectiveSpec::stride`) over the blade's width `b` (at least the spacing `s`). A stroke severs
//! every fibre within half the blade's width of it, `b·ρ/(k²s²)` of them per metre at a fibre density
//! `ρ`, so it cuts `L·ρ` square metres per metre of its length, the same at every spacing.
//!
//! Must not import wgpu, winit or egui.

use super::{Geometry, LinkKind, Model, Tissue};
use crate::chainmail::{ElementId, LinkId};
use crate::fem::ElasticMaterial;

/// Poisson's ratio of a ChainMail volume's tissue where its material has none
/// ([`crate::chainmail::Material::poisson_ratio`]): soft tissue is nearly incompressible.
pub const VOLUME_POISSON: f64 = 0.45;

/// Each link's geometric factor: `k = E·t·factor` for a layer on a surface, `E·factor` otherwise.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct LinkFactors {
    /// Per link: `w / L` (layers on a surface) or `A / L` (fibres, volumes), in 1/1 or metres.
    factor: Vec<f32>,
    /// Per link: the cross-section a blade cuts through, as a factor of the thickness for layers on a
    /// surface (`w`), in square metres in a volume, and for a fibre its length times the area its site
    /// stands for (`L·k²s²`, cubic metres, divided by the blade's width when cut); then that area's
    /// side `k·s`.
    cut: Vec<[f32; 2]>,
    /// Per link: how much tissue it stands for ([`Tissue::link_extent`]).
    extent: Vec<f32>,
}

/// How a link carries load.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Spring {
    /// A strip of membrane: `E·t·w/L`, tension only.
    Membrane,
    /// A connective fibre: `E·A/L`, tension only.
    Fibre,
    /// A link of a solid: `c·A/L` on the change of its offset, every direction.
    Solid,
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

impl LinkFactors {
    /// The factors of every link of a built tissue, from its rest geometry.
    pub(crate) fn of(tissue: &Tissue) -> Self {
        let body = &tissue.body;
        let lattice = body.lattice();
        let rest = lattice.rest_positions();
        let world = |e: ElementId| tissue.geometry.to_world(rest[e.index()]);
        let links = body.link_count();
        // Share of element pairs joined by a fibre: each fibre stands for 1/density cells.
        let fibres = tissue.link_kind.iter().filter(|k| **k == LinkKind::Connective).count();
        let density = if tissue.sheet > 0 && fibres > 0 { fibres as f32 / tissue.sheet as f32 } else { 1.0 };
        let mut factor = vec![0.0; links];
        let mut cut = vec![[0.0; 2]; links];
        let mut extent = vec![0.0; links];
        for (l, ((f, c), x)) in factor.iter_mut().zip(cut.iter_mut()).zip(extent.iter_mut()).enumerate() {
            let id = LinkId(l as u32);
            let Some([a, b]) = lattice.link_ends(id) else { continue };
            let kind = tissue.link_kind[l];
            let r = sub(world(b), world(a));
            let len = norm(r).max(f32::MIN_POSITIVE);
            // Links roughly perpendicular to this one at either end: half of each on either side make
            // up the tributary width (a layer) or the side of the tributary square (fibres, volumes).
            let (mut perp, mut count) = (0.0, 0u32);
            for end in [a, b] {
                for (n, m) in lattice.neighbours(end) {
                    let other = tissue.link_kind[m.index()];
                    let related = if kind == LinkKind::Connective { other != kind } else { other == kind };
                    if m == id || !related {
                        continue;
                    }
                    let s = sub(world(n), world(end));
                    let sl = norm(s);
                    let cos = (s[0] * r[0] + s[1] * r[1] + s[2] * r[2]) / (sl * len).max(f32::MIN_POSITIVE);
                    if cos.abs() < 0.5 {
                        perp += sl;
                        count += 1;
                    }
                }
            }
            match spring(tissue, kind) {
                Spring::Membrane => {
                    let w = perp / 4.0;
                    *f = w / len;
                    *c = [w, 0.0];
                    *x = w;
                }
                Spring::Fibre => {
                    let side = perp / 8.0;
                    let area = side * side / density;
                    *f = area / len;
                    // The cells its site stands for (one where every element is a site), and the
                    // side of that square.
                    let cells = tissue.fibre_stride[0] as f32 * tissue.fibre_stride[1] as f32;
                    *c = [len * side * side * cells, side * cells.sqrt()];
                    *x = area;
                }
                Spring::Solid => {
                    // The mean perpendicular link, on the faces too: relaxation weighs every link
                    // alike, and the springs must be those it balances.
                    let side = perp / count.max(1) as f32;
                    *f = side * side / len;
                    *c = [side * side, 0.0];
                    *x = side * side;
                }
            }
        }
        Self { factor, cut, extent }
    }
}

/// The modulus of a volume's lattice, pascals ([`ElasticMaterial::lattice_modulus`] at the material's
/// Poisson's ratio, [`VOLUME_POISSON`] where it has none).
fn volume_modulus(m: &crate::chainmail::Material) -> f32 {
    let nu = m.poisson_ratio.map_or(VOLUME_POISSON, f64::from);
    ElasticMaterial::new(f64::from(m.young_modulus), nu).lattice_modulus() as f32
}

fn spring(tissue: &Tissue, kind: LinkKind) -> Spring {
    match (kind, tissue.geometry) {
        (LinkKind::Connective, _) => Spring::Fibre,
        (LinkKind::Layer(_), Geometry::Surface(_)) => Spring::Membrane,
        (LinkKind::Layer(_), Geometry::Volume) => Spring::Solid,
    }
}

impl Tissue {
    /// Spring constant of a link, newtons per metre, from its material as it is now.
    pub fn link_stiffness(&self, l: LinkId) -> f32 {
        let (Some(&g), Some(&kind)) = (self.forces.factor.get(l.index()), self.link_kind.get(l.index()))
        else {
            return 0.0;
        };
        let Some(m) = self.body.link_material(l).and_then(|m| self.body.material(m)) else { return 0.0 };
        match spring(self, kind) {
            Spring::Membrane => m.young_modulus * m.thickness * g,
            Spring::Fibre => m.young_modulus * g,
            Spring::Solid => volume_modulus(m) * g,
        }
    }

    /// The force an intact link exerts on its element `from`, newtons (world axes): towards the other
    /// end when a membrane or fibre is stretched; for a solid's link, towards restoring its rest
    /// offset; zero for a broken link.
    fn link_force_on(&self, l: LinkId, from: ElementId, to: ElementId) -> [f32; 3] {
        if !self.body.link_intact(l) {
            return [0.0; 3];
        }
        if spring(self, self.link_kind[l.index()]) == Spring::Solid {
            // A volume's lattice coordinates are world coordinates.
            let (Some(d), Some(r)) = (self.body.link_offset(l), self.body.lattice().link_rest(l)) else {
                return [0.0; 3];
            };
            let first = self.body.lattice().link_ends(l).is_some_and(|[a, _]| a == from);
            let k = if first { self.link_stiffness(l) } else { -self.link_stiffness(l) };
            return [0, 1, 2].map(|i| k * (d[i] - r[i]));
        }
        let (Some(pa), Some(pb)) = (self.world_position(from), self.world_position(to)) else {
            return [0.0; 3];
        };
        let d = sub(pb, pa);
        let len = norm(d);
        let rest = self.rest_len.get(l.index()).copied().unwrap_or(len);
        let extension = (len - rest).max(0.0);
        if extension == 0.0 || len <= 0.0 {
            return [0.0; 3];
        }
        let s = self.link_stiffness(l) * extension / len;
        [s * d[0], s * d[1], s * d[2]]
    }

    /// Tension of a link, newtons: positive when it pulls its ends together, negative when a solid's
    /// link pushes them apart, zero when broken or slack (along the link: a solid's shear is left
    /// out).
    pub fn link_tension(&self, l: LinkId) -> f32 {
        let Some([a, b]) = self.body.lattice().link_ends(l) else { return 0.0 };
        let (Some(pa), Some(pb)) = (self.world_position(a), self.world_position(b)) else { return 0.0 };
        let (f, d) = (self.link_force_on(l, a, b), sub(pb, pa));
        (f[0] * d[0] + f[1] * d[1] + f[2] * d[2]) / norm(d).max(f32::MIN_POSITIVE)
    }

    /// The force the tissue exerts on a set of elements, newtons (world axes): the sum of the forces
    /// of the intact links that leave the set (those between two of its elements cancel). What forceps holding `held`
    /// feel, or a probe pressing on them. A finite-element tissue reports its model's reaction at the
    /// node it last drove instead.
    pub fn force_on(&self, held: &[ElementId]) -> [f32; 3] {
        self.force_on_where(held, |n| held.contains(&n))
    }

    /// [`Tissue::force_on`] for a large set: whether a neighbour is in the set is read from `marks`,
    /// a bit per element (scratch the caller keeps: sized here when the body's element count changes,
    /// all clear on return), not searched for along `held`. Forceps at a fine spacing hold hundreds
    /// of elements (a 2 mm jaw at 512 x 384): searching took 20 to 30 us a step; a sorted copy with a
    /// binary search per neighbour (until 2026-11-29) 4 to 5 us, each step a stroke cut a fibre while
    /// the forceps held (the cut changes the body's revision, so the force is summed again). The same
    /// sum in the same order as [`Tissue::force_on`], so the same force to the bit.
    pub fn force_on_many(&self, held: &[ElementId], marks: &mut Vec<u64>) -> [f32; 3] {
        let words = self.body.element_count().div_ceil(64);
        if marks.len() != words {
            marks.clear();
            marks.resize(words, 0);
        }
        let set = |marks: &mut [u64], e: ElementId, on: bool| {
            if let Some(w) = marks.get_mut(e.index() / 64) {
                let bit = 1u64 << (e.index() % 64);
                *w = if on { *w | bit } else { *w & !bit };
            }
        };
        for &e in held {
            set(marks, e, true);
        }
        let marked = &marks[..];
        let f = self.force_on_where(held, |n| crate::chainmail::has_bit(marked, n.index()));
        for &e in held {
            set(marks, e, false);
        }
        f
    }

    /// [`Tissue::force_on`] with the set's membership test given.
    #[inline(always)]
    fn force_on_where(&self, held: &[ElementId], within: impl Fn(ElementId) -> bool) -> [f32; 3] {
        if let Model::Fem(fem) = &self.model {
            return if held.is_empty() { [0.0; 3] } else { fem.reaction() };
        }
        // A volume of elastic cells pushes back by its cells' energy: `K u` holds the set, so the
        // tissue exerts its opposite.
        if let Some(g) = self.body.elastic_force(held) {
            return g.map(|x| -x);
        }
        let mut f = [0.0f32; 3];
        for &e in held {
            for (n, l) in self.body.lattice().neighbours(e) {
                if within(n) {
                    continue;
                }
                let g = self.link_force_on(l, e, n);
                f = [f[0] + g[0], f[1] + g[1], f[2] + g[2]];
            }
        }
        f
    }

    /// How stiffly the tissue resists moving a held patch of radius `radius` (metres) around
    /// `centre` further as one, newtons per metre, from the material and the tissue's size rather than
    /// its elements (so the same at every spacing): for a layer, the annulus of membrane between the
    /// patch and the nearest pinned element at `R_out`, `2π·E·t / ln(R_out / radius)` (plane stress,
    /// ν = 0, `R_out` at least twice the radius); for a volume, a rigid punch on the lattice,
    /// `4·c·radius`. Walks the pinned elements once: call it once per grasp, not every step.
    pub fn patch_stiffness(&self, centre: ElementId, radius: f32) -> f32 {
        let radius = radius.max(f32::MIN_POSITIVE);
        // The stiffest material among the centre's own (not connective) links.
        let modulus = |scale: &dyn Fn(&crate::chainmail::Material) -> f32| {
            self.body
                .lattice()
                .neighbours(centre)
                .filter(|&(_, l)| self.link_kind.get(l.index()).is_some_and(|k| *k != LinkKind::Connective))
                .filter_map(|(_, l)| self.body.link_material(l).and_then(|m| self.body.material(m)))
                .map(scale)
                .fold(0.0f32, f32::max)
        };
        match self.geometry {
            Geometry::Volume => 4.0 * radius * modulus(&volume_modulus),
            Geometry::Surface(_) => {
                let rest = self.body.lattice().rest_positions();
                let Some(&c) = rest.get(centre.index()) else { return 0.0 };
                let c = self.geometry.to_world(c);
                let mut nearest = f32::INFINITY;
                for p in self.body.pinned_elements() {
                    if let Some(&r) = rest.get(p.index()) {
                        nearest = nearest.min(norm(sub(self.geometry.to_world(r), c)));
                    }
                }
                let ratio = (nearest / radius).clamp(2.0, 1.0e6);
                std::f32::consts::TAU * modulus(&|m| m.young_modulus * m.thickness) / ratio.ln()
            }
        }
    }

    /// Energy needed to cut a link, joules: its material's toughness times the area the blade cuts
    /// (see the module's comment).
    pub fn cut_energy(&self, l: LinkId) -> f32 {
        let (Some(&[c, side]), Some(&kind)) = (self.forces.cut.get(l.index()), self.link_kind.get(l.index()))
        else {
            return 0.0;
        };
        let Some(m) = self.body.link_material(l).and_then(|m| self.body.material(m)) else { return 0.0 };
        match spring(self, kind) {
            Spring::Membrane => m.toughness * m.thickness * c,
            // The fibre's share of the band the blade sweeps; under a blade narrower than the fibres'
            // spacing each fibre stands for its site's side of the stroke, as one row of them would.
            Spring::Fibre => m.toughness * c / (2.0 * self.blade_half_width).max(side).max(f32::MIN_POSITIVE),
            Spring::Solid => m.toughness * c,
        }
    }

    /// How much tissue a link stands for, the same at every resolution when summed over the links a
    /// cut or tear breaks: for a layer on a surface, the length of a line across the layer that
    /// breaks it (its tributary width, metres); for a connective fibre, the area of the layers'
    /// interface it holds (its cell's area over the fibres' density, square metres); for a solid's
    /// link, its tributary cross-section (square metres). Zero for an unknown link.
    pub fn link_extent(&self, l: LinkId) -> f32 {
        self.forces.extent.get(l.index()).copied().unwrap_or(0.0)
    }

    /// Energy spent cutting since the last call, joules (taken).
    pub fn take_cut_energy(&mut self) -> f32 {
        std::mem::take(&mut self.cut_energy)
    }

    /// The elements disturbed since relaxation last converged: the only ones whose links' forces may
    /// have changed.
    pub fn active_elements(&self) -> &[ElementId] {
        &self.active
    }

    /// The element the probe pressed on in the last [`Tissue::push`], if it touched the tissue.
    pub fn probe_contact(&self) -> Option<ElementId> {
        self.probe.contact
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chainmail::Material;
    use crate::surface::Surface;
    use crate::tissue::{LayerSpec, LayeredSpec, Pinning, TissueSpec};

    fn sheet(n: usize, material: Material) -> Tissue {
        let spec = TissueSpec::Layered(LayeredSpec {
            surface: Surface::Plane { width: 0.04, depth: 0.04 },
            resolution: [n, n],
            u_coords: None,
            v_coords: None,
            layers: vec![LayerSpec { name: "skin".into(), color: [1.0; 4], offset: 0.0, material }],
            connective: None,
            pinned: Pinning::Boundary,
        });
        Tissue::build(&spec).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn membrane_springs_are_e_times_t_at_any_spacing() {
        let m = Material { young_modulus: 2.0e6, thickness: 5.0e-4, ..Material::default() };
        for n in [9, 17, 33] {
            let t = sheet(n, m);
            // An interior link (the middle row's first link along u from the centre).
            let c = ElementId((n / 2 + n * (n / 2)) as u32);
            let (_, l) = t.body().lattice().neighbours(c).next().unwrap_or_else(|| panic!("no link"));
            let k = t.link_stiffness(l);
            assert!((k - 1000.0).abs() < 1.0, "{n}: k = {k}");
        }
    }

    #[test]
    fn a_uniformly_stretched_sheet_pulls_its_edge_by_tension_times_length() {
        // Every element moved out by 10 % from the centre: uniform biaxial strain 0.1, tension
        // E·t·0.1 N/m on any cut. The net pull on one interior element is zero, on the whole right
        // column minus its corners it is the tension times the column's length.
        let m = Material { young_modulus: 1.0e6, thickness: 1.0e-3, ..Material::relative(2.0, 0.5, 1.0) };
        for n in [11, 21] {
            let mut t = sheet(n, m);
            let rest: Vec<[f32; 3]> = t.body().lattice().rest_positions().to_vec();
            for (i, p) in rest.iter().enumerate() {
                let _ = t.body_mut().set_position(ElementId(i as u32), [1.1 * p[0], 1.1 * p[1], p[2]]);
            }
            let mid = ElementId((n / 2 + n * (n / 2)) as u32);
            let f = t.force_on(&[mid]);
            assert!(norm(f) < 1e-3, "{n}: interior {f:?}");
            let column: Vec<ElementId> = (1..n - 1).map(|j| ElementId((n - 1 + n * j) as u32)).collect();
            let f = t.force_on(&column);
            // Length of the column (rest, between the corners' half cells): (n - 2) cells of 0.04/(n-1).
            let expected = 1.0e6 * 1.0e-3 * 0.1 * 0.04 * (n - 2) as f32 / (n - 1) as f32;
            assert!((-f[0] - expected).abs() < 0.02 * expected, "{n}: {f:?} against {expected}");
        }
    }

    #[test]
    fn a_patch_is_as_stiff_at_any_spacing() {
        let m = Material { young_modulus: 2.0e6, thickness: 5.0e-4, ..Material::default() };
        let k: Vec<f32> = [17, 33, 65]
            .iter()
            .map(|&n| sheet(n, m).patch_stiffness(ElementId((n / 2 + n * (n / 2)) as u32), 0.001))
            .collect();
        // The annulus from the jaws (1 mm) to the pinned edge (20 mm): 2π·E·t / ln 20.
        let expected = std::f32::consts::TAU * 1000.0 / 20.0f32.ln();
        for x in &k {
            assert!((x - expected).abs() < 1e-3 * expected, "{k:?} against {expected}");
        }
    }

    /// Two layers joined by fibres whose sites are 1 mm apart: at 1, 0.5 and 0.25 mm spacing (one
    /// element in 1, 2 and 4 a site) they have the same fibres, and together the fibres are as stiff
    /// and cost as much to cut through.
    #[test]
    fn fibres_are_as_many_as_stiff_and_as_tough_at_any_spacing() {
        use crate::tissue::ConnectiveSpec;
        let m = Material { young_modulus: 2.0e6, thickness: 5.0e-4, ..Material::relative(1.3, 0.8, 0.3) };
        let fibre = Material { young_modulus: 2.0e4, toughness: 500.0, ..Material::relative(2.0, 0.5, 0.5) };
        let layer =
            |name: &str, offset: f32| LayerSpec { name: name.into(), color: [1.0; 4], offset, material: m };
        let totals: Vec<(usize, [u32; 2], f32, f32)> = [41, 81, 161]
            .iter()
            .map(|&n| {
                let t = Tissue::build(&TissueSpec::Layered(LayeredSpec {
                    surface: Surface::Plane { width: 0.04, depth: 0.04 },
                    resolution: [n, n],
                    u_coords: None,
                    v_coords: None,
                    layers: vec![layer("upper", 0.003), layer("lower", 0.0)],
                    connective: Some(ConnectiveSpec {
                        material: fibre,
                        density: 0.5,
                        min_gap: 0.0,
                        spacing: 0.001,
                    }),
                    pinned: Pinning::Boundary,
                }))
                .unwrap_or_else(|e| panic!("{e}"));
                let fibres: Vec<LinkId> = t.connective_links().collect();
                let stiffness = fibres.iter().map(|&l| t.link_stiffness(l)).sum();
                let toughness = fibres.iter().map(|&l| t.cut_energy(l)).sum();
                (fibres.len(), t.fibre_stride, stiffness, toughness)
            })
            .collect();
        assert_eq!(totals.iter().map(|t| t.1).collect::<Vec<_>>(), [[1, 1], [2, 2], [4, 4]]);
        let (count, _, stiffness, toughness) = totals[0];
        assert!(count > 500, "{count} fibres");
        for &(c, stride, k, e) in &totals[1..] {
            assert_eq!(c, count, "stride {stride:?}: the same sites");
            assert!(
                (k - stiffness).abs() < 0.05 * stiffness,
                "stride {stride:?}: stiffness {k} against {stiffness}"
            );
            assert!(
                (e - toughness).abs() < 0.05 * toughness,
                "stride {stride:?}: cut energy {e} against {toughness}"
            );
        }
    }

    /// The force on a large set with its membership read from a bit per element is the plain search's
    /// to the bit, on a stretched and sheared sheet and a set in no particular order, and the bits are
    /// left clear.
    #[test]
    fn a_large_set_feels_the_force_a_search_finds() {
        let mut t = sheet(33, Material::relative(2.0, 0.5, 1.0));
        let rest: Vec<[f32; 3]> = t.body().lattice().rest_positions().to_vec();
        for (i, p) in rest.iter().enumerate() {
            let shear = 0.05 * p[2] + 0.001 * (i % 7) as f32;
            let _ = t.body_mut().set_position(ElementId(i as u32), [1.1 * p[0] + shear, p[1], 0.95 * p[2]]);
        }
        // A patch of 9 x 9 around the centre, listed from the centre outwards in a scrambled order.
        let mut held: Vec<ElementId> =
            (12..21).flat_map(|j| (12..21).map(move |i| ElementId((i + 33 * j) as u32))).collect();
        held.sort_by_key(|e| (e.0 * 7919) % 101);
        let mut marks = Vec::new();
        let (plain, many) = (t.force_on(&held), t.force_on_many(&held, &mut marks));
        assert!(norm(plain) > 0.0, "no force on the patch");
        assert_eq!(plain.map(f32::to_bits), many.map(f32::to_bits));
        assert!(marks.iter().all(|&w| w == 0), "marks left set");
        let again = t.force_on_many(&held, &mut marks);
        assert_eq!(plain.map(f32::to_bits), again.map(f32::to_bits));
    }

    #[test]
    fn slack_membrane_pushes_nothing() {
        let mut t = sheet(9, Material::default());
        let e = ElementId(4 + 9 * 4);
        let p = t.body().positions()[e.index()];
        let _ = t.body_mut().set_position(e, [p[0] + 0.001, p[1], p[2]]);
        // One link is compressed (ignored), the opposite one stretched: a pull back along -x only.
        let f = t.force_on(&[e]);
        assert!(f[0] < 0.0 && f[1].abs() < 1e-6, "{f:?}");
    }
}
