//! The tissue's procedural surface texture, made once on the CPU (no files, no GPU types): a tileable
//! square whose channels the tissue shader mixes per layer.
//!
//! - red: fibre grain, streaks along `u` (the dura's collagen);
//! - green: vessels, meandering lines of two widths (the arachnoid's surface vessels);
//! - blue: fine capillaries, thinner and fainter;
//! - alpha: slow mottling (both).
//!
//! Drawn in the surface's rest coordinates, so the pattern moves and stretches with the tissue.
//! Sampling a texture costs a software rasteriser far less per pixel than evaluating noise in the shader.

/// Side of the texture, texels.
pub const TEXTURE_SIZE: u32 = 256;
/// Metres of tissue one repeat of the texture covers.
pub const TEXTURE_TILE_M: f32 = 0.03;

/// A hash of a lattice point, in `[0, 1)`.
fn hash(x: i32, y: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x27d4_eb2d) ^ (y as u32).wrapping_mul(0x1656_67b1) ^ seed;
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Value noise with period `px` × `py` cells, at `(x, y)` in cells; smooth, in `[0, 1]`.
fn noise(x: f32, y: f32, px: i32, py: i32, seed: u32) -> f32 {
    let (xi, yi) = (x.floor(), y.floor());
    let (fx, fy) = (x - xi, y - yi);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let (x0, y0) = ((xi as i32).rem_euclid(px), (yi as i32).rem_euclid(py));
    let (x1, y1) = ((x0 + 1) % px, (y0 + 1) % py);
    let a = hash(x0, y0, seed);
    let b = hash(x1, y0, seed);
    let c = hash(x0, y1, seed);
    let d = hash(x1, y1, seed);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sy
}

/// Fractal sum of `octaves` noises, the first with `cells` × `cells` cells over the tile; `[0, 1]`.
fn fbm(u: f32, v: f32, cells: i32, octaves: u32, seed: u32) -> f32 {
    let (mut sum, mut amp, mut norm, mut c) = (0.0, 1.0, 0.0, cells);
    for o in 0..octaves {
        sum += amp * noise(u * c as f32, v * c as f32, c, c, seed.wrapping_add(o * 7919));
        norm += amp;
        amp *= 0.5;
        c *= 2;
    }
    sum / norm
}

/// A line along the level set `fbm = 0.5`, `width` wide in noise units: 1 on the line, 0 off it.
fn ridge(n: f32, width: f32) -> f32 {
    let d = (n - 0.5).abs() / width;
    (1.0 - d * d).max(0.0)
}

/// The texture's texels, row by row, RGBA8 (`TEXTURE_SIZE`² of them). Deterministic.
pub fn tissue_texels() -> Vec<[u8; 4]> {
    let n = TEXTURE_SIZE;
    let mut out = Vec::with_capacity((n * n) as usize);
    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            // Grain: long streaks along u (few cells along u, many along v), two octaves.
            let g1 = noise(u * 6.0, v * 96.0, 6, 96, 11);
            let g2 = noise(u * 12.0, v * 192.0, 12, 192, 12);
            let grain = 0.6 * g1 + 0.4 * g2;
            // Vessels: level-set lines of warped noise; the warp makes them wander and branch-like.
            let wu = u + 0.08 * (fbm(u, v, 3, 2, 21) - 0.5);
            let wv = v + 0.08 * (fbm(u, v, 3, 2, 22) - 0.5);
            let big = ridge(fbm(wu, wv, 3, 3, 31), 0.028);
            let small = ridge(fbm(wu, wv, 6, 3, 41), 0.02);
            let vessels = big.max(0.65 * small);
            let capillaries = ridge(fbm(u, v, 12, 2, 51), 0.03);
            let mottle = fbm(u, v, 4, 3, 61);
            out.push([byte(grain), byte(vessels), byte(capillaries), byte(mottle)]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_is_deterministic_and_tiles() {
        let a = tissue_texels();
        assert_eq!(a, tissue_texels());
        assert_eq!(a.len(), (TEXTURE_SIZE * TEXTURE_SIZE) as usize);
        // Noise at u = 1 equals noise at u = 0: the periodic lattice wraps.
        for (x, y) in [(0.3f32, 0.7f32), (0.0, 0.2)] {
            let here = fbm(x, y, 4, 3, 5);
            let wrapped = fbm(x + 1.0, y, 4, 3, 5);
            assert!((here - wrapped).abs() < 1e-4, "{here} vs {wrapped}");
        }
        // Every channel varies (a flat channel would be a bug in the generator).
        for c in 0..4 {
            let (lo, hi) = a.iter().fold((255u8, 0u8), |(lo, hi), t| (lo.min(t[c]), hi.max(t[c])));
            assert!(hi - lo > 60, "channel {c}: {lo}..{hi}");
        }
    }
}
