//! The session: the scene, the world stepping on a fixed clock, the commands given to it (recorded) or
//! read from a recording (replayed), the assessment, the scene file watch. No windows here.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use super::AppError;
use crate::chainmail::{Material, MaterialId};
use crate::instrument::{Command as InstrumentCommand, Picker};
use crate::runner::Player;
use crate::scene::{Action as ScriptAction, DEFAULT_SCENE, DEFAULT_SCENE_PATH, Recorder, Recording, Scene};
use crate::simulation::{Command, FixedClock, Snapshot, World};
use crate::training::{Advice, Assessment, Assessor};
use crate::ui::{FrameSample, ReportSummary, Timing};

/// Most steps a frame may run: at 1000 Hz, a frame slower than this many milliseconds falls behind.
const MAX_STEPS_PER_FRAME: u32 = 100;
/// Most wall time a frame spends stepping: past it the frame draws and the rest of the steps are
/// dropped (the simulation falls behind real time instead of the window freezing).
const SIM_BUDGET_PER_FRAME: Duration = Duration::from_millis(30);
/// How often the scene file's modification time is checked.
const WATCH_EVERY: Duration = Duration::from_millis(500);

/// Where the world's commands come from.
pub enum Driver {
    /// The trainee: commands gathered per frame, pushed before the frame's first step and recorded.
    Live {
        /// Commands gathered since the last step.
        pending: Vec<Command>,
        /// The recording, when one could be opened.
        recorder: Option<Recorder>,
        /// Where recordings go: the first path, then `-2`, `-3`... after reloads.
        record_base: PathBuf,
        /// Recordings started so far.
        recordings: u32,
        /// Commands recorded in the current recording.
        recorded: u64,
    },
    /// A recording or script played step by step; user input does not reach the world.
    Replay {
        /// The player.
        player: Player,
        /// The actions played (kept to play again from the start when seeking back).
        actions: Vec<ScriptAction>,
        /// The last step the recording reaches.
        last_step: u64,
        /// Paused.
        paused: bool,
        /// Times real time.
        speed: f32,
        /// Commands in the recording.
        commands: usize,
        /// What is played (for the status line).
        label: String,
    },
}

/// Polls a scene file's modification time.
struct Watch {
    path: PathBuf,
    modified: Option<SystemTime>,
    last_poll: Instant,
}

impl Watch {
    fn new(path: &Path) -> Self {
        Self { path: path.to_path_buf(), modified: modified(path), last_poll: Instant::now() }
    }

    /// Whether the file changed since the last poll (checked at most every [`WATCH_EVERY`]).
    fn changed(&mut self) -> bool {
        if self.last_poll.elapsed() < WATCH_EVERY {
            return false;
        }
        self.last_poll = Instant::now();
        let now = modified(&self.path);
        if now.is_some() && now != self.modified {
            self.modified = now;
            return true;
        }
        false
    }
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// The running simulation and everything around it.
pub struct Session {
    /// The scene running.
    pub scene: Scene,
    /// The scene's text (what recordings store).
    pub scene_source: String,
    /// The scene's path as given (or the built-in name).
    pub scene_label: String,
    /// The world.
    pub world: World,
    /// The fixed-step clock.
    pub clock: FixedClock,
    /// The world as of the last step, for drawing and picking.
    pub snapshot: Snapshot,
    /// Picking against the snapshot (refreshed when the snapshot changes).
    pub picker: Picker,
    picker_step: Option<u64>,
    /// The live assessment, when the scene has goals.
    pub assessor: Option<Assessor>,
    /// Input source.
    pub driver: Driver,
    /// Frame and step times.
    pub timing: Timing,
    watch: Option<Watch>,
    /// The last failed reload, shown until a good one.
    pub scene_error: Option<String>,
    /// The scene file changed while the session ran: waiting for the trainee's answer.
    pub reload_pending: bool,
    /// What stops the trainee now (refreshed after the steps of each frame).
    pub advice: Option<Advice>,
    message: Option<(String, Instant)>,
    started: Instant,
    dropped: bool,
}

/// Now, UTC, as `2026-11-22_05-30-12` (names of recordings and screenshots).
pub fn date_time_stem() -> String {
    let secs = SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    let (year, month, day, h, m, s) = crate::training::utc_date_time(secs);
    format!("{year:04}-{month:02}-{day:02}_{h:02}-{m:02}-{s:02}")
}

/// `recordings/2026-11-22_05-30-12.ron` under the current folder (a counter is added if it exists).
pub fn default_recording_path() -> PathBuf {
    let stem = date_time_stem();
    let dir = PathBuf::from("recordings");
    let mut path = dir.join(format!("{stem}.ron"));
    let mut n = 2;
    while path.exists() {
        path = dir.join(format!("{stem}-{n}.ron"));
        n += 1;
    }
    path
}

/// `base` for the first recording, `base-2.ron`, `base-3.ron`... for later ones.
fn numbered(base: &Path, n: u32) -> PathBuf {
    if n <= 1 {
        return base.to_path_buf();
    }
    let stem =
        base.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "recording".into());
    base.with_file_name(format!("{stem}-{n}.ron"))
}

