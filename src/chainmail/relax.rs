//! Elastic relaxation: moves free elements toward the rest offsets of their links, lowering the energy
//! `½ Σ k |(p_b - r_b) - (p_a - r_a)|²` sweep by sweep.
//!
//! Each sweep is a damped Jacobi update of the displacement field `u = p - rest`: every free element
//! goes a fraction [`OMEGA`] of the way to the stiffness-weighted mean displacement of its intact
//! neighbours, but no further than the ChainMail limits of its links allow (Gibson: relaxation adjusts
//! positions *within* the constraints, so a taut fibre stays taut). For a graph Laplacian a Jacobi step
//! scaled per coordinate by factors in `[0, 1]` never raises the energy when `OMEGA <= 1`; below 1 it
//! also cannot stall in the checkerboard mode of a bipartite grid.

use std::time::{Duration, Instant};

use super::body::{Body, FIXED, SlotClass};
use super::deform::Workspace;
use super::ids::ElementId;

/// Jacobi damping factor.
pub const OMEGA: f32 = 0.9;

/// How much relaxation a call may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelaxBudget {
    /// Most sweeps. Deterministic runs bound relaxation by sweeps only.
    pub max_sweeps: u32,
    /// Stop early when this much wall time has passed (interactive use; breaks bit-for-bit
    /// reproducibility, so headless runs leave it `None`).
    pub max_time: Option<Duration>,
    /// Stop early when no element moved more than this in a sweep (lattice units).
    pub tolerance: f32,
}

impl RelaxBudget {
    /// A budget of `n` sweeps, no time limit, no early stop.
    pub fn sweeps(n: u32) -> Self {
        Self { max_sweeps: n, max_time: None, tolerance: 0.0 }
    }
}

/// Where relaxation works.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RelaxRegion {
    /// Every free element.
    #[default]
    All,
    /// Only the elements moved by the last deformation (cheap, local).
    Moved,
}

/// What a relaxation call did.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct RelaxReport {
    /// Sweeps done.
    pub sweeps: u32,
    /// Largest move of any element in the last sweep.
    pub last_change: f32,
    /// Stopped because the last change fell below the tolerance.
    pub converged: bool,
}

impl Body {
    /// Relaxes the body within `budget`. Pinned and held elements stay where they are.
    pub fn relax(&mut self, ws: &mut Workspace, budget: RelaxBudget, region: RelaxRegion) -> RelaxReport {
        self.within_budget(ws, budget, |body, ws| match region {
            RelaxRegion::All => body.sweep_all(ws),
            RelaxRegion::Moved => body.sweep_moved(ws),
        })
    }

    /// Runs `sweep` (which returns the largest move of the sweep) until the budget is spent or the
    /// moves fall to the tolerance.
    fn within_budget(
        &mut self,
        ws: &mut Workspace,
        budget: RelaxBudget,
        mut sweep: impl FnMut(&mut Body, &mut Workspace) -> f32,
    ) -> RelaxReport {
        ws.fit(self);
        let started = budget.max_time.map(|_| Instant::now());
        let mut report = RelaxReport::default();
        while report.sweeps < budget.max_sweeps {
            let change = sweep(self, ws);
            report.sweeps += 1;
            report.last_change = change;
            if change <= budget.tolerance {
                report.converged = true;
                break;
            }
            if let (Some(t0), Some(limit)) = (started, budget.max_time)
                && t0.elapsed() >= limit
            {
                break;
            }
        }
        report
    }

    /// The relaxed position of element `i`: where it is if pinned or held, else [`Body::relaxed_in`]
    /// over the body's positions.
    #[inline(always)]
    pub(crate) fn relaxed_unless_fixed(&self, i: usize) -> [f32; 3] {
        self.relaxed_in(i, |j| self.pos[j])
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
        let p = pos_of(i);
        if self.flags[i] & FIXED != 0 {
            return p;
        }
        let (w, rest) = (self.width, &self.lattice.rest);
        let row = i * w..(i + 1) * w;
        relaxed_with(
            pos_of,
            p,
            rest[i],
            &self.slot_nbr[row.clone()],
            &self.slot_class[row],
            &self.classes,
            |_, j| rest[j],
        )
    }

