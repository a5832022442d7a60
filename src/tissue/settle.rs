//! The disturbed region, kept proportional to what changes: relaxation sweeps only the region (in
//! place, so that it never takes a link out of its limits) and
//! notes how far each element moved in its last sweep; at the end of the step the region keeps only
//! the elements that still move (more than [`SETTLED`]) and their neighbours, so it shrinks again as
//! the tissue settles, and relaxation, contact and the tear check cost what is still moving.

use super::{RegionScan, Tissue, scan};
#[cfg(all(debug_assertions, not(feature = "count-allocations")))]
use crate::chainmail::LinkId;
use crate::chainmail::{ElementId, RelaxBudget, RelaxReport};

/// An element that moved less than this in its last relaxation sweep (metres, lattice units) has
/// settled: a tenth of a micrometre, far below what a trainee can see or an instrument feel.
pub const SETTLED: f32 = 1e-7;

/// Most element updates one step's relaxation makes: a region of up to a quarter of this gets the
/// budget's sweeps, a larger one fewer (as many whole sweeps as fit), and one larger than this a part
/// of a sweep, continued from where the last step stopped (the region is in element order, so the
/// sweep goes round it over the next steps). A step then costs a bounded amount however much of the
/// sheet a lift disturbs (the sweep runs about 330 instructions an update; in the careful exercise's
/// early lift on a 2.45 GHz AVX2 machine, 2026-11-25, the phase took about 30 ns an update at
/// 128 x 96 and 85 ns at 256 x 192, whose region outgrows the caches), and the region, kept
/// until it converges, goes on relaxing over the next steps: the chain reaction and the limits' repair
/// after contact (`limits.rs`) put every element within its links' limits, so an element not reached
/// this step is only less smooth, never out of its limits. Counted in updates, not time, so that runs
/// stay bit for bit reproducible.
pub const REGION_UPDATES: usize = 1 << 13;

/// Fewest element updates one step's relaxation makes: a step whose chain reactions moved many
/// elements (a lift raising the whole tent) has done much of its work already, so its relaxation gets
/// [`REGION_UPDATES`] less what they moved, but never less than this; the region keeps relaxing over
/// the next, quieter steps.
pub const REGION_UPDATES_LEAST: usize = REGION_UPDATES / 4;

