//! The comparison of ChainMail with relaxation against the linear FEM on the same block: same grid,
//! same base pinned (the y = 0 face), the same displacement imposed on the top-centre node, a small one
//! (2 % of the block height) and a large one (20 %). For each, the surface displacement error of
//! ChainMail against the FEM (RMS over the free surface nodes of `|u_cm − u_fem|`, divided by the
//! imposed displacement's magnitude) and the time per step of each.
//!
//! ChainMail parameters (defaults of [`CompareConfig`], [`chainmail_material`]): relative limits
//! stretch 1.2, compress 0.7, shear 0.3 (compress 0.7 rather than the engine's 0.8 so that the large
//! push, 20 % of the height on one column of links, is reachable without a pinned element blocking it);
//! relaxation of elastic cells with the FEM material's modulus and Poisson's ratio
//! ([`Material::poisson_ratio`]: each lattice cell cut into the FEM's six tetrahedra, relaxed by
//! projected Gauss-Seidel within the limits), over the whole body until no element moves more than
//! `1e-6 ×` the imposed displacement in a sweep (nor less than two f32 spacings across the block; at
//! most 20 000 sweeps). `poisson_ratio: None` compares Gibson's relaxation of the links' springs
//! instead (`dissect compare --energy links`). A *ChainMail step* for timing is one deformation plus 10
//! relaxation sweeps. An *FEM step* is one [`FemModel::impose`] (a 3 × 3 solve and the selective
//! multiplication). Elastic cells relax to the FEM's own answer where the limits do not bind, so the
//! relaxed error measures what the limits change; the links' springs relax to the lattice's discrete
//! harmonic field, which is not linear elasticity (no Poisson effect), so theirs measures the model too.
//!
//! The force on the grasped patch (the top nodes within [`CompareConfig::grasp_radius`]) is the FEM's
//! reaction against ChainMail's: with elastic cells, `K u` summed over the patch
//! ([`Body::elastic_force`]); with the links' springs, each link `c·A/L` on the change of its offset
//! with `c` = [`ElasticMaterial::lattice_modulus`] (no constant fitted). The base's is the same sum
//! over the pinned base.
//!
//! Measured on block_16 (release, 2-core box, E = 3 kPa, ν = 0.45, spacing 5 mm, 5 nodes grasped,
//! 2026-11-30). Elastic cells: relaxed RMS error 0.007 (2 %) and 0.184 (20 %), 10 sweeps 0.134 and
//! 0.146; force 0.0759 N against the FEM's 0.0759 N at 2 %, 0.281 N against 0.759 N at 20 % (the
//! limits carry the rest to the base: 1.76 N); ChainMail step (deform + 10 sweeps) 4 to 5 ms,
//! relaxation to convergence 2 400 and 5 500 sweeps (0.9 and 1.9 s). The links' springs: 0.131 and
//! 0.281 relaxed, force 0.0808 N at 2 %; step 0.6 ms. FEM load 5 to 6 s, 165 MiB dense; FEM step
//! ≈ 15 µs.

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
    /// ChainMail material. Default [`chainmail_material`] of the FEM material: relative stretch 1.2,
    /// compress 0.7, shear 0.3, elastic cells of the FEM's E and ν.
    pub chainmail: Material,
    /// Imposed displacements as fractions of the block height `(ny − 1) · spacing`. Default
    /// `[0.02, 0.2]`.
    pub magnitudes: Vec<f64>,
    /// Direction of the imposed displacement (normalised here). Default `[0, −1, 0]`: pushing down.
    pub direction: [f64; 3],
    /// The grasped patch: every top node within this distance of the top-centre node (across the top
    /// face) is imposed the same displacement, as forceps hold a patch of tissue, metres. Default
    /// 0.005 (the centre and its four neighbours at the default spacing); 0 pushes one node.
    #[serde(default = "default_grasp_radius")]
    pub grasp_radius: f64,
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
            chainmail: chainmail_material(&ElasticMaterial::default()),
            magnitudes: vec![0.02, 0.2],
            direction: [0.0, -1.0, 0.0],
            grasp_radius: default_grasp_radius(),
            relax_tolerance: 1e-6,
            max_sweeps: 20_000,
            step_sweeps: 10,
            timing_repeats: 50,
            memory_limit: super::model::DEFAULT_MEMORY_LIMIT,
        }
    }
}

/// The ChainMail material that stands for `material` in the comparison: relative limits stretch 1.2,
/// compress 0.7, shear 0.3, elastic cells of the same Young's modulus and Poisson's ratio.
pub fn chainmail_material(material: &ElasticMaterial) -> Material {
    Material {
        poisson_ratio: Some(material.poisson as f32),
        young_modulus: material.young as f32,
        ..Material::relative(1.2, 0.7, 0.3)
    }
}

