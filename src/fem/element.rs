//! The linear tetrahedron: shape-function gradients, the strain-displacement matrix `B` and the element
//! stiffness `Ke = V · Bᵀ D B`.

use nalgebra::{Matrix3, SMatrix};

use super::error::FemError;

/// The 6 × 12 strain-displacement matrix of a linear tetrahedron: strains in Voigt order
/// `(εxx, εyy, εzz, γxy, γyz, γzx)` from the 12 nodal displacements `(u0x, u0y, u0z, u1x, …)`.
pub type BMatrix = SMatrix<f64, 6, 12>;
/// A 12 × 12 element stiffness matrix.
pub type ElementStiffness = SMatrix<f64, 12, 12>;

/// Gradients of the four shape functions and the volume of a tetrahedron with corners `p`, or `None`
/// when it is degenerate.
pub fn shape_gradients(p: &[[f64; 3]; 4]) -> Option<([[f64; 3]; 4], f64)> {
    let col = |a: usize| nalgebra::Vector3::new(p[a][0] - p[0][0], p[a][1] - p[0][1], p[a][2] - p[0][2]);
    let x = Matrix3::from_columns(&[col(1), col(2), col(3)]);
    let det = x.determinant();
    let scale = (1..4).map(|a| col(a).norm()).fold(0.0f64, f64::max);
    let tiny = det.abs() <= 1e-12 * scale * scale * scale;
    if tiny || !det.is_finite() {
        return None;
    }
    let inv = x.try_inverse()?;
    // ξ = X⁻¹ (x − p0): the gradient of N_a (a = 1..3) is row a − 1 of X⁻¹; N0 = 1 − ΣN_a.
    let mut g = [[0.0; 3]; 4];
    for a in 1..4 {
        for k in 0..3 {
            g[a][k] = inv[(a - 1, k)];
            g[0][k] -= inv[(a - 1, k)];
        }
    }
    Some((g, det.abs() / 6.0))
}

/// The strain-displacement matrix for shape-function gradients `g`.
pub fn b_matrix(g: &[[f64; 3]; 4]) -> BMatrix {
    let mut b = BMatrix::zeros();
    for (a, &[bx, by, bz]) in g.iter().enumerate() {
        let c = 3 * a;
        b[(0, c)] = bx;
        b[(1, c + 1)] = by;
        b[(2, c + 2)] = bz;
        b[(3, c)] = by;
        b[(3, c + 1)] = bx;
        b[(4, c + 1)] = bz;
        b[(4, c + 2)] = by;
        b[(5, c)] = bz;
        b[(5, c + 2)] = bx;
    }
    b
}

/// The element stiffness `V · Bᵀ D B` and the volume of the tetrahedron `index` with corners `p`.
pub fn tet_stiffness(
    index: usize,
    p: &[[f64; 3]; 4],
    d: &[[f64; 6]; 6],
) -> Result<(ElementStiffness, f64), FemError> {
    let (g, volume) = shape_gradients(p).ok_or(FemError::DegenerateElement { index, volume: 0.0 })?;
    let b = b_matrix(&g);
    let dm = SMatrix::<f64, 6, 6>::from_fn(|i, j| d[i][j]);
    Ok((b.transpose() * dm * b * volume, volume))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::ElasticMaterial;

    const UNIT: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn rigid_motions_have_no_energy() {
        let d = ElasticMaterial::new(1000.0, 0.3).d_matrix();
        let p = [[0.1, 0.0, 0.2], [1.3, 0.1, 0.0], [0.2, 0.9, 0.1], [0.0, 0.3, 1.1]];
        let (k, v) = tet_stiffness(0, &p, &d).expect("tet");
        assert!(v > 0.0);
        let translation = SMatrix::<f64, 12, 1>::from_fn(|i, _| [0.3, -0.2, 0.5][i % 3]);
        // A small rotation about z: u = ω × x.
        let rotation = SMatrix::<f64, 12, 1>::from_fn(|i, _| {
            let x = p[i / 3];
            [-x[1], x[0], 0.0][i % 3]
        });
        assert!((k * translation).norm() < 1e-9 * k.norm());
        assert!((k * rotation).norm() < 1e-9 * k.norm());
        assert!((k - k.transpose()).norm() < 1e-9 * k.norm());
    }

    #[test]
    fn uniform_strain_is_exact() {
        let (g, v) = shape_gradients(&UNIT).expect("tet");
        assert!((v - 1.0 / 6.0).abs() < 1e-15);
        let b = b_matrix(&g);
        // u = (0.01 x, 0, 0): εxx = 0.01 only.
        let u = SMatrix::<f64, 12, 1>::from_fn(|i, _| if i % 3 == 0 { 0.01 * UNIT[i / 3][0] } else { 0.0 });
        let e = b * u;
        assert!((e[0] - 0.01).abs() < 1e-15 && e.rows(1, 5).norm() < 1e-15);
    }

    #[test]
    fn flat_tet_is_degenerate() {
        let d = ElasticMaterial::default().d_matrix();
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        assert!(matches!(tet_stiffness(3, &flat, &d), Err(FemError::DegenerateElement { index: 3, .. })));
    }
}
