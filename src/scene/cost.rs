//! How much a scene's steps will cost, roughly, against the time its rate gives them: a scene can be
//! valid and still far too slow to run live (a fine sheet with hundreds of relaxation sweeps per step).

use super::types::{Scene, Tissue, VolumeModel};

/// Time one relaxation sweep takes per element, nanoseconds: the engine's measured floor on the
/// development machine (README, "Performance", and `docs/performance.md`); slower machines take longer.
pub const SWEEP_NS_PER_ELEMENT: f64 = 1.0;

/// How far over its step time a scene's estimate may go before it is warned about.
pub const WARN_FACTOR: f64 = 2.0;

impl Scene {
    /// Estimated time of one step's relaxation, seconds: elements × sweeps × `SWEEP_NS_PER_ELEMENT`
    /// (a lower bound: the chain reaction, contact and tears come on top).
    pub fn relax_seconds_per_step(&self) -> f64 {
        if let Tissue::Volume(v) = &self.tissue
            && let VolumeModel::Fem(_) = v.model
        {
            return 0.0;
        }
        self.element_count() as f64 * f64::from(self.simulation.relax_sweeps) * SWEEP_NS_PER_ELEMENT * 1e-9
    }

    /// A warning when the steps will cost far more than the rate allows (`WARN_FACTOR` times the
    /// step), for `dissect check` and the trainer; `None` when the scene should keep up.
    pub fn cost_warning(&self) -> Option<String> {
        let cost = self.relax_seconds_per_step();
        let budget = self.simulation.step_seconds();
        (cost > WARN_FACTOR * budget).then(|| {
            format!(
                "each step will take at least {:.1} ms ({} elements × {} relaxation sweeps at about {} ns per \
                 element and sweep), {:.0} times the {:.2} ms a step has at rate_hz {}: the trainer will fall \
                 behind real time; expected fewer elements, fewer relax_sweeps or a lower rate_hz",
                cost * 1e3,
                self.element_count(),
                self.simulation.relax_sweeps,
                SWEEP_NS_PER_ELEMENT,
                cost / budget,
                budget * 1e3,
                self.simulation.rate_hz
            )
        })
    }
}
