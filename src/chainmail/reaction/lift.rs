//! A lift's rigid blocks: the normal pass of a surface (a sheet, or layers joined by fibres) whose
//! seeds rise again as they rose in the last reaction from the same seeds moves the taut part of the
//! tent as one, a block of 8 × 8 elements at a time, and checks element by element only the rim.
//!
//! An element that a completion moved ends on a bound met exactly with the element that moved it,
//! and so on back to the seeds: it hangs from them by a chain of bounds, and an element that rose by
//! the seeds' rise (within a thousandth of it) hangs from them rigidly. When the same seeds rise again
//! and the body's pins, holds, cuts and materials are as they were, such an element rises by the
//! seeds' rise again. So a block whose every element rose with the seeds last time (and holds no fixed
//! element) is raised at once by the seeds' new rise; its elements keep their places relative to each other, so
//! every bound between two raised elements holds as it held. Only bounds that leave a raised block
//! towards an element that was not raised can be newly outside: the raised blocks' edges that face a
//! block not raised, and fibres to a layer's block not raised, are queued for the completion, which
//! treats them as moved (stamped, their old positions kept) and goes on from there as usual.
//!
//! Whatever else moved a raised block's elements since (relaxation, contact, the limits' repair)
//! leaves the raise valid: relative places are kept and every bound leaving the block is checked.
//! It may then move an element more than the least the bounds ask, by what those moves changed.
//!
//! A raised element enters the workspace's moved list only if the completion moves it again: the
//! rest have moved as a body, which strains nothing (`Workspace::raised_unlisted` counts them). A
//! tissue's disturbed region therefore keeps only the rim of a rising tent, not its taut inside.
//!
//! The careful meninges exercise's final lift at 256 × 192 raises about 15 000 of its 19 000 moving
//! elements this way (about 230 blocks) and queues about 2 100 at their rim; its heights agree with
//! the element-by-element completion's to a few nanometres (`tests/chainmail_pairs_reference.rs`).

use crate::chainmail::body::{Body, FIXED};
use crate::chainmail::workspace::Workspace;

/// Side of a block, in elements.
const SIDE: usize = 8;

/// Elements in a block.
const FULL: u16 = (SIDE * SIDE) as u16;

/// A rise is the seeds' when it is within this share of theirs.
const MATCH: f32 = 1e-3;

/// The blocks of a body: `nbx × nby` whole blocks per layer (elements past the last whole block of a
/// row or column are never raised), `nz` layers of `nx × ny` elements.
#[derive(Clone, Copy, Debug)]
struct Grid {
    nx: usize,
    ny: usize,
    nz: usize,
    nbx: usize,
    nby: usize,
}

impl Grid {
    /// The blocks of a surface with normal pairs (one or two layers), if it is one.
    fn of(body: &Body) -> Option<Self> {
        let [nx, ny, nz] = body.lattice.dims?;
        if !body.pairs.any() || nz > 2 || nx < SIDE || ny < SIDE {
            return None;
        }
        Some(Self { nx, ny, nz, nbx: nx / SIDE, nby: ny / SIDE })
    }

    fn blocks(&self) -> usize {
        self.nbx * self.nby * self.nz
    }

    /// Block `b`'s coordinates `(bx, by, layer)`.
    fn coords(&self, b: usize) -> (usize, usize, usize) {
        (b % self.nbx, (b / self.nbx) % self.nby, b / (self.nbx * self.nby))
    }

    fn block(&self, bx: usize, by: usize, k: usize) -> usize {
        bx + self.nbx * (by + self.nby * k)
    }

    /// The element at the first corner of block `b`.
    fn first(&self, b: usize) -> usize {
        let (bx, by, k) = self.coords(b);
        bx * SIDE + self.nx * (by * SIDE + self.ny * k)
    }

