//! The vector form of a run's chunks, for AVX-512 (one register per sixteen lanes, mask registers)
//! and AVX2 (two registers; `lanes.rs`): checked without branches and, when all of a chunk passes,
//! written straight from the registers the check computed (no round trip through memory). Runs go
//! up a row ([`chunk`]) or down it ([`batch_down`]); the results are the portable path's and the
//! one-by-one path's bit for bit.

use super::arrays::{
    At, CHUNK, Moving, Pattern, RUN, Run, Slices, bad_bytes, class_breaks, push_ends, slots,
};
use super::lanes::Lanes;

/// Lane `i` holds `i`.
const IOTA: [u32; CHUNK] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

/// [`IOTA`] in a vector.
#[inline(always)]
fn iota<L: Lanes>() -> L::U {
    pulp::cast(IOTA)
}

/// Sixteen `u32` from the start of `x`.
#[inline(always)]
fn load<L: Lanes>(x: &[u32]) -> Option<L::U> {
    x.first_chunk::<CHUNK>().map(|a| pulp::cast(*a))
}

/// The candidates `pc` clamped into their boxes around the sponsors `ps` (as `clamp_masked`, by
/// comparisons, bit for bit), and a bit at `3 i` for each element `i` the clamp leaves in place.
#[inline(always)]
fn clamp<L: Lanes>(v: L, ps: [L::F; 3], pc: [L::F; 3], bounds: &Pattern) -> ([L::F; 3], u64) {
    let lo: [L::F; 3] = pulp::cast(bounds.lo);
    let hi: [L::F; 3] = pulp::cast(bounds.hi);
    let mut x = pc;
    let mut same = 0u64;
    for i in 0..3 {
        let (l, h) = (v.sub_f(ps[i], hi[i]), v.sub_f(ps[i], lo[i]));
        let y = v.select(v.less(pc[i], l), l, pc[i]);
        x[i] = v.select(v.greater(y, h), h, y);
        same |= u64::from(v.equal_f_bits(x[i], pc[i])) << (CHUNK * i);
    }
    // An element stays put when all three of its lanes do.
    (x, same & (same >> 1) & (same >> 2) & 0o1111_1111_1111_1111)
}

/// What a chunk's checks read: sixteen list entries (in list order), and from the lowest
/// sponsor and candidate in memory `[ls, lc]` on, the candidates' stamps, the sponsors' and
/// candidates' positions, their byte checks ([`bad_bytes`]) and the class change bits of
/// sixteen elements from `breaks_at` in slot `t`.
struct Loaded<L: Lanes> {
    e: L::U,
    st: L::U,
    ps: [L::F; 3],
    pc: [L::F; 3],
    bad_bytes: u128,
    breaks: u16,
}

impl<L: Lanes> Loaded<L> {
    #[inline(always)]
    fn at(b: Slices<'_>, m: &Moving<'_>, at: At, [ls, lc]: [usize; 2], breaks_at: usize) -> Option<Self> {
        Some(Self {
            e: load::<L>(at.entries(m.lists))?,
            st: load::<L>(m.stamp.get(lc..)?)?,
            ps: load3::<L>(m.pos.get(ls..)?)?,
            pc: load3::<L>(m.pos.get(lc..)?)?,
            bad_bytes: bad_bytes(b, ls, lc)?,
            breaks: class_breaks(b, at.t, breaks_at)?,
        })
    }
}

/// Sixteen positions from the start of `x`, as three vectors.
#[inline(always)]
fn load3<L: Lanes>(x: &[[f32; 3]]) -> Option<[L::F; 3]> {
    x.first_chunk::<CHUNK>().map(|a| pulp::cast(*a))
}

/// As [`super::chunk::check_chunk`] (same checks, same clamps, bit for bit); when the whole chunk passes
/// it is also written: old positions, new positions, stamps, sponsors and the moved list. Returns
/// how many leading elements pass and whether they were written (else their clamped positions are
/// in `q`).
#[inline(always)]
pub(super) fn chunk<L: Lanes>(
    v: L,
    b: Slices<'_>,
    m: &mut Moving<'_>,
    at: At,
    bounds: &Pattern,
    q: &mut [f32; 3 * CHUNK],
) -> (usize, bool) {
    let At { s, c, after, .. } = at;
    let Some(Loaded { e, st, ps, pc, bad_bytes, breaks }) = Loaded::<L>::at(b, m, at, [s, c], s) else {
        return (0, false);
    };
    let gs = v.splat(m.g);
    let in_sequence = v.equal_bits(e, v.add(v.splat(s as u32), iota::<L>()));
    let unmoved = !v.equal_bits(st, gs);
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
    let sponsors = v.add(v.splat(s as u32), iota::<L>());
    let order = pulp::cast::<L::U, [u32; CHUNK]>(v.add(v.splat(c as u32), iota::<L>()));
    // The first `k` lanes.
    let lanes = ((1u32 << k) - 1) as u16;
    let moves = Moves { c, pc, x, sponsors, lanes, order: &order[..k] };
    if !moves.write(v, m) {
        // Not reached (the reads above covered the same range); the caller writes it instead.
        *q = pulp::cast(x);
        return (k, false);
    }
    (k, true)
}

