//! The tear scan's table for flat surfaces: each element's links from its `a` end, with what the scan
//! reads of them that never changes (the neighbour, the kind, the squared rest length) and copies of
//! what changes only when a material is edited (the box's class, the material's tear ratio), in the
//! adjacency's order. The scan of the disturbed region ([`Tissue::scan_tears`]) then reads one record
//! per link it checks, not the element's whole adjacency (half of it the links' `b` ends, skipped one
//! by one) and four link- or slot-indexed arrays. [`Tissue::scan_region`] is the plain path;
//! in debug builds every scan compares the two.

use super::{BoxCheck, Geometry, LinkKind, ScanFound, Tissue, limits, near_bar, settle, tear_divide};
use crate::chainmail::schedule::{in_turns, wake_ahead};
use crate::chainmail::{Body, ElementId, INTACT, LinkId, Prefetch, SIDE_B_BIT};

/// Set in [`ScanLink::link`] for a link within a layer (whose stretch the scan reports).
const LAYER: u32 = SIDE_B_BIT;

/// One link as the tear scan reads it, from its `a` end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanLink {
    /// The `b` end.
    nbr: u32,
    /// The link, with [`LAYER`] set for a layer's link.
    link: u32,
    /// The squared world rest length (at least the smallest positive float, squared).
    rest2: f32,
    /// The class of the link's slot at its `a` end (the box the scan tests): a copy of the body's, as
    /// of [`ScanTable::epoch`].
    class: u32,
    /// The squared tear ratio of the link's material (infinite for none), as of [`ScanTable::epoch`]
    /// and [`ScanTable::ratio2`]: read here, not through the material, in the scan's loop.
    ratio2: f32,
}

/// Each element's links from its `a` end: those of element `e` are `links[start[e]..start[e + 1]]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct ScanTable {
    start: Vec<u32>,
    links: Vec<ScanLink>,
    /// Each link's slot at its `a` end (`a · width + t`), in the order of `links`: where the classes
    /// are read again when the body's boxes change.
    slots: Vec<u32>,
    /// The body's [`Body::boxes_epoch`] the classes and tear ratios were copied at.
    epoch: u64,
    /// Each material's squared tear ratio the links' `ratio2` were copied from.
    ratio2: Vec<f32>,
}

impl ScanTable {
    pub(crate) fn new(body: &Body, kind: &[LinkKind], rest_len: &[f32]) -> Self {
        let lat = body.lattice();
        let n = body.element_count();
        let w = body.width;
        let mut start = Vec::with_capacity(n + 1);
        let mut links = Vec::with_capacity(lat.adj_link.len() / 2);
        let mut slots = Vec::with_capacity(lat.adj_link.len() / 2);
        for e in 0..n {
            start.push(links.len() as u32);
            let (s0, s1) = (lat.adj_start[e] as usize, lat.adj_start[e + 1] as usize);
            for s in s0..s1 {
                let raw = lat.adj_link[s];
                if raw & SIDE_B_BIT != 0 {
                    continue;
                }
                let l = raw as usize;
                let layer = matches!(kind.get(l), Some(LinkKind::Layer(_)));
                let rest = rest_len.get(l).copied().unwrap_or(0.0).max(f32::MIN_POSITIVE);
                links.push(ScanLink {
                    nbr: lat.adj_nbr[s],
                    link: raw | if layer { LAYER } else { 0 },
                    rest2: rest * rest,
                    class: 0,
                    ratio2: f32::INFINITY,
                });
                slots.push((e * w + s - s0) as u32);
            }
        }
        start.push(links.len() as u32);
        let mut table = ScanTable { start, links, slots, epoch: 0, ratio2: Vec::new() };
        let mut ratio2 = Vec::new();
        tear_ratios2_into(body, &mut ratio2);
        table.refresh(body, &ratio2);
        table
    }

