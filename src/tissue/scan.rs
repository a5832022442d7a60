//! The tear scan's table for flat surfaces: each element's links from its `a` end, with what the scan
//! reads of them that never changes (the neighbour, the body's slot, the kind, the squared rest
//! length), in the adjacency's order. The scan of the disturbed region ([`Tissue::scan_tears`]) then
//! reads one record per link it checks, not the element's whole adjacency (half of it the links' `b`
//! ends, skipped one by one) and four link-indexed arrays. [`Tissue::scan_region`] is the plain path;
//! in debug builds every scan compares the two.

use super::{BoxCheck, LinkKind, ScanFound, Tissue, limits, settle, tear_test};
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
    /// path's to the bit), reading the scan table.
    #[inline(always)]
    pub(super) fn scan_flat<const BOXES: bool>(
        &self,
        tear2: &[Option<f32>],
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
        for &id in &self.active {
            let e = id.index();
            let (Some(&t0), Some(&t1), Some(&p)) = (start.get(e), start.get(e + 1), pos.get(e)) else {
                continue;
            };
            let mut keep = false;
            let mut moved_e = false;
            if BOXES {
                if let Some(r) = rest_pos.get(e) {
                    out.drift = out.drift.max((p[0] - r[0]).abs().max((p[1] - r[1]).abs()));
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
                let y = k.nbr as usize;
                let Some(&q) = pos.get(y) else { continue };
                if BOXES {
                    let class = slot_class.get(k.slot as usize).copied().unwrap_or(0) as usize;
                    if let Some(&wide) = wide.get(class)
                        && limits::beyond(p, q, wide)
                        && (moved_e || moved(y))
                    {
                        out.outside = true;
                    }
                }
                // `world(q).distance_squared(world(p))` with the world's axes `(u, h, v)`.
                let d = [q[0] - p[0], q[2] - p[2], q[1] - p[1]];
                let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                let layer = k.link & LAYER != 0;
                let ratio2 = material
                    .get(l)
                    .and_then(|m| tear2.get(m.index()).copied().flatten())
                    .unwrap_or(f32::INFINITY);
                tear_test(d2, k.rest2, ratio2, layer, &mut max_stretch2, || {
                    hits.push(LinkId(k.link & !LAYER))
                });
            }
            if keep && let Some(k) = out.keep.as_deref_mut() {
                k.push(id);
            }
        }
        max_stretch2
    }
}
