//! What the panels and the hand read of a world, copied out of it: the step, its counters, the
//! instrument, the forces, the materials. A [`WorldView`] is a plain value, so a world stepping on a
//! thread of its own can publish it beside its [`Snapshot`](crate::snapshot::Snapshot) and the windows
//! read it while the next steps run.

use super::{Forces, StepCounters, World, WorldConfig};
use crate::chainmail::{Material, MaterialId};
use crate::instrument::Instrument;
use crate::tissue::Damage;

/// A copy of what a frame shows of a world, refilled in place by [`World::view_into`].
#[derive(Clone, Debug, PartialEq)]
pub struct WorldView {
    step: u64,
    last: StepCounters,
    elements_moved_total: u64,
    config: WorldConfig,
    instrument: Instrument,
    grasped_position: Option<[f32; 3]>,
    forces: Forces,
    max_stretch: f32,
    damage: Damage,
    layers: Vec<(String, MaterialId)>,
    materials: Vec<Material>,
}

impl Default for WorldView {
    fn default() -> Self {
        Self {
            step: 0,
            last: StepCounters::default(),
            elements_moved_total: 0,
            config: WorldConfig::default(),
            instrument: Instrument::default(),
            grasped_position: None,
            forces: Forces::default(),
            max_stretch: 0.0,
            damage: Damage::default(),
            layers: Vec::new(),
            materials: Vec::new(),
        }
    }
}

impl World {
    /// Refills `out` with this world's figures (reusing its allocations).
    pub fn view_into(&self, out: &mut WorldView) {
        let tissue = self.tissue();
        out.step = self.step_count();
        out.last = *self.last_step();
        out.elements_moved_total = self.elements_moved_total();
        out.config = *self.config();
        out.instrument.clone_from(self.instrument());
        out.grasped_position = self.instrument().grasped.and_then(|e| tissue.world_position(e));
        out.forces = *self.forces();
        out.max_stretch = tissue.max_stretch();
        out.damage = tissue.damage();
        out.layers.clear();
        out.layers.extend(tissue.layers().iter().map(|l| (l.name.clone(), l.material)));
        out.materials.clear();
        out.materials.extend_from_slice(tissue.body().materials());
    }

    /// This world's figures as a new [`WorldView`].
    pub fn view(&self) -> WorldView {
        let mut v = WorldView::default();
        self.view_into(&mut v);
        v
    }
}

impl WorldView {
    /// Steps run so far.
    pub fn step_count(&self) -> u64 {
        self.step
    }

    /// The last step's counters.
    pub fn last_step(&self) -> &StepCounters {
        &self.last
    }

    /// Elements moved by all chain reactions so far.
    pub fn elements_moved_total(&self) -> u64 {
        self.elements_moved_total
    }

    /// The world's settings.
    pub fn config(&self) -> &WorldConfig {
        &self.config
    }

    /// The instrument.
    pub fn instrument(&self) -> &Instrument {
        &self.instrument
    }

    /// Where the element the forceps hold is, world metres.
    pub fn grasped_position(&self) -> Option<[f32; 3]> {
        self.grasped_position
    }

    /// The forces of the last step, newtons.
    pub fn forces(&self) -> &Forces {
        &self.forces
    }

    /// Largest stretch of an in-layer link after the last step.
    pub fn max_stretch(&self) -> f32 {
        self.max_stretch
    }

    /// What the tissue went through so far.
    pub fn damage(&self) -> Damage {
        self.damage
    }

    /// Each layer's name and material, upper first.
    pub fn layers(&self) -> &[(String, MaterialId)] {
        &self.layers
    }

    /// The tissue's materials, by [`MaterialId`].
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// A material by id.
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.materials.get(id.index())
    }
}