impl Tissue {
    /// Damped Gauss-Seidel sweeps over the disturbed region within `budget` and [`REGION_UPDATES`]
    /// (the element update of
    /// [`crate::chainmail::Body::relax_elements`], applied in place in the region's order), noting
    /// each element's move in the last sweep.
    pub(crate) fn relax_region(&mut self, budget: RelaxBudget) -> RelaxReport {
        self.ws.fit(&self.body);
        if self.filling() {
            self.settle_fill();
        }
        self.order_region();
        self.last_move.resize(self.body.element_count(), 0.0);
        // The step's chain reactions have done part of its work already.
        let updates = REGION_UPDATES.saturating_sub(self.step_moved).max(REGION_UPDATES_LEAST);
        // An elastic cell's update reads 26 neighbours' blocks, about ten times a link's: half the
        // updates keep a 16³ volume's step under a millisecond (`relax/elastic.rs`).
        let updates = if self.body.has_elastic() { updates / 2 } else { updates };
        // Settling tissue shares the updates with the coarse correction (once the release's fill has
        // found the whole of what settles). Not while the forceps clamp part of the tissue (the probe
        // used beside a grasp, two-handed): the correction's places take no account of what the clamp
        // holds, and beside it they put links out of their boxes that the limits' repair, bouncing
        // against the clamp, cannot bring back (`tests/tissue_limits.rs`,
        // `a_clamped_drag_keeps_its_limits_while_the_probe_is_used`). The sweeps, which keep every
        // link within its box, bring such tissue back alone.
        // (Nor while the probe's ball holds what it touches: `press.rs`; found by
        // `tests/tissue_limits.rs`, `a_fast_deep_probe_keeps_the_limits`.)
        // (Nor in a volume with elastic cells: the correction's coarse operator is the links'
        // Laplacian, not the cells' elasticity; its sweeps alone settle such a volume.)
        let correcting =
            self.settling && self.jaws.held.is_empty() && !self.probe.holding && !self.body.has_elastic();
        let updates = if correcting && !self.filling() { updates / 2 } else { updates };
        if correcting && self.coarse.placing() {
            // The correction is placing the region's elements: sweeps now would be undone when the
            // places are written, so the step's updates are the correction's.
            let mut report = RelaxReport { converged: false, ..RelaxReport::default() };
            self.settle_work(2 * updates, &mut report);
            // Nothing swept: unless the correction's places were written too, nothing has moved.
            self.swept = Some((0, 0));
            return report;
        }
        let sweeps = (updates / self.active.len().max(1)).max(1);
        let budget = RelaxBudget { max_sweeps: budget.max_sweeps.min(sweeps as u32), ..budget };
        // A region larger than the step's updates: the next `updates` elements from the cursor,
        // round the region (in element order), and no claim of convergence.
        let (start, len) = if self.active.len() > updates {
            let cursor = self.relax_cursor;
            let at = self.active.partition_point(|e| e.0 < cursor);
            (if at == self.active.len() { 0 } else { at }, updates)
        } else {
            (0, self.active.len())
        };
        let partial = len < self.active.len();
        self.swept = (self.settling && partial).then_some((start, len));
        if partial {
            let last = self.active[(start + len - 1) % self.active.len()];
            self.relax_cursor = last.0 + 1;
        }
        let (head, tail) = self.active.split_at(start);
        // The sweep goes round the region: from `start` to its end, then from its beginning.
        let part =
            if len <= tail.len() { [&tail[..len], &[][..]] } else { [tail, &head[..len - tail.len()]] };
        let (body, last_move, simd) = (&mut self.body, &mut self.last_move, self.ws.simd());
        // In place (Gauss-Seidel): the element is kept inside its links' boxes around its neighbours'
        // current positions, so links that hold keep holding. A Jacobi sweep moves both ends of a
        // link at once, each within the box around the other's old position, and can leave the link
        // outside its limits.
        let mut report = crate::chainmail::sweeps_within(budget, || body.sweep_region(simd, part, last_move));
        if report.sweeps > 0 {
            body.note_relaxation();
        }
        if self.body.has_elastic() {
            self.grow_elastic_region();
        }
        if partial {
            report.converged = false;
        }
        if correcting && !self.filling() {
            self.settle_work(updates, &mut report);
        } else if self.settling && !self.filling() {
            // (Clamped: the settling still ends after its most steps.)
            self.settle_steps += 1;
            if self.settle_steps >= SETTLE_STEPS {
                self.settling = false;
            }
        }
        report
    }

    /// Makes the coarse correction's aggregates (once per lattice): they follow the links within a
    /// layer, so that no aggregate spans a lifted layer and the one under it.
    pub(crate) fn fit_coarse(&mut self) {
        let kinds = &self.link_kind;
        self.coarse.fit(&self.body, |l| matches!(kinds.get(l), Some(super::LinkKind::Layer(_)) | None));
    }

    /// A step's share of the coarse correction of settling tissue (`updates` of work): the elements
    /// it moves stay in (or join) the region; a correction that moved nothing more than
    /// [`SETTLE_MOVE`] ends the settling, as does [`SETTLE_STEPS`] of it.
    fn settle_work(&mut self, updates: usize, report: &mut RelaxReport) {
        self.fit_coarse();
        let (last_move, in_active, active) = (&mut self.last_move, &mut self.in_active, &mut self.active);
        let (joined, repair) = (&mut self.region_scratch, &mut self.repair);
        joined.clear();
        let work = self.body.coarse_work(&mut self.coarse, active, updates, |i, was, m| {
            repair.note(i as u32, was);
            if let Some(l) = last_move.get_mut(i) {
                *l = l.max(m);
            }
            if let Some(a) = in_active.get_mut(i)
                && !*a
            {
                *a = true;
                joined.push(crate::chainmail::ElementId(i as u32));
            }
        });
        active.append(joined);
        if work.work > 0 {
            self.body.note_relaxation();
            report.converged = false;
        }
        self.settle_steps += 1;
        if work.finished.is_some_and(|m| m <= SETTLE_MOVE) || self.settle_steps >= SETTLE_STEPS {
            self.settling = false;
        }
    }