fn build(scene: &Scene, label: &str) -> Result<(World, Option<Assessor>), AppError> {
    // Sessions relax by sweeps only, never by wall time, so that a recording replays bit for bit; a
    // frame that cannot keep up drops steps instead (see `SIM_BUDGET_PER_FRAME`).
    let world = scene
        .build_world(false)
        .map_err(|e| AppError::Scene(format!("{label}: the tissue cannot be built: {e}")))?;
    let assessor =
        scene.goals.clone().map(|g| Assessor::new(g, world.tissue(), f64::from(scene.simulation.rate_hz)));
    Ok((world, assessor))
}

impl Session {
    fn with(
        scene: Scene,
        scene_source: String,
        scene_label: String,
        driver: Driver,
    ) -> Result<Self, AppError> {
        let (world, assessor) = build(&scene, &scene_label)?;
        let clock = FixedClock::new(f64::from(scene.simulation.rate_hz), MAX_STEPS_PER_FRAME);
        let mut snapshot = Snapshot::default();
        world.snapshot_into(&mut snapshot);
        Ok(Self {
            scene,
            scene_source,
            scene_label,
            world,
            clock,
            snapshot,
            picker: Picker::default(),
            picker_step: None,
            assessor,
            driver,
            timing: Timing::default(),
            watch: None,
            scene_error: None,
            reload_pending: false,
            advice: None,
            message: None,
            started: Instant::now(),
            dropped: false,
        })
    }

    /// A live session on the scene at `path` (watched for changes) or the built-in scene, recorded to
    /// `record`.
    pub fn live(path: Option<&Path>, record: PathBuf) -> Result<Self, AppError> {
        let (source, label) = match path {
            Some(p) => (
                std::fs::read_to_string(p).map_err(|e| AppError::Scene(format!("{}: {e}", p.display())))?,
                p.display().to_string(),
            ),
            None => (DEFAULT_SCENE.to_string(), DEFAULT_SCENE_PATH.to_string()),
        };
        let scene = Scene::from_str(&source, &label).map_err(|e| AppError::Scene(e.to_string()))?;
        let driver = Driver::Live {
            pending: Vec::new(),
            recorder: None,
            record_base: record,
            recordings: 0,
            recorded: 0,
        };
        let mut session = Self::with(scene, source, label, driver)?;
        session.watch = path.map(Watch::new);
        session.start_recording();
        Ok(session)
    }

