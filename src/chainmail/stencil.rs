//! The grid fast path of a whole-body relaxation sweep.
//!
//! On a grid lattice most elements are *regular*: free, with every neighbour at a fixed offset in the
//! flat arrays (`i ± 1`, `i ± nx`, `i ± nx·ny`, in the adjacency's slot order), links of one weight
//! whose boxes depend only on the row (a y-link's on its y coordinate, a z-link's on z, x-links the
//! same along the whole grid), and rest offsets to its neighbours that cancel (a uniform grid, up to
//! the rounding of the rest coordinates). For such an element the damped Jacobi target needs no rest
//! positions: it is `(1 - ω) p + ω · mean(p_j)`, and its constraint boxes are the row's. Runs of
//! regular elements are relaxed a vector at a time with explicit SIMD (`pulp`, which picks AVX-512,
//! AVX2 or plain floats at run time). Everything else (borders, wrap seams, cut links, pins, held
//! elements, other materials or stiffnesses, graded or curvilinear grids) goes through the generic
//! row loop; the two agree up to rounding.
//!
//! On a uniform grid the rest length `c[i + 1] - c[i]` varies in its last bits from column to column
//! and row to row (the coordinates are rounded), and with it the boxes of a relative material. Boxes
//! that agree to within that rounding count as the same: the sweep clamps to a common box, a few units
//! in the last place of the coordinates off the link's own.
//!
//! The sweep works in place (see [`Body::sweep_stencil`]): slab by slab (rows of a sheet, layers of a
//! volume), each written back once the next is computed, so every element reads its neighbours' old
//! positions (a Jacobi sweep). Large bodies are cut into bands of slabs swept on the thread pool with
//! halo copies of the slabs beyond their ends, with the same result.

use super::body::{Body, FIXED, SlotClass};
use super::relax::{OMEGA, relaxed_with};

/// The widest vector the sweep uses: sixteen floats (AVX-512). Bounds are kept as lanes of three
/// floats per element, long enough for three such vectors.
const MAX_LANES: usize = 16;
type Lanes = [f32; 3 * MAX_LANES];

/// What the fast path knows of a grid body; rebuilt when pins, cuts or materials change.
#[derive(Clone, Debug, Default)]
pub(crate) struct Stencil {
    /// Grid dimensions.
    dims: [usize; 3],
    /// Flat offset of the neighbour in each adjacency slot of an interior element.
    pub(crate) offs: Vec<isize>,
    /// 1 where an element's slots hold exactly the neighbours at `offs` (a fact of the lattice: not a
    /// border, not a wrap seam). The chain reaction finds those neighbours by adding the offset.
    pub(crate) interior: Vec<u8>,
    /// 1 where an element's slots hold the neighbours at `offs`, except along x where they may also
    /// be padding (the ends of a row): the chain reaction's runs across rows take such elements.
    pub(crate) across: Vec<u8>,
    /// 1 where the rest offsets to an element's neighbours sum to zero up to rounding.
    balanced: Vec<u8>,
    /// Elements per slab (a row of a sheet, a layer of a volume), and whether every element's
    /// neighbours lie in its own slab or the next one either side (not so across a wrap seam of the
    /// slowest axis: then the sweep cannot work in place and the generic sweep runs).
    slab: usize,
    slab_local: bool,
    /// How far (relative) boxes may differ and still count as the same: the rounding of the rest
    /// coordinates, relative to the shortest link, which a relative material's boxes inherit.
    same_box: f32,
    /// Grid axis of each slot.
    slot_axis: Vec<usize>,
    /// For each slot, the class most elements have there, by grid coordinate along the slot's axis.
    pattern: Vec<Vec<u32>>,
    /// For the x slots: the class most columns have, and for each column whether its class has the
    /// same box and weight.
    x_class: [u32; 2],
    x_column: Vec<u8>,
    /// 1 where an element is regular, and 1 for each row whose interior `1..nx - 1` is.
    regular: Vec<u8>,
    regular_rows: Vec<u8>,
    /// The bounds (lo, hi) of each class regular elements use, as lanes of three floats per element,
    /// and for each slot and grid coordinate along its axis which (x slots: one entry, `x_class`).
    row_blocks: Vec<[Lanes; 2]>,
    row_block_of: Vec<Vec<u32>>,
    /// The two end elements of every row (x = 0 and x = nx - 1), in row order.
    edges: Vec<Edge>,
    /// Whether the tables describe the body as it is.
    pub(crate) fresh: bool,
}

