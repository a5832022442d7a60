//! A lift's rigid elements: the normal pass of a surface (a sheet, or layers joined by fibres) whose
//! seeds rise again as they rose in the last reaction from the same seeds moves the taut part of the
//! tent as one, a word of 64 elements at a time, and checks element by element only its rim.
//!
//! An element that a completion moved ends on a bound met exactly with the element that moved it,
//! and so on back to the seeds: it hangs from them by a chain of bounds, and an element that rose by
//! the seeds' rise (within a thousandth of it) hangs from them rigidly. When the same seeds rise again
//! and the body's pins, holds, cuts and materials are as they were, such an element rises by the
//! seeds' rise again. So every element that rose with the seeds last time (and is not fixed) is
//! raised at once by the seeds' new rise; these elements keep their places relative to each other,
//! so every bound between two raised elements holds as it held. Only bounds that leave the raised set
//! towards an element that was not raised can be newly outside: the raised elements with a neighbour
//! on the grid (a link or a normal pair: the eight around it) not raised, or on a grid's edge (which
//! a wrapped axis joins to the other), and those whose fibre to the other layer's element not raised
//! the raise left outside, are queued for the completion, which treats them as moved (stamped, their
//! old heights kept) and goes on from there as usual. The set is found a word at a time: a word of
//! the raised elements' bits and the same word shifted by each neighbour's offset.
//!
//! The raise comes first in the pass, right after the seeds have moved and before Gibson's lists run
//! from them: the lists then stop at the raised elements (stamped, moved already) instead of carrying
//! the seeds' rise through the taut tent around the jaws element by element, moving it to the same
//! heights (each hangs from the seeds by bounds met exactly) but as many more listed moves for the
//! completion to check and the disturbed region to take in. (Raised after the lists until 2026-11-29:
//! the careful exercise's lists then moved about 28 elements a held element, each step of a lift, 3 500
//! at 512 x 384; the step's mean fell by 13-15 % at 256 x 192 and 512 x 384.) Only a reaction that
//! goes the whole way is expected to, though: the raise waits for the lists in a search's unmeasured
//! tries (which stop at the first fixed element the lists meet) and wherever the last search from the
//! same seeds was stopped short (see [`Lift::raises_first`]).
//!
//! Whatever else moved a raised element since (relaxation, contact, the limits' repair) leaves the
//! raise valid: relative places are kept and every bound leaving the set is checked. It may then move
//! an element more than the least the bounds ask, by what those moves changed.
//!
//! The raise keeps each raised element's height before it (`Lift::old_z`, 4 bytes an element), not
//! its whole old position in the workspace (12): the raise moves the height only, so the rest of
//! the old position is where the element is. The completion reads that height where it reads a moved
//! element's old one, writes the whole old position of a raised element it lists, and a rollback puts
//! the heights back. (Until 2026-11-29 the raise copied the positions: callgrind with a 2 MiB
//! second-level cache simulated, the careful exercise's final lift at 512 x 384, steps 1440-1460 on
//! one thread, then missed that cache 3.02 M times and 2.78 M after; its estimated cycles fell by
//! 3.6 %, and by 2.3 % at 256 x 192.)
//!
//! A raised element enters the workspace's moved list only if the completion moves it again: the
//! rest have moved as a body, which strains nothing (`Workspace::raised_unlisted` counts them). A
//! tissue's disturbed region therefore keeps only the rim of a rising tent, not its taut inside.
//!
//! The memory was a bit per block of 8 × 8 elements until 2026-11-28: a block rose only when all 64
//! of its elements had, and the careful meninges exercise's final lift at 256 × 192 then took about
//! 3 300 elements a step one by one that had risen with the seeds, in the 80 blocks along the tent's
//! foot. Its heights agree with the element-by-element completion's to a few nanometres
//! (`tests/chainmail_pairs_reference.rs`).

use crate::chainmail::body::{Body, FIXED};
use crate::chainmail::workspace::Workspace;

