//! What a chain reaction reads ([`Slices`]: the body's arrays) and writes ([`Moving`]: positions,
//! the workspace's records and candidate lists), where a run of a candidate list starts, and the
//! checks every path of the reaction shares (the one-by-one loop, the portable chunks and the
//! vector chunks), so that they agree bit for bit.

use crate::chainmail::body::{FIXED, SlotClass};
use crate::chainmail::coords::clamp;
use crate::chainmail::workspace::Workspace;

/// Longest run moved at once.
pub(super) const RUN: usize = 1024;

/// Elements a run checks and writes at once, without branches (a multiple of the vector widths).
pub(super) const CHUNK: usize = 16;

/// The body's read-only arrays the chain reaction uses.
#[derive(Clone, Copy)]
pub(super) struct Slices<'a> {
    pub(super) nbrs: &'a [u32],
    pub(super) classes: &'a [SlotClass],
    pub(super) slot_class: &'a [u32],
    /// The body's class change bits (`Body::class_change`) and words per slot.
    pub(super) class_change: &'a [u64],
    pub(super) class_words: usize,
    pub(super) flags: &'a [u8],
    pub(super) interior: &'a [u8],
    /// `Stencil::across`: elements whose neighbours across rows are at the grid offsets.
    pub(super) across: &'a [u8],
    pub(super) offs: &'a [isize],
    pub(super) width: usize,
}

impl Slices<'_> {
    /// The neighbour of element `e` through adjacency slot `u`: by grid offset for interior elements,
    /// which keeps a load off the chain of dependent loads (list entry, neighbour, its stamp), else
    /// from the adjacency row.
    #[inline(always)]
    pub(super) fn neighbour(&self, e: usize, u: usize) -> usize {
        match (self.interior.get(e), self.offs.get(u)) {
            (Some(1), Some(&o)) => e.wrapping_add_signed(o),
            _ => self.nbrs[e * self.width + u] as usize,
        }
    }
}

/// What a chain reaction writes: the body's positions and, for the elements it moves, their old
/// positions, stamps and sponsors and the moved list, and the candidate lists (`n` entries each, the
/// list of slot `u` ending at `tail[u]`).
pub(super) struct Moving<'a> {
    pub(super) pos: &'a mut [[f32; 3]],
    pub(super) old: &'a mut [[f32; 3]],
    pub(super) stamp: &'a mut [u32],
    pub(super) sponsor: &'a mut [u32],
    pub(super) moved: &'a mut Vec<u32>,
    pub(super) lists: &'a mut [u32],
    pub(super) tail: &'a mut [usize],
    /// The stamp of this reaction's moves.
    pub(super) g: u32,
}

impl<'a> Moving<'a> {
    /// A chain reaction's writes: the body's positions `pos` and the workspace's arrays for its
    /// elements, with `width` candidate lists ending at `tail`.
    pub(super) fn of(
        pos: &'a mut [[f32; 3]],
        ws: &'a mut Workspace,
        width: usize,
        tail: &'a mut [usize],
    ) -> Self {
        let n = pos.len();
        Moving {
            pos,
            old: &mut ws.old[..n],
            stamp: &mut ws.stamp[..n],
            sponsor: &mut ws.sponsor[..n],
            moved: &mut ws.moved,
            lists: &mut ws.lists[..n * width],
            tail,
            g: ws.generation,
        }
    }

    /// Elements in the body.
    #[inline(always)]
    pub(super) fn n(&self) -> usize {
        self.pos.len()
    }

    /// Whether element `e` has moved in this reaction (`false` past the end).
    #[inline(always)]
    pub(super) fn has_moved(&self, e: usize) -> bool {
        self.stamp.get(e) == Some(&self.g)
    }

    /// Moves element `c` to `q`, sponsored by `s`.
    #[inline(always)]
    pub(super) fn record(&mut self, c: usize, q: [f32; 3], s: usize) {
        self.old[c] = self.pos[c];
        self.pos[c] = q;
        self.stamp[c] = self.g;
        self.sponsor[c] = s as u32;
        self.moved.push(c as u32);
    }

    /// The records of the chunk of elements from `c`: old positions, positions, stamps, sponsors
    /// (`None` past the end).
    #[inline(always)]
    pub(super) fn chunk_at(&mut self, c: usize) -> Option<ChunkRecords<'_>> {
        Some((
            self.old.get_mut(c..)?.first_chunk_mut::<CHUNK>()?,
            self.pos.get_mut(c..)?.first_chunk_mut::<CHUNK>()?,
            self.stamp.get_mut(c..)?.first_chunk_mut::<CHUNK>()?,
            self.sponsor.get_mut(c..)?.first_chunk_mut::<CHUNK>()?,
        ))
    }

    /// Appends element `c` to the candidate list of slot `u`.
    #[inline(always)]
    pub(super) fn push(&mut self, u: usize, c: usize) {
        let n = self.n();
        self.lists[u * n + self.tail[u]] = c as u32;
        self.tail[u] += 1;
    }
}

/// A chunk's old positions, positions, stamps and sponsors.
pub(super) type ChunkRecords<'a> =
    (&'a mut [[f32; 3]; CHUNK], &'a mut [[f32; 3]; CHUNK], &'a mut [u32; CHUNK], &'a mut [u32; CHUNK]);

/// Where a run of a candidate list starts, for the run paths.
pub(super) struct Run {
    /// Start of the list in the workspace's list buffer.
    pub(super) list: usize,
    /// First unprocessed entry and end of the list.
    pub(super) head: usize,
    pub(super) end: usize,
    /// The list's slot and its grid offset.
    pub(super) t: usize,
    pub(super) o: isize,
    /// The slots a run's moves push across rows ([`onward`]), one bit each.
    pub(super) onward: u64,
}