    /// Plays a recording (`dissect replay FILE`) on the scene it carries.
    pub fn replay(path: &Path) -> Result<Self, AppError> {
        let recording = Recording::load(path).map_err(|e| AppError::Scene(e.to_string()))?;
        let scene = Scene::from_str(&recording.scene_source, &recording.scene)
            .map_err(|e| AppError::Scene(format!("the recorded scene: {e}")))?;
        let commands = recording.actions.iter().filter(|a| matches!(a, ScriptAction::Command(_))).count();
        let last_step = crate::scene::Script(recording.actions.clone()).duration_steps();
        let driver = Driver::Replay {
            player: Player::new(recording.actions.clone()),
            actions: recording.actions,
            last_step,
            paused: false,
            speed: 1.0,
            commands,
            label: path.display().to_string(),
        };
        Self::with(scene, recording.scene_source, recording.scene, driver)
    }

    /// Plays a script on a scene (the hidden `--demo-script`, for screenshots and demonstrations).
    pub fn demo(scene_path: Option<&Path>, script_path: &Path) -> Result<Self, AppError> {
        let script = crate::scene::Script::load(script_path).map_err(|e| AppError::Scene(e.to_string()))?;
        let mut session = Self::live(scene_path, PathBuf::new())?;
        if let Driver::Live { recorder: Some(r), .. } = &mut session.driver {
            let _ = std::fs::remove_file(r.path());
        }
        let commands = script.0.iter().filter(|a| matches!(a, ScriptAction::Command(_))).count();
        session.driver = Driver::Replay {
            player: Player::new(script.0.clone()),
            last_step: script.duration_steps(),
            actions: script.0,
            paused: false,
            speed: 1.0,
            commands,
            label: script_path.display().to_string(),
        };
        Ok(session)
    }

    fn start_recording(&mut self) {
        let message = {
            let Driver::Live { recorder, record_base, recordings, recorded, .. } = &mut self.driver else {
                return;
            };
            if record_base.as_os_str().is_empty() {
                return;
            }
            *recordings += 1;
            *recorded = 0;
            let path = numbered(record_base, *recordings);
            match Recorder::create(&path, &self.scene_label, &self.scene_source) {
                Ok(r) => {
                    println!("dissect: recording to {}", path.display());
                    *recorder = Some(r);
                    None
                }
                Err(e) => {
                    *recorder = None;
                    Some(format!("cannot record to {}: {e}", path.display()))
                }
            }
        };
        if let Some(m) = message {
            eprintln!("dissect: {m}");
            self.say(m);
        }
    }

    /// Ends the current recording (at the world's step), printing its path.
    fn finish_recording(&mut self) {
        let step = self.world.step_count();
        if let Driver::Live { recorder, recorded, .. } = &mut self.driver
            && let Some(r) = recorder.take()
        {
            let path = r.path().to_path_buf();
            match r.finish(step) {
                Ok(()) => println!(
                    "dissect: session ended at step {step}; {recorded} commands recorded in {}",
                    path.display()
                ),
                Err(e) => eprintln!("dissect: {}: {e}", path.display()),
            }
        }
    }

    /// The recording's path, if recording.
    pub fn recording_path(&self) -> Option<PathBuf> {
        match &self.driver {
            Driver::Live { recorder: Some(r), .. } => Some(r.path().to_path_buf()),
            _ => None,
        }
    }

    /// Whether user input reaches the world.
    pub fn input_enabled(&self) -> bool {
        matches!(self.driver, Driver::Live { .. })
    }

    /// Gathers a command for the next step (ignored while replaying). Consecutive moves collapse into
    /// the last one; a move to where the instrument already is, with nothing else pending, is dropped.
    pub fn queue(&mut self, command: impl Into<Command>) {
        use InstrumentCommand::MoveTo;
        let command = command.into();
        if let Driver::Live { pending, .. } = &mut self.driver {
            if pending.is_empty() && command == MoveTo(self.world.instrument().target).into() {
                return;
            }
            if let (Command::Instrument(MoveTo(p)), Some(Command::Instrument(MoveTo(last)))) =
                (&command, pending.last_mut())
            {
                *last = *p;
                return;
            }
            pending.push(command);
        }
    }

