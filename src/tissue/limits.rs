//! Limits hold: at the end of a step every intact link the step disturbed is back inside its
//! constraint box.
//!
//! Gibson's chain reaction places each element within the box of its sponsor only. Where an element
//! is reached through several paths at once (a probe pushing the dura deep moves the arachnoid through
//! many fibres, each its own path), or where a group of sources moves together (the forceps' jaws), or
//! where contact writes what is left of a gap directly, a link between two elements moved along
//! different paths can be left outside its box; relaxation, which keeps each element within the
//! intersection of its links' boxes, repairs it only where that intersection is not empty.
//!
//! The repair finishes the chain reaction: the elements the step moved (and nothing else: the cost
//! is what moved) are checked against their links' boxes, coordinate by coordinate; a link outside
//! its box is mended by moving one end the least distance back into the other's box, and the end
//! moved is queued and checked in turn. Which end moves is what the chain reaction would have
//! decided: the one the step moved less in the direction of the excess *follows* the one it moved
//! more (the leader), so the disturbance spreads outward from the instrument, as in the chain
//! reaction; a held end (the forceps' jaws) leads a free one, and a pinned end never moves. The
//! contact between the layers (the upper layer at least `min_gap` above its partner) is one more
//! constraint of the same kind, so the repair never pushes the layers through each other.
//!
//! Per coordinate the boxes are difference constraints, and moving followers towards their leaders
//! is a label-correcting shortest-path pass: it ends with every constraint met wherever followers
//! can meet them. Where they cannot (a follower bounced between leaders: the arachnoid next to its
//! pinned edge under a dura pushed deep, or a layer pressed between a held patch and a lower layer
//! stretched to its pins), an element moved [`BOUNCES`] times stops following and leads instead,
//! outranking the free and held elements and every element that bounced out after it: the
//! stiffness of the pins travels back towards the instrument, and in the end what the instrument
//! moved gives way (a held element slips in the jaws: the pull is cut short, as pins cut a chain
//! reaction short). The rest shape meets every limit with only the pins fixed, so such a placement
//! always exists. The moves of one repair are bounded ([`MOVES_PER_ELEMENT`]); what is left then
//! (never seen in the tests) is checked again next step, and a link past its tear ratio tears.

use super::Tissue;
use crate::chainmail::ElementId;

/// A link is mended when it lies further than this outside its box (a share of the element spacing:
/// a thousandth, 0.3 µm at 256 × 192 on the default scenes, far below what a trainee sees, what the
/// forces feel or what the tear ratios are set against). Not smaller: a tent lifted along `v` links
/// meets `u` links whose spacing differs by a part in a thousand (0.3141 against 0.3137 mm at
/// 256 × 192), which leaves excesses of about 3·10⁻⁴ spacing all down its slope; mending those moved
/// 2 000 to 8 000 elements by under 10⁻³ spacing each in every lifting step, and doubled the
/// exercise's slowest steps.
pub const TOLERANCE: f32 = 1e-3;

/// Most times one element may be moved by one repair before it stops following (it then leads:
/// what it is bounced between must give way instead).
pub const BOUNCES: u16 = 8;

/// The strength of a held element (see [`Tissue::strength`]): under every rank an element that
/// bounced out can have.
const HELD: u32 = 1 << 31;

/// Most element moves of one repair, per element the step moved (and at least [`MIN_MOVES`]): a
/// bound on its cost where the limits cannot all hold and followers would be bounced for ever.
pub const MOVES_PER_ELEMENT: usize = 16;
/// See [`MOVES_PER_ELEMENT`].
pub const MIN_MOVES: usize = 4096;

