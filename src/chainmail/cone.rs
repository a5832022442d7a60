//! A lift's cone: the least distance `D` over the bounds along the third coordinate from a set of
//! seeds (the held elements), the first part of a lift kept as a distance field
//! (`docs/implicit-lift.md`).
//!
//! Along the normal every bound a body keeps is a difference constraint on two heights: a link slot's
//! box bounds `z[owner] - z[nbr]` by `hi`, so `z[nbr] >= z[owner] - hi`, and a normal pair's the same
//! way. Read each as an edge from the owner to the neighbour weighing `hi` ([`Cone::start`] takes a
//! negative `hi` as zero: the distance is then an upper bound of the true one, and the cone below
//! still a bound; the lift's cone, [`ConeLift`], takes every weight as it is, each edge reweighted by
//! the rest heights so that none is negative: a fibre's bound keeps the upper layer above the lower).
//! With `D[j]` the least distance from the seeds to `j` over these edges, every state whose bounds
//! hold has `z[j] >= A - D[j]` (`A` the seeds' common height), and a lift of the seeds to `A'` is
//! `max(z_before, A' - D)`: the test `tissue::grasp::tests::a_lift_is_a_distance_field_from_the_held_elements`
//! holds both on the careful exercise. Nothing here reads positions: `D` stays true for as long as the
//! seeds, the cuts and the materials stay as they were.
//!
//! [`Cone::grow`] settles elements in order of distance (Dijkstra, with a 4-ary heap of keys that
//! pack an element's distance above its index) and only as far as asked, so that a lift can grow its
//! cone by the ring its rise reaches in a step. Its scratch is kept between calls: after the first
//! cone of a body, starting and growing one allocates nothing. [`distances_plain`] is the reference it
//! is compared with: label-correcting sweeps over every element until nothing changes.
//!
//! [`ConeLift`] is the lift itself (`Body::lift_by_cone`, which the forceps' jaws take along the
//! normal): the chain reaction's heights without its lists, its completion or its search (a test
//! compares the two, `tissue::grasp::tests::the_cone_s_lift_is_the_chain_reaction_s`).
//!
//! The distances are found over the body's own rows (slots and pairs), not a grid: the same cone
//! serves any topology the body has.

use std::cmp::Reverse;
// (A 4-ary heap: popped about once an element settled, it settles 12 to 14 % faster than std's binary
// heap, `cargo bench --bench chainmail -- cone`.)
use dary_heap::QuaternaryHeap;

use super::body::{Body, FIXED, HELD, PINNED};
use super::ids::ElementId;
use super::simd::{Prefetch, SimdLevel};
use super::workspace::Workspace;

/// The least distances over a body's bounds along the third coordinate from a set of seeds, settled
/// in order of distance as far as [`Cone::grow`] is asked to go.
#[derive(Clone, Debug, Default)]
pub struct Cone {
    /// Each element's best distance so far (infinite where not reached): final for settled elements.
    dist: Vec<f32>,
    /// Elements in the order they were settled (their distances in that order never fall).
    settled: Vec<u32>,
    /// Elements whose distance was set, to be reset by the next [`Cone::start`].
    touched: Vec<u32>,
    /// Reached, not settled: the distance's bits above the element's index, least first.
    heap: QuaternaryHeap<Reverse<u64>>,
    /// Each slot class's upper bound along the third coordinate, as an edge weight (see the module).
    class_hi: Vec<f32>,
    /// A press's search's queue (`Cone::search_moving`), and how many of its searches went on by the
    /// heap.
    queue: Vec<u64>,
    pub(crate) by_heap_searches: u64,
    /// Every element within this distance is settled.
    radius: f32,
    /// The distances are taken relative to the rest heights (see [`Cone::start_at`]): every edge's
    /// weight, negative ones too, is exact.
    rest: bool,
    /// The elements reached (pushed on the heap) since the list was last emptied, by
    /// `ConeLift::reach`, which looks again only at these after a growth (kept for a cone relative to
    /// the rest heights only: the lift's).
    pushed: Vec<u32>,
    /// The cone of a press (the seeds going down): every bound read the other way up, as the lower
    /// bound of `-z` (each slot's and pair's `-lo` as the edge's weight, the rest heights negated).
    down: bool,
}

/// An edge's weight from a bound's `hi`: not below zero; `None` for a slot that bounds nothing (a
/// broken link's or a padding slot's infinite box).
#[inline(always)]
fn weight(hi: f32) -> Option<f32> {
    hi.is_finite().then_some(hi.max(0.0))
}

#[inline(always)]
fn key(d: f32, e: u32) -> u64 {
    // A distance is never below zero (nor NaN), so its bits order as it does.
    (u64::from(d.to_bits()) << 32) | u64::from(e)
}

impl Cone {
    /// An empty cone: no seeds, nothing settled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a cone from `seeds` (at distance zero; indices outside the body are skipped), forgetting
    /// the last one. Nothing is settled until [`Cone::grow`].
    pub fn start(&mut self, body: &Body, seeds: &[ElementId]) {
        self.start_at(body, seeds.iter().map(|s| (s.0, 0.0)), false);
    }

    /// [`Cone::start`] with each seed at its own distance (not below zero). With `rest`, each edge
    /// `u -> y` of weight `hi` (negative ones as they are: an element whose bound keeps it above its
    /// neighbour) weighs `hi - r[u] + r[y]`, `r` the rest heights (Johnson's reweighting: the rest
    /// state meets every bound, so no weight is below zero and Dijkstra's order holds); the distance
    /// found for `y` is then `D[y] + r[y]` less the seeds' offset, and its cone holds heights relative
    /// to rest.
    pub(crate) fn start_at(&mut self, body: &Body, seeds: impl Iterator<Item = (u32, f32)>, rest: bool) {
        self.rest = rest;
        let n = body.pos.len();
        if self.dist.len() != n {
            self.dist.clear();
            self.dist.resize(n, f32::INFINITY);
            self.touched.clear();
        }
        for &e in &self.touched {
            if let Some(d) = self.dist.get_mut(e as usize) {
                *d = f32::INFINITY;
            }
        }
        self.touched.clear();
        self.settled.clear();
        self.heap.clear();
        self.pushed.clear();
        self.radius = f32::NEG_INFINITY;
        self.class_hi.clear();
        let down = self.down;
        self.class_hi
            .extend(body.classes.iter().map(|c| if down { -c.bounds[0][2] } else { c.bounds[1][2] }));
        for (e, d0) in seeds {
            let d0 = d0.max(0.0);
            if let Some(d) = self.dist.get_mut(e as usize)
                && *d > d0
            {
                if d.is_infinite() {
                    self.touched.push(e);
                }
                *d = d0;
                self.heap.push(Reverse(key(d0, e)));
            }
        }
    }

