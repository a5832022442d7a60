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
use super::workspace::{SearchScratch, Workspace};
use arrays::{Moving, Patterns, Run, Slices, candidate_box, clamp_masked};
pub(crate) use lift::{Lift, has_bit};
use runs::{Wide, batch};

mod arrays;
mod chunk;
mod complete;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod lift;
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
    pub(crate) const fn mask(self) -> [bool; 3] {
        match self {
            Pass::All => [true; 3],
            Pass::Plane => [true, true, false],
            Pass::Normal => [false, false, true],
        }
    }
}

/// Most times a blocked deformation is halved while searching for the largest one allowed (the
/// search stops sooner once the interval is under [`BISECT_TOLERANCE`]).
const BISECT_STEPS: u32 = 20;

/// A bisection stops once the source's move is known to within this (lattice units: metres on
/// tissue; a tenth of a micrometre, far below what a trainee sees or an instrument feels).
pub(crate) const BISECT_TOLERANCE: f32 = 1e-7;

/// Most estimates tried from a blocked reaction's measured excess before bisecting.
const ESTIMATES: u32 = 3;

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

/// How a chain reaction ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outcome {
    /// Every element that had to move moved; the moves stay.
    Done,
    /// A fixed element would have had to move: everything was rolled back. When the reaction was
    /// run to the end to measure it, `excess` is the most any fixed element would have had to move,
    /// per coordinate (else zeros).
    Blocked { excess: [f32; 3] },
}