/// The repair's scratch, sized once per tissue (no step allocates once warmed up).
#[derive(Clone, Debug, Default)]
pub(crate) struct Repair {
    /// Where each element was when the step first moved it (valid where `stamps` holds the current
    /// stamp).
    from: Vec<[f32; 3]>,
    /// The stamp of the step that last moved each element: dense (4 bytes an element), because every
    /// move of a step reads it and a lifting step moves tens of thousands of elements in the chain
    /// reaction's order, not the memory's.
    stamps: Vec<u32>,
    /// The step's stamp (never 0 once a step has started).
    stamp: u32,
    /// The elements the step moved by chain reactions or direct writes, each once.
    pub(crate) suspects: Vec<u32>,
    /// Elements left with a link outside its box at the last repair (checked again next step).
    carry: Vec<u32>,
    /// How many of `suspects` were carried over from the last repair (they come first).
    carried: usize,
    /// The last repair had links to mend (see `Tissue::restore_limits`).
    repaired: bool,
    /// Contact found layers closer than their gap this step (its moves may undo the gaps it checked
    /// earlier, and it leaves pairs with both ends fixed as they are).
    pub(crate) contact: bool,
    queue: Vec<u32>,
    queued: Vec<bool>,
    /// Times each element was moved by the current repair, and its rank once it has bounced
    /// [`BOUNCES`] times (higher ranks bounced out earlier); both reset for those moved.
    bounces: Vec<u16>,
    rank: Vec<u32>,
    bounced: Vec<u32>,
    /// The rank the next element to bounce out gets.
    next_rank: u32,
}

impl Repair {
    pub(crate) fn fit(&mut self, n: usize) {
        if self.from.len() != n {
            use crate::chainmail::touched;
            self.from = touched(n, [0.0; 3]);
            self.stamps = touched(n, 0);
            self.queued = touched(n, false);
            self.bounces = touched(n, 0);
            self.rank = touched(n, 0);
            self.stamp = 1;
            // Each holds an element at most once: room for all of them now, so that no step grows
            // them (a released tent's correction notes every element of it in one step).
            for list in [&mut self.suspects, &mut self.carry] {
                *list = touched(n, 0);
                list.clear();
            }
            self.carried = 0;
        }
    }

    /// Makes every element one of this step's carried suspects: its links are checked against their
    /// boxes whatever the step moves (after a material edit any box may have changed, and nothing
    /// need move for a link to be outside its new one).
    pub(crate) fn suspect_all(&mut self, n: usize) {
        self.fit(n);
        // Carried suspects come first; every element is one, so the step's own moves need not be.
        self.suspects.clear();
        self.suspects.extend(0..n as u32);
        self.carried = n;
    }

    /// Notes that element `e`, at `was` before, is about to move or has moved this step.
    #[inline]
    pub(crate) fn note(&mut self, e: u32, was: [f32; 3]) {
        note_in((&mut self.stamps, &mut self.from, &mut self.suspects), self.stamp, e, was);
    }

    /// [`Repair::note`] for every element of `moved` (in its order) at its position in `old`
    /// (elements `old` has none for are passed over), with the arrays borrowed once: a lift notes
    /// tens of thousands of elements a step.
    pub(crate) fn note_all(&mut self, moved: &[u32], old: &[[f32; 3]]) {
        let stamp = self.stamp;
        let (stamps, from, suspects) = (&mut self.stamps[..], &mut self.from[..], &mut self.suspects);
        for &e in moved {
            if let Some(&was) = old.get(e as usize) {
                note_in((&mut *stamps, &mut *from, &mut *suspects), stamp, e, was);
            }
        }
    }

    /// Whether the step has moved nothing the repair hears of (no chain reaction, contact move or
    /// direct write), and the last repair left nothing to check again.
    pub(crate) fn quiet(&self) -> bool {
        self.suspects.is_empty() && self.carried == 0 && !self.contact && !self.repaired
    }

    /// Starts the next step: what the last one moved is forgotten, what its repair left is kept.
    pub(crate) fn next_step(&mut self) {
        self.suspects.clear();
        self.stamp = self.stamp.wrapping_add(1).max(1);
        if self.stamp == 1 {
            self.stamps.fill(0);
        }
        std::mem::swap(&mut self.suspects, &mut self.carry);
        self.carried = self.suspects.len();
        self.contact = false;
    }

    /// How far element `i` moved this step along coordinate `k` (0 if the step did not move it).
    #[inline]
    fn moved(&self, i: usize, k: usize, p: f32) -> f32 {
        if self.stamps[i] == self.stamp { p - self.from[i][k] } else { 0.0 }
    }
}