    /// A press's search through what moves, from the seeds [`Cone::start_at`] put in: label-correcting
    /// in the order elements are reached (a queue, not the heap: on a near-uniform lattice most are
    /// reached at their least distance first, and one reached closer later is taken again), going on
    /// from an element only where `expand(element, distance)` says. Every element reached ends in
    /// the settled list with its least distance over paths through the elements expanded (an element
    /// that `expand` refuses at a distance is refused at any larger one, so the refused are never
    /// needed). Only for a cone relative to the rest heights.
    pub(crate) fn search_moving(&mut self, body: &Body, expand: impl Fn(usize, f32) -> bool) {
        let w = body.width;
        let (slot_nbr, slot_class, pairs) = (&body.slot_nbr[..], &body.slot_class[..], &body.pairs);
        let rest_pos = body.lattice.rest_positions();
        if !self.rest || rest_pos.len() != body.pos.len() {
            return;
        }
        let sign = if self.down { -1.0f32 } else { 1.0 };
        let down = self.down;
        let Self { dist, settled, touched, heap, class_hi, queue, by_heap_searches, .. } = self;
        // The seeds in order of distance, then every element as it is reached.
        queue.clear();
        queue.extend(heap.iter().map(|&Reverse(k)| k));
        heap.clear();
        queue.sort_unstable();
        let (mut next, mut by_heap) = (0, false);
        loop {
            let k = if by_heap {
                let Some(Reverse(k)) = heap.pop() else { break };
                k
            } else {
                let Some(&k) = queue.get(next) else { break };
                next += 1;
                // Elements reached closer again and again (a deep dent, where the queue's order is
                // far from the distances'): the rest goes by the heap.
                if queue.len() > REACHED_AGAIN * touched.len() + QUEUE_LEAST {
                    heap.extend(queue[next..].iter().map(|&k| Reverse(k)));
                    by_heap = true;
                    *by_heap_searches += 1;
                }
                k
            };
            let (du, u) = (f32::from_bits((k >> 32) as u32), k as u32 as usize);
            if dist.get(u).is_none_or(|&d| du != d) || !expand(u, du) {
                continue; // reached closer since, or need not move
            }
            let ru = sign * rest_pos[u][2];
            let mut reach = |y: u32, bound: f32| {
                let Some(ry) = rest_pos.get(y as usize).map(|p| sign * p[2]) else { return };
                if !bound.is_finite() {
                    return;
                }
                // (At rest every bound holds: below zero only by rounding.)
                let nd = du + (bound - ru + ry).max(0.0);
                if let Some(d) = dist.get_mut(y as usize)
                    && nd < *d
                {
                    if d.is_infinite() {
                        touched.push(y);
                    }
                    *d = nd;
                    if by_heap {
                        heap.push(Reverse(key(nd, y)));
                    } else {
                        queue.push(key(nd, y));
                    }
                }
            };
            let slots = u * w..(u + 1) * w;
            if let (Some(nbrs), Some(cls)) = (slot_nbr.get(slots.clone()), slot_class.get(slots)) {
                for (&y, &c) in nbrs.iter().zip(cls) {
                    if y as usize != u {
                        reach(y, class_hi.get(c as usize).copied().unwrap_or(f32::INFINITY));
                    }
                }
            }
            for (y, [lo, hi]) in pairs.row(u) {
                if y as usize != u {
                    reach(y, if down { -lo } else { hi });
                }
            }
        }
        queue.clear();
        settled.clone_from(touched);
        self.radius = f32::INFINITY;
    }

    /// Settles every element within `radius` of the seeds (and no further); returns how many this call
    /// settled. The body must have the slots, pairs and classes it had at [`Cone::start`].
    pub fn grow(&mut self, body: &Body, radius: f32) -> usize {
        self.grow_within(body, radius, usize::MAX).0
    }

    /// [`Cone::grow`], settling no more than `budget` elements: returns how many it settled and
    /// whether it reached `radius`. A growth cut short settles a prefix of the order a whole one
    /// settles in (every element nearer than the next on the heap), and the next call goes on from
    /// there.
    pub fn grow_within(&mut self, body: &Body, radius: f32, budget: usize) -> (usize, bool) {
        // (A lift's loop and a press's compiled apart, so that a lift's settles as it did before
        // presses shared it.)
        if self.down {
            self.grow_in::<true>(body, radius, budget)
        } else {
            self.grow_in::<false>(body, radius, budget)
        }
    }

    /// [`Cone::grow_within`]; `DOWN` is `self.down`.
    #[inline(always)]
    fn grow_in<const DOWN: bool>(&mut self, body: &Body, radius: f32, budget: usize) -> (usize, bool) {
        let before = self.settled.len();
        let mut short = None;
        let w = body.width;
        let (slot_nbr, slot_class, pairs) = (&body.slot_nbr[..], &body.slot_class[..], &body.pairs);
        let rest_pos = body.lattice.rest_positions();
        let rest = self.rest && rest_pos.len() == body.pos.len();
        // A press reads every height the other way up (see `down`).
        let sign = if DOWN { -1.0f32 } else { 1.0 };
        let (pair_nbr, pw) = (&pairs.nbr[..], pairs.width);
        // (Hints only: the environment's level, not a workspace's.)
        let fetch = Prefetch::new(SimdLevel::from_env());
        let Self { dist, settled, touched, heap, class_hi, pushed, .. } = self;
        while let Some(&Reverse(k)) = heap.peek() {
            let (du, u) = (f32::from_bits((k >> 32) as u32), k as u32 as usize);
            if du > radius {
                break;
            }
            if settled.len() - before >= budget {
                short = Some(du);
                break;
            }
            heap.pop();
            // The next element to settle is most often the heap's top now: its rows are asked for
            // while this one's neighbours are reached (the settled elements lie apart in memory).
            if let Some(&Reverse(next)) = heap.peek() {
                let v = next as u32 as usize;
                fetch.at(slot_nbr, v * w);
                fetch.at(slot_class, v * w);
                fetch.at(pair_nbr, v * pw);
                fetch.at(rest_pos, v);
                fetch.at(dist, v);
            }
            if dist.get(u).is_none_or(|&d| du > d) {
                continue; // a stale entry: `u` was reached closer since
            }
            settled.push(u as u32);
            // (`sign` is a constant: a lift's product by 1 is the height itself.)
            let ru = if rest { sign * rest_pos[u][2] } else { 0.0 };
            let mut relax = |y: u32, hi: f32| {
                let wt = if rest {
                    let Some(ry) = rest_pos.get(y as usize).map(|p| sign * p[2]) else { return };
                    if !hi.is_finite() {
                        return;
                    }
                    // (At rest every bound holds: below zero only by rounding.)
                    (hi - ru + ry).max(0.0)
                } else {
                    let Some(wt) = weight(hi) else { return };
                    wt
                };
                let nd = du + wt;
                if let Some(d) = dist.get_mut(y as usize)
                    && nd < *d
                {
                    if d.is_infinite() {
                        touched.push(y);
                    }
                    *d = nd;
                    heap.push(Reverse(key(nd, y)));
                    if rest {
                        pushed.push(y);
                    }
                }
            };
            let slots = u * w..(u + 1) * w;
            if let (Some(nbrs), Some(cls)) = (slot_nbr.get(slots.clone()), slot_class.get(slots)) {
                for (&y, &c) in nbrs.iter().zip(cls) {
                    if y as usize != u {
                        relax(y, class_hi.get(c as usize).copied().unwrap_or(f32::INFINITY));
                    }
                }
            }
            for (y, [lo, hi]) in pairs.row(u) {
                if y as usize != u {
                    relax(y, if DOWN { -lo } else { hi });
                }
            }
        }
        // Cut short, every element nearer than the heap's least is settled (an element still to
        // settle is at least that far: Dijkstra's order), and no other.
        let reached = match short {
            None => radius,
            Some(du) if du > 0.0 => f32::from_bits(du.to_bits() - 1),
            Some(_) => f32::NEG_INFINITY,
        };
        self.radius = self.radius.max(reached);
        (self.settled.len() - before, short.is_none())
    }

    /// The least distance from the seeds to `e`, if `e` is settled (reachable, and within the radius
    /// grown to; after a growth cut short by its budget, the elements it settled at its last distance
    /// answer once the next growth has gone past it).
    pub fn distance(&self, e: ElementId) -> Option<f32> {
        let d = *self.dist.get(e.index())?;
        (d <= self.radius && d.is_finite()).then_some(d)
    }