/// The writes of a chunk's moves: candidates from `c` (memory order) at `pc`, moving to `x`, in
/// the lanes set in `lanes`, with `sponsors`; `order` is the moved list's part.
struct Moves<'a, L: Lanes> {
    c: usize,
    pc: [L::F; 3],
    x: [L::F; 3],
    sponsors: L::U,
    lanes: u16,
    order: &'a [u32],
}

impl<L: Lanes> Moves<'_, L> {
    /// Writes new and old positions, stamps, sponsors and the moved list; the lanes not moved are
    /// written back as they were (they are other elements than the moved ones, and nothing else
    /// writes them meanwhile). `false`, with nothing written, if the range is not in the body.
    #[inline(always)]
    fn write(&self, v: L, m: &mut Moving<'_>) -> bool {
        let &Moves { c, pc, mut x, sponsors, lanes, order } = self;
        let gs = v.splat(m.g);
        let Some((o, p, st, sp)) = m.chunk_at(c) else {
            return false;
        };
        if lanes == u16::MAX {
            *o = pulp::cast(pc);
            *p = pulp::cast(x);
            *st = pulp::cast(gs);
            *sp = pulp::cast(sponsors);
        } else {
            // Each element's three coordinates.
            let coords = (0..CHUNK).filter(|&i| lanes >> i & 1 == 1).fold(0u64, |m, i| m | 0b111 << (3 * i));
            let was: [L::F; 3] = pulp::cast(*o);
            let mut new_old = was;
            for i in 0..3 {
                let m = v.mask((coords >> (CHUNK * i)) as u16);
                x[i] = v.select(m, x[i], pc[i]);
                new_old[i] = v.select(m, pc[i], was[i]);
            }
            let (st_was, sp_was): (L::U, L::U) = (pulp::cast(*st), pulp::cast(*sp));
            let lanes = v.mask(lanes);
            *o = pulp::cast(new_old);
            *p = pulp::cast(x);
            *st = pulp::cast(v.select_u(lanes, gs, st_was));
            *sp = pulp::cast(v.select_u(lanes, sponsors, sp_was));
        }
        match order.first_chunk::<CHUNK>() {
            // A fixed length: vector moves, not a call.
            Some(all) if order.len() == CHUNK => m.moved.extend_from_slice(all),
            _ => m.moved.extend_from_slice(order),
        }
        true
    }
}

/// [`chunk`] for a run down the row: sponsors `s, s - 1, ..., s - 15` (list entries in that
/// order) and candidates `c, c - 1, ...`. The body's arrays are loaded in memory order (lane `i`
/// holds element `s - 15 + i`), so the run's first failure is the highest failing lane. Returns
/// how many moves were written: none when the chunk's first fails, or when fewer than two would
/// be in the run so far (left to the one-by-one path).
#[inline(always)]
fn chunk_down<L: Lanes>(v: L, b: Slices<'_>, m: &mut Moving<'_>, at: At, bounds: &Pattern) -> usize {
    let At { s, c, after, .. } = at;
    let (Some(ls), Some(lc)) = (s.checked_sub(CHUNK - 1), c.checked_sub(CHUNK - 1)) else {
        return 0;
    };
    // Change bits of elements `ls + 1 ..= s + 1`: element `ls + i` keeps the run's class while
    // every bit `j >= i` is clear (bit 15, the element above the chunk, matters only after it).
    let Some(Loaded { e, st, ps, pc, bad_bytes, breaks }) = Loaded::<L>::at(b, m, at, [ls, lc], ls + 1)
    else {
        return 0;
    };
    let gs = v.splat(m.g);
    // Entries in list order: lane `k` is sponsor `s - k`.
    let in_sequence = v.equal_bits(e, v.sub(v.splat(s as u32), iota::<L>()));
    let moved_now = v.equal_bits(st, gs);
    let breaks = breaks & if after == 0 { 0x7fff } else { 0xffff };
    let (x, still) = clamp(v, ps, pc, bounds);
    // One more than the highest failing lane, by memory order (0 when none fails): the highest set
    // bit `b` of bits `per` to a lane is in lane `b / per`, and `(b + 1).div_ceil(per)` is one more.
    let above = |bits: u128, per: u32| (128 - bits.leading_zeros()).div_ceil(per) as usize;
    let highest = above(u128::from(moved_now), 1)
        .max(above(bad_bytes, 8))
        .max(above(u128::from(breaks), 1))
        .max(above(u128::from(still), 3));
    let k = (CHUNK - highest).min((!in_sequence).trailing_zeros() as usize);
    // Fewer than two moves in all are left to the one-by-one path.
    if k == 0 || k + after < 2 {
        return 0;
    }
    // Moved in the run's order: `c, c - 1, ...`; the top `k` lanes.
    let order = pulp::cast::<L::U, [u32; CHUNK]>(v.sub(v.splat(c as u32), iota::<L>()));
    let sponsors = v.add(v.splat(ls as u32), iota::<L>());
    let lanes = (((1u32 << k) - 1) << (CHUNK - k)) as u16;
    let moves = Moves { c: lc, pc, x, sponsors, lanes, order: &order[..k] };
    if moves.write(v, m) { k } else { 0 }
}