fn default_grasp_radius() -> f64 {
    0.005
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
    /// Force the FEM needs on the grasped nodes for this displacement (their sum), newtons.
    pub fem_force: [f64; 3],
    /// Force ChainMail needs on the grasped nodes after relaxation to convergence, newtons: with
    /// elastic cells `K u` summed over them; with the links' springs, minus the pull of the links
    /// leaving the patch, each a spring `c·A/L` on the change of its offset, `c` =
    /// [`ElasticMaterial::lattice_modulus`] of the FEM's material. As the tissue computes a volume's
    /// force (`tissue/force.rs`).
    pub chainmail_force: [f64; 3],
    /// The same after one timed step (`step_sweeps` sweeps), newtons.
    pub chainmail_force_step: [f64; 3],
    /// What the same springs pull on the pinned base after relaxation to convergence, newtons: equal
    /// to `chainmail_force` when every free element is balanced by its springs alone, more when link
    /// limits hold elements where their springs would not (the force then reaches the base through
    /// the limits).
    pub chainmail_base_force: [f64; 3],
    /// `|chainmail_force − fem_force| / |fem_force|`.
    pub force_error: f64,
    /// Links of the ChainMail lattice that the FEM's own displacement field (every node's, the
    /// interior recovered from the surface) puts outside their constraint boxes by more than a
    /// thousandth of a spacing: no ChainMail state that keeps its limits can match the FEM there.
    pub fem_links_outside: usize,
    /// The most any link lies outside its box in the FEM's field, in spacings.
    pub fem_worst_outside: f64,
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
    /// Top nodes grasped (imposed the displacement).
    pub grasped_nodes: usize,
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
            "block {}×{}×{} nodes, spacing {} m, {} tets; FEM E = {} Pa, ν = {}; ChainMail {:?}, relaxing {}",
            c.dims[0],
            c.dims[1],
            c.dims[2],
            c.spacing,
            self.tets,
            c.material.young,
            c.material.poisson,
            c.chainmail.limits,
            match c.chainmail.poisson_ratio {
                Some(nu) => format!("elastic cells (ν = {nu})"),
                None => "the links' springs".to_string(),
            }
        )?;
        writeln!(
            f,
            "FEM: {} free surface nodes, {} condensed dofs, load {:.2} s, dense {:.1} MiB; {} top nodes grasped (within {} m)",
            self.surface_nodes,
            self.condensed_dofs,
            self.fem_load_s,
            self.fem_dense_mib,
            self.grasped_nodes,
            c.grasp_radius
        )?;
        writeln!(f, "errors: RMS over free surface nodes of |u_cm − u_fem| / |imposed|")?;
        writeln!(
            f,
            "| imposed | achieved | rms unrelaxed | rms {} sweeps | rms relaxed | max relaxed | sweeps | CM step µs | CM converge ms | FEM step µs | FEM force N | CM force N ({} sweeps) | CM force N (relaxed) | force error | CM base N |",
            c.step_sweeps, c.step_sweeps
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")?;
        for r in &self.rows {
            writeln!(
                f,
                "| {:.0} % ({:.2} mm) | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {}{} | {:.1} | {:.1} | {:.1} | {:.4} | {:.4} | {:.4} | {:.0} % | {:.4} |",
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
                100.0 * r.force_error,
                norm(r.chainmail_base_force)
            )?;
        }
        for r in &self.rows {
            let at = 100.0 * r.fraction_of_height;
            match r.fem_links_outside {
                0 => writeln!(
                    f,
                    "at {at:.0} %, the FEM's own field keeps every link within ChainMail's limits"
                )?,
                n => writeln!(
                    f,
                    "at {at:.0} %, the FEM's own field puts {n} links outside ChainMail's limits (by up to {:.2} spacings): no state within the limits can follow it there",
                    r.fem_worst_outside
                )?,
            }
        }
        Ok(())
    }
}