    /// The elements settled so far, in order of distance.
    pub fn settled(&self) -> impl ExactSizeIterator<Item = ElementId> + '_ {
        self.settled.iter().map(|&e| ElementId(e))
    }
}

/// A press's search by its queue goes on by the heap once the queue has held this many entries per
/// element reached (plus [`QUEUE_LEAST`]): 1.2 in a 1.5 mm press sliding at 512 × 384, 4.4 on average
/// and up to 8 in a 6 mm one.
/// (In unit tests at the first element reached again, so that their small presses take both ways.)
const REACHED_AGAIN: usize = if cfg!(test) { 1 } else { 2 };
const QUEUE_LEAST: usize = if cfg!(test) { 0 } else { 4096 };

/// Elements per bit of a lift's map of where its cone has settled elements.
const BLOCK: usize = 64;

/// A lift along the normal kept as a cone (`docs/implicit-lift.md`): while the same elements are held
/// and nothing is cut, torn, pinned or given a new material, the distances `D` from them stay true, and
/// a rise of the held elements to `A'` (the highest's height) leaves every element at
/// `max(z, A' - D)`, the least heights that meet every bound along the normal and lie at or above
/// the heights before. The cone grows by the ring the rise reaches (`Body::lift_by_cone`), each
/// element settled once per grasp, not searched again from the jaws every step.
#[derive(Clone, Debug, Default)]
pub struct ConeLift {
    cone: Cone,
    /// The seeds and their heights' offsets from the first (bits), as the cone was started from,
    /// and the body's revision and shape then.
    seeds: Vec<u32>,
    offs: Vec<u32>,
    key: Option<(u64, u64)>,
    /// The seeds in order (to tell a seed from another fixed element).
    sorted: Vec<u32>,
    /// How many settled elements have been looked at for fixed ones, and the fixed ones found.
    scanned: usize,
    fixed: Vec<u32>,
    /// A bit per block of [`BLOCK`] elements with a settled element.
    blocks: Vec<u64>,
    /// Per element, its height when the highest seed is at the lowest seed's rest height, less that
    /// height (`rest - D`): infinitely low for an element not settled or fixed. The write of a lift
    /// reads this and the heights alone (4 bytes an element beside the positions' 12, not the
    /// distances', the rest positions' and the flags' 17).
    lift_at: Vec<f32>,
    /// The lowest rest height of a seed (the cone's distances are relative to it; for a press, of the
    /// heights the other way up).
    base: f32,
    /// A press ([`ConeLift::pressing`]): the seeds go down, every element to `min(z, A' + D)`.
    down: bool,
    /// A press's last level (the deepest seed's goal, heights the other way up), while its cone is
    /// the same.
    pressed: Option<f32>,
    /// A press's offsets as the cone takes them (scratch).
    kept: Vec<f32>,
    /// A press's cone holds the least distances (grown by radius), not a search that stopped where
    /// the tissue need not move: it may be kept for the next press.
    complete: bool,
    /// Most elements a lift settles in one call (`0`: [`LIFT_GROWTH`]).
    pub(crate) growth: usize,
}

/// Most elements a lift's cone settles in one call of `Body::lift_by_cone`: a lift that needs more
/// waits, its jaws where they are, and goes on growing at the next call. The first lift after a cut
/// starts the cone again, and a taut tent needs it grown over its whole area at once: 51 169 elements,
/// 7.6 ms, in the careful exercise's final lift at 512 x 384, 12 241 at 256 x 192 (a cone settles
/// about 150 ns an element there). With this budget that lift waits 14 steps (3 at 256 x 192; none
/// at 128 x 96, whose cone is 2 862), each under a millisecond, while the hand rises 0.19 mm; then
/// the jaws catch up in one step.
pub(crate) const LIFT_GROWTH: usize = 4096;

impl ConeLift {
    /// No cone yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A press's cone (the probe's): the seeds go down and every other element to `min(z, A' + D)`,
    /// `D` the least distances over the bounds read the other way up (each one's lower bound along
    /// the normal). The seeds need not be held. The same code as a lift's, every height negated.
    pub fn pressing() -> Self {
        Self { down: true, cone: Cone { down: true, ..Cone::default() }, ..Self::default() }
    }

    /// The cone itself.
    #[cfg(test)]
    pub(crate) fn cone(&self) -> &Cone {
        &self.cone
    }

    /// Whether a press's cone holds the least distances (it is kept while the footprint stays), not
    /// a search that went only through what moved.
    pub fn is_complete(&self) -> bool {
        self.complete
    }

    /// `1` for a lift, `-1` for a press: heights times this are the cone's.
    #[inline(always)]
    fn sign(&self) -> f32 {
        if self.down { -1.0 } else { 1.0 }
    }

    /// What `lift_at` holds where nothing rises (or falls): infinitely low for a lift, high for a press.
    #[inline(always)]
    fn still(&self) -> f32 {
        self.sign() * f32::NEG_INFINITY
    }

    /// Sizes the cone's per-element arrays and its growth's lists for `body` ahead of its first lift
    /// (their memory written), so that no lift does.
    pub(crate) fn fit_body(&mut self, body: &Body) {
        let n = body.pos.len();
        if self.lift_at.len() != n {
            self.lift_at = super::touched(n, self.still());
        }
        if self.cone.dist.len() != n {
            self.cone.dist = super::touched(n, f32::INFINITY);
            self.cone.touched.clear();
        }
        // The growth's lists and heap too, at their largest (one entry an element; the heap may hold
        // more, stale ones, and then grows). Grown as a lift reached further, a list's new memory was
        // first written in a step, and such a step could wait for the kernel to find and clear a huge
        // page: 6.0 to 6.4 ms at step 219 or 291 of the careful exercise's first lift at 512 × 384, in
        // two `dissect run`s of three, the normal pass's CPU time all of it.
        let c = &mut self.cone;
        for list in [&mut c.settled, &mut c.touched, &mut c.pushed] {
            if list.capacity() < n {
                *list = super::touched(n, u32::MAX);
                list.clear();
            }
        }
        if c.heap.capacity() < n {
            let mut entries = super::touched(n, Reverse(u64::MAX));
            entries.clear();
            c.heap = QuaternaryHeap::from(entries);
        }
    }

    /// Starts the cone again if the seeds, their offsets or the body changed since it was started.
    fn fit(&mut self, body: &Body, seeds: &[u32], offs: &[f32], top: f32) {
        let key = (body.revision, body.shape);
        let same = self.key == Some(key)
            && self.seeds == seeds
            && self.offs.len() == offs.len()
            && self.offs.iter().zip(offs).all(|(a, b)| *a == b.to_bits());
        if same {
            return;
        }
        self.pressed = None;
        self.key = Some(key);
        self.seeds.clear();
        self.seeds.extend_from_slice(seeds);
        self.offs.clear();
        self.offs.extend(offs.iter().map(|o| o.to_bits()));
        self.sorted.clear();
        self.sorted.extend_from_slice(seeds);
        self.sorted.sort_unstable();
        // (What the last cone settled is forgotten first.)
        let n = body.pos.len();
        let still = self.still();
        if self.lift_at.len() != n {
            self.lift_at.clear();
            self.lift_at.resize(n, still);
        } else {
            for &e in &self.cone.settled {
                if let Some(o) = self.lift_at.get_mut(e as usize) {
                    *o = still;
                }
            }
        }
        self.scanned = 0;
        self.fixed.clear();
        self.blocks.clear();
        self.blocks.resize(body.pos.len().div_ceil(BLOCK).div_ceil(64), 0);
        // Heights relative to rest: a seed's distance is its depth under the highest plus its rest
        // height over the lowest seed's.
        let rest = body.lattice.rest_positions();
        let sign = self.sign();
        let r = |s: u32| rest.get(s as usize).map_or(0.0, |p| sign * p[2]);
        self.base = seeds.iter().fold(f32::INFINITY, |m, &s| m.min(r(s)));
        let base = self.base;
        self.cone.down = self.down;
        self.cone.start_at(
            body,
            seeds.iter().zip(offs).map(|(&s, &o)| (s, top - sign * o + r(s) - base)),
            true,
        );
    }