/// A rise is the seeds' when it is within this share of theirs.
const MATCH: f32 = 1e-3;

/// The grid of a body: `nz` layers of `nx × ny` elements, element `i + nx (j + ny k)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Grid {
    nx: usize,
    ny: usize,
    nz: usize,
}

impl Grid {
    /// The grid of a surface with normal pairs (one or two layers), if it is one.
    fn of(body: &Body) -> Option<Self> {
        let [nx, ny, nz] = body.lattice.dims?;
        let whole = nx.checked_mul(ny)?.checked_mul(nz)?;
        if !body.pairs.any() || nz == 0 || nz > 2 || nx < 2 || ny < 2 || whole != body.pos.len() {
            return None;
        }
        Some(Self { nx, ny, nz })
    }

    fn len(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    fn words(&self) -> usize {
        self.len().div_ceil(64)
    }

    /// The element `e`'s partner in the other layer (of two), its place there: a fibre, if any, joins
    /// the two.
    fn partner(&self, e: usize) -> usize {
        let layer = self.nx * self.ny;
        if e < layer { e + layer } else { e - layer }
    }

    /// Of word `w` of `set` (a bit per element), the elements whose eight neighbours on their layer's
    /// grid (along the rows, across them and diagonally: the links and the normal pairs) are in `set`
    /// too, reading a neighbour past a row's end or a layer's as the element at that offset (a grid's
    /// edge elements are for the caller to take out).
    fn surrounded(&self, set: &[u64], w: usize) -> u64 {
        let (nx, at) = (self.nx as isize, (w * 64) as isize);
        let mut x = set.get(w).copied().unwrap_or(0);
        for o in [1, -1, nx, -nx, nx + 1, nx - 1, -nx + 1, -nx - 1] {
            x &= word_at(set, at + o);
        }
        x
    }

    /// The bits of the elements on a layer's edge (first or last of a row or a column).
    fn edges(&self) -> Vec<u64> {
        let mut bits = vec![0; self.words()];
        for e in 0..self.len() {
            let (i, j) = (e % self.nx, (e / self.nx) % self.ny);
            if i == 0 || i + 1 == self.nx || j == 0 || j + 1 == self.ny {
                bits[e / 64] |= 1 << (e % 64);
            }
        }
        bits
    }
}

/// The bits of elements `at..at + 64` (none past either end), bit `b` for element `at + b`.
#[inline(always)]
fn word_at(words: &[u64], at: isize) -> u64 {
    let (q, r) = (at.div_euclid(64), at.rem_euclid(64) as u32);
    let get = |w: isize| usize::try_from(w).ok().and_then(|w| words.get(w)).copied().unwrap_or(0);
    if r == 0 { get(q) } else { (get(q) >> r) | (get(q + 1) << (64 - r)) }
}

/// The words of a bitset (a bit per element) outside which every word is clear: the loops over a
/// lift's sets and the completion's queue run over these words, not over the whole body's. (Until
/// 2026-11-29 each reaction went over every word of each set several times: a reaction from the
/// forceps' centre that moved one element took 5.5 us at 256 x 192 and 17.5 us at 512 x 384.)
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Span {
    lo: usize,
    hi: usize,
}

impl Span {
    /// Takes word `w` in.
    #[inline(always)]
    pub(crate) fn add(&mut self, w: usize) {
        if self.lo >= self.hi {
            *self = Span { lo: w, hi: w + 1 };
        } else {
            self.lo = self.lo.min(w);
            self.hi = self.hi.max(w + 1);
        }
    }

    /// The words, first to last (none if empty).
    #[inline(always)]
    pub(crate) fn words(self) -> std::ops::Range<usize> {
        self.lo.min(self.hi)..self.hi
    }

    /// The words of `bits` within the span (those of them `bits` has).
    pub(crate) fn of(self, bits: &[u64]) -> &[u64] {
        let r = self.words();
        bits.get(r.start.min(bits.len())..r.end.min(bits.len())).unwrap_or_default()
    }