    /// Runs the steps a frame of `frame` real time calls for: live commands are pushed (and recorded
    /// with that step's number) before the first of them; a replay feeds its player before each.
    pub fn advance(&mut self, frame: Duration) {
        let frame = match &self.driver {
            Driver::Replay { paused: true, .. } => Duration::ZERO,
            Driver::Replay { speed, .. } => frame.mul_f32(*speed),
            Driver::Live { .. } => frame,
        };
        let mut steps = self.clock.advance(frame);
        let t = Instant::now();
        let mut step_us = 0.0;
        let mut ran = 0;
        if steps > 0
            && let Driver::Live { pending, recorder, recorded, .. } = &mut self.driver
        {
            let step = self.world.step_count();
            for c in pending.drain(..) {
                if let Some(r) = recorder {
                    if let Err(e) = r.record(step, &c) {
                        eprintln!("dissect: recording stopped: {e}");
                        *recorder = None;
                    } else {
                        *recorded += 1;
                    }
                }
                self.world.push(c);
            }
        }
        self.dropped = false;
        while steps > 0 {
            if t.elapsed() > SIM_BUDGET_PER_FRAME {
                self.dropped = true;
                break;
            }
            steps -= 1;
            if let Driver::Replay { player, .. } = &mut self.driver {
                player.feed(&mut self.world);
                if player.finished() {
                    break;
                }
            }
            step_us += self.world.step().total_us();
            if let Some(notice) = self.world.tissue_mut().take_notice() {
                self.say(notice);
            }
            ran += 1;
            if let Some(a) = &mut self.assessor {
                a.observe(&self.world);
            }
        }
        if ran > 0 {
            self.world.snapshot_into(&mut self.snapshot);
            self.advice = self.assessor.as_ref().and_then(|a| a.advice(&self.world));
        }
        self.timing.push(FrameSample {
            t: self.started.elapsed().as_secs_f64(),
            frame_ms: frame.as_secs_f32() * 1000.0,
            sim_ms: t.elapsed().as_secs_f32() * 1000.0,
            step_us: if ran > 0 { step_us / ran as f32 } else { 0.0 },
            steps: ran,
        });
    }

    /// Rebuilds the picker if the snapshot moved on since it was last built.
    pub fn refresh_picker(&mut self) {
        if self.picker_step != Some(self.snapshot.step) {
            self.picker.refresh(&self.snapshot);
            self.picker_step = Some(self.snapshot.step);
        }
    }

    /// Whether the simulation runs slower than real time: the last frame dropped time, or fewer than
    /// 90 % of the scene's steps per second ran over the last second.
    pub fn behind(&self) -> bool {
        let rate = self.world.config().rate_hz as f32;
        let warm = self.started.elapsed() > Duration::from_secs(2);
        let running = !self.replay_finished();
        running
            && (self.clock.is_behind()
                || self.dropped
                || (warm && self.timing.steps_per_second() < 0.9 * rate))
    }

    /// Whether a replay has played everything.
    pub fn replay_finished(&self) -> bool {
        matches!(&self.driver, Driver::Replay { player, .. } if player.finished())
    }

    /// One line about the session for the status bar.
    pub fn status(&self) -> String {
        match &self.driver {
            Driver::Live { recorder: Some(r), recorded, .. } => {
                format!("REC {} ({recorded} commands)", r.path().display())
            }
            Driver::Live { .. } => "not recording".to_string(),
            Driver::Replay { label, commands, player, .. } => format!(
                "REPLAY {label} ({commands} commands){}",
                if player.finished() { " — finished" } else { "" }
            ),
        }
    }

    /// Shows a message for a few seconds.
    pub fn say(&mut self, message: impl Into<String>) {
        self.message = Some((message.into(), Instant::now()));
    }

    /// The current message, if still fresh.
    pub fn message(&self) -> Option<&str> {
        self.message.as_ref().filter(|(_, t)| t.elapsed() < Duration::from_secs(6)).map(|(m, _)| m.as_str())
    }

    /// The assessment now.
    pub fn assessment(&self) -> Option<Assessment> {
        self.assessor.as_ref().map(|a| a.assessment(&self.world))
    }

