//! The tissue's parts as scenes describe them: layers, connective fibres, pins. Plain data with serde,
//! read from scene files by [`crate::scene`] and built into a [`super::Tissue`].

use serde::{Deserialize, Serialize};

use crate::chainmail::Material;

/// One tissue layer.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// Name shown in panels and reports, e.g. `"dura"`. Required, not empty, unique in the scene.
    pub name: String,
    /// Linear RGBA colour, each channel in `[0, 1]`. Default `(0.8, 0.6, 0.55, 1.0)`.
    #[serde(default = "default_color")]
    pub color: [f32; 4],
    /// Offset along the outward surface normal from the base surface, metres. Default 0. With two
    /// layers, the upper layer's offset must be greater.
    #[serde(default)]
    pub offset: f32,
    /// How the layer's links stretch, compress, shear and tear. Default: [`Material::default`].
    #[serde(default)]
    pub material: Material,
}

fn default_color() -> [f32; 4] {
    [0.8, 0.6, 0.55, 1.0]
}

/// Connective fibres between the two layers: each joins an element of layer 0 to the element of
/// layer 1 at the same `(u, v)`.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ConnectiveSpec {
    /// The fibres' material (their rest length is the layer gap). Default: [`Material::default`].
    #[serde(default)]
    pub material: Material,
    /// Share of the fibres' sites joined (every element pair, or one in [`ConnectiveSpec::stride`]),
    /// in `(0, 1]`. The pattern is deterministic: see [`ConnectiveSpec::joins`]. Default 1 (every
    /// site).
    #[serde(default = "one")]
    pub density: f32,
    /// The layers are never pushed closer than this, metres, in `[0, gap)` where `gap` is the
    /// difference of the two offsets. Default 0.
    #[serde(default)]
    pub min_gap: f32,
    /// How far apart the fibres' sites are, metres across the surface, at least 0: where the element
    /// spacing is finer, one element in `k` along each axis is a site (`k` the nearest whole number to
    /// this over the spacing, see [`ConnectiveSpec::stride`]), so that a finer `resolution` joins the
    /// layers with the same fibres per square millimetre, not more. 0: every element is a site.
    /// Default `FIBRE_SPACING`.
    #[serde(default = "fibre_spacing")]
    pub spacing: f32,
}

/// The default spacing of the fibres' sites: 0.3 mm, about the element spacing of the bundled 8 cm
/// sheets at 256 x 192, the finest resolution their exercises are checked at across resolutions
/// (`tests/exercise_resolution.rs`); at and below it every element is a site.
pub const FIBRE_SPACING: f32 = 0.0003;

fn one() -> f32 {
    1.0
}

fn fibre_spacing() -> f32 {
    FIBRE_SPACING
}

impl ConnectiveSpec {
    /// How many elements apart the fibres' sites are along `u` and `v` on a layer whose elements are
    /// `du` and `dv` metres apart: the nearest whole number to [`ConnectiveSpec::spacing`] over each,
    /// at least 1 (and at most `u32::MAX`).
    pub fn stride(&self, du: f32, dv: f32) -> [u32; 2] {
        [du, dv].map(|d| {
            let k = (self.spacing / d).round();
            if k >= 1.0 { k.min(u32::MAX as f32) as u32 } else { 1 }
        })
    }

    /// Whether the element pair at `(i, j)` (indices along u and v) has a fibre, its sites `stride`
    /// elements apart: the site at `(i, j) / stride` joined by [`ConnectiveSpec::joins`]'s pattern
    /// (the same sites, in metres, at every resolution whose stride makes them so).
    pub fn joins_at(&self, i: u32, j: u32, [ku, kv]: [u32; 2]) -> bool {
        let (ku, kv) = (ku.max(1), kv.max(1));
        i.is_multiple_of(ku) && j.is_multiple_of(kv) && self.joins(i / ku, j / kv)
    }

