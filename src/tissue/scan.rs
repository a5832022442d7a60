//! The tear scan's table for flat surfaces: each element's links from its `a` end, with what the scan
//! reads of them that never changes (the neighbour, the body's slot, the kind, the squared rest
//! length), in the adjacency's order. The scan of the disturbed region ([`Tissue::scan_tears`]) then
//! reads one record per link it checks, not the element's whole adjacency (half of it the links' `b`
//! ends, skipped one by one) and four link-indexed arrays. [`Tissue::scan_region`] is the plain path;
//! in debug builds every scan compares the two.

use super::{BoxCheck, LinkKind, NEAR, ScanFound, Tissue, limits, settle};
use std::cmp::Ordering;

use crate::chainmail::{Body, INTACT, LinkId, SIDE_B_BIT};

/// Set in [`ScanLink::link`] for a link within a layer (whose stretch the scan reports).
const LAYER: u32 = SIDE_B_BIT;

/// One link as the tear scan reads it, from its `a` end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanLink {
    /// The body's slot of the link at its `a` end (`a · width + t`), for its box's class.
    slot: u32,
    /// The `b` end.
    nbr: u32,
    /// The link, with [`LAYER`] set for a layer's link.
    link: u32,
    /// The squared world rest length (at least the smallest positive float, squared).
    rest2: f32,
}

/// Each element's links from its `a` end: those of element `e` are `links[start[e]..start[e + 1]]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct ScanTable {
    start: Vec<u32>,
    links: Vec<ScanLink>,
}

impl ScanTable {
    pub(crate) fn new(body: &Body, kind: &[LinkKind], rest_len: &[f32]) -> Self {
        let lat = body.lattice();
        let n = body.element_count();
        let w = body.width;
        let mut start = Vec::with_capacity(n + 1);
        let mut links = Vec::with_capacity(lat.adj_link.len() / 2);
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
                    slot: (e * w + s - s0) as u32,
                    nbr: lat.adj_nbr[s],
                    link: raw | if layer { LAYER } else { 0 },
                    rest2: rest * rest,
                });
            }
        }
        start.push(links.len() as u32);
        ScanTable { start, links }
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
        let (pos, state, material) =
            (&self.body.pos[..], &self.body.link_state[..], &self.body.link_material[..]);
        let slot_class = &self.body.slot_class[..];
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
                let ratio =
                    material.get(l).and_then(|m| ratio2.get(m.index())).copied().unwrap_or(f32::INFINITY);
                let layer = k.link & LAYER != 0;
                // `tear_test`'s first comparison (a NaN goes on, as there).
                let bar = if layer { ratio.min(max_stretch2) } else { ratio };
                let near = matches!(d2.partial_cmp(&(bar * k.rest2 * NEAR)), Some(Ordering::Greater) | None);
                let outside = BOXES && {
                    let class = slot_class.get(k.slot as usize).copied().unwrap_or(0) as usize;
                    wide.get(class).is_some_and(|&w| limits::beyond(p, q, w))
                };
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

/// `tear_test` of a link the scan found near the bar (`d2` past the bar's multiplication test):
/// the division, the largest stretch and the tear, out of the scan's loop.
#[cold]
#[inline(never)]
fn scan_link(k: &ScanLink, d2: f32, ratio2: f32, max_stretch2: &mut f32, hits: &mut Vec<LinkId>) {
    let stretch2 = d2 / k.rest2;
    if k.link & LAYER != 0 {
        *max_stretch2 = max_stretch2.max(stretch2);
    }
    if stretch2 > ratio2 {
        hits.push(LinkId(k.link & !LAYER));
    }
}
