//! The chain reaction: one element is moved, its neighbours follow only as far as their links demand.

use super::body::{Body, FIXED};
use super::error::{ChainMailError, finite};
use super::ids::ElementId;
use super::lattice::{Lattice, SIDE_B};

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

/// Scratch for deformations and relaxation. Sized once per body; no step allocates.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    /// `stamp[i] == generation` when element `i` moved in the current deformation.
    stamp: Vec<u32>,
    generation: u32,
    /// Position before the current deformation, valid where stamped.
    old: Vec<[f32; 3]>,
    /// The sponsor of each moved element (itself for the source), valid where stamped.
    sponsor: Vec<u32>,
    /// Elements moved by the current deformation, in the order they moved.
    pub(crate) moved: Vec<u32>,
    /// Gibson's candidate lists, one per adjacency slot (a direction on grids: x-, x+, y-, y+, z-,
    /// z+): list `t` occupies `lists[t * n..(t + 1) * n]` and holds moved elements whose neighbour
    /// through slot `t` is still to be checked. Each moved element enters each list once.
    lists: Vec<u32>,
    /// Heads and tails of the candidate lists for widths without a specialised path.
    list_ends: Vec<usize>,
    /// Relaxation's second buffer.
    pub(crate) next: Vec<[f32; 3]>,
}

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

impl Workspace {
    /// A workspace sized for `body`.
    pub fn new(body: &Body) -> Self {
        let mut ws = Self::default();
        ws.fit(body);
        ws
    }

    /// Resizes for `body` if needed (allocates only when the body grew).
    pub fn fit(&mut self, body: &Body) {
        let n = body.element_count();
        if self.stamp.len() != n {
            self.stamp = vec![0; n];
            self.generation = 0;
            self.old = vec![[0.0; 3]; n];
            self.sponsor = vec![0; n];
            self.next = vec![[0.0; 3]; n];
            self.moved = Vec::with_capacity(n);
        }
        if self.lists.len() != n * body.width {
            self.lists = vec![0; n * body.width];
        }
    }

    /// Elements moved by the last deformation, in the order they moved (the source first).
    pub fn moved(&self) -> impl ExactSizeIterator<Item = ElementId> + '_ {
        self.moved.iter().map(|&i| ElementId(i))
    }

    /// The sponsor of an element moved by the last deformation (the source is its own sponsor).
    pub fn sponsor(&self, e: ElementId) -> Option<ElementId> {
        let i = e.index();
        (self.stamp.get(i) == Some(&self.generation) && self.generation != 0)
            .then(|| ElementId(self.sponsor[i]))
    }

    /// An element's position before the last deformation, if it moved.
    pub fn old_position(&self, e: ElementId) -> Option<[f32; 3]> {
        self.sponsor(e).map(|_| self.old[e.index()])
    }

    fn next_generation(&mut self) {
        if self.generation == u32::MAX {
            self.stamp.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
        self.moved.clear();
    }

    fn rollback(&mut self, pos: &mut [[f32; 3]]) {
        for &i in &self.moved {
            pos[i as usize] = self.old[i as usize];
        }
        // Forget the moves: a fresh generation unstamps them.
        self.next_generation();
    }
}

#[inline(always)]
fn clamp_to(p: [f32; 3], lo: [f32; 3], hi: [f32; 3], mask: [bool; 3]) -> [f32; 3] {
    let mut q = p;
    for k in 0..3 {
        if mask[k] {
            q[k] = p[k].max(lo[k]).min(hi[k]);
        }
    }
    q
}