/// An element at the end of a row, with its adjacency row and the rest positions the generic
/// relaxation reads, gathered so that the sweep reads them in order: scattered through the body's
/// arrays, two per row, each would be a cache miss costing as much as the row's other elements.
#[derive(Clone, Copy, Debug, Default)]
struct Edge {
    nbr: [u32; 6],
    class: [u32; 6],
    nbr_rest: [[f32; 3]; 6],
    rest: [f32; 3],
    fixed: bool,
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
fn close(x: f32, y: f32, tolerance: f32) -> bool {
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
        self.fresh = true;
    }
}

/// What a vector of one phase (which coordinate its first lane holds) needs of its row: for each
/// axis (slots `2a`, `2a + 1`), the shift that takes the plus neighbour's box onto the minus one's
/// and the minus slot's bounds `[shift, lo, hi]` (entries `0..W / 2`), and the target's constant.
type PhaseConsts<S, const W: usize> = ([[<S as pulp::Simd>::f32s; 3]; W], <S as pulp::Simd>::f32s);

/// The last row's bounds blocks and the constants made of them, kept from row to row.
type RowCache<S, const W: usize> = ([u32; W], Option<[PhaseConsts<S, W>; 3]>);

/// Relaxes one vector of regular elements' coordinates at `p`, with the neighbours' coordinates `nb`
/// (slot order) lane by lane: the damped Jacobi target `a p + b Σ p_j` (`a = 1 - ω`, `b = ω / W`),
/// shortened per coordinate where it would leave the boxes `[p_j + lo_j, p_j + hi_j]` of the
/// element's links, never reversed (as `relaxed_row`). `change` keeps the largest step up and the
/// largest step down (no absolute value needed).
///
/// Along an axis the two boxes are one box shifted (the plus link's box on `p[i] - p[j]` is the
/// minus link's, negated): with the plus neighbour moved by the shift, the pair bounds the element
/// by `max(minus, plus') + lo` and `min(minus, plus') + hi`, five operations where two boxes take
/// six. The shift comes back out of the sum in the target's constant.
#[inline(always)]
fn vector<S: pulp::Simd, const W: usize>(
    simd: S,
    p: S::f32s,
    nb: [S::f32s; W],
    (axes, k): &PhaseConsts<S, W>,
    [a, b, tiny]: [S::f32s; 3],
    change: &mut [S::f32s; 2],
) -> S::f32s {
    let pair = |ax: usize| {
        let [shift, lo, hi] = axes[ax];
        let (minus, plus) = (nb[2 * ax], simd.add_f32s(nb[2 * ax + 1], shift));
        let sum = simd.add_f32s(minus, plus);
        (sum, simd.add_f32s(simd.max_f32s(minus, plus), lo), simd.add_f32s(simd.min_f32s(minus, plus), hi))
    };
    let (mut sum, mut lo, mut hi) = pair(0);
    for ax in 1..W / 2 {
        let (s, l, h) = pair(ax);
        sum = simd.add_f32s(sum, s);
        lo = simd.max_f32s(lo, l);
        hi = simd.min_f32s(hi, h);
    }
    // Fused multiply-adds where the instruction set has them (plain `a·b + c` otherwise).
    let target = simd.mul_add_e_f32s(b, sum, simd.mul_add_e_f32s(a, p, *k));
    let floor = simd.min_f32s(lo, p);
    let ceil = simd.max_f32s(hi, p);
    let q = simd.min_f32s(simd.max_f32s(target, floor), ceil);
    // Coordinates that relaxation drives toward zero (a sheet's out-of-plane ones) would otherwise
    // decay through the subnormal range, where each operation costs a hundred cycles.
    let q = simd.sub_f32s(simd.add_f32s(q, tiny), tiny);
    let d = simd.sub_f32s(q, p);
    change[0] = simd.max_f32s(change[0], d);
    change[1] = simd.min_f32s(change[1], d);
    q
}