    /// Clears the words of `bits` within the span, and the span.
    pub(crate) fn clear(&mut self, bits: &mut [u64]) {
        let r = self.words();
        let n = bits.len();
        if let Some(b) = bits.get_mut(r.start.min(n)..r.end.min(n)) {
            b.fill(0);
        }
        *self = Span::default();
    }

    /// Makes `bits` `words` words long and all clear, and the span empty: only the span's words are
    /// cleared when the length is right already.
    pub(crate) fn reset(&mut self, bits: &mut Vec<u64>, words: usize) {
        if bits.len() == words {
            self.clear(bits);
        } else {
            bits.clear();
            bits.resize(words, 0);
            *self = Span::default();
        }
    }
}

/// Copies the words of `src` within `span` into `dst` (all clear, as long as `src`) and returns the
/// copy's span.
fn copy_span(dst: &mut [u64], src: &[u64], span: Span) -> Span {
    let r = span.words();
    match (dst.get_mut(r.clone()), src.get(r)) {
        (Some(d), Some(s)) => {
            d.copy_from_slice(s);
            span
        }
        _ => Span::default(),
    }
}

/// What the last large reactions from some seeds raised: per element, whether it rose with the seeds,
/// under which seeds, lattice and revision, and by how much.
#[derive(Clone, Debug, Default)]
struct Memo {
    seeds: Vec<u32>,
    shape: u64,
    revision: u64,
    rise: f32,
    rose: Vec<u64>,
    /// The words of `rose` that may have a bit set.
    span: Span,
    used: u64,
    /// The last search from these seeds moved them their whole way (no fixed element stopped it).
    whole: bool,
}

/// The rigid elements' scratch and memory, in the workspace.
#[derive(Clone, Debug, Default)]
pub(crate) struct Lift {
    /// Whether reactions raise rigid elements (the tissue's workspaces do; a plain body's does not
    /// unless asked: `Workspace::set_rigid_blocks`).
    pub(crate) enabled: bool,
    /// One memory per set of seeds (a forceps pull runs two reactions a step: its centre's, then the
    /// rest of its jaws').
    memos: [Memo; 2],
    tick: u64,
    /// This reaction's rigid elements, a bit each, and the words that may have one.
    rigid: Vec<u64>,
    rigid_span: Span,
    /// Whether this reaction raised any element.
    pub(crate) raised: bool,
    /// A bit per raised element the completion has not moved again (not in the moved list): the
    /// raised elements but those the completion listed, which the moved list holds.
    pub(crate) unlisted: Vec<u64>,
    /// The words of `unlisted` that may have a bit set.
    pub(crate) unlisted_span: Span,
    /// How many raised elements are not in the moved list.
    pub(crate) unlisted_count: usize,
    /// Each raised element's height before the raise, where `unlisted` has its bit (the raise writes
    /// no old position: its other coordinates are where they were, and the completion writes the
    /// whole old position of a raised element it lists).
    pub(crate) old_z: Vec<f32>,
    /// The raised elements the completion must check (their bounds may leave the raised set).
    pub(crate) rim: Vec<u32>,
    /// The grid's edge elements, a bit each, and the grid they are for.
    edges: Vec<u64>,
    edges_of: Option<Grid>,
    /// Each element's fibre bound on its height over its partner's, widened (`[-inf, inf]` for none):
    /// read from the element's slots once per word of elements and body revision (`fibre_key`), not
    /// every step (the slots' rows are the raise's slowest reads).
    fibre_z: Vec<[f32; 2]>,
    /// Per word of elements, a bit for each element with a fibre bound (a finite one).
    fibre_bits: Vec<u64>,
    fibre_key: Vec<(u64, u64)>,
    /// Every element that rose with the seeds in the reaction being recorded (scratch), and the words
    /// that may have one.
    rose_all: Vec<u64>,
    rose_all_span: Span,
}

impl Lift {
    /// Whether a reaction from `seeds` raises its rigid elements before Gibson's lists run: when the
    /// last search from them moved them their whole way. A pull the pins stop (a search that shortens
    /// it) raises after the lists, which meet the fixed elements and measure them before the raise
    /// would stop the lists short of them (the completion then walked the whole tent to measure them:
    /// the durotomy's last pull at 256 x 192 took 2.5 times as long).
    pub(crate) fn raises_first(&self, seeds: &[u32]) -> bool {
        self.enabled && self.memos.iter().any(|m| m.whole && m.seeds == seeds)
    }