/// The slots across rows, away from the sponsors, that the candidates of a run through a slot of
/// grid offset `o` push to, one bit each: every slot whose offset is neither back to the sponsors
/// (`-o`) nor along the row (±1). `None` if a slot lies past the mask's 64 bits (no grid has so many).
pub(super) fn onward(offs: &[isize], o: isize) -> Option<u64> {
    if offs.len() > 64 {
        return None;
    }
    Some(
        offs.iter()
            .enumerate()
            .filter(|&(_, &ou)| ou != -o && ou.unsigned_abs() != 1)
            .fold(0, |m, (u, _)| m | 1 << u),
    )
}

/// The slots set in `mask`, lowest first.
#[inline(always)]
pub(super) fn slots(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let u = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            u
        })
    })
}

/// One chunk of a run: its list entries from index `entry` of the candidate lists (the list ending
/// at `end`), its first sponsor `s` and candidate `c` (in list order) through slot `t`, and how many
/// moves of the run came before it.
#[derive(Clone, Copy)]
pub(super) struct At {
    pub(super) entry: usize,
    pub(super) end: usize,
    pub(super) s: usize,
    pub(super) c: usize,
    pub(super) t: usize,
    pub(super) after: usize,
}

impl At {
    /// The chunk's list entries (to the list's end).
    #[inline(always)]
    pub(super) fn entries<'a>(&self, lists: &'a [u32]) -> &'a [u32] {
        lists.get(self.entry..self.end).unwrap_or_default()
    }
}

/// A class's bounds laid out for the chunk checks: lane `j` holds coordinate `j % 3`; coordinates
/// the pass leaves alone get infinite bounds, so the clamp leaves them alone too.
pub(super) struct Pattern {
    pub(super) lo: [f32; 3 * CHUNK],
    pub(super) hi: [f32; 3 * CHUNK],
}

impl Default for Pattern {
    fn default() -> Self {
        Self { lo: [0.0; 3 * CHUNK], hi: [0.0; 3 * CHUNK] }
    }
}

impl Pattern {
    fn of<const MASK: u8>(c: &SlotClass) -> Self {
        let [lo, hi] = c.bounds;
        let lane = |j: usize, x: [f32; 3], off: f32| if MASK & (1 << (j % 3)) != 0 { x[j % 3] } else { off };
        let lo = std::array::from_fn(|j| lane(j, lo, f32::NEG_INFINITY));
        let hi = std::array::from_fn(|j| lane(j, hi, f32::INFINITY));
        Self { lo, hi }
    }
}

/// The last few patterns built: the classes of a grid's rows repeat (their rest lengths differ only
/// in the rounding of the coordinates), so most runs find theirs here.
pub(super) struct Patterns {
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
    pub(super) fn get<const MASK: u8>(&mut self, class: u32, b: Slices<'_>) -> &Pattern {
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
pub(super) fn class_breaks(b: Slices<'_>, t: usize, s: usize) -> Option<u16> {
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
pub(super) fn bad_bytes(b: Slices<'_>, s: usize, c: usize) -> Option<u128> {
    // The flags are 0 or 1, so `x ^ ONES` is non-zero exactly where one is 0.
    const ONES: u128 = u128::MAX / 255;
    let (across_s, across_c) = (b.across.get(s..).and_then(word)?, b.across.get(c..).and_then(word)?);
    let flags = b.flags.get(c..).and_then(word)?;
    Some((across_s ^ ONES) | (across_c ^ ONES) | (flags & (ONES * FIXED as u128)))
}

/// The pushes along the row of a run of moved candidates from `first` to `last` (both ends
/// included, either way along the row): only its two ends can have a neighbour there outside the
/// run (and back toward the sponsors every neighbour has moved).
#[inline(always)]
pub(super) fn push_ends(b: Slices<'_>, [first, last]: [usize; 2], m: &mut Moving<'_>) {
    for u in 0..b.width {
        if b.offs[u].unsigned_abs() == 1 {
            for c in [first, last].into_iter().take(if first == last { 1 } else { 2 }) {
                // The real neighbour: a row's end has padding there (itself, moved), and the run's
                // own elements have moved by now.
                if !m.has_moved(b.neighbour(c, u)) {
                    m.push(u, c);
                }
            }
        }
    }
}

/// Clamps the coordinates selected by `MASK` into `[lo, hi]` (`lo <= hi`, all finite or infinite, no
/// NaN) with the engine's one clamp.
#[inline(always)]
pub(super) fn clamp_masked<const MASK: u8>(p: [f32; 3], lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
    let mut q = p;
    for k in 0..3 {
        if MASK & (1 << k) != 0 {
            q[k] = clamp(p[k], lo[k], hi[k]);
        }
    }
    q
}

/// Where a sponsor at `ps` puts its candidate through a slot of `class` bounds `[elo, ehi]` (which
/// bound `p[s] - p[c]`): `p[c]` must lie in `[ps - ehi, ps - elo]`.
#[inline(always)]
pub(super) fn candidate_box(ps: [f32; 3], [elo, ehi]: [[f32; 3]; 2]) -> [[f32; 3]; 2] {
    [[ps[0] - ehi[0], ps[1] - ehi[1], ps[2] - ehi[2]], [ps[0] - elo[0], ps[1] - elo[1], ps[2] - elo[2]]]
}