/// The shift lanes that take the box `[lo1, hi1]` onto `[lo0, hi0]` (`lo1 = lo0 + shift`,
/// `hi1 = hi0 + shift`), if they are one box shifted to within `tolerance`.
fn shift_lanes(lo0: &Lanes, hi0: &Lanes, lo1: &Lanes, hi1: &Lanes, tolerance: f32) -> Option<Lanes> {
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

/// Three vectors of `S` from `s` at float `at`, if there.
#[inline(always)]
fn load3<S: pulp::Simd>(s: &[f32], at: usize) -> Option<[S::f32s; 3]> {
    let (head, _) = S::as_simd_f32s(s.get(at..at + 3 * S::F32_LANES)?);
    Some([*head.first()?, *head.get(1)?, *head.get(2)?])
}

/// The old positions of one slab and of the slabs either side (`None` past the grid's ends), as a
/// band sweeping in place sees them: its own slab not yet written, the one before kept back until
/// this one is computed, and halo copies where the neighbour slab belongs to another band.
#[derive(Clone, Copy)]
struct Window<'a> {
    /// Elements per slab, and the slab's index in the grid.
    slab: usize,
    s: usize,
    prev: Option<&'a [[f32; 3]]>,
    cur: &'a [[f32; 3]],
    next: Option<&'a [[f32; 3]]>,
}

impl<'a> Window<'a> {
    /// The old position of element `j`, which lies in this slab or one either side (a stencil's
    /// grid is slab-local).
    #[inline(always)]
    fn pos(&self, j: usize) -> [f32; 3] {
        // Comparisons, not a division: this runs for every neighbour of every row end.
        let base = self.s * self.slab;
        let (slab, local) = if j < base {
            (self.prev, (j + self.slab).wrapping_sub(base))
        } else if j - base < self.slab {
            (Some(self.cur), j - base)
        } else {
            (self.next, j - base - self.slab)
        };
        slab.and_then(|s| s.get(local)).copied().unwrap_or_default()
    }

    /// The stream of slot offset `off` (in elements) for the run of `n` floats from element
    /// `first` of this slab: the neighbour slab's same place for a whole slab's offset, else this
    /// slab shifted.
    #[inline(always)]
    fn stream(&self, off: isize, first: usize, n: usize) -> Option<&'a [f32]> {
        let (slab, at) = if off == self.slab as isize {
            (self.next?, first)
        } else if off == -(self.slab as isize) {
            (self.prev?, first)
        } else {
            (self.cur, usize::try_from(first as isize + off).ok()?)
        };
        slab.as_flattened().get(3 * at..3 * at + n)
    }
}

/// One band of whole slabs swept in place, as an operation for [`pulp::Arch::dispatch`].
struct Band<'a, const W: usize> {
    body: &'a Body,
    stencil: &'a Stencil,
    /// The band's first slab, its positions, the old slabs either side (halo copies), and two
    /// slabs of scratch.
    first: usize,
    region: &'a mut [[f32; 3]],
    prev: Option<&'a [[f32; 3]]>,
    next: Option<&'a [[f32; 3]]>,
    scratch: &'a mut [[f32; 3]],
}

impl<const W: usize> pulp::WithSimd for Band<'_, W> {
    type Output = f32;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> f32 {
        let Band { body, stencil: st, first, region, prev, next, scratch } = self;
        let slab = st.slab;
        let m = region.len() / slab;
        let (now, pending) = scratch.split_at_mut(slab);
        let mut buffers = [now, &mut pending[..slab]];
        let mut change = 0.0f32;
        let mut lane_change = [simd.splat_f32s(0.0); 2];
        let mut cache = ([u32::MAX; W], None);
        for r in 0..m {
            {
                // Slab `r - 1` is still old: its new positions wait in `buffers[1]`.
                let (done, rest) = region.split_at(r * slab);
                let window = Window {
                    slab,
                    s: first + r,
                    prev: if r == 0 { prev } else { done.get((r - 1) * slab..) },
                    cur: &rest[..slab],
                    next: if r + 1 < m { rest.get(slab..2 * slab) } else { next },
                };
                let [now, _] = &mut buffers;
                body.relax_slab::<S, W>(simd, st, &window, now, &mut change, &mut lane_change, &mut cache);
            }
            if r > 0 {
                region[(r - 1) * slab..r * slab].copy_from_slice(buffers[1]);
            }
            buffers.swap(0, 1);
        }
        if let Some(last) = region.get_mut((m.max(1) - 1) * slab..) {
            last.copy_from_slice(buffers[1]);
        }
        let lanes = simd.reduce_max_f32s(lane_change[0]).max(-simd.reduce_min_f32s(lane_change[1]));
        if lanes > change { lanes } else { change }
    }
}

