//! Where a cut looks: the links of one kind bucketed by where their first end rests in the surface's
//! `(u, v)` plane, so that a blade stroke visits only the links near it and a cut costs what it
//! crosses, not the whole sheet. Elements move, so a query widens its box by how far any element has
//! drifted from rest (`Tissue::drift`: followed step by step from the disturbed region) and by the
//! longest rest link: every link a stroke can reach is visited, and the links it hits are cut in id
//! order, exactly as a scan of every link would cut them.
//!
//! The same grid buckets a layer's elements by where they rest (`LinkGrid::of_elements`, a link's
//! reach then zero), for the search of the element nearest a point (`Tissue::nearest_element`).

use crate::chainmail::Body;

/// About this many links (or elements) share a cell.
const PER_CELL: f32 = 64.0;

/// The links of one kind in cells of a uniform grid over their first ends' rest `(u, v)` (or a layer's
/// elements over theirs).
#[derive(Clone, Debug, Default)]
pub(crate) struct LinkGrid {
    lo: [f32; 2],
    cell: f32,
    dims: [usize; 2],
    /// Cell `c`'s links are `ids[start[c]..start[c + 1]]`, cells row by row along `u`.
    start: Vec<u32>,
    ids: Vec<u32>,
    /// The longest rest link of the kind across the plane (largest of `|du|`, `|dv|`).
    span: f32,
}

impl LinkGrid {
    /// Buckets `ids` (links of `body`); `wrapped` surfaces (a `u` that wraps round) get one cell.
    pub(crate) fn new(body: &Body, ids: &[u32], wrapped: bool) -> Self {
        Self::with_cells_of(body, ids, wrapped, PER_CELL)
    }

    /// [`LinkGrid::new`] with about `per_cell` links a cell (tests use small cells, where a query
    /// box too small shows).
    pub(crate) fn with_cells_of(body: &Body, ids: &[u32], wrapped: bool, per_cell: f32) -> Self {
        let lat = body.lattice();
        let rest = lat.rest_positions();
        let mut span = 0.0f32;
        for &l in ids {
            if let Some(off) = lat.link_rest(crate::chainmail::LinkId(l)) {
                span = span.max(off[0].abs()).max(off[1].abs());
            }
        }
        let at = |l: u32| {
            lat.link_ends(crate::chainmail::LinkId(l)).and_then(|[a, _]| rest.get(a.index()).copied())
        };
        Self::bucket(ids, at, span, wrapped, per_cell)
    }

    /// Elements (`ids`, of `body`) bucketed by where they rest, as links are by their first end: what
    /// a search for the element nearest a point reads (see `Tissue::nearest_element`).
    pub(crate) fn of_elements(body: &Body, ids: &[u32], wrapped: bool) -> Self {
        Self::of_elements_in_cells_of(body, ids, wrapped, PER_CELL)
    }

    /// [`LinkGrid::of_elements`] with about `per_cell` elements a cell.
    pub(crate) fn of_elements_in_cells_of(body: &Body, ids: &[u32], wrapped: bool, per_cell: f32) -> Self {
        let rest = body.lattice().rest_positions();
        Self::bucket(ids, |e| rest.get(e as usize).copied(), 0.0, wrapped, per_cell)
    }

