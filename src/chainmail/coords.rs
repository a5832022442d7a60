//! Coordinate arithmetic shared by the lattice, the body and both loops: differences, lengths and the
//! one scalar clamp.

/// `a - b`.
#[inline]
pub(crate) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Euclidean length.
#[inline]
pub(crate) fn norm(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// `x` clamped into `[lo, hi]` by plain comparisons (`lo` first), which compile to single min and
/// max instructions. The engine's loops all clamp through this (or, in vectors, through the same
/// comparisons lane by lane), so that their results agree bit for bit. With `lo <= hi` and no NaN
/// it is `x.max(lo).min(hi)` up to the sign of a zero.
#[inline(always)]
pub(crate) fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}