    /// The block element `e` lies in, if any.
    fn block_of(&self, e: usize) -> Option<usize> {
        // In 32 bits (element indices are), where division is several times faster.
        let (e, nx, ny) = (u32::try_from(e).ok()?, self.nx as u32, self.ny as u32);
        let (i, rest) = ((e % nx) as usize, e / nx);
        let (j, k) = ((rest % ny) as usize, (rest / ny) as usize);
        let (bx, by) = (i / SIDE, j / SIDE);
        (bx < self.nbx && by < self.nby && k < self.nz).then(|| self.block(bx, by, k))
    }
}

/// What the last large reactions from some seeds raised: per block, whether every element rose with
/// the seeds, under which seeds, lattice and revision, and by how much.
#[derive(Clone, Debug, Default)]
struct Memo {
    seeds: Vec<u32>,
    shape: u64,
    revision: u64,
    rise: f32,
    rose: Vec<u64>,
    used: u64,
}

/// The rigid blocks' scratch and memory, in the workspace.
#[derive(Clone, Debug, Default)]
pub(crate) struct Lift {
    /// Whether reactions raise rigid blocks (the tissue's workspaces do; a plain body's does not
    /// unless asked: `Workspace::set_rigid_blocks`).
    pub(crate) enabled: bool,
    /// One memory per set of seeds (a forceps pull runs two reactions a step: its centre's, then the
    /// rest of its jaws').
    memos: [Memo; 2],
    tick: u64,
    /// This reaction's rigid blocks, a bit each.
    rigid: Vec<u64>,
    /// The elements this reaction raised, block by block.
    pub(crate) raised: Vec<u32>,
    /// A bit per element raised by this reaction, and a bit per raised element the completion has
    /// not moved again (not in the moved list).
    pub(crate) raised_bits: Vec<u64>,
    pub(crate) unlisted: Vec<u64>,
    /// How many raised elements are not in the moved list.
    pub(crate) unlisted_count: usize,
    /// The raised elements the completion must check (their bounds may leave the raised blocks).
    pub(crate) rim: Vec<u32>,
    /// Per block, the elements that rose with the seeds (recording).
    count: Vec<u16>,
    /// Each element's fibre bound on its height over its partner's, widened (`[-inf, inf]` for none):
    /// read from the element's slots once per block and body revision (`fibre_key`), not every step
    /// (the slots' rows are the raise's slowest reads).
    fibre_z: Vec<[f32; 2]>,
    fibre_key: Vec<(u64, u64)>,
}

impl Lift {
    /// Forgets this reaction's raise (its elements are back where they were, or accepted).
    pub(crate) fn clear_reaction(&mut self) {
        if !self.raised.is_empty() {
            self.raised.clear();
            self.raised_bits.fill(0);
            self.unlisted.fill(0);
        }
        self.unlisted_count = 0;
        self.rim.clear();
        self.count.fill(0);
    }
}

/// Whether bit `i` is set (false past the words).
#[inline(always)]
pub(crate) fn has_bit(words: &[u64], i: usize) -> bool {
    words.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
}