    /// Notes that a search from `seeds` moved nothing (a fixed element stopped every share of it).
    pub(crate) fn stopped(&mut self, seeds: &[u32]) {
        for m in self.memos.iter_mut().filter(|m| m.seeds == seeds) {
            m.whole = false;
        }
    }

    /// Forgets what the last reactions raised: a lift made otherwise since (`chainmail::ConeLift`)
    /// left the tent where the memory no longer says.
    pub(crate) fn forget(&mut self) {
        for m in &mut self.memos {
            m.whole = false;
            m.rise = 0.0;
        }
    }

    /// Sizes the per-element scratch for `body` (when a workspace is fitted, not at the first raise).
    pub(crate) fn fit(&mut self, body: &Body) {
        let n = body.pos.len();
        let words = n.div_ceil(64);
        if self.unlisted.len() != words {
            self.unlisted = vec![0; words];
            self.unlisted_span = Span::default();
        }
        if self.old_z.len() != n {
            self.old_z = crate::chainmail::workspace::touched(n, 0.0);
        }
        if Grid::of(body).is_some_and(|g| g.nz == 2)
            && (self.fibre_z.len() != n || self.fibre_key.len() != words)
        {
            self.fibre_z = vec![[f32::NEG_INFINITY, f32::INFINITY]; n];
            self.fibre_bits = vec![0; words];
            self.fibre_key = vec![(0, 0); words];
        }
    }

    /// Forgets this reaction's raise (its elements are back where they were, or accepted).
    pub(crate) fn clear_reaction(&mut self) {
        if self.raised {
            self.raised = false;
            self.unlisted_span.clear(&mut self.unlisted);
        }
        self.unlisted_count = 0;
        self.rim.clear();
    }
}

/// Adds `dz` to the height of every position of `run`, writing each height before into `old_z` (as
/// long as `run`), four positions (twelve coordinates) at a time where it can, so that the loop runs
/// on vectors: the other coordinates have `-0.0` added, which leaves every float as it is (a zero's
/// sign too), so the result is the plain `p[2] += dz`'s to the bit.
#[inline(always)]
fn rise_by(run: &mut [[f32; 3]], old_z: &mut [f32], dz: f32) {
    let rise: [f32; 12] = std::array::from_fn(|k| if k % 3 == 2 { dz } else { -0.0 });
    let mut chunks = run.as_flattened_mut().chunks_exact_mut(12);
    let mut zs = old_z.chunks_exact_mut(4);
    for (c, z) in (&mut chunks).zip(&mut zs) {
        for (k, z) in z.iter_mut().enumerate() {
            *z = c[3 * k + 2];
        }
        for (x, d) in c.iter_mut().zip(rise) {
            *x += d;
        }
    }
    let rest = chunks.into_remainder().iter_mut().skip(2).step_by(3);
    for (x, z) in rest.zip(zs.into_remainder()) {
        *z = *x;
        *x += dz;
    }
}

/// Whether bit `i` is set (false past the words).
#[inline(always)]
pub(crate) fn has_bit(words: &[u64], i: usize) -> bool {
    words.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
}

impl Body {
    /// The seeds' common rise in the current reaction (all moved, along the normal, by the same
    /// amount within [`MATCH`]), if it is one.
    fn seeds_rise(&self, ws: &Workspace, seeds: &[u32]) -> Option<f32> {
        let g = ws.generation;
        let mut rise: Option<f32> = None;
        for &s in seeds {
            let s = s as usize;
            if ws.stamp.get(s) != Some(&g) {
                return None;
            }
            let r = self.pos[s][2] - ws.old[s][2];
            match rise {
                None => rise = Some(r),
                Some(d) if (r - d).abs() <= MATCH * d.abs() => {}
                Some(_) => return None,
            }
        }
        rise.filter(|d| d.is_finite() && *d > 0.0)
    }