    fn sweep_all(&mut self, ws: &mut Workspace) -> f32 {
        // Grids take the stencil path: in place, in vectors, in bands on the pool's threads; the same
        // result up to rounding (regular elements skip the rest positions, whose offsets cancel).
        if let Some(change) = self.sweep_stencil(&mut ws.next) {
            return change;
        }
        // Constant widths let the row loop unroll: 4 on sheets, 6 in volumes.
        match self.width {
            4 => self.sweep_all_width(ws, 4),
            6 => self.sweep_all_width(ws, 6),
            w => self.sweep_all_width(ws, w),
        }
    }

    /// One Jacobi sweep over every element, streaming through the rows of the fixed-width adjacency.
    #[inline(always)]
    fn sweep_all_width(&mut self, ws: &mut Workspace, width: usize) -> f32 {
        let mut change = 0.0f32;
        let (pos, rest) = (&self.pos[..], &self.lattice.rest[..]);
        let rows = self.slot_nbr.chunks_exact(width).zip(self.slot_class.chunks_exact(width));
        let elements = pos.iter().zip(rest).zip(&self.flags).zip(&mut ws.next[..]);
        let classes = &self.classes[..];
        for ((nbrs, slot_class), (((&p, &r), &flags), next)) in rows.zip(elements) {
            let q =
                if flags & FIXED != 0 { p } else { relaxed_row(pos, rest, p, r, nbrs, classes, slot_class) };
            change = max_change(change, p, q);
            *next = q;
        }
        std::mem::swap(&mut self.pos, &mut ws.next);
        change
    }

    /// Relaxes only the listed elements within `budget` (the rest of the body holds still). Used to
    /// relax the region an instrument has disturbed, which may span several deformations.
    pub fn relax_elements(
        &mut self,
        ws: &mut Workspace,
        budget: RelaxBudget,
        elements: &[ElementId],
    ) -> RelaxReport {
        self.within_budget(ws, budget, |body, ws| {
            let mut change = 0.0f32;
            for &e in elements {
                let i = e.index();
                if i >= body.pos.len() {
                    continue;
                }
                let p = body.pos[i];
                let q = body.relaxed_unless_fixed(i);
                change = max_change(change, p, q);
                ws.next[i] = q;
            }
            for &e in elements {
                if let Some(q) = ws.next.get(e.index()) {
                    body.pos[e.index()] = *q;
                }
            }
            change
        })
    }

    fn sweep_moved(&mut self, ws: &mut Workspace) -> f32 {
        let mut change = 0.0f32;
        for &i in &ws.moved {
            let i = i as usize;
            let p = self.pos[i];
            let q = self.relaxed_unless_fixed(i);
            change = max_change(change, p, q);
            ws.next[i] = q;
        }
        for &i in &ws.moved {
            self.pos[i as usize] = ws.next[i as usize];
        }
        change
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
fn relaxed_row(
    pos: &[[f32; 3]],
    rest: &[[f32; 3]],
    p: [f32; 3],
    r: [f32; 3],
    nbrs: &[u32],
    classes: &[SlotClass],
    slot_class: &[u32],
) -> [f32; 3] {
    let rest = &rest[..pos.len()];
    relaxed_with(|j| pos[j], p, r, nbrs, slot_class, classes, |_, j| rest[j])
}

/// [`relaxed_row`] with the neighbours' positions given by `pos_of(neighbour)` and their rest
/// positions by `rest_of(slot, neighbour)`.
#[inline(always)]
pub(crate) fn relaxed_with(
    pos_of: impl Fn(usize) -> [f32; 3],
    p: [f32; 3],
    r: [f32; 3],
    nbrs: &[u32],
    slot_class: &[u32],
    classes: &[SlotClass],
    rest_of: impl Fn(usize, usize) -> [f32; 3],
) -> [f32; 3] {
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
        return p;
    }
    let inv = OMEGA / wsum;
    let mut q = p;
    for c in 0..3 {
        let target = p[c] + (acc[c] * inv - OMEGA * (p[c] - r[c]));
        // Never leave the boxes further than the element already is; never step backwards.
        let floor = if lo[c] < p[c] { lo[c] } else { p[c] };
        let ceil = if hi[c] > p[c] { hi[c] } else { p[c] };
        let t = if target > floor { target } else { floor };
        let t = if t < ceil { t } else { ceil };
        // No subnormal coordinates (see `stencil::FLUSH`).
        q[c] = (t + super::stencil::FLUSH) - super::stencil::FLUSH;
    }
    q
}