/// Added to and taken from every relaxed coordinate: values under `2^-84` become 0 and values
/// under `2^-36` are rounded to multiples of `2^-83`, so that no coordinate is subnormal; larger
/// values are unchanged (the sum rounds back to them exactly).
pub(crate) const FLUSH: f32 = 8.673617e-19; // 2^-60

/// Bodies of fewer elements sweep on one thread: a second one costs more to start than it saves.
const PARALLEL_MIN: usize = 1 << 15;
/// Fewest slabs a band has.
const BAND_MIN: usize = 4;

/// How long the calling thread waits for the pool's band by spinning before it blocks.
const SPIN: std::time::Duration = std::time::Duration::from_millis(2);

/// Runs `here` on the calling thread and `there` on the thread pool, and returns both results.
///
/// `rayon::join` called from outside the pool hands both halves to the pool and puts the caller to
/// sleep until they are done: on this project's virtual machines waking the sleeping threads costs
/// tens of microseconds, as much as a quarter of a whole-body sweep. Here only one pool thread is
/// woken, and the caller, once done with its own half, spins briefly rather than sleeping (and
/// then blocks as usual, which also lets a pool thread calling this run the other half itself).
fn here_and_there<A, B>(here: A, there: B) -> (f32, f32)
where
    A: FnOnce() -> f32,
    B: FnOnce() -> f32 + Send,
{
    use std::sync::atomic::{AtomicBool, Ordering};
    let done = AtomicBool::new(false);
    let mut far = 0.0;
    let near = rayon::in_place_scope(|s| {
        s.spawn(|_| {
            far = there();
            done.store(true, Ordering::Release);
        });
        let near = here();
        let start = std::time::Instant::now();
        while !done.load(Ordering::Acquire) && start.elapsed() < SPIN {
            for _ in 0..64 {
                std::hint::spin_loop();
            }
        }
        near
    });
    (near, far)
}

/// Scratch slabs a sweep split `depth` times needs: two per band, two halos per split.
fn scratch_slabs(depth: u32) -> usize {
    (0..depth).fold(2, |s, _| 2 * s + 2)
}

impl Body {
    /// One Jacobi sweep over every element through the grid fast path, in place, with `scratch`
    /// (the workspace's spare positions); `None` if this body has no stencil, its neighbours reach
    /// across a seam of the slowest axis, or it is too short. Returns the largest move.
    ///
    /// A band of slabs (rows of a sheet, layers of a volume) computes each slab into scratch and
    /// writes it back once the next one is computed, so every element sees its neighbours' old
    /// positions (a Jacobi sweep) while positions are read once and written once. Large bodies are
    /// cut into bands swept on the pool's threads, each seeing copies of the slabs beyond its ends:
    /// the result does not depend on the cut.
    pub(crate) fn sweep_stencil(&mut self, scratch: &mut [[f32; 3]]) -> Option<f32> {
        let st = self.stencil.as_ref()?;
        let n = self.pos.len();
        let slab = st.slab;
        if !st.slab_local || slab == 0 || !n.is_multiple_of(slab) || scratch.len() < 2 * slab {
            return None;
        }
        let slabs = n / slab;
        let threads = if n >= PARALLEL_MIN { rayon::current_num_threads() } else { 1 };
        // One band per thread (the calling thread sweeps one of them); one thread sweeps alone.
        let mut depth = 0;
        while threads > 1
            && (1 << (depth + 1)) <= threads
            && slabs >> (depth + 1) >= BAND_MIN
            && scratch_slabs(depth + 1) * slab <= scratch.len()
        {
            depth += 1;
        }
        let mut stencil = self.stencil.take()?;
        if !stencil.fresh {
            stencil.refresh(self);
        }
        let mut pos = std::mem::take(&mut self.pos);
        let change = match stencil.offs.len() {
            4 => Some(self.sweep_range::<4>(&stencil, 0, &mut pos, None, None, scratch, depth, true)),
            6 => Some(self.sweep_range::<6>(&stencil, 0, &mut pos, None, None, scratch, depth, true)),
            _ => None,
        };
        self.pos = pos;
        self.stencil = Some(stencil);
        change
    }

