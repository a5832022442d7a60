//! The normal pass's completion on a body with normal pairs (`pairs.rs`): Gibson's lists place each
//! element within its sponsor's link only, which on a grid gives a square pyramid; the pairs (a
//! cell's diagonals) ask more of the elements off the axes. What the lists moved is checked against
//! every bound on the normal coordinate, its links' and its pairs', and a bound outside is met by
//! moving one end the least distance along the normal; the end moved is checked in turn.
//!
//! Which end moves is what the chain reaction would decide: the one this reaction moved less in the
//! direction of the excess follows the other, so the lift spreads outward from the source. A bound
//! that was as far outside before the reaction (relaxation and contact can leave such) is left to the
//! limits' repair after the step, as the lists leave it. A fixed element that would have to follow
//! blocks the reaction as in the lists (the excess is measured for the search). Per coordinate the
//! bounds are difference constraints, so this is a label-correcting shortest-path pass: each element
//! ends at the least move that meets them.
//!
//! The elements to check wait as a bit each and are taken in element order, forward and then
//! backward until none waits (as the chamfer passes of a distance transform: on a grid two sweeps
//! carry a lift round the tent): first what the lists moved, then each element as it moves. Only
//! moved elements are ever checked, each against its own bounds, so the cost is what moved, and
//! memory is read in order. (A first-in first-out queue, which carries a point lift outward ring by
//! ring, checked as many elements for 1 % fewer instructions, but in an order the caches do not
//! follow: the careful exercise at 256 × 192 took 1.5 times the CPU time of these sweeps.)
//!
//! The fast path (`Run::fast`, the usual widths) tests an element's bounds in one branch-free pass
//! (the links' widened by the tolerance once per slot class and cached in the workspace, the pairs'
//! widened as they are read: a table of them would be as many more bytes to read per element), and
//! lets the usual follower (an element this reaction has not moved, free, behind an element that
//! has) follow in the loop; the plain path (`Run::plain`, any widths) reads every bound where it
//! lies, widens it there and decides every bound in `meet`. Both give the same positions, moves and
//! sponsors bit for bit (`tests/chainmail_pairs_reference.rs` compares them).
//!
//! The careful meninges exercise at 256 × 192 (its final lift; steps 1440-1450 under callgrind):
//! the fast path took 92.0 M instructions, 384 per element checked, before the rework of 2026-11-25
//! (most of them bounds checks, spills and the queue's state kept in memory), 81.3 M after, and the
//! lift's normal passes about 6 % less CPU time. Compiled for AVX2 (pulp's dispatch) it took 71.2 M
//! instructions but 5 % more CPU time than before, for AVX-512 1.4 times: it waits on its rows'
//! loads (2.6 first-level cache misses per element checked), not on instructions.

use super::Measure;
use super::lift::Span;
use crate::chainmail::body::{Body, FIXED, SlotClass};
use crate::chainmail::pairs::{self, Pairs};
use crate::chainmail::workspace::Workspace;

/// Most moves of one pass, per element of the body (and at least [`MIN_MOVES`]): a bound on its cost
/// where the bounds cannot all be met.
const MOVES_PER_ELEMENT: usize = 8;
const MIN_MOVES: usize = 1024;

/// A bound counts as met within this share of its width (rounding of the bounds and positions).
const TOLERANCE: f32 = 1e-5;

/// A bound `[lo, hi]` on the normal offset widened by the tolerance on either side: what the
/// completion tests (infinite bounds stay infinite).
#[inline(always)]
fn widen_z([lo, hi]: [f32; 2]) -> [f32; 2] {
    let tol = TOLERANCE * (hi - lo);
    [lo - tol, hi + tol]
}

/// Bounds `[lo, hi]` as the fast path reads them: widened, then as they are.
fn widened(bound: [f32; 2]) -> [f32; 4] {
    let [wlo, whi] = widen_z(bound);
    [wlo, whi, bound[0], bound[1]]
}

