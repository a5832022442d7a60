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
//! against bounds widened by the tolerance once (the links' per slot class, cached in the workspace;
//! the pairs' kept with them), and lets the usual follower (an element this reaction has not moved,
//! free, behind an element that has) follow in the loop (`follow`); the plain path (`Run::plain`,
//! any widths) reads every bound where it lies, widens it there and decides every bound in `meet`.
//! Both give the same positions, moves and sponsors bit for bit (`tests/chainmail_pairs_reference.rs`
//! compares them).

use super::Measure;
use crate::chainmail::body::{Body, FIXED, SlotClass};
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
pub(crate) fn widen_z([lo, hi]: [f32; 2]) -> [f32; 2] {
    let tol = TOLERANCE * (hi - lo);
    [lo - tol, hi + tol]
}

/// Where one bound of the completion stands: `z[x] - z[y]` must lie in `[lo, hi]`.
struct Bound {
    x: usize,
    y: usize,
    lo: f32,
    hi: f32,
}

/// The elements waiting to be checked: a bit each, taken in element order, forward and then
/// backward and so on (memory is read in order; on a grid two sweeps carry a lift round the tent,
/// as the chamfer passes of a distance transform).
struct Queue {
    bits: Vec<u64>,
    /// How many bits are set.
    len: usize,
    /// The word the sweep is at, and its direction.
    word: usize,
    forward: bool,
}

impl Queue {
    /// Queues element `e` unless it waits already.
    #[inline(always)]
    fn push(&mut self, e: usize) {
        let (word, bit) = (e / 64, 1u64 << (e % 64));
        if let Some(w) = self.bits.get_mut(word)
            && *w & bit == 0
        {
            *w |= bit;
            self.len += 1;
        }
    }

    /// The next waiting element of the sweep, taken out of the queue.
    #[inline(always)]
    fn pop(&mut self) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        loop {
            if let Some(&w) = self.bits.get(self.word)
                && w != 0
            {
                let b = if self.forward { w.trailing_zeros() } else { 63 - w.leading_zeros() };
                self.bits[self.word] = w & !(1u64 << b);
                self.len -= 1;
                return Some(self.word * 64 + b as usize);
            }
            // The next word, or the sweep turns at the end.
            if self.forward {
                if self.word + 1 < self.bits.len() {
                    self.word += 1;
                } else {
                    self.forward = false;
                }
            } else if self.word > 0 {
                self.word -= 1;
            } else {
                self.forward = true;
            }
        }
    }
}

