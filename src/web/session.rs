//! A session in the browser: an [`Episode`] of the scene's world, driven by the trainee (the commands
//! also kept in memory, as a recording to download) or by a bundled script (played exactly as
//! `dissect run` plays it, so that the figures match the native run's).

use std::time::Duration;

use web_time::Instant;

use crate::instrument::Picker;
use crate::runner::{Episode, MetricsRecorder, Player, Source};
use crate::scene::{Action as ScriptAction, Recording, Scene, Script};
use crate::simulation::{Command, Snapshot, World, WorldView};
use crate::training::Assessor;
use crate::ui::{FrameSample, Timing};

/// The bundled scenes, by name (the default first).
pub const SCENES: &[(&str, &str)] = &[
    ("durotomy", crate::scene::DEFAULT_SCENE),
    ("meninges", include_str!("../../scenes/meninges.ron")),
    ("cylinder", include_str!("../../scenes/cylinder.ron")),
    ("sphere", include_str!("../../scenes/sphere.ron")),
    ("volume", include_str!("../../scenes/volume.ron")),
    ("fem_block", include_str!("../../scenes/fem_block.ron")),
];

/// The bundled scripts, by name.
pub const SCRIPTS: &[(&str, &str)] = &[
    ("durotomy", include_str!("../../scenes/scripts/durotomy.ron")),
    ("durotomy_careful", include_str!("../../scenes/scripts/durotomy_careful.ron")),
    ("durotomy_careless", include_str!("../../scenes/scripts/durotomy_careless.ron")),
    ("meninges", include_str!("../../scenes/scripts/meninges.ron")),
    ("meninges_careful", include_str!("../../scenes/scripts/meninges_careful.ron")),
    ("meninges_careless", include_str!("../../scenes/scripts/meninges_careless.ron")),
    ("cylinder", include_str!("../../scenes/scripts/cylinder.ron")),
    ("sphere", include_str!("../../scenes/scripts/sphere.ron")),
    ("volume", include_str!("../../scenes/scripts/volume.ron")),
    ("fem_block", include_str!("../../scenes/scripts/fem_block.ron")),
];

/// Most steps one frame may run: half a second at 1 kHz (a software-rendered page draws a frame in
/// 250 to 500 ms).
const MAX_STEPS_PER_FRAME: u32 = 500;
/// Wall time one frame may spend stepping, at least (a slow frame falls behind rather than freezing the
/// page) ...
const SIM_BUDGET_PER_FRAME: Duration = Duration::from_millis(40);
/// ... or this share of the frame's own time, when that is more: where drawing a frame takes hundreds
/// of milliseconds (software WebGL2), 40 ms of steps a frame left the simulation at a third of real
/// time while the tissue moved; with half of a frame for its steps it keeps real time as long as the
/// steps take less than the drawing does.
const SIM_SHARE_OF_FRAME: f32 = 0.5;

/// What the page keeps besides the episode.
pub enum Driver {
    /// The trainee: every command given so far, with the step it was given before (the recording).
    Live { log: Vec<(u64, Command)> },
    /// A bundled script, with `dissect run`'s figures gathered step by step.
    Script { name: String, metrics: MetricsRecorder, done: bool },
}

/// One scene running in the page.
pub struct Session {
    /// The scene.
    pub scene: Scene,
    /// Its text (for the recording).
    pub source: String,
    /// Its name (`scenes/meninges.ron`, or the dropped file's name).
    pub label: String,
    /// The world, its assessment and its source of commands.
    pub episode: Episode,
    /// What the renderer shows.
    pub snapshot: Snapshot,
    /// What the panels show (the world's figures, refreshed with the snapshot).
    pub view: WorldView,
    /// Ray casts against the snapshot.
    pub picker: Picker,
    picker_step: Option<u64>,
    /// Input log or script figures.
    pub driver: Driver,
    /// Frame and step times.
    pub timing: Timing,
    started: Instant,
    dropped: bool,
    message: Option<(String, Instant)>,
}

