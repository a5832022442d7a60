//! The comparison of ChainMail with relaxation against the linear FEM on the same block: same grid,
//! same base pinned (the y = 0 face), the same displacement imposed on the top-centre node, a small one
//! (2 % of the block height) and a large one (20 %). For each, the surface displacement error of
//! ChainMail against the FEM (RMS over the free surface nodes of `|u_cm − u_fem|`, divided by the
//! imposed displacement's magnitude) and the time per step of each.
//!
//! ChainMail parameters (defaults of [`CompareConfig`]): relative limits stretch 1.2, compress 0.7,
//! shear 0.3 (compress 0.7 rather than the engine's 0.8 so that the large push, 20 % of the height on
//! one column of links, is reachable without a pinned element blocking it), relaxation stiffness 1,
//! relaxation over the whole body until no element moves more than `1e-6 ×` the imposed displacement
//! in a sweep (at most 20 000 sweeps). A *ChainMail step* for timing is one deformation plus 10
//! relaxation sweeps. An *FEM step* is one [`FemModel::impose`] (a 3 × 3 solve and the selective
//! multiplication). Relaxation converges to the discrete harmonic field of the lattice whatever the
//! limits, so the relaxed error measures the graph-Laplacian model against linear elasticity; the
//! unrelaxed and 10-sweep errors show what the limits give before that.
//!
//! Measured on block_16 (release, 2-core box, E = 3 kPa, ν = 0.45, spacing 5 mm): FEM load 2.8 s,
//! 165 MiB dense; relaxed ChainMail RMS error 0.084 of the imposed displacement (max 0.18) at both 2 %
//! and 20 %, unrelaxed 0.077 (2 %) and 0.149 (20 %); ChainMail step (deform + 10 sweeps) ≈ 0.43 ms,
//! FEM step ≈ 2 µs.

use std::fmt;
use web_time::Instant;

use serde::{Deserialize, Serialize};

use super::error::FemError;
use super::material::ElasticMaterial;
use super::mesh::{NodeId, Split, TetMesh};
use super::model::{Base, FemModel, LoadOptions, Supports};
use crate::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

/// What to compare.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CompareConfig {
    /// Nodes along each axis (the same for the ChainMail lattice). Default `[16, 16, 16]` (block_16).
    pub dims: [usize; 3],
    /// Grid spacing, metres. Default 0.005 (a 7.5 cm block at 16³).
    pub spacing: f64,
    /// FEM material. Default: E = 3 kPa, ν = 0.45, ρ = 1000 kg/m³.
    pub material: ElasticMaterial,
    /// How cubes are cut into tetrahedra. Default six.
    pub split: Split,
    /// ChainMail material. Default relative stretch 1.2, compress 0.7, shear 0.3, stiffness 1.
    pub chainmail: Material,
    /// Imposed displacements as fractions of the block height `(ny − 1) · spacing`. Default
    /// `[0.02, 0.2]`.
    pub magnitudes: Vec<f64>,
    /// Direction of the imposed displacement (normalised here). Default `[0, −1, 0]`: pushing down.
    pub direction: [f64; 3],
    /// Relaxation stops when no element moved more than this fraction of the imposed displacement in a
    /// sweep. Default 1e-6.
    pub relax_tolerance: f64,
    /// Most relaxation sweeps for the converged ChainMail answer. Default 20 000.
    pub max_sweeps: u32,
    /// Relaxation sweeps in one timed ChainMail step. Default 10.
    pub step_sweeps: u32,
    /// How many steps are timed (the mean is reported). Default 50.
    pub timing_repeats: u32,
    /// Memory limit of the FEM load, bytes. Default 512 MiB.
    pub memory_limit: usize,
}

impl Default for CompareConfig {
    fn default() -> Self {
        Self {
            dims: [16, 16, 16],
            spacing: 0.005,
            material: ElasticMaterial::default(),
            split: Split::Six,
            chainmail: Material::relative(1.2, 0.7, 0.3),
            magnitudes: vec![0.02, 0.2],
            direction: [0.0, -1.0, 0.0],
            relax_tolerance: 1e-6,
            max_sweeps: 20_000,
            step_sweeps: 10,
            timing_repeats: 50,
            memory_limit: super::model::DEFAULT_MEMORY_LIMIT,
        }
    }
}