impl Tissue {
    /// Brings every intact link the step disturbed back inside its box (see the module's comment).
    /// Returns how many element moves it made.
    pub fn restore_limits(&mut self) -> u32 {
        if self.is_fem() {
            return 0;
        }
        self.take_moved();
        let n = self.body.element_count();
        let mut r = std::mem::take(&mut self.repair);
        r.fit(n);
        let tol = TOLERANCE * self.spacing;
        let pair = (self.layers.len() == 2 && matches!(self.geometry, super::Geometry::Surface(_)))
            .then_some((self.sheet, self.min_gap));
        r.queue.clear();
        r.bounced.clear();
        r.next_rank = u32::MAX - 1;
        r.carry.clear();
        // Only the elements with a link outside its box start the queue; whatever the repair moves
        // joins it. Most steps have none. That is found by the tear check's scan of the region, in
        // memory order (the region holds every element the step moved and their neighbours), which
        // also tests each link there against its box; the layers' gaps hold if contact found none
        // short (it has just checked every element of the region); the last repair's leftovers are
        // checked on their own; and a step in which contact found a gap short (it may have moved
        // elements, and where it wrote them directly the region may lack their neighbours) takes
        // the full path. The scan's tears stand if the repair moves nothing.
        // Repairs come in runs (a lift that keeps pulling against pins): a step after one that
        // repaired goes straight to the full path, where the scan would only have been done twice
        // (the repair's moves make the tear check scan again).
        // Normal pairs (a layer cell's diagonals) are not in the scan: the normal pass meets every
        // pair of what it moves (to a far finer tolerance), relaxation never moves an element out of
        // one, and the pass says when it left one outside (`Body::take_pairs_unmet`).
        let unmet = self.body.take_pairs_unmet() > tol;
        let any = if r.repaired || unmet {
            true
        } else if r.quiet() && self.scan_sweep_window() {
            // Settling tissue whose sweep alone moved part of its region: the sweep keeps every link
            // within its box, and the tear check has looked at the links it moved.
            false
        } else {
            let boxes = super::BoxCheck { tol, stamps: &r.stamps, stamp: r.stamp };
            let found = self.scan_tears(Some(boxes)).1;
            let any = found
                || (r.contact && pair.is_some())
                || r.suspects[..r.carried.min(r.suspects.len())]
                    .iter()
                    .any(|&e| self.violates(e as usize, tol, pair));
            // The plain path beside the scan: every suspect's links, one by one (in debug builds, so
            // that every test's steps compare the two).
            #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
            {
                let plain = r.suspects.iter().any(|&e| self.violates(e as usize, tol, pair));
                debug_assert!(!plain || any, "the tear scan missed a link out of its box");
                debug_assert!(!found || plain, "the tear scan found a link out of its box the suspects lack");
            }
            any
        };
        let seeds = if any { r.suspects.len() } else { 0 };
        for k in 0..seeds {
            let e = r.suspects[k];
            if !r.queued[e as usize] && self.violates(e as usize, tol, pair) {
                r.queued[e as usize] = true;
                r.queue.push(e);
            }
        }
        r.repaired = !r.queue.is_empty();
        let mut moves = 0u32;
        let cap = (MOVES_PER_ELEMENT * r.suspects.len()).max(MIN_MOVES) as u32;
        let mut head = 0;
        while head < r.queue.len() && moves < cap {
            let x = r.queue[head] as usize;
            head += 1;
            r.queued[x] = false;
            let w = self.body.width;
            for t in 0..w {
                let y = self.body.slot_nbr[x * w + t] as usize;
                let [lo, hi] = self.body.classes[self.body.slot_class[x * w + t] as usize].bounds;
                let (px, py) = (self.body.pos[x], self.body.pos[y]);
                // Most links of an element hold: one branch-free test first (padding slots and broken
                // links have infinite boxes and pass it).
                if !outside(px, py, [lo, hi], tol) {
                    continue;
                }
                let mut qx = px;
                let mut qy = py;
                for k in 0..3 {
                    let d = px[k] - py[k];
                    // The signed excess of `p[x] - p[y]` over its range.
                    let over = if d > hi[k] {
                        d - hi[k]
                    } else if d < lo[k] {
                        d - lo[k]
                    } else {
                        continue;
                    };
                    if over.abs() <= tol {
                        continue;
                    }
                    match self.follower(&r, x, y, k, over) {
                        Some(true) => qx[k] = py[k] + (d - over),
                        Some(false) => qy[k] = px[k] - (d - over),
                        None => r.carry.push(x as u32),
                    }
                }
                moves += self.repair_move(&mut r, x, qx) + self.repair_move(&mut r, y, qy);
            }
            // Normal pairs (a cell's diagonals) bound the normal coordinate as links do. (The chain
            // reaction's normal pass meets them already: only direct writes leave them out.)
            let pw = self.body.pairs.width;
            for t in 0..pw {
                let y = self.body.pairs.nbr[x * pw + t] as usize;
                let [lo, hi] = self.body.pairs.bound(x * pw + t);
                let (px, py) = (self.body.pos[x], self.body.pos[y]);
                let d = px[2] - py[2];
                let over = if d > hi + tol {
                    d - hi
                } else if d < lo - tol {
                    d - lo
                } else {
                    continue;
                };
                let (mut qx, mut qy) = (px, py);
                match self.follower(&r, x, y, 2, over) {
                    Some(true) => qx[2] = py[2] + (d - over),
                    Some(false) => qy[2] = px[2] - (d - over),
                    None => r.carry.push(x as u32),
                }
                moves += self.repair_move(&mut r, x, qx) + self.repair_move(&mut r, y, qy);
            }
            // The layers' contact: the upper element at least `min_gap` above its partner.
            if let Some((sheet, gap)) = pair {
                let (l, u) = partners(x, sheet);
                if u < n {
                    let (pl, pu) = (self.body.pos[l], self.body.pos[u]);
                    // `p[l] - p[u]` may be at most `-gap`.
                    let d = pl[2] - pu[2];
                    let over = d + gap;
                    if over > tol {
                        let (mut ql, mut qu) = (pl, pu);
                        match self.follower(&r, l, u, 2, over) {
                            Some(true) => ql[2] = pu[2] - gap,
                            Some(false) => qu[2] = pl[2] + gap,
                            None => r.carry.push(x as u32),
                        }
                        moves += self.repair_move(&mut r, l, ql) + self.repair_move(&mut r, u, qu);
                    }
                }
            }
        }
        // What the repair could not mend (two fixed ends, or the bound on its moves reached) is
        // looked at again next step, after the tear check has had its say.
        for k in head..r.queue.len() {
            let i = r.queue[k];
            r.queued[i as usize] = false;
            r.carry.push(i);
        }
        for &i in &r.bounced {
            r.bounces[i as usize] = 0;
            r.rank[i as usize] = 0;
        }
        if moves > 0 {
            self.body.note_motion();
        }
        if moves > 0 || !r.carry.is_empty() {
            self.settled = false;
        }
        self.repair = r;
        moves
    }