    /// Raises this reaction's rigid elements by the seeds' rise (see the module's comment) and lists
    /// the raised elements the completion must check in `ws.lift.rim`. `class_z` is the completion's
    /// table of the links' normal bounds per class, widened (`[lo, hi, ..]`, padded to a power of two).
    pub(super) fn raise_rigid(&mut self, ws: &mut Workspace, seeds: &[u32], class_z: &[[f32; 4]]) {
        ws.lift.clear_reaction();
        if !ws.lift.enabled {
            return;
        }
        let Some(grid) = Grid::of(self) else { return };
        let Some(dz) = self.seeds_rise(ws, seeds) else { return };
        let words = grid.words();
        let (shape, revision) = (self.shape, self.revision);
        let lift = &mut ws.lift;
        let Some(at) = lift.memos.iter().position(|m| {
            m.seeds == seeds
                && m.shape == shape
                && m.revision == revision
                && m.rise > 0.0
                && m.rose.len() == words
        }) else {
            return;
        };
        lift.tick += 1;
        lift.memos[at].used = lift.tick;
        lift.rigid_span.reset(&mut lift.rigid, words);
        lift.rigid_span = copy_span(&mut lift.rigid, &lift.memos[at].rose, lift.memos[at].span);
        let span = lift.rigid_span.words();
        let n = self.pos.len();
        // No fixed element is rigid (the memory may predate a grasp).
        let flags = &self.flags[..n];
        let mut any = false;
        for (w, x) in lift.rigid.iter_mut().enumerate().take(span.end).skip(span.start) {
            if *x == 0 {
                continue;
            }
            let first = w * 64;
            let row = &flags[first..(first + 64).min(n)];
            // (A fold, not `any`: without an early exit the test runs on vectors.)
            if row.iter().fold(0, |a, &f| a | f) & FIXED != 0 {
                for (b, &f) in row.iter().enumerate() {
                    if f & FIXED != 0 {
                        *x &= !(1 << b);
                    }
                }
            }
            any |= *x != 0;
        }
        if !any {
            return;
        }
        // (Sized when the workspace was fitted: this only makes sure.)
        lift.fit(self);
        let g = ws.generation;
        let (pos, old_z, stamp) = (&mut self.pos[..n], &mut lift.old_z[..n], &mut ws.stamp[..n]);
        let mut raised = 0usize;
        if lift.edges_of != Some(grid) {
            lift.edges = grid.edges();
            lift.edges_of = Some(grid);
        }
        let (w_slots, mask) = (self.width, class_z.len().wrapping_sub(1));
        let (slot_nbr, slot_class) = (&self.slot_nbr[..n * w_slots], &self.slot_class[..n * w_slots]);
        let layer = grid.nx * grid.ny;
        let key = (self.revision, self.boxes_epoch);
        let il = layer as isize;
        let rigid = &lift.rigid[..];
        // The raise, and word by word after it (while the word's positions are in cache) the rim:
        // rigid elements with a neighbour not rigid (the eight around them on their layer's grid:
        // links and normal pairs; a grid's edge, which a wrapped axis joins to the other, always
        // counts as one), and those whose fibre to the other layer's element, if not rigid, the raise
        // left outside its bound (such an element is not raised, so it reads the same before the
        // raise of its word as after). (Two passes until 2026-11-29; one, under callgrind over the
        // careful exercise's steps 1 300-1 470 at 512 x 384: 13.6 M fewer instructions, 0.8 M fewer
        // first-level misses, as many last-level ones: the partner's height and the fibre bound.)
        for (w, &x) in rigid.iter().enumerate().take(span.end).skip(span.start) {
            if x == 0 {
                continue;
            }
            // Not the elements the lists moved already (each is queued as it is); the rest run by run
            // of consecutive elements (a word inside a tent is one run of 64).
            let first = w * 64;
            let stamps = &stamp[first..(first + 64).min(n)];
            let mut moved = 0u64;
            if stamps.iter().fold(false, |a, &s| a | (s == g)) {
                for (b, &s) in stamps.iter().enumerate() {
                    moved |= u64::from(s == g) << b;
                }
            }
            let (mut y, up) = (x & !moved, x & !moved);
            while y != 0 {
                let at = y.trailing_zeros() as usize;
                let len = ((!(y >> at)).trailing_zeros() as usize).min(64 - at);
                y &= if at + len == 64 { 0 } else { u64::MAX << (at + len) };
                let r = first + at..(first + at + len).min(n);
                stamp[r.clone()].fill(g);
                rise_by(&mut pos[r.clone()], &mut old_z[r], dz);
            }
            raised += up.count_ones() as usize;
            lift.unlisted[w] |= up;
            if up != 0 {
                lift.unlisted_span.add(w);
            }
            let base = first as isize;
            let inner = grid.surrounded(rigid, w) & !lift.edges[w];
            let mut out = x & !inner;
            while out != 0 {
                let b = out.trailing_zeros() as usize;
                out &= out - 1;
                lift.rim.push((first + b) as u32);
            }
            if grid.nz < 2 || inner == 0 {
                continue;
            }
            // Each element's partner in the other layer (the fibre, if any, joins an element to it):
            // above for the first layer's, below for the second's (a word may hold both).
            let lower = if first + 64 <= layer {
                u64::MAX
            } else if first >= layer {
                0
            } else {
                (1u64 << (layer - first)) - 1
            };
            let partner = (word_at(rigid, base + il) & lower) | (word_at(rigid, base - il) & !lower);
            let mut lonely = inner & !partner;
            if lonely == 0 {
                continue;
            }
            if lift.fibre_key[w] != key {
                let mut bound = 0u64;
                for e in first..(first + 64).min(n) {
                    let p = grid.partner(e);
                    let slots = e * w_slots..e * w_slots + w_slots;
                    let t = slot_nbr[slots.clone()].iter().position(|&y| y as usize == p);
                    lift.fibre_z[e] = match t {
                        Some(t) => {
                            let [lo, hi, _, _] = class_z[slot_class[slots][t] as usize & mask];
                            [lo, hi]
                        }
                        None => [f32::NEG_INFINITY, f32::INFINITY],
                    };
                    let [lo, hi] = lift.fibre_z[e];
                    if lo > f32::NEG_INFINITY || hi < f32::INFINITY {
                        bound |= 1 << (e - first);
                    }
                }
                lift.fibre_bits[w] = bound;
                lift.fibre_key[w] = key;
            }
            lonely &= lift.fibre_bits[w];
            while lonely != 0 {
                let b = lonely.trailing_zeros() as usize;
                lonely &= lonely - 1;
                let e = first + b;
                let [lo, hi] = lift.fibre_z[e];
                let d = pos[e][2] - pos[grid.partner(e)][2];
                if d > hi || d < lo {
                    lift.rim.push(e as u32);
                }
            }
        }
        lift.unlisted_count = raised;
        lift.raised = raised > 0;
    }

