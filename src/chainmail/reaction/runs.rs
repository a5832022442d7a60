//! Runs of a candidate list across rows moved as one: the entries are consecutive sponsors (up a
//! row or down it) whose candidates in the next row are consecutive too and independent of each
//! other, so a run is checked and written a chunk of sixteen at a time, with the one-by-one path's
//! moves, order and sponsors. Chunks take the vector path (`vector.rs`: AVX-512 or AVX2) where the
//! level allows it, else the portable one (`chunk.rs`).

use super::arrays::{
    At, CHUNK, Moving, Pattern, Patterns, RUN, Run, Slices, candidate_box, clamp_masked, push_ends, slots,
};
use super::chunk::check_chunk;
#[cfg(target_arch = "x86_64")]
use super::lanes::Lanes;
#[cfg(target_arch = "x86_64")]
use super::vector;
use crate::chainmail::body::FIXED;
use crate::chainmail::simd::SimdLevel;
#[cfg(target_arch = "x86_64")]
use pulp::x86::{V3, V4};

/// The vector registers the chunks use, as the level and the machine allow.
#[derive(Clone, Copy)]
pub(super) enum Wide {
    /// AVX-512: one register per chunk, mask registers.
    #[cfg(target_arch = "x86_64")]
    Avx512(V4),
    /// AVX2: two registers per chunk.
    #[cfg(target_arch = "x86_64")]
    Avx2(V3),
    /// Plain loops over lanes, which the compiler vectorises as it can.
    Portable,
}

impl Wide {
    /// The widest the level and the machine allow.
    #[inline(always)]
    pub(super) fn of(level: SimdLevel) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(v) = level.v4() {
                return Self::Avx512(v);
            }
            if let Some(v) = level.v3() {
                return Self::Avx2(v);
            }
        }
        let _ = level;
        Self::Portable
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
#[inline(always)]
pub(super) fn batch<const MASK: u8>(
    run: &Run,
    b: Slices<'_>,
    m: &mut Moving<'_>,
    patterns: &mut Patterns,
    wide: Wide,
) -> usize {
    let &Run { list, head, end, t, o, .. } = run;
    let s0 = m.lists[list + head] as usize;
    if b.across.get(s0) != Some(&1) {
        return 0;
    }
    let c0 = s0.wrapping_add_signed(o);
    // The first candidate has moved already, and maybe those of the entries after it: such entries
    // are done with, as one by one.
    // Runs go up or down the row: entries `s0, s0 + 1, ...` or `s0, s0 - 1, ...` (the order in which
    // the list along the row moved them).
    let down = head + 1 < end && m.lists[list + head + 1] as usize == s0.wrapping_sub(1);
    let step = |k: usize| if down { s0.wrapping_sub(k) } else { s0 + k };
    if m.has_moved(c0) {
        let mut k = 1;
        while k < RUN
            && head + k < end
            && m.lists[list + head + k] as usize == step(k)
            && b.across.get(step(k)) == Some(&1)
            && m.has_moved(step(k).wrapping_add_signed(o))
        {
            k += 1;
        }
        return k;
    }
    let Some(&cls) = b.slot_class.get(s0 * b.width + t) else {
        return 0;
    };
    let bounds = patterns.get::<MASK>(cls, b);
    let cls = cls as usize;
    match (wide, down) {
        #[cfg(target_arch = "x86_64")]
        (Wide::Avx512(v), true) => vector::batch_down(v, run, b, m, bounds),
        #[cfg(target_arch = "x86_64")]
        (Wide::Avx2(v), true) => vector::batch_down(v, run, b, m, bounds),
        (Wide::Portable, true) => 0,
        #[cfg(target_arch = "x86_64")]
        (Wide::Avx512(v), false) => batch_up::<MASK, _>(v, run, b, m, [cls, s0, c0], bounds),
        #[cfg(target_arch = "x86_64")]
        (Wide::Avx2(v), false) => batch_up::<MASK, _>(v, run, b, m, [cls, s0, c0], bounds),
        (Wide::Portable, false) => batch_up::<MASK, _>(Plain, run, b, m, [cls, s0, c0], bounds),
    }
}

/// A chunk's clamped positions, three coordinates per element.
type Clamped = [f32; 3 * CHUNK];

