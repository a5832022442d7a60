//! Tissue: one or two SurfaceChainMail layers joined by connective fibres, or a ChainMail volume; how
//! it is grasped, pushed, cut and torn, and how it keeps its layers apart.
//!
//! A layered tissue is a single ChainMail lattice in `(u, v, h)` coordinates (see [`crate::surface`]):
//! each layer is a `u × v` sheet at its rest offset `h`, and the connective fibres are the links along
//! `h` between the two sheets, with their own, softer material. A deformation runs in two parts, as in
//! the paper: first the chain reaction in the `(u, v)` plane ([`Pass::Plane`]), then the pass along the
//! surface normal ([`Pass::Normal`]), where a neighbour whose normal separation exceeds
//! `MaxRelShear × Dist` moves along its normal to exactly that separation. The two results combine into
//! the new 3D shape `X(u, v) + h·N(u, v)`.
//!
//! Must not import wgpu, winit or egui. Topology changes (cuts, tears) happen only in
//! [`Tissue::apply_cuts`] and [`Tissue::apply_tears`], which bump [`Tissue::topology_version`].

mod bits;
mod build;
mod cut;
mod fem_drive;
mod force;
mod grasp;
mod grow;
mod limits;
mod link_grid;
mod mesh;
mod press;
mod scan;
mod settle;
mod spec;

pub use build::{LayeredSpec, TissueError, TissueSpec, VolumeSpec};
pub use cut::{CutDepth, CutSegment};
pub use fem_drive::{FEM_CUT_REFUSED, FemDrive, FemSpec};
pub use mesh::MeshRecipe;
pub use spec::{ConnectiveSpec, Edge, LayerSpec, Pinning};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::chainmail::{Body, BreakReason, ElementId, LinkId, MaterialId, Pass, RelaxBudget, Workspace};
use crate::surface::Surface;

/// How lattice coordinates map to the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Geometry {
    /// Layers on a parametric surface: lattice `(u, v, h)`.
    Surface(Surface),
    /// A volume: lattice coordinates are world coordinates.
    Volume,
}

impl Geometry {
    /// World position of lattice coordinates.
    #[inline]
    pub fn to_world(&self, p: [f32; 3]) -> [f32; 3] {
        match self {
            Geometry::Surface(s) => s.to_world(p),
            Geometry::Volume => p,
        }
    }

    /// Lattice coordinates of a world point (`u_hint` chooses the branch of a wrapped `u`).
    #[inline]
    pub fn to_lattice(&self, p: [f32; 3], u_hint: f32) -> [f32; 3] {
        match self {
            Geometry::Surface(s) => s.to_lattice(p, u_hint),
            Geometry::Volume => p,
        }
    }
}

/// A little under 1: the tear check's multiplication test lets through every link whose stretch, divided
/// out and rounded, could lie above the bar (16 units in the last place of margin against the 3 that
/// rounding can take).
const NEAR: f32 = 1.0 - 1e-6;

/// The tear scan's test of one link at squared length `d2` (squared rest length `rest2`, squared tear
/// ratio `ratio2`): a layer's link raises `max_stretch2`, a link past its ratio is `hit`.
#[inline(always)]
fn tear_test(d2: f32, rest2: f32, ratio2: f32, layer: bool, max_stretch2: &mut f32, hit: impl FnOnce()) {
    if near_bar(d2, rest2, ratio2, layer, *max_stretch2) {
        tear_divide(d2, rest2, ratio2, layer, max_stretch2, hit);
    }
}

/// Whether the pair of element `e` (of a sheet of `sheet` elements a layer) is closer than `min_gap`
/// along the normal, or its gap is NaN.
#[inline(always)]
fn gap_short(pos: &[[f32; 3]], sheet: u32, min_gap: f32, e: ElementId) -> bool {
    let (l, u) = limits::partners(e.index(), sheet);
    match (pos.get(l), pos.get(u)) {
        (Some(pl), Some(pu)) => !matches!(
            (pu[2] - pl[2]).partial_cmp(&min_gap),
            Some(std::cmp::Ordering::Greater | std::cmp::Ordering::Equal)
        ),
        _ => false,
    }
}

/// The first half of [`tear_test`]: whether the link may be the largest stretch so far or past its
/// tear ratio. Most links are neither: a multiplication tells, a little on the safe side (`NEAR` lets
/// through every link whose quotient could round above the bar), so the division runs only near the
/// bar and its results are exactly those of dividing every link. The bar is `ratio2.min(max_stretch2)`
/// for a layer's link: neither is ever NaN (a validated material's ratio, and the largest stretch
/// never takes a NaN), so a comparison does. A NaN length goes on to the division.
#[inline(always)]
fn near_bar(d2: f32, rest2: f32, ratio2: f32, layer: bool, max_stretch2: f32) -> bool {
    let bar = if layer && max_stretch2 < ratio2 { max_stretch2 } else { ratio2 };
    matches!(d2.partial_cmp(&(bar * rest2 * NEAR)), Some(std::cmp::Ordering::Greater) | None)
}

/// The second half of [`tear_test`], for a link near its bar: the division, the largest stretch and
/// the tear.
#[inline(always)]
fn tear_divide(d2: f32, rest2: f32, ratio2: f32, layer: bool, max_stretch2: &mut f32, hit: impl FnOnce()) {
    let stretch2 = d2 / rest2;
    if layer {
        *max_stretch2 = max_stretch2.max(stretch2);
    }
    if stretch2 > ratio2 {
        hit();
    }
}

/// What the tear scan needs to also test links against their boxes (see `limits.rs`): the tolerance,
/// and which elements the step moved (those whose stamp is `stamp`).
#[derive(Clone, Copy)]
pub(crate) struct BoxCheck<'a> {
    pub(crate) tol: f32,
    pub(crate) stamps: &'a [u32],
    pub(crate) stamp: u32,
}

const NO_BOXES: BoxCheck<'static> = BoxCheck { tol: 0.0, stamps: &[], stamp: 0 };

/// What the limits' repair's scan of the region found (see [`Tissue::scan_tears`]): it stands for the
/// tear check, the drift and the region's pruning while the body's motion and revision are still
/// `key` (nothing moved, cut or torn since; tears and cuts add elements to the region).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RegionScan {
    key: (u64, u64),
    /// The largest squared stretch of the layers' links (`tear_hits` holds the tears).
    max_stretch2: f32,
    /// The region's drift (see `Tissue::drift`).
    pub(crate) drift: f32,
}