    /// Has this step's repair check every element's links against their boxes: for a material edit,
    /// which may leave links outside their new boxes where nothing moves (an educator tightening the
    /// limits under a held lift). Costs one check of the whole body, once.
    pub fn limits_changed(&mut self) {
        if self.is_fem() {
            return;
        }
        self.repair.suspect_all(self.body.element_count());
        self.settled = false;
    }

    /// Which end of a link (or contact) between `x` and `y` follows the other along coordinate `k`,
    /// where `p[x] - p[y]` lies `over` outside its range: `Some(true)` for `x`, `Some(false)` for
    /// `y`, `None` when neither may move (both pinned).
    #[inline]
    fn follower(&self, r: &Repair, x: usize, y: usize, k: usize, over: f32) -> Option<bool> {
        let (sx, sy) = (self.strength(r, x), self.strength(r, y));
        if sx != sy {
            return Some(sx < sy);
        }
        if sx == u32::MAX {
            return None;
        }
        // As strong as each other (both free, or both held): each end's share of the excess from its
        // own move this step; the larger leads.
        let s = over.signum();
        let lead_x = r.moved(x, k, self.body.pos[x][k]) * s;
        let lead_y = -r.moved(y, k, self.body.pos[y][k]) * s;
        Some(lead_y > lead_x)
    }

    /// How firmly element `i` stays where it is in a repair: a pinned element never moves
    /// (`u32::MAX`); an element that has bounced [`BOUNCES`] times gives way only to pinned elements
    /// and to those that bounced out before it; a held one (the forceps' jaws) leads the free ones
    /// and gives way to those (the tissue slips in the jaws rather than leave its limits: the pull is
    /// cut short, as pins cut a chain reaction short); the free ones (0) follow by how far the step
    /// moved them.
    #[inline]
    fn strength(&self, r: &Repair, i: usize) -> u32 {
        let e = ElementId(i as u32);
        if self.body.is_pinned(e) {
            u32::MAX
        } else if r.rank[i] != 0 {
            r.rank[i]
        } else if self.body.is_held(e) {
            HELD
        } else {
            0
        }
    }