    /// Sweeps the slabs of `region` (from slab `first`), split `depth` times into bands run in
    /// parallel. `prev` and `next` are the old slabs beyond the region's ends.
    #[allow(clippy::too_many_arguments)]
    fn sweep_range<const W: usize>(
        &self,
        st: &Stencil,
        first: usize,
        region: &mut [[f32; 3]],
        prev: Option<&[[f32; 3]]>,
        next: Option<&[[f32; 3]]>,
        scratch: &mut [[f32; 3]],
        depth: u32,
        top: bool,
    ) -> f32 {
        let slab = st.slab;
        let half = region.len() / slab / 2;
        if depth == 0 || half == 0 {
            // Each band is compiled once per instruction set and the widest the CPU has is chosen
            // at run time (AVX-512 or AVX2 on x86-64, single floats elsewhere). Rows too short for
            // AVX-512's sixteen elements take AVX2's eight.
            let band = Band::<W> { body: self, stencil: st, first, region, prev, next, scratch };
            #[cfg(target_arch = "x86_64")]
            if st.dims[0] < 2 + 16
                && let Some(v3) = pulp::x86::V3::try_new()
            {
                return pulp::Simd::vectorize(v3, band);
            }
            return pulp::Arch::new().dispatch(band);
        }
        let (halos, rest) = scratch.split_at_mut(2 * slab);
        let (left_last, right_first) = halos.split_at_mut(slab);
        left_last.copy_from_slice(&region[(half - 1) * slab..half * slab]);
        right_first.copy_from_slice(&region[half * slab..(half + 1) * slab]);
        let (left, right) = region.split_at_mut(half * slab);
        let (left_scratch, right_scratch) = rest.split_at_mut(rest.len() / 2);
        let left = || {
            self.sweep_range::<W>(st, first, left, prev, Some(right_first), left_scratch, depth - 1, false)
        };
        let right = || {
            self.sweep_range::<W>(
                st,
                first + half,
                right,
                Some(left_last),
                next,
                right_scratch,
                depth - 1,
                false,
            )
        };
        // Inside the pool a plain `join`; from outside it, the calling thread takes a band itself.
        let (a, b) = if top { here_and_there(right, left) } else { rayon::join(left, right) };
        a.max(b)
    }