    /// Puts the disturbed region in element order, so that sweeps (and the contact and tear checks
    /// after them) read memory in order rather than in the order the chain reaction reached it: a
    /// bit per element, set for the region and read back word by word. The elements the step's
    /// chain reactions moved and their neighbours join it here, a word at a time (`grow.rs`), as
    /// [`Tissue::take_moved`] would have put them in one by one before.
    fn order_region(&mut self) {
        let n = self.body.element_count();
        // (The moved elements' bits are sized for the body, as the growth's masks are; if they ever
        // were not, the plain path puts them in.)
        if self.moved_pending && self.moved_bits.words() != n.div_ceil(64) {
            self.take_moved();
        }
        // (Empty: the last call took every bit out.)
        let bits = &mut self.region_bits;
        bits.fit(n);
        // The region is mostly in order already (last step's, in order, and what joined since): a
        // word is gathered while its elements follow one another and written once.
        let (mut word, mut x) = (usize::MAX, 0u64);
        for e in &self.active {
            let w = e.index() / 64;
            if w != word {
                bits.or(word, x);
                (word, x) = (w, 0);
            }
            x |= 1 << (e.index() % 64);
        }
        bits.or(word, x);
        if self.moved_pending {
            self.moved_pending = false;
            // Every element joining is marked as moving (what `take_moved` marks); only elements
            // within both per-element arrays join, as there.
            let last_move = &mut self.last_move[..];
            let within = last_move.len().min(self.in_active.len());
            self.growth.take(self.body.lattice(), &mut self.moved_bits, |w, x| {
                let first = w * 64;
                if x == u64::MAX && first + 64 <= within {
                    last_move[first..first + 64].fill(f32::INFINITY);
                    bits.or(w, x);
                    return;
                }
                // Only elements within both arrays: all of the word's but past the end.
                let y = if first + 64 <= within {
                    x
                } else if first < within {
                    x & ((1u64 << (within - first)) - 1)
                } else {
                    0
                };
                bits.or(w, y);
                let mut y = y;
                while y != 0 {
                    last_move[first + y.trailing_zeros() as usize] = f32::INFINITY;
                    y &= y - 1;
                }
            });
        }
        // (The list taken out of `self` while it is rebuilt, so that its length stays in a register.)
        let mut active = std::mem::take(&mut self.active);
        active.clear();
        let in_active = &mut self.in_active[..];
        // The words with a bit, in order (not every word of the body), left empty.
        bits.drain(|w, word| {
            let first = w * 64;
            // A whole word of the region (most of a large one): its 64 elements at once.
            if word == u64::MAX && first + 64 <= in_active.len() {
                active.extend((first as u32..first as u32 + 64).map(crate::chainmail::ElementId));
                in_active[first..first + 64].fill(true);
                return;
            }
            let mut x = word;
            while x != 0 {
                let e = (w * 64) as u32 + x.trailing_zeros();
                x &= x - 1;
                active.push(crate::chainmail::ElementId(e));
                if let Some(a) = in_active.get_mut(e as usize) {
                    *a = true;
                }
            }
        });
        self.active = active;
    }