/// Where one bound of the completion stands: `z[x] - z[y]` must lie in `[lo, hi]`.
struct Bound {
    x: usize,
    y: usize,
    lo: f32,
    hi: f32,
}

/// The elements waiting to be checked: a bit each in a slice of words, taken in element order,
/// forward and then backward and so on (memory is read in order; on a grid two sweeps carry a lift
/// round the tent, as the chamfer passes of a distance transform). The word the sweep is at is kept
/// here (`cur`) and written back when the sweep leaves it (and by [`Queue::finish`]). The sweep turns
/// at the first and last words an element was ever queued in (`span`), not at the body's ends: past
/// them every word is clear, so the elements come in the same order, without reading the words of
/// the whole body (a sweep over 512 x 384's two layers reads 6 144).
#[derive(Clone, Copy)]
struct Queue {
    /// The word the sweep is at (its bits in `cur`), and its direction.
    word: usize,
    cur: u64,
    forward: bool,
    /// How many bits are set.
    len: usize,
    /// The words any element was queued in.
    span: Span,
}

impl Queue {
    /// An empty queue (its words all clear), its sweep at the first word going forward.
    fn new() -> Self {
        Self { word: 0, cur: 0, forward: true, len: 0, span: Span::default() }
    }

    /// Queues element `e` unless it waits already.
    #[inline(always)]
    fn push(&mut self, bits: &mut [u64], e: usize) {
        let (word, bit) = (e / 64, 1u64 << (e % 64));
        self.span.add(word);
        if word == self.word {
            if self.cur & bit == 0 {
                self.cur |= bit;
                self.len += 1;
            }
        } else if let Some(w) = bits.get_mut(word)
            && *w & bit == 0
        {
            *w |= bit;
            self.len += 1;
        }
    }

    /// The next waiting element of the sweep, taken out of the queue.
    #[inline(always)]
    fn pop(&mut self, bits: &mut [u64]) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        loop {
            if self.cur != 0 {
                let b = if self.forward { self.cur.trailing_zeros() } else { 63 - self.cur.leading_zeros() };
                self.cur &= !(1u64 << b);
                self.len -= 1;
                return Some(self.word * 64 + b as usize);
            }
            // The next word (this one is empty) within the span, or the sweep turns at its end. (The
            // sweep starts at the first word, which may lie before the span: it goes straight to it.)
            let words = self.span.words();
            let next = if self.forward {
                (self.word + 1 < words.end).then(|| (self.word + 1).max(words.start))
            } else {
                (self.word > words.start).then(|| (self.word - 1).min(words.end.saturating_sub(1)))
            };
            match next {
                Some(next) => {
                    if let Some(w) = bits.get_mut(self.word) {
                        *w = 0;
                    }
                    self.word = next;
                    self.cur = bits.get(next).copied().unwrap_or(0);
                }
                None => self.forward = !self.forward,
            }
        }
    }

    /// Writes the word the sweep is at back to `bits`.
    fn finish(&self, bits: &mut [u64]) {
        if let Some(w) = bits.get_mut(self.word) {
            *w = self.cur;
        }
    }
}

/// What one pass has done so far and whether it goes on.
#[derive(Clone, Copy)]
struct Tally {
    moves: usize,
    cap: usize,
    blocked: bool,
    /// Stop now: a fixed element would move and the search needs no more measure.
    stop: bool,
    /// The largest excess of a bound left outside (no worse than before the reaction); infinite
    /// when the cap was reached with elements still to check.
    unmet: f32,
}

impl Tally {
    /// Counts what meeting a bound did; queues what moved.
    #[inline(always)]
    fn count(
        &mut self,
        met: Met,
        (queue, bits): (&mut Queue, &mut [u64]),
        measure: Option<Measure>,
        excess: &mut [f32; 3],
    ) {
        match met {
            Met::Held => {}
            Met::Unmet(x) => self.unmet = self.unmet.max(x),
            Met::Moved(f) => {
                self.moves += 1;
                queue.push(bits, f);
            }
            Met::Fixed(x) => {
                self.blocked = true;
                excess[2] = excess[2].max(x);
                match measure {
                    Some(m) if !m.leaves_no_room(*excess) => {}
                    _ => self.stop = true,
                }
            }
        }
    }