/// What the limits' repair's scan of the region finds besides tears (see [`Tissue::scan_region`]).
#[derive(Default)]
struct ScanFound<'a> {
    /// A link the step moved lies outside its box.
    outside: bool,
    /// The largest of `|du|`, `|dv|` from rest over the region (see `Tissue::drift`).
    drift: f32,
    /// The region's elements that still move or have a neighbour that does (see
    /// `Tissue::prune_region`), in the region's order.
    keep: Option<&'a mut Vec<ElementId>>,
}

/// What a link is part of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LinkKind {
    /// A link within layer `n` (0 is the upper layer, as in [`Tissue::layers`]).
    Layer(u8),
    /// A connective fibre between the layers.
    Connective,
}

/// A layer (or a volume's outer surface) as drawn and picked.
#[derive(Clone, Debug)]
pub struct Layer {
    /// Name from the scene.
    pub name: String,
    /// Linear RGBA colour.
    pub color: [f32; 4],
    /// First element of the layer; its elements are `first .. first + count`.
    pub first: u32,
    /// Number of elements (vertices of its mesh).
    pub count: u32,
    /// The layer's material.
    pub material: MaterialId,
    /// Candidate triangles (element ids, global) with the two lattice links each spans; a triangle is
    /// drawn while both links are intact.
    pub(crate) triangles: Vec<([u32; 3], [u32; 2])>,
    /// `[nu, nv]` when the layer's elements are a surface grid in rows along `u` (see
    /// [`crate::snapshot::LayerMesh::grid`]).
    pub(crate) grid: Option<[u32; 2]>,
    /// Rings closed by a fan round an extra vertex (a sphere's poles, which are not lattice rows so
    /// that no link is degenerate): each ring's elements in order, the links between neighbours, and
    /// whether the fan's winding must be flipped to face outwards.
    pub(crate) caps: Vec<Cap>,
    /// Which of its triangles are drawn: a new number whenever a link between two of its elements
    /// breaks, one no other layer or tissue has (a fibre cut leaves both layers' triangles as they
    /// were, so neither the published frame nor the renderer rebuilds them).
    pub(crate) version: u64,
}

/// A ring of elements closed by a fan round a vertex drawn at the ring's pole.
#[derive(Clone, Debug)]
pub(crate) struct Cap {
    pub(crate) ring: Vec<u32>,
    pub(crate) links: Vec<u32>,
    pub(crate) flip: bool,
}

/// A topology change, for whoever keeps structures built on the mesh (render buffers, picking).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopologyEvent {
    /// The link that broke.
    pub link: LinkId,
    /// What it was part of.
    pub kind: LinkKind,
    /// Why it broke.
    pub reason: BreakReason,
}

/// Running totals of what the tissue went through.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Damage {
    /// In-layer links cut.
    pub layer_links_cut: u64,
    /// Connective links cut.
    pub connective_links_cut: u64,
    /// Links torn by over-stretching (either kind).
    pub links_torn: u64,
    /// How much of the layers tore ([`Tissue::link_extent`] summed): metres of tear line on a
    /// surface, square metres in a volume.
    #[serde(default)]
    pub layer_torn: f32,
    /// Area of connective tissue torn, square metres.
    #[serde(default)]
    pub connective_torn_m2: f32,
}

/// What moves the tissue when an instrument displaces an element.
#[derive(Clone, Debug)]
pub enum Model {
    /// Gibson's chain reaction (in two passes on a surface), then relaxation; cuts and tears change
    /// the topology.
    ChainMail,
    /// A linear finite-element volume: the displacement is imposed on the condensed, pre-inverted
    /// model, which gives every surface node's answer. No relaxation, no tears; cuts are refused
    /// (condensation assumes a fixed topology).
    Fem(Box<FemDrive>),
}

