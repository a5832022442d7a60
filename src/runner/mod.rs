//! Running a script against a world, headless and deterministically: the player that turns timed
//! actions into per-step instrument commands, and the figures a run reports.
//!
//! Must not import wgpu, winit or egui (pictures are drawn by the caller through `render`).

mod player;

pub use player::{Action, Player, Point};

use serde::Serialize;

use crate::chainmail::LinkId;
use crate::simulation::World;
use crate::tissue::{LinkKind, Tissue};

/// Summary statistics of the step time, microseconds.
#[derive(Serialize, Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeStats {
    /// Mean.
    pub mean: f32,
    /// Median.
    pub p50: f32,
    /// 99th percentile.
    pub p99: f32,
    /// Largest.
    pub max: f32,
}

impl TimeStats {
    /// Statistics of a set of samples (sorted in place).
    pub fn of(samples: &mut [f32]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        samples.sort_by(f32::total_cmp);
        let at = |q: f32| samples[((samples.len() - 1) as f32 * q).round() as usize];
        Self {
            mean: samples.iter().sum::<f32>() / samples.len() as f32,
            p50: at(0.5),
            p99: at(0.99),
            max: samples[samples.len() - 1],
        }
    }
}

/// The figures of a run: what `metrics.json` holds.
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Steps run.
    pub steps: u64,
    /// Elements moved by all chain reactions.
    pub elements_moved_total: u64,
    /// Links cut (both kinds).
    pub links_cut: u64,
    /// Links torn.
    pub links_torn: u64,
    /// Largest stretch (world length over rest length) seen.
    pub max_stretch: f32,
    /// Step wall time, microseconds.
    pub step_time_us: TimeStats,
    /// Wall time per phase, microseconds, mean over the steps, by phase name.
    pub phase_time_us: Vec<(String, f32)>,
    /// The exercise's assessment, when the scene has goals.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub assessment: Option<crate::training::Assessment>,
}

/// Gathers the figures step by step.
#[derive(Clone, Debug, Default)]
pub struct MetricsRecorder {
    times: Vec<f32>,
    phases: [f64; 6],
    max_stretch: f32,
}

impl MetricsRecorder {
    /// A recorder with room for `steps` samples.
    pub fn with_capacity(steps: usize) -> Self {
        Self { times: Vec::with_capacity(steps), phases: [0.0; 6], max_stretch: 1.0 }
    }

    /// Call after each step.
    pub fn observe(&mut self, world: &World) {
        let c = world.last_step();
        self.times.push(c.total_us());
        for (acc, t) in self.phases.iter_mut().zip(c.phase_us) {
            *acc += t as f64;
        }
        self.max_stretch = self.max_stretch.max(world.tissue().max_stretch());
    }

    /// The figures so far.
    pub fn metrics(&self, world: &World) -> Metrics {
        let d = world.tissue().damage();
        let n = self.times.len().max(1) as f64;
        let mut times = self.times.clone();
        Metrics {
            steps: world.step_count(),
            elements_moved_total: world.elements_moved_total(),
            links_cut: d.layer_links_cut + d.connective_links_cut,
            links_torn: d.links_torn,
            max_stretch: self.max_stretch,
            step_time_us: TimeStats::of(&mut times),
            phase_time_us: crate::simulation::PHASES
                .iter()
                .zip(self.phases)
                .map(|(name, t)| (name.to_string(), (t / n) as f32))
                .collect(),
            assessment: None,
        }
    }
}

/// A broken link in `state.json`.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct BrokenLink {
    /// Link id.
    pub link: u32,
    /// Its two elements.
    pub elements: [u32; 2],
    /// What it was part of.
    pub kind: LinkKind,
    /// Cut or torn.
    pub reason: crate::chainmail::BreakReason,
}

/// A layer's final state in `state.json`.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct LayerState {
    /// Name.
    pub name: String,
    /// World positions of its elements, metres.
    pub positions: Vec<[f32; 3]>,
}

/// The final state of a run: what `state.json` holds. Bit-identical for the same scene and script on
/// the same machine.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct State {
    /// Steps run.
    pub steps: u64,
    /// Layers, upper first.
    pub layers: Vec<LayerState>,
    /// Every broken link.
    pub broken_links: Vec<BrokenLink>,
}

impl State {
    /// The state of a tissue after `steps` steps.
    pub fn of(tissue: &Tissue, steps: u64) -> Self {
        let layers = tissue
            .layers()
            .iter()
            .rev()
            .map(|l| LayerState {
                name: l.name.clone(),
                positions: (l.first..l.first + l.count)
                    .filter_map(|e| tissue.world_position(crate::chainmail::ElementId(e)))
                    .collect(),
            })
            .collect();
        let body = tissue.body();
        let broken_links = (0..body.link_count() as u32)
            .map(LinkId)
            .filter_map(|l| {
                let reason = body.link_broken(l)?;
                let [a, b] = body.lattice().link_ends(l)?;
                Some(BrokenLink { link: l.0, elements: [a.0, b.0], kind: tissue.link_kind(l)?, reason })
            })
            .collect();
        Self { steps, layers, broken_links }
    }
}