    /// Replaces a material; a refusal is shown.
    pub fn set_material(&mut self, id: MaterialId, material: Material) {
        // Through the world's input, so that the recording replays it.
        if let Err(e) = material.validate() {
            self.say(format!("material refused: {e}"));
            return;
        }
        self.queue(Command::SetMaterial(id, material));
    }

    /// Sets the most relaxation sweeps per step.
    pub fn set_sweeps(&mut self, sweeps: u32) {
        self.queue(Command::SetRelaxSweeps(sweeps));
    }

    /// Checks the scene file; reloads it if it changed. Returns true when a new scene runs.
    pub fn poll_reload(&mut self) -> bool {
        let changed = self.watch.as_mut().is_some_and(Watch::changed);
        changed && self.request_reload()
    }

    /// Whether a reload would throw away work: the clock has started, or commands were recorded.
    pub fn running(&self) -> bool {
        let started = self.assessor.as_ref().is_some_and(|a| a.started());
        started || matches!(self.driver, Driver::Live { recorded, .. } if recorded > 0)
    }

    /// Reloads at once when nothing would be lost; otherwise asks first (`reload_pending`). Returns
    /// true when a new scene runs.
    pub fn request_reload(&mut self) -> bool {
        if self.input_enabled() && self.running() {
            self.reload_pending = true;
            return false;
        }
        self.reload()
    }

    /// Where a replay stands, for its controls.
    pub fn replay_state(&self) -> Option<crate::ui::ReplayState> {
        match &self.driver {
            Driver::Replay { last_step, paused, speed, .. } => Some(crate::ui::ReplayState {
                step: self.world.step_count(),
                last_step: *last_step,
                paused: *paused,
                speed: *speed,
            }),
            Driver::Live { .. } => None,
        }
    }

    /// Replay: pause or play on.
    pub fn set_paused(&mut self, pause: bool) {
        if let Driver::Replay { paused, .. } = &mut self.driver {
            *paused = pause;
        }
    }

    /// Replay: times real time (0.05 to 16).
    pub fn set_speed(&mut self, to: f32) {
        if let Driver::Replay { speed, .. } = &mut self.driver {
            *speed = to.clamp(0.05, 16.0);
        }
    }

    /// Replay: goes to step `target`, playing again from the start when it lies behind (the
    /// simulation is deterministic, so the same steps give the same tissue).
    pub fn seek(&mut self, target: u64) {
        let Driver::Replay { actions, .. } = &self.driver else { return };
        if target < self.world.step_count() {
            let actions = actions.clone();
            let Ok((world, assessor)) = build(&self.scene, &self.scene_label) else { return };
            self.world = world;
            self.assessor = assessor;
            if let Driver::Replay { player, .. } = &mut self.driver {
                *player = Player::new(actions);
            }
        }
        while self.world.step_count() < target {
            if let Driver::Replay { player, .. } = &mut self.driver {
                player.feed(&mut self.world);
                if player.finished() {
                    break;
                }
            }
            self.world.step();
            if let Some(a) = &mut self.assessor {
                a.observe(&self.world);
            }
        }
        self.world.snapshot_into(&mut self.snapshot);
        self.advice = self.assessor.as_ref().and_then(|a| a.advice(&self.world));
        self.picker_step = None;
    }

