//! The chain reaction: one element is moved, its neighbours follow only as far as their links demand.
//!
//! This file holds the API (a deformation, with bisection when a pinned or held element blocks it)
//! and the one-by-one reaction over Gibson's per-direction candidate lists; `runs.rs` moves runs of
//! a list across rows a chunk at a time (`chunk.rs` portable, `vector.rs` with AVX-512 or AVX2
//! registers, `lanes.rs`), all on the arrays and checks of `arrays.rs`.

use super::body::{Body, FIXED, PINNED};
use super::coords::{norm, sub};
use super::error::{ChainMailError, finite};
use super::ids::ElementId;
use super::lattice::{Lattice, SIDE_B};
use super::workspace::Workspace;
use arrays::{Moving, Patterns, Run, Slices, candidate_box, clamp_masked};
use runs::{Wide, batch};

mod arrays;
mod chunk;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod runs;
#[cfg(target_arch = "x86_64")]
mod vector;

/// Which coordinates a deformation constrains and moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Pass {
    /// All three coordinates: Gibson's 3D ChainMail.
    #[default]
    All,
    /// The first two coordinates only: SurfaceChainMail's pass in the (u, v) plane.
    Plane,
    /// The third coordinate only: SurfaceChainMail's pass along the surface normal.
    Normal,
}

impl Pass {
    const fn mask(self) -> [bool; 3] {
        match self {
            Pass::All => [true; 3],
            Pass::Plane => [true, true, false],
            Pass::Normal => [false, false, true],
        }
    }
}

/// How many times a blocked deformation is halved while searching for the largest one allowed.
const BISECT_STEPS: u32 = 20;

/// What a deformation did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deformation {
    /// Where the source element was asked to go.
    pub requested: [f32; 3],
    /// Where it went: `requested` unless pinned elements stopped it short.
    pub achieved: [f32; 3],
    /// Share of the requested displacement that was achieved, in `[0, 1]`.
    pub fraction: f32,
    /// Elements moved, the source included.
    pub moved: u32,
    /// Chain reactions tried (1 when nothing blocked).
    pub attempts: u32,
}

impl Body {
    /// Moves element `source` towards `target` (lattice coordinates) and lets the chain reaction
    /// carry its neighbours. If the move would have to displace a pinned or held element, it is rolled
    /// back and the largest permissible fraction is found by bisection; the result says how far the
    /// source really went. Every element moves at most once.
    pub fn deform(
        &mut self,
        ws: &mut Workspace,
        source: ElementId,
        target: [f32; 3],
        pass: Pass,
    ) -> Result<Deformation, ChainMailError> {
        self.check_element(source)?;
        for &x in &target {
            finite("deformation target", x)?;
        }
        ws.fit(self);
        let start = self.pos[source.index()];
        let mask = pass.mask();
        let mut goal = start;
        for k in 0..3 {
            if mask[k] {
                goal[k] = target[k];
            }
        }
        let mut result =
            Deformation { requested: goal, achieved: start, fraction: 0.0, moved: 0, attempts: 0 };
        if self.flags[source.index()] & PINNED != 0 || goal == start {
            ws.next_generation();
            return Ok(result);
        }
        let at = |t: f32| -> [f32; 3] {
            if t >= 1.0 { goal } else { [0, 1, 2].map(|k| start[k] + t * (goal[k] - start[k])) }
        };
        result.attempts = 1;
        if self.chain_reaction(ws, source.index(), goal, mask) {
            result.achieved = goal;
            result.fraction = 1.0;
            result.moved = ws.moved.len() as u32;
            return Ok(result);
        }
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..BISECT_STEPS {
            let mid = 0.5 * (lo + hi);
            result.attempts += 1;
            if self.chain_reaction(ws, source.index(), at(mid), mask) {
                lo = mid;
                ws.rollback(&mut self.pos);
            } else {
                hi = mid;
            }
        }
        if lo > 0.0 {
            result.attempts += 1;
            if self.chain_reaction(ws, source.index(), at(lo), mask) {
                result.achieved = at(lo);
                result.fraction = lo;
                result.moved = ws.moved.len() as u32;
                return Ok(result);
            }
        }
        ws.next_generation();
        Ok(result)
    }