    #[inline(always)]
    fn goes_on(&self) -> bool {
        !self.stop && self.moves < self.cap
    }
}

/// What a pass writes: positions, and for the elements it moves their old positions, stamps,
/// sponsors and the moved list (as the lists record them).
struct Moves<'a> {
    pos: &'a mut [[f32; 3]],
    old: &'a mut [[f32; 3]],
    stamp: &'a mut [u32],
    sponsor: &'a mut [u32],
    moved: &'a mut Vec<u32>,
    /// Raised elements not in `moved` yet, a bit each, and how many (`lift.rs`).
    unlisted: (&'a mut [u64], &'a mut usize),
    /// The raised elements' heights before the raise (`Lift::old_z`: their old positions but for
    /// the height are where they are).
    old_z: &'a [f32],
    g: u32,
}

/// The outcome of one pass: whether a fixed element would have had to move, and how far outside a
/// bound of a moved element was left (see [`Tally::unmet`]).
pub(super) struct Completion {
    pub(super) blocked: bool,
    pub(super) unmet: f32,
}

impl Body {
    /// The links' bounds on the normal coordinate per slot class, widened and as they are
    /// (`[lo - tol, hi + tol, lo, hi]`), taken out of the workspace (give it back to `ws.class_z`): a
    /// class's bounds never change (a new box is a new class, and the table is rebuilt only under a new
    /// revision); padded with bounds that always hold to a power of two (the fast path masks a class
    /// with it).
    pub(super) fn class_z_table(&self, ws: &mut Workspace) -> Vec<[f32; 4]> {
        let mut class_z = std::mem::take(&mut ws.class_z);
        let key = (self.revision, self.classes.len());
        let len = self.classes.len().next_power_of_two();
        if ws.class_z_key != key || class_z.len() != len {
            class_z.clear();
            class_z.extend(self.classes.iter().map(|c| widened([c.bounds[0][2], c.bounds[1][2]])));
            class_z.resize(len, widened(pairs::FREE));
            ws.class_z_key = key;
        }
        class_z
    }

    /// The normal pairs' bounds per class as the completion reads them (see [`Body::class_z_table`]),
    /// taken out of the workspace (give it back to `ws.pair_z`).
    fn pair_z_table(&self, ws: &mut Workspace) -> Vec<[f32; 4]> {
        let mut pair_z = std::mem::take(&mut ws.pair_z);
        let table = &self.pairs.table;
        let len = table.len().next_power_of_two();
        if ws.pair_z_key != self.pairs.epoch || pair_z.len() != len {
            pair_z.clear();
            pair_z.extend(table.iter().map(|&b| widened(b)));
            pair_z.resize(len, widened(pairs::FREE));
            ws.pair_z_key = self.pairs.epoch;
        }
        pair_z
    }