/// Sets `len` bits from bit `at` (not past the words).
#[inline(always)]
fn set_bits(words: &mut [u64], at: usize, len: usize) {
    for e in at..at + len {
        if let Some(w) = words.get_mut(e / 64) {
            *w |= 1 << (e % 64);
        }
    }
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

    /// Raises this reaction's rigid blocks by the seeds' rise (see the module's comment) and lists the
    /// raised elements the completion must check in `ws.lift.rim`. `class_z` is the completion's
    /// table of the links' normal bounds per class, widened (`[lo, hi, ..]`, padded to a power of two).
    pub(super) fn raise_rigid(&mut self, ws: &mut Workspace, seeds: &[u32], class_z: &[[f32; 4]]) {
        ws.lift.clear_reaction();
        if !ws.lift.enabled {
            return;
        }
        let Some(grid) = Grid::of(self) else { return };
        let Some(dz) = self.seeds_rise(ws, seeds) else { return };
        let words = grid.blocks().div_ceil(64);
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
        lift.rigid.clear();
        lift.rigid.extend_from_slice(&lift.memos[at].rose);
        let n = self.pos.len();
        // No fixed element in a rigid block (the memory may predate a grasp).
        let flags = &self.flags[..n];
        for b in 0..grid.blocks() {
            if !has_bit(&lift.rigid, b) {
                continue;
            }
            let first = grid.first(b);
            let fixed =
                (0..SIDE).any(|c| flags[first + c * grid.nx..][..SIDE].iter().any(|&f| f & FIXED != 0));
            if fixed {
                lift.rigid[b / 64] &= !(1 << (b % 64)); // not rigid after all
            }
        }
        if lift.rigid.iter().all(|&w| w == 0) {
            return;
        }
        let words_n = n.div_ceil(64);
        if lift.raised_bits.len() != words_n {
            lift.raised_bits = vec![0; words_n];
            lift.unlisted = vec![0; words_n];
        }
        let g = ws.generation;
        let (pos, old, stamp) = (&mut self.pos[..n], &mut ws.old[..n], &mut ws.stamp[..n]);
        let is_rigid = |rigid: &[u64], bx: isize, by: isize, k: usize| -> Option<bool> {
            (bx >= 0 && by >= 0 && (bx as usize) < grid.nbx && (by as usize) < grid.nby)
                .then(|| has_bit(rigid, grid.block(bx as usize, by as usize, k)))
        };
        lift.count.clear();
        lift.count.resize(grid.blocks(), 0);
        for b in 0..grid.blocks() {
            if !has_bit(&lift.rigid, b) {
                continue;
            }
            let first = grid.first(b);
            let mut raised = 0;
            for c in 0..SIDE {
                let row = first + c * grid.nx;
                let r = row..row + SIDE;
                if stamp[r.clone()].iter().all(|&s| s != g) {
                    // The usual row: none moved by the lists.
                    old[r.clone()].copy_from_slice(&pos[r.clone()]);
                    stamp[r.clone()].fill(g);
                    for p in &mut pos[r.clone()] {
                        p[2] += dz;
                    }
                    lift.raised.extend(row as u32..(row + SIDE) as u32);
                    set_bits(&mut lift.raised_bits, row, SIDE);
                    set_bits(&mut lift.unlisted, row, SIDE);
                    raised += SIDE as u16;
                    continue;
                }
                for e in r {
                    // An element the lists moved already is queued as it is.
                    if stamp[e] == g {
                        continue;
                    }
                    old[e] = pos[e];
                    stamp[e] = g;
                    pos[e][2] += dz;
                    lift.raised.push(e as u32);
                    set_bits(&mut lift.raised_bits, e, 1);
                    set_bits(&mut lift.unlisted, e, 1);
                    raised += 1;
                }
            }
            lift.count[b] = raised;
        }
        lift.unlisted_count = lift.raised.len();
        // The rim: the edges of a block beside one not raised (or beside the grid's own edge, which a
        // wrapped axis joins to the other, or its part past the last whole block, never raised), and
        // fibres to the other layer's block, if not raised, whose bound the raise left outside.
        let (w, mask) = (self.width, class_z.len().wrapping_sub(1));
        let (slot_nbr, slot_class) = (&self.slot_nbr[..n * w], &self.slot_class[..n * w]);
        let layer = grid.nx * grid.ny;
        let key = (self.revision, self.boxes_epoch);
        if grid.nz == 2 && (lift.fibre_z.len() != n || lift.fibre_key.len() != grid.blocks()) {
            lift.fibre_z = vec![[f32::NEG_INFINITY, f32::INFINITY]; n];
            lift.fibre_key = vec![(0, 0); grid.blocks()];
        }
        for b in 0..grid.blocks() {
            if !has_bit(&lift.rigid, b) {
                continue;
            }
            let (bx, by, k) = grid.coords(b);
            let (bxi, byi) = (bx as isize, by as isize);
            let mut edge = false;
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    let (x, y) = (bxi + dx, byi + dy);
                    if (dx, dy) != (0, 0) && is_rigid(&lift.rigid, x, y, k) != Some(true) {
                        edge = true;
                    }
                }
            }
            let first = grid.first(b);
            if edge {
                for c in 0..SIDE {
                    let row = first + c * grid.nx;
                    if c == 0 || c == SIDE - 1 {
                        lift.rim.extend(row as u32..(row + SIDE) as u32);
                    } else {
                        lift.rim.push(row as u32);
                        lift.rim.push((row + SIDE - 1) as u32);
                    }
                }
            }
            if grid.nz < 2 || is_rigid(&lift.rigid, bxi, byi, 1 - k) == Some(true) {
                continue;
            }
            // The fibre, if any, joins an element to its place in the other layer.
            let other = if k == 0 { layer as isize } else { -(layer as isize) };
            if lift.fibre_key[b] != key {
                for c in 0..SIDE {
                    let row = first + c * grid.nx;
                    for e in row..row + SIDE {
                        let partner = e.wrapping_add_signed(other);
                        let slots = e * w..e * w + w;
                        let t = slot_nbr[slots.clone()].iter().position(|&y| y as usize == partner);
                        lift.fibre_z[e] = match t {
                            Some(t) => {
                                let [lo, hi, _, _] = class_z[slot_class[slots][t] as usize & mask];
                                [lo, hi]
                            }
                            None => [f32::NEG_INFINITY, f32::INFINITY],
                        };
                    }
                }
                lift.fibre_key[b] = key;
            }
            for c in 0..SIDE {
                let row = first + c * grid.nx;
                for e in row..row + SIDE {
                    let [lo, hi] = lift.fibre_z[e];
                    let d = pos[e][2] - pos[e.wrapping_add_signed(other)][2];
                    if d > hi || d < lo {
                        lift.rim.push(e as u32);
                    }
                }
            }
        }
    }

    /// Remembers, after a reaction that stands, which blocks rose with its seeds (`seeds`: the ones
    /// that moved).
    pub(crate) fn record_rigid(&self, ws: &mut Workspace, seeds: &[u32]) {
        if !ws.lift.enabled {
            return;
        }
        let Some(grid) = Grid::of(self) else { return };
        let rise = self.seeds_rise(ws, seeds).unwrap_or(0.0);
        let blocks = grid.blocks();
        let lift = &mut ws.lift;
        // Each block's count of raised elements (`raise_rigid`) and of elements moved with the seeds.
        lift.count.resize(blocks, 0);
        if rise > 0.0 {
            // A block with an element that moved otherwise is marked past `FULL`.
            const OTHER: u16 = u16::MAX / 2;
            let tol = MATCH * rise;
            for &e in &ws.moved {
                let e = e as usize;
                let Some(b) = grid.block_of(e) else { continue };
                let r = self.pos[e][2] - ws.old[e][2];
                let with = (r - rise).abs() <= tol;
                let raised = has_bit(&lift.raised_bits, e);
                lift.count[b] = match (with, raised) {
                    (true, true) => lift.count[b],
                    (true, false) => lift.count[b].saturating_add(1),
                    (false, _) => OTHER,
                };
            }
        }
        lift.tick += 1;
        let tick = lift.tick;
        // These seeds' memory, or the one used longest ago.
        let slot = lift
            .memos
            .iter()
            .position(|m| m.seeds == seeds)
            .unwrap_or(if lift.memos[0].used <= lift.memos[1].used { 0 } else { 1 });
        let Lift { memos, count, .. } = lift;
        let memo = &mut memos[slot];
        memo.seeds.clear();
        memo.seeds.extend_from_slice(seeds);
        memo.used = tick;
        memo.shape = self.shape;
        memo.revision = self.revision;
        memo.rise = rise;
        memo.rose.clear();
        memo.rose.resize(blocks.div_ceil(64), 0);
        for (b, &c) in count.iter().enumerate() {
            if c == FULL {
                set_bits(&mut memo.rose, b, 1);
            }
        }
    }
}