/// How a run's chunks are checked, written and pushed: with vector registers of one width, or
/// portably. Chosen once per run, so that a chunk's path has no branch on the width (and nothing of
/// another width's path is set up in its loop).
trait ChunkPath: Copy {
    /// As [`vector::chunk`]: how many leading elements pass and whether they were written.
    fn chunk(
        self,
        b: Slices<'_>,
        m: &mut Moving<'_>,
        at: At,
        bounds: &Pattern,
        q: &mut Clamped,
    ) -> (usize, bool);
    /// Pushes candidates `c..c + k` to the list of slot `u` where their neighbours `d..d + k` have
    /// not moved.
    fn push(self, m: &mut Moving<'_>, u: usize, cdk: [usize; 3]);
}

/// The portable chunks, plain loops over lanes.
#[derive(Clone, Copy)]
struct Plain;

impl ChunkPath for Plain {
    #[inline(always)]
    fn chunk(
        self,
        b: Slices<'_>,
        m: &mut Moving<'_>,
        at: At,
        bounds: &Pattern,
        q: &mut Clamped,
    ) -> (usize, bool) {
        (check_chunk(b, m, at, bounds, q), false)
    }
    #[inline(always)]
    fn push(self, m: &mut Moving<'_>, u: usize, cdk: [usize; 3]) {
        push(m, u, cdk);
    }
}

#[cfg(target_arch = "x86_64")]
impl<L: Lanes> ChunkPath for L {
    #[inline(always)]
    fn chunk(
        self,
        b: Slices<'_>,
        m: &mut Moving<'_>,
        at: At,
        bounds: &Pattern,
        q: &mut Clamped,
    ) -> (usize, bool) {
        vector::chunk(self, b, m, at, bounds, q)
    }
    #[inline(always)]
    fn push(self, m: &mut Moving<'_>, u: usize, cdk: [usize; 3]) {
        vector::push(self, m, u, cdk, false);
    }
}

/// [`batch`] for a run up the row, from sponsor `s0` and candidate `c0` of slot class `cls`.
#[inline(always)]
fn batch_up<const MASK: u8, P: ChunkPath>(
    path: P,
    run: &Run,
    b: Slices<'_>,
    m: &mut Moving<'_>,
    [cls, s0, c0]: [usize; 3],
    bounds: &Pattern,
) -> usize {
    let &Run { list, head, end, t, onward, .. } = run;
    let width = b.width;
    let mut done = 0;
    let mut q = [0.0f32; 3 * CHUNK];
    while done < RUN {
        let (s, c) = (s0 + done, c0.wrapping_add(done));
        let at = At { entry: list + head + done, end: list + end, s, c, t, after: done };
        let mut written = false;
        let k = if head + done + CHUNK > end {
            0
        } else {
            let k;
            (k, written) = path.chunk(b, m, at, bounds, &mut q);
            k
        };
        let k = if k > 0 {
            k
        } else {
            // Near the list's end: one element, checked as one by one.
            let ok = head + done < end
                && m.lists[list + head + done] as usize == s
                && b.across.get(s) == Some(&1)
                && b.across.get(c) == Some(&1)
                && !m.has_moved(c)
                && b.flags[c] & FIXED == 0
                && b.slot_class[s * width + t] as usize == cls;
            if !ok {
                break;
            }
            let [lo, hi] = candidate_box(m.pos[s], b.classes[cls].bounds);
            let x = clamp_masked::<MASK>(m.pos[c], lo, hi);
            if x == m.pos[c] {
                break;
            }
            q[..3].copy_from_slice(&x);
            1
        };
        if done + k < 2 {
            // Fewer than two: the one-by-one path does it as cheaply.
            return 0;
        }
        if !written && !write(m, [s, c, k], &q) {
            break;
        }
        // Pushes across rows, away from the sponsors (no neighbour in the run there: the candidates
        // are placed by the grid offsets and distinct rows apart), written without a branch: each
        // slot takes the entry, the end advances only for unmoved neighbours (the list has room: `c`
        // is not in it yet).
        for u in slots(onward) {
            // In range: the candidates' neighbours across rows are at the grid offsets.
            path.push(m, u, [c, c.wrapping_add_signed(b.offs[u]), k]);
        }
        done += k;
        if k < CHUNK {
            break;
        }
    }
    if done == 0 {
        return 0;
    }
    push_ends(b, [c0, c0 + done - 1], m);
    done
}

/// Writes `k` moves of candidates `c..c + k` to the positions in `q`, sponsored by `s..s + k`.
/// `false`, with nothing written, if a whole chunk is not in the body (never, after its checks).
#[inline(always)]
fn write(m: &mut Moving<'_>, [s, c, k]: [usize; 3], q: &[f32; 3 * CHUNK]) -> bool {
    if k < CHUNK {
        for j in 0..k {
            m.record(c + j, [q[3 * j], q[3 * j + 1], q[3 * j + 2]], s + j);
        }
        return true;
    }
    // Fixed lengths, so the copies are vector moves rather than calls.
    let g = m.g;
    let Some((old, now, st, sp)) = m.chunk_at(c) else {
        return false;
    };
    *old = *now;
    now.as_flattened_mut().copy_from_slice(q);
    *st = [g; CHUNK];
    *sp = std::array::from_fn(|j| (s + j) as u32);
    m.moved.extend_from_slice(&std::array::from_fn::<u32, CHUNK, _>(|j| (c + j) as u32));
    true
}

/// Pushes candidates `c..c + k` to the candidate list of slot `u` where their neighbours
/// `d..d + k` have not moved, without a branch per entry.
#[inline(always)]
fn push(m: &mut Moving<'_>, u: usize, [c, d, k]: [usize; 3]) {
    let (n, g) = (m.n(), m.g);
    let (ds, list, end) = (&m.stamp[d..d + k], &mut m.lists[u * n..(u + 1) * n], &mut m.tail[u]);
    if ds.iter().fold(true, |a, &x| a & (x != g)) && *end + k <= n {
        for (j, e) in list[*end..*end + k].iter_mut().enumerate() {
            *e = (c + j) as u32;
        }
        *end += k;
    } else {
        for (j, &x) in ds.iter().enumerate() {
            list[*end] = (c + j) as u32;
            *end += (x != g) as usize;
        }
    }
}