#[inline(always)]
fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
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
        if self.flags[source.index()] & super::body::PINNED != 0 || goal == start {
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
        match mask {
            [true, true, true] => self.chain_reaction_in::<0b111>(ws, source, goal),
            [true, true, false] => self.chain_reaction_in::<0b011>(ws, source, goal),
            [false, false, true] => self.chain_reaction_in::<0b100>(ws, source, goal),
            _ => unreachable!("Pass::mask gives one of three masks"),
        }
    }

    /// The chain reaction for a constant coordinate mask (bit `k` set: coordinate `k` is constrained
    /// and moved).
    ///
    /// Gibson's order: one candidate list per direction (adjacency slot `t`; on grids x-, x+, y-, y+,
    /// z-, z+), processed in turn, each until it is empty, and round again until all are. A moved
    /// element enters the list of each direction whose neighbour has not moved yet (padding slots
    /// point at the element itself, which has); when list `t` reaches it, its neighbour through slot `t` is checked
    /// against it (both positions are final by then: the sponsor has moved, the candidate has not).
    /// The walk runs along grid rows, so memory is read in order, and the moves, their order and
    /// their sponsors are those of per-direction FIFO lists of `(candidate, link, sponsor)` entries.
    fn chain_reaction_in<const MASK: u8>(
        &mut self,
        ws: &mut Workspace,
        source: usize,
        goal: [f32; 3],
    ) -> bool {
        // Constant widths let the row loop unroll: 4 on sheets, 6 in volumes.
        match self.width {
            4 => self.chain_reaction_rows::<MASK>(ws, source, goal, 4, &mut [0; 4], &mut [0; 4]),
            6 => self.chain_reaction_rows::<MASK>(ws, source, goal, 6, &mut [0; 6], &mut [0; 6]),
            w => {
                let mut ends = std::mem::take(&mut ws.list_ends);
                ends.resize(2 * w, 0);
                let (heads, tails) = ends.split_at_mut(w);
                let done = self.chain_reaction_rows::<MASK>(ws, source, goal, w, heads, tails);
                ws.list_ends = ends;
                done
            }
        }
    }

    #[inline(always)]
    fn chain_reaction_rows<const MASK: u8>(
        &mut self,
        ws: &mut Workspace,
        source: usize,
        goal: [f32; 3],
        width: usize,
        heads: &mut [usize],
        tails: &mut [usize],
    ) -> bool {
        ws.next_generation();
        let g = ws.generation;
        let n = self.pos.len();
        // Every per-element slice cut to exactly `n`, so one bounds check on an index serves them all.
        let (nbrs, classes, slot_class, flags) =
            (&self.slot_nbr[..n * width], &self.classes[..], &self.slot_class[..n * width], &self.flags[..n]);
        let pos = &mut self.pos[..n];
        let (stamp, old, sponsor, moved, lists) = (
            &mut ws.stamp[..n],
            &mut ws.old[..n],
            &mut ws.sponsor[..n],
            &mut ws.moved,
            &mut ws.lists[..n * width],
        );
        // Interior grid elements find their neighbours by offset (`Slices::neighbour`).
        let (offs, interior): (&[isize], &[u8]) = match &self.stencil {
            Some(st) if st.interior.len() == n => (&st.offs, &st.interior[..n]),
            _ => (&[], &[]),
        };
        let b = Slices { nbrs, classes, slot_class, flags, interior, offs, width };
        let (head, tail) = (&mut heads[..width], &mut tails[..width]);
        head.fill(0);
        let lists_used = width;

        old[source] = pos[source];
        pos[source] = goal;
        stamp[source] = g;
        sponsor[source] = source as u32;
        moved.push(source as u32);
        for t in 0..lists_used {
            lists[t * n] = source as u32;
            tail[t] = 1;
        }

        let mut run_positions = [[0.0f32; 3]; RUN];
        let mut blocked = false;
        'reaction: loop {
            let mut progressed = false;
            for t in 0..lists_used {
                let list = t * n;
                // Lists across rows (y and z on grids) hold runs of consecutive interior sponsors whose
                // candidates are consecutive too and independent of each other: such a run is moved
                // as one (see `batch`), with the same moves, order, sponsors and list entries.
                let across = offs.get(t).filter(|o| o.unsigned_abs() > 1).copied();
                while head[t] < tail[t] {
                    progressed = true;
                    if let Some(o) = across {
                        let run = Run { list, head: head[t], tail: tail[t], t, o, g };
                        let done = batch::<MASK>(
                            &run,
                            b,
                            pos,
                            stamp,
                            old,
                            sponsor,
                            moved,
                            lists,
                            tail,
                            &mut run_positions,
                        );
                        if done > 0 {
                            head[t] += done;
                            continue;
                        }
                    }
                    let s = lists[list + head[t]] as usize;
                    head[t] += 1;
                    let c = b.neighbour(s, t);
                    let class = slot_class[s * width + t];
                    // Stamped: moved already (padding slots point at `s` itself).
                    if stamp[c] == g {
                        continue;
                    }
                    // The slot bounds `p[s] - p[c]`, so `p[c]` must lie in `[ps - ehi, ps - elo]`; a
                    // broken link's box is infinite and never moves `c`.
                    let ps = pos[s];
                    let [elo, ehi] = classes[class as usize].bounds;
                    let blo = [ps[0] - ehi[0], ps[1] - ehi[1], ps[2] - ehi[2]];
                    let bhi = [ps[0] - elo[0], ps[1] - elo[1], ps[2] - elo[2]];
                    let pc = pos[c];
                    let q = clamp_masked::<MASK>(pc, blo, bhi);
                    if q == pc {
                        continue;
                    }
                    if flags[c] & FIXED != 0 {
                        if self.lattice.fixed_blocks(
                            &self.link_box,
                            s,
                            t,
                            c,
                            [old[s], ps, pc, q],
                            mask_of::<MASK>(),
                        ) {
                            blocked = true;
                            break 'reaction;
                        }
                        continue;
                    }
                    old[c] = pc;
                    pos[c] = q;
                    stamp[c] = g;
                    sponsor[c] = s as u32;
                    moved.push(c as u32);
                    // Gibson: sponsor only neighbours that have not moved (the sponsor among them).
                    for u in 0..lists_used {
                        if stamp.get(b.neighbour(c, u)) != Some(&g) {
                            lists[u * n + tail[u]] = c as u32;
                            tail[u] += 1;
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

/// Where a run of a candidate list starts, for [`batch`].
struct Run {
    /// Start of the list in the workspace's list buffer.
    list: usize,
    /// First unprocessed entry and end of the list.
    head: usize,
    tail: usize,
    /// The list's slot, its grid offset and the generation.
    t: usize,
    o: isize,
    g: u32,
}

/// The body's read-only arrays the chain reaction uses.
#[derive(Clone, Copy)]
struct Slices<'a> {
    nbrs: &'a [u32],
    classes: &'a [super::body::SlotClass],
    slot_class: &'a [u32],
    flags: &'a [u8],
    interior: &'a [u8],
    offs: &'a [isize],
    width: usize,
}

impl Slices<'_> {
    /// The neighbour of element `e` through adjacency slot `u`: by grid offset for interior elements,
    /// which keeps a load off the chain of dependent loads (list entry, neighbour, its stamp), else
    /// from the adjacency row.
    #[inline(always)]
    fn neighbour(&self, e: usize, u: usize) -> usize {
        match (self.interior.get(e), self.offs.get(u)) {
            (Some(1), Some(&o)) => e.wrapping_add_signed(o),
            _ => self.nbrs[e * self.width + u] as usize,
        }
    }
}

/// Longest run moved at once.
const RUN: usize = 64;

/// Moves a run of candidates at once: list entries `s, s + 1, ...` (interior sponsors), whose
/// candidates `s + o, s + o + 1, ...` lie in another row, are free, have not moved and must move.
/// Processed one by one they would not affect each other, so the run is checked first, then its moves
/// are written in bulk. List entries are written as one by one, except those whose neighbour is in
/// the run: that neighbour has moved by the time the entry would be read, so the entry could only be
/// skipped. Returns how many entries were consumed (0: take the one-by-one path for the next entry;
/// 1 with nothing written: its candidate had moved already, as the one-by-one path would find).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn batch<const MASK: u8>(
    run: &Run,
    b: Slices<'_>,
    pos: &mut [[f32; 3]],
    stamp: &mut [u32],
    old: &mut [[f32; 3]],
    sponsor: &mut [u32],
    moved: &mut Vec<u32>,
    lists: &mut [u32],
    tail: &mut [usize],
    q: &mut [[f32; 3]; RUN],
) -> usize {
    let &Run { list, head, tail: end, t, o, g } = run;
    let width = b.width;
    let n = pos.len();
    let s0 = lists[list + head] as usize;
    if b.interior.get(s0) != Some(&1) {
        return 0;
    }
    let c0 = s0.wrapping_add_signed(o);
    // The first candidate has moved already: the entry is done with, as one by one.
    if stamp.get(c0) == Some(&g) {
        return 1;
    }
    let mut m = 0;
    while m < RUN && head + m < end {
        let s = s0 + m;
        let c = c0.wrapping_add(m);
        if lists[list + head + m] as usize != s
            || b.interior.get(s) != Some(&1)
            || c >= n
            || stamp[c] == g
            || b.flags[c] & FIXED != 0
        {
            break;
        }
        let ps = pos[s];
        let [elo, ehi] = b.classes[b.slot_class[s * width + t] as usize].bounds;
        let blo = [ps[0] - ehi[0], ps[1] - ehi[1], ps[2] - ehi[2]];
        let bhi = [ps[0] - elo[0], ps[1] - elo[1], ps[2] - elo[2]];
        let pc = pos[c];
        q[m] = clamp_masked::<MASK>(pc, blo, bhi);
        if q[m] == pc {
            break;
        }
        m += 1;
    }
    if m < 2 {
        return 0;
    }
    let run = c0..c0 + m;
    old[run.clone()].copy_from_slice(&pos[run.clone()]);
    pos[run.clone()].copy_from_slice(&q[..m]);
    stamp[run.clone()].fill(g);
    for (k, sp) in sponsor[run.clone()].iter_mut().enumerate() {
        *sp = (s0 + k) as u32;
    }
    moved.extend(run.clone().map(|c| c as u32));
    let all_interior = b.interior.get(run.clone()).is_some_and(|r| r.iter().all(|&i| i == 1));
    for (u, tail) in tail.iter_mut().enumerate().take(width) {
        // The list's end in a local, not behind the reference: a store and a reload per entry
        // would chain every push to the one before.
        let mut end = *tail;
        let list = &mut lists[u * n..(u + 1) * n];
        let mut push = |c: usize, d: usize| {
            if !run.contains(&d) && stamp.get(d) != Some(&g) {
                list[end] = c as u32;
                end += 1;
            }
        };
        match b.offs.get(u) {
            // Back toward the sponsors, which have all moved: nothing to push.
            Some(&back) if all_interior && back == -o => {}
            // Along the run only its ends can have a neighbour outside it.
            Some(&o) if all_interior && o.unsigned_abs() == 1 => {
                for c in [c0, c0 + m - 1] {
                    push(c, c.wrapping_add_signed(o));
                }
            }
            Some(&o) if all_interior => {
                for c in run.clone() {
                    push(c, c.wrapping_add_signed(o));
                }
            }
            _ => {
                for c in run.clone() {
                    push(c, b.neighbour(c, u));
                }
            }
        }
        *tail = end;
    }
    m
}

const fn mask_of<const MASK: u8>() -> [bool; 3] {
    [MASK & 1 != 0, MASK & 2 != 0, MASK & 4 != 0]
}

/// Clamps the coordinates selected by `MASK` into `[lo, hi]` (`lo <= hi`, all finite or infinite, no
/// NaN): plain comparisons, which compile to single min/max instructions.
#[inline(always)]
fn clamp_masked<const MASK: u8>(p: [f32; 3], lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
    let mut q = p;
    for k in 0..3 {
        if MASK & (1 << k) != 0 {
            let x = if p[k] < lo[k] { lo[k] } else { p[k] };
            q[k] = if x > hi[k] { hi[k] } else { x };
        }
    }
    q
}

impl Lattice {
    /// Whether moving fixed element `c` to `q` (from `pc`), as demanded by its sponsor `s` (which moved
    /// from `po` to `ps`) through the link of `s`'s adjacency entry `t`, would make that link worse than
    /// it was before this deformation (relaxation can leave links slightly outside their boxes).
    #[cold]
    #[inline(never)]
    fn fixed_blocks(
        &self,
        link_box: &[[[f32; 3]; 2]],
        s: usize,
        t: usize,
        c: usize,
        [po, ps, pc, q]: [[f32; 3]; 4],
        mask: [bool; 3],
    ) -> bool {
        let link = self.adj_link[self.adj_start[s] as usize + t];
        debug_assert_eq!(self.adj_nbr[self.adj_start[s] as usize + t] as usize, c);
        let [lo, hi] = link_box[(link & !SIDE_B) as usize];
        // The sponsor is the link's `a` end unless the entry was taken from `b`'s list.
        let (blo, bhi) = if link & SIDE_B == 0 {
            ([ps[0] + lo[0], ps[1] + lo[1], ps[2] + lo[2]], [ps[0] + hi[0], ps[1] + hi[1], ps[2] + hi[2]])
        } else {
            ([ps[0] - hi[0], ps[1] - hi[1], ps[2] - hi[2]], [ps[0] - lo[0], ps[1] - lo[1], ps[2] - lo[2]])
        };
        let shift = [po[0] - ps[0], po[1] - ps[1], po[2] - ps[2]];
        let before = clamp_to(
            pc,
            [blo[0] + shift[0], blo[1] + shift[1], blo[2] + shift[2]],
            [bhi[0] + shift[0], bhi[1] + shift[1], bhi[2] + shift[2]],
            mask,
        );
        let scale = (hi[0] - lo[0]).abs().max((hi[1] - lo[1]).abs()).max((hi[2] - lo[2]).abs())
            + (lo[0].abs() + lo[1].abs() + lo[2].abs());
        let tol = 1e-5 * scale;
        dist2(q, pc).sqrt() > dist2(before, pc).sqrt() + tol
    }
}
