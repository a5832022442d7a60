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
        // Compiled for the widest vectors the machine has (pulp picks at run time): the runs' checks
        // are written as plain loops over lanes and vectorise.
        let arch = pulp::Arch::new();
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
    /// point at the element itself, which has); when list `t` reaches it, its neighbour through slot `t` is checked
    /// against it (both positions are final by then: the sponsor has moved, the candidate has not).
    /// The walk runs along grid rows, so memory is read in order, and the moves, their order and
    /// their sponsors are those of per-direction FIFO lists of `(candidate, link, sponsor)` entries.
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
            4 => self.chain_reaction_rows::<MASK>(ws, source, goal, 4, &mut [0; 4], &mut [0; 4], wide),
            6 => self.chain_reaction_rows::<MASK>(ws, source, goal, 6, &mut [0; 6], &mut [0; 6], wide),
            w => {
                let mut ends = std::mem::take(&mut ws.list_ends);
                ends.resize(2 * w, 0);
                let (heads, tails) = ends.split_at_mut(w);
                let done = self.chain_reaction_rows::<MASK>(ws, source, goal, w, heads, tails, wide);
                ws.list_ends = ends;
                done
            }
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn chain_reaction_rows<const MASK: u8>(
        &mut self,
        ws: &mut Workspace,
        source: usize,
        goal: [f32; 3],
        width: usize,
        heads: &mut [usize],
        tails: &mut [usize],
        wide: Wide,
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
        let (offs, interior, across): (&[isize], &[u8], &[u8]) = match &self.stencil {
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

        let mut patterns = Patterns::default();
        let mut blocked = false;
        'reaction: loop {
            let mut progressed = false;
            for t in 0..lists_used {
                let list = t * n;
                // Lists across rows (y and z on grids) hold runs of consecutive sponsors (up or down
                // a row) whose candidates are consecutive too and independent of each other: such a
                // run is moved as one (see `batch`), with the same moves, order and sponsors.
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
                            &mut patterns,
                            wide,
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
        #[cfg(target_arch = "x86_64")]
        let wide = pulp::x86::V4::try_new();
        #[cfg(not(target_arch = "x86_64"))]
        let wide = None;
        self.body.chain_reaction_in::<MASK>(self.ws, self.source, self.goal, wide)
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
    /// The body's class change bits (`Body::class_change`) and words per slot.
    class_change: &'a [u64],
    class_words: usize,
    flags: &'a [u8],
    interior: &'a [u8],
    /// `Stencil::across`: elements whose neighbours across rows are at the grid offsets.
    across: &'a [u8],
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
const RUN: usize = 1024;

/// Elements a run checks and writes at once, without branches (a multiple of the vector widths).
const CHUNK: usize = 16;

/// A class's bounds laid out for [`check_chunk`]: lane `j` holds coordinate `j % 3`; coordinates the
/// pass leaves alone get infinite bounds, so the clamp leaves them alone too.
struct Pattern {
    lo: [f32; 3 * CHUNK],
    hi: [f32; 3 * CHUNK],
}

impl Default for Pattern {
    fn default() -> Self {
        Self { lo: [0.0; 3 * CHUNK], hi: [0.0; 3 * CHUNK] }
    }
}

impl Pattern {
    fn of<const MASK: u8>(c: &super::body::SlotClass) -> Self {
        let [lo, hi] = c.bounds;
        let lane = |j: usize, x: [f32; 3], off: f32| if MASK & (1 << (j % 3)) != 0 { x[j % 3] } else { off };
        let lo = std::array::from_fn(|j| lane(j, lo, f32::NEG_INFINITY));
        let hi = std::array::from_fn(|j| lane(j, hi, f32::INFINITY));
        Self { lo, hi }
    }
}

/// The last few patterns built: the classes of a grid's rows repeat (their rest lengths differ only
/// in the rounding of the coordinates), so most runs find theirs here.
struct Patterns {
    /// The cached patterns' classes, apart, so that a lookup reads one line.
    classes: [u32; 4],
    cache: [Pattern; 4],
    /// The entry the next miss replaces.
    next: usize,
}

impl Default for Patterns {
    fn default() -> Self {
        Self { classes: [u32::MAX; 4], cache: Default::default(), next: 0 }
    }
}

impl Patterns {
    #[inline(always)]
    fn get<const MASK: u8>(&mut self, class: u32, b: Slices<'_>) -> &Pattern {
        let i = match self.classes.iter().position(|&x| x == class) {
            Some(i) => i,
            None => {
                let i = self.next;
                self.next = (i + 1) % self.cache.len();
                self.cache[i] = Pattern::of::<MASK>(&b.classes[class as usize]);
                self.classes[i] = class;
                i
            }
        };
        &self.cache[i]
    }
}

/// The class change bits of elements `s..s + CHUNK` in slot `t`: bit `j` is set where element `s + j`
/// has another class there than element `s + j - 1`.
#[inline(always)]
fn class_breaks(b: Slices<'_>, t: usize, s: usize) -> Option<u16> {
    // The spare word at the end of each slot's bits keeps `base + 1` within the slot.
    let base = t * b.class_words + s / 64;
    let (lo, hi) = (*b.class_change.get(base)?, *b.class_change.get(base + 1)?);
    Some(((u128::from(hi) << 64 | u128::from(lo)) >> (s % 64)) as u16)
}

/// Sixteen bytes as one word, for checking byte flags sixteen at a time.
#[inline(always)]
fn word(bytes: &[u8]) -> Option<u128> {
    bytes.first_chunk::<CHUNK>().map(|b| u128::from_le_bytes(*b))
}

/// The byte checks of sixteen sponsors from `s` and sixteen candidates from `c` (in memory order):
/// byte `i` is non-zero where sponsor or candidate `i` has a neighbour across rows off the grid
/// offsets, or the candidate is pinned or held.
#[inline(always)]
fn bad_bytes(b: Slices<'_>, s: usize, c: usize) -> Option<u128> {
    // The flags are 0 or 1, so `x ^ ONES` is non-zero exactly where one is 0.
    const ONES: u128 = u128::MAX / 255;
    let (across_s, across_c) = (b.across.get(s..).and_then(word)?, b.across.get(c..).and_then(word)?);
    let flags = b.flags.get(c..).and_then(word)?;
    Some((across_s ^ ONES) | (across_c ^ ONES) | (flags & (ONES * FIXED as u128)))
}

/// How many leading elements of a chunk pass the one-by-one path's checks, for sponsors `s..s + CHUNK`
/// (list entries `entries`) and candidates `c..c + CHUNK` through slot `t`, whose run has the class
/// of `bounds` (from element `s - after`): entry in sequence, sponsor and candidate with their
/// neighbours across rows at the grid offsets (`Stencil::across`),
/// candidate not moved and free, sponsor's link of the run's class (no change bit since the run's
/// first), candidate pushed out of its box. The candidates' clamped positions go to `q`. Every
/// check runs on every lane without a branch, so the loops vectorise; the first failure is read off
/// the bit masks. All ranges must be in bounds (else 0).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn check_chunk<const MASK: u8>(
    b: Slices<'_>,
    entries: &[u32],
    (s, c, t, g): (usize, usize, usize, u32),
    stamp: &[u32],
    pos: &[[f32; 3]],
    bounds: &Pattern,
    q: &mut [f32; 3 * CHUNK],
    after: usize,
) -> usize {
    let (Some(entries), Some(stamps), Some(breaks), Some(ps), Some(pc)) = (
        entries.first_chunk::<CHUNK>(),
        stamp.get(c..).and_then(<[u32]>::first_chunk::<CHUNK>),
        class_breaks(b, t, s),
        pos.get(s..).and_then(<[[f32; 3]]>::first_chunk::<CHUNK>),
        pos.get(c..).and_then(<[[f32; 3]]>::first_chunk::<CHUNK>),
    ) else {
        return 0;
    };
    let Some(bad_bytes) = bad_bytes(b, s, c) else {
        return 0;
    };
    // The run's first element has the run's class by definition; the others must not change it.
    let mut bad = u32::from(breaks) & !u32::from(after == 0);
    for k in 0..CHUNK {
        let fail = (entries[k] != (s + k) as u32) | (stamps[k] == g);
        bad |= (fail as u32) << k;
    }
    let (ps, pc) = (ps.as_flattened(), pc.as_flattened());
    let mut same = 0u64;
    for j in 0..3 * CHUNK {
        // As `clamp_masked`: `p[c]` into `[p[s] - hi, p[s] - lo]`.
        let (lo, hi) = (ps[j] - bounds.hi[j], ps[j] - bounds.lo[j]);
        let x = if pc[j] < lo { lo } else { pc[j] };
        let x = if x > hi { hi } else { x };
        q[j] = x;
        same |= ((x == pc[j]) as u64) << j;
    }
    // An element stays put when all three of its lanes do.
    let still = same & (same >> 1) & (same >> 2) & 0o1111_1111_1111_1111;
    let first_bad_byte = bad_bytes.trailing_zeros() as usize / 8;
    (bad.trailing_zeros() as usize).min(first_bad_byte).min(still.trailing_zeros() as usize / 3).min(CHUNK)
}

/// The AVX-512 registers, when the machine has them.
#[cfg(target_arch = "x86_64")]
type Wide = Option<pulp::x86::V4>;
#[cfg(target_arch = "x86_64")]
use wide::chunk as wide_chunk;

/// Elsewhere none: the chunks take the portable path.
#[cfg(not(target_arch = "x86_64"))]
type Wide = Option<std::convert::Infallible>;
#[cfg(not(target_arch = "x86_64"))]
#[allow(clippy::too_many_arguments)]
fn wide_chunk(
    v: std::convert::Infallible,
    _: Slices<'_>,
    _: &[u32],
    _: (usize, usize, usize, u32),
    _: &Pattern,
    _: [&mut [[f32; 3]]; 2],
    _: [&mut [u32]; 2],
    _: &mut Vec<u32>,
    _: &mut [f32; 3 * CHUNK],
    _: usize,
) -> (usize, bool) {
    match v {}
}

/// The AVX-512 form of a chunk: checked with mask registers and, when all of it passes, written
/// straight from the registers the check computed (no round trip through memory).
#[cfg(target_arch = "x86_64")]
mod wide {
    use super::{CHUNK, Pattern, Slices};
    use pulp::Simd;
    use pulp::x86::V4;
    use pulp::{f32x16, u32x16};

    const IOTA: u32x16 = u32x16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);

    /// Sixteen `u32` from the start of `x`.
    #[inline(always)]
    fn load(x: &[u32]) -> Option<u32x16> {
        x.first_chunk::<CHUNK>().map(|a| pulp::cast(*a))
    }

    /// The candidates `pc` clamped into their boxes around the sponsors `ps` (as `clamp_masked`, by
    /// comparisons, bit for bit), and a bit at `3 i` for each element `i` the clamp leaves in place.
    #[inline(always)]
    fn clamp(v: V4, ps: [f32x16; 3], pc: [f32x16; 3], bounds: &Pattern) -> ([f32x16; 3], u64) {
        let lo: [f32x16; 3] = pulp::cast(bounds.lo);
        let hi: [f32x16; 3] = pulp::cast(bounds.hi);
        let mut x = pc;
        let mut same = 0u64;
        for i in 0..3 {
            let (l, h) = (v.sub_f32s(ps[i], hi[i]), v.sub_f32s(ps[i], lo[i]));
            let y = v.select_f32x16(v.cmp_lt_f32x16(pc[i], l), l, pc[i]);
            x[i] = v.select_f32x16(v.cmp_gt_f32x16(y, h), h, y);
            same |= (v.cmp_eq_f32x16(x[i], pc[i]).0 as u64) << (CHUNK * i);
        }
        // An element stays put when all three of its lanes do.
        (x, same & (same >> 1) & (same >> 2) & 0o1111_1111_1111_1111)
    }

    /// What a chunk's checks read: sixteen list entries (in list order), and from the lowest
    /// sponsor and candidate in memory `[ls, lc]` on, the candidates' stamps, the sponsors' and
    /// candidates' positions, their byte checks ([`super::bad_bytes`]) and the class change bits of
    /// sixteen elements from `breaks_at` in slot `t`.
    struct Loaded {
        e: u32x16,
        st: u32x16,
        ps: [f32x16; 3],
        pc: [f32x16; 3],
        bad_bytes: u128,
        breaks: u16,
    }

    impl Loaded {
        #[inline(always)]
        fn at(
            b: Slices<'_>,
            entries: &[u32],
            stamp: &[u32],
            pos: &[[f32; 3]],
            [ls, lc]: [usize; 2],
            t: usize,
            breaks_at: usize,
        ) -> Option<Self> {
            Some(Self {
                e: load(entries)?,
                st: load(stamp.get(lc..)?)?,
                ps: load3(pos.get(ls..)?)?,
                pc: load3(pos.get(lc..)?)?,
                bad_bytes: super::bad_bytes(b, ls, lc)?,
                breaks: super::class_breaks(b, t, breaks_at)?,
            })
        }
    }

    /// Sixteen positions from the start of `x`, as three vectors.
    #[inline(always)]
    fn load3(x: &[[f32; 3]]) -> Option<[f32x16; 3]> {
        x.first_chunk::<CHUNK>().map(|a| pulp::cast(*a))
    }

    /// As [`super::check_chunk`] (same checks, same clamps, bit for bit); when the whole chunk passes
    /// it is also written: old positions, new positions, stamps, sponsors and the moved list. Returns
    /// how many leading elements pass and whether they were written (else their clamped positions are
    /// in `q`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn chunk(
        v: V4,
        b: Slices<'_>,
        entries: &[u32],
        (s, c, t, g): (usize, usize, usize, u32),
        bounds: &Pattern,
        [pos, old]: [&mut [[f32; 3]]; 2],
        [stamp, sponsor]: [&mut [u32]; 2],
        moved: &mut Vec<u32>,
        q: &mut [f32; 3 * CHUNK],
        after: usize,
    ) -> (usize, bool) {
        let Some(Loaded { e, st, ps, pc, bad_bytes, breaks }) =
            Loaded::at(b, entries, stamp, pos, [s, c], t, s)
        else {
            return (0, false);
        };
        let gs = v.splat_u32s(g);
        let in_sequence = v.equal_u32s(e, v.add_u32s(v.splat_u32s(s as u32), IOTA)).0;
        let unmoved = !v.equal_u32s(st, gs).0;
        // The run's first element has the run's class by definition; the others must not change it.
        let bad = !(in_sequence & unmoved) | breaks & !u16::from(after == 0);
        let (x, still) = clamp(v, ps, pc, bounds);
        let k = (bad.trailing_zeros() as usize)
            .min(bad_bytes.trailing_zeros() as usize / 8)
            .min(still.trailing_zeros() as usize / 3)
            .min(CHUNK);
        // Fewer than two moves in all are left to the one-by-one path.
        if k == 0 || k + after < 2 {
            *q = pulp::cast(x);
            return (k, false);
        }
        let sponsors = v.add_u32s(v.splat_u32s(s as u32), IOTA);
        let order = pulp::cast::<u32x16, [u32; CHUNK]>(v.add_u32s(v.splat_u32s(c as u32), IOTA));
        // The first `k` lanes.
        let lanes = ((1u32 << k) - 1) as u16;
        let moves = Moves { c, pc, x, g, sponsors, lanes, order: &order[..k] };
        if !moves.write(v, [pos, old], [stamp, sponsor], moved) {
            // Not reached (the reads above covered the same range); the caller writes it instead.
            *q = pulp::cast(x);
            return (k, false);
        }
        (k, true)
    }

    /// The writes of a chunk's moves: candidates from `c` (memory order) at `pc`, moving to `x`, in
    /// the lanes set in `lanes`, with `sponsors`; `order` is the moved list's part.
    struct Moves<'a> {
        c: usize,
        pc: [f32x16; 3],
        x: [f32x16; 3],
        g: u32,
        sponsors: u32x16,
        lanes: u16,
        order: &'a [u32],
    }

    impl Moves<'_> {
        /// Writes new and old positions, stamps, sponsors and the moved list; the lanes not moved are
        /// written back as they were (they are other elements than the moved ones, and nothing else
        /// writes them meanwhile). `false`, with nothing written, if the range is not in the body.
        #[inline(always)]
        fn write(
            &self,
            v: V4,
            [pos, old]: [&mut [[f32; 3]]; 2],
            [stamp, sponsor]: [&mut [u32]; 2],
            moved: &mut Vec<u32>,
        ) -> bool {
            let &Moves { c, pc, mut x, g, sponsors, lanes, order } = self;
            let (Some(o), Some(p), Some(st), Some(sp)) = (
                old.get_mut(c..).and_then(<[[f32; 3]]>::first_chunk_mut::<CHUNK>),
                pos.get_mut(c..).and_then(<[[f32; 3]]>::first_chunk_mut::<CHUNK>),
                stamp.get_mut(c..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
                sponsor.get_mut(c..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
            ) else {
                return false;
            };
            let gs = v.splat_u32s(g);
            if lanes == u16::MAX {
                *o = pulp::cast(pc);
                *p = pulp::cast(x);
                *st = pulp::cast(gs);
                *sp = pulp::cast(sponsors);
            } else {
                // Each element's three coordinates.
                let coords =
                    (0..CHUNK).filter(|&i| lanes >> i & 1 == 1).fold(0u64, |m, i| m | 0b111 << (3 * i));
                let was: [f32x16; 3] = pulp::cast(*o);
                let mut new_old = was;
                for i in 0..3 {
                    let m = pulp::b16((coords >> (CHUNK * i)) as u16);
                    x[i] = v.select_f32x16(m, x[i], pc[i]);
                    new_old[i] = v.select_f32x16(m, pc[i], was[i]);
                }
                let (st_was, sp_was): (u32x16, u32x16) = (pulp::cast(*st), pulp::cast(*sp));
                let lanes = pulp::b16(lanes);
                *o = pulp::cast(new_old);
                *p = pulp::cast(x);
                *st = pulp::cast(v.select_u32s(lanes, gs, st_was));
                *sp = pulp::cast(v.select_u32s(lanes, sponsors, sp_was));
            }
            match order.first_chunk::<CHUNK>() {
                // A fixed length: vector moves, not a call.
                Some(all) if order.len() == CHUNK => moved.extend_from_slice(all),
                _ => moved.extend_from_slice(order),
            }
            true
        }
    }

    /// [`chunk`] for a run down the row: sponsors `s, s - 1, ..., s - 15` (list entries in that
    /// order) and candidates `c, c - 1, ...`. The body's arrays are loaded in memory order (lane `i`
    /// holds element `s - 15 + i`), so the run's first failure is the highest failing lane. Returns
    /// how many moves were written: none when the chunk's first fails, or when fewer than two would
    /// be in the run so far (left to the one-by-one path).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn chunk_down(
        v: V4,
        b: Slices<'_>,
        entries: &[u32],
        (s, c, t, g): (usize, usize, usize, u32),
        bounds: &Pattern,
        [pos, old]: [&mut [[f32; 3]]; 2],
        [stamp, sponsor]: [&mut [u32]; 2],
        moved: &mut Vec<u32>,
        after: usize,
    ) -> usize {
        let (Some(ls), Some(lc)) = (s.checked_sub(CHUNK - 1), c.checked_sub(CHUNK - 1)) else {
            return 0;
        };
        // Change bits of elements `ls + 1 ..= s + 1`: element `ls + i` keeps the run's class while
        // every bit `j >= i` is clear (bit 15, the element above the chunk, matters only after it).
        let Some(Loaded { e, st, ps, pc, bad_bytes, breaks }) =
            Loaded::at(b, entries, stamp, pos, [ls, lc], t, ls + 1)
        else {
            return 0;
        };
        let gs = v.splat_u32s(g);
        // Entries in list order: lane `k` is sponsor `s - k`.
        let in_sequence = v.equal_u32s(e, v.sub_u32s(v.splat_u32s(s as u32), IOTA)).0;
        let moved_now = v.equal_u32s(st, gs).0;
        let breaks = breaks & if after == 0 { 0x7fff } else { 0xffff };
        let (x, still) = clamp(v, ps, pc, bounds);
        // The highest failing lane, by memory order (16 when none fails).
        let top =
            |bits: u128, per: u32| if bits == 0 { None } else { Some((127 - bits.leading_zeros()) / per) };
        let failing = [
            top(u128::from(moved_now), 1),
            top(bad_bytes, 8),
            top(u128::from(breaks), 1),
            top(u128::from(still), 3),
        ];
        let highest = failing.iter().flatten().max().map_or(0, |&i| i as usize + 1);
        let k = (CHUNK - highest).min((!in_sequence).trailing_zeros() as usize);
        // Fewer than two moves in all are left to the one-by-one path.
        if k == 0 || k + after < 2 {
            return 0;
        }
        // Moved in the run's order: `c, c - 1, ...`; the top `k` lanes.
        let order = pulp::cast::<u32x16, [u32; CHUNK]>(v.sub_u32s(v.splat_u32s(c as u32), IOTA));
        let sponsors = v.add_u32s(v.splat_u32s(ls as u32), IOTA);
        let lanes = (((1u32 << k) - 1) << (CHUNK - k)) as u16;
        let moves = Moves { c: lc, pc, x, g, sponsors, lanes, order: &order[..k] };
        if moves.write(v, [pos, old], [stamp, sponsor], moved) { k } else { 0 }
    }

    /// [`super::batch`] for a run down the row (entries `s0, s0 - 1, ...`), a chunk at a time, as
    /// the one-by-one path would: the same moves in the same order, the same sponsors, and the same
    /// list entries but for those whose neighbour has moved by the time they would be read.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn batch_down(
        v: V4,
        run: &super::Run,
        b: Slices<'_>,
        [pos, old]: [&mut [[f32; 3]]; 2],
        [stamp, sponsor]: [&mut [u32]; 2],
        moved: &mut Vec<u32>,
        lists: &mut [u32],
        tail: &mut [usize],
        bounds: &Pattern,
    ) -> usize {
        let &super::Run { list, head, tail: end, t, o, g } = run;
        let n = pos.len();
        let s0 = lists[list + head] as usize;
        let c0 = s0.wrapping_add_signed(o);
        let mut m = 0;
        while m < super::RUN && head + m + CHUNK <= end && m < s0 {
            let (s, c) = (s0 - m, c0.wrapping_sub(m));
            let entries = &lists[list + head + m..list + end];
            // How many were moved and written (none: the run ends here).
            let k = chunk_down(v, b, entries, (s, c, t, g), bounds, [pos, old], [stamp, sponsor], moved, m);
            if k == 0 {
                break;
            }
            // Pushes across rows, away from the sponsors, in the run's order.
            for (u, tail) in tail.iter_mut().enumerate().take(b.width) {
                let ou = b.offs[u];
                if ou == -o || ou.unsigned_abs() == 1 {
                    continue;
                }
                let list = &mut lists[u * n..(u + 1) * n];
                push(v, stamp, [c, c.wrapping_add_signed(ou), k], true, g, list, tail);
            }
            m += k;
            if k < CHUNK {
                break;
            }
        }
        if m == 0 {
            return 0;
        }
        super::push_ends(b, [c0, c0 + 1 - m], stamp, g, lists, tail);
        m
    }

    /// Pushes candidates `c, c ± 1, ...` (`k` of them, down the row if `down`) to a candidate list
    /// (`list`, ending at `end`) where their neighbours `d, d ± 1, ...` have not moved: sixteen at
    /// once when none has.
    #[inline(always)]
    pub(super) fn push(
        v: V4,
        stamp: &[u32],
        [c, d, k]: [usize; 3],
        down: bool,
        g: u32,
        list: &mut [u32],
        end: &mut usize,
    ) {
        // The neighbours' stamps in memory order: the first `k` lanes up the row, the last `k` down.
        let (first, lanes) = if down {
            (d.checked_sub(CHUNK - 1), (((1u32 << k) - 1) << (CHUNK - k)) as u16)
        } else {
            (Some(d), ((1u32 << k) - 1) as u16)
        };
        let cs = v.splat_u32s(c as u32);
        if let (Some(ds), Some(slots)) = (
            first.and_then(|f| stamp.get(f..)).and_then(load),
            list.get_mut(*end..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
        ) && v.equal_u32s(ds, v.splat_u32s(g)).0 & lanes == 0
        {
            // Entries past `k` land beyond the list's end, where nothing reads them.
            *slots = pulp::cast(if down { v.sub_u32s(cs, IOTA) } else { v.add_u32s(cs, IOTA) });
            *end += k;
            return;
        }
        for j in 0..k {
            let (c, d) = if down { (c - j, d - j) } else { (c + j, d + j) };
            list[*end] = c as u32;
            *end += (stamp[d] != g) as usize;
        }
    }
}