    /// Loads the scene again (from its file, or the built-in text): on success the world restarts (and
    /// a new recording begins); on failure the error is kept for display and the running scene stays.
    pub fn reload(&mut self) -> bool {
        if !self.input_enabled() {
            return false;
        }
        let loaded = match &self.watch {
            Some(w) => Scene::load(&w.path).and_then(|s| {
                std::fs::read_to_string(&w.path)
                    .map(|src| (s, src))
                    .map_err(|source| crate::scene::SceneError::Io { path: w.path.clone(), source })
            }),
            None => {
                Scene::from_str(&self.scene_source, &self.scene_label).map(|s| (s, self.scene_source.clone()))
            }
        };
        let (scene, source) = match loaded {
            Ok(x) => x,
            Err(e) => {
                eprintln!("{e}");
                self.scene_error = Some(e.to_string());
                return false;
            }
        };
        let (world, assessor) = match build(&scene, &self.scene_label) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("{e}");
                self.scene_error = Some(e.to_string());
                return false;
            }
        };
        self.finish_recording();
        self.scene = scene;
        self.scene_source = source;
        self.world = world;
        self.assessor = assessor;
        self.clock = FixedClock::new(f64::from(self.scene.simulation.rate_hz), MAX_STEPS_PER_FRAME);
        self.world.snapshot_into(&mut self.snapshot);
        self.picker_step = None;
        self.scene_error = None;
        self.reload_pending = false;
        self.advice = None;
        if let Driver::Live { pending, .. } = &mut self.driver {
            pending.clear();
        }
        self.start_recording();
        self.say(format!("reloaded {}", self.scene_label));
        true
    }

    /// Writes `<recording>.report.json` and `<recording>.report.png` (next to the recording, or in the
    /// current folder) when the scene has goals.
    pub fn write_report(&mut self) -> Option<ReportSummary> {
        let assessor = self.assessor.as_ref()?;
        let assessment = assessor.assessment(&self.world);
        let base = self.recording_path().unwrap_or_else(|| PathBuf::from("session.ron"));
        let json = base.with_extension("report.json");
        let png = base.with_extension("report.png");
        let report = assessor.report(&self.world, &self.scene.title, crate::training::utc_now_string());
        let result = crate::training::write_report(&json, &report)
            .and_then(|()| crate::training::write_plot(&png, &report));
        match result {
            Ok(()) => {
                println!("dissect: report written to {} and {}", json.display(), png.display());
                Some(ReportSummary { assessment, json, png })
            }
            Err(e) => {
                self.say(format!("report not written: {e}"));
                None
            }
        }
    }

    /// Ends the session: the report (with goals) and the recording are written.
    pub fn finish(&mut self) {
        if self.input_enabled() {
            self.write_report();
        }
        if let Driver::Replay { commands, .. } = &self.driver {
            println!("dissect: replay ended at step {}; {commands} commands played", self.world.step_count());
        }
        self.finish_recording();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recordings_are_numbered_after_the_first() {
        assert_eq!(numbered(Path::new("r/a.ron"), 1), PathBuf::from("r/a.ron"));
        assert_eq!(numbered(Path::new("r/a.ron"), 3), PathBuf::from("r/a-3.ron"));
        let p = default_recording_path();
        assert!(p.starts_with("recordings"));
        assert_eq!(p.extension().and_then(|e| e.to_str()), Some("ron"));
    }

    #[test]
    fn live_commands_are_pushed_before_a_step_and_replayed_alike() {
        let dir = std::env::temp_dir().join(format!("dissect-session-{}", std::process::id()));
        let rec = dir.join("r.ron");
        let mut live = Session::live(None, rec.clone()).expect("live session");
        live.queue(InstrumentCommand::Select(crate::simulation::InstrumentKind::Scalpel));
        live.queue(InstrumentCommand::MoveTo([0.0, 0.01, 0.0]));
        live.queue(InstrumentCommand::MoveTo([0.001, 0.01, 0.0]));
        live.advance(Duration::from_millis(5));
        live.queue(InstrumentCommand::MoveTo([0.002, 0.01, 0.0]));
        live.advance(Duration::from_micros(100)); // no step: the command waits
        live.advance(Duration::from_millis(3));
        let steps = live.world.step_count();
        assert_eq!(steps, 8);
        live.finish();
        let mut replay = Session::replay(&rec).expect("replay");
        for _ in 0..10 {
            replay.advance(Duration::from_millis(5));
        }
        assert_eq!(replay.world.step_count(), steps);
        assert_eq!(replay.world.instrument().target, [0.002, 0.01, 0.0]);
        assert!(replay.replay_finished());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