    /// Copies the body's classes and the materials' squared tear ratios (`ratio2`) again if its boxes
    /// or those ratios have changed since the last copy (a material edited: rare, and then once for
    /// the whole table).
    pub(crate) fn refresh(&mut self, body: &Body, ratio2: &[f32]) {
        if self.epoch == body.boxes_epoch && self.epoch != 0 && self.ratio2 == ratio2 {
            return;
        }
        for (k, &slot) in self.links.iter_mut().zip(&self.slots) {
            k.class = body.slot_class.get(slot as usize).copied().unwrap_or(0);
            let material =
                body.link_material.get((k.link & !LAYER) as usize).map_or(usize::MAX, |m| m.index());
            k.ratio2 = ratio2.get(material).copied().unwrap_or(f32::INFINITY);
        }
        self.epoch = body.boxes_epoch;
        self.ratio2.clear();
        self.ratio2.extend_from_slice(ratio2);
    }
}

/// Each of the body's materials' squared tear ratio (infinite for none), into `ratio2` (cleared
/// first): what the tear check compares squared lengths with.
pub(crate) fn tear_ratios2_into(body: &Body, ratio2: &mut Vec<f32>) {
    ratio2.clear();
    ratio2.extend(body.materials().iter().map(|m| m.tear_ratio.map_or(f32::INFINITY, |r| r * r)));
}

impl Tissue {
    /// [`Tissue::scan_region`] on a flat surface, whose world is its lattice with the axes permuted
    /// (`Surface::flat_to_world`: lengths are summed in the world's order, so every figure is the plain
    /// path's to the bit), reading the scan table (which holds each link's tear ratio).
    ///
    /// Most links hold nothing of interest: inside their box, and neither the largest stretch so far
    /// nor near their tear ratio. The loop tests both with a few comparisons and sends the rest to
    /// [`Tissue::scan_link`] out of its way, so that it keeps its values in registers.
    #[inline(always)]
    pub(super) fn scan_flat<const BOXES: bool>(
        &self,
        region: &[ElementId],
        hits: &mut Vec<LinkId>,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &mut ScanFound<'_>,
    ) -> f32 {
        let lat = self.body.lattice();
        let (adj_start, adj_nbr) = (&lat.adj_start[..], &lat.adj_nbr[..]);
        let (start, table) = (&self.scan_table.start[..], &self.scan_table.links[..]);
        let (pos, state) = (&self.body.pos[..], &self.body.link_state[..]);
        let moved = |i: usize| boxes.stamps.get(i) == Some(&boxes.stamp);
        let (rest_pos, last_move) = (lat.rest_positions(), &self.last_move[..]);
        let moving = |i: usize| last_move.get(i).is_some_and(|&m| m > settle::SETTLED);
        let mut max_stretch2 = 0.0f32;
        let mut drift = out.drift;
        // (The kept list taken out of `out` for the loop, so that its place is not read again at
        // every element.)
        let mut keep_list = out.keep.take();
        let fetch = Prefetch::new(self.ws.simd());
        for (i, &id) in region.iter().enumerate() {
            let e = id.index();
            // The region's elements lie apart in memory, each a fresh set of cache lines: the loop
            // waits on them unless their first link records, adjacency and position are asked for
            // ahead. (Also asking for the element's rest position, last move and stamp did not help;
            // asking, half as far ahead, for the link states, the neighbours' positions and their last
            // moves was slower: 24 and 46 µs for the phase.)
            if let Some(f) = region.get(i + Prefetch::AHEAD) {
                let f = f.index();
                if let (Some(&t), Some(&a)) = (start.get(f), adj_start.get(f)) {
                    fetch.at(table, t as usize);
                    fetch.at(adj_nbr, a as usize);
                }
                fetch.at(pos, f);
            }
            let (Some(&t0), Some(&t1), Some(&p)) = (start.get(e), start.get(e + 1), pos.get(e)) else {
                continue;
            };
            let mut keep = false;
            let mut moved_e = false;
            if BOXES {
                if let Some(r) = rest_pos.get(e) {
                    // `drift.max(..)` for a drift that is never NaN: a NaN leaves it as it was.
                    let (du, dv) = ((p[0] - r[0]).abs(), (p[1] - r[1]).abs());
                    if du > drift {
                        drift = du;
                    }
                    if dv > drift {
                        drift = dv;
                    }
                    keep = moving(e);
                }
                if !keep && let (Some(&s0), Some(&s1)) = (adj_start.get(e), adj_start.get(e + 1)) {
                    let nbrs = adj_nbr.get(s0 as usize..s1 as usize).unwrap_or_default();
                    keep = nbrs.iter().any(|&y| moving(y as usize));
                }
                moved_e = moved(e);
            }
            for k in table.get(t0 as usize..t1 as usize).unwrap_or_default() {
                let l = (k.link & !LAYER) as usize;
                if state.get(l) != Some(&INTACT) {
                    continue;
                }
                let Some(&q) = pos.get(k.nbr as usize) else { continue };
                // `world(q).distance_squared(world(p))` with the world's axes `(u, h, v)`.
                let d = [q[0] - p[0], q[2] - p[2], q[1] - p[1]];
                let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                if near_bar(d2, k.rest2, k.ratio2, k.link & LAYER != 0, max_stretch2) {
                    scan_link(k, d2, &mut max_stretch2, hits);
                }
                // Only a link with an end the step moved counts outside its box, and most links have
                // none: the box is tested only for those (a stamp read, where the box takes a dozen
                // reads and comparisons).
                if BOXES
                    && !out.outside
                    && (moved_e || moved(k.nbr as usize))
                    && wide.get(k.class as usize).is_some_and(|&w| limits::beyond(p, q, w))
                {
                    out.outside = true;
                }
            }
            if keep && let Some(k) = keep_list.as_deref_mut() {
                k.push(id);
            }
        }
        out.keep = keep_list;
        out.drift = drift;
        max_stretch2
    }
}