/// Moves a run of candidates at once: list entries `s, s + 1, ...` (or `s, s - 1, ...`; sponsors
/// whose neighbours across rows are at the grid offsets), whose candidates `s + o, s + o + 1, ...`
/// lie in another row, are likewise placed, free, have not moved and must
/// move. Processed one by one they would not affect each other, so the run is checked and written a
/// chunk at a time. List entries are written as one by one, except those whose neighbour is in the
/// run or among the sponsors: that neighbour has moved by the time the entry would be read, so the
/// entry could only be skipped. Returns how many entries were consumed (0: take the one-by-one path
/// for the next entry; entries whose candidates had all moved already are consumed with nothing
/// written, as the one-by-one path would find).
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
    patterns: &mut Patterns,
    wide: Wide,
) -> usize {
    let &Run { list, head, tail: end, t, o, g } = run;
    let width = b.width;
    let n = pos.len();
    let s0 = lists[list + head] as usize;
    if b.across.get(s0) != Some(&1) {
        return 0;
    }
    let c0 = s0.wrapping_add_signed(o);
    // The first candidate has moved already, and maybe those of the entries after it: such entries
    // are done with, as one by one.
    // Runs go up or down the row: entries `s0, s0 + 1, ...` or `s0, s0 - 1, ...` (the order in which
    // the list along the row moved them).
    let down = head + 1 < end && lists[list + head + 1] as usize == s0.wrapping_sub(1);
    let step = |k: usize| if down { s0.wrapping_sub(k) } else { s0 + k };
    if stamp.get(c0) == Some(&g) {
        let mut k = 1;
        while k < RUN
            && head + k < end
            && lists[list + head + k] as usize == step(k)
            && b.across.get(step(k)) == Some(&1)
            && stamp.get(step(k).wrapping_add_signed(o)) == Some(&g)
        {
            k += 1;
        }
        return k;
    }
    let Some(&cls) = b.slot_class.get(s0 * width + t) else {
        return 0;
    };
    let bounds = patterns.get::<MASK>(cls, b);
    if down {
        #[cfg(target_arch = "x86_64")]
        if let Some(v) = wide {
            return wide::batch_down(v, run, b, [pos, old], [stamp, sponsor], moved, lists, tail, bounds);
        }
        return 0;
    }
    let mut m = 0;
    let mut q = [0.0f32; 3 * CHUNK];
    while m < RUN {
        let (s, c) = (s0 + m, c0.wrapping_add(m));
        let mut written = false;
        let k = if head + m + CHUNK > end {
            0
        } else if let Some(v) = wide {
            let entries = &lists[list + head + m..list + end];
            let k;
            (k, written) = wide_chunk(
                v,
                b,
                entries,
                (s, c, t, g),
                bounds,
                [pos, old],
                [stamp, sponsor],
                moved,
                &mut q,
                m,
            );
            k
        } else {
            check_chunk::<MASK>(
                b,
                &lists[list + head + m..list + end],
                (s, c, t, g),
                stamp,
                pos,
                bounds,
                &mut q,
                m,
            )
        };
        let k = if k > 0 {
            k
        } else {
            // Near the list's end: one element, checked as one by one.
            let ok = head + m < end
                && lists[list + head + m] as usize == s
                && b.across.get(s) == Some(&1)
                && b.across.get(c) == Some(&1)
                && stamp[c] != g
                && b.flags[c] & FIXED == 0
                && b.slot_class[s * width + t] == cls;
            if !ok {
                break;
            }
            let [elo, ehi] = b.classes[cls as usize].bounds;
            let ps = pos[s];
            let blo = [ps[0] - ehi[0], ps[1] - ehi[1], ps[2] - ehi[2]];
            let bhi = [ps[0] - elo[0], ps[1] - elo[1], ps[2] - elo[2]];
            let x = clamp_masked::<MASK>(pos[c], blo, bhi);
            if x == pos[c] {
                break;
            }
            q[..3].copy_from_slice(&x);
            1
        };
        if m + k < 2 {
            // Fewer than two: the one-by-one path does it as cheaply.
            return 0;
        }
        let cs = c..c + k;
        if written {
        } else if k == CHUNK {
            // Fixed lengths, so the copies are vector moves rather than calls.
            let (Some(old), Some(now), Some(st), Some(sp)) = (
                old.get_mut(c..).and_then(<[[f32; 3]]>::first_chunk_mut::<CHUNK>),
                pos.get_mut(c..).and_then(<[[f32; 3]]>::first_chunk_mut::<CHUNK>),
                stamp.get_mut(c..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
                sponsor.get_mut(c..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
            ) else {
                break;
            };
            *old = *now;
            now.as_flattened_mut().copy_from_slice(&q);
            *st = [g; CHUNK];
            *sp = std::array::from_fn(|j| (s + j) as u32);
            moved.extend_from_slice(&std::array::from_fn::<u32, CHUNK, _>(|j| (c + j) as u32));
        } else {
            for (j, c) in cs.clone().enumerate() {
                old[c] = pos[c];
                pos[c] = [q[3 * j], q[3 * j + 1], q[3 * j + 2]];
                stamp[c] = g;
                sponsor[c] = (s + j) as u32;
                moved.push(c as u32);
            }
        }
        // Pushes across rows, away from the sponsors (no neighbour in the run there: the candidates
        // are placed by the grid offsets and distinct rows apart), written without a branch: each slot takes the entry,
        // the end advances only for unmoved neighbours (the list has room: `c` is not in it yet).
        for (u, tail) in tail.iter_mut().enumerate().take(width) {
            let ou = b.offs[u];
            if ou == -o || ou.unsigned_abs() == 1 {
                continue;
            }
            let mut end = *tail;
            let list = &mut lists[u * n..(u + 1) * n];
            // In range: the candidates' neighbours across rows are at the grid offsets.
            let d = c.wrapping_add_signed(ou);
            #[cfg(target_arch = "x86_64")]
            if let Some(v) = wide {
                wide::push(v, stamp, [c, d, k], false, g, list, &mut end);
                *tail = end;
                continue;
            }
            let ds = &stamp[d..d + k];
            if ds.iter().fold(true, |a, &x| a & (x != g)) && end + k <= n {
                for (j, e) in list[end..end + k].iter_mut().enumerate() {
                    *e = (c + j) as u32;
                }
                end += k;
            } else {
                for (j, &x) in ds.iter().enumerate() {
                    list[end] = (c + j) as u32;
                    end += (x != g) as usize;
                }
            }
            *tail = end;
        }
        m += k;
        if k < CHUNK {
            break;
        }
    }
    if m == 0 {
        return 0;
    }
    push_ends(b, [c0, c0 + m - 1], stamp, g, lists, tail);
    m
}

/// The pushes along the row of a run of moved candidates from `first` to `last` (both ends
/// included, either way along the row): only its two ends can have a neighbour there outside the
/// run (and back toward the sponsors every neighbour has moved).
fn push_ends(
    b: Slices<'_>,
    [first, last]: [usize; 2],
    stamp: &[u32],
    g: u32,
    lists: &mut [u32],
    tail: &mut [usize],
) {
    let n = stamp.len();
    for (u, tail) in tail.iter_mut().enumerate().take(b.width) {
        if b.offs[u].unsigned_abs() == 1 {
            for c in [first, last].into_iter().take(if first == last { 1 } else { 2 }) {
                // The real neighbour: a row's end has padding there (itself, moved), and the run's
                // own elements have moved by now.
                let d = b.neighbour(c, u);
                if stamp.get(d) != Some(&g) {
                    lists[u * n + *tail] = c as u32;
                    *tail += 1;
                }
            }
        }
    }
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