    /// Whether the site at `(i, j)` (indices along u and v) has a fibre: a fixed, evenly spread
    /// pattern (an ordered-dither threshold) so the same scene always gives the same fibres.
    pub fn joins(&self, i: u32, j: u32) -> bool {
        if self.density >= 1.0 {
            return true;
        }
        // Hash (i, j) into [0, 1): a well-spread, reproducible threshold.
        let mut h = (u64::from(i) << 32 | u64::from(j)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        h ^= h >> 29;
        h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 32;
        let t = (h >> 40) as f32 / (1u64 << 24) as f32;
        t < self.density
    }
}

/// Which elements of a surface layer are held in place.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub enum Pinning {
    /// Nothing is pinned: the tissue floats (instruments still hold what they grasp).
    None,
    /// Every edge of an axis that does not wrap: all four edges of a plane or box, both ends of a
    /// cylinder, both poles of a sphere.
    #[default]
    Boundary,
    /// The listed edges only, e.g. `Edges([UMin, UMax])`. Not on a wrapped axis.
    Edges(Vec<Edge>),
    /// Every element whose `(u, v)` fractions fall in both ranges (inclusive), e.g. a small patch
    /// on a sphere: `Patch(u: (0.0, 0.1), v: (0.0, 0.1))`.
    Patch {
        /// Range of `u` fractions, `lo <= hi`, in `[0, 1]`.
        u: (f32, f32),
        /// Range of `v` fractions, `lo <= hi`, in `[0, 1]`.
        v: (f32, f32),
    },
}

/// An edge of the `(u, v)` parameter square.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Edge {
    /// `u = 0` (x = −width/2 on a plane).
    UMin,
    /// `u = 1`.
    UMax,
    /// `v = 0` (z = −depth/2 on a plane, one end of a cylinder, the south pole of a sphere).
    VMin,
    /// `v = 1`.
    VMax,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fibres(spacing: f32) -> ConnectiveSpec {
        ConnectiveSpec { material: Material::default(), density: 0.5, min_gap: 0.0, spacing }
    }

    /// The stride is the nearest whole number of elements to the spacing along each axis, never 0
    /// (every element a site at and below the spacing, and for a spacing of 0), and a spacing beyond
    /// any count of elements leaves one site per sheet rather than overflowing.
    #[test]
    fn the_stride_rounds_the_spacing_to_elements() {
        let c = fibres(FIBRE_SPACING);
        assert_eq!(c.stride(0.08 / 511.0, 0.06 / 383.0), [2, 2], "512 x 384 of an 8 x 6 cm sheet");
        assert_eq!(c.stride(0.08 / 255.0, 0.06 / 191.0), [1, 1], "256 x 192");
        assert_eq!(c.stride(0.08 / 63.0, 0.06 / 47.0), [1, 1], "64 x 48");
        assert_eq!(c.stride(0.08 / 1023.0, 0.0003), [4, 1], "each axis on its own");
        assert_eq!(fibres(0.0).stride(1e-6, 1e-6), [1, 1], "0: every element");
        assert_eq!(fibres(1e30).stride(1e-6, 1e-6), [u32::MAX, u32::MAX], "beyond any sheet");
        assert_eq!(fibres(1e30).stride(f32::INFINITY, f32::INFINITY), [1, 1], "no links along an axis");
    }

    /// With a stride, only the elements on the stride's lattice are sites, and the site at `(i, j) · k`
    /// is joined where the unstrided pattern joins `(i, j)`.
    #[test]
    fn strided_sites_follow_the_pattern() {
        let c = fibres(FIBRE_SPACING);
        for j in 0..40 {
            for i in 0..40 {
                assert_eq!(c.joins_at(i, j, [1, 1]), c.joins(i, j));
                let on = i.is_multiple_of(2) && j.is_multiple_of(3);
                assert_eq!(c.joins_at(i, j, [2, 3]), on && c.joins(i / 2, j / 3), "({i}, {j})");
            }
        }
        assert!(c.joins_at(0, 0, [u32::MAX, u32::MAX]) == c.joins(0, 0));
    }
}