/// A deformable tissue.
#[derive(Clone, Debug)]
pub struct Tissue {
    pub(crate) body: Body,
    /// What finishes the meshes filled raw (the geometry and the layers' caps, which never change).
    pub(crate) mesh_recipe: std::sync::Arc<MeshRecipe>,
    pub(crate) ws: Workspace,
    pub(crate) geometry: Geometry,
    pub(crate) layers: Vec<Layer>,
    pub(crate) link_kind: Vec<LinkKind>,
    /// The links of each kind, bucketed where they rest (a cut looks only at the kind its depth
    /// reaches, and there only near its stroke).
    pub(crate) kind_links: Vec<(LinkKind, link_grid::LinkGrid)>,
    /// Links a stroke may reach (scratch of a cut).
    pub(crate) cut_candidates: Vec<u32>,
    /// Each layer's surface elements bucketed where they rest, on a flat surface (empty otherwise):
    /// where the search for the element nearest a point looks (`Tissue::nearest_element`).
    pub(crate) layer_elements: Vec<link_grid::LinkGrid>,
    /// How far any element has drifted from rest across the surface, and at which motion count of
    /// the body that was measured.
    pub(crate) drift_max: f32,
    pub(crate) drift_at: Option<u64>,
    /// Scratch of the tear check: each material's tear ratio, squared (infinite for none).
    pub(crate) tear_scratch: Vec<f32>,
    /// The links a tear check found past their tear ratio, broken after the scan.
    pub(crate) tear_hits: Vec<LinkId>,
    /// What the limits' repair's scan of the region found this step (with `tear_hits` and
    /// `scan_keep`; see [`Tissue::scan`]).
    pub(crate) region_scan: Option<RegionScan>,
    /// What the region keeps at the end of the step, as that scan found it (see `prune_region`).
    pub(crate) scan_keep: Vec<ElementId>,
    /// The slot classes' boxes widened by the repair's tolerance, for the tear scan's box test.
    pub(crate) wide_scratch: Vec<[[f32; 3]; 2]>,
    /// Each element's links from its `a` end, as the tear scan reads them on a flat surface.
    pub(crate) scan_table: scan::ScanTable,
    /// The lattice's common patterns of neighbours, for growing the region a word at a time
    /// (`grow.rs`).
    pub(crate) growth: grow::Growth,
    /// The aggregates of the region's coarse-grid correction (`settle.rs`), made when the tissue is
    /// built.
    pub(crate) coarse: crate::chainmail::Coarse,
    /// Whether tissue let go is settling: the region's relaxation adds the coarse correction
    /// (`settle.rs`). Set by a release, cleared by a grasp and once the region is empty.
    pub(crate) settling: bool,
    /// Steps the current settling has lasted.
    pub(crate) settle_steps: u32,
    /// The fill of a release (`Tissue::settle_from`): elements found, as bits, and those to visit.
    pub(crate) fill_bits: Vec<u64>,
    pub(crate) fill_stack: Vec<u32>,
    pub(crate) fill_found: Vec<u32>,
    /// Scratch of the pieces of a tear scan split over two threads (see `scan.rs`).
    pub(crate) scan_spare: scan::ScanSpare,
    /// World rest length of each link, metres (for stretch and tearing).
    pub(crate) rest_len: Vec<f32>,
    /// The connective fibres in link order, each with where it stands at rest (see
    /// [`crate::snapshot::Snapshot::fibre_sites`]): filled once, read by every snapshot.
    pub(crate) fibre_sites: Vec<(LinkId, [f32; 4])>,
    /// How many elements apart the fibres' sites are along `u` and `v` (`ConnectiveSpec::stride`):
    /// a fibre's site stands for their product of the interface's cells, `[1, 1]` where every element
    /// is a site.
    pub(crate) fibre_stride: [u32; 2],
    /// Elements per layer sheet (`nu × nv`) for layered tissue; pairs across layers differ by this.
    pub(crate) sheet: u32,
    pub(crate) min_gap: f32,
    /// Elements disturbed since relaxation last converged.
    pub(crate) active: Vec<ElementId>,
    pub(crate) in_active: Vec<bool>,
    /// Each element's move in its last relaxation sweep (infinite when put into the region since;
    /// 0 outside the region), for pruning the region.
    pub(crate) last_move: Vec<f32>,
    pub(crate) region_scratch: Vec<ElementId>,
    /// The region as the last step's relaxation, contact and repair left it, before it was pruned
    /// (for tests that tell what relaxation moved from what a pull moved).
    #[cfg(test)]
    pub(crate) stepped_region: Vec<ElementId>,
    /// A bit per element, for putting the region in order (empty between steps).
    pub(crate) region_bits: bits::Bits,
    /// A bit per element the step's chain reactions moved and the region has not taken in yet: they
    /// and their neighbours join it in memory order ([`Tissue::take_moved`]), not in the order a
    /// reaction reached them (a lifting step moves tens of thousands).
    pub(crate) moved_bits: bits::Bits,
    /// Whether `moved_bits` holds any bit.
    pub(crate) moved_pending: bool,
    /// Where the next partial relaxation sweep of a large region starts (an element id; see
    /// `settle::REGION_UPDATES`).
    pub(crate) relax_cursor: u32,
    /// This step's relaxation of settling tissue swept only part of its region: where in the region
    /// (`active[start..]`, going round, `len` elements), if nothing else has moved this step
    /// (`Tissue::sweep_window`).
    pub(crate) swept: Option<(usize, usize)>,
    /// Steps whose contact and tear checks looked only at what the sweep moved (see
    /// `Tissue::scan_sweep_window`).
    pub(crate) swept_checks: u64,
    /// Elements the step's chain reactions have moved so far (relaxation gets what is left of
    /// `settle::REGION_UPDATES`).
    pub(crate) step_moved: usize,
    /// The last relaxation converged and nothing has moved since: [`Tissue::end_step`] may forget the
    /// disturbed region.
    pub(crate) settled: bool,
    pub(crate) cut_queue: Vec<CutSegment>,
    pub(crate) events: Vec<TopologyEvent>,
    pub(crate) topology_version: u64,
    pub(crate) damage: Damage,
    /// Largest link stretch (world length over rest length) seen at the last check.
    pub(crate) max_stretch: f32,
    pub(crate) spacing: f32,
    /// What moves the elements: ChainMail, or a finite-element model (volumes).
    pub(crate) model: Model,
    /// Something the trainee should be told (a refused cut).
    pub(crate) notice: Option<String>,
    /// What the forceps' jaws hold.
    pub(crate) jaws: grasp::Jaws,
    /// Connective fibres within this distance of a `Between` stroke are severed, metres.
    pub(crate) blade_half_width: f32,
    /// Elements on the outer surface (vertices of a drawn triangle): what instruments can touch.
    pub(crate) on_surface: Vec<bool>,
    /// Lattice coordinates where surface fractions 0 lie, and what fraction 1 adds (see
    /// [`Tissue::surface_fractions`]).
    pub(crate) extent_lo: [f32; 3],
    pub(crate) extent_span: [f32; 3],
    /// Spring constants' geometric factors and cut areas per link (see `force.rs`).
    pub(crate) forces: force::LinkFactors,
    /// Energy spent cutting since it was last taken, joules.
    pub(crate) cut_energy: f32,
    /// The probe: what it pressed at the last push, and its press's cone (`press.rs`).
    pub(crate) probe: press::Probe,
    /// What the step moved, and the scratch of the repair that keeps the links within their limits
    /// (see `limits.rs`).
    pub(crate) repair: limits::Repair,
}

impl Tissue {
    /// The ChainMail body.
    pub fn body(&self) -> &Body {
        &self.body
    }

    /// Mutable access to the body (materials tuned live, pins changed).
    pub fn body_mut(&mut self) -> &mut Body {
        self.drift_at = None; // whatever moves through it moves outside the disturbed region
        &mut self.body
    }

    /// How lattice coordinates map to the world.
    pub fn geometry(&self) -> Geometry {
        self.geometry
    }

    /// The layers, upper (outer) first, as scenes list them and snapshots show them. (In the lattice
    /// the lower layer's elements come first: `first` says where each layer's run starts.)
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// What each link is part of.
    pub fn link_kind(&self, l: LinkId) -> Option<LinkKind> {
        self.link_kind.get(l.index()).copied()
    }