    /// An elastic volume's dent or pull spreads by relaxation beyond what the chain reactions moved
    /// (the cells' energy reaches past the links' limits, as an elastic solid's field does): the
    /// neighbours of every element of the region that moved more than [`SETTLED`] in the last sweep
    /// join it. The region then grows as far as the field moves things, and no further, and shrinks
    /// again as they settle (`prune_region`). The links' springs need not: their relaxation stays
    /// within what the chain reactions disturbed.
    fn grow_elastic_region(&mut self) {
        let mut joining = std::mem::take(&mut self.region_scratch);
        joining.clear();
        let lat = self.body.lattice();
        for &e in &self.active {
            let i = e.index();
            if self.last_move.get(i).is_none_or(|&m| m <= SETTLED) {
                continue;
            }
            let (s0, s1) = (lat.adj_start[i] as usize, lat.adj_start[i + 1] as usize);
            for &n in &lat.adj_nbr[s0..s1] {
                if self.in_active.get(n as usize).is_some_and(|&a| !a) {
                    joining.push(crate::chainmail::ElementId(n));
                }
            }
        }
        for &e in &joining {
            self.activate(e.0);
        }
        joining.clear();
        self.region_scratch = joining;
    }

    /// Shrinks the disturbed region to the elements still moving and their neighbours (elements put
    /// in since the last relaxation stay).
    pub(crate) fn prune_region(&mut self) {
        // Settling tissue keeps its region until the correction says it has settled: its sweeps'
        // moves shrink long before the tissue is back (`settle_work`).
        if self.settling {
            return;
        }
        let mut keep = std::mem::take(&mut self.region_scratch);
        keep.clear();
        // The limits' repair's scan of the region found what it keeps, if nothing has moved, been
        // cut or torn since (which would change what moves, or add to the region).
        let scanned = self.scan().is_some();
        if scanned {
            std::mem::swap(&mut keep, &mut self.scan_keep);
        }
        let kept = |e: &&crate::chainmail::ElementId| {
            let i = e.index();
            let moving = |j: usize| self.last_move.get(j).is_some_and(|&m| m > SETTLED);
            let lat = self.body.lattice();
            let (s0, s1) = (lat.adj_start[i] as usize, lat.adj_start[i + 1] as usize);
            moving(i) || lat.adj_nbr[s0..s1].iter().any(|&n| moving(n as usize))
        };
        if !scanned {
            keep.extend(self.active.iter().filter(kept));
        }
        // The plain path beside the scan's (in debug builds, so that every test's steps compare them).
        debug_assert!(
            !scanned || keep.iter().eq(self.active.iter().filter(kept)),
            "the scan's region differs from the plain prune's"
        );
        // What is kept is a subsequence of the region (in its order): one pass over the region, a
        // cursor in what is kept, forgets the rest.
        let mut kept_at = keep.iter().peekable();
        for &e in &self.active {
            if kept_at.next_if_eq(&&e).is_none() {
                if let Some(a) = self.in_active.get_mut(e.index()) {
                    *a = false;
                }
                if let Some(m) = self.last_move.get_mut(e.index()) {
                    *m = 0.0;
                }
            }
        }
        debug_assert!(kept_at.next().is_none(), "the kept elements are not a subsequence of the region");
        std::mem::swap(&mut self.active, &mut keep);
        self.region_scratch = keep;
    }
}

/// Displacement from rest (metres, lattice units) that makes an element part of what a release lets
/// go: a micrometre, far below what a trainee can see.
pub const DISPLACED: f32 = 1e-6;

/// Elements a release's fill visits a step (`Tissue::settle_fill`): about 0.3 ms of work (65 ns an
/// element at 256 x 192 and 512 x 384).
pub const FILL_STEP: usize = 1 << 12;

/// A coarse correction that moves no element more than this (metres) ends a settling: what is left
/// is a few micrometres, and the sweeps go on with it as with any region.
pub const SETTLE_MOVE: f32 = 1e-6;

/// Most steps a settling lasts (5 s at 1 kHz): tissue its links' limits hold away from its
/// equilibrium would otherwise keep the correction going for good.
pub const SETTLE_STEPS: u32 = 5000;

