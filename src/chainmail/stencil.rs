//! What the fast paths know of a grid body: the flat offsets of each slot's neighbour (both loops),
//! which elements have their neighbours there (the chain reaction's runs across rows), and the
//! relaxation sweep's tables: which elements are *regular* and the row boxes their vectors clamp to.
//!
//! On a grid lattice most elements are regular: free, with every neighbour at a fixed offset in the
//! flat arrays (`i ± 1`, `i ± nx`, `i ± nx·ny`, in the adjacency's slot order), links of one weight
//! whose boxes depend only on the row (a y-link's on its y coordinate, a z-link's on z, x-links the
//! same along the whole grid), and rest offsets to its neighbours that cancel (a uniform grid, up to
//! the rounding of the rest coordinates). Everything else (borders, wrap seams, cut links, pins, held
//! elements, other materials or stiffnesses, graded or curvilinear grids) takes the generic paths.
//!
//! On a uniform grid the rest length `c[i + 1] - c[i]` varies in its last bits from column to column
//! and row to row (the coordinates are rounded), and with it the boxes of a relative material. Boxes
//! that agree to within that rounding count as the same: the sweep clamps to a common box, a few units
//! in the last place of the coordinates off the link's own.
//!
//! A [`Workspace`](super::Workspace) keeps the stencil of the body it serves: the lattice's part is
//! built once per lattice, the sweep's tables again whenever the body's revision changes.

use super::body::{Body, FIXED, SlotClass};

/// The widest vector the sweep uses: sixteen floats (AVX-512). Bounds are kept as lanes of three
/// floats per element, long enough for three such vectors.
pub(crate) const MAX_LANES: usize = 16;
pub(crate) type Lanes = [f32; 3 * MAX_LANES];

/// What the fast paths know of a grid body.
#[derive(Clone, Debug, Default)]
pub(crate) struct Stencil {
    /// Grid dimensions.
    pub(crate) dims: [usize; 3],
    /// Flat offset of the neighbour in each adjacency slot of an interior element.
    pub(crate) offs: Vec<isize>,
    /// 1 where an element's slots hold exactly the neighbours at `offs` (a fact of the lattice: not a
    /// border, not a wrap seam). The chain reaction finds those neighbours by adding the offset.
    pub(crate) interior: Vec<u8>,
    /// 1 where an element's slots hold the neighbours at `offs`, except along x where they may also
    /// be padding (the ends of a row): the chain reaction's runs across rows take such elements.
    pub(crate) across: Vec<u8>,
    /// 1 where the rest offsets to an element's neighbours sum to zero up to rounding.
    pub(crate) balanced: Vec<u8>,
    /// Elements per slab (a row of a sheet, a layer of a volume), and whether every element's
    /// neighbours lie in its own slab or the next one either side (not so across a wrap seam of the
    /// slowest axis: then the sweep cannot work in place and the generic sweep runs).
    pub(crate) slab: usize,
    pub(crate) slab_local: bool,
    /// How far (relative) boxes may differ and still count as the same: the rounding of the rest
    /// coordinates, relative to the shortest link, which a relative material's boxes inherit.
    pub(crate) same_box: f32,
    /// Grid axis of each slot.
    pub(crate) slot_axis: Vec<usize>,
    /// For each slot, the class most elements have there, by grid coordinate along the slot's axis.
    pub(crate) pattern: Vec<Vec<u32>>,
    /// For the x slots: the class most columns have, and for each column whether its class has the
    /// same box and weight.
    pub(crate) x_class: [u32; 2],
    pub(crate) x_column: Vec<u8>,
    /// 1 where an element is regular, and 1 for each row whose interior `1..nx - 1` is.
    pub(crate) regular: Vec<u8>,
    pub(crate) regular_rows: Vec<u8>,
    /// The bounds (lo, hi) of each class regular elements use, as lanes of three floats per element,
    /// and for each slot and grid coordinate along its axis which (x slots: one entry, `x_class`).
    pub(crate) row_blocks: Vec<[Lanes; 2]>,
    pub(crate) row_block_of: Vec<Vec<u32>>,
    /// The two end elements of every row (x = 0 and x = nx - 1), in row order.
    pub(crate) edges: Vec<Edge>,
    /// The [`Body::revision`] the sweep's tables describe (0: none yet).
    pub(crate) revision: u64,
}

