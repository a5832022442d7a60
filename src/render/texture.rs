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
//!
//! Each [`SurfacePattern`] gets its own texture made from those channels ([`pattern_texels`]), holding
//! what the tissue shader needs per pixel and nothing to compute: r the factor of the layer's colour
//! (over [`ALBEDO_SCALE`]), g the weight of the pattern's vessel colour ([`vessel_color`]), b the
//! extra wetness over vessels (the highlight is `1 + 0.5 b` times as strong).

use crate::snapshot::SurfacePattern;

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

/// The layer colour's factor is stored divided by this (it reaches about 1.17 on the dura's grain).
pub const ALBEDO_SCALE: f32 = 1.2;

/// The colour (linear RGB) a pattern's vessels mix the layer's colour towards.
pub fn vessel_color(pattern: SurfacePattern) -> [f32; 3] {
    match pattern {
        // The meningeal vessels, faint through the dura.
        SurfacePattern::Grain => [0.55, 0.12, 0.12],
        // Red vessels on the arachnoid's translucent pink film.
        SurfacePattern::Vessels => [0.42, 0.03, 0.05],
        SurfacePattern::Plain => [0.0; 3],
    }
}

/// One pattern's texture (RGBA8, `TEXTURE_SIZE`² texels, row by row) from [`tissue_texels`]: for each
/// texel the layer colour's factor `s`, the vessel weight `w` and the extra wetness `x`, so that the
/// shader's colour is `colour × s + vessel_color × w`:
/// - grain (dura): mottled collagen grain, the meningeal vessels faint through it (`w` = 0.18 of them);
/// - vessels (arachnoid): vessels and fainter capillaries at 0.85 over the film, wetter on the vessels;
/// - plain: the mottle only.
pub fn pattern_texels(texels: &[[u8; 4]], pattern: SurfacePattern) -> Vec<[u8; 4]> {
    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    texels
        .iter()
        .map(|t| {
            let [grain, vessels, capillaries, mottle] = t.map(|c| f32::from(c) / 255.0);
            let m = 0.9 + 0.2 * mottle;
            let (s, w, wet) = match pattern {
                SurfacePattern::Grain => {
                    let w = 0.18 * vessels;
                    (m * (0.9 + 0.16 * grain) * (1.0 - w), w, 0.0)
                }
                SurfacePattern::Vessels => {
                    let w = 0.85 * vessels.max(0.45 * capillaries);
                    (m * (1.0 - w), w, vessels)
                }
                SurfacePattern::Plain => (m, 0.0, 0.0),
            };
            [byte(s / ALBEDO_SCALE), byte(w), byte(wet), 255]
        })
        .collect()
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

    #[test]
    fn pattern_textures_hold_the_colour_factor_without_clipping() {
        let texels = tissue_texels();
        for pattern in [SurfacePattern::Grain, SurfacePattern::Vessels, SurfacePattern::Plain] {
            let p = pattern_texels(&texels, pattern);
            assert_eq!(p.len(), texels.len());
            // The factor is clipped at neither end of its byte.
            let (lo, hi) = p.iter().fold((255u8, 0u8), |(lo, hi), t| (lo.min(t[0]), hi.max(t[0])));
            assert!(hi < 255 && lo > 0, "{pattern:?}: colour factor bytes {lo}..{hi}");
        }
        // The arachnoid's vessels darken its film and make it wetter; the dura is never wetter.
        let film = pattern_texels(&texels, SurfacePattern::Vessels);
        assert!(film.iter().any(|t| t[1] > 150 && t[2] > 150));
        assert!(pattern_texels(&texels, SurfacePattern::Grain).iter().all(|t| t[2] == 0));
    }
}
