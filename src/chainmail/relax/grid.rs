//! The grid kernel of a whole-body sweep: runs of regular elements (see `stencil.rs`) relaxed a SIMD
//! vector at a time (`pulp`: AVX-512, AVX2 or plain floats, as the workspace's level allows), the
//! other elements through the plain kernel, slab by slab (rows of a sheet, layers of a volume) in
//! place. For a regular element the damped Jacobi target needs no rest positions: it is
//! `(1 - ω) p + ω · mean(p_j)`, and its constraint boxes are the row's; the result agrees with the
//! plain kernel up to rounding.
//!
//! A band of slabs computes each slab into scratch and writes it back once the next one is
//! computed, so every element sees its neighbours' old positions (a Jacobi sweep) while positions
//! are read once and written once; `bands.rs` cuts a body into bands.

use super::kernel::{FLUSH, OMEGA, max_change, relaxed_bounded};
use crate::chainmail::body::Body;
use crate::chainmail::simd::SimdLevel;
use crate::chainmail::stencil::{Lanes, MAX_LANES, Stencil, shift_lanes};

/// What a vector of one phase (which coordinate its first lane holds) needs of its row: for each
/// axis (slots `2a`, `2a + 1`), the shift that takes the plus neighbour's box onto the minus one's
/// and the minus slot's bounds `[shift, lo, hi]` (entries `0..W / 2`), and the target's constant.
type PhaseConsts<S, const W: usize> = ([[<S as pulp::Simd>::f32s; 3]; W], <S as pulp::Simd>::f32s);

/// The last row's bounds blocks and the constants made of them, kept from row to row.
type RowCache<S, const W: usize> = ([u32; W], Option<[PhaseConsts<S, W>; 3]>);

/// What a band's sweep carries from slab to slab: the generic elements' largest move, the vectors'
/// largest steps up and down, and the last row's constants.
struct Sweeper<S: pulp::Simd, const W: usize> {
    change: f32,
    lane_change: [S::f32s; 2],
    cache: RowCache<S, W>,
}

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
    pub(super) prev: Option<&'a [[f32; 3]]>,
    cur: &'a [[f32; 3]],
    pub(super) next: Option<&'a [[f32; 3]]>,
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
pub(super) struct Band<'a, const W: usize> {
    pub(super) body: &'a Body,
    pub(super) stencil: &'a Stencil,
    /// The widest SIMD it may use.
    pub(super) simd: SimdLevel,
    /// The band's first slab, its positions, the old slabs either side (halo copies), and two
    /// slabs of scratch.
    pub(super) first: usize,
    pub(super) region: &'a mut [[f32; 3]],
    pub(super) prev: Option<&'a [[f32; 3]]>,
    pub(super) next: Option<&'a [[f32; 3]]>,
    pub(super) scratch: &'a mut [[f32; 3]],
}

impl<const W: usize> pulp::WithSimd for Band<'_, W> {
    type Output = f32;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> f32 {
        let Band { body, stencil: st, first, region, prev, next, scratch, .. } = self;
        let slab = st.slab;
        let m = region.len() / slab;
        let (now, pending) = scratch.split_at_mut(slab);
        let mut buffers = [now, &mut pending[..slab]];
        let mut sweeper = Sweeper::<S, W> {
            change: 0.0,
            lane_change: [simd.splat_f32s(0.0); 2],
            cache: ([u32::MAX; W], None),
        };
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
                body.relax_slab::<S, W>(simd, st, &window, now, &mut sweeper);
            }
            if r > 0 {
                region[(r - 1) * slab..r * slab].copy_from_slice(buffers[1]);
            }
            buffers.swap(0, 1);
        }
        if let Some(last) = region.get_mut((m.max(1) - 1) * slab..) {
            last.copy_from_slice(buffers[1]);
        }
        let Sweeper { change, lane_change, .. } = sweeper;
        let lanes = simd.reduce_max_f32s(lane_change[0]).max(-simd.reduce_min_f32s(lane_change[1]));
        if lanes > change { lanes } else { change }
    }
}

impl Body {
    /// Computes the relaxed positions of the window's slab into `out` from the window's old
    /// positions. `change` gathers the generic elements' largest move, `lane_change` the vectors'.
    #[inline(always)]
    fn relax_slab<S: pulp::Simd, const W: usize>(
        &self,
        simd: S,
        st: &Stencil,
        window: &Window<'_>,
        out: &mut [[f32; 3]],
        sweeper: &mut Sweeper<S, W>,
    ) {
        let Sweeper { change, lane_change, cache: (consts_of, consts) } = sweeper;
        let [nx, ny, nz] = st.dims;
        let base = window.s * st.slab;
        let w = self.width;
        let classes = &self.classes;
        let pos_of = |j: usize| window.pos(j);
        let generic = |i: usize, out: &mut [[f32; 3]], change: &mut f32| {
            let (p, q) = (pos_of(i), self.relaxed_in(i, pos_of));
            *change = max_change(*change, p, q);
            out[i - base] = q;
        };
        // A row end through its gathered copy (the same arithmetic as `generic`).
        let edge = |i: usize, at: usize, out: &mut [[f32; 3]], change: &mut f32| {
            let p = pos_of(i);
            let q = match st.edges.get(at) {
                Some(e) if !e.fixed => {
                    relaxed_bounded(pos_of, p, e.rest, &e.nbr[..w], &e.class[..w], classes, |t, _| {
                        e.nbr_rest[t]
                    })
                    .0
                }
                _ => p,
            };
            *change = max_change(*change, p, q);
            out[i - base] = q;
        };
        let interior = |c: usize, len: usize| len < 2 || (c > 0 && c + 1 < len);
        // The row's constants by phase, rebuilt when the row's classes change; `None` where an axis's
        // two boxes are not one box shifted (then the row takes the generic path).
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
                    let first = row + x - base;
                    if !relax_run::<S, W>(simd, st, window, first..first + len, consts, run, lane_change) {
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

/// Relaxes the regular elements `elements` (at least `S::F32_LANES` of them) of the window's slab
/// into `out` (starting at the first one's place), three vectors at a time; the last three
/// are moved back to end with the run, overlapping their neighbours (computed twice, alike).
/// Returns `false`, with the run not (or not all) written, if a stream is missing.
#[inline(always)]
fn relax_run<S: pulp::Simd, const W: usize>(
    simd: S,
    st: &Stencil,
    window: &Window<'_>,
    elements: std::ops::Range<usize>,
    consts: &[PhaseConsts<S, W>; 3],
    out: &mut [[f32; 3]],
    lane_change: &mut [S::f32s; 2],
) -> bool {
    let (first, n, g) = (elements.start, 3 * elements.len(), 3 * S::F32_LANES);
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