/// An element at the end of a row, with its adjacency row and the rest positions the generic
/// relaxation reads, gathered so that the sweep reads them in order: scattered through the body's
/// arrays, two per row, each would be a cache miss costing as much as the row's other elements.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Edge {
    pub(crate) nbr: [u32; 6],
    pub(crate) class: [u32; 6],
    pub(crate) nbr_rest: [[f32; 3]; 6],
    pub(crate) rest: [f32; 3],
    pub(crate) fixed: bool,
}

/// Boyer-Moore majority vote: the value most of `values` have, if any has more than half.
fn majority(values: impl Iterator<Item = u32>) -> u32 {
    let (mut value, mut count) = (0u32, 0u32);
    for v in values {
        if count == 0 {
            (value, count) = (v, 1);
        } else if v == value {
            count += 1;
        } else {
            count -= 1;
        }
    }
    value
}

/// Whether two bounds are equal to within `tolerance` (relative), infinities only to themselves.
pub(crate) fn close(x: f32, y: f32, tolerance: f32) -> bool {
    x == y || (x - y).abs() <= tolerance * x.abs().max(y.abs())
}

/// Whether two classes have boxes equal to within `tolerance` (relative).
fn same_box(a: &SlotClass, b: &SlotClass, tolerance: f32) -> bool {
    let (a, b) = (a.bounds.as_flattened(), b.bounds.as_flattened());
    a.iter().zip(b).all(|(&x, &y)| close(x, y, tolerance))
}

impl Stencil {
    /// The stencil of a grid body, if the body has the grid's slot layout (two slots per axis of more
    /// than one element, x first), else `None`.
    pub(crate) fn for_body(body: &Body) -> Option<Self> {
        let dims = body.lattice.dims?;
        let [nx, ny, nz] = dims;
        let strides = [1isize, nx as isize, (nx * ny) as isize];
        let mut offs = Vec::new();
        let mut slot_axis = Vec::new();
        for (axis, &len) in dims.iter().enumerate() {
            if len >= 2 {
                offs.extend([-strides[axis], strides[axis]]);
                slot_axis.extend([axis, axis]);
            }
        }
        if offs.len() != body.width || slot_axis.first() != Some(&0) {
            return None;
        }
        let w = body.width;
        let n = body.pos.len();
        let rows = body.slot_nbr.chunks_exact(w);
        let interior = rows
            .clone()
            .enumerate()
            .map(|(i, row)| {
                let at = |t: usize| i as isize + offs[t];
                row.iter().enumerate().all(|(t, &j)| (0..n as isize).contains(&at(t)) && j as isize == at(t))
                    as u8
            })
            .collect();
        let across = rows
            .clone()
            .enumerate()
            .map(|(i, row)| {
                let at = |t: usize| i as isize + offs[t];
                row.iter().enumerate().all(|(t, &j)| {
                    ((0..n as isize).contains(&at(t)) && j as isize == at(t))
                        || (slot_axis[t] == 0 && j as usize == i)
                }) as u8
            })
            .collect();
        let rest = &body.lattice.rest;
        let balanced = rows
            .clone()
            .enumerate()
            .map(|(i, row)| {
                (0..3).all(|c| {
                    let ri = rest[i][c] as f64;
                    let (sum, size) = row.iter().fold((0.0f64, 0.0f64), |(s, m), &j| {
                        let rj = rest[j as usize][c] as f64;
                        (s + (rj - ri), m + rj.abs() + ri.abs())
                    });
                    sum.abs() <= 4.0 * f32::EPSILON as f64 * size
                }) as u8
            })
            .collect();
        let slab = if nz > 1 { nx * ny } else { nx };
        let slab_local =
            rows.enumerate().all(|(i, row)| row.iter().all(|&j| (j as usize / slab).abs_diff(i / slab) <= 1));
        let pattern = slot_axis.iter().map(|&a| vec![0; dims[a]]).collect();
        let largest = rest.iter().flatten().fold(0.0f32, |m, &c| m.max(c.abs()));
        let offsets = body.lattice.rest_offset.iter();
        let shortest =
            offsets.map(|o| o.iter().fold(0.0f32, |m, &c| m.max(c.abs()))).fold(f32::INFINITY, f32::min);
        // Capped at one part in a thousand: boxes further apart are different materials.
        let same_box = (8.0 * f32::EPSILON * (1.0 + largest / shortest)).min(1e-3);
        Some(Self {
            dims,
            offs,
            interior,
            across,
            balanced,
            slab,
            slab_local,
            same_box,
            slot_axis,
            pattern,
            ..Self::default()
        })
    }