/// The comparison at one imposed displacement.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct CompareRow {
    /// Imposed displacement as a fraction of the block height.
    pub fraction_of_height: f64,
    /// Its magnitude, metres.
    pub imposed: f64,
    /// Share of the imposed displacement ChainMail's deformation achieved (1 unless pinned elements
    /// blocked it).
    pub chainmail_achieved: f64,
    /// RMS surface error after the chain reaction alone, relative to `imposed`.
    pub rms_unrelaxed: f64,
    /// RMS surface error after one timed step (deformation + `step_sweeps` sweeps), relative.
    pub rms_step: f64,
    /// RMS surface error after relaxation to convergence, relative.
    pub rms_relaxed: f64,
    /// Largest surface error after relaxation to convergence, relative.
    pub max_relaxed: f64,
    /// Sweeps relaxation took.
    pub sweeps: u32,
    /// Whether relaxation met its tolerance within `max_sweeps`.
    pub converged: bool,
    /// Force the FEM needs at the node for this displacement, newtons.
    pub fem_force: [f64; 3],
    /// Force ChainMail's springs need at the node (minus their pull on it) after relaxation to
    /// convergence, newtons: each link a bar of the FEM's Young's modulus and its tributary
    /// cross-section, as the tissue computes it (`tissue/force.rs`).
    pub chainmail_force: [f64; 3],
    /// The same after one timed step (`step_sweeps` sweeps), newtons.
    pub chainmail_force_step: [f64; 3],
    /// `|chainmail_force − fem_force| / |fem_force|`.
    pub force_error: f64,
    /// Mean time of one ChainMail step (deformation + `step_sweeps` sweeps), microseconds.
    pub chainmail_step_us: f64,
    /// Time of the ChainMail deformation plus relaxation to convergence, milliseconds.
    pub chainmail_converge_ms: f64,
    /// Mean time of one FEM step (imposed displacement: small solve + selective multiplication),
    /// microseconds.
    pub fem_step_us: f64,
}

/// The result of [`compare()`].
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct CompareReport {
    /// The configuration used.
    pub config: CompareConfig,
    /// Free surface nodes over which errors are taken.
    pub surface_nodes: usize,
    /// Condensed degrees of freedom of the FEM.
    pub condensed_dofs: usize,
    /// Tetrahedra.
    pub tets: usize,
    /// FEM load time (assembly, condensation, inverse), seconds.
    pub fem_load_s: f64,
    /// Dense memory of the FEM, MiB.
    pub fem_dense_mib: f64,
    /// One row per imposed magnitude.
    pub rows: Vec<CompareRow>,
}

impl fmt::Display for CompareReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.config;
        writeln!(
            f,
            "block {}×{}×{} nodes, spacing {} m, {} tets; FEM E = {} Pa, ν = {}; ChainMail {:?}",
            c.dims[0],
            c.dims[1],
            c.dims[2],
            c.spacing,
            self.tets,
            c.material.young,
            c.material.poisson,
            c.chainmail.limits
        )?;
        writeln!(
            f,
            "FEM: {} free surface nodes, {} condensed dofs, load {:.2} s, dense {:.1} MiB",
            self.surface_nodes, self.condensed_dofs, self.fem_load_s, self.fem_dense_mib
        )?;
        writeln!(f, "errors: RMS over free surface nodes of |u_cm − u_fem| / |imposed|")?;
        writeln!(
            f,
            "| imposed | achieved | rms unrelaxed | rms {} sweeps | rms relaxed | max relaxed | sweeps | CM step µs | CM converge ms | FEM step µs | FEM force N | CM force N ({} sweeps) | CM force N (relaxed) | force error |",
            c.step_sweeps, c.step_sweeps
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")?;
        for r in &self.rows {
            writeln!(
                f,
                "| {:.0} % ({:.2} mm) | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {}{} | {:.1} | {:.1} | {:.1} | {:.4} | {:.4} | {:.4} | {:.0} % |",
                100.0 * r.fraction_of_height,
                1000.0 * r.imposed,
                r.chainmail_achieved,
                r.rms_unrelaxed,
                r.rms_step,
                r.rms_relaxed,
                r.max_relaxed,
                r.sweeps,
                if r.converged { "" } else { " (not converged)" },
                r.chainmail_step_us,
                r.chainmail_converge_ms,
                r.fem_step_us,
                norm(r.fem_force),
                norm(r.chainmail_force_step),
                norm(r.chainmail_force),
                100.0 * r.force_error
            )?;
        }
        Ok(())
    }
}