    /// Completes the normal pass of a body with normal pairs (see the module's comment), raising a
    /// lift's rigid elements first when `raise` gives the seeds (`lift.rs`; otherwise they rose before
    /// the lists). A fixed element that would have to move raises `excess` (the normal coordinate) by
    /// how far; with `measure` `None` the pass stops at the first.
    pub(super) fn complete_pairs(
        &mut self,
        ws: &mut Workspace,
        raise: Option<&[u32]>,
        measure: Option<Measure>,
        excess: &mut [f32; 3],
    ) -> Completion {
        let n = self.pos.len();
        let mut tally = Tally {
            moves: 0,
            cap: (MOVES_PER_ELEMENT * n).max(MIN_MOVES),
            blocked: false,
            stop: false,
            unmet: 0.0,
        };
        let class_z = self.class_z_table(ws);
        let pair_z = self.pair_z_table(ws);
        // A lift's rigid elements rise now if they did not before the lists (from these seeds).
        if let Some(seeds) = raise {
            self.raise_rigid(ws, seeds, &class_z);
        }
        // All clear between passes (each clears what it leaves queued), so only sized here.
        let mut bits = std::mem::take(&mut ws.pair_bits);
        if bits.len() != n.div_ceil(64) {
            bits.clear();
            bits.resize(n.div_ceil(64), 0);
        }
        let mut queue = Queue::new();
        for k in 0..ws.moved.len() {
            queue.push(&mut bits, ws.moved[k] as usize);
        }
        for k in 0..ws.lift.rim.len() {
            queue.push(&mut bits, ws.lift.rim[k] as usize);
        }
        let plain = ws.plain_pairs;
        let mut m = Moves {
            pos: &mut self.pos[..n],
            old: &mut ws.old[..n],
            stamp: &mut ws.stamp[..n],
            sponsor: &mut ws.sponsor[..n],
            moved: &mut ws.moved,
            unlisted: (&mut ws.lift.unlisted, &mut ws.lift.unlisted_count),
            old_z: &ws.lift.old_z,
            g: ws.generation,
        };
        let b = Bounds {
            flags: &self.flags[..n],
            slot_nbr: &self.slot_nbr[..],
            slot_class: &self.slot_class[..],
            classes: &self.classes[..],
            class_z: &class_z[..],
            pairs: &self.pairs,
            pair_z: &pair_z[..],
            widths: [self.width, self.pairs.width],
        };
        let mut run = Run { bits: &mut bits, queue: &mut queue, tally: &mut tally, measure, excess };
        match (self.width, self.pairs.width, plain) {
            (4, 4, false) => run.fast::<4, 4>(&b, &mut m),
            (5, 4, false) => run.fast::<5, 4>(&b, &mut m),
            _ => run.plain(&b, &mut m),
        }
        // What is still queued (the cap reached) was not checked.
        if queue.len > 0 && !tally.stop {
            tally.unmet = f32::INFINITY;
        }
        queue.finish(&mut bits);
        if queue.len > 0 {
            let mut span = queue.span;
            span.clear(&mut bits);
        }
        ws.class_z = class_z;
        ws.pair_z = pair_z;
        ws.pair_bits = bits;
        Completion { blocked: tally.blocked, unmet: tally.unmet }
    }
}

/// What a pass reads: the body's flags, link slots and classes (and the classes' normal bounds,
/// widened and as they are: `[lo - tol, hi + tol, lo, hi]`), its normal pairs (and their classes'
/// bounds, the same way), and the widths of both rows.
struct Bounds<'a> {
    flags: &'a [u8],
    slot_nbr: &'a [u32],
    slot_class: &'a [u32],
    classes: &'a [SlotClass],
    class_z: &'a [[f32; 4]],
    pairs: &'a Pairs,
    pair_z: &'a [[f32; 4]],
    widths: [usize; 2],
}

/// One pass's queue, tally and what it measures.
struct Run<'a> {
    bits: &'a mut [u64],
    queue: &'a mut Queue,
    tally: &'a mut Tally,
    measure: Option<Measure>,
    excess: &'a mut [f32; 3],
}

