//! Elastic relaxation: moves free elements toward the rest offsets of their links, lowering the energy
//! `½ Σ k |(p_b - r_b) - (p_a - r_a)|²` sweep by sweep.
//!
//! Each sweep is a damped Jacobi update of the displacement field `u = p - rest`: every free element
//! goes a fraction ω (`OMEGA`, 0.9) of the way to the stiffness-weighted mean displacement of its intact
//! neighbours, but no further than the ChainMail limits of its links allow (Gibson: relaxation adjusts
//! positions *within* the constraints, so a taut fibre stays taut). For a graph Laplacian a Jacobi step
//! scaled per coordinate by factors in `[0, 1]` never raises the energy when `OMEGA <= 1`; below 1 it
//! also cannot stall in the checkerboard mode of a bipartite grid.

use std::time::Duration;

use web_time::Instant;

use super::body::{Body, FIXED};
use super::ids::ElementId;
use super::workspace::Workspace;
pub use coarse::Coarse;
pub(crate) use elastic::Elastic;
use kernel::{max_change, relaxed_row};

mod bands;
mod coarse;
mod elastic;
mod grid;
mod kernel;
mod region;

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
        self.refresh_elastic();
        if self.has_elastic() {
            // Elastic cells relax in place (Gauss-Seidel, each element's move lowering the energy).
            return self.within_budget(ws, budget, |body, ws| match region {
                RelaxRegion::All => body.sweep_in_place(0..body.pos.len()),
                RelaxRegion::Moved => {
                    let moved = std::mem::take(&mut ws.moved);
                    let change = body.sweep_in_place(moved.iter().map(|&i| i as usize));
                    ws.moved = moved;
                    change
                }
            });
        }
        self.within_budget(ws, budget, |body, ws| match region {
            RelaxRegion::All => body.sweep_all(ws),
            RelaxRegion::Moved => body.sweep_moved(ws),
        })
    }

    /// One in-place sweep over `elements` (each moved with the moves before it made): the sweep of a
    /// body with elastic cells.
    fn sweep_in_place(&mut self, elements: impl Iterator<Item = usize>) -> f32 {
        let mut change = 0.0f32;
        for i in elements {
            if i >= self.pos.len() {
                continue;
            }
            let p = self.pos[i];
            let q = self.relaxed_unless_fixed(i);
            change = max_change(change, p, q);
            self.pos[i] = q;
        }
        change
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
        let report = sweeps_within(budget, || sweep(self, ws));
        if report.sweeps > 0 {
            self.note_motion();
        }
        report
    }

    fn sweep_all(&mut self, ws: &mut Workspace) -> f32 {
        // Grids take the stencil path: in place, in vectors, in bands on the pool's threads; the same
        // result up to rounding (regular elements skip the rest positions, whose offsets cancel).
        // (Normal pairs bound more than the links: the plain element update keeps them.)
        if self.pairs.any() {
            return self.sweep_all_elements(ws);
        }
        if let Some(change) = self.sweep_grid(ws) {
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

    /// One Jacobi sweep over every element with the plain element update (pairs included).
    fn sweep_all_elements(&mut self, ws: &mut Workspace) -> f32 {
        let mut change = 0.0f32;
        for i in 0..self.pos.len() {
            let (p, q) = (self.pos[i], self.relaxed_unless_fixed(i));
            change = max_change(change, p, q);
            ws.next[i] = q;
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
        self.refresh_elastic();
        if self.has_elastic() {
            return self.within_budget(ws, budget, |body, _| {
                body.sweep_in_place(elements.iter().map(|e| e.index()))
            });
        }
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

/// Runs `sweep` (which returns the largest move of the sweep) until `budget` is spent or the moves
/// fall to its tolerance: the one budget loop of every relaxation (the whole body's and a disturbed
/// region's).
pub(crate) fn sweeps_within(budget: RelaxBudget, mut sweep: impl FnMut() -> f32) -> RelaxReport {
    let started = budget.max_time.map(|_| Instant::now());
    let mut report = RelaxReport::default();
    while report.sweeps < budget.max_sweeps {
        let change = sweep();
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