/// The text of a bundled scene or script by name.
pub fn bundled(table: &[(&str, &'static str)], name: &str) -> Option<&'static str> {
    table.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

impl Session {
    /// A live session on a scene's text; the error is the scene's own (`label:line:column: ...`).
    pub fn new(source: &str, label: &str) -> Result<Self, String> {
        let scene = Scene::from_str(source, label).map_err(|e| e.to_string())?;
        // As natively: relaxation by sweeps only, never by wall time, so that runs are deterministic.
        let mut world =
            scene.build_world(false).map_err(|e| format!("{label}: the tissue cannot be built: {e}"))?;
        // A software-rendered browser frame can take a quarter of a second: one frame may catch up that
        // much simulated time (the clock's longest frame) rather than fall behind at once.
        let mut config = *world.config();
        config.max_steps_per_advance = config.max_steps_per_advance.max(MAX_STEPS_PER_FRAME);
        world.set_config(config);
        let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
        let episode = Episode::new(world, assessor, Source::Live);
        let mut snapshot = Snapshot::default();
        episode.snapshot_into(&mut snapshot);
        Ok(Self {
            scene,
            source: source.to_string(),
            label: label.to_string(),
            view: episode.world().view(),
            episode,
            snapshot,
            picker: Picker::default(),
            picker_step: None,
            driver: Driver::Live { log: Vec::new() },
            timing: Timing::default(),
            started: Instant::now(),
            dropped: false,
            message: None,
        })
    }

    /// The world.
    pub fn world(&self) -> &World {
        self.episode.world()
    }

    /// The live assessment's assessor, when the scene has goals.
    pub fn assessor(&self) -> Option<&Assessor> {
        self.episode.assessor()
    }

    /// Plays `script` (named `name`) instead of taking input.
    pub fn play(&mut self, script_source: &str, name: &str) -> Result<(), String> {
        let label = format!("scenes/scripts/{name}.ron");
        let script = Script::from_str(script_source, &label).map_err(|e| e.to_string())?;
        script.check_against(&self.scene).map_err(|e| format!("{label}: {e}"))?;
        let steps = script.duration_steps().min(10_000_000) as usize;
        self.episode.set_source(Source::Script(Player::new(script.0)));
        self.driver = Driver::Script {
            name: name.to_string(),
            metrics: MetricsRecorder::with_capacity(steps),
            done: false,
        };
        Ok(())
    }

    /// Whether the trainee's input reaches the world.
    pub fn input_enabled(&self) -> bool {
        self.episode.is_live()
    }

    /// Whether a script has played to its end.
    pub fn script_done(&self) -> bool {
        matches!(self.driver, Driver::Script { done: true, .. })
    }

    /// Gathers a command for the next step (consecutive moves collapse into the last).
    pub fn queue(&mut self, command: Command) {
        if !self.input_enabled() {
            return;
        }
        if self.episode.pending().is_empty() && command == Command::MoveTo(self.world().instrument().target) {
            return;
        }
        if let (Command::MoveTo(p), Some(Command::MoveTo(last))) = (&command, self.episode.last_pending_mut())
        {
            *last = *p;
            return;
        }
        self.episode.push(command);
    }

    /// Runs the steps a frame of `frame` real time calls for on the world's clock, one at a time (a
    /// script's figures are gathered after each, as `dissect run` does).
    pub fn advance(&mut self, frame: Duration) {
        let t = Instant::now();
        let budget = SIM_BUDGET_PER_FRAME.max(frame.mul_f32(SIM_SHARE_OF_FRAME));
        let due = self.episode.world_mut().due_steps(frame);
        let given = self.world().step_count();
        let pending = self.episode.pending().to_vec();
        let (mut step_us, mut ran) = (0.0, 0u32);
        self.dropped = false;
        for _ in 0..due {
            if t.elapsed() > budget {
                self.dropped = true;
                break;
            }
            let Some(c) = self.episode.step() else {
                if let Driver::Script { done, .. } = &mut self.driver {
                    *done = true;
                }
                break;
            };
            step_us += c.total_us();
            ran += 1;
            if let Driver::Script { metrics, .. } = &mut self.driver {
                metrics.observe(self.episode.world());
            }
        }
        if ran > 0 {
            if let Driver::Live { log } = &mut self.driver {
                log.extend(pending.into_iter().map(|c| (given, c)));
            }
            if let Some(notice) = self.episode.world_mut().tissue_mut().take_notice() {
                self.say(notice);
            }
            self.episode.snapshot_into(&mut self.snapshot);
            self.episode.world().view_into(&mut self.view);
        }
        self.timing.push(FrameSample {
            t: self.started.elapsed().as_secs_f64(),
            frame_ms: frame.as_secs_f32() * 1000.0,
            sim_ms: t.elapsed().as_secs_f32() * 1000.0,
            step_us: if ran > 0 { step_us / ran as f32 } else { 0.0 },
            steps: ran,
        });
    }

    /// Rebuilds the picker if the snapshot moved on.
    pub fn refresh_picker(&mut self) {
        if self.picker_step != Some(self.snapshot.step) {
            self.picker.refresh(&self.snapshot);
            self.picker_step = Some(self.snapshot.step);
        }
    }

    /// Whether the simulation runs slower than real time.
    pub fn behind(&self) -> bool {
        let rate = self.world().config().rate_hz as f32;
        let warm = self.started.elapsed() > Duration::from_secs(2);
        !self.script_done()
            && (self.world().is_behind()
                || self.dropped
                || (warm && self.timing.steps_per_second() < 0.9 * rate))
    }

    /// One line about the session for the status bar.
    pub fn status(&self) -> String {
        match &self.driver {
            Driver::Live { log } => {
                format!("in the browser: {} commands (download the recording below)", log.len())
            }
            Driver::Script { name, done, .. } => {
                format!("SCRIPT {name}{}", if *done { " — finished" } else { "" })
            }
        }
    }

    /// Shows a message for a few seconds.
    pub fn say(&mut self, message: impl Into<String>) {
        self.message = Some((message.into(), Instant::now()));
    }

    /// The message to show, if still fresh.
    pub fn message(&self) -> Option<&str> {
        self.message.as_ref().filter(|(_, t)| t.elapsed() < Duration::from_secs(6)).map(|(m, _)| m.as_str())
    }

    /// The session's input as a recording (`dissect replay` plays it); a script session records the
    /// script.
    pub fn recording_text(&self) -> Result<String, String> {
        let mut actions = Vec::new();
        match &self.driver {
            Driver::Live { log } => {
                let mut last = None;
                for (step, c) in log {
                    if last != Some(*step) {
                        actions.push(ScriptAction::At(*step));
                        last = Some(*step);
                    }
                    actions.push(ScriptAction::Command(c.clone()));
                }
                actions.push(ScriptAction::At(self.world().step_count()));
            }
            Driver::Script { name, .. } => {
                let script = bundled(SCRIPTS, name).and_then(|s| Script::from_str(s, name).ok());
                actions = script.map(|s| s.0).unwrap_or_default();
            }
        }
        let recording = Recording { scene: self.label.clone(), scene_source: self.source.clone(), actions };
        ron::ser::to_string_pretty(&recording, ron::ser::PrettyConfig::default()).map_err(|e| e.to_string())
    }

    /// `report.json`'s text, when the scene has goals.
    pub fn report_text(&self) -> Option<Result<String, String>> {
        let a = self.assessor()?;
        // The browser's clock (std's is not there on wasm32-unknown-unknown), to the second.
        let iso = String::from(js_sys::Date::new_0().to_iso_string());
        let date = match iso.split_once('.') {
            Some((whole, _)) => format!("{whole}Z"),
            None => iso,
        };
        let report = a.report(self.world(), &self.scene.title, date);
        Some(crate::training::report_json(&report).map_err(|e| e.to_string()))
    }

    /// The figures of a finished script as `dissect run`'s `metrics.json` has them.
    pub fn metrics_json(&self) -> Option<String> {
        let Driver::Script { metrics, .. } = &self.driver else { return None };
        let mut m = metrics.metrics(self.world());
        m.assessment = self.assessor().map(|a| a.assessment(self.world()));
        serde_json::to_string_pretty(&m).ok()
    }
}