    /// The height the cone gives element `j` at distance `d` (relative to rest: the cone's) when the
    /// highest seed is at `a`: `a - D[j]` (for a press, heights the other way up).
    #[inline(always)]
    fn height(&self, rest: &[[f32; 3]], a: f32, d: f32, j: usize) -> f32 {
        (a - self.base) - d + self.sign() * rest[j][2]
    }

    /// The largest distance of an element reached and not settled that a rise of the highest seed to
    /// `a1` would lift (`None`: none would, and none beyond them either; see [`Body::lift_by_cone`]).
    ///
    /// With `all`, every element on the heap is looked at; otherwise only those reached since the last
    /// call (the others were looked at then, for the same rise, and their heights have not changed).
    fn reach(&mut self, pos: &[[f32; 3]], rest: &[[f32; 3]], a1: f32, all: bool) -> Option<f32> {
        let mut reach: Option<f32> = None;
        let mut look = |u: usize, du: f32| {
            let (Some(&d), Some(p)) = (self.cone.dist.get(u), pos.get(u)) else { return };
            if d != du || du <= self.cone.radius || u >= rest.len() {
                return; // stale, or settled
            }
            if self.height(rest, a1, du, u) > self.sign() * p[2] {
                reach = Some(reach.map_or(du, |r: f32| r.max(du)));
            }
        };
        if all {
            for &Reverse(k) in self.cone.heap.iter() {
                look(k as u32 as usize, f32::from_bits((k >> 32) as u32));
            }
        } else {
            for &u in &self.cone.pushed {
                let u = u as usize;
                if let Some(&d) = self.cone.dist.get(u) {
                    look(u, d);
                }
            }
        }
        self.cone.pushed.clear();
        reach
    }

    /// Looks at the elements settled since the last call: fixed ones (not seeds) are kept, and their
    /// blocks marked.
    fn scan(&mut self, flags: &[u8], rest: &[[f32; 3]]) {
        let (sign, still) = (self.sign(), self.still());
        for &e in &self.cone.settled[self.scanned..] {
            let i = e as usize;
            if let Some(w) = self.blocks.get_mut(i / BLOCK / 64) {
                *w |= 1 << ((i / BLOCK) % 64);
            }
            let fixed = flags.get(i).is_none_or(|f| f & FIXED != 0);
            if fixed && self.sorted.binary_search(&e).is_err() {
                self.fixed.push(e);
            }
            if let (Some(o), Some(r), Some(&d)) =
                (self.lift_at.get_mut(i), rest.get(i), self.cone.dist.get(i))
            {
                // (A press keeps `-(-r - d)`: its write then adds as a lift's does.)
                *o = if fixed { still } else { sign * (sign * r[2] - d) };
            }
        }
        self.scanned = self.cone.settled.len();
    }
}

impl ConeLift {
    /// The least height the first seed may rise to (with the highest seed's offset) before a fixed
    /// element found from `fixed[from..]` would have to move: its height plus its distance.
    fn stop(&self, pos: &[[f32; 3]], rest: &[[f32; 3]], from: usize) -> f32 {
        self.fixed.get(from..).unwrap_or(&[]).iter().fold(f32::INFINITY, |m, &p| {
            let p = p as usize;
            match (pos.get(p), self.cone.dist.get(p)) {
                (Some(q), Some(&d)) => m.min(q[2] - self.height(rest, 0.0, d, p)),
                _ => m,
            }
        })
    }
}

impl Body {
    /// The normal pass of a lift by the cone: `seeds` (the held elements, the first the one the
    /// others hang from by `offs`, their heights' offsets from it) rise together so that the first
    /// reaches `goal`, or as far toward it as the pinned (or otherwise fixed) elements the cone
    /// reaches allow, and every other element goes to `max(z, A' - D)`. Returns the elements moved
    /// (the seeds and the elements that rose by other than the seeds' rise, the tent's foot, in the
    /// workspace's moved list; those that rose with the seeds, straining nothing, counted as
    /// [`Workspace::raised_unlisted`]) and the share of the rise allowed. `None`, with nothing moved,
    /// where the cone does not apply: the seeds do not hang from the first by their offsets, the
    /// move is not a rise, or a seed is not held (the chain reaction then moves the tissue). `(0, 1)`,
    /// with nothing moved, while the cone grows toward what the rise needs ([`LIFT_GROWTH`]).
    ///
    /// Every element the cone has settled is looked at, in blocks of [`BLOCK`] in memory order: the
    /// taut inside of a tent is written every step, as the chain reaction's raise wrote it, but the
    /// completion's walk over its foot and rim (`reaction/complete.rs`) is the cone's ring.
    /// With AVX2 the write takes eight elements at a time, their positions as they lie in three
    /// registers (`TentV3`; the plain path element by element, a test compares the two): in the
    /// careful exercise the normal pass at 512 × 384 fell from 38-39 to 34-36 µs a step.
    ///
    /// Only elements the cone has settled can rise: an element reached and not settled that would not
    /// rise bounds every element behind it, by the bounds along its shortest path, which hold.
    pub(crate) fn lift_by_cone(
        &mut self,
        ws: &mut Workspace,
        lift: &mut ConeLift,
        seeds: &[u32],
        offs: &[f32],
        goal: f32,
    ) -> Option<(u32, f32)> {
        let n = self.pos.len();
        let &first = seeds.first()?;
        let c = self.pos.get(first as usize)?[2];
        let dz = goal - c;
        if lift.down || seeds.len() != offs.len() || !(dz > 0.0 && dz.is_finite()) {
            return None;
        }
        for (&s, &o) in seeds.iter().zip(offs) {
            let (Some(p), Some(&f)) = (self.pos.get(s as usize), self.flags.get(s as usize)) else {
                return None;
            };
            if f & PINNED != 0 || f & HELD == 0 || (p[2] - (c + o)).abs() > HANG {
                return None;
            }
        }
        let top = offs.iter().fold(f32::NEG_INFINITY, |m, &o| m.max(o));
        let (a0, asked) = (c + top, goal + top);
        lift.fit(self, seeds, offs, top);
        let rest = &self.lattice.rest_positions()[..n];
        // The pinned (or otherwise held) elements the rise reaches stop it where the first of them
        // would have to move: at its height plus its distance. Each one settled bounds the rise, so
        // the cone grows only toward what the rise, so bounded, would lift: an element it has not
        // settled would not rise, and its stop lies above the bound. A lift the pins already stop
        // grows nothing (the careful durotomy's fold, blocked for 900 steps, grew its cone over
        // most of the sheet, a ring every 20 steps, up to 1.2 ms each, at 256 x 192).
        // (Read off the fixed elements and the distances alone, not the goal: a blocked pull stays
        // blocked however far it asks, as `tissue::grasp::BlockedPull` assumes.)
        let mut stop = lift.stop(&self.pos, rest, 0);
        let mut a1 = asked;
        let mut all = true;
        let mut budget = if lift.growth == 0 { LIFT_GROWTH } else { lift.growth };
        loop {
            if stop < a1 {
                // As the chain reaction's search: a move shorter than its tolerance is none.
                if stop - a0 <= super::reaction::BISECT_TOLERANCE {
                    return Some((0, 0.0));
                }
                a1 = stop;
            }
            let Some(r) = lift.reach(&self.pos, rest, a1, all) else { break };
            let (settled, reached) = lift.cone.grow_within(self, r + (a1 - a0), budget);
            let known = lift.fixed.len();
            lift.scan(&self.flags, rest);
            stop = stop.min(lift.stop(&self.pos, rest, known));
            if !reached {
                // The jaws wait for the cone (see `LIFT_GROWTH`): nothing moves this time.
                return Some((0, 1.0));
            }
            budget -= settled;
            all = false;
        }
        let fraction = if a1 < asked { (a1 - a0) / (asked - a0) } else { 1.0 };
        let goal = a1 - top;
        let dz = goal - c;
        ws.fit(self);
        ws.next_generation();
        ws.lift.forget();
        let g = ws.generation;
        for (&s, &o) in seeds.iter().zip(offs) {
            let s = s as usize;
            ws.stamp[s] = g;
            ws.old[s] = self.pos[s];
            ws.sponsor[s] = s as u32;
            ws.moved.push(s as u32);
            self.pos[s][2] = goal + o;
        }
        // What rose by the seeds' rise (within a thousandth of it, as the chain reaction's raise
        // takes it) rose as a body.
        let slack = 1e-3 * dz;
        let simd = ws.simd();
        let (stamp, old, sponsor, moved) = (&mut ws.stamp, &mut ws.old, &mut ws.sponsor, &mut ws.moved);
        let tent = Tent {
            pos: &mut self.pos[..n],
            lift_at: &lift.lift_at[..n],
            b1: a1 - lift.base,
            dz,
            slack,
            marks: Marks { stamp, old, sponsor, moved, generation: g },
        };
        let rigid = tent.write::<false>(&lift.blocks, simd);
        ws.lift.unlisted_count = rigid;
        self.note_motion();
        Some(((ws.moved.len() + rigid) as u32, fraction))
    }
}

