//! Linear isotropic elasticity: Young's modulus and Poisson's ratio, their Lamé constants and the
//! 6 × 6 material matrix `D` of Hooke's law `σ = D ε`.

use serde::{Deserialize, Serialize};

use super::error::{FemError, finite};

/// A homogeneous, isotropic, linear elastic material.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ElasticMaterial {
    /// Young's modulus E, pascals. Must be positive. Default 3 kPa (soft tissue such as liver).
    pub young: f64,
    /// Poisson's ratio ν, in (−1, 0.5). Default 0.45 (nearly incompressible tissue).
    pub poisson: f64,
    /// Mass density ρ, kg/m³, for the dynamic mode. Must be positive. Default 1000.
    pub density: f64,
}

impl Default for ElasticMaterial {
    fn default() -> Self {
        Self { young: 3.0e3, poisson: 0.45, density: 1000.0 }
    }
}

impl ElasticMaterial {
    /// A material with the given Young's modulus (Pa) and Poisson's ratio, density 1000 kg/m³.
    pub fn new(young: f64, poisson: f64) -> Self {
        Self { young, poisson, ..Self::default() }
    }

    /// Checks the ranges: all finite, E > 0, −1 < ν < 0.5, ρ > 0.
    pub fn validate(&self) -> Result<(), FemError> {
        finite("Young's modulus", self.young)?;
        finite("Poisson's ratio", self.poisson)?;
        finite("density", self.density)?;
        if self.young <= 0.0 {
            return Err(FemError::BadMaterial(format!(
                "Young's modulus is {} Pa, expected a positive value",
                self.young
            )));
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(FemError::BadMaterial(format!(
                "Poisson's ratio is {}, expected a value in (-1, 0.5): at 0.5 the material is incompressible \
                 and λ is infinite; at -1 the shear modulus μ is infinite",
                self.poisson
            )));
        }
        if self.density <= 0.0 {
            return Err(FemError::BadMaterial(format!(
                "density is {} kg/m³, expected a positive value",
                self.density
            )));
        }
        Ok(())
    }

    /// Lamé constants `(λ, μ)`, pascals: `λ = Eν / ((1 + ν)(1 − 2ν))`, `μ = E / (2(1 + ν))`.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
    }

    /// The modulus `c` of a lattice of difference springs equivalent to this material at a loaded
    /// surface, pascals: `c = μ / (1 − ν) = E / (2(1 − ν²))`.
    ///
    /// A link of rest offset `L` and tributary cross-section `A` is then a spring of `c·A/L` pulling
    /// its ends' displacements together (`k·(u_b − u_a)`, in every direction: the energy ChainMail's
    /// relaxation minimises); on a cubic lattice of spacing `a`, `k = c·a`. Each displacement
    /// component of such a lattice is a harmonic field of conductivity `c`: under a force `F` normal
    /// to a half-space's surface it sinks by `F / (2π c r)` at distance `r`, where Boussinesq's
    /// elastic half-space sinks by `F (1 − ν) / (2π μ r)`; a rigid disc of radius `R` pressed by `w`
    /// takes `4 c R w` in the lattice and `2 E R w / (1 − ν²)` in the solid. Both agree when
    /// `c = μ / (1 − ν)`, with no constant fitted to a mesh.
    pub fn lattice_modulus(&self) -> f64 {
        let nu = self.poisson;
        self.young / (2.0 * (1.0 - nu * nu))
    }

    /// The material matrix `D` for strains in Voigt order `(εxx, εyy, εzz, γxy, γyz, γzx)` with
    /// engineering shear strains.
    pub fn d_matrix(&self) -> [[f64; 6]; 6] {
        let (l, m) = self.lame();
        let mut d = [[0.0; 6]; 6];
        for (i, row) in d.iter_mut().enumerate().take(3) {
            for (j, x) in row.iter_mut().enumerate().take(3) {
                *x = if i == j { l + 2.0 * m } else { l };
            }
        }
        for (i, row) in d.iter_mut().enumerate().skip(3) {
            row[i] = m;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_materials_are_refused_with_a_message() {
        for (e, nu) in [(1.0, 0.5), (1.0, 0.7), (1.0, -1.0), (0.0, 0.3), (-5.0, 0.3), (f64::NAN, 0.3)] {
            let err = ElasticMaterial::new(e, nu).validate().expect_err("refused");
            assert!(!err.to_string().is_empty());
        }
        assert!(ElasticMaterial::new(1.0, f64::INFINITY).validate().is_err());
        assert!(ElasticMaterial { density: 0.0, ..ElasticMaterial::default() }.validate().is_err());
        assert!(ElasticMaterial::default().validate().is_ok());
        assert!(ElasticMaterial::new(1.0, -0.99).validate().is_ok());
    }

    #[test]
    fn lame_constants() {
        let (l, m) = ElasticMaterial::new(1.0, 0.25).lame();
        assert!((l - 0.4).abs() < 1e-12 && (m - 0.4).abs() < 1e-12);
    }
}