/// [`super::runs::batch`] for a run down the row (entries `s0, s0 - 1, ...`), a chunk at a time, as
/// the one-by-one path would: the same moves in the same order, the same sponsors, and the same
/// list entries but for those whose neighbour has moved by the time they would be read.
#[inline(always)]
pub(super) fn batch_down<L: Lanes>(
    v: L,
    run: &Run,
    b: Slices<'_>,
    m: &mut Moving<'_>,
    bounds: &Pattern,
) -> usize {
    let &Run { list, head, end, t, o, onward } = run;
    let s0 = m.lists[list + head] as usize;
    let c0 = s0.wrapping_add_signed(o);
    let mut done = 0;
    while done < RUN && head + done + CHUNK <= end && done < s0 {
        let (s, c) = (s0 - done, c0.wrapping_sub(done));
        let at = At { entry: list + head + done, end: list + end, s, c, t, after: done };
        // How many were moved and written (none: the run ends here).
        let k = chunk_down(v, b, m, at, bounds);
        if k == 0 {
            break;
        }
        // Pushes across rows, away from the sponsors, in the run's order.
        for u in slots(onward) {
            push(v, m, u, [c, c.wrapping_add_signed(b.offs[u]), k], true);
        }
        done += k;
        if k < CHUNK {
            break;
        }
    }
    if done == 0 {
        return 0;
    }
    push_ends(b, [c0, c0 + 1 - done], m);
    done
}

/// Pushes candidates `c, c ± 1, ...` (`k` of them, down the row if `down`) to the candidate list
/// of slot `u` where their neighbours `d, d ± 1, ...` have not moved: sixteen at once when none has.
#[inline(always)]
pub(super) fn push<L: Lanes>(v: L, m: &mut Moving<'_>, u: usize, [c, d, k]: [usize; 3], down: bool) {
    let (n, g) = (m.n(), m.g);
    let (stamp, list, end) = (&*m.stamp, &mut m.lists[u * n..(u + 1) * n], &mut m.tail[u]);
    // The neighbours' stamps in memory order: the first `k` lanes up the row, the last `k` down.
    let (first, lanes) = if down {
        (d.checked_sub(CHUNK - 1), (((1u32 << k) - 1) << (CHUNK - k)) as u16)
    } else {
        (Some(d), ((1u32 << k) - 1) as u16)
    };
    let cs = v.splat(c as u32);
    if let (Some(ds), Some(slots)) = (
        first.and_then(|f| stamp.get(f..)).and_then(load::<L>),
        list.get_mut(*end..).and_then(<[u32]>::first_chunk_mut::<CHUNK>),
    ) && v.equal_bits(ds, v.splat(g)) & lanes == 0
    {
        // Entries past `k` land beyond the list's end, where nothing reads them.
        *slots = pulp::cast(if down { v.sub(cs, iota::<L>()) } else { v.add(cs, iota::<L>()) });
        *end += k;
        return;
    }
    push_each(stamp, list, end, g, [c, d, k], down);
}

/// [`push`] one entry at a time, where some neighbour has moved or the chunk runs past an end (rare:
/// out of line, so that its loop's setup stays off the chunk's path).
#[cold]
#[inline(never)]
fn push_each(stamp: &[u32], list: &mut [u32], end: &mut usize, g: u32, [c, d, k]: [usize; 3], down: bool) {
    for j in 0..k {
        let (c, d) = if down { (c - j, d - j) } else { (c + j, d + j) };
        list[*end] = c as u32;
        *end += (stamp[d] != g) as usize;
    }
}
