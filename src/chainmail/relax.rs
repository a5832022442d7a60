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

use super::body::{Body, FIXED};
use super::deform::Workspace;
use super::ids::ElementId;
use super::lattice::SIDE_B;

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
        ws.fit(self);
        let started = budget.max_time.map(|_| Instant::now());
        let mut report = RelaxReport::default();
        while report.sweeps < budget.max_sweeps {
            let change = match region {
                RelaxRegion::All => self.sweep_all(ws),
                RelaxRegion::Moved => self.sweep_moved(ws),
            };
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

    /// The relaxed position of element `i` (assumed free): a damped Jacobi step toward the weighted mean
    /// displacement of its neighbours, shortened per coordinate where it would leave the constraint boxes
    /// of its intact links (the box of each link taken at the neighbour's current position). A step is
    /// only ever shortened, never reversed, so the energy still cannot rise (each coordinate's step is
    /// the Jacobi step scaled by a factor in `[0, 1]`, and `ω ≤ 1`).
    #[inline(always)]
    fn relaxed(&self, i: usize) -> [f32; 3] {
        let lat = &self.lattice;
        let (s0, s1) = (lat.adj_start[i] as usize, lat.adj_start[i + 1] as usize);
        let mut acc = [0.0f32; 3];
        let mut wsum = 0.0f32;
        let mut lo = [f32::NEG_INFINITY; 3];
        let mut hi = [f32::INFINITY; 3];
        for k in s0..s1 {
            let w = self.adj_w[k];
            if w == 0.0 {
                continue;
            }
            let j = lat.adj_nbr[k] as usize;
            let link = lat.adj_link[k];
            let (p, r) = (self.pos[j], lat.rest[j]);
            let [blo, bhi] = self.link_box[(link & !SIDE_B) as usize];
            for c in 0..3 {
                acc[c] += w * (p[c] - r[c]);
                // `i` is the link's `b` end when the entry sits in `b`'s list.
                let (l, h) = if link & SIDE_B != 0 {
                    (p[c] + blo[c], p[c] + bhi[c])
                } else {
                    (p[c] - bhi[c], p[c] - blo[c])
                };
                lo[c] = lo[c].max(l);
                hi[c] = hi[c].min(h);
            }
            wsum += w;
        }
        let p = self.pos[i];
        if wsum <= 0.0 {
            return p;
        }
        let r = lat.rest[i];
        let inv = OMEGA / wsum;
        let mut q = p;
        for c in 0..3 {
            let target = p[c] + (acc[c] * inv - OMEGA * (p[c] - r[c]));
            // Never leave the boxes further than the element already is; never step backwards.
            q[c] = target.max(lo[c].min(p[c])).min(hi[c].max(p[c]));
        }
        q
    }

    fn sweep_all(&mut self, ws: &mut Workspace) -> f32 {
        let mut change = 0.0f32;
        for i in 0..self.pos.len() {
            let p = self.pos[i];
            let q = if self.flags[i] & FIXED != 0 { p } else { self.relaxed(i) };
            change = change.max((q[0] - p[0]).abs()).max((q[1] - p[1]).abs()).max((q[2] - p[2]).abs());
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
        ws.fit(self);
        let started = budget.max_time.map(|_| Instant::now());
        let mut report = RelaxReport::default();
        while report.sweeps < budget.max_sweeps {
            let mut change = 0.0f32;
            for &e in elements {
                let i = e.index();
                if i >= self.pos.len() {
                    continue;
                }
                let p = self.pos[i];
                let q = if self.flags[i] & FIXED != 0 { p } else { self.relaxed(i) };
                change = change.max((q[0] - p[0]).abs()).max((q[1] - p[1]).abs()).max((q[2] - p[2]).abs());
                ws.next[i] = q;
            }
            for &e in elements {
                if let Some(q) = ws.next.get(e.index()) {
                    self.pos[e.index()] = *q;
                }
            }
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

    fn sweep_moved(&mut self, ws: &mut Workspace) -> f32 {
        let mut change = 0.0f32;
        for &i in &ws.moved {
            let i = i as usize;
            let p = self.pos[i];
            let q = if self.flags[i] & FIXED != 0 { p } else { self.relaxed(i) };
            change = change.max((q[0] - p[0]).abs()).max((q[1] - p[1]).abs()).max((q[2] - p[2]).abs());
            ws.next[i] = q;
        }
        for &i in &ws.moved {
            self.pos[i as usize] = ws.next[i as usize];
        }
        change
    }
}
