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
    /// Share of element pairs joined, in `(0, 1]`. The pattern is deterministic: see
    /// [`ConnectiveSpec::joins`]. Default 1 (every pair).
    #[serde(default = "one")]
    pub density: f32,
    /// The layers are never pushed closer than this, metres, in `[0, gap)` where `gap` is the
    /// difference of the two offsets. Default 0.
    #[serde(default)]
    pub min_gap: f32,
}

fn one() -> f32 {
    1.0
}

impl ConnectiveSpec {
    /// Whether the element pair at `(i, j)` (indices along u and v) has a fibre: a fixed, evenly
    /// spread pattern (an ordered-dither threshold) so the same scene always gives the same fibres.
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
