//! A volume driven by the linear finite-element model instead of ChainMail (Bro-Nielsen and Cotin):
//! the ChainMail lattice keeps the geometry, the surface mesh and the picking; grasps and pushes impose
//! displacements on surface nodes, and the condensed, pre-inverted model gives the surface's answer by
//! selective matrix-vector multiplication. Cutting is refused: condensation assumes a fixed topology.

use crate::chainmail::{Body, ElementId};
use crate::fem::{
    Base, DynamicModel, DynamicParams, ElasticMaterial, FemError, FemModel, ImposeWork, LoadOptions, NodeId,
    Split, Supports, TetMesh,
};

/// Why a cut on a finite-element volume is refused.
pub const FEM_CUT_REFUSED: &str = "cutting is refused for a finite-element volume: its condensed, pre-inverted stiffness assumes a fixed topology";

/// Parameters of a finite-element volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FemSpec {
    /// Young's modulus, pascals.
    pub young: f32,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson: f32,
    /// Mass density, kg/m³.
    pub density: f32,
    /// Mass-proportional damping, 1/s (dynamic mode).
    pub damping: f32,
    /// Integrate in time (mass and damping) over the world's step instead of solving for equilibrium
    /// every step.
    pub dynamic: bool,
}

/// The model and its current surface displacement.
#[derive(Clone, Debug)]
pub struct FemDrive {
    model: FemModel,
    dynamic: Option<DynamicModel>,
    /// Condensed displacement (static mode).
    u: Vec<f64>,
    /// Scratch of an imposed set: the nodes and displacements, the solve's workspace, and the
    /// loads of a dynamic step (kept so that a press allocates nothing step after step).
    nodes: Vec<(NodeId, [f64; 3])>,
    work: ImposeWork,
    loads: Vec<(NodeId, [f64; 3])>,
    /// The force the block exerts on whatever drives its node (minus the force imposing the
    /// displacement), newtons.
    reaction: [f32; 3],
}

impl FemDrive {
    /// Loads the model for a block of `dims` nodes at `spacing` metres, base clamped, stepped every
    /// `step_seconds` (dynamic mode). Reports progress in `[0, 1]` to `progress`.
    pub fn load(
        dims: [usize; 3],
        spacing: f32,
        spec: &FemSpec,
        step_seconds: f32,
        progress: impl FnMut(f32),
    ) -> Result<Self, FemError> {
        let mesh = TetMesh::block(dims, spacing as f64, Split::Six)?;
        let supports = Supports::base(&mesh, Base::Clamped);
        let material = ElasticMaterial {
            young: spec.young as f64,
            poisson: spec.poisson as f64,
            density: spec.density as f64,
        };
        let options = LoadOptions::default();
        let model = FemModel::load(mesh, material, &supports, &options, progress)?;
        let dynamic = if spec.dynamic {
            Some(DynamicModel::new(
                &model,
                DynamicParams { dt: step_seconds as f64, damping: spec.damping as f64 },
                &options,
            )?)
        } else {
            None
        };
        let u = vec![0.0; model.condensed_dofs()];
        Ok(Self {
            model,
            dynamic,
            u,
            nodes: Vec::new(),
            work: ImposeWork::default(),
            loads: Vec::new(),
            reaction: [0.0; 3],
        })
    }

    /// Imposes `displacement` (metres) on the surface node of element `e` and writes every surface
    /// node's position into `body`; returns how many it wrote.
    pub fn impose(&mut self, e: ElementId, displacement: [f32; 3], body: &mut Body) -> Result<u32, FemError> {
        let node = [(NodeId(e.0), displacement.map(f64::from))];
        let forces = self.model.impose_with(&node, &mut self.u, &mut self.work)?;
        let force = forces.first().copied().unwrap_or([0.0; 3]);
        self.reaction = force.map(|x| -x as f32);
        if let Some(dynamic) = &mut self.dynamic {
            let u = dynamic.step(&[(node[0].0, force)])?;
            self.u.copy_from_slice(u);
        }
        Ok(self.write_into(body))
    }

    /// Imposes a displacement (metres) on each of several surface nodes at once, as a ball does on
    /// the top face it presses, and returns the force that imposes each (newtons, on the node; kept in
    /// the drive's scratch, which grows to the largest set and allocates no further). The
    /// reaction is their sum. Surface displacements are read with [`FemDrive::displacement`] and
    /// written by [`FemDrive::write_into`]. A dynamic block takes its time step only with `step`
    /// (a press tries several sets of nodes in a step and keeps the last).
    pub fn impose_many(
        &mut self,
        imposed: &[(ElementId, [f32; 3])],
        step: bool,
    ) -> Result<&[[f64; 3]], FemError> {
        let Self { model, dynamic, u, nodes, work, loads, reaction } = self;
        nodes.clear();
        nodes.extend(imposed.iter().map(|&(e, d)| (NodeId(e.0), d.map(f64::from))));
        let forces = model.impose_with(nodes, u, work)?;
        let total = forces.iter().fold([0.0f64; 3], |t, f| [t[0] + f[0], t[1] + f[1], t[2] + f[2]]);
        *reaction = total.map(|x| -x as f32);
        if step && let Some(dynamic) = dynamic {
            loads.clear();
            loads.extend(nodes.iter().zip(forces).map(|(n, f)| (n.0, *f)));
            u.copy_from_slice(dynamic.step(loads)?);
        }
        Ok(forces)
    }

    /// Whether the block integrates in time (its dynamic mode).
    pub fn is_dynamic(&self) -> bool {
        self.dynamic.is_some()
    }

    /// The displacement of element `e`'s surface node now, metres (`None` for an interior node).
    pub fn displacement(&self, e: ElementId) -> Option<[f32; 3]> {
        self.model.displacement(&self.u, NodeId(e.0)).map(|v| v.map(|x| x as f32))
    }

    /// Writes every surface node's position (its rest position plus its displacement) into `body`;
    /// returns how many it wrote.
    pub fn write_into(&self, body: &mut Body) -> u32 {
        let mut written = 0;
        for &n in self.model.surface_nodes() {
            let e = ElementId(n.0);
            if let (Some(v), Some(&r)) =
                (self.model.displacement(&self.u, n), body.lattice().rest_positions().get(e.index()))
            {
                let _ = body.set_position(e, [r[0] + v[0] as f32, r[1] + v[1] as f32, r[2] + v[2] as f32]);
                written += 1;
            }
        }
        written
    }

    /// The force the block exerts on the instrument driving its node, newtons (zero when let go).
    pub fn reaction(&self) -> [f32; 3] {
        self.reaction
    }

    /// Lets go: no imposed displacement, the block returns to rest (its surface written into `body`;
    /// returns how many nodes).
    pub fn release(&mut self, body: &mut Body) -> u32 {
        self.u.fill(0.0);
        self.reaction = [0.0; 3];
        if let Some(d) = &mut self.dynamic {
            d.reset();
        }
        self.write_into(body)
    }
}
