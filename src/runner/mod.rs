//! Running a world: the [`Episode`] every driver steps (a world, its assessment, its recording, and a
//! command source), the script player that turns timed actions into per-step commands, and the
//! figures and final state of a headless, deterministic run.
//!
//! Must not import wgpu, winit or egui (pictures are drawn by the caller through `render`).

mod episode;
mod player;
#[cfg(not(target_arch = "wasm32"))]
pub mod priority;
mod stats;
#[cfg(not(target_arch = "wasm32"))]
pub mod thread;

pub use episode::{Advance, Episode, Source};
pub use player::{Player, resolve};
pub use stats::StepTimes;
#[cfg(not(target_arch = "wasm32"))]
pub use thread::{Event, Given, Input, Pace, Published, SimThread};

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
    times: StepTimes,
    phases: [f64; 7],
    max_stretch: f32,
}

impl MetricsRecorder {
    /// A recorder. Its memory is fixed (the step times go into a histogram, [`StepTimes`]), whatever
    /// `steps` says: the argument is kept for callers that size it.
    pub fn with_capacity(steps: usize) -> Self {
        let _ = steps;
        Self { times: StepTimes::new(), phases: [0.0; 7], max_stretch: 1.0 }
    }

    /// Call after each step.
    pub fn observe(&mut self, world: &World) {
        let c = world.last_step();
        self.times.record(c.total_us());
        for (acc, t) in self.phases.iter_mut().zip(c.phase_us) {
            *acc += t as f64;
        }
        self.max_stretch = self.max_stretch.max(world.tissue().max_stretch());
    }

    /// The figures so far.
    pub fn metrics(&self, world: &World) -> Metrics {
        let d = world.tissue().damage();
        let n = self.times.count().max(1) as f64;
        Metrics {
            steps: world.step_count(),
            elements_moved_total: world.elements_moved_total(),
            links_cut: d.layer_links_cut + d.connective_links_cut,
            links_torn: d.links_torn,
            max_stretch: self.max_stretch,
            step_time_us: self.times.stats(),
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
    /// What it was part of. `Layer(n)` counts from the lowest layer here (0 is the lower of two), as
    /// `state.json` has always written it, so that states of older runs still compare.
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
            .map(|l| LayerState {
                name: l.name.clone(),
                positions: (l.first..l.first + l.count)
                    .filter_map(|e| tissue.world_position(crate::chainmail::ElementId(e)))
                    .collect(),
            })
            .collect();
        let body = tissue.body();
        let lowest = tissue.layers().len().saturating_sub(1) as u8;
        let broken_links = (0..body.link_count() as u32)
            .map(LinkId)
            .filter_map(|l| {
                let reason = body.link_broken(l)?;
                let [a, b] = body.lattice().link_ends(l)?;
                let kind = match tissue.link_kind(l)? {
                    LinkKind::Layer(n) => LinkKind::Layer(lowest - n),
                    k => k,
                };
                Some(BrokenLink { link: l.0, elements: [a.0, b.0], kind, reason })
            })
            .collect();
        Self { steps, layers, broken_links }
    }
}

/// Why a run could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene's tissue could not be built.
    #[error("{path}: {source}")]
    Tissue {
        /// The scene file.
        path: String,
        /// The cause.
        source: crate::tissue::TissueError,
    },
    /// The script does not fit the scene.
    #[error("{path}: {reason}")]
    Script {
        /// The script file.
        path: String,
        /// What does not fit.
        reason: String,
    },
    /// Writing an output failed.
    #[error("{path}: {reason}")]
    Write {
        /// The file.
        path: String,
        /// The cause.
        reason: String,
    },
}

/// What a headless run leaves behind.
pub struct RunOutput {
    /// The world at the end.
    pub world: World,
    /// Its figures.
    pub metrics: Metrics,
    /// The assessment, when the scene has goals.
    pub assessor: Option<crate::training::Assessor>,
    /// The recording of the run's commands, when one was asked for (to be finished by the caller).
    pub recorder: Option<crate::scene::Recorder>,
    /// The scene's title (for the report).
    pub title: String,
}

/// Runs `script` on `scene` without a window: `steps` steps, or until the script ends. Deterministic:
/// no time budget is used, so the same inputs give the same state bit for bit. With a `recording`,
/// the commands given to the world are recorded as they go (a recording replays to the same state);
/// it comes back in the output, to be finished.
pub fn run(
    scene: &crate::scene::Scene,
    scene_path: &str,
    script: &crate::scene::Script,
    script_path: &str,
    steps: Option<u64>,
    recording: Option<crate::scene::Recorder>,
) -> Result<RunOutput, RunError> {
    script.check_against(scene).map_err(|reason| RunError::Script { path: script_path.into(), reason })?;
    let world =
        scene.build_world(false).map_err(|source| RunError::Tissue { path: scene_path.into(), source })?;
    let assessor = scene.goals.clone().map(|g| crate::training::Assessor::new(g, &world));
    let mut episode = Episode::new(world, assessor, Source::Script(Player::new(script.0.clone())));
    if let Some(r) = recording {
        episode.record_to(r);
    }
    episode.run_past_end(steps.is_some());
    let limit = steps.unwrap_or(u64::MAX);
    let mut figures =
        MetricsRecorder::with_capacity(steps.unwrap_or(script.duration_steps()).min(10_000_000) as usize);
    while episode.world().step_count() < limit && episode.step().is_some() {
        if let Some((path, reason)) = episode.take_record_error() {
            return Err(RunError::Write { path, reason });
        }
        figures.observe(episode.world());
    }
    let (world, assessor, recorder) = episode.into_parts();
    let mut metrics = figures.metrics(&world);
    metrics.assessment = assessor.as_ref().map(|a| a.assessment(&world));
    Ok(RunOutput { world, metrics, assessor, recorder, title: scene.title.clone() })
}

/// Writes `metrics.json`, `state.json` and, with goals, `report.json` and `report.png` into `dir`.
pub fn write_outputs(dir: &std::path::Path, out: &RunOutput) -> Result<(), RunError> {
    let werr = |p: &std::path::Path, e: &dyn std::fmt::Display| RunError::Write {
        path: p.display().to_string(),
        reason: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| werr(dir, &e))?;
    let path = dir.join("metrics.json");
    let text = serde_json::to_string_pretty(&out.metrics).map_err(|e| werr(&path, &e))?;
    std::fs::write(&path, text).map_err(|e| werr(&path, &e))?;
    let path = dir.join("state.json");
    let state = State::of(out.world.tissue(), out.world.step_count());
    let text = serde_json::to_string(&state).map_err(|e| werr(&path, &e))?;
    std::fs::write(&path, text).map_err(|e| werr(&path, &e))?;
    if let Some(a) = &out.assessor {
        let report = a.report(&out.world, &out.title, crate::training::utc_now_string());
        let path = dir.join("report.json");
        crate::training::write_report(&path, &report).map_err(|e| werr(&path, &e))?;
        let path = dir.join("report.png");
        crate::training::write_plot(&path, &report).map_err(|e| werr(&path, &e))?;
    }
    Ok(())
}