/// Regions of fewer elements are scanned on one thread: a second thread costs more than it saves.
/// (8 192 while the stepping thread could be held up by a helper without a core, see
/// `chainmail::worker_pool`; then 2 048, measured by the contact and limits phase alone. Measured by
/// the whole step, 2026-11-29 (Intel machine, AVX2, the careful exercise, alternating runs), a split
/// scan's phase is shorter but the next step's normal pass and relaxation are longer by as much:
/// they write the positions the helper's core has just read (at 256 x 192, final lift, one thread
/// against two: normal pass 295-302 against 345-352 us, relaxation 146-147 against 164, contact and
/// limits 296-303 against 234-241). At 16 384 the 128 x 96 exercise's mean step fell from 45-47 to
/// 41-42 us and its p99 from 325-355 to 289-299 us (five pairs); 256 x 192 moved within the noise
/// (means 104-114 against 107-109 us); 512 x 384's large lifts still split.)
pub(crate) const SPLIT_MIN: usize = 1 << 14;

/// Elements in a piece of a split scan (and at least two pieces). Pieces of 512 cost the careful
/// exercise's final lift at 256 x 192 more: its contact and limits phase over the first lift's mean
/// step, 0.46 to 0.54 with pieces of 512 and 0.38 to 0.52 with these (four alternating pairs on the
/// Intel machine, 2026-11-28).
const PIECE: usize = 1 << 11;

/// Most pieces a split scan's region is cut into: enough that the two threads finish within a small
/// piece of each other.
const PIECES: usize = 32;

/// Whether a scan of `len` elements is split over two threads (from `split_min` elements, when rayon's
/// pool has a thread to spare).
fn splits(len: usize, split_min: usize) -> bool {
    len >= split_min.max(2) && rayon::current_num_threads() >= 2
}

/// One piece's findings of a tear scan split over two threads.
#[derive(Clone, Debug, Default)]
struct Piece {
    hits: Vec<LinkId>,
    keep: Vec<ElementId>,
    outside: bool,
    drift: f32,
    max_stretch2: f32,
}

/// The pieces' findings of a tear scan split over two threads, kept between steps so that a split
/// scan allocates nothing once the region has been as large before.
#[derive(Debug, Default)]
pub(crate) struct ScanSpare {
    pieces: Vec<std::sync::Mutex<Piece>>,
}