    /// One chain reaction with the source moved to `goal`. On success the moves stay (recorded in the
    /// workspace); when a fixed element would have to move, everything is rolled back and `false`
    /// returned.
    fn chain_reaction(&mut self, ws: &mut Workspace, source: usize, goal: [f32; 3], mask: [bool; 3]) -> bool {
        // Compiled for the widest vectors the workspace's level and the machine allow (pulp picks at
        // run time): the runs' portable checks are written as plain loops over lanes and vectorise.
        let arch = ws.simd().arch();
        match mask {
            [true, true, true] => arch.dispatch(Reaction::<0b111> { body: self, ws, source, goal }),
            [true, true, false] => arch.dispatch(Reaction::<0b011> { body: self, ws, source, goal }),
            [false, false, true] => arch.dispatch(Reaction::<0b100> { body: self, ws, source, goal }),
            _ => unreachable!("Pass::mask gives one of three masks"),
        }
    }
    /// The chain reaction for a constant coordinate mask (bit `k` set: coordinate `k` is constrained
    /// and moved).
    ///
    /// Gibson's order: one candidate list per direction (adjacency slot `t`; on grids x-, x+, y-, y+,
    /// z-, z+), processed in turn, each until it is empty, and round again until all are. A moved
    /// element enters the list of each direction whose neighbour has not moved yet (padding slots
    /// point at the element itself, which has); when list `t` reaches it, its neighbour through slot
    /// `t` is checked against it (both positions are final by then: the sponsor has moved, the
    /// candidate has not). The walk runs along grid rows, so memory is read in order, and the moves,
    /// their order and their sponsors are those of per-direction FIFO lists of
    /// `(candidate, link, sponsor)` entries.
    #[inline(always)]
    fn chain_reaction_in<const MASK: u8>(
        &mut self,
        ws: &mut Workspace,
        source: usize,
        goal: [f32; 3],
        wide: Wide,
    ) -> bool {
        // Constant widths let the row loop unroll: 4 on sheets, 6 in volumes.
        match self.width {
            4 => self.chain_reaction_rows::<MASK>(ws, source, goal, [&mut [0; 4], &mut [0; 4]], wide),
            6 => self.chain_reaction_rows::<MASK>(ws, source, goal, [&mut [0; 6], &mut [0; 6]], wide),
            w => {
                let mut ends = std::mem::take(&mut ws.list_ends);
                ends.resize(2 * w, 0);
                let (heads, tails) = ends.split_at_mut(w);
                let done = self.chain_reaction_rows::<MASK>(ws, source, goal, [heads, tails], wide);
                ws.list_ends = ends;
                done
            }
        }
    }

    /// [`Body::chain_reaction_in`] with the lists' heads and tails (one per slot: the body's width).
    #[inline(always)]
    fn chain_reaction_rows<const MASK: u8>(
        &mut self,
        ws: &mut Workspace,
        source: usize,
        goal: [f32; 3],
        [head, tail]: [&mut [usize]; 2],
        wide: Wide,
    ) -> bool {
        ws.next_generation();
        let width = self.width;
        let n = self.pos.len();
        // Every per-element slice cut to exactly `n`, so one bounds check on an index serves them all.
        let (nbrs, classes, slot_class, flags) =
            (&self.slot_nbr[..n * width], &self.classes[..], &self.slot_class[..n * width], &self.flags[..n]);
        // Interior grid elements find their neighbours by offset (`Slices::neighbour`).
        let (offs, interior, across): (&[isize], &[u8], &[u8]) = match &ws.stencil {
            Some(st) if st.interior.len() == n && st.across.len() == n => {
                (&st.offs, &st.interior[..n], &st.across[..n])
            }
            _ => (&[], &[], &[]),
        };
        let (class_change, class_words) = (&self.class_change[..], self.class_words);
        let b = Slices {
            nbrs,
            classes,
            slot_class,
            class_change,
            class_words,
            flags,
            interior,
            across,
            offs,
            width,
        };
        let (head, tail) = (&mut head[..width], &mut tail[..width]);
        head.fill(0);
        let mut m = Moving {
            pos: &mut self.pos[..n],
            old: &mut ws.old[..n],
            stamp: &mut ws.stamp[..n],
            sponsor: &mut ws.sponsor[..n],
            moved: &mut ws.moved,
            lists: &mut ws.lists[..n * width],
            tail,
            g: ws.generation,
        };
        m.record(source, goal, source);
        for t in 0..width {
            m.lists[t * n] = source as u32;
            m.tail[t] = 1;
        }

        let mut patterns = Patterns::default();
        let mut blocked = false;
        'reaction: loop {
            let mut progressed = false;
            for t in 0..width {
                let list = t * n;
                // Lists across rows (y and z on grids) hold runs of consecutive sponsors (up or down
                // a row) whose candidates are consecutive too and independent of each other: such a
                // run is moved as one (see `runs.rs`), with the same moves, order and sponsors.
                let across = offs.get(t).filter(|o| o.unsigned_abs() > 1).copied();
                while head[t] < m.tail[t] {
                    progressed = true;
                    if let Some(o) = across {
                        let run = Run { list, head: head[t], end: m.tail[t], t, o };
                        let done = batch::<MASK>(&run, b, &mut m, &mut patterns, wide);
                        if done > 0 {
                            head[t] += done;
                            continue;
                        }
                    }
                    let s = m.lists[list + head[t]] as usize;
                    head[t] += 1;
                    let c = b.neighbour(s, t);
                    // Stamped: moved already (padding slots point at `s` itself).
                    if m.stamp[c] == m.g {
                        continue;
                    }
                    // A broken link's box is infinite and never moves `c`.
                    let ps = m.pos[s];
                    let [lo, hi] = candidate_box(ps, classes[slot_class[s * width + t] as usize].bounds);
                    let pc = m.pos[c];
                    let q = clamp_masked::<MASK>(pc, lo, hi);
                    if q == pc {
                        continue;
                    }
                    if flags[c] & FIXED != 0 {
                        let (lattice, link_box) = (&self.lattice, &self.link_box[..]);
                        if fixed_blocks::<MASK>(lattice, link_box, [s, t, c], [m.old[s], ps, pc, q]) {
                            blocked = true;
                            break 'reaction;
                        }
                        continue;
                    }
                    m.record(c, q, s);
                    // Gibson: sponsor only neighbours that have not moved (the sponsor among them).
                    for u in 0..width {
                        if !m.has_moved(b.neighbour(c, u)) {
                            m.push(u, c);
                        }
                    }
                }
            }
            if !progressed {
                break;
            }
        }
        if blocked {
            ws.rollback(&mut self.pos);
            return false;
        }
        true
    }
}