impl Body {
    /// Moves element `source` towards `target` (lattice coordinates) and lets the chain reaction
    /// carry its neighbours. If the move would have to displace a pinned or held element, it is rolled
    /// back and the largest permissible fraction is found (see [`Body::deform_group`]); the result
    /// says how far the source really went. Every element moves at most once.
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
        let start = self.pos[source.index()];
        let mask = pass.mask();
        let mut goal = start;
        for k in 0..3 {
            if mask[k] {
                goal[k] = target[k];
            }
        }
        let result = self.deform_seeds(ws, &[source.0], &[goal], mask);
        Ok(result)
    }

    /// Moves every element of `sources` to its goal in `goals` (lattice coordinates, the coordinates
    /// `pass` leaves alone ignored) in one chain reaction started from all of them at once, so that
    /// they never block one another (the rest of a forceps' jaws, once the centre has moved). Pinned
    /// sources stay. Gibson's order keeps a chain reaction within every link's limits when it starts
    /// from one element; from several, an element reached from one source is not checked again
    /// against another, so use this for small moves (each source's within its links' slack).
    /// If a pinned or held element outside the group would have to move, the moves are shortened
    /// together, as [`Body::deform`] shortens one. The result is the first source's.
    pub fn deform_group(
        &mut self,
        ws: &mut Workspace,
        sources: &[ElementId],
        goals: &[[f32; 3]],
        pass: Pass,
    ) -> Result<Deformation, ChainMailError> {
        for &e in sources {
            self.check_element(e)?;
        }
        for g in goals {
            for &x in g {
                finite("deformation target", x)?;
            }
        }
        let mask = pass.mask();
        let mut seeds = std::mem::take(&mut ws.seeds);
        let mut full = std::mem::take(&mut ws.seed_full);
        seeds.clear();
        full.clear();
        for (e, g) in sources.iter().zip(goals) {
            let p = self.pos[e.index()];
            seeds.push(e.0);
            full.push([0, 1, 2].map(|k| if mask[k] { g[k] } else { p[k] }));
        }
        let result = self.deform_seeds(ws, &seeds, &full, mask);
        ws.seeds = seeds;
        ws.seed_full = full;
        Ok(result)
    }

    /// The search behind [`Body::deform`] and [`Body::deform_group`]: each seed's goal at the full
    /// move in `full` (masked already); a share `t` of the move takes each seed `t` of its way.
    fn deform_seeds(
        &mut self,
        ws: &mut Workspace,
        seeds: &[u32],
        full: &[[f32; 3]],
        mask: [bool; 3],
    ) -> Deformation {
        ws.fit(self);
        let mut scratch = std::mem::take(&mut ws.search);
        let result = self.search(ws, &mut scratch, seeds, full, mask);
        if result.fraction == 0.0 {
            ws.next_generation();
            ws.lift.stopped(&scratch.free);
        } else if mask == Pass::Normal.mask() {
            self.record_rigid(ws, &scratch.free, result.fraction >= 1.0);
        }
        if result.moved > 0 {
            self.note_motion();
        }
        ws.search = scratch;
        result
    }

    /// [`Body::deform_seeds`] with its scratch taken out of the workspace. A result with a share
    /// above 0 leaves its moves in place (recorded in the workspace).
    fn search(
        &mut self,
        ws: &mut Workspace,
        sc: &mut SearchScratch,
        seeds: &[u32],
        full: &[[f32; 3]],
        mask: [bool; 3],
    ) -> Deformation {
        let first = seeds.first().copied();
        let start = first.map_or([0.0; 3], |f| self.pos[f as usize]);
        let requested = full.first().copied().unwrap_or(start);
        let mut result = Deformation { requested, achieved: start, fraction: 0.0, moved: 0, attempts: 0 };
        // Pinned seeds cannot move, nor need seeds already at their goals.
        sc.free.clear();
        sc.starts.clear();
        sc.goals.clear();
        // The largest move of any seed, per coordinate (what a measured excess is set against).
        let mut delta = [0.0f32; 3];
        for (&s, g) in seeds.iter().zip(full) {
            let p = self.pos[s as usize];
            if self.flags[s as usize] & PINNED == 0 && *g != p {
                sc.free.push(s);
                sc.starts.push(p);
                sc.goals.push(*g);
                for k in 0..3 {
                    delta[k] = delta[k].max((g[k] - p[k]).abs());
                }
            }
        }
        let Some(first) = first.filter(|_| !sc.free.is_empty()) else { return result };
        let size = delta.iter().fold(0.0f32, |m, d| m.max(*d));
        // One chain reaction with the seeds a share `t` of their way (exactly the goals at the end).
        // A measured reaction stops once what it has measured already leaves no room for a move: the
        // search would then end with nothing moved however much more it measured (`Measure`).
        let mut attempt = |body: &mut Body, ws: &mut Workspace, t: f32, measure: bool| -> Outcome {
            let measure = measure.then_some(Measure { share: t, delta, size });
            if t >= 1.0 {
                return body.chain_reaction(ws, &sc.free, &sc.goals, mask, measure);
            }
            sc.at.clear();
            for (p, g) in sc.starts.iter().zip(&sc.goals) {
                sc.at.push([0, 1, 2].map(|c| p[c] + t * (g[c] - p[c])));
            }
            body.chain_reaction(ws, &sc.free, &sc.at, mask, measure)
        };
        // The share of the move at which the fixed elements of a blocked reaction would just stay.
        let estimate = |t: f32, excess: [f32; 3]| Measure { share: t, delta, size }.estimate(excess);
        let done = |mut result: Deformation, ws: &Workspace, t: f32, body: &Body| {
            result.achieved = body.pos[first as usize];
            result.fraction = t.min(1.0);
            result.moved = (ws.moved.len() + ws.lift.unlisted_count) as u32;
            result
        };
        result.attempts = 1;
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let mut next = match attempt(self, ws, 1.0, true) {
            Outcome::Done => return done(result, ws, 1.0, self),
            Outcome::Blocked { excess } => estimate(1.0, excess),
        };
        // Shortened by what the blocked reaction measured: usually exact after one try. No element
        // moves further than its sponsor, so shortening the move by some amount lowers what a fixed
        // element would have to move by at most as much: the estimate is the most the tissue can
        // allow, and when it leaves no room, there is none.
        for _ in 0..ESTIMATES {
            if next >= hi {
                break; // nothing measured to shorten by: bisect
            }
            // (`lo` is 0 here, as `Measure::leaves_no_room` assumes.)
            if (next - lo) * size <= BISECT_TOLERANCE {
                return result;
            }
            result.attempts += 1;
            match attempt(self, ws, next, true) {
                Outcome::Done => return done(result, ws, next, self),
                Outcome::Blocked { excess } => {
                    hi = next;
                    next = estimate(next, excess).min(hi);
                }
            }
        }
        // Bisection between the largest share known to work and the smallest known to block.
        for _ in 0..BISECT_STEPS {
            if (hi - lo) * size <= BISECT_TOLERANCE {
                break;
            }
            let mid = 0.5 * (lo + hi);
            result.attempts += 1;
            if attempt(self, ws, mid, false) == Outcome::Done {
                lo = mid;
                ws.rollback(&mut self.pos);
            } else {
                hi = mid;
            }
        }
        if lo > 0.0 {
            result.attempts += 1;
            if attempt(self, ws, lo, false) == Outcome::Done {
                return done(result, ws, lo, self);
            }
        }
        result
    }

    /// One chain reaction with the seeds moved to their goals. On success the moves stay (recorded in
    /// the workspace); when a fixed element would have to move, everything is rolled back. With
    /// `measure`, a blocked reaction runs to its end (the fixed elements stay) to measure how far they
    /// would have had to go; without, it stops at the first.
    fn chain_reaction(
        &mut self,
        ws: &mut Workspace,
        seeds: &[u32],
        goals: &[[f32; 3]],
        mask: [bool; 3],
        measure: Option<Measure>,
    ) -> Outcome {
        // Compiled for the widest vectors the workspace's level and the machine allow (pulp picks at
        // run time): the runs' portable checks are written as plain loops over lanes and vectorise.
        let arch = ws.simd().arch();
        let r = Seeds { seeds, goals, measure };
        match mask {
            [true, true, true] => arch.dispatch(Reaction::<0b111> { body: self, ws, r }),
            [true, true, false] => arch.dispatch(Reaction::<0b011> { body: self, ws, r }),
            [false, false, true] => arch.dispatch(Reaction::<0b100> { body: self, ws, r }),
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
    fn chain_reaction_in<const MASK: u8>(&mut self, ws: &mut Workspace, r: Seeds<'_>, wide: Wide) -> Outcome {
        // Constant widths let the row loop unroll: 4 on sheets, 5 on two layers joined by fibres, 6 in
        // volumes.
        match self.width {
            4 => self.chain_reaction_rows::<MASK>(ws, r, [&mut [0; 4], &mut [0; 4]], wide),
            5 => self.chain_reaction_rows::<MASK>(ws, r, [&mut [0; 5], &mut [0; 5]], wide),
            6 => self.chain_reaction_rows::<MASK>(ws, r, [&mut [0; 6], &mut [0; 6]], wide),
            w => {
                let mut ends = std::mem::take(&mut ws.list_ends);
                ends.resize(2 * w, 0);
                let (heads, tails) = ends.split_at_mut(w);
                let done = self.chain_reaction_rows::<MASK>(ws, r, [heads, tails], wide);
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
        r: Seeds<'_>,
        [head, tail]: [&mut [usize]; 2],
        wide: Wide,
    ) -> Outcome {
        ws.next_generation();
        let width = self.width;
        let n = self.pos.len();
        let (head, tail) = (&mut head[..width], &mut tail[..width]);
        head.fill(0);
        // Every seed moves first, sponsoring itself, and enters every list (in the seeds' order).
        let mut seeded = 0;
        {
            let mut m = Moving::of(&mut self.pos[..n], ws, width, &mut *tail);
            for (&s, &g) in r.seeds.iter().zip(r.goals) {
                let s = s as usize;
                if s >= n || m.has_moved(s) {
                    continue;
                }
                m.record(s, g, s);
                for t in 0..width {
                    m.lists[t * n + seeded] = s as u32;
                }
                seeded += 1;
            }
        }
        // The normal pass of a lift that went its whole way last time: its rigid elements rise with
        // the seeds before the lists run (`lift.rs`), so that the lists stop at them rather than carry
        // the seeds' rise through the taut tent element by element; their rim is checked by the
        // completion. Elsewhere (a search's unmeasured tries, a pull the pins stopped short last time)
        // the raise waits for the lists, which meet the fixed elements first.
        let raise_first =
            MASK == 0b100 && self.pairs.any() && r.measure.is_some() && ws.lift.raises_first(r.seeds);
        if raise_first {
            let class_z = self.class_z_table(ws);
            self.raise_rigid(ws, r.seeds, &class_z);
            ws.class_z = class_z;
        }
        // Every per-element slice cut to exactly `n`, so one bounds check on an index serves them all.
        let (nbrs, classes, slot_class, flags) =
            (&self.slot_nbr[..n * width], &self.classes[..], &self.slot_class[..n * width], &self.flags[..n]);
        // Interior grid elements find their neighbours by offset (`Slices::neighbour`). (The stencil
        // is taken out of the workspace while the lists run, and given back after them.)
        let stencil = ws.stencil.take();
        let (offs, interior, across): (&[isize], &[u8], &[u8]) = match &stencil {
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
        let mut m = Moving::of(&mut self.pos[..n], ws, width, tail);
        m.tail.fill(seeded);

        let mut patterns = Patterns::default();
        let mut blocked = false;
        let mut excess = [0.0f32; 3];
        'reaction: loop {
            let mut progressed = false;
            for t in 0..width {
                let list = t * n;
                // Lists across rows (y and z on grids) hold runs of consecutive sponsors (up or down
                // a row) whose candidates are consecutive too and independent of each other: such a
                // run is moved as one (see `runs.rs`), with the same moves, order and sponsors.
                let across = offs
                    .get(t)
                    .filter(|o| o.unsigned_abs() > 1)
                    .and_then(|&o| Some((o, arrays::onward(offs, o)?)));
                while head[t] < m.tail[t] {
                    progressed = true;
                    if let Some((o, onward)) = across {
                        let run = Run { list, head: head[t], end: m.tail[t], t, o, onward };
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
                        if let Some(x) =
                            fixed_blocks::<MASK>(lattice, link_box, [s, t, c], [m.old[s], ps, pc, q])
                        {
                            blocked = true;
                            let Some(measure) = r.measure else { break 'reaction };
                            for k in 0..3 {
                                excess[k] = excess[k].max(x[k]);
                            }
                            if measure.leaves_no_room(excess) {
                                break 'reaction;
                            }
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
        ws.stencil = stencil;
        // The normal pass of a body with normal pairs: the lists above kept each element within its
        // sponsor's link; the pairs (and the links the pairs' moves disturb) are met after them.
        if MASK == 0b100 && self.pairs.any() && (!blocked || r.measure.is_some()) {
            let done = self.complete_pairs(ws, (!raise_first).then_some(r.seeds), r.measure, &mut excess);
            blocked |= done.blocked;
            // A bound of a moved element left outside: the limits' repair hears of it.
            if !blocked {
                self.pairs.unmet = self.pairs.unmet.max(done.unmet);
            }
        }
        if blocked {
            ws.rollback(&mut self.pos);
            return Outcome::Blocked { excess };
        }
        Outcome::Done
    }
}

/// The seeds of one chain reaction: the elements moved first and their goals; whether a blocked
/// reaction runs on to be measured.
#[derive(Clone, Copy)]
struct Seeds<'a> {
    seeds: &'a [u32],
    goals: &'a [[f32; 3]],
    measure: Option<Measure>,
}

/// A blocked reaction measured for the search: the seeds a share `share` of their way, `delta` the
/// largest move of any seed per coordinate, `size` the largest of those.
#[derive(Clone, Copy)]
pub(super) struct Measure {
    share: f32,
    delta: [f32; 3],
    size: f32,
}

impl Measure {
    /// The share of the move at which fixed elements that would have to move `excess` would just
    /// stay.
    #[inline]
    fn estimate(&self, excess: [f32; 3]) -> f32 {
        let mut cut = 0.0f32;
        for (&x, &d) in excess.iter().zip(&self.delta) {
            if d > 0.0 {
                cut = cut.max(x / d);
            }
        }
        self.share - cut
    }

    /// Whether `excess`, measured so far, already leaves the search (below any share known to work,
    /// which is 0 while it estimates) no room to move: the excess only grows as the reaction goes on,
    /// so the search's estimate and its answer (nothing moves) are the ones the whole reaction gives.
    /// A blocked pull that the tissue holds entirely (the forceps past where the pins let the tissue
    /// go) then stops at the first fixed elements that hold it, not after spreading over the tent.
    #[inline]
    fn leaves_no_room(&self, excess: [f32; 3]) -> bool {
        let next = self.estimate(excess);
        next < 1.0 && next * self.size <= BISECT_TOLERANCE
    }
}

/// One chain reaction, as an operation for [`pulp::Arch::dispatch`].
struct Reaction<'a, const MASK: u8> {
    body: &'a mut Body,
    ws: &'a mut Workspace,
    r: Seeds<'a>,
}

impl<const MASK: u8> pulp::WithSimd for Reaction<'_, MASK> {
    type Output = Outcome;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Outcome {
        let wide = Wide::of(self.ws.simd());
        self.body.chain_reaction_in::<MASK>(self.ws, self.r, wide)
    }
}

/// Whether moving fixed element `c` to `q` (from `pc`), as demanded by its sponsor `s` (which moved
/// from `po` to `ps`) through the link of `s`'s adjacency entry `t`, would make that link worse than
/// it was before this deformation (relaxation can leave links slightly outside their boxes): if so,
/// by how much more than before `c` would have to move, per coordinate.
#[cold]
#[inline(never)]
fn fixed_blocks<const MASK: u8>(
    lattice: &Lattice,
    link_box: &[[[f32; 3]; 2]],
    [s, t, c]: [usize; 3],
    [po, ps, pc, q]: [[f32; 3]; 4],
) -> Option<[f32; 3]> {
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
    (norm(sub(q, pc)) > norm(sub(before, pc)) + tol)
        .then(|| [0, 1, 2].map(|k| ((q[k] - pc[k]).abs() - (before[k] - pc[k]).abs()).max(0.0)))
}