    /// Finds the common class of each slot by grid coordinate, marks the regular elements, and lays
    /// out the bounds and the row ends.
    pub(crate) fn refresh(&mut self, body: &Body) {
        let [nx, ny, nz] = self.dims;
        let n = body.pos.len();
        let w = body.width;
        let classes = &body.classes;
        // Element `i` sits at grid coordinates `at`; slot `t` runs along axis `slot_axis[t]`.
        let mut count: Vec<Vec<u32>> = self.pattern.iter().map(|p| vec![0; p.len()]).collect();
        let mut i = 0;
        for k in 0..nz {
            for j in 0..ny {
                for x in 0..nx {
                    let at = [x, j, k];
                    for t in 0..w {
                        let c = at[self.slot_axis[t]];
                        let class = body.slot_class[i * w + t];
                        let (pattern, count) = (&mut self.pattern[t][c], &mut count[t][c]);
                        if *count == 0 {
                            (*pattern, *count) = (class, 1);
                        } else if *pattern == class {
                            *count += 1;
                        } else {
                            *count -= 1;
                        }
                    }
                    i += 1;
                }
            }
        }
        let interior_columns = 1..nx.saturating_sub(1);
        for t in 0..2 {
            let columns = self.pattern[t].get(interior_columns.clone()).unwrap_or_default();
            self.x_class[t] = majority(columns.iter().copied());
        }
        let x_classes = self.x_class.map(|c| classes[c as usize]);
        self.x_column = (0..nx)
            .map(|x| {
                (0..2).all(|t| {
                    let c = classes[self.pattern[t][x] as usize];
                    c.w.to_bits() == x_classes[t].w.to_bits() && same_box(&c, &x_classes[t], self.same_box)
                }) as u8
            })
            .collect();
        // One weight for every class a regular element can have?
        let mut weights = self.pattern.iter().skip(2).flatten().chain(&self.x_class).filter(|&&c| c != 0);
        let one_weight = match weights.next() {
            Some(&c) => {
                let w = classes[c as usize].w;
                w > 0.0 && weights.all(|&c| classes[c as usize].w.to_bits() == w.to_bits())
            }
            None => false,
        };
        self.regular.resize(n, 0);
        let mut i = 0;
        for k in 0..nz {
            for j in 0..ny {
                for x in 0..nx {
                    let at = [x, j, k];
                    let row = &body.slot_class[i * w..(i + 1) * w];
                    let mut ok = one_weight
                        && self.x_column[x] == 1
                        && self.interior[i] == 1
                        && self.balanced[i] == 1
                        && body.flags[i] & FIXED == 0;
                    for (t, &class) in row.iter().enumerate() {
                        ok &= class == self.pattern[t][at[self.slot_axis[t]]] && class != 0;
                    }
                    self.regular[i] = ok as u8;
                    i += 1;
                }
            }
        }
        let whole = |r: &[u8]| r.get(interior_columns.clone()).is_some_and(|r| r.iter().all(|&r| r == 1));
        self.regular_rows.clear();
        self.regular_rows.extend(self.regular.chunks_exact(nx).map(|r| whole(r) as u8));
        // Blocks of classes whose boxes agree to within the rounding of the rest coordinates are
        // shared, so that on a uniform grid every row has the same blocks.
        self.row_blocks.clear();
        self.row_block_of.clear();
        // The class each block was made from.
        let mut made_from: Vec<SlotClass> = Vec::new();
        for (t, pattern) in self.pattern.iter().enumerate() {
            let used = if t < 2 { std::slice::from_ref(&self.x_class[t]) } else { &pattern[..] };
            let mut of = Vec::with_capacity(used.len());
            for &class in used {
                let c = classes[class as usize];
                let index = match made_from.iter().position(|b| same_box(b, &c, self.same_box)) {
                    Some(index) => index,
                    None => {
                        let lanes = |b: [f32; 3]| std::array::from_fn(|e| b[e % 3]);
                        self.row_blocks.push([lanes(c.bounds[0]), lanes(c.bounds[1])]);
                        made_from.push(c);
                        made_from.len() - 1
                    }
                };
                of.push(index as u32);
            }
            self.row_block_of.push(of);
        }
        self.edges.clear();
        for row in (0..n).step_by(nx) {
            for i in [row, row + nx - 1] {
                let rest = body.lattice.rest[i];
                let mut edge = Edge { rest, fixed: body.flags[i] & FIXED != 0, ..Edge::default() };
                for t in 0..w {
                    let j = body.slot_nbr[i * w + t];
                    edge.nbr[t] = j;
                    edge.class[t] = body.slot_class[i * w + t];
                    edge.nbr_rest[t] = body.lattice.rest[j as usize];
                }
                self.edges.push(edge);
            }
        }
        self.revision = body.revision;
    }
}