    /// Remembers, after a reaction that stands, which elements rose with its seeds (`seeds`: the ones
    /// that moved), and whether they moved their whole way (`whole`: see [`Lift::raises_first`]).
    ///
    /// An element is remembered as rigid only if it rose with the seeds and so did the eight around it:
    /// a margin of one element keeps the raise off the tent's foot, where relaxation loosens the bounds
    /// between steps, so that an element raised there would go higher than the least the bounds ask and
    /// relaxation would take it back down step after step, keeping it in the disturbed region. (The
    /// careful exercise at 256 x 192, steps 1300-1530 under callgrind on one thread: 1 506 M
    /// instructions with 8 x 8 blocks, 1 372 M with this margin, 1 821 M with none and 1 440 M with
    /// two; raising runs of elements at once and skipping elements with no fibre bound then took it to
    /// 1 312 M.)
    pub(crate) fn record_rigid(&self, ws: &mut Workspace, seeds: &[u32], whole: bool) {
        if !ws.lift.enabled {
            return;
        }
        let Some(grid) = Grid::of(self) else { return };
        let rise = self.seeds_rise(ws, seeds).unwrap_or(0.0);
        let words = grid.words();
        let lift = &mut ws.lift;
        lift.tick += 1;
        let tick = lift.tick;
        // These seeds' memory, or the one used longest ago.
        let slot = lift
            .memos
            .iter()
            .position(|m| m.seeds == seeds)
            .unwrap_or(if lift.memos[0].used <= lift.memos[1].used { 0 } else { 1 });
        let Lift { memos, unlisted, unlisted_span, rose_all, rose_all_span, .. } = lift;
        let memo = &mut memos[slot];
        memo.seeds.clear();
        memo.seeds.extend_from_slice(seeds);
        memo.used = tick;
        memo.whole = whole;
        memo.shape = self.shape;
        memo.revision = self.revision;
        memo.rise = rise;
        memo.span.reset(&mut memo.rose, words);
        if rise > 0.0 {
            // Raised and not moved again: rose by the seeds' rise. Moved by the lists or the
            // completion: rose with them if within a thousandth of their rise.
            if unlisted.len() == words {
                memo.span = copy_span(&mut memo.rose, unlisted, *unlisted_span);
            }
            let tol = MATCH * rise;
            for &e in &ws.moved {
                let e = e as usize;
                let r = self.pos[e][2] - ws.old[e][2];
                if (r - rise).abs() <= tol
                    && let Some(w) = memo.rose.get_mut(e / 64)
                {
                    *w |= 1 << (e % 64);
                    memo.span.add(e / 64);
                }
            }
            // Only those whose eight neighbours rose with them too (see above).
            rose_all_span.reset(rose_all, words);
            *rose_all_span = copy_span(rose_all, &memo.rose, memo.span);
            let span = memo.span.words();
            for (w, x) in memo.rose.iter_mut().enumerate().take(span.end).skip(span.start) {
                if *x != 0 {
                    *x = grid.surrounded(rose_all, w);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A span takes in the words added, clears only its own words, and a copy into a reset set is
    /// the source everywhere.
    #[test]
    fn spans_bound_the_words_set() {
        let mut span = Span::default();
        assert!(span.words().is_empty());
        span.add(7);
        span.add(3);
        span.add(5);
        assert_eq!(span.words(), 3..8);
        let mut bits = vec![u64::MAX; 10];
        span.clear(&mut bits);
        assert_eq!(bits, [!0, !0, !0, 0, 0, 0, 0, 0, !0, !0]);
        assert!(span.words().is_empty());

        let (mut src, mut src_span) = (vec![0u64; 10], Span::default());
        src[4] = 9;
        src_span.add(4);
        src[6] = 1;
        src_span.add(6);
        let (mut dst, mut dst_span) = (vec![0u64; 10], Span::default());
        dst[1] = 5;
        dst_span.add(1);
        dst[9] = 2;
        dst_span.add(9);
        dst_span.reset(&mut dst, 10);
        assert!(dst.iter().all(|&w| w == 0) && dst_span.words().is_empty());
        dst_span = copy_span(&mut dst, &src, src_span);
        assert_eq!(dst, src);
        assert_eq!(dst_span, src_span);
        let mut short = vec![1u64; 3];
        dst_span.reset(&mut short, 10);
        assert_eq!(short, [0; 10]);
        assert_eq!(src_span.of(&src), &[9, 0, 1]);
    }
}