    /// Computes the relaxed positions of the window's slab into `out` from the window's old
    /// positions. `change` gathers the generic elements' largest move, `lane_change` the vectors'.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn relax_slab<S: pulp::Simd, const W: usize>(
        &self,
        simd: S,
        st: &Stencil,
        window: &Window<'_>,
        out: &mut [[f32; 3]],
        change: &mut f32,
        lane_change: &mut [S::f32s; 2],
        cache: &mut RowCache<S, W>,
    ) {
        let [nx, ny, nz] = st.dims;
        let base = window.s * st.slab;
        let w = self.width;
        let classes = &self.classes;
        let pos_of = |j: usize| window.pos(j);
        let generic = |i: usize, out: &mut [[f32; 3]], change: &mut f32| {
            let (p, q) = (pos_of(i), self.relaxed_in(i, pos_of));
            *change = super::relax::max_change(*change, p, q);
            out[i - base] = q;
        };
        // A row end through its gathered copy (the same arithmetic as `generic`).
        let edge = |i: usize, at: usize, out: &mut [[f32; 3]], change: &mut f32| {
            let p = pos_of(i);
            let q = match st.edges.get(at) {
                Some(e) if !e.fixed => {
                    relaxed_with(pos_of, p, e.rest, &e.nbr[..w], &e.class[..w], classes, |t, _| e.nbr_rest[t])
                }
                _ => p,
            };
            *change = super::relax::max_change(*change, p, q);
            out[i - base] = q;
        };
        let interior = |c: usize, len: usize| len < 2 || (c > 0 && c + 1 < len);
        // The row's constants by phase, rebuilt when the row's classes change; `None` where an axis's
        // two boxes are not one box shifted (then the row takes the generic path).
        let (consts_of, consts) = cache;
        for row in (base..base + st.slab).step_by(nx) {
            let (j, k) = ((row / nx) % ny, row / (nx * ny));
            if !(interior(j, ny) && interior(k, nz)) {
                for i in row..row + nx {
                    generic(i, out, change);
                }
                continue;
            }
            let mut of = [u32::MAX; W];
            for (t, of) in of.iter_mut().enumerate() {
                let c = match st.slot_axis[t] {
                    0 => 0,
                    1 => j,
                    _ => k,
                };
                *of = st.row_block_of.get(t).and_then(|of| of.get(c)).copied().unwrap_or(u32::MAX);
            }
            if of != *consts_of {
                *consts_of = of;
                *consts = self.row_consts::<S, W>(simd, st, &of);
            }
            let Some(consts) = consts else {
                for i in row..row + nx {
                    generic(i, out, change);
                }
                continue;
            };
            // Runs of regular elements along the row's interior `1..nx - 1`.
            let regular = st.regular.get(row + 1..row + nx - 1).unwrap_or_default();
            let whole = st.regular_rows.get(row / nx) == Some(&1);
            let mut x = 1;
            while x < nx - 1 {
                let len =
                    if whole { nx - 2 } else { regular[x - 1..].iter().take_while(|&&r| r == 1).count() };
                if len >= S::F32_LANES {
                    let run = &mut out[row + x - base..];
                    // A run whose streams are not all there (never, on a stencil's grid) is done one
                    // element at a time instead.
                    if !relax_run::<S, W>(simd, st, window, row + x - base, len, consts, run, lane_change) {
                        for i in row + x..row + x + len {
                            generic(i, out, change);
                        }
                    }
                    x += len;
                } else {
                    let end = x + len.max(1);
                    for i in row + x..row + end {
                        generic(i, out, change);
                    }
                    x = end;
                }
            }
            // The ends last: the vectors have brought the next row into the cache.
            edge(row, 2 * (row / nx), out, change);
            edge(row + nx - 1, 2 * (row / nx) + 1, out, change);
        }
    }

    /// The constants of a row whose slots have the bounds blocks `of`, by phase; `None` if an axis's
    /// two boxes are not one box shifted.
    #[inline(always)]
    fn row_consts<S: pulp::Simd, const W: usize>(
        &self,
        simd: S,
        st: &Stencil,
        of: &[u32; W],
    ) -> Option<[PhaseConsts<S, W>; 3]> {
        let block = |t: usize| st.row_blocks.get(of[t] as usize);
        let mut lanes = [[[0.0f32; 3 * MAX_LANES]; 3]; W];
        let mut total = [0.0f32; 3 * MAX_LANES];
        for (ax, lanes) in lanes.iter_mut().enumerate().take(W / 2) {
            let ([lo0, hi0], [lo1, hi1]) = (block(2 * ax)?, block(2 * ax + 1)?);
            let shift = shift_lanes(lo0, hi0, lo1, hi1, st.same_box)?;
            for (t, s) in total.iter_mut().zip(&shift) {
                *t += s;
            }
            *lanes = [shift, *lo0, *hi0];
        }
        let k = total.map(|s| -(OMEGA / W as f32) * s);
        let load = |l: &Lanes| load3::<S>(l, 0);
        let zero = simd.splat_f32s(0.0);
        let mut consts = [([[zero; 3]; W], zero); 3];
        let ks = load(&k)?;
        for (v, (axes, kv)) in consts.iter_mut().enumerate() {
            *kv = ks[v];
            for ax in 0..W / 2 {
                for e in 0..3 {
                    axes[ax][e] = load(&lanes[ax][e])?[v];
                }
            }
        }
        Some(consts)
    }
}

