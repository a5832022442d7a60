//! The tear scan's table for flat surfaces: each element's links from its `a` end, with what the scan
//! reads of them that never changes (the neighbour, the kind, the squared rest length) and copies of
//! what changes only when a material is edited (the box's class, the material), in the adjacency's
//! order. The scan of the disturbed region ([`Tissue::scan_tears`]) then reads one record per link it
//! checks, not the element's whole adjacency (half of it the links' `b` ends, skipped one by one) and
//! four link- or slot-indexed arrays. [`Tissue::scan_region`] is the plain path;
//! in debug builds every scan compares the two.

use super::{BoxCheck, LinkKind, ScanFound, Tissue, limits, near_bar, settle, tear_divide};
use crate::chainmail::{Body, INTACT, LinkId, SIDE_B_BIT};

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
    /// The class of the link's slot at its `a` end (the box the scan tests), and the link's material:
    /// copies of the body's, as of [`ScanTable::epoch`].
    class: u32,
    material: u32,
}

/// Each element's links from its `a` end: those of element `e` are `links[start[e]..start[e + 1]]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct ScanTable {
    start: Vec<u32>,
    links: Vec<ScanLink>,
    /// Each link's slot at its `a` end (`a · width + t`), in the order of `links`: where the classes
    /// are read again when the body's boxes change.
    slots: Vec<u32>,
    /// The body's [`Body::boxes_epoch`] the classes and materials were copied at.
    epoch: u64,
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
                    material: 0,
                });
                slots.push((e * w + s - s0) as u32);
            }
        }
        start.push(links.len() as u32);
        let mut table = ScanTable { start, links, slots, epoch: 0 };
        table.refresh(body);
        table
    }

    /// Copies the body's classes and materials again if its boxes have changed since the last copy
    /// (a material edited: rare, and then once for the whole table).
    pub(crate) fn refresh(&mut self, body: &Body) {
        if self.epoch == body.boxes_epoch && self.epoch != 0 {
            return;
        }
        for (k, &slot) in self.links.iter_mut().zip(&self.slots) {
            k.class = body.slot_class.get(slot as usize).copied().unwrap_or(0);
            k.material =
                body.link_material.get((k.link & !LAYER) as usize).map_or(u32::MAX, |m| m.index() as u32);
        }
        self.epoch = body.boxes_epoch;
    }
}

impl Tissue {
    /// [`Tissue::scan_region`] on a flat surface, whose world is its lattice with the axes permuted
    /// (`Surface::flat_to_world`: lengths are summed in the world's order, so every figure is the plain
    /// path's to the bit), reading the scan table. `ratio2` is each material's squared tear ratio
    /// (infinite for none).
    ///
    /// Most links hold nothing of interest: inside their box, and neither the largest stretch so far
    /// nor near their tear ratio. The loop tests both with a few comparisons and sends the rest to
    /// [`Tissue::scan_link`] out of its way, so that it keeps its values in registers.
    #[inline(always)]
    pub(super) fn scan_flat<const BOXES: bool>(
        &self,
        ratio2: &[f32],
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
        for &id in &self.active {
            let e = id.index();
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
                let ratio = ratio2.get(k.material as usize).copied().unwrap_or(f32::INFINITY);
                let near = near_bar(d2, k.rest2, ratio, k.link & LAYER != 0, max_stretch2);
                let outside = BOXES && wide.get(k.class as usize).is_some_and(|&w| limits::beyond(p, q, w));
                if near || outside {
                    let moved_y = BOXES && outside && (moved_e || moved(k.nbr as usize));
                    out.outside |= moved_y;
                    if near {
                        scan_link(k, d2, ratio, &mut max_stretch2, hits);
                    }
                }
            }
            if keep && let Some(k) = out.keep.as_deref_mut() {
                k.push(id);
            }
        }
        out.drift = drift;
        max_stretch2
    }
}

impl Tissue {
    /// [`Tissue::scan_flat`] compiled for the widest vectors the workspace's level and the machine
    /// allow (pulp's dispatch): the same operations in shorter code, and no contraction into fused
    /// multiply-adds, so the same figures to the bit.
    pub(super) fn scan_flat_simd<const BOXES: bool>(
        &self,
        ratio2: &[f32],
        hits: &mut Vec<LinkId>,
        boxes: &BoxCheck<'_>,
        wide: &[[[f32; 3]; 2]],
        out: &mut ScanFound<'_>,
    ) -> f32 {
        let scan = FlatScan::<BOXES> { tissue: self, ratio2, hits, boxes, wide, out };
        self.ws.simd().arch().dispatch(scan)
    }
}

/// [`Tissue::scan_flat`]'s arguments, for pulp's dispatch.
struct FlatScan<'a, 'b, 'c, const BOXES: bool> {
    tissue: &'a Tissue,
    ratio2: &'a [f32],
    hits: &'a mut Vec<LinkId>,
    boxes: &'a BoxCheck<'b>,
    wide: &'a [[[f32; 3]; 2]],
    out: &'a mut ScanFound<'c>,
}

impl<const BOXES: bool> pulp::WithSimd for FlatScan<'_, '_, '_, BOXES> {
    type Output = f32;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> f32 {
        self.tissue.scan_flat::<BOXES>(self.ratio2, self.hits, self.boxes, self.wide, self.out)
    }
}

/// The rest of `tear_test` for a link the scan found near its bar, out of the scan's loop.
#[cold]
#[inline(never)]
fn scan_link(k: &ScanLink, d2: f32, ratio2: f32, max_stretch2: &mut f32, hits: &mut Vec<LinkId>) {
    tear_divide(d2, k.rest2, ratio2, k.link & LAYER != 0, max_stretch2, || {
        hits.push(LinkId(k.link & !LAYER))
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chainmail::{Material, MaterialId};
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

    fn tissue() -> Tissue {
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
            }),
            pinned: Pinning::Boundary,
        }))
        .expect("tissue")
    }

    /// Links whose copies in the table differ from the body's class and material.
    fn stale(t: &Tissue) -> usize {
        let table = &t.scan_table;
        table
            .links
            .iter()
            .zip(&table.slots)
            .filter(|&(k, &slot)| {
                let material = t.body.link_material(LinkId(k.link & !LAYER)).map(|m| m.index() as u32);
                k.class != t.body.slot_class[slot as usize] || Some(k.material) != material
            })
            .count()
    }

    /// The table's copies of the boxes' classes and the materials follow an edited material and a link
    /// given another material, at the next scan (the plain path the scan is compared with in debug
    /// builds reads the body's own).
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
        let other = MaterialId(if m.0 == 0 { 1 } else { 0 });
        t.body_mut().set_link_material(LinkId(0), other).expect("material");
        assert!(stale(&t) > 0, "the link kept its material");
        t.scan_tears(None);
        assert_eq!(stale(&t), 0, "the scan's table kept the old material");
    }
}