impl Clone for ScanSpare {
    /// Scratch: a clone starts empty.
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl Tissue {
    /// [`Tissue::scan_flat`] over the whole region: on two threads at once when the region has at
    /// least `split_min` elements (the step's scan: [`SPLIT_MIN`]; tests split small regions) and
    /// rayon's pool has a thread to spare. The region is then cut into pieces of about [`PIECE`]
    /// elements, or `split_min` if fewer (at least two, at most [`PIECES`]), which the two threads
    /// take in turn (`spare` holds each piece's findings), so that both finish together however the
    /// pieces cost. The pieces' findings are joined in the region's order: the same tears in the same
    /// order, elements kept and box findings, and the same largest stretch and drift to the bit
    /// (maxima, in whatever order they are taken; a piece that starts from a lower largest stretch
    /// only sends more links to the division).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn scan_flat_split<const BOXES: bool>(
        &self,
        hits: &mut Vec<LinkId>,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &mut ScanFound<'_>,
        spare: &mut ScanSpare,
        split_min: usize,
    ) -> f32 {
        let region = &self.active[..];
        if !splits(region.len(), split_min) {
            return self.scan_flat_simd::<BOXES>(region, hits, boxes, wide, out);
        }
        let len = PIECE.min(split_min).max(1);
        let pieces = region.len().div_ceil(len).clamp(2, PIECES);
        let len = region.len().div_ceil(pieces);
        if spare.pieces.len() < pieces {
            spare.pieces.resize_with(pieces, Default::default);
        }
        let keeps = out.keep.is_some();
        let start = out.drift;
        let slots = &spare.pieces[..pieces];
        in_turns(pieces, |k| {
            let part = region.get(k * len..((k + 1) * len).min(region.len())).unwrap_or_default();
            // Each piece's slot is locked by the one thread that took the piece (never contended). A
            // lock poisoned by an earlier panic still holds scratch, cleared here.
            let mut slot = slots[k].lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let Piece { hits, keep, outside, drift, max_stretch2 } = &mut *slot;
            hits.clear();
            keep.clear();
            let mut found = ScanFound { outside: false, drift: start, keep: keeps.then_some(keep) };
            *max_stretch2 = self.scan_flat_simd::<BOXES>(part, hits, boxes, wide, &mut found);
            (*outside, *drift) = (found.outside, found.drift);
        });
        let mut max_stretch2 = 0.0f32;
        for slot in slots {
            // (A panic in a piece's scan has reached the caller through the scope by now.)
            let piece = slot.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            hits.extend_from_slice(&piece.hits);
            if let Some(k) = out.keep.as_deref_mut() {
                k.extend_from_slice(&piece.keep);
            }
            out.outside |= piece.outside;
            // The scan's own maximum: a NaN drift (never met: positions are finite) leaves it as it was.
            if piece.drift > out.drift {
                out.drift = piece.drift;
            }
            max_stretch2 = max_stretch2.max(piece.max_stretch2);
        }
        max_stretch2
    }

    /// Wakes a pool thread ahead of the step's tear scan if that scan will be split over two threads
    /// (a flat surface's region of [`SPLIT_MIN`] elements or more), so that the thread is awake when
    /// the scan hands out its pieces (see `chainmail::schedule::wake_ahead`). Contact calls it, just
    /// before the scan.
    pub(super) fn wake_scan_helper(&self) {
        let flat = matches!(self.geometry, Geometry::Surface(s) if s.is_flat());
        if flat && !self.is_fem() && splits(self.active.len(), SPLIT_MIN) {
            wake_ahead();
        }
    }

    /// [`Tissue::scan_flat`] compiled for the widest vectors the workspace's level and the machine
    /// allow (pulp's dispatch): the same operations in shorter code, and no contraction into fused
    /// multiply-adds, so the same figures to the bit.
    fn scan_flat_simd<const BOXES: bool>(
        &self,
        region: &[ElementId],
        hits: &mut Vec<LinkId>,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &mut ScanFound<'_>,
    ) -> f32 {
        let scan = FlatScan::<BOXES> { tissue: self, region, hits, boxes, wide, out };
        self.ws.simd().arch().dispatch(scan)
    }
}