/// What one pass has done so far and whether it goes on.
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
    fn count(&mut self, met: Met, queue: &mut Queue, measure: Option<Measure>, excess: &mut [f32; 3]) {
        match met {
            Met::Held => {}
            Met::Unmet(x) => self.unmet = self.unmet.max(x),
            Met::Moved(f) => {
                self.moves += 1;
                queue.push(f);
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
    g: u32,
}

/// The outcome of one pass: whether a fixed element would have had to move, and how far outside a
/// bound of a moved element was left (see [`Tally::unmet`]).
pub(super) struct Completion {
    pub(super) blocked: bool,
    pub(super) unmet: f32,
}

impl Body {
    /// Completes the normal pass of a body with normal pairs (see the module's comment). A fixed element that would have to move raises `excess` (the normal
    /// coordinate) by how far; with `measure` `None` the pass stops at the first.
    pub(super) fn complete_pairs(
        &mut self,
        ws: &mut Workspace,
        measure: Option<Measure>,
        excess: &mut [f32; 3],
    ) -> Completion {
        let n = self.pos.len();
        let mut queue = Queue { bits: std::mem::take(&mut ws.pair_bits), len: 0, word: 0, forward: true };
        queue.bits.clear();
        queue.bits.resize(n.div_ceil(64), 0);
        for k in 0..ws.moved.len() {
            queue.push(ws.moved[k] as usize);
        }
        let mut tally = Tally {
            moves: 0,
            cap: (MOVES_PER_ELEMENT * n).max(MIN_MOVES),
            blocked: false,
            stop: false,
            unmet: 0.0,
        };
        let mut class_z = std::mem::take(&mut ws.class_z);
        // The links' bounds widened per slot class (a class's bounds never change: a new box is a
        // new class, and the table is rebuilt only under a new revision).
        let key = (self.revision, self.classes.len());
        if ws.class_z_key != key || class_z.len() != self.classes.len() {
            class_z.clear();
            class_z.extend(self.classes.iter().map(|c| widen_z([c.bounds[0][2], c.bounds[1][2]])));
            ws.class_z_key = key;
        }
        let plain = ws.plain_pairs;
        let mut m = Moves {
            pos: &mut self.pos[..n],
            old: &mut ws.old[..n],
            stamp: &mut ws.stamp[..n],
            sponsor: &mut ws.sponsor[..n],
            moved: &mut ws.moved,
            g: ws.generation,
        };
        let b = Bounds {
            flags: &self.flags[..n],
            slot_nbr: &self.slot_nbr[..],
            slot_class: &self.slot_class[..],
            classes: &self.classes[..],
            class_z: &class_z[..],
            pair_nbr: &self.pairs.nbr[..],
            pair_bounds: &self.pairs.bounds[..],
            pair_wide: &self.pairs.wide[..],
            widths: [self.width, self.pairs.width],
        };
        let mut run = Run { queue: &mut queue, tally: &mut tally, measure, excess };
        match (self.width, self.pairs.width, plain) {
            (4, 4, false) => run.fast::<4, 4>(&b, &mut m),
            (5, 4, false) => run.fast::<5, 4>(&b, &mut m),
            _ => run.plain(&b, &mut m),
        }
        // What is still queued (the cap reached) was not checked.
        if queue.len > 0 && !tally.stop {
            tally.unmet = f32::INFINITY;
        }
        ws.class_z = class_z;
        ws.pair_bits = queue.bits;
        Completion { blocked: tally.blocked, unmet: tally.unmet }
    }
}

/// What a pass reads: the body's flags, link slots and classes (and the classes' normal bounds
/// widened), its pair slots with their bounds and widened bounds, and the widths of both rows.
struct Bounds<'a> {
    flags: &'a [u8],
    slot_nbr: &'a [u32],
    slot_class: &'a [u32],
    classes: &'a [SlotClass],
    class_z: &'a [[f32; 2]],
    pair_nbr: &'a [u32],
    pair_bounds: &'a [[f32; 2]],
    pair_wide: &'a [[f32; 2]],
    widths: [usize; 2],
}

/// One pass's queue, tally and what it measures.
struct Run<'a> {
    queue: &'a mut Queue,
    tally: &'a mut Tally,
    measure: Option<Measure>,
    excess: &'a mut [f32; 3],
}

