//! The plain relaxation kernel: one element's damped Jacobi step, shortened to the boxes of its
//! links. Every sweep runs it (the generic sweeps for every element, the grid sweep for the elements
//! its vectors leave), and the grid sweep's vectors are checked against it.

use crate::chainmail::body::{Body, FIXED, SlotClass};
use crate::chainmail::coords::clamp;

/// Jacobi damping factor.
pub const OMEGA: f32 = 0.9;

/// Added to and taken from every relaxed coordinate: values under `2^-84` become 0 and values
/// under `2^-36` are rounded to multiples of `2^-83`, so that no coordinate is subnormal; larger
/// values are unchanged (the sum rounds back to them exactly).
pub(crate) const FLUSH: f32 = 8.673617e-19; // 2^-60

impl Body {
    /// The relaxed position of element `i`: where it is if pinned or held, else [`Body::relaxed_in`]
    /// over the body's positions.
    #[inline(always)]
    pub(crate) fn relaxed_unless_fixed(&self, i: usize) -> [f32; 3] {
        self.relaxed_in(i, |j| self.pos[j])
    }

    /// [`Body::relaxed_unless_fixed`], then moved into the intersection of element `i`'s link boxes
    /// around its neighbours' current positions, coordinate by coordinate, where that intersection
    /// is not empty (one pass over the links for both: the in-place sweep of a disturbed region).
    #[inline]
    pub(crate) fn relaxed_into_boxes(&self, i: usize) -> [f32; 3] {
        let Some((q, lo, hi)) = self.relaxed_bounded_in(i, |j| self.pos[j]) else { return self.pos[i] };
        let q = self.relaxed_elastic(i, self.pos[i], lo, hi, |j| self.pos[j]).unwrap_or(q);
        let mut out = q;
        for c in 0..3 {
            if lo[c] <= hi[c] {
                out[c] = out[c].clamp(lo[c], hi[c]);
            }
        }
        out
    }

    /// The relaxed position of element `i`, positions read through `pos_of` (a sweep working in place
    /// reads its neighbours' old positions from where it keeps them). Pinned and held elements stay
    /// where they are. A free one takes a damped Jacobi step toward the weighted mean displacement of
    /// its neighbours, shortened per coordinate where it would leave the constraint boxes of its
    /// intact links (the box of each link taken at the neighbour's current position). A step is only
    /// ever shortened, never reversed, so the energy still cannot rise (each coordinate's step is the
    /// Jacobi step scaled by a factor in `[0, 1]`, and `ω ≤ 1`).
    #[inline(always)]
    pub(crate) fn relaxed_in(&self, i: usize, pos_of: impl Fn(usize) -> [f32; 3]) -> [f32; 3] {
        match self.relaxed_bounded_in(i, &pos_of) {
            Some((q, lo, hi)) => self.relaxed_elastic(i, pos_of(i), lo, hi, &pos_of).unwrap_or(q),
            None => pos_of(i),
        }
    }

    /// [`Body::relaxed_in`] with the intersection of the element's link boxes; `None` for a fixed
    /// element.
    #[inline(always)]
    pub(super) fn relaxed_bounded_in(
        &self,
        i: usize,
        pos_of: impl Fn(usize) -> [f32; 3],
    ) -> Option<([f32; 3], [f32; 3], [f32; 3])> {
        if self.flags[i] & FIXED != 0 {
            return None;
        }
        let p = pos_of(i);
        let (w, rest) = (self.width, &self.lattice.rest);
        let row = i * w..(i + 1) * w;
        let (q, mut lo, mut hi) = relaxed_bounded(
            &pos_of,
            p,
            rest[i],
            &self.slot_nbr[row.clone()],
            &self.slot_class[row],
            &self.classes,
            |_, j| rest[j],
        );
        if !self.pairs.any() {
            return Some((q, lo, hi));
        }
        // Normal pairs bound the normal coordinate too: the intersection with theirs, and the step
        // shortened to it as to the links' (never further out than the element is, never backwards).
        for (j, [blo, bhi]) in self.pairs.row(i) {
            let z = pos_of(j as usize)[2];
            lo[2] = lo[2].max(z + blo);
            hi[2] = hi[2].min(z + bhi);
        }
        let mut q = q;
        let floor = if lo[2] < p[2] { lo[2] } else { p[2] };
        let ceil = if hi[2] > p[2] { hi[2] } else { p[2] };
        q[2] = clamp(q[2], floor, ceil);
        Some((q, lo, hi))
    }
}