/// What a press asks of [`Body::press_by_cone`] (see there).
pub(crate) struct Press<'a> {
    /// The elements pressed (free ones).
    pub(crate) seeds: &'a [u32],
    /// Each seed's goal over `goal`.
    pub(crate) offs: &'a [f32],
    /// The height the seeds' offsets are taken from (the ball's lowest point).
    pub(crate) goal: f32,
    /// How far the offsets may drift from the cone's before it is started again.
    pub(crate) tolerance: f32,
    /// A footprint pressed again after a search through what moved starts a whole cone.
    pub(crate) whole: bool,
}

impl Body {
    /// The probe's press by a cone ([`ConeLift::pressing`]): the ball's footprint, `seeds` (free
    /// elements), each to go down to `goal + offs[k]` (the ball's surface above it), and every element
    /// to `min(z, A' + D)`: the highest heights at or below the heights before that meet every bound
    /// along the normal with each seed at or below its goal. A seed already below its goal stays (a
    /// ball pushes, it does not pull). Offsets within `tolerance` of the cone's keep the cone (the
    /// footprint's elements drift across the surface by a little as relaxation settles them). With
    /// `whole`, a press of the footprint of the last press, whose search went only through what moved,
    /// starts a whole cone (to be kept); without, it searches through what moves again. Returns
    /// the elements moved (listed in the workspace as [`Body::lift_by_cone`] lists them, the dent's
    /// taut inside that went down by the ball's own move counted as
    /// [`Workspace::raised_unlisted`]), or `None` where the cone does not apply (a seed pinned or
    /// held, or not in the body; the chain reaction then presses).
    ///
    /// Pinned or held elements the press reaches stop it where the first of them would have to
    /// move, as they stop a lift.
    pub(crate) fn press_by_cone(
        &mut self,
        ws: &mut Workspace,
        press: &mut ConeLift,
        ball: &Press,
    ) -> Option<u32> {
        let Press { seeds, offs, goal, tolerance, whole } = *ball;
        let n = self.pos.len();
        if !press.down || seeds.is_empty() || seeds.len() != offs.len() || !goal.is_finite() {
            return None;
        }
        for (&s, &o) in seeds.iter().zip(offs) {
            let f = *self.flags.get(s as usize)?;
            if f & FIXED != 0 || !o.is_finite() {
                return None;
            }
        }
        // The cone's own offsets while the footprint is the same and has drifted by less than the
        // tolerance.
        let same = press.key == Some((self.revision, self.shape))
            && press.seeds == seeds
            && press.offs.len() == offs.len()
            && press.offs.iter().zip(offs).all(|(a, b)| (f32::from_bits(*a) - b).abs() <= tolerance);
        let mut kept = std::mem::take(&mut press.kept);
        kept.clear();
        if same {
            kept.extend(press.offs.iter().map(|&a| f32::from_bits(a)));
        } else {
            kept.extend_from_slice(offs);
        }
        // A new footprint (a ball sliding across the tissue: one every step or two) is searched from
        // only through what moves: the tissue was within every bound, so an element that need not
        // move bounds nothing behind it that it did not bound before. The same footprint pressed
        // again (with `whole`) starts a whole cone, and a ball pressing where it pressed last keeps
        // it (grown by the ring each press reaches, written a block at a time).
        let restart = !(same && press.complete);
        if restart {
            press.key = None;
        }
        // Heights the other way up from here to the write: the deepest seed's goal is the level `a1`.
        let top = kept.iter().fold(f32::NEG_INFINITY, |m, &o| m.max(-o));
        let mut a1 = -goal + top;
        press.fit(self, seeds, &kept, top);
        press.kept = kept;
        let rest = &self.lattice.rest_positions()[..n];
        if restart {
            press.complete = same && whole;
        }
        if press.complete {
            // How far the ball went since the last press by this cone (none the first time).
            let dz = press.pressed.map_or(0.0, |a0| (a1 - a0).max(0.0));
            let mut all = true;
            while let Some(r) = press.reach(&self.pos, rest, a1, all) {
                press.cone.grow(self, r + dz);
                all = false;
            }
        } else {
            let (base, flags, pos) = (press.base, &self.flags[..n], &self.pos[..n]);
            // (Heights the other way up: an element moves where its cone height lies above it.)
            let moves =
                |u: usize, du: f32| (a1 - base) - du - rest[u][2] > -pos[u][2] && flags[u] & FIXED == 0;
            press.cone.search_moving(self, moves);
        }
        press.scan(&self.flags, rest);
        let stop = press.fixed.iter().fold(f32::INFINITY, |m, &p| {
            let p = p as usize;
            m.min(-self.pos[p][2] - press.height(rest, 0.0, press.cone.dist[p], p))
        });
        a1 = a1.min(stop);
        let dz = press.pressed.map_or(0.0, |a0| a1 - a0);
        press.pressed = Some(a1);
        ws.fit(self);
        ws.next_generation();
        ws.lift.forget();
        let simd = ws.simd();
        let (stamp, old, sponsor, moved) = (&mut ws.stamp, &mut ws.old, &mut ws.sponsor, &mut ws.moved);
        let tent = Tent {
            pos: &mut self.pos[..n],
            lift_at: &press.lift_at[..n],
            b1: -(a1 - press.base),
            dz: -dz,
            slack: 1e-3 * dz.abs(),
            marks: Marks { stamp, old, sponsor, moved, generation: ws.generation },
        };
        let rigid = tent.write::<true>(&press.blocks, simd);
        ws.lift.unlisted_count = rigid;
        if rigid + ws.moved.len() > 0 {
            self.note_motion();
        }
        Some((ws.moved.len() + rigid) as u32)
    }
}

/// The write of a lift: every element of the blocks the cone has settled goes to
/// `max(z, b1 + lift_at)`, and those that rose by other than `dz` (beyond `slack`) are listed as
/// moved (their marks in the workspace, in memory order).
struct Tent<'a> {
    pos: &'a mut [[f32; 3]],
    lift_at: &'a [f32],
    /// The highest seed's height over the cone's base.
    b1: f32,
    dz: f32,
    slack: f32,
    marks: Marks<'a>,
}

