//! The portable form of a run's chunk check: plain loops over the sixteen lanes, without branches,
//! which the compiler vectorises for whatever instruction set the reaction was dispatched to.

use super::arrays::{At, CHUNK, Moving, Pattern, Slices, bad_bytes, class_breaks};
use crate::chainmail::coords::clamp;

/// How many leading elements of a chunk pass the one-by-one path's checks, for sponsors `s..s + CHUNK`
/// and candidates `c..c + CHUNK` through slot `t` (from `at`), whose run has the class of `bounds`:
/// entry in sequence, sponsor and candidate with their neighbours across rows at the grid offsets
/// (`Stencil::across`), candidate not moved and free, sponsor's link of the run's class (no change
/// bit since the run's first), candidate pushed out of its box. The candidates' clamped positions go
/// to `q`. Every check runs on every lane without a branch, so the loops vectorise; the first
/// failure is read off the bit masks. All ranges must be in bounds (else 0).
#[inline(always)]
pub(super) fn check_chunk(
    b: Slices<'_>,
    m: &Moving<'_>,
    at: At,
    bounds: &Pattern,
    q: &mut [f32; 3 * CHUNK],
) -> usize {
    let At { s, c, t, after, .. } = at;
    let (Some(entries), Some(stamps), Some(breaks), Some(ps), Some(pc)) = (
        at.entries(m.lists).first_chunk::<CHUNK>(),
        m.stamp.get(c..).and_then(<[u32]>::first_chunk::<CHUNK>),
        class_breaks(b, t, s),
        m.pos.get(s..).and_then(<[[f32; 3]]>::first_chunk::<CHUNK>),
        m.pos.get(c..).and_then(<[[f32; 3]]>::first_chunk::<CHUNK>),
    ) else {
        return 0;
    };
    let Some(bad_bytes) = bad_bytes(b, s, c) else {
        return 0;
    };
    // The run's first element has the run's class by definition; the others must not change it.
    let mut bad = u32::from(breaks) & !u32::from(after == 0);
    for k in 0..CHUNK {
        let fail = (entries[k] != (s + k) as u32) | (stamps[k] == m.g);
        bad |= (fail as u32) << k;
    }
    let (ps, pc) = (ps.as_flattened(), pc.as_flattened());
    let mut same = 0u64;
    for j in 0..3 * CHUNK {
        // As `clamp_masked`: `p[c]` into `[p[s] - hi, p[s] - lo]`.
        let x = clamp(pc[j], ps[j] - bounds.hi[j], ps[j] - bounds.lo[j]);
        q[j] = x;
        same |= ((x == pc[j]) as u64) << j;
    }
    // An element stays put when all three of its lanes do.
    let still = same & (same >> 1) & (same >> 2) & 0o1111_1111_1111_1111;
    let first_bad_byte = bad_bytes.trailing_zeros() as usize / 8;
    (bad.trailing_zeros() as usize).min(first_bad_byte).min(still.trailing_zeros() as usize / 3).min(CHUNK)
}