/// `change` raised to the largest coordinate move from `p` to `q` (all finite).
#[inline(always)]
pub(crate) fn max_change(change: f32, p: [f32; 3], q: [f32; 3]) -> f32 {
    let mut m = change;
    for c in 0..3 {
        let d = (q[c] - p[c]).abs();
        m = if d > m { d } else { m };
    }
    m
}

/// The relaxed position of an element at `p` (rest `r`) whose adjacency row is `nbrs` and
/// `slot_class` (boxes on `p[owner] - p[nbr]` and weights in `classes`). Broken links and padding
/// slots have weight 0 and an infinite box: they add exactly nothing (the sums start at +0, so adding
/// ±0 leaves them bit for bit).
#[inline(always)]
pub(super) fn relaxed_row(
    pos: &[[f32; 3]],
    rest: &[[f32; 3]],
    p: [f32; 3],
    r: [f32; 3],
    nbrs: &[u32],
    classes: &[SlotClass],
    slot_class: &[u32],
) -> [f32; 3] {
    let rest = &rest[..pos.len()];
    relaxed_bounded(|j| pos[j], p, r, nbrs, slot_class, classes, |_, j| rest[j]).0
}

/// [`relaxed_row`] with the neighbours' positions given by `pos_of(neighbour)` and their rest
/// positions by `rest_of(slot, neighbour)`; also gives the intersection of the element's link boxes
/// (low and high corners, per coordinate; empty where low exceeds high).
#[inline(always)]
pub(crate) fn relaxed_bounded(
    pos_of: impl Fn(usize) -> [f32; 3],
    p: [f32; 3],
    r: [f32; 3],
    nbrs: &[u32],
    slot_class: &[u32],
    classes: &[SlotClass],
    rest_of: impl Fn(usize, usize) -> [f32; 3],
) -> ([f32; 3], [f32; 3], [f32; 3]) {
    let mut acc = [0.0f32; 3];
    let mut wsum = 0.0f32;
    let mut lo = [f32::NEG_INFINITY; 3];
    let mut hi = [f32::INFINITY; 3];
    for (t, (&j, &class)) in nbrs.iter().zip(slot_class).enumerate() {
        let SlotClass { bounds: [blo, bhi], w } = classes[class as usize];
        let j = j as usize;
        let (pj, rj) = (pos_of(j), rest_of(t, j));
        for c in 0..3 {
            acc[c] += w * (pj[c] - rj[c]);
            // The slot bounds `p[i] - p[j]`: `p[i]` must lie in `[pj + blo, pj + bhi]`.
            let (l, h) = (pj[c] + blo[c], pj[c] + bhi[c]);
            lo[c] = if l > lo[c] { l } else { lo[c] };
            hi[c] = if h < hi[c] { h } else { hi[c] };
        }
        wsum += w;
    }
    if wsum <= 0.0 {
        return (p, lo, hi);
    }
    let inv = OMEGA / wsum;
    let mut q = p;
    for c in 0..3 {
        let target = p[c] + (acc[c] * inv - OMEGA * (p[c] - r[c]));
        // Never leave the boxes further than the element already is; never step backwards.
        let floor = if lo[c] < p[c] { lo[c] } else { p[c] };
        let ceil = if hi[c] > p[c] { hi[c] } else { p[c] };
        let t = clamp(target, floor, ceil);
        // No subnormal coordinates (see `FLUSH`).
        q[c] = (t + FLUSH) - FLUSH;
    }
    (q, lo, hi)
}