/// The workspace's marks of a moved element.
struct Marks<'a> {
    stamp: &'a mut [u32],
    old: &'a mut [[f32; 3]],
    sponsor: &'a mut [u32],
    moved: &'a mut Vec<u32>,
    generation: u32,
}

impl Marks<'_> {
    /// Lists element `j`, at `was` before it rose.
    #[inline(always)]
    fn list(&mut self, j: usize, was: [f32; 3]) {
        if let (Some(s), Some(o), Some(p)) =
            (self.stamp.get_mut(j), self.old.get_mut(j), self.sponsor.get_mut(j))
        {
            (*s, *o, *p) = (self.generation, was, j as u32);
        }
        self.moved.push(j as u32);
    }
}

impl Tent<'_> {
    /// Writes the blocks whose bits are set, at the widest level `simd` allows (the same heights,
    /// lists and count at every level); returns how many elements rose with the seeds.
    /// With `DOWN` (a press) every element goes to `min(z, b1 + lift_at)` instead.
    fn write<const DOWN: bool>(self, blocks: &[u64], simd: super::SimdLevel) -> usize {
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = simd.v3() {
            return pulp::Simd::vectorize(v3, TentV3::<DOWN> { tent: self, blocks, v3 });
        }
        let _ = simd;
        self.write_plain::<DOWN>(blocks)
    }

    /// The plain path: element by element.
    fn write_plain<const DOWN: bool>(mut self, blocks: &[u64]) -> usize {
        let n = self.pos.len();
        let mut rigid = 0;
        for b in block_indices(blocks) {
            rigid += self.elements::<DOWN>(b * BLOCK..((b + 1) * BLOCK).min(n));
        }
        rigid
    }

    /// Writes `range` element by element.
    #[inline(always)]
    fn elements<const DOWN: bool>(&mut self, range: std::ops::Range<usize>) -> usize {
        let (b1, dz, slack) = (self.b1, self.dz, self.slack);
        let mut rigid = 0;
        for j in range {
            let (Some(p), Some(&l)) = (self.pos.get_mut(j), self.lift_at.get(j)) else { break };
            let (new, z) = (b1 + l, p[2]);
            if if DOWN { new < z } else { new > z } {
                if (new - z - dz).abs() > slack {
                    let was = *p;
                    p[2] = new;
                    self.marks.list(j, was);
                } else {
                    rigid += 1;
                    p[2] = new;
                }
            }
        }
        rigid
    }
}

/// The indices of the set bits of `blocks`, in order.
fn block_indices(blocks: &[u64]) -> impl Iterator<Item = usize> + '_ {
    blocks.iter().enumerate().flat_map(|(w, &bits)| {
        let mut x = bits;
        std::iter::from_fn(move || {
            (x != 0).then(|| {
                let b = w * 64 + x.trailing_zeros() as usize;
                x &= x - 1;
                b
            })
        })
    })
}

/// The write with AVX2, eight elements (three registers of their positions as they lie) at a time:
/// the heights `b1 + lift_at` are spread to the third lane of each element's three, the other lanes
/// infinitely low, so that a lane-wise maximum writes the heights and leaves the rest as they were;
/// the comparisons are the plain path's, lane by lane.
#[cfg(target_arch = "x86_64")]
struct TentV3<'a, 'b, const DOWN: bool> {
    tent: Tent<'a>,
    blocks: &'b [u64],
    v3: pulp::x86::V3,
}

#[cfg(target_arch = "x86_64")]
impl<const DOWN: bool> pulp::WithSimd for TentV3<'_, '_, DOWN> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> usize {
        use core::arch::x86_64::{__m256, _CMP_GT_OQ, _CMP_LT_OQ};
        let TentV3 { mut tent, blocks, v3 } = self;
        let (avx, avx2) = (v3.avx, v3.avx2);
        let n = tent.pos.len();
        // Where each element's height goes among the 24 lanes: lanes 2, 5, .. 23 of the three
        // registers take elements 0 to 7.
        let spread = [
            avx._mm256_setr_epi32(0, 0, 0, 0, 0, 1, 0, 0),
            avx._mm256_setr_epi32(2, 0, 0, 3, 0, 0, 4, 0),
            avx._mm256_setr_epi32(0, 5, 0, 0, 6, 0, 0, 7),
        ];
        // (A press's lanes other than the heights are infinitely high, its comparison and write the
        // other way.)
        let low = avx._mm256_set1_ps(if DOWN { f32::INFINITY } else { f32::NEG_INFINITY });
        let (b1, dz, slack) =
            (avx._mm256_set1_ps(tent.b1), avx._mm256_set1_ps(tent.dz), avx._mm256_set1_ps(tent.slack));
        let magnitude = avx._mm256_castsi256_ps(avx._mm256_set1_epi32(0x7fff_ffff));
        let mut rigid = 0usize;
        let fetch = Prefetch::new(SimdLevel::Avx2);
        let mut order = block_indices(blocks).peekable();
        while let Some(b) = order.next() {
            // Blocks follow each other with gaps, each too short a run for the hardware to fetch
            // ahead of: the next block's lines are asked for while this one is written.
            if let Some(&c) = order.peek() {
                let c = c * BLOCK;
                for k in (0..BLOCK).step_by(16) {
                    fetch.at(tent.lift_at, c + k);
                }
                for k in (0..BLOCK).step_by(5) {
                    fetch.at(tent.pos, c + k);
                }
            }
            let end = ((b + 1) * BLOCK).min(n);
            let mut j = b * BLOCK;
            while j + 8 <= end {
                let (Some(l), Some(p)) = (
                    tent.lift_at.get(j..).and_then(<[f32]>::first_chunk::<8>),
                    tent.pos.get(j..).and_then(<[[f32; 3]]>::first_chunk::<8>),
                ) else {
                    break;
                };
                let l = avx._mm256_add_ps(b1, pulp::cast(*l));
                let was: [__m256; 3] = pulp::cast(*p);
                // (No closures here: they would not inherit the instruction set `vectorize` enables.)
                let new0 =
                    avx._mm256_blend_ps::<0b0010_0100>(low, avx2._mm256_permutevar8x32_ps(l, spread[0]));
                let new1 =
                    avx._mm256_blend_ps::<0b0100_1001>(low, avx2._mm256_permutevar8x32_ps(l, spread[1]));
                let new2 =
                    avx._mm256_blend_ps::<0b1001_0010>(low, avx2._mm256_permutevar8x32_ps(l, spread[2]));
                let rise = if DOWN {
                    (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_LT_OQ>(new0, was[0])) as u32)
                        | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_LT_OQ>(new1, was[1])) as u32) << 8
                        | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_LT_OQ>(new2, was[2])) as u32) << 16
                } else {
                    (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(new0, was[0])) as u32)
                        | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(new1, was[1])) as u32) << 8
                        | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(new2, was[2])) as u32) << 16
                };
                if rise == 0 {
                    j += 8;
                    continue;
                }
                let d0 = avx._mm256_and_ps(avx._mm256_sub_ps(avx._mm256_sub_ps(new0, was[0]), dz), magnitude);
                let d1 = avx._mm256_and_ps(avx._mm256_sub_ps(avx._mm256_sub_ps(new1, was[1]), dz), magnitude);
                let d2 = avx._mm256_and_ps(avx._mm256_sub_ps(avx._mm256_sub_ps(new2, was[2]), dz), magnitude);
                let off = (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(d0, slack)) as u32)
                    | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(d1, slack)) as u32) << 8
                    | (avx._mm256_movemask_ps(avx._mm256_cmp_ps::<_CMP_GT_OQ>(d2, slack)) as u32) << 16;
                let list = rise & off;
                rigid += (rise.count_ones() - list.count_ones()) as usize;
                let mut x = list;
                while x != 0 {
                    let k = (x.trailing_zeros() / 3) as usize;
                    x &= x - 1;
                    if let Some(&w) = p.get(k) {
                        tent.marks.list(j + k, w);
                    }
                }
                let out: [__m256; 3] = if DOWN {
                    [
                        avx._mm256_min_ps(new0, was[0]),
                        avx._mm256_min_ps(new1, was[1]),
                        avx._mm256_min_ps(new2, was[2]),
                    ]
                } else {
                    [
                        avx._mm256_max_ps(new0, was[0]),
                        avx._mm256_max_ps(new1, was[1]),
                        avx._mm256_max_ps(new2, was[2]),
                    ]
                };
                if let Some(p) = tent.pos.get_mut(j..).and_then(<[[f32; 3]]>::first_chunk_mut::<8>) {
                    *p = pulp::cast(out);
                }
                j += 8;
            }
            rigid += tent.elements::<DOWN>(j..end);
        }
        rigid
    }
}