impl Tissue {
    /// Lets the tissue around `seeds` settle: every element joined to a seed through elements
    /// displaced from rest by more than [`DISPLACED`] joins the disturbed region (a tent the forceps
    /// held up, a dent the probe pressed in: found by a fill over the lattice's adjacency, so it costs
    /// what is displaced), and the region's relaxation adds the coarse-grid correction until it
    /// settles (`chainmail/relax/coarse.rs`): released tissue goes back to its equilibrium in about
    /// the same time at every resolution. The chain reactions that put it there left nothing else to
    /// move it back.
    ///
    /// The fill visits [`FILL_STEP`] elements now and as many in each step after it until it is done
    /// (`Tissue::settle_fill`); the sweeps work on what it has found, and the correction waits for
    /// the whole of it.
    pub(crate) fn settle_from(&mut self, seeds: impl IntoIterator<Item = crate::chainmail::ElementId>) {
        if self.is_fem() {
            return;
        }
        let n = self.body.element_count();
        self.fill_bits.clear();
        self.fill_bits.resize(n.div_ceil(64), 0);
        self.fill_stack.clear();
        for e in seeds {
            let i = e.index();
            if i < n && self.fill_bits[i / 64] & (1 << (i % 64)) == 0 {
                self.fill_bits[i / 64] |= 1 << (i % 64);
                self.fill_stack.push(i as u32);
            }
        }
        if !self.fill_stack.is_empty() {
            // A correction under way started from another region: the next one takes this one.
            self.coarse.cancel();
            self.settling = true;
            self.settle_steps = 0;
            self.settle_fill();
        }
    }

    /// Whether a release's fill is still under way (`Tissue::settle_from`).
    pub(crate) fn filling(&self) -> bool {
        self.settling && !self.fill_stack.is_empty()
    }

    /// Goes on with a release's fill: visits up to [`FILL_STEP`] elements, each joining the region,
    /// and queues their displaced neighbours. (All of it in the release's step until 2026-11-29: 1.3 ms
    /// for a 5 mm lift's tent at 256 x 192, 4.1 ms at 512 x 384.)
    pub(crate) fn settle_fill(&mut self) {
        let mut stack = std::mem::take(&mut self.fill_stack);
        let mut found = std::mem::take(&mut self.fill_found);
        found.clear();
        let (pos, rest) = (self.body.positions(), self.body.lattice().rest_positions());
        let displaced = |i: usize| (0..3).any(|c| (pos[i][c] - rest[i][c]).abs() > DISPLACED);
        let lat = self.body.lattice();
        while found.len() < FILL_STEP
            && let Some(i) = stack.pop()
        {
            let i = i as usize;
            found.push(i as u32);
            let (s0, s1) = (lat.adj_start[i] as usize, lat.adj_start[i + 1] as usize);
            for &j in &lat.adj_nbr[s0..s1] {
                let j = j as usize;
                if self.fill_bits[j / 64] & (1 << (j % 64)) == 0 && displaced(j) {
                    self.fill_bits[j / 64] |= 1 << (j % 64);
                    stack.push(j as u32);
                }
            }
        }
        for &i in &found {
            self.activate(i);
        }
        self.fill_stack = stack;
        self.fill_found = found;
    }
}

impl Tissue {
    /// The part of the region this step's sweep went over, if that sweep is all that has moved
    /// elements since the last step's checks: settling tissue (its fill done) whose region is four
    /// times a step's sweep or more (or a step that swept nothing: the correction placing), in a
    /// step in which nothing else moved (the caller asks the limits'
    /// repair whether anything did; contact asks it too). Two slices of the region: the sweep goes
    /// round it.
    pub(crate) fn sweep_window(&self) -> Option<[&[ElementId]; 2]> {
        let (start, len) = self.swept?;
        // (Its links are read element by element, from both ends: over a quarter of the region the
        // region's own scan, from one end and on vectors, costs less.)
        if !self.settling || self.filling() || len.saturating_mul(4) > self.active.len() {
            return None;
        }
        let tail = self.active.get(start..)?;
        Some(if len <= tail.len() {
            [&tail[..len], &[][..]]
        } else {
            [tail, self.active.get(..len - tail.len())?]
        })
    }

