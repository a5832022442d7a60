//! Materials: how far a link may stretch, compress and shear, how stiff it is in relaxation, and when
//! it tears.

use serde::{Deserialize, Serialize};

use super::error::{ChainMailError, finite};

/// The geometric limits of a link, in one of the two forms of the papers.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Limits {
    /// Li, Brodlie and Phillips: limits relative to the link's rest length `Dist`, for non-uniform
    /// lattices. Along the link the separation stays within `min_compress·Dist ..= max_stretch·Dist`;
    /// across it within `±max_shear·Dist`.
    Relative {
        /// MaxRelStretch, at least 1. Example: 1.2 lets a link grow by a fifth.
        max_stretch: f32,
        /// MinRelCompress, in `(0, 1]`. Example: 0.8.
        min_compress: f32,
        /// MaxRelShear, not negative. Example: 0.3.
        max_shear: f32,
    },
    /// Gibson: absolute limits in lattice units (metres on a plain grid), for uniform lattices.
    Absolute {
        /// minDx: smallest separation along the link.
        min_dist: f32,
        /// maxDx: largest separation along the link.
        max_dist: f32,
        /// maxHorizDy: largest offset across the link.
        max_shear: f32,
    },
}

impl Default for Limits {
    fn default() -> Self {
        Limits::Relative { max_stretch: 1.2, min_compress: 0.8, max_shear: 0.3 }
    }
}

/// A link material.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// ChainMail limits. Default: relative, stretch 1.2, compress 0.8, shear 0.3.
    #[serde(default)]
    pub limits: Limits,
    /// Weight of the link in relaxation (dimensionless, relative to other materials). Default 1.
    #[serde(default = "one")]
    pub stiffness: f32,
    /// A link whose length exceeds `tear_ratio` times its rest length breaks (tears). `None`: never.
    #[serde(default)]
    pub tear_ratio: Option<f32>,
    /// Young's modulus E of the tissue, pascals: with [`Material::thickness`], what the tissue's force on
    /// an instrument is computed from (the chain reaction and relaxation do not use it). Default
    /// [`DEFAULT_YOUNG_MODULUS`] (1 MPa).
    #[serde(default = "default_young")]
    pub young_modulus: f32,
    /// Thickness of a layer, metres: a membrane's link of rest length `L` and width `w` is a spring of
    /// `E·t·w/L` newtons per metre (on a square grid `E·t`, whatever the element spacing). Not used by
    /// connective fibres (their cross-section is their elements' area) or volumes. Default
    /// [`DEFAULT_THICKNESS`] (1 mm).
    #[serde(default = "default_thickness")]
    pub thickness: f32,
    /// Energy needed to cut through a unit area of the tissue, joules per square metre: the scalpel's
    /// resistance. Default [`DEFAULT_TOUGHNESS`].
    #[serde(default = "default_toughness")]
    pub toughness: f32,
    /// Poisson's ratio ν of a volume, in `(−1, 0.5)`: with it, a volume's relaxation lowers the
    /// linear-elastic energy of each lattice cell (the cell cut into six tetrahedra, as the FEM reference
    /// cuts it), so pressed tissue bulges at its sides as a solid does, and stays within the limits.
    /// `None` (the default): relaxation lowers the links' own energy, each link a spring on its
    /// offset (Gibson's relaxation, with no Poisson effect). Surfaces have no cells and ignore it.
    #[serde(default)]
    pub poisson_ratio: Option<f32>,
}

/// Default Young's modulus, pascals: a soft membrane (skin and meninges lie between about 0.1 and
/// 60 MPa in tensile tests).
pub const DEFAULT_YOUNG_MODULUS: f32 = 1.0e6;
/// Default layer thickness, metres.
pub const DEFAULT_THICKNESS: f32 = 1.0e-3;
/// Default cutting toughness, joules per square metre (soft tissues: about 0.1 to 5 kJ/m²).
pub const DEFAULT_TOUGHNESS: f32 = 1000.0;

fn one() -> f32 {
    1.0
}

fn default_young() -> f32 {
    DEFAULT_YOUNG_MODULUS
}

fn default_thickness() -> f32 {
    DEFAULT_THICKNESS
}

fn default_toughness() -> f32 {
    DEFAULT_TOUGHNESS
}

impl Default for Material {
    fn default() -> Self {
        Self {
            limits: Limits::default(),
            stiffness: 1.0,
            tear_ratio: None,
            young_modulus: DEFAULT_YOUNG_MODULUS,
            thickness: DEFAULT_THICKNESS,
            toughness: DEFAULT_TOUGHNESS,
            poisson_ratio: None,
        }
    }
}

impl Material {
    /// A material that does not deform at all: the body moves as one.
    pub fn rigid() -> Self {
        Self {
            limits: Limits::Relative { max_stretch: 1.0, min_compress: 1.0, max_shear: 0.0 },
            ..Self::default()
        }
    }

    /// Relative limits with the given stretch, compress and shear.
    pub fn relative(max_stretch: f32, min_compress: f32, max_shear: f32) -> Self {
        Self { limits: Limits::Relative { max_stretch, min_compress, max_shear }, ..Self::default() }
    }