/// [`Tissue::scan_flat`]'s arguments, for pulp's dispatch.
struct FlatScan<'a, 'b, 'c, const BOXES: bool> {
    tissue: &'a Tissue,
    region: &'a [ElementId],
    hits: &'a mut Vec<LinkId>,
    boxes: &'a BoxCheck<'b>,
    wide: &'a [[[f32; 3]; 2]],
    out: &'a mut ScanFound<'c>,
}

impl<const BOXES: bool> pulp::WithSimd for FlatScan<'_, '_, '_, BOXES> {
    type Output = f32;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> f32 {
        self.tissue.scan_flat::<BOXES>(self.region, self.hits, self.boxes, self.wide, self.out)
    }
}

/// The rest of `tear_test` for a link the scan found near its bar, out of the scan's loop.
#[cold]
#[inline(never)]
fn scan_link(k: &ScanLink, d2: f32, max_stretch2: &mut f32, hits: &mut Vec<LinkId>) {
    tear_divide(d2, k.rest2, k.ratio2, k.link & LAYER != 0, max_stretch2, || {
        hits.push(LinkId(k.link & !LAYER))
    });
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::chainmail::{BreakReason, Material, MaterialId};
    use crate::surface::Surface;
    use crate::tissue::{ConnectiveSpec, LayerSpec, LayeredSpec, Pinning, TissueSpec};

    fn layer(name: &str, offset: f32) -> LayerSpec {
        LayerSpec {
            name: name.into(),
            color: [1.0; 4],
            offset,
            material: Material { tear_ratio: Some(3.0), ..Material::relative(1.15, 0.85, 0.3) },
        }
    }

    /// Two layers (12 × 10, a dura over an arachnoid) joined by fibres, pinned at the edges.
    pub(in crate::tissue) fn tissue() -> Tissue {
        Tissue::build(&TissueSpec::Layered(LayeredSpec {
            surface: Surface::Plane { width: 0.06, depth: 0.06 },
            resolution: [12, 10],
            u_coords: None,
            v_coords: None,
            layers: vec![layer("dura", 0.003), layer("arachnoid", 0.0)],
            connective: Some(ConnectiveSpec {
                material: Material { stiffness: 0.3, tear_ratio: None, ..Material::relative(2.0, 0.5, 0.5) },
                density: 1.0,
                min_gap: 0.0005,
                spacing: 0.0,
            }),
            pinned: Pinning::Boundary,
        }))
        .expect("tissue")
    }

    /// Links whose copies in the table differ from the body's class and their material's tear ratio.
    fn stale(t: &Tissue) -> usize {
        let table = &t.scan_table;
        table
            .links
            .iter()
            .zip(&table.slots)
            .filter(|&(k, &slot)| {
                let material = t.body.link_material(LinkId(k.link & !LAYER)).map(|m| m.index() as u32);
                let ratio2 = material
                    .and_then(|m| t.body.materials().get(m as usize))
                    .and_then(|m| m.tear_ratio)
                    .map_or(f32::INFINITY, |r| r * r);
                k.class != t.body.slot_class[slot as usize] || k.ratio2.to_bits() != ratio2.to_bits()
            })
            .count()
    }

    /// The table's copies of the boxes' classes and the materials' tear ratios follow an edited
    /// material and a link given another material, at the next scan (the plain path the scan is
    /// compared with in debug builds reads the body's own).
    #[test]
    fn the_scan_table_follows_edited_materials() {
        let mut t = tissue();
        assert_eq!(stale(&t), 0, "a new table copies the body's");
        let m = t.body.link_material(LinkId(0)).expect("material");
        let tighter = Material { tear_ratio: Some(3.0), ..Material::relative(1.1, 0.9, 0.2) };
        t.body_mut().set_material(m, tighter).expect("edit");
        assert!(stale(&t) > 0, "the edit changed no box");
        t.scan_tears(None);
        assert_eq!(stale(&t), 0, "the scan's table kept the old boxes");
        let weaker = Material { tear_ratio: Some(2.0), ..tighter };
        t.body_mut().set_material(m, weaker).expect("edit");
        assert!(stale(&t) > 0, "the edit changed no tear ratio");
        t.scan_tears(None);
        assert_eq!(stale(&t), 0, "the scan's table kept the old tear ratio");
        // (Another material, whose boxes and tear ratio differ from the edited one's.)
        let other = MaterialId(if m.0 == 0 { 1 } else { 0 });
        t.body_mut().set_link_material(LinkId(0), other).expect("material");
        assert!(stale(&t) > 0, "the link kept its material");
        t.scan_tears(None);
        assert_eq!(stale(&t), 0, "the scan's table kept the old material");
    }

    /// What one scan of the region finds (tears in order, kept elements, the box finding, the drift
    /// and the largest stretch, both as bits), split over two threads from `split_min` elements.
    fn findings<const BOXES: bool>(
        t: &Tissue,
        split_min: usize,
    ) -> (Vec<LinkId>, Vec<ElementId>, bool, u32, u32) {
        // (The table holds each link's tear ratio, copied when the tissue was built.)
        let tol = 1e-4;
        let wide: Vec<_> = t.body.classes.iter().map(|c| limits::widen(c.bounds, tol)).collect();
        // Moved this step: only the last few elements (the one moved far among them), so that only
        // the region's second half finds a link out of its box.
        let stamps: Vec<u32> = (0..t.body.element_count() as u32).map(|e| u32::from(e >= 225)).collect();
        let boxes = BoxCheck { tol, stamps: &stamps, stamp: 1 };
        let (mut hits, mut keep, mut spare) = (Vec::new(), Vec::new(), ScanSpare::default());
        let mut out = ScanFound { keep: BOXES.then_some(&mut keep), ..Default::default() };
        let m = t.scan_flat_split::<BOXES>(&mut hits, &boxes, &wide, &mut out, &mut spare, split_min);
        let (outside, drift) = (out.outside, out.drift.to_bits());
        (hits, keep, outside, drift, m.to_bits())
    }

    /// A tear scan split over two threads finds what one thread finds, in the same order and to the
    /// bit, on a region with tears, links out of their boxes, drift, and elements settled and not.
    #[test]
    fn a_scan_split_over_two_threads_finds_what_one_finds() {
        let mut t = tissue();
        let n = t.body.element_count() as u32;
        for e in 0..n {
            t.activate(e);
        }
        // Some elements settled (the region keeps them only beside one that moves), some moved far
        // enough to tear their links and leave their boxes, spread over both halves of the region.
        for e in (0..n).filter(|e| e % 40 < 25) {
            t.last_move[e as usize] = 0.0;
        }
        for (k, e) in [7u32, 31, 58, 100, 133, 170, 201, 229].into_iter().enumerate() {
            let p = t.body.position(ElementId(e)).expect("element");
            let d = 0.012 + 0.002 * k as f32;
            t.body_mut().set_position(ElementId(e), [p[0] + d, p[1] - 0.5 * d, p[2] + d]).expect("move");
        }
        // The far element's fibre cut, so that its links out of their boxes are all the second half's.
        let fibre = t.body.lattice().neighbours(ElementId(229)).find(|&(m, _)| m.0 < 120).map(|(_, l)| l);
        t.body_mut().break_link(fibre.expect("fibre"), BreakReason::Cut).expect("cut");
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
        for split_min in [2, 17, 120] {
            let (one, two) =
                pool.install(|| (findings::<true>(&t, usize::MAX), findings::<true>(&t, split_min)));
            let halves = one.0.iter().map(|l| l.0 < t.body.lattice().link_count() as u32 / 2);
            assert!(halves.clone().any(|a| a) && halves.clone().any(|a| !a), "tears in one half only");
            assert!(one.2, "no link out of its box");
            assert!(one.1.len() < n as usize && !one.1.is_empty(), "every element or none kept");
            assert_eq!(one, two, "split from {split_min}: the scan with boxes differs");
            let (one, two) =
                pool.install(|| (findings::<false>(&t, usize::MAX), findings::<false>(&t, split_min)));
            assert_eq!(one, two, "split from {split_min}: the tear scan differs");
        }
    }
}