fn norm(v: [f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn chainmail(e: crate::chainmail::ChainMailError) -> FemError {
    FemError::BadParameter(format!("ChainMail: {e}"))
}

/// Surface error statistics `(rms, max)` of ChainMail against the FEM, relative to `scale`.
fn errors(model: &FemModel, body: &Body, u_fem: &[f64], scale: f64) -> (f64, f64) {
    let rest = body.lattice().rest_positions();
    let pos = body.positions();
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    let nodes = model.surface_nodes();
    for &n in nodes {
        let uf = model.displacement(u_fem, n).unwrap_or([0.0; 3]);
        let (p, r) = (pos[n.index()], rest[n.index()]);
        let mut e2 = 0.0;
        for k in 0..3 {
            let d = (p[k] as f64 - r[k] as f64) - uf[k];
            e2 += d * d;
        }
        sum += e2;
        max = max.max(e2.sqrt());
    }
    ((sum / nodes.len().max(1) as f64).sqrt() / scale, max / scale)
}

/// The force needed at element `e` of a ChainMail volume to hold it where it is against its links,
/// newtons: each link a bar of modulus `young` and the tributary cross-section around it (the square of
/// a quarter of the perpendicular links' lengths at both ends, summed: `a²` inside a cubic lattice),
/// the rule `tissue/force.rs` applies to volumes.
fn spring_force(body: &Body, e: ElementId, young: f64) -> [f64; 3] {
    let lattice = body.lattice();
    let (pos, rest) = (body.positions(), lattice.rest_positions());
    let sub = |a: [f32; 3], b: [f32; 3]| [0, 1, 2].map(|k| f64::from(a[k]) - f64::from(b[k]));
    let len = |d: [f64; 3]| d.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut f = [0.0; 3];
    for (n, l) in lattice.neighbours(e) {
        if !body.link_intact(l) {
            continue;
        }
        let r = sub(rest[n.index()], rest[e.index()]);
        let rl = len(r);
        let mut perp = 0.0;
        for end in [e, n] {
            for (m, other) in lattice.neighbours(end) {
                let s = sub(rest[m.index()], rest[end.index()]);
                let cos = (s[0] * r[0] + s[1] * r[1] + s[2] * r[2]) / (len(s) * rl).max(f64::MIN_POSITIVE);
                if other != l && cos.abs() < 0.5 {
                    perp += len(s);
                }
            }
        }
        let side = perp / 8.0;
        let k = young * side * side / rl.max(f64::MIN_POSITIVE);
        let d = sub(pos[n.index()], pos[e.index()]);
        let dl = len(d).max(f64::MIN_POSITIVE);
        let s = k * (dl - rl) / dl;
        // The links pull the element by s·d; holding it there takes the opposite.
        for x in 0..3 {
            f[x] -= s * d[x];
        }
    }
    f
}

/// Runs the comparison (see the module docs for what is measured and the parameters chosen).
pub fn compare(cfg: &CompareConfig) -> Result<CompareReport, FemError> {
    let norm = cfg.direction.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(FemError::BadParameter(format!(
            "direction {:?} must be a non-zero vector",
            cfg.direction
        )));
    }
    if cfg.magnitudes.iter().any(|m| !(m.is_finite() && *m > 0.0)) {
        return Err(FemError::BadParameter(format!("magnitudes {:?} must be positive", cfg.magnitudes)));
    }
    if !(cfg.relax_tolerance.is_finite() && cfg.relax_tolerance >= 0.0) || cfg.timing_repeats == 0 {
        return Err(FemError::BadParameter("relax_tolerance must be ≥ 0 and timing_repeats ≥ 1".into()));
    }
    let dir = cfg.direction.map(|x| x / norm);
    let mesh = TetMesh::block(cfg.dims, cfg.spacing, cfg.split)?;
    let tets = mesh.tet_count();
    let supports = Supports::base(&mesh, Base::Clamped);
    let t0 = Instant::now();
    let model = FemModel::load(
        mesh,
        cfg.material,
        &supports,
        &LoadOptions { memory_limit: cfg.memory_limit },
        |_| {},
    )?;
    let fem_load_s = t0.elapsed().as_secs_f64();

    let [nx, ny, nz] = cfg.dims;
    let top = model.mesh().node_at(nx / 2, ny - 1, nz / 2).ok_or(FemError::EmptyGrid { dims: cfg.dims })?;
    let lattice = Lattice::volume(nx, ny, nz, cfg.spacing as f32).map_err(chainmail)?;
    let mut body = Body::new(lattice, cfg.chainmail).map_err(chainmail)?;
    for n in 0..model.mesh().node_count() {
        if model.mesh().grid_position(NodeId(n as u32)).is_some_and(|g| g[1] == 0) {
            body.set_pinned(ElementId(n as u32), true).map_err(chainmail)?;
        }
    }
    let source = ElementId(top.0);
    body.set_held(source, true).map_err(chainmail)?;
    let mut ws = Workspace::new(&body);
    let rest = body.lattice().rest_positions()[source.index()];
    let height = (ny - 1) as f64 * cfg.spacing;
    let mut u = vec![0.0; model.condensed_dofs()];

    let mut rows = Vec::with_capacity(cfg.magnitudes.len());
    for &fraction in &cfg.magnitudes {
        let imposed = fraction * height;
        let d = dir.map(|x| x * imposed);
        let target = [0, 1, 2].map(|k| rest[k] + d[k] as f32);

        // FEM: the reference answer, then its timing.
        let forces = model.impose(&[(top, d)], &mut u)?;
        let t = Instant::now();
        for _ in 0..cfg.timing_repeats {
            model.impose(std::hint::black_box(&[(top, d)]), &mut u)?;
        }
        let fem_step_us = t.elapsed().as_secs_f64() * 1e6 / cfg.timing_repeats as f64;

        // ChainMail: one timed step, repeated from rest.
        let mut step_time = 0.0;
        for _ in 0..cfg.timing_repeats {
            body.reset_to_rest();
            let t = Instant::now();
            body.deform(&mut ws, source, target, Pass::All).map_err(chainmail)?;
            body.relax(&mut ws, RelaxBudget::sweeps(cfg.step_sweeps), RelaxRegion::All);
            step_time += t.elapsed().as_secs_f64();
        }
        let (rms_step, _) = errors(&model, &body, &u, imposed);
        let chainmail_force_step = spring_force(&body, source, cfg.material.young);

        // ChainMail: the chain reaction alone, then relaxation to convergence.
        body.reset_to_rest();
        let t = Instant::now();
        let def = body.deform(&mut ws, source, target, Pass::All).map_err(chainmail)?;
        let (rms_unrelaxed, _) = errors(&model, &body, &u, imposed);
        let t_unrelaxed = t.elapsed();
        let t = Instant::now();
        let budget = RelaxBudget {
            max_sweeps: cfg.max_sweeps,
            max_time: None,
            tolerance: (cfg.relax_tolerance * imposed) as f32,
        };
        let report = body.relax(&mut ws, budget, RelaxRegion::All);
        let converge = t_unrelaxed + t.elapsed();
        let (rms_relaxed, max_relaxed) = errors(&model, &body, &u, imposed);
        let chainmail_force = spring_force(&body, source, cfg.material.young);
        let fem_force = forces.first().copied().unwrap_or([0.0; 3]);
        let diff = (0..3).map(|k| (chainmail_force[k] - fem_force[k]).powi(2)).sum::<f64>().sqrt();
        let scale = fem_force.iter().map(|x| x * x).sum::<f64>().sqrt().max(f64::MIN_POSITIVE);
        rows.push(CompareRow {
            fraction_of_height: fraction,
            imposed,
            chainmail_achieved: def.fraction as f64,
            rms_unrelaxed,
            rms_step,
            rms_relaxed,
            max_relaxed,
            sweeps: report.sweeps,
            converged: report.converged,
            fem_force,
            chainmail_force,
            chainmail_force_step,
            force_error: diff / scale,
            chainmail_step_us: step_time * 1e6 / cfg.timing_repeats as f64,
            chainmail_converge_ms: converge.as_secs_f64() * 1e3,
            fem_step_us,
        });
    }
    Ok(CompareReport {
        config: cfg.clone(),
        surface_nodes: model.surface_nodes().len(),
        condensed_dofs: model.condensed_dofs(),
        tets,
        fem_load_s,
        fem_dense_mib: model.dense_bytes() as f64 / (1u64 << 20) as f64,
        rows,
    })
}