    /// Checks that the limits can hold: finite, stretch at least 1, compress in (0, 1], shear not
    /// negative, stiffness positive, tear ratio above the stretch limit.
    pub fn validate(&self) -> Result<(), ChainMailError> {
        match self.limits {
            Limits::Relative { max_stretch, min_compress, max_shear } => {
                finite("max_stretch", max_stretch)?;
                finite("min_compress", min_compress)?;
                finite("max_shear", max_shear)?;
                if max_stretch < 1.0 {
                    return Err(ChainMailError::BadMaterial(format!(
                        "max_stretch is {max_stretch}, expected at least 1 (a link may not be forced shorter than its rest length by stretching)"
                    )));
                }
                if !(min_compress > 0.0 && min_compress <= 1.0) {
                    return Err(ChainMailError::BadMaterial(format!(
                        "min_compress is {min_compress}, expected a value in (0, 1]"
                    )));
                }
                if max_shear < 0.0 {
                    return Err(ChainMailError::BadMaterial(format!(
                        "max_shear is {max_shear}, expected 0 or more"
                    )));
                }
            }
            Limits::Absolute { min_dist, max_dist, max_shear } => {
                finite("min_dist", min_dist)?;
                finite("max_dist", max_dist)?;
                finite("max_shear", max_shear)?;
                if !(min_dist > 0.0 && min_dist <= max_dist) {
                    return Err(ChainMailError::BadMaterial(format!(
                        "min_dist {min_dist} and max_dist {max_dist}: expected 0 < min_dist <= max_dist"
                    )));
                }
                if max_shear < 0.0 {
                    return Err(ChainMailError::BadMaterial(format!(
                        "max_shear is {max_shear}, expected 0 or more"
                    )));
                }
            }
        }
        finite("stiffness", self.stiffness)?;
        if self.stiffness <= 0.0 {
            return Err(ChainMailError::BadMaterial(format!(
                "stiffness is {}, expected a positive number",
                self.stiffness
            )));
        }
        for (name, x, unit) in [
            ("young_modulus", self.young_modulus, "pascals"),
            ("thickness", self.thickness, "metres"),
            ("toughness", self.toughness, "joules per square metre"),
        ] {
            finite(name, x)?;
            if x <= 0.0 {
                return Err(ChainMailError::BadMaterial(format!(
                    "{name} is {x}, expected a positive number of {unit}"
                )));
            }
        }
        if let Some(nu) = self.poisson_ratio {
            finite("poisson_ratio", nu)?;
            if !(nu > -1.0 && nu < 0.5) {
                return Err(ChainMailError::BadMaterial(format!(
                    "poisson_ratio is {nu}, expected a value in (-1, 0.5) (0.5 would be incompressible)"
                )));
            }
        }
        if let Some(t) = self.tear_ratio {
            finite("tear_ratio", t)?;
            if t <= 1.0 {
                return Err(ChainMailError::BadMaterial(format!(
                    "tear_ratio is {t}, expected more than 1 (links would tear at rest)"
                )));
            }
        }
        Ok(())
    }

    /// The constraint box `[lo, hi]` on a link's offset, for a link of rest offset `rest` (its largest
    /// component positive, along `axis`) and per-axis reference lengths `scale` (the `Dist` that the
    /// relative limits multiply, which may differ per axis on a surface lattice).
    pub(crate) fn link_box(&self, rest: [f32; 3], axis: usize, scale: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for k in 0..3 {
            if k == axis {
                let (a, b) = match self.limits {
                    Limits::Relative { max_stretch, min_compress, .. } => {
                        (min_compress * rest[k], max_stretch * rest[k])
                    }
                    Limits::Absolute { min_dist, max_dist, .. } => (min_dist, max_dist),
                };
                lo[k] = a.min(b);
                hi[k] = a.max(b);
            } else {
                let s = match self.limits {
                    Limits::Relative { max_shear, .. } => max_shear * scale[k],
                    Limits::Absolute { max_shear, .. } => max_shear,
                };
                lo[k] = rest[k] - s;
                hi[k] = rest[k] + s;
            }
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_material_is_valid() {
        assert!(Material::default().validate().is_ok());
        assert!(Material::rigid().validate().is_ok());
    }

    #[test]
    fn inverted_limits_are_refused() {
        assert!(Material::relative(0.5, 0.8, 0.1).validate().is_err());
        assert!(Material::relative(1.2, 1.5, 0.1).validate().is_err());
        assert!(Material::relative(1.2, 0.8, -0.1).validate().is_err());
        assert!(Material::relative(f32::NAN, 0.8, 0.1).validate().is_err());
        for nu in [0.5, -1.0, f32::NAN, 2.0] {
            assert!(Material { poisson_ratio: Some(nu), ..Material::default() }.validate().is_err());
        }
        assert!(Material { poisson_ratio: Some(0.45), ..Material::default() }.validate().is_ok());
    }

    #[test]
    fn relative_box_scales_with_rest_length() {
        let m = Material::relative(1.5, 0.5, 0.25);
        let (lo, hi) = m.link_box([2.0, 0.0, 0.0], 0, [2.0, 2.0, 2.0]);
        assert_eq!(lo, [1.0, -0.5, -0.5]);
        assert_eq!(hi, [3.0, 0.5, 0.5]);
    }
}