/// How far a seed may lie from where its offset hangs it, in the lattice's units (metres): a few
/// rounding errors of a height.
const HANG: f32 = 1e-9;

/// The reference for [`Cone`]: each element's least distance from `seeds` over the same edges, found
/// by sweeping every element's edges until no distance falls (infinite where unreachable).
pub fn distances_plain(body: &Body, seeds: &[ElementId]) -> Vec<f32> {
    let n = body.pos.len();
    let mut d = vec![f32::INFINITY; n];
    for s in seeds {
        if let Some(x) = d.get_mut(s.index()) {
            *x = 0.0;
        }
    }
    let mut changed = true;
    while changed {
        changed = false;
        for u in 0..n {
            let du = d[u];
            if du.is_infinite() {
                continue;
            }
            let slots = (u * body.width..(u + 1) * body.width)
                .map(|k| (body.slot_nbr[k], body.classes[body.slot_class[k] as usize].bounds[1][2]));
            for (y, hi) in slots.chain(body.pairs.row(u).map(|(y, [_, hi])| (y, hi))) {
                let Some(wt) = weight(hi) else { continue };
                let (y, nd) = (y as usize, du + wt);
                if y != u && y < n && nd < d[y] {
                    d[y] = nd;
                    changed = true;
                }
            }
        }
    }
    d
}