impl Run<'_> {
    /// The pass for `W` link slots and `P` pair slots per element: each element's bounds tested in
    /// one branch-free pass against bounds widened once, the rest out of the loop's way.
    #[inline(never)]
    fn fast<const W: usize, const P: usize>(&mut self, b: &Bounds<'_>, m: &mut Moves<'_>) {
        let n = m.pos.len();
        let (slot_nbr, slot_class) = (&b.slot_nbr[..n * W], &b.slot_class[..n * W]);
        let (pair_nbr, pair_bounds, pair_wide) =
            (&b.pair_nbr[..n * P], &b.pair_bounds[..n * P], &b.pair_wide[..n * P]);
        let class_z = b.class_z;
        while self.tally.goes_on() {
            let Some(x) = self.queue.pop() else { break };
            let (Some(nbrs), Some(cls), Some(pn), Some(pw)) = (
                slot_nbr.get(x * W..).and_then(|s| s.first_chunk::<W>()),
                slot_class.get(x * W..).and_then(|s| s.first_chunk::<W>()),
                pair_nbr.get(x * P..).and_then(|s| s.first_chunk::<P>()),
                pair_wide.get(x * P..).and_then(|s| s.first_chunk::<P>()),
            ) else {
                continue;
            };
            let z = m.pos[x][2];
            let mut out = 0u32;
            for t in 0..W {
                let [lo, hi] = class_z[cls[t] as usize];
                let d = z - m.pos[nbrs[t] as usize][2];
                out |= (((d > hi) | (d < lo)) as u32) << t;
            }
            for t in 0..P {
                let [lo, hi] = pw[t];
                let d = z - m.pos[pn[t] as usize][2];
                out |= (((d > hi) | (d < lo)) as u32) << (W + t);
            }
            while out != 0 {
                let t = out.trailing_zeros() as usize;
                out &= out - 1;
                let (y, [lo, hi]) = if t < W {
                    let [blo, bhi] = b.classes[cls[t] as usize].bounds;
                    (nbrs[t] as usize, [blo[2], bhi[2]])
                } else {
                    (pn[t - W] as usize, pair_bounds[x * P + t - W])
                };
                let met = match follow(m, b.flags, Bound { x, y, lo, hi }) {
                    Some(met) => met,
                    None => meet(m, b.flags, Bound { x, y, lo, hi }),
                };
                self.tally.count(met, self.queue, self.measure, self.excess);
                if self.tally.stop {
                    break;
                }
            }
        }
    }

    /// The pass for any widths, reading every bound where it lies and widening it there: the
    /// reference the fast path is compared with, and the path of unusual widths.
    #[inline(never)]
    fn plain(&mut self, b: &Bounds<'_>, m: &mut Moves<'_>) {
        let [w, pw] = b.widths;
        // The bounds found outside, met after all are tested (as the fast path does).
        let mut out = [(0usize, [0.0f32; 2]); 64];
        while self.tally.goes_on() {
            let Some(x) = self.queue.pop() else { break };
            let mut found = 0;
            let z = m.pos[x][2];
            for t in 0..w + pw {
                let (y, bound) = if t < w {
                    let [lo, hi] = b.classes[b.slot_class[x * w + t] as usize].bounds;
                    (b.slot_nbr[x * w + t] as usize, [lo[2], hi[2]])
                } else {
                    (b.pair_nbr[x * pw + t - w] as usize, b.pair_bounds[x * pw + t - w])
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
                self.tally.count(met, self.queue, self.measure, self.excess);
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

/// [`meet`] where `y` has not moved in this reaction and is free (most bounds the fast path finds
/// outside: `x` has just moved and `y` follows it), in the loop and without its general case: the
/// same arithmetic, so the same result bit for bit; `None` where `meet` must decide (it then does
/// as if this had not been called: nothing is written before).
#[inline(always)]
fn follow(m: &mut Moves<'_>, flags: &[u8], Bound { x, y, lo, hi }: Bound) -> Option<Met> {
    if m.stamp[y] == m.g || flags[y] & FIXED != 0 {
        return None;
    }
    let (zx, zy) = (m.pos[x][2], m.pos[y][2]);
    let d = zx - zy;
    let over = if d > hi { d - hi } else { d - lo };
    let tol = TOLERANCE * (hi - lo);
    if over.abs() <= tol {
        return Some(Met::Held);
    }
    let wx = if m.stamp[x] == m.g { m.old[x][2] } else { zx };
    let before = outside_by(wx - zy, lo, hi);
    if over.abs() <= before.abs() + tol {
        return Some(Met::Unmet(over.abs()));
    }
    // `meet`'s leads, `y`'s own being zero (it has not moved).
    let lead_x = (zx - wx) * over.signum();
    if 0.0 > lead_x {
        return None;
    }
    m.old[y] = m.pos[y];
    m.stamp[y] = m.g;
    m.sponsor[y] = x as u32;
    m.moved.push(y as u32);
    m.pos[y][2] = zx - (d - over);
    Some(Met::Moved(y))
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
    let was = |i: usize, p: f32| if m.stamp[i] == m.g { m.old[i][2] } else { p };
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
    }
    m.pos[f][2] = goal;
    Met::Moved(f)
}