/// One chain reaction, as an operation for [`pulp::Arch::dispatch`].
struct Reaction<'a, const MASK: u8> {
    body: &'a mut Body,
    ws: &'a mut Workspace,
    source: usize,
    goal: [f32; 3],
}

impl<const MASK: u8> pulp::WithSimd for Reaction<'_, MASK> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> bool {
        let wide = Wide::of(self.ws.simd());
        self.body.chain_reaction_in::<MASK>(self.ws, self.source, self.goal, wide)
    }
}

/// Whether moving fixed element `c` to `q` (from `pc`), as demanded by its sponsor `s` (which moved
/// from `po` to `ps`) through the link of `s`'s adjacency entry `t`, would make that link worse than
/// it was before this deformation (relaxation can leave links slightly outside their boxes).
#[cold]
#[inline(never)]
fn fixed_blocks<const MASK: u8>(
    lattice: &Lattice,
    link_box: &[[[f32; 3]; 2]],
    [s, t, c]: [usize; 3],
    [po, ps, pc, q]: [[f32; 3]; 4],
) -> bool {
    let link = lattice.adj_link[lattice.adj_start[s] as usize + t];
    debug_assert_eq!(lattice.adj_nbr[lattice.adj_start[s] as usize + t] as usize, c);
    let [lo, hi] = link_box[(link & !SIDE_B) as usize];
    // The sponsor is the link's `a` end unless the entry was taken from `b`'s list.
    let (blo, bhi) = if link & SIDE_B == 0 {
        ([ps[0] + lo[0], ps[1] + lo[1], ps[2] + lo[2]], [ps[0] + hi[0], ps[1] + hi[1], ps[2] + hi[2]])
    } else {
        ([ps[0] - hi[0], ps[1] - hi[1], ps[2] - hi[2]], [ps[0] - lo[0], ps[1] - lo[1], ps[2] - lo[2]])
    };
    let shift = [po[0] - ps[0], po[1] - ps[1], po[2] - ps[2]];
    let before = clamp_masked::<MASK>(
        pc,
        [blo[0] + shift[0], blo[1] + shift[1], blo[2] + shift[2]],
        [bhi[0] + shift[0], bhi[1] + shift[1], bhi[2] + shift[2]],
    );
    let scale = (hi[0] - lo[0]).abs().max((hi[1] - lo[1]).abs()).max((hi[2] - lo[2]).abs())
        + (lo[0].abs() + lo[1].abs() + lo[2].abs());
    let tol = 1e-5 * scale;
    norm(sub(q, pc)) > norm(sub(before, pc)) + tol
}