impl Run<'_> {
    /// The pass for `W` link slots and `P` pair slots per element: each element's bounds tested in
    /// one branch-free pass against bounds widened once, the usual follower (an element this
    /// reaction has not moved, free, behind an element that has) moved in the loop, the rest left to
    /// [`meet`]: the same arithmetic as [`meet`], so the same result bit for bit. Every row is
    /// resliced to the body's length once, so that one test of the element popped stands for all
    /// its rows; the queue and the tally are kept in locals for the pass.
    #[inline(never)]
    fn fast<const W: usize, const P: usize>(&mut self, b: &Bounds<'_>, m: &mut Moves<'_>) {
        let n = m.pos.len();
        // Every index a row holds is below its table's length (the body's invariant), so `min`
        // with the last element and a mask of the classes (the table's length is a power of two)
        // change none: they only spare a test and a branch per index.
        let (Some(last), Some(class_mask)) = (n.checked_sub(1), b.class_z.len().checked_sub(1)) else {
            return self.plain(b, m);
        };
        let nbr_rows = &b.slot_nbr[..n * W].as_chunks::<W>().0[..n];
        let cls_rows = &b.slot_class[..n * W].as_chunks::<W>().0[..n];
        let pn_rows = &b.pairs.nbr[..n * P].as_chunks::<P>().0[..n];
        let pc_rows = &b.pairs.class[..n * P].as_chunks::<P>().0[..n];
        let Some(pair_mask) = b.pair_z.len().checked_sub(1) else { return self.plain(b, m) };
        let pair_z = b.pair_z;
        let (class_z, flags, g) = (b.class_z, &b.flags[..n], m.g);
        let pos = &mut m.pos[..n];
        let old = &mut m.old[..n];
        let stamp = &mut m.stamp[..n];
        let sponsor = &mut m.sponsor[..n];
        let moved = &mut *m.moved;
        let (unlisted, unlisted_count, old_z) = (&mut *m.unlisted.0, &mut *m.unlisted.1, m.old_z);
        let bits = &mut *self.bits;
        let (mut queue, mut tally) = (*self.queue, *self.tally);
        while tally.goes_on() {
            let Some(x) = queue.pop(bits) else { break };
            let Some(nbrs) = nbr_rows.get(x) else { continue };
            let (cls, pn) = (&cls_rows[x], &pn_rows[x]);
            let z = pos[x][2];
            let mut out = 0u32;
            for t in 0..W {
                let [lo, hi, _, _] = class_z[cls[t] as usize & class_mask];
                let d = z - pos[(nbrs[t] as usize).min(last)][2];
                out |= (((d > hi) | (d < lo)) as u32) << t;
            }
            for (t, &c) in pc_rows[x].iter().enumerate() {
                let [lo, hi, _, _] = pair_z[c as usize & pair_mask];
                let d = z - pos[(pn[t] as usize).min(last)][2];
                out |= (((d > hi) | (d < lo)) as u32) << (W + t);
            }
            while out != 0 {
                let t = out.trailing_zeros() as usize;
                out &= out - 1;
                let (y, lo, hi) = if t < W {
                    let [_, _, lo, hi] = class_z[cls[t] as usize & class_mask];
                    ((nbrs[t] as usize).min(last), lo, hi)
                } else {
                    let k = (t - W) % P;
                    let [_, _, lo, hi] = pair_z[pc_rows[x][k] as usize & pair_mask];
                    ((pn[k] as usize).min(last), lo, hi)
                };
                // `meet` where `y` has not moved in this reaction and is free (most bounds found
                // outside: `x` has just moved and `y` follows it).
                if stamp[y] != g && flags[y] & FIXED == 0 {
                    let (zx, zy) = (pos[x][2], pos[y][2]);
                    let d = zx - zy;
                    let over = if d > hi { d - hi } else { d - lo };
                    let tol = TOLERANCE * (hi - lo);
                    if over.abs() <= tol {
                        continue;
                    }
                    let wx = Before { stamp, old, unlisted, old_z, g }.z(x, zx);
                    let before = outside_by(wx - zy, lo, hi);
                    if over.abs() <= before.abs() + tol {
                        tally.unmet = tally.unmet.max(over.abs());
                        continue;
                    }
                    // `meet`'s leads, `y`'s own being zero (it has not moved): `y` follows unless
                    // `x`'s lead is below zero.
                    let lead_x = (zx - wx) * over.signum();
                    if lead_x >= 0.0 || lead_x.is_nan() {
                        old[y] = pos[y];
                        stamp[y] = g;
                        sponsor[y] = x as u32;
                        moved.push(y as u32);
                        pos[y][2] = zx - (d - over);
                        tally.count(Met::Moved(y), (&mut queue, bits), self.measure, self.excess);
                        continue;
                    }
                }
                let mut m =
                    Moves { pos, old, stamp, sponsor, moved, unlisted: (unlisted, unlisted_count), old_z, g };
                let met = meet(&mut m, flags, Bound { x, y, lo, hi });
                tally.count(met, (&mut queue, bits), self.measure, self.excess);
                if tally.stop {
                    break;
                }
            }
        }
        (*self.queue, *self.tally) = (queue, tally);
    }

    /// The pass for any widths, reading every bound where it lies and widening it there: the
    /// reference the fast path is compared with, and the path of unusual widths.
    #[inline(never)]
    fn plain(&mut self, b: &Bounds<'_>, m: &mut Moves<'_>) {
        let [w, pw] = b.widths;
        // The bounds found outside, met after all are tested (as the fast path does).
        let mut out = [(0usize, [0.0f32; 2]); 64];
        while self.tally.goes_on() {
            let Some(x) = self.queue.pop(self.bits) else { break };
            let mut found = 0;
            let z = m.pos[x][2];
            for t in 0..w + pw {
                let (y, bound) = if t < w {
                    let [lo, hi] = b.classes[b.slot_class[x * w + t] as usize].bounds;
                    (b.slot_nbr[x * w + t] as usize, [lo[2], hi[2]])
                } else {
                    (b.pairs.nbr[x * pw + t - w] as usize, b.pairs.bound(x * pw + t - w))
                };
                let [lo, hi] = widen_z(bound);
                let d = z - m.pos[y][2];
                if (d > hi || d < lo) && found < out.len() {
                    out[found] = (y, bound);
                    found += 1;
                }
            }
            for &(y, [lo, hi]) in &out[..found] {
                let met = meet(m, b.flags, Bound { x, y, lo, hi });
                self.tally.count(met, (self.queue, self.bits), self.measure, self.excess);
                if self.tally.stop {
                    break;
                }
            }
        }
    }
}