/// The shift lanes that take the box `[lo1, hi1]` onto `[lo0, hi0]` (`lo1 = lo0 + shift`,
/// `hi1 = hi0 + shift`), if they are one box shifted to within `tolerance`.
pub(crate) fn shift_lanes(
    lo0: &Lanes,
    hi0: &Lanes,
    lo1: &Lanes,
    hi1: &Lanes,
    tolerance: f32,
) -> Option<Lanes> {
    let mut shift = [0.0f32; 3 * MAX_LANES];
    for l in 0..shift.len() {
        let (a, b, c, d) = (lo0[l], hi0[l], lo1[l], hi1[l]);
        let s = if a.is_finite() && c.is_finite() {
            c - a
        } else if b.is_finite() && d.is_finite() {
            d - b
        } else {
            0.0
        };
        if !(close(a + s, c, tolerance) && close(b + s, d, tolerance)) {
            return None;
        }
        shift[l] = s;
    }
    Some(shift)
}

#[cfg(test)]
mod tests {
    use super::super::{Body, Lattice, Material, RelaxBudget, RelaxRegion, Workspace};

    #[test]
    fn interior_of_a_plain_sheet_is_regular() {
        let body =
            Body::new(Lattice::sheet(64, 32, 0.001).expect("sheet"), Material::relative(1.2, 0.8, 0.3))
                .expect("body");
        let mut ws = Workspace::new(&body);
        let mut st = ws.stencil.clone().expect("stencil");
        st.refresh(&body);
        let regular = st.regular.iter().filter(|&&r| r == 1).count();
        assert_eq!(regular, 62 * 30, "every interior element is regular");
        assert!(st.regular_rows.iter().skip(1).take(30).all(|&r| r == 1), "whole rows");
        let mut body = body;
        body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::All);
        let revision = Some(body.revision);
        assert_eq!(ws.stencil.as_ref().map(|s| s.revision), revision, "refreshed once, then kept");
    }
}