    /// The tear check of a step in which only the sweep moved elements ([`Tissue::sweep_window`]):
    /// the links of the elements it swept, from both ends (every link whose length it changed), not
    /// the whole region's; the others are as the last step's checks found them. Stands for the step
    /// as the limits' repair's scan of the region does (`region_scan`): its tears (each once), the
    /// largest stretch (the swept links', or the last figure if that is larger: while tissue settles
    /// the region's figure falls only at a whole scan, a correction's step or contact's) and the drift
    /// (the swept elements'; nothing else moved). Returns false (and does nothing) if the step is
    /// not such a step. (Every step of a settling scanned the whole released tent until 2026-11-29:
    /// 250 us a step at 256 x 192, 620 at 512 x 384.)
    pub(crate) fn scan_sweep_window(&mut self) -> bool {
        let mut tear2 = std::mem::take(&mut self.tear_scratch);
        let mut hits = std::mem::take(&mut self.tear_hits);
        let found = self.sweep_window().map(|window| {
            scan::tear_ratios2_into(&self.body, &mut tear2);
            hits.clear();
            let geometry = self.geometry;
            // (A flat surface's world is its lattice with the axes permuted, to the bit.)
            let flat = matches!(geometry, super::Geometry::Surface(s) if s.is_flat());
            let world = |p| {
                glam::Vec3::from(if flat {
                    crate::surface::Surface::flat_to_world(p)
                } else {
                    geometry.to_world(p)
                })
            };
            let mut out = super::ScanFound::default();
            let mut max2 = 0.0f32;
            for part in window {
                let m = self.scan_region::<false, true>(
                    part,
                    &tear2,
                    &mut hits,
                    world,
                    &super::NO_BOXES,
                    &[],
                    &mut out,
                );
                max2 = max2.max(m);
            }
            let (pos, rest) = (self.body.positions(), self.body.lattice().rest_positions());
            let drift = window.iter().flat_map(|w| w.iter()).fold(0.0f32, |d, e| {
                let (p, r) = (pos[e.index()], rest[e.index()]);
                d.max((p[0] - r[0]).abs().max((p[1] - r[1]).abs()))
            });
            (max2, drift)
        });
        let done = found.is_some();
        if let Some((max2, drift)) = found {
            // A link between two swept elements is met from both.
            hits.sort_unstable_by_key(|l| l.0);
            hits.dedup();
            let key = (self.body.motion(), self.body.revision());
            let max_stretch2 = max2.max(self.max_stretch * self.max_stretch);
            #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
            self.check_sweep_window(&tear2, &hits, max_stretch2);
            self.region_scan = Some(RegionScan { key, max_stretch2, drift });
            self.swept_checks += 1;
        }
        self.tear_hits = hits;
        self.tear_scratch = tear2;
        done
    }

    /// The region's own scan beside the swept elements' (debug builds): every tear it finds is among
    /// theirs, and its largest stretch is no more than the figure they give.
    #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
    fn check_sweep_window(&self, tear2: &[f32], hits: &[LinkId], max_stretch2: f32) {
        let geometry = self.geometry;
        let world = |p| glam::Vec3::from(geometry.to_world(p));
        let (mut full, mut out) = (Vec::new(), super::ScanFound::default());
        let m = self.scan_region::<false, false>(
            &self.active,
            tear2,
            &mut full,
            world,
            &super::NO_BOXES,
            &[],
            &mut out,
        );
        for l in &full {
            debug_assert!(
                hits.binary_search_by_key(&l.0, |h| h.0).is_ok(),
                "the swept elements' tear check missed {l:?}"
            );
        }
        debug_assert!(
            m <= max_stretch2 * (1.0 + 1e-5),
            "the region's largest stretch {m} is over the swept's {max_stretch2}"
        );
    }
}