/// What meeting one bound did.
enum Met {
    /// Nothing to do: within the tolerance.
    Held,
    /// Left outside by this much: no worse than before the reaction.
    Unmet(f32),
    /// Element `f` moved.
    Moved(usize),
    /// A fixed element would have had to move this much further than before.
    Fixed(f32),
}

/// The signed amount by which `d` lies outside `[lo, hi]` (0 within): how far outside a bound was
/// before the reaction moved its ends.
#[inline(always)]
fn outside_by(d: f32, lo: f32, hi: f32) -> f32 {
    if d > hi {
        d - hi
    } else if d < lo {
        d - lo
    } else {
        0.0
    }
}

/// Where the elements were before this reaction, as the completion reads it: an element's old
/// position where it moved (`stamp` at `g`), the height before the raise where it was raised and not
/// listed since (`unlisted`, `old_z`).
struct Before<'a> {
    stamp: &'a [u32],
    old: &'a [[f32; 3]],
    unlisted: &'a [u64],
    old_z: &'a [f32],
    g: u32,
}

impl Before<'_> {
    /// Element `i`'s height before this reaction, `z` its height now.
    #[inline(always)]
    fn z(&self, i: usize, z: f32) -> f32 {
        if self.stamp.get(i) != Some(&self.g) {
            z
        } else if super::has_bit(self.unlisted, i) {
            self.old_z.get(i).copied().unwrap_or(z)
        } else {
            self.old.get(i).map_or(z, |o| o[2])
        }
    }
}