/// Relaxes the `len` (at least `S::F32_LANES`) regular elements from element `first` of the
/// window's slab into `out` (starting at `first`'s place), three vectors at a time; the last three
/// are moved back to end with the run, overlapping their neighbours (computed twice, alike).
/// Returns `false`, with the run not (or not all) written, if a stream is missing.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn relax_run<S: pulp::Simd, const W: usize>(
    simd: S,
    st: &Stencil,
    window: &Window<'_>,
    first: usize,
    len: usize,
    consts: &[PhaseConsts<S, W>; 3],
    out: &mut [[f32; 3]],
    lane_change: &mut [S::f32s; 2],
) -> bool {
    let (n, g) = (3 * len, 3 * S::F32_LANES);
    let (Some(p), Some(out)) = (window.stream(0, first, n), out.as_flattened_mut().get_mut(..n)) else {
        return false;
    };
    let mut nbrs: [&[f32]; W] = [&[]; W];
    for (t, nb) in nbrs.iter_mut().enumerate() {
        let Some(s) = window.stream(st.offs[t], first, n) else { return false };
        *nb = s;
    }
    let weights = [simd.splat_f32s(1.0 - OMEGA), simd.splat_f32s(OMEGA / W as f32), simd.splat_f32s(FLUSH)];
    // Whole groups of three vectors, straight from the streams. Plain loops and indexing: a
    // closure would not inherit the instruction set, and each vector operation would be a call.
    let pv = S::as_simd_f32s(p).0;
    let m = pv.len();
    let mut nv: [&[S::f32s]; W] = [&[]; W];
    for t in 0..W {
        nv[t] = S::as_simd_f32s(nbrs[t]).0;
    }
    let ov = S::as_mut_simd_f32s(out).0;
    if ov.len() != m || nv.iter().any(|v| v.len() != m) {
        return false;
    }
    let whole = m - m % 3;
    let mut nb = [simd.splat_f32s(0.0); W];
    // Locals, so that the loop keeps them in registers.
    let (consts, mut change) = (*consts, *lane_change);
    for k in (0..whole).step_by(3) {
        for (v, consts) in consts.iter().enumerate() {
            let i = k + v;
            for t in 0..W {
                nb[t] = nv[t][i];
            }
            ov[i] = vector::<S, W>(simd, pv[i], nb, consts, weights, &mut change);
        }
    }
    *lane_change = change;
    if whole * S::F32_LANES == n {
        return true;
    }
    // The rest: one group moved back to end with the run.
    let last = n - g;
    let (Some(pk), Some(o)) = (load3::<S>(p, last), out.get_mut(last..last + g)) else { return false };
    let mut nbs = [pk; W];
    for t in 0..W {
        let Some(v) = load3::<S>(nbrs[t], last) else { return false };
        nbs[t] = v;
    }
    let (head, _) = S::as_mut_simd_f32s(o);
    for (v, (slot, consts)) in head.iter_mut().zip(&consts).enumerate() {
        for t in 0..W {
            nb[t] = nbs[t][v];
        }
        *slot = vector::<S, W>(simd, pk[v], nb, consts, weights, lane_change);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::super::{Body, Lattice, Material, RelaxBudget, RelaxRegion, Workspace};

    #[test]
    fn interior_of_a_plain_sheet_is_regular() {
        let body =
            Body::new(Lattice::sheet(64, 32, 0.001).expect("sheet"), Material::relative(1.2, 0.8, 0.3))
                .expect("body");
        let mut st = body.stencil.clone().expect("stencil");
        st.refresh(&body);
        let regular = st.regular.iter().filter(|&&r| r == 1).count();
        assert_eq!(regular, 62 * 30, "every interior element is regular");
        assert!(st.regular_rows.iter().skip(1).take(30).all(|&r| r == 1), "whole rows");
        let mut body = body;
        let mut ws = Workspace::new(&body);
        body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::All);
        assert!(body.stencil.as_ref().is_some_and(|s| s.fresh), "refreshed once, then kept");
    }
}
