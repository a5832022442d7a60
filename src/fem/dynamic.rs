//! The dynamic mode on the condensed system: `M ü + C u̇ + S u = f` with mass lumped at the free
//! surface nodes, Rayleigh damping `C = c · M`, and finite differences in time,
//!
//! `M (uⁿ⁺¹ − 2uⁿ + uⁿ⁻¹)/Δt² + C (uⁿ⁺¹ − uⁿ⁻¹)/(2Δt) + S uⁿ⁺¹ = f`,
//!
//! so `A uⁿ⁺¹ = f + M (2uⁿ − uⁿ⁻¹)/Δt² + C uⁿ⁻¹/(2Δt)` with `A = S + M/Δt² + C/(2Δt)`, inverted once.
//! Taking the stiffness at the new step keeps the scheme stable for any step; at rest (`uⁿ⁺¹ = uⁿ =
//! uⁿ⁻¹`) it reduces to the static `S u = f`. The right-hand side is dense, so each step is a full
//! `n × n` product, not a selective one (as the paper notes).
//!
//! The interior nodes' mass is dropped by the condensation (only surface nodes carry mass), as in
//! Bro-Nielsen and Cotin; the static answer does not depend on it.

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, Side};

use super::error::{FemError, finite};
use super::mesh::NodeId;
use super::model::{FemModel, LoadOptions};

/// Parameters of the dynamic mode.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicParams {
    /// Time step Δt, seconds. Default 0.01 s.
    pub dt: f64,
    /// Mass-proportional damping `c` in `C = c · M`, per second. Default 20 /s.
    pub damping: f64,
}

impl Default for DynamicParams {
    fn default() -> Self {
        Self { dt: 0.01, damping: 20.0 }
    }
}

/// The dynamic condensed system with its state (the last two surface displacements).
#[derive(Clone, Debug)]
pub struct DynamicModel {
    a_inv: Mat<f64>,
    /// Lumped mass per condensed dof, kg.
    mass: Vec<f64>,
    params: DynamicParams,
    dof: Vec<[u32; 3]>,
    u_prev: Vec<f64>,
    u: Vec<f64>,
    rhs: Vec<f64>,
}

impl DynamicModel {
    /// Builds `A = S + M/Δt² + C/(2Δt)` from a loaded model and inverts it (refused if the extra dense
    /// matrix exceeds `options.memory_limit`). Starts at rest.
    pub fn new(model: &FemModel, params: DynamicParams, options: &LoadOptions) -> Result<Self, FemError> {
        finite("time step", params.dt)?;
        finite("damping", params.damping)?;
        if params.dt <= 0.0 || params.damping < 0.0 {
            return Err(FemError::BadParameter(format!(
                "time step {} s must be positive and damping {} /s not negative",
                params.dt, params.damping
            )));
        }
        let n = model.condensed_dofs();
        let bytes = (n * n * 8) as f64;
        if bytes > options.memory_limit as f64 {
            return Err(FemError::TooBig {
                what: format!("the dense dynamic system inverse ({n} × {n} f64)"),
                needed_mib: bytes / (1u64 << 20) as f64,
                limit_mib: options.memory_limit as f64 / (1u64 << 20) as f64,
            });
        }
        let mut mass = vec![0.0; n];
        for &node in model.surface_nodes() {
            for a in 0..3 {
                if let Some(j) = model.condensed_dof(node, a) {
                    mass[j] = model.nodal_masses()[node.index()];
                }
            }
        }
        let diag = 1.0 / (params.dt * params.dt) + params.damping / (2.0 * params.dt);
        let mut a = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            let col = a.col_as_slice_mut(j);
            if let Some(s) = model.condensed_column(j) {
                col.copy_from_slice(s);
            }
            col[j] += diag * mass[j];
        }
        let llt = a
            .llt(Side::Lower)
            .map_err(|e| FemError::Singular { which: "dynamic", detail: format!("{e:?}") })?;
        let a_inv = llt.inverse();
        Ok(Self {
            a_inv,
            mass,
            params,
            dof: model.dof_table().to_vec(),
            u_prev: vec![0.0; n],
            u: vec![0.0; n],
            rhs: vec![0.0; n],
        })
    }

    /// The current surface displacement (condensed dofs, metres; read node values with
    /// [`FemModel::displacement`]).
    pub fn displacement(&self) -> &[f64] {
        &self.u
    }

    /// The parameters.
    pub fn params(&self) -> DynamicParams {
        self.params
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        self.u.fill(0.0);
        self.u_prev.fill(0.0);
    }

    /// Advances one step under the given forces (newtons) on free surface nodes; components on fixed
    /// axes are ignored. Returns the new surface displacement.
    pub fn step(&mut self, forces: &[(NodeId, [f64; 3])]) -> Result<&[f64], FemError> {
        let n = self.u.len();
        let (dt, c) = (self.params.dt, self.params.damping);
        for (i, r) in self.rhs.iter_mut().enumerate() {
            let m = self.mass[i];
            *r = m * (2.0 * self.u[i] - self.u_prev[i]) / (dt * dt) + c * m * self.u_prev[i] / (2.0 * dt);
        }
        for (node, f) in forces {
            let d = self
                .dof
                .get(node.index())
                .ok_or(FemError::NodeOutOfRange { id: node.0, count: self.dof.len() })?;
            for a in 0..3 {
                finite("force", f[a])?;
                let j = d[a] as usize;
                if d[a] == u32::MAX {
                    continue;
                }
                if j >= n {
                    return Err(FemError::NotSurfaceNode {
                        id: node.0,
                        reason: "it is an interior node, eliminated by the condensation",
                    });
                }
                self.rhs[j] += f[a];
            }
        }
        // uⁿ⁻¹ ← uⁿ; uⁿ ← A⁻¹ rhs (reusing the old uⁿ⁻¹ buffer).
        std::mem::swap(&mut self.u_prev, &mut self.u);
        self.u.fill(0.0);
        for (j, &r) in self.rhs.iter().enumerate() {
            if r != 0.0 {
                for (ui, &a) in self.u.iter_mut().zip(self.a_inv.col_as_slice(j)) {
                    *ui += a * r;
                }
            }
        }
        Ok(&self.u)
    }
}