    /// `ids` in cells of about `per_cell` by the rest position `at` gives each (lattice coordinates;
    /// `(u, v)` are the first two); `span`: how far from that point what an id stands for reaches.
    fn bucket(
        ids: &[u32],
        at: impl Fn(u32) -> Option<[f32; 3]>,
        span: f32,
        wrapped: bool,
        per_cell: f32,
    ) -> Self {
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        for &l in ids {
            let Some(p) = at(l) else { continue };
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let extent = [(hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0)];
        let area = (extent[0] * extent[1]).max(f32::MIN_POSITIVE);
        let mut cell = (area * per_cell / ids.len().max(1) as f32).sqrt();
        // No more cells along an axis than links: links along one line (a layer 2 elements wide has
        // its fibres in one row) have no area, and the cell from it was 1e-19 m, a grid of 10^17 cells.
        cell = cell.max(extent[0].max(extent[1]) / ids.len().max(1) as f32);
        if wrapped || !cell.is_finite() || cell <= 0.0 || !lo[0].is_finite() {
            cell = f32::INFINITY;
        }
        let dims = if cell.is_finite() {
            [(extent[0] / cell) as usize + 1, (extent[1] / cell) as usize + 1]
        } else {
            [1, 1]
        };
        let cell_of = |p: [f32; 3]| -> usize {
            if dims == [1, 1] {
                return 0;
            }
            let i = (((p[0] - lo[0]) / cell) as usize).min(dims[0] - 1);
            let j = (((p[1] - lo[1]) / cell) as usize).min(dims[1] - 1);
            j * dims[0] + i
        };
        // Counting sort by cell: ids stay in id order within a cell.
        let mut start = vec![0u32; dims[0] * dims[1] + 1];
        let cells: Vec<usize> = ids.iter().map(|&l| at(l).map_or(0, cell_of)).collect();
        for &c in &cells {
            start[c + 1] += 1;
        }
        for c in 0..dims[0] * dims[1] {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut sorted = vec![0u32; ids.len()];
        for (&l, &c) in ids.iter().zip(&cells) {
            sorted[fill[c] as usize] = l;
            fill[c] += 1;
        }
        Self { lo, cell, dims, start, ids: sorted, span }
    }

    /// Every link whose first end rests within the box `[lo, hi]` widened by `drift` (how far any
    /// element may have moved from rest across the plane) and by what a link can reach from its first
    /// end, appended to `out` in no particular order.
    pub(crate) fn near(&self, lo: [f32; 2], hi: [f32; 2], drift: f32, out: &mut Vec<u32>) {
        for ids in self.cells_near(lo, hi, drift) {
            out.extend_from_slice(ids);
        }
    }

    /// [`LinkGrid::near`]'s ids a run of cells at a time (each run in id order within a cell).
    pub(crate) fn cells_near(&self, lo: [f32; 2], hi: [f32; 2], drift: f32) -> impl Iterator<Item = &[u32]> {
        // Both ends lie within `drift` of where they rest, and the second end rests within `span` of
        // the first: the whole link lies within `span + drift` of its first end's rest position.
        let widen = drift + self.span;
        let whole = self.dims == [1, 1];
        let range = |k: usize| -> Option<(usize, usize)> {
            let a = (lo[k] - widen - self.lo[k]) / self.cell;
            let b = (hi[k] + widen - self.lo[k]) / self.cell;
            if whole || !(a.is_finite() && b.is_finite()) {
                return Some((0, self.dims[k] - 1));
            }
            if b < 0.0 || a >= self.dims[k] as f32 {
                return None;
            }
            Some(((a.max(0.0)) as usize, (b as usize).min(self.dims[k] - 1)))
        };
        let rows = match (range(0), range(1)) {
            (Some((i0, i1)), Some((j0, j1))) => Some((i0, i1, j0..=j1)),
            _ => None,
        };
        rows.into_iter().flat_map(move |(i0, i1, js)| {
            js.map(move |j| {
                let (s, e) = (
                    self.start[j * self.dims[0] + i0] as usize,
                    self.start[j * self.dims[0] + i1 + 1] as usize,
                );
                &self.ids[s..e]
            })
        })
    }

    /// The width of a cell (lattice units; infinite when every id is in one cell).
    pub(crate) fn cell_width(&self) -> f32 {
        self.cell
    }

    /// Whether [`LinkGrid::cells_near`] of the same box reads every cell.
    pub(crate) fn covers(&self, lo: [f32; 2], hi: [f32; 2], drift: f32) -> bool {
        let widen = drift + self.span;
        self.is_whole()
            || (0..2).all(|k| {
                lo[k] - widen <= self.lo[k] && hi[k] + widen >= self.lo[k] + self.dims[k] as f32 * self.cell
            })
    }

    /// Whether every id is in one cell (a wrapped surface or a volume): a query reads them all.
    pub(crate) fn is_whole(&self) -> bool {
        self.dims == [1, 1]
    }
}