/// Meets a bound found outside (see the module's comment): the end this reaction moved less in the
/// direction of the excess follows the other. (Out of the loops: most bounds they test hold.)
#[inline(never)]
fn meet(m: &mut Moves<'_>, flags: &[u8], Bound { x, y, lo, hi }: Bound) -> Met {
    let (zx, zy) = (m.pos[x][2], m.pos[y][2]);
    let d = zx - zy;
    // The signed excess of `z[x] - z[y]` over `[lo, hi]`.
    let over = if d > hi { d - hi } else { d - lo };
    let tol = TOLERANCE * (hi - lo);
    if over.abs() <= tol {
        return Met::Held;
    }
    let before = Before { stamp: m.stamp, old: m.old, unlisted: m.unlisted.0, old_z: m.old_z, g: m.g };
    let was = |i: usize, p: f32| before.z(i, p);
    let (wx, wy) = (was(x, zx), was(y, zy));
    let before = outside_by(wx - wy, lo, hi);
    // No worse than before the reaction: not this reaction's doing (the limits' repair sees to it).
    if over.abs() <= before.abs() + tol {
        return Met::Unmet(over.abs());
    }
    // Each end's share of the excess from its own move in this reaction; the larger leads.
    let s = over.signum();
    let (lead_x, lead_y) = ((zx - wx) * s, -(zy - wy) * s);
    let (f, leader, goal) = if lead_y > lead_x { (x, y, zy + (d - over)) } else { (y, x, zx - (d - over)) };
    if flags[f] & FIXED != 0 {
        return Met::Fixed(over.abs() - before.abs());
    }
    if m.stamp[f] != m.g {
        m.old[f] = m.pos[f];
        m.stamp[f] = m.g;
        m.sponsor[f] = leader as u32;
        m.moved.push(f as u32);
    } else if let Some(w) = m.unlisted.0.get_mut(f / 64)
        && *w & (1 << (f % 64)) != 0
    {
        // Raised as a rigid element, and now moved on its own: listed as moved from where it was
        // (below its place now by the raise, which moved its height only).
        *w &= !(1 << (f % 64));
        let p = m.pos[f];
        m.old[f] = [p[0], p[1], m.old_z.get(f).copied().unwrap_or(p[2])];
        *m.unlisted.1 -= 1;
        m.sponsor[f] = leader as u32;
        m.moved.push(f as u32);
    }
    m.pos[f][2] = goal;
    Met::Moved(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The elements of a queue in the order a sweep over every word of the body takes them (the
    /// queue before its sweeps turned at the span's ends), with `more` pushed after each pop
    /// (`more[k]`, the elements the `k`-th popped element queues).
    fn swept_whole(words: usize, first: &[usize], more: &[Vec<usize>]) -> Vec<usize> {
        let mut bits = vec![0u64; words];
        for &e in first {
            bits[e / 64] |= 1 << (e % 64);
        }
        let (mut word, mut forward, mut out) = (0usize, true, Vec::new());
        while bits.iter().any(|&w| w != 0) {
            if bits[word] != 0 {
                let w = bits[word];
                let b = if forward { w.trailing_zeros() } else { 63 - w.leading_zeros() } as usize;
                bits[word] &= !(1 << b);
                let e = word * 64 + b;
                for &f in more.get(out.len()).map(Vec::as_slice).unwrap_or_default() {
                    bits[f / 64] |= 1 << (f % 64);
                }
                out.push(e);
                continue;
            }
            match if forward { (word + 1 < words).then(|| word + 1) } else { word.checked_sub(1) } {
                Some(next) => word = next,
                None => forward = !forward,
            }
        }
        out
    }

    proptest! {
        /// The queue's sweeps, turning at the first and last words anything was queued in, take the
        /// elements in the order of sweeps over every word, and leave every word clear.
        #[test]
        fn sweeps_within_the_span_take_the_same_order(
            first in proptest::collection::vec(0usize..64 * 40, 1..20),
            more in proptest::collection::vec(proptest::collection::vec(0usize..64 * 40, 0..3), 0..40),
        ) {
            let words = 40;
            let mut bits = vec![0u64; words];
            let mut queue = Queue::new();
            for &e in &first {
                queue.push(&mut bits, e);
            }
            let mut got = Vec::new();
            while let Some(e) = queue.pop(&mut bits) {
                for &f in more.get(got.len()).map(Vec::as_slice).unwrap_or_default() {
                    queue.push(&mut bits, f);
                }
                got.push(e);
            }
            queue.finish(&mut bits);
            prop_assert_eq!(got, swept_whole(words, &first, &more));
            prop_assert!(bits.iter().all(|&w| w == 0));
        }
    }
}