    /// Moves element `i` to `q` for the repair (if `q` differs from where it is): notes it, counts
    /// its bounce, queues it. Returns 1 if it moved.
    fn repair_move(&mut self, r: &mut Repair, i: usize, q: [f32; 3]) -> u32 {
        let p = self.body.pos[i];
        if q == p {
            return 0;
        }
        r.note(i as u32, p);
        self.body.pos[i] = q;
        if r.bounces[i] == 0 {
            r.bounced.push(i as u32);
        }
        r.bounces[i] = r.bounces[i].saturating_add(1);
        if r.bounces[i] == BOUNCES && r.rank[i] == 0 {
            r.rank[i] = r.next_rank;
            r.next_rank = r.next_rank.saturating_sub(1).max(HELD + 1);
        }
        if !r.queued[i] {
            r.queued[i] = true;
            r.queue.push(i as u32);
        }
        self.activate(i as u32);
        1
    }

    /// Whether an intact link of element `i` lies more than `tol` outside its box, or (with `pair`:
    /// the sheet's size and the smallest gap) `i` is closer than the gap to its partner in the other
    /// layer. Broken links and padding slots have infinite boxes and never count.
    #[inline]
    fn violates(&self, i: usize, tol: f32, pair: Option<(u32, f32)>) -> bool {
        let body = &self.body;
        let w = body.width;
        let (nbrs, cls) = (&body.slot_nbr[i * w..(i + 1) * w], &body.slot_class[i * w..(i + 1) * w]);
        let pi = body.pos[i];
        for (&y, &c) in nbrs.iter().zip(cls) {
            if outside(pi, body.pos[y as usize], body.classes[c as usize].bounds, tol) {
                return true;
            }
        }
        for (y, [lo, hi]) in body.pairs.row(i) {
            let d = pi[2] - body.pos[y as usize][2];
            if (d > hi + tol) | (d < lo - tol) {
                return true;
            }
        }
        if let Some((sheet, gap)) = pair {
            let (l, u) = partners(i, sheet);
            if let (Some(pl), Some(pu)) = (body.pos.get(l), body.pos.get(u)) {
                return pl[2] - pu[2] + gap > tol;
            }
        }
        false
    }
}

/// Whether `p[x] - p[y]` lies more than `tol` outside the slot's bounds `[lo, hi]` in any coordinate
/// (branch-free: most links hold; infinite bounds never count).
#[inline(always)]
fn outside(px: [f32; 3], py: [f32; 3], bounds: [[f32; 3]; 2], tol: f32) -> bool {
    beyond(px, py, widen(bounds, tol))
}

/// A slot's bounds `[lo, hi]` widened by `tol` on either side.
#[inline(always)]
pub(crate) fn widen([lo, hi]: [[f32; 3]; 2], tol: f32) -> [[f32; 3]; 2] {
    [lo.map(|x| x - tol), hi.map(|x| x + tol)]
}

/// Whether `p[x] - p[y]` lies outside the (widened) bounds `[lo, hi]` in any coordinate.
#[inline(always)]
pub(crate) fn beyond(px: [f32; 3], py: [f32; 3], [lo, hi]: [[f32; 3]; 2]) -> bool {
    let mut out = false;
    for k in 0..3 {
        let d = px[k] - py[k];
        out |= (d > hi[k]) | (d < lo[k]);
    }
    out
}

/// [`Repair::note`] on the repair's arrays borrowed apart (so that [`Repair::note_all`] borrows them
/// once for a whole reaction's moves).
#[inline(always)]
fn note_in(
    (stamps, from, suspects): (&mut [u32], &mut [[f32; 3]], &mut Vec<u32>),
    stamp: u32,
    e: u32,
    was: [f32; 3],
) {
    if let Some(s) = stamps.get_mut(e as usize)
        && *s != stamp
    {
        *s = stamp;
        if let Some(f) = from.get_mut(e as usize) {
            *f = was;
        }
        suspects.push(e);
    }
}

/// The lower and upper element of the layer pair element `i` belongs to (`sheet` elements apart).
#[inline(always)]
pub(super) fn partners(i: usize, sheet: u32) -> (usize, usize) {
    let s = sheet as usize;
    if i >= s { (i - s, i) } else { (i, i + s) }
}