    /// Every connective link.
    pub fn connective_links(&self) -> impl Iterator<Item = LinkId> + '_ {
        self.link_kind
            .iter()
            .enumerate()
            .filter(|(_, k)| **k == LinkKind::Connective)
            .map(|(i, _)| LinkId(i as u32))
    }

    /// Bumped at every cut or tear.
    pub fn topology_version(&self) -> u64 {
        self.topology_version
    }

    /// Damage so far.
    pub fn damage(&self) -> Damage {
        self.damage
    }

    /// Largest stretch of an in-layer link found by the last [`Tissue::apply_tears`] (the force proxy;
    /// connective fibres are left out, they are meant to stretch before they are cut).
    pub fn max_stretch(&self) -> f32 {
        self.max_stretch
    }

    /// Typical element spacing, metres.
    pub fn spacing(&self) -> f32 {
        self.spacing
    }

    /// Smallest normal gap kept between the layers, metres.
    pub fn min_gap(&self) -> f32 {
        self.min_gap
    }

    /// The topology events since the last call (drained).
    pub fn drain_events(&mut self) -> std::vec::Drain<'_, TopologyEvent> {
        self.events.drain(..)
    }

    /// World position of an element.
    pub fn world_position(&self, e: ElementId) -> Option<[f32; 3]> {
        self.body.positions().get(e.index()).map(|&p| self.geometry.to_world(p))
    }

    /// Which layer an element belongs to (0 is the upper layer).
    pub fn layer_of(&self, e: ElementId) -> Option<usize> {
        self.layers.iter().position(|l| e.0 >= l.first && e.0 < l.first + l.count)
    }

    /// The element of the other layer paired with `e` (same `u`, `v` column), for two-layer tissue.
    pub fn partner(&self, e: ElementId) -> Option<ElementId> {
        if self.layers.len() != 2 || self.sheet == 0 {
            return None;
        }
        match self.layer_of(e)? {
            0 => Some(ElementId(e.0 - self.sheet)),
            _ => Some(ElementId(e.0 + self.sheet)),
        }
    }

    /// The element on the surface nearest to a world point, optionally within one layer (0 is the
    /// upper layer). Elements inside a volume are out of an instrument's reach. On a flat surface it
    /// looks only near the point, as far as the elements' drift from rest requires (see
    /// `Tissue::nearest_in`): a grasp costs a few microseconds, not a walk over the whole layer
    /// (0.6 ms at 512 × 384).
    pub fn nearest_element(&self, p: [f32; 3], layer: Option<usize>) -> Option<ElementId> {
        let drift = match self.geometry {
            Geometry::Surface(s) if s.is_flat() && self.layer_elements.len() == self.layers.len() => {
                self.drift_bound()
            }
            _ => None,
        };
        let mut best: Option<(f32, u32)> = None;
        // In element order (the lower layer first), so that ties go to the lower id.
        for (li, l) in self.layers.iter().enumerate().rev() {
            if layer.is_some_and(|x| x != li) {
                continue;
            }
            let found = match (drift, self.layer_elements.get(li)) {
                (Some(d), Some(grid)) if !grid.is_whole() => self.nearest_in(grid, p, d),
                _ => None,
            }
            .unwrap_or_else(|| self.nearest_of(l.first..l.first + l.count, p));
            if let Some((d, i)) = found
                && best.is_none_or(|(bd, _)| d < bd)
            {
                best = Some((d, i));
            }
        }
        best.map(|(_, i)| ElementId(i))
    }

    /// The surface element of `ids` nearest `p` (world) and its squared distance; ties go to the
    /// lower id. The plain search, and what the search by cells is compared with.
    fn nearest_of(&self, ids: impl Iterator<Item = u32>, p: [f32; 3]) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for i in ids {
            if !self.on_surface.get(i as usize).copied().unwrap_or(false) {
                continue;
            }
            let Some(&q) = self.body.positions().get(i as usize) else { continue };
            let d = Vec3::from(self.geometry.to_world(q)).distance_squared(Vec3::from(p));
            if best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                best = Some((d, i));
            }
        }
        best
    }

    /// [`Tissue::nearest_of`] a layer's elements on a flat surface, looking only where the nearest can
    /// be: no element lies further than `drift` across the plane from where it rests (each of `u`
    /// and `v`), so one whose rest lies more than `w` from `p` along `u` or `v` is more than
    /// `w − drift` away. The search reads the cells within `w` of `p` (from a cell's width, doubled
    /// until it holds an element no further than `w − drift`, or the whole layer); then no element
    /// outside them can be nearer or as near. The same answer as the plain search, ties included;
    /// `None` where it cannot bound the search (a point or drift that is not finite), for the plain one.
    fn nearest_in(&self, grid: &link_grid::LinkGrid, p: [f32; 3], drift: f32) -> Option<Option<(f32, u32)>> {
        // A flat surface's lattice coordinates are the world's permuted (`Surface::flat_to_world`).
        let uv = [p[0], p[2]];
        if !(p.iter().all(|x| x.is_finite()) && drift.is_finite()) {
            return None;
        }
        let mut w = grid.cell_width().max(self.spacing);
        while w.is_finite() {
            let mut best: Option<(f32, u32)> = None;
            for ids in grid.cells_near(uv, uv, w) {
                if let Some(b) = self.nearest_of(ids.iter().copied(), p)
                    && best.is_none_or(|(bd, bi)| b.0 < bd || (b.0 == bd && b.1 < bi))
                {
                    best = Some(b);
                }
            }
            let reach = w - drift;
            if grid.covers(uv, uv, w) || best.is_some_and(|(d, _)| reach > 0.0 && d <= reach * reach) {
                return Some(best);
            }
            w *= 2.0;
        }
        None
    }

    /// The world point at fractions `(uf, vf)` of the surface's `u` and `v` extent and `h` metres along
    /// the normal from the base surface (for a volume: over its top face, `h` above it).
    pub fn surface_point(&self, uf: f32, vf: f32, h: f32) -> [f32; 3] {
        let (lo, span) = (self.extent_lo, self.extent_span);
        match self.geometry {
            Geometry::Surface(s) => s.to_world([lo[0] + uf * span[0], lo[1] + vf * span[1], h]),
            Geometry::Volume => [lo[0] + uf * span[0], lo[1] + span[1] + h, lo[2] + vf * span[2]],
        }
    }

    /// The surface fractions `(u, v)` of a point in lattice coordinates, as scenes, scripts and goals
    /// give them (for a volume: across its top face).
    pub fn surface_fractions(&self, p: [f32; 3]) -> (f32, f32) {
        let (lo, span) = (self.extent_lo, self.extent_span);
        let k = match self.geometry {
            Geometry::Surface(_) => 1,
            Geometry::Volume => 2,
        };
        ((p[0] - lo[0]) / span[0], (p[k] - lo[k]) / span[k])
    }

    /// How many steps' contact and tear checks looked only at the elements the step's sweep moved
    /// (settling tissue, see `settle.rs`), since the tissue was built.
    pub fn swept_checks(&self) -> u64 {
        self.swept_checks
    }

    /// Marks an element as held by an instrument (or lets it go).
    pub fn set_held(&mut self, e: ElementId, held: bool) {
        self.hold(e, held);
        if held {
            self.settling = false;
        } else {
            // What is let go settles (`settle.rs`): nothing else would move it back.
            self.settle_from([e]);
        }
    }

    /// [`Tissue::set_held`] without the settling of a release.
    pub(crate) fn hold(&mut self, e: ElementId, held: bool) {
        // Out-of-range ids are ignored: the instrument only holds ids this tissue issued.
        let _ = self.body.set_held(e, held);
        if !held && let Model::Fem(fem) = &mut self.model {
            fem.release(&mut self.body);
        }
    }

    /// What moves the tissue.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Sets the scalpel's blade width, metres: a `Between` stroke severs the fibres within half of it.
    pub fn set_blade_width(&mut self, width: f32) {
        if width.is_finite() && width > 0.0 {
            self.blade_half_width = 0.5 * width;
        }
    }

    /// Whether a finite-element model drives this tissue.
    pub fn is_fem(&self) -> bool {
        matches!(self.model, Model::Fem(_))
    }

    /// The last thing the trainee should be told (a refused cut), taken.
    pub fn take_notice(&mut self) -> Option<String> {
        self.notice.take()
    }

    /// Moves element `e` to `goal` (lattice coordinates) through the tissue's model: one ChainMail
    /// pass, or the finite-element answer to the imposed displacement. Returns the elements moved and
    /// the share of the move the tissue allowed.
    fn displace(&mut self, e: ElementId, goal: [f32; 3], pass: Pass) -> (u32, f32) {
        match &mut self.model {
            Model::ChainMail => {
                let Ok(d) = self.body.deform(&mut self.ws, e, goal, pass) else { return (0, 0.0) };
                self.activate_moved();
                (d.moved, d.fraction)
            }
            Model::Fem(fem) => {
                let r = self.body.lattice().rest_positions()[e.index()];
                let d = [goal[0] - r[0], goal[1] - r[1], goal[2] - r[2]];
                match fem.impose(e, d, &mut self.body) {
                    Ok(moved) => (moved, 1.0),
                    Err(err) => {
                        self.notice = Some(err.to_string());
                        (0, 1.0)
                    }
                }
            }
        }
    }

    pub(crate) fn activate(&mut self, e: u32) {
        let i = e as usize;
        if let Some(m) = self.last_move.get_mut(i) {
            *m = f32::INFINITY;
        }
        if i < self.in_active.len() && !self.in_active[i] {
            self.in_active[i] = true;
            self.active.push(ElementId(e));
        }
    }

    /// Notes the elements the last chain reaction moved (for the limits' repair, in the reaction's
    /// order) and marks them to join the disturbed region with their neighbours. Elements a lift
    /// raised as rigid elements (`chainmail/reaction/lift.rs`) moved as a body and are not among them:
    /// the region keeps the rising tent's rim, not its taut inside, which nothing strains.
    fn activate_moved(&mut self) {
        self.step_moved += self.ws.moved.len() + self.ws.raised_unlisted();
        let n = self.body.element_count();
        self.repair.fit(n);
        self.moved_bits.fit(n);
        // Two loops with their arrays borrowed once (a lift moves tens of thousands of elements a
        // step; one loop kept its state in memory).
        let (moved, bits) = (&self.ws.moved[..], &mut self.moved_bits);
        self.repair.note_all(moved, &self.ws.old);
        let mut any = false;
        for &e in moved {
            if (e as usize) < n {
                bits.set(e as usize);
                any = true;
            }
        }
        self.moved_pending |= any;
    }

    /// Puts the elements chain reactions moved since the last call, and their neighbours, into the
    /// disturbed region (in memory order: the same region, read and written in order).
    pub(crate) fn take_moved(&mut self) {
        if !self.moved_pending {
            return;
        }
        self.moved_pending = false;
        let lat = self.body.lattice();
        let (adj_start, adj_nbr) = (&lat.adj_start[..], &lat.adj_nbr[..]);
        let (last_move, in_active, active) =
            (&mut self.last_move[..], &mut self.in_active[..], &mut self.active);
        // `activate`, on the arrays borrowed once.
        let mut activate = |i: usize| {
            if let (Some(m), Some(a)) = (last_move.get_mut(i), in_active.get_mut(i)) {
                *m = f32::INFINITY;
                if !*a {
                    *a = true;
                    active.push(ElementId(i as u32));
                }
            }
        };
        self.moved_bits.drain(|w, mut x| {
            while x != 0 {
                let e = w * 64 + x.trailing_zeros() as usize;
                x &= x - 1;
                activate(e);
                let (Some(&s0), Some(&s1)) = (adj_start.get(e), adj_start.get(e + 1)) else { continue };
                for &n in adj_nbr.get(s0 as usize..s1 as usize).unwrap_or(&[]) {
                    activate(n as usize);
                }
            }
        });
    }

    /// The deformation passes of this tissue, in order: `[Plane, Normal]` on a surface, `[All]` in a
    /// volume.
    pub fn passes(&self) -> &'static [Pass] {
        match self.geometry {
            Geometry::Surface(_) => &[Pass::Plane, Pass::Normal],
            Geometry::Volume => &[Pass::All],
        }
    }

    /// One deformation pass of a pull of element `e` towards a world point (the world runs
    /// [`Tissue::passes`] in order, timing each): returns the elements moved and the share of the move
    /// the tissue allowed. Pins cut the move short.
    pub fn pull_pass(&mut self, e: ElementId, target: [f32; 3], pass: Pass) -> (u32, f32) {
        let Ok(p) = self.body.position(e) else { return (0, 0.0) };
        let t = self.geometry.to_lattice(target, p[0]);
        if self.is_fem() {
            return self.displace(e, t, pass);
        }
        let slot = grasp::pass_index(pass);
        if let Some(b) = self.jaws.blocked[slot]
            && b.covers(e, (p, t), pass, &self.body, self.jaws.strict)
        {
            self.jaws.spared += 1;
            return (0, b.fraction);
        }
        let (moved, fraction) = if self.jaws.held.len() > 1 && self.jaws.held.first().map(|h| h.0) == Some(e)
        {
            self.pull_jaws(t, pass)
        } else {
            self.displace(e, t, pass)
        };
        self.jaws.blocked[slot] =
            (moved == 0 && fraction < 1.0).then(|| grasp::BlockedPull::new(e, p, t, &self.body, fraction));
        (moved, fraction)
    }

    /// Relaxes the disturbed region within `budget`. The region is kept for the step's contact and
    /// tear checks, which look only there; [`Tissue::end_step`] forgets it once it has converged.
    pub fn relax(&mut self, budget: RelaxBudget) -> crate::chainmail::RelaxReport {
        // What the step's chain reactions moved joins the region as the relaxation puts it in order
        // (`settle.rs`), not one element at a time here.
        if self.is_fem() || (self.active.is_empty() && !self.moved_pending) {
            self.take_moved();
            self.settled = true;
            return crate::chainmail::RelaxReport { converged: true, ..Default::default() };
        }
        let report = self.relax_region(budget);
        self.settled = report.converged;
        report
    }

    /// Closes a step: forgets the disturbed region if the step's relaxation converged and contact
    /// moved nothing afterwards; otherwise shrinks it to what still moves (see `settle.rs`).
    pub fn end_step(&mut self) {
        self.take_moved();
        #[cfg(test)]
        self.stepped_region.clone_from(&self.active);
        if matches!(self.geometry, Geometry::Surface(_)) {
            self.drift(); // before the region forgets what moved
        }
        self.step_moved = 0;
        self.repair.next_step();
        if self.settled && !self.settling {
            for e in self.active.drain(..) {
                self.in_active[e.index()] = false;
                self.last_move[e.index()] = 0.0;
            }
        } else if !self.is_fem() {
            self.prune_region();
        }
        self.settled = false;
        self.region_scan = None;
        self.swept = None;
        if self.active.is_empty() {
            self.settling = false;
        }
    }

    /// Relaxes the whole body within `budget` (for spare time, and for tests).
    pub fn relax_all(&mut self, budget: RelaxBudget) -> crate::chainmail::RelaxReport {
        self.drift_at = None; // moves outside the disturbed region
        self.body.relax(&mut self.ws, budget, crate::chainmail::RelaxRegion::All)
    }

    /// Keeps the layers apart: wherever an element of the upper layer has come closer than the minimum
    /// gap to its partner below (along the normal), the free one of the two moves away (both halfway
    /// when both are free), each by a chain reaction along the normal, so that the layers' limits
    /// hold; where pins or holds cut those short, the rest is written directly, so the layers never
    /// cross. Returns how many pairs were corrected.
    pub fn enforce_contact(&mut self) -> u32 {
        self.take_moved();
        self.wake_scan_helper();
        if self.layers.len() != 2 || !matches!(self.geometry, Geometry::Surface(_)) {
            return 0;
        }
        let mut fixed = 0;
        // Settling tissue whose sweep alone moved part of its region: only the pairs it moved can
        // have come closer, and if none has, the rest of the region is as the last step left it.
        if self.repair.quiet()
            && let Some(window) = self.sweep_window()
        {
            let (pos, sheet, min_gap) = (&self.body.pos[..], self.sheet, self.min_gap);
            if !window.iter().flat_map(|w| w.iter()).any(|&e| gap_short(pos, sheet, min_gap, e)) {
                return 0;
            }
        }
        let count = self.active.len();
        let mut next = 0;
        while next < count {
            // Either element of a pair may be the disturbed one (a grasped lower layer pushed up into
            // an upper layer cut free of it moves only itself). Most pairs keep their gap: they are
            // passed over reading the positions' array alone, and only a short gap (or a NaN one) is
            // handled below.
            let (pos, sheet, min_gap) = (&self.body.pos[..], self.sheet, self.min_gap);
            let short_at = self.active[next..count].iter().position(|&e| gap_short(pos, sheet, min_gap, e));
            let Some(at) = short_at else { break };
            let (l, u) = limits::partners(self.active[next + at].index(), self.sheet);
            next += at + 1;
            let (lower, upper) = (ElementId(l as u32), ElementId(u as u32));
            let (Some(&pl), Some(&pu)) = (self.body.pos.get(l), self.body.pos.get(u)) else { continue };
            let gap = pu[2] - pl[2];
            // Whatever contact does with the pair (even nothing, both ends fixed), the limits' repair
            // looks at the step's gaps itself.
            self.repair.contact = true;
            let short = self.min_gap - gap;
            let free_l = !(self.body.is_pinned(lower) || self.body.is_held(lower));
            let free_u = !(self.body.is_pinned(upper) || self.body.is_held(upper));
            // How a shortfall is shared: halves when both are free, else all to the free one.
            let split = |short: f32| match (free_l, free_u) {
                (true, true) => (-0.5 * short, 0.5 * short),
                (true, false) => (-short, 0.0),
                _ => (0.0, short),
            };
            if !(free_l || free_u) {
                continue;
            }
            let (dl, du) = split(short);
            // Each element is pushed by a chain reaction along the normal, so its neighbours follow
            // and no link leaves its limits (moving the pair alone stretched the links beside it by
            // up to the gap, which on a fine mesh is several spacings and tore them).
            for (e, d) in [(lower, dl), (upper, du)] {
                if d == 0.0 {
                    continue;
                }
                let Ok(p) = self.body.position(e) else { continue };
                if self.body.deform(&mut self.ws, e, [p[0], p[1], p[2] + d], Pass::Normal).is_ok() {
                    self.activate_moved();
                }
            }
            // Chain reactions stop at pins and holds: a held patch pushed down onto a lower layer
            // stretched to its pins leaves both reactions short. The layers must still not cross, so
            // what is left of the gap is written directly (split as above); the links beside the pair
            // may then sit past their limits until relaxation and the next pull share it out.
            let (Ok(pl), Ok(pu)) = (self.body.position(lower), self.body.position(upper)) else { continue };
            let short = self.min_gap - (pu[2] - pl[2]);
            if short > 0.0 {
                let (dl, du) = split(short);
                self.repair.fit(self.body.element_count());
                self.repair.note(lower.0, pl);
                self.repair.note(upper.0, pu);
                let _ = self.body.set_position(lower, [pl[0], pl[1], pl[2] + dl]);
                let _ = self.body.set_position(upper, [pu[0], pu[1], pu[2] + du]);
            }
            self.activate(lower.0);
            self.activate(upper.0);
            fixed += 1;
        }
        if fixed > 0 {
            self.settled = false;
        }
        fixed
    }

    /// Breaks every link near the disturbed region stretched past its material's tear ratio (world
    /// length over rest length), counting them as torn. Also records the largest stretch seen.
    pub fn apply_tears(&mut self) -> u32 {
        self.take_moved();
        if self.is_fem() {
            return 0;
        }
        // The limits' repair scans the region for tears as it looks for links out of their boxes
        // (`limits.rs`): its findings stand if nothing has moved or been cut since.
        let max_stretch2 = match self.scan() {
            Some(s) => s.max_stretch2,
            None => self.scan_tears(None).0,
        };
        let hits = std::mem::take(&mut self.tear_hits);
        let mut torn = 0;
        for &l in &hits {
            if self.break_link(l, BreakReason::Tear) {
                torn += 1;
            }
        }
        if !self.active.is_empty() {
            self.max_stretch = max_stretch2.sqrt();
        }
        self.tear_hits = hits;
        torn
    }

    /// The tear check's scan of the disturbed region (see [`Tissue::scan_region`]): fills
    /// `tear_hits` and returns the largest squared stretch of the layers' links, and with `boxes`
    /// whether a link the step moved lies outside its box.
    pub(crate) fn scan_tears(&mut self, boxes: Option<BoxCheck<'_>>) -> (f32, bool) {
        let mut keep = std::mem::take(&mut self.scan_keep);
        keep.clear();
        // Each material's tear ratio, squared (lengths are compared squared: no root per link).
        let mut tear2 = std::mem::take(&mut self.tear_scratch);
        scan::tear_ratios2_into(&self.body, &mut tear2);
        let mut hits = std::mem::take(&mut self.tear_hits);
        hits.clear();
        // Each slot class's box widened by the tolerance (a handful of classes).
        let mut wide = std::mem::take(&mut self.wide_scratch);
        wide.clear();
        if let Some(b) = boxes {
            wide.extend(self.body.classes.iter().map(|c| limits::widen(c.bounds, b.tol)));
        }
        let geometry = self.geometry;
        // A flat surface's world is its lattice with the axes permuted: the same lengths, without the
        // surface's general map per link end.
        #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
        let flat = |p| Vec3::from(Surface::flat_to_world(p));
        let general = |p| Vec3::from(geometry.to_world(p));
        if matches!(geometry, Geometry::Surface(s) if s.is_flat()) {
            self.scan_table.refresh(&self.body, &tear2);
        }
        let mut out = ScanFound { keep: boxes.is_some().then_some(&mut keep), ..Default::default() };
        let mut spare = std::mem::take(&mut self.scan_spare);
        const SPLIT: usize = scan::SPLIT_MIN;
        let max2 = match (geometry, boxes) {
            (Geometry::Surface(s), None) if s.is_flat() => {
                let m =
                    self.scan_flat_split::<false>(&mut hits, &NO_BOXES, &wide, &mut out, &mut spare, SPLIT);
                #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
                self.check_scan::<false>(&tear2, &hits, flat, &NO_BOXES, &wide, &out, m);
                m
            }
            (Geometry::Surface(s), Some(b)) if s.is_flat() => {
                let m = self.scan_flat_split::<true>(&mut hits, &b, &wide, &mut out, &mut spare, SPLIT);
                #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
                self.check_scan::<true>(&tear2, &hits, flat, &b, &wide, &out, m);
                m
            }
            (_, None) => self.scan_region::<false, false>(
                &self.active,
                &tear2,
                &mut hits,
                general,
                &NO_BOXES,
                &wide,
                &mut out,
            ),
            (_, Some(b)) => {
                self.scan_region::<true, false>(&self.active, &tear2, &mut hits, general, &b, &wide, &mut out)
            }
        };
        let (outside, drift) = (out.outside, out.drift);
        self.scan_spare = spare;
        self.tear_scratch = tear2;
        self.tear_hits = hits;
        self.wide_scratch = wide;
        self.scan_keep = keep;
        if boxes.is_some() {
            let key = (self.body.motion(), self.body.revision());
            self.region_scan = Some(RegionScan { key, max_stretch2: max2, drift });
        }
        (max2, outside)
    }

    /// The limits' repair's scan of the region this step, if it still stands (see [`RegionScan`]).
    pub(crate) fn scan(&self) -> Option<RegionScan> {
        self.region_scan.filter(|s| s.key == (self.body.motion(), self.body.revision()))
    }

    /// The tear check's scan of `region` (the disturbed region, or part of it): each intact link with
    /// an end there, from its `a` end (from both with `BOTH_ENDS`, so that a link with both ends there
    /// is met twice), in the region's order; links past their material's tear ratio go to `hits` (in the
    /// order met). Returns the largest squared stretch of the layers' links. `world` maps lattice
    /// coordinates to the world. With `BOXES`, `out` is set where a link with an end the step moved
    /// lies more than the tolerance outside its box (lattice coordinates): what the limits' repair
    /// would find, but for the layers' gaps, which contact has just checked; and it gathers the
    /// region's drift and the elements the region keeps at the end of the step, which read the same
    /// elements and neighbours.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn scan_region<const BOXES: bool, const BOTH_ENDS: bool>(
        &self,
        region: &[ElementId],
        tear2: &[f32],
        hits: &mut Vec<LinkId>,
        world: impl Fn([f32; 3]) -> Vec3,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &mut ScanFound<'_>,
    ) -> f32 {
        let lat = self.body.lattice();
        let (adj_start, adj_link, adj_nbr) = (&lat.adj_start[..], &lat.adj_link[..], &lat.adj_nbr[..]);
        let (pos, state, material) =
            (&self.body.pos[..], &self.body.link_state[..], &self.body.link_material[..]);
        let (rest_len, kind) = (&self.rest_len[..], &self.link_kind[..]);
        let (w, slot_class) = (self.body.width, &self.body.slot_class[..]);
        let moved = |i: usize| boxes.stamps.get(i) == Some(&boxes.stamp);
        let (rest_pos, last_move) = (lat.rest_positions(), &self.last_move[..]);
        let moving = |i: usize| last_move.get(i).is_some_and(|&m| m > settle::SETTLED);
        let mut max_stretch2 = 0.0f32;
        for &id in region {
            let e = id.index();
            let (Some(&s0), Some(&s1), Some(&p)) = (adj_start.get(e), adj_start.get(e + 1), pos.get(e))
            else {
                continue;
            };
            // The drift and what the region keeps (`Tissue::drift`, `Tissue::prune_region`).
            let mut keep = false;
            if BOXES && let Some(r) = rest_pos.get(e) {
                out.drift = out.drift.max((p[0] - r[0]).abs().max((p[1] - r[1]).abs()));
                keep = moving(e);
            }
            let pa = world(p);
            for s in s0 as usize..s1 as usize {
                let raw = adj_link[s];
                if BOXES && !keep {
                    keep = moving(adj_nbr[s] as usize);
                }
                if !BOTH_ENDS && raw & crate::chainmail::SIDE_B_BIT != 0 {
                    continue; // each link is checked from its `a` end only
                }
                let l = (raw & !crate::chainmail::SIDE_B_BIT) as usize;
                if state[l] != crate::chainmail::INTACT {
                    continue;
                }
                let y = adj_nbr[s] as usize;
                let q = pos[y];
                if BOXES {
                    // The slot's box widened by the tolerance, per class (`wide`).
                    let wide = wide[slot_class[e * w + s - s0 as usize] as usize];
                    if limits::beyond(p, q, wide) && (moved(e) || moved(y)) {
                        out.outside = true;
                    }
                }
                let rest = rest_len[l].max(f32::MIN_POSITIVE);
                let rest2 = rest * rest;
                let d2 = world(q).distance_squared(pa);
                // The force proxy is the layers' stretch: fibres are meant to stretch before they are cut.
                let layer = matches!(kind[l], LinkKind::Layer(_));
                let ratio2 = tear2.get(material[l].index()).copied().unwrap_or(f32::INFINITY);
                tear_test(d2, rest2, ratio2, layer, &mut max_stretch2, || hits.push(LinkId(l as u32)));
            }
            if keep && let Some(k) = out.keep.as_deref_mut() {
                k.push(id);
            }
        }
        max_stretch2
    }

    /// The plain scan beside the table's (debug builds): the same largest stretch, tears, box
    /// finding, drift and kept elements, to the bit.
    #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
    #[allow(clippy::too_many_arguments)]
    fn check_scan<const BOXES: bool>(
        &self,
        tear2: &[f32],
        hits: &[LinkId],
        world: impl Fn([f32; 3]) -> Vec3,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &ScanFound<'_>,
        max2: f32,
    ) {
        let (mut plain_hits, mut plain_keep) = (Vec::new(), Vec::new());
        let mut plain =
            ScanFound { keep: out.keep.is_some().then_some(&mut plain_keep), ..Default::default() };
        let m = self.scan_region::<BOXES, false>(
            &self.active,
            tear2,
            &mut plain_hits,
            world,
            boxes,
            wide,
            &mut plain,
        );
        let (outside, drift) = (plain.outside, plain.drift);
        debug_assert_eq!(m.to_bits(), max2.to_bits(), "the tear scans' largest stretch differs");
        debug_assert_eq!(plain_hits, hits, "the tear scans' tears differ");
        debug_assert_eq!(outside, out.outside, "the tear scans' box findings differ");
        debug_assert_eq!(drift.to_bits(), out.drift.to_bits(), "the tear scans' drift differs");
        if let Some(keep) = out.keep.as_deref() {
            debug_assert_eq!(&plain_keep, keep, "the tear scans' kept elements differ");
        }
    }

    /// World length of a link over its world rest length.
    pub fn world_stretch(&self, l: LinkId) -> f32 {
        let Some([a, b]) = self.body.lattice().link_ends(l) else { return 0.0 };
        let (Some(pa), Some(pb)) = (self.world_position(a), self.world_position(b)) else { return 0.0 };
        Vec3::from(pb).distance(Vec3::from(pa)) / self.rest_len[l.index()].max(f32::MIN_POSITIVE)
    }

    /// Largest world stretch over every intact link of the given kind (or all), for reports.
    pub fn max_world_stretch(&self, kind: Option<LinkKind>) -> f32 {
        (0..self.body.link_count())
            .map(|i| LinkId(i as u32))
            .filter(|&l| self.body.link_intact(l) && kind.is_none_or(|k| self.link_kind[l.index()] == k))
            .map(|l| self.world_stretch(l))
            .fold(0.0, f32::max)
    }

    /// Breaks one link, records the event and the damage. Returns `true` if it was intact.
    pub(crate) fn break_link(&mut self, l: LinkId, reason: BreakReason) -> bool {
        if !matches!(self.body.break_link(l, reason), Ok(true)) {
            return false;
        }
        let kind = self.link_kind[l.index()];
        if reason == BreakReason::Cut {
            self.cut_energy += self.cut_energy(l);
        }
        match (reason, kind) {
            (BreakReason::Tear, _) => {
                self.damage.links_torn += 1;
                let extent = self.link_extent(l);
                match kind {
                    LinkKind::Connective => self.damage.connective_torn_m2 += extent,
                    LinkKind::Layer(_) => self.damage.layer_torn += extent,
                }
            }
            (BreakReason::Cut, LinkKind::Connective) => self.damage.connective_links_cut += 1,
            (BreakReason::Cut, LinkKind::Layer(_)) => self.damage.layer_links_cut += 1,
        }
        self.events.push(TopologyEvent { link: l, kind, reason });
        self.topology_version += 1;
        if let Some([a, b]) = self.body.lattice().link_ends(l)
            && let Some(layer) = self.layers.iter_mut().find(|y| a.0.wrapping_sub(y.first) < y.count)
            && b.0.wrapping_sub(layer.first) < layer.count
        {
            layer.version = crate::chainmail::fresh_number();
        }
        if let Some([a, b]) = self.body.lattice().link_ends(l) {
            self.activate(a.0);
            self.activate(b.0);
        }
        true
    }

    /// Elements in the disturbed region.
    pub fn active_count(&self) -> usize {
        self.active.len()
    }
}