/// How many links the FEM's whole displacement field `u` (surface dofs; the interior recovered) puts
/// outside their ChainMail boxes by more than a thousandth of a spacing, and the most any lies out, in
/// spacings. Leaves `body` at rest.
fn fem_outside_limits(
    model: &FemModel,
    body: &mut Body,
    u: &[f64],
    spacing: f64,
) -> Result<(usize, f64), FemError> {
    let field = model.full_field(u)?;
    body.reset_to_rest();
    let rest = body.lattice().rest_positions().to_vec();
    for (n, (d, r)) in field.iter().zip(&rest).enumerate() {
        let p = [0, 1, 2].map(|k| r[k] + d[k] as f32);
        body.set_position(ElementId(n as u32), p).map_err(chainmail)?;
    }
    let (mut outside, mut worst) = (0, 0.0f64);
    for l in 0..body.link_count() {
        let v = body.link_violation(crate::chainmail::LinkId(l as u32)).unwrap_or(0.0) as f64 / spacing;
        if v > 1e-3 {
            outside += 1;
        }
        worst = worst.max(v);
    }
    body.reset_to_rest();
    Ok((outside, worst))
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

/// The force needed on a set of elements of a ChainMail volume to hold them where they are against
/// the links that leave the set, newtons: each link a spring `modulus·A/L` on the change of its
/// offset from rest, `A` the square of the mean length of the perpendicular links at both ends (`a²`
/// on a cubic lattice, on its faces too: relaxation weighs every link alike, and so must the springs
/// whose balance it finds), the rule `tissue/force.rs` applies to volumes.
fn spring_force(body: &Body, set: &[ElementId], modulus: f64) -> [f64; 3] {
    let lattice = body.lattice();
    let (pos, rest) = (body.positions(), lattice.rest_positions());
    let sub = |a: [f32; 3], b: [f32; 3]| [0, 1, 2].map(|k| f64::from(a[k]) - f64::from(b[k]));
    let len = |d: [f64; 3]| d.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut f = [0.0; 3];
    for &e in set {
        for (n, l) in lattice.neighbours(e) {
            if !body.link_intact(l) || set.contains(&n) {
                continue;
            }
            let r = sub(rest[n.index()], rest[e.index()]);
            let rl = len(r);
            let (mut perp, mut count) = (0.0, 0usize);
            for end in [e, n] {
                for (m, other) in lattice.neighbours(end) {
                    let s = sub(rest[m.index()], rest[end.index()]);
                    let cos =
                        (s[0] * r[0] + s[1] * r[1] + s[2] * r[2]) / (len(s) * rl).max(f64::MIN_POSITIVE);
                    if other != l && cos.abs() < 0.5 {
                        perp += len(s);
                        count += 1;
                    }
                }
            }
            let side = perp / count.max(1) as f64;
            let k = modulus * side * side / rl.max(f64::MIN_POSITIVE);
            let d = sub(pos[n.index()], pos[e.index()]);
            // The link pulls the element by k·(d − r); holding it there takes the opposite.
            for x in 0..3 {
                f[x] -= k * (d[x] - r[x]);
            }
        }
    }
    f
}

/// The force that holds `set` where it is: the elastic cells' (`K u` over the set) where the body
/// has them, else the links' springs ([`spring_force`]).
fn held_force(body: &Body, set: &[ElementId], modulus: f64) -> [f64; 3] {
    match body.elastic_force(set) {
        Some(f) => f.map(f64::from),
        None => spring_force(body, set, modulus),
    }
}

/// Moves the grasped patch as the tissue's forceps do: the centre to `centre_goal` in a chain
/// reaction of its own, then the rest to their goals together, the centre held; then all held.
fn grasp(
    body: &mut Body,
    ws: &mut Workspace,
    held: &[ElementId],
    goals: &[[f32; 3]],
    centre_goal: [f32; 3],
) -> Result<crate::chainmail::Deformation, FemError> {
    for &e in held {
        body.set_held(e, false).map_err(chainmail)?;
    }
    let def = body.deform(ws, held[0], centre_goal, Pass::All).map_err(chainmail)?;
    body.set_held(held[0], true).map_err(chainmail)?;
    if held.len() > 1 {
        body.deform_group(ws, &held[1..], goals, Pass::All).map_err(chainmail)?;
    }
    for &e in held {
        body.set_held(e, true).map_err(chainmail)?;
    }
    Ok(def)
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
    if !(cfg.grasp_radius.is_finite() && cfg.grasp_radius >= 0.0) {
        return Err(FemError::BadParameter(format!("grasp_radius {} m must be 0 or more", cfg.grasp_radius)));
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
    // The grasped patch, its centre first.
    let mut patch = vec![top];
    let reach = (cfg.grasp_radius / cfg.spacing).max(0.0) + 1e-9;
    for k in 0..nz {
        for i in 0..nx {
            let (di, dk) = (i as f64 - (nx / 2) as f64, k as f64 - (nz / 2) as f64);
            if let Some(n) = model.mesh().node_at(i, ny - 1, k)
                && n != top
                && (di * di + dk * dk).sqrt() <= reach
            {
                patch.push(n);
            }
        }
    }
    let held: Vec<ElementId> = patch.iter().map(|n| ElementId(n.0)).collect();
    let modulus = cfg.material.lattice_modulus();
    let lattice = Lattice::volume(nx, ny, nz, cfg.spacing as f32).map_err(chainmail)?;
    let mut body = Body::new(lattice, cfg.chainmail).map_err(chainmail)?;
    let mut pinned = Vec::new();
    for n in 0..model.mesh().node_count() {
        if model.mesh().grid_position(NodeId(n as u32)).is_some_and(|g| g[1] == 0) {
            body.set_pinned(ElementId(n as u32), true).map_err(chainmail)?;
            pinned.push(ElementId(n as u32));
        }
    }
    let mut ws = Workspace::new(&body);
    let rest = body.lattice().rest_positions().to_vec();
    let mut goals = vec![[0.0f32; 3]; held.len() - 1];
    let height = (ny - 1) as f64 * cfg.spacing;
    let mut u = vec![0.0; model.condensed_dofs()];

    let mut rows = Vec::with_capacity(cfg.magnitudes.len());
    for &fraction in &cfg.magnitudes {
        let imposed = fraction * height;
        let d = dir.map(|x| x * imposed);
        let moved = |e: ElementId| [0, 1, 2].map(|k| rest[e.index()][k] + d[k] as f32);
        for (g, &e) in goals.iter_mut().zip(&held[1..]) {
            *g = moved(e);
        }
        let imposed_nodes: Vec<(NodeId, [f64; 3])> = patch.iter().map(|&n| (n, d)).collect();

        // FEM: the reference answer, then its timing.
        let mut work = super::ImposeWork::default();
        let forces = model.impose_with(&imposed_nodes, &mut u, &mut work)?.to_vec();
        let t = Instant::now();
        for _ in 0..cfg.timing_repeats {
            model.impose_with(std::hint::black_box(&imposed_nodes), &mut u, &mut work)?;
        }
        let fem_step_us = t.elapsed().as_secs_f64() * 1e6 / cfg.timing_repeats as f64;

        // ChainMail: one timed step, repeated from rest.
        let mut step_time = 0.0;
        for _ in 0..cfg.timing_repeats {
            body.reset_to_rest();
            let t = Instant::now();
            grasp(&mut body, &mut ws, &held, &goals, moved(held[0]))?;
            body.relax(&mut ws, RelaxBudget::sweeps(cfg.step_sweeps), RelaxRegion::All);
            step_time += t.elapsed().as_secs_f64();
        }
        let (rms_step, _) = errors(&model, &body, &u, imposed);
        let chainmail_force_step = held_force(&body, &held, modulus);

        // ChainMail: the chain reaction alone, then relaxation to convergence.
        body.reset_to_rest();
        let t = Instant::now();
        let def = grasp(&mut body, &mut ws, &held, &goals, moved(held[0]))?;
        let (rms_unrelaxed, _) = errors(&model, &body, &u, imposed);
        let t_unrelaxed = t.elapsed();
        let t = Instant::now();
        // (No finer than twice the spacing of f32 positions across the block: sweeps of elastic
        // cells end in moves of an ulp or two, which a finer tolerance would wait on for ever.)
        let extent = cfg.dims.iter().map(|&n| (n - 1) as f64 * cfg.spacing).fold(0.0, f64::max);
        let budget = RelaxBudget {
            max_sweeps: cfg.max_sweeps,
            max_time: None,
            tolerance: (cfg.relax_tolerance * imposed).max(2.0 * f64::from(f32::EPSILON) * extent) as f32,
        };
        let report = body.relax(&mut ws, budget, RelaxRegion::All);
        let converge = t_unrelaxed + t.elapsed();
        let (rms_relaxed, max_relaxed) = errors(&model, &body, &u, imposed);
        let chainmail_force = held_force(&body, &held, modulus);
        let base = held_force(&body, &pinned, modulus);
        let chainmail_base_force = base.map(|x| -x);
        let fem_force = forces.iter().fold([0.0; 3], |s, f| [0, 1, 2].map(|k| s[k] + f[k]));
        let (fem_links_outside, fem_worst_outside) = fem_outside_limits(&model, &mut body, &u, cfg.spacing)?;
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
            chainmail_base_force,
            force_error: diff / scale,
            fem_links_outside,
            fem_worst_outside,
            chainmail_step_us: step_time * 1e6 / cfg.timing_repeats as f64,
            chainmail_converge_ms: converge.as_secs_f64() * 1e3,
            fem_step_us,
        });
    }
    Ok(CompareReport {
        config: cfg.clone(),
        surface_nodes: model.surface_nodes().len(),
        grasped_nodes: patch.len(),
        condensed_dofs: model.condensed_dofs(),
        tets,
        fem_load_s,
        fem_dense_mib: model.dense_bytes() as f64 / (1u64 << 20) as f64,
        rows,
    })
}