/// The reference for a press ([`ConeLift::pressing`]): the heights when every seed goes to
/// `min(z, goal)` and every bound along the normal pushes the element it bounds down as far as it
/// must (`z[y] <= z[u] - lo` for each slot and pair of `u`), swept over every element until nothing
/// falls. Fixed elements are treated as free: compare only presses that do not reach them.
pub fn press_plain(body: &Body, seeds: &[(ElementId, f32)]) -> Vec<f32> {
    let n = body.pos.len();
    let mut z: Vec<f32> = body.pos.iter().map(|p| p[2]).collect();
    for &(s, g) in seeds {
        if let Some(x) = z.get_mut(s.index()) {
            *x = x.min(g);
        }
    }
    let mut changed = true;
    while changed {
        changed = false;
        for u in 0..n {
            let zu = z[u];
            let slots = (u * body.width..(u + 1) * body.width)
                .map(|k| (body.slot_nbr[k], body.classes[body.slot_class[k] as usize].bounds[0][2]));
            for (y, lo) in slots.chain(body.pairs.row(u).map(|(y, [lo, _])| (y, lo))) {
                let y = y as usize;
                if y != u && y < n && lo.is_finite() && zu - lo < z[y] {
                    z[y] = zu - lo;
                    changed = true;
                }
            }
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::super::{Body, BreakReason, ElementId, Lattice, LinkId, Material, SimdLevel};
    use super::{BLOCK, Cone, Marks, Tent, distances_plain};

    /// A soft sheet of `n × n`, spacing `d`, shear limit `shear`.
    fn sheet(n: usize, d: f32, shear: f32) -> Body {
        Body::new(Lattice::sheet(n, n, d).expect("sheet"), Material::relative(1.2, 0.8, shear)).expect("body")
    }

    /// The meninges' two layers at `res` (links, fibres and normal pairs, two materials), with the
    /// links crossing a line cut.
    fn meninges(res: [u32; 2]) -> Body {
        let scene = crate::scene::Scene::from_str(include_str!("../../scenes/meninges.ron"), "meninges.ron")
            .expect("scene")
            .with_resolution(res[0], res[1]);
        let world = scene.build_world(false).expect("world");
        let mut body = world.tissue().body().clone();
        let nx = res[0] as usize;
        for l in 0..body.link_count() {
            let id = LinkId(l as u32);
            let [a, b] = body.lattice().link_ends(id).expect("link");
            let (ia, ib) = (a.index() % nx, b.index() % nx);
            let (ja, jb) = (a.index() / nx, b.index() / nx);
            // A cut across a third of the first layer, a quarter of the way along.
            if a.index() < body.element_count() / 2
                && ia.min(ib) < nx / 4
                && ia.max(ib) >= nx / 4
                && ja.min(jb) > res[1] as usize / 3
            {
                body.break_link(id, BreakReason::Cut).expect("cut");
            }
        }
        body
    }

    /// Every element the cone settles within a radius has the reference's distance, to the bit, and
    /// every element the reference puts within the radius is settled; grown in pieces, the cone settles
    /// the same elements with the same distances as grown at once.
    #[test]
    fn the_cone_is_the_plain_distances() {
        let body = meninges([40, 30]);
        let n = body.element_count();
        for seeds in [vec![n / 4 + 20], vec![n / 4 + 20, n / 4 + 21, n / 4 + 60, n / 4 + 61], vec![0, n - 1]]
        {
            let seeds: Vec<ElementId> = seeds.into_iter().map(|e| ElementId(e as u32)).collect();
            let plain = distances_plain(&body, &seeds);
            let far = plain.iter().copied().filter(|d| d.is_finite()).fold(0.0f32, f32::max);
            assert!(far > 0.0, "the seeds reach something");
            let mut cone = Cone::new();
            for radius in [0.0, far / 3.0, far] {
                cone.start(&body, &seeds);
                let settled = cone.grow(&body, radius);
                let within = plain.iter().filter(|&&d| d <= radius).count();
                assert_eq!(settled, within, "radius {radius}: settled against the reference's count");
                for (e, &d) in plain.iter().enumerate() {
                    let got = cone.distance(ElementId(e as u32));
                    assert_eq!(
                        got,
                        (d <= radius && d.is_finite()).then_some(d),
                        "element {e}, radius {radius}"
                    );
                }
                let order: Vec<f32> = cone.settled().map(|e| plain[e.index()]).collect();
                assert!(order.is_sorted(), "settled in order of distance");
            }
            let mut pieces = Cone::new();
            pieces.start(&body, &seeds);
            let mut total = 0;
            for k in 1..=7 {
                total += pieces.grow(&body, far * k as f32 / 7.0);
            }
            assert_eq!(total, n - plain.iter().filter(|d| d.is_infinite()).count());
            let whole: Vec<_> = cone.settled().collect();
            assert_eq!(pieces.settled().collect::<Vec<_>>(), whole, "grown in pieces");
        }
    }

    /// A growth cut short by a budget (`Cone::grow_within`, a lift's growth spread over steps) settles
    /// a prefix of the whole growth's order, answers distances for what it settled nearer than the
    /// last it settled and for nothing it did not settle, and, called again until it reaches the radius, settles the same elements in the same order with
    /// the same distances as one growth.
    #[test]
    fn a_growth_cut_short_goes_on_where_it_stopped() {
        let body = meninges([40, 30]);
        let n = body.element_count();
        let seeds: Vec<ElementId> =
            [n / 4 + 20, n / 4 + 21, n / 4 + 60].into_iter().map(|e| ElementId(e as u32)).collect();
        let plain = distances_plain(&body, &seeds);
        let far = plain.iter().copied().filter(|d| d.is_finite()).fold(0.0f32, f32::max);
        let mut whole = Cone::new();
        whole.start(&body, &seeds);
        whole.grow(&body, far * 0.6);
        let order: Vec<ElementId> = whole.settled().collect();
        assert!(order.len() > 500, "{} settled", order.len());
        for budget in [1, 7, 100, 499] {
            let mut cone = Cone::new();
            cone.start(&body, &seeds);
            let mut calls = 0;
            loop {
                let (settled, reached) = cone.grow_within(&body, far * 0.6, budget);
                calls += 1;
                assert!(settled <= budget, "budget {budget}: {settled} settled in one call");
                let so_far: Vec<ElementId> = cone.settled().collect();
                assert_eq!(so_far[..], order[..so_far.len()], "budget {budget}: a prefix of the order");
                let mut is_settled = vec![false; n];
                for e in &so_far {
                    is_settled[e.index()] = true;
                }
                // (Elements as far as the last settled may wait on the heap beside it: those settled
                // at that distance answer at the next call.)
                let last = so_far.last().map_or(f32::NEG_INFINITY, |e| plain[e.index()]);
                for (e, &d) in plain.iter().enumerate() {
                    let got = cone.distance(ElementId(e as u32));
                    if is_settled[e] && (d < last || reached) {
                        assert_eq!(got, Some(d), "budget {budget}, call {calls}: element {e}");
                    } else if !is_settled[e] {
                        assert_eq!(got, None, "budget {budget}, call {calls}: element {e}");
                    }
                }
                if reached {
                    break;
                }
                assert_eq!(settled, budget, "cut short only by the budget");
            }
            assert_eq!(cone.settled().collect::<Vec<_>>(), order, "budget {budget}");
            assert!(calls >= order.len().div_ceil(budget), "budget {budget}: {calls} calls");
        }
    }

    /// On a uniform sheet (no pairs) an element `k` links from the seed along an axis is `k` shear
    /// limits away, and one `i` and `j` links off along both is `i + j` of them (the lattice's own
    /// metric); a cut link is no way through, and a cone started again forgets the last one.
    #[test]
    fn a_sheet_s_cone_is_its_lattice_metric() {
        let (n, d, shear) = (21usize, 0.001f32, 0.3f32);
        let mut body = sheet(n, d, shear);
        let c = n / 2 + n * (n / 2);
        let mut cone = Cone::new();
        cone.start(&body, &[ElementId(c as u32)]);
        cone.grow(&body, f32::INFINITY);
        let step = shear * d;
        for (i, j) in [(1, 0), (0, 3), (4, 4), (10, 2)] {
            let e = ElementId((c + i + n * j) as u32);
            let want = (i + j) as f32 * step;
            let got = cone.distance(e).expect("settled");
            assert!((got - want).abs() <= 1e-6 * want.max(step), "({i}, {j}): {got} against {want}");
        }
        // Cut every link from the seed's row to the next: the rows above are out of reach.
        let row = c / n;
        for l in 0..body.link_count() {
            let id = LinkId(l as u32);
            let [a, b] = body.lattice().link_ends(id).expect("link");
            if (a.index() / n).min(b.index() / n) == row && a.index() / n != b.index() / n {
                body.break_link(id, BreakReason::Cut).expect("cut");
            }
        }
        cone.start(&body, &[ElementId(c as u32)]);
        cone.grow(&body, f32::INFINITY);
        assert_eq!(cone.distance(ElementId((c + n) as u32)), None, "no way across a whole cut row");
        let plain = distances_plain(&body, &[ElementId(c as u32)]);
        assert!(plain[c + n].is_infinite());
        assert_eq!(cone.distance(ElementId((c + 1) as u32)), Some(plain[c + 1]));
    }

    /// What a lift's write leaves: the positions' bits, the count of elements that rose with the
    /// seeds, the moved list and the moved elements' marks.
    type Written = (Vec<[u32; 3]>, usize, Vec<u32>, Vec<(u32, [u32; 3], u32)>);

    /// A lift's write at `level` over `heights` (each element's height and its `lift_at`, the
    /// second absent for an element outside the cone); with `down`, a press's (`dz` below zero).
    fn written(
        level: SimdLevel,
        heights: &[(f32, Option<f32>)],
        blocks: &[u64],
        b1: f32,
        dz: f32,
        down: bool,
    ) -> Written {
        let n = heights.len();
        let mut pos: Vec<[f32; 3]> =
            heights.iter().enumerate().map(|(j, &(z, _))| [j as f32, 0.5, z]).collect();
        let still = if down { f32::INFINITY } else { f32::NEG_INFINITY };
        let lift_at: Vec<f32> = heights.iter().map(|&(_, l)| l.unwrap_or(still)).collect();
        let (mut stamp, mut old, mut sponsor, mut moved) =
            (vec![0; n], vec![[0.0; 3]; n], vec![0; n], Vec::new());
        let marks = Marks {
            stamp: &mut stamp,
            old: &mut old,
            sponsor: &mut sponsor,
            moved: &mut moved,
            generation: 7,
        };
        let tent = Tent { pos: &mut pos, lift_at: &lift_at, b1, dz, slack: 1e-3 * dz.abs(), marks };
        let rigid = if down { tent.write::<true>(blocks, level) } else { tent.write::<false>(blocks, level) };
        let bits = |p: [f32; 3]| p.map(f32::to_bits);
        let marks =
            moved.iter().map(|&j| (stamp[j as usize], bits(old[j as usize]), sponsor[j as usize])).collect();
        (pos.into_iter().map(bits).collect(), rigid, moved, marks)
    }

    proptest! {
        /// The write of a lift with AVX2 (eight elements a time) gives the plain path's heights,
        /// lists, marks and count to the bit: elements that rise with the seeds, by less, not at all,
        /// outside the cone, in blocks the cone has or has not settled, and a last block cut short;
        /// and the same for a press (the probe's), everything the other way up.
        #[test]
        fn the_vector_write_is_the_plain_write(
            heights in proptest::collection::vec(
                (0u8..4, -2.0f32..2.0, proptest::option::weighted(0.8, -2.0f32..2.0)),
                1..5 * BLOCK,
            ),
            blocks in any::<u64>(),
            b1 in -1.0f32..1.0,
            dz in 1e-4f32..0.5,
            down in any::<bool>(),
        ) {
            let dz = if down { -dz } else { dz };
            // Heights on the cone before the rise (so that most rise by `dz` exactly), over it, or
            // anywhere.
            let heights: Vec<(f32, Option<f32>)> = heights
                .iter()
                .map(|&(kind, z, l)| match (kind, l) {
                    (0 | 1, Some(l)) => ((b1 - dz) + l, Some(l)),
                    (2, Some(l)) => (b1 + l + if down { -z.abs() } else { z.abs() }, Some(l)),
                    _ => (z, l),
                })
                .collect();
            let blocks = [blocks | 1];
            let plain = written(SimdLevel::Scalar, &heights, &blocks, b1, dz, down);
            let vector = written(SimdLevel::Avx2, &heights, &blocks, b1, dz, down);
            prop_assert_eq!(plain, vector);
        }
    }
}
