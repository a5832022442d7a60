//! The session: the scene, the episode it runs (the world on its clock, the commands given to it and
//! recorded, or read from a recording and replayed, the assessment), the scene file watch. No windows
//! here.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use super::AppError;
use crate::chainmail::{Material, MaterialId};
use crate::instrument::{Command as InstrumentCommand, Picker};
use crate::runner::{Episode, Player, Source};
use crate::scene::{Action as ScriptAction, DEFAULT_SCENE, DEFAULT_SCENE_PATH, Recorder, Recording, Scene};
use crate::simulation::{Command, Snapshot, World};
use crate::training::{Assessment, Assessor};
use crate::ui::{FrameSample, ReportSummary, Timing};

/// Most wall time a frame spends stepping: past it the frame draws and the rest of the steps are
/// dropped (the simulation falls behind real time instead of the window freezing).
const SIM_BUDGET_PER_FRAME: Duration = Duration::from_millis(30);
/// How often the scene file's modification time is checked.
const WATCH_EVERY: Duration = Duration::from_millis(500);

/// Who drives the session's episode.
pub enum Driver {
    /// The trainee: commands gathered per frame, pushed before the frame's first step and recorded.
    Live {
        /// Where recordings go: the first path, then `-2`, `-3`... after reloads.
        record_base: PathBuf,
        /// Recordings started so far.
        recordings: u32,
    },
    /// A recording or script played step by step; user input does not reach the world.
    Replay {
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
    /// The world on its clock, its assessment, its recording, and where its commands come from.
    pub episode: Episode,
    /// The world as of the last step, for drawing and picking.
    pub snapshot: Snapshot,
    /// Picking against the snapshot (refreshed when the snapshot changes).
    pub picker: Picker,
    picker_step: Option<u64>,
    /// Input source.
    pub driver: Driver,
    /// Frame and step times.
    pub timing: Timing,
    watch: Option<Watch>,
    /// The last failed reload, shown until a good one.
    pub scene_error: Option<String>,
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

fn build(scene: &Scene, label: &str, source: Source) -> Result<Episode, AppError> {
    // Sessions relax by sweeps only, never by wall time, so that a recording replays bit for bit; a
    // frame that cannot keep up drops steps instead (see `SIM_BUDGET_PER_FRAME`).
    let world = scene
        .build_world(false)
        .map_err(|e| AppError::Scene(format!("{label}: the tissue cannot be built: {e}")))?;
    let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
    Ok(Episode::new(world, assessor, source))
}

impl Session {
    fn with(
        scene: Scene,
        scene_source: String,
        scene_label: String,
        driver: Driver,
        source: Source,
    ) -> Result<Self, AppError> {
        let episode = build(&scene, &scene_label, source)?;
        let mut snapshot = Snapshot::default();
        episode.snapshot_into(&mut snapshot);
        // A scene that cannot keep up is said once, in the window and the log.
        let warning = scene.cost_warning().map(|w| {
            eprintln!("dissect: {scene_label}: warning: {w}");
            (format!("warning: {w}"), Instant::now())
        });
        Ok(Self {
            scene,
            scene_source,
            scene_label,
            episode,
            snapshot,
            picker: Picker::default(),
            picker_step: None,
            driver,
            timing: Timing::default(),
            watch: None,
            scene_error: None,
            message: warning,
            started: Instant::now(),
            dropped: false,
        })
    }

    /// A live session on the scene at `path` (watched for changes) or the built-in scene, recorded to
    /// `record`.
    pub fn live(path: Option<&Path>, record: PathBuf) -> Result<Self, AppError> {
        let (source, label) = match path {
            Some(p) => (
                crate::scene::read_file(p).map_err(|e| AppError::Scene(e.to_string()))?,
                p.display().to_string(),
            ),
            None => (DEFAULT_SCENE.to_string(), DEFAULT_SCENE_PATH.to_string()),
        };
        let scene = Scene::from_str(&source, &label).map_err(|e| AppError::Scene(e.to_string()))?;
        let driver = Driver::Live { record_base: record, recordings: 0 };
        let mut session = Self::with(scene, source, label, driver, Source::Live)?;
        session.watch = path.map(Watch::new);
        session.start_recording();
        Ok(session)
    }

    /// Plays a recording (`dissect replay FILE`) on the scene it carries.
    pub fn replay(path: &Path) -> Result<Self, AppError> {
        let recording = Recording::load(path).map_err(|e| AppError::Scene(e.to_string()))?;
        let scene = Scene::from_str(&recording.scene_source, &recording.scene)
            .map_err(|e| AppError::Scene(format!("the recorded scene: {e}")))?;
        // A tampered recording can do no more than its scene allows.
        recording
            .script()
            .check_against(&scene)
            .map_err(|e| AppError::Scene(format!("{}: {e}", path.display())))?;
        let commands = recording.actions.iter().filter(|a| matches!(a, ScriptAction::Command(_))).count();
        let driver = Driver::Replay { commands, label: path.display().to_string() };
        let source = Source::Script(Player::new(recording.actions));
        Self::with(scene, recording.scene_source, recording.scene, driver, source)
    }

    /// Plays a script on a scene (the hidden `--demo-script`, for screenshots and demonstrations).
    pub fn demo(scene_path: Option<&Path>, script_path: &Path) -> Result<Self, AppError> {
        let script = crate::scene::Script::load(script_path).map_err(|e| AppError::Scene(e.to_string()))?;
        // An empty recording path: nothing is recorded.
        let mut session = Self::live(scene_path, PathBuf::new())?;
        script
            .check_against(&session.scene)
            .map_err(|e| AppError::Scene(format!("{}: {e}", script_path.display())))?;
        let commands = script.0.iter().filter(|a| matches!(a, ScriptAction::Command(_))).count();
        session.driver = Driver::Replay { commands, label: script_path.display().to_string() };
        session.episode.set_source(Source::Script(Player::new(script.0)));
        Ok(session)
    }

    fn start_recording(&mut self) {
        let Driver::Live { record_base, recordings } = &mut self.driver else {
            return;
        };
        if record_base.as_os_str().is_empty() {
            return;
        }
        *recordings += 1;
        let path = numbered(record_base, *recordings);
        match Recorder::create(&path, &self.scene_label, &self.scene_source) {
            Ok(r) => {
                println!("dissect: recording to {}", path.display());
                self.episode.record_to(r);
            }
            Err(e) => {
                let m = format!("cannot record to {}: {e}", path.display());
                eprintln!("dissect: {m}");
                self.say(m);
            }
        }
    }

    /// Ends the current recording (at the world's step), printing its path.
    fn finish_recording(&mut self) {
        let step = self.world().step_count();
        let recorded = self.episode.recorded();
        if let Some(r) = self.episode.take_recorder() {
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
        self.episode.recorder().map(|r| r.path().to_path_buf())
    }

    /// The world.
    pub fn world(&self) -> &World {
        self.episode.world()
    }

    /// The live assessment, when the scene has goals.
    pub fn assessor(&self) -> Option<&Assessor> {
        self.episode.assessor()
    }

    /// Drives the instrument from a haptic device from the next step on.
    pub fn set_haptic(&mut self, link: crate::haptics::HapticLink) {
        self.episode.set_haptic(link);
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
        if !self.input_enabled() {
            return;
        }
        if self.episode.pending().is_empty() && command == MoveTo(self.world().instrument().target).into() {
            return;
        }
        if let (Command::Instrument(MoveTo(p)), Some(Command::Instrument(MoveTo(last)))) =
            (&command, self.episode.last_pending_mut())
        {
            *last = *p;
            return;
        }
        self.episode.push(command);
    }

    /// Runs the steps a frame of `frame` real time calls for on the world's clock (see
    /// [`Episode::advance`]): live commands are pushed (and recorded with that step's number) before the
    /// first of them; a replay feeds its player before each.
    pub fn advance(&mut self, frame: Duration) {
        let t = Instant::now();
        let a = self.episode.advance(frame, Some(SIM_BUDGET_PER_FRAME));
        if let Some((path, e)) = self.episode.take_record_error() {
            eprintln!("dissect: recording stopped: {path}: {e}");
        }
        if let Some(m) = self.episode.take_haptic_error() {
            eprintln!("dissect: {m}");
            self.say(m);
        }
        if let Some(notice) = self.episode.world_mut().tissue_mut().take_notice() {
            self.say(notice);
        }
        self.dropped = a.dropped;
        if a.steps > 0 {
            self.episode.snapshot_into(&mut self.snapshot);
        }
        self.timing.push(FrameSample {
            t: self.started.elapsed().as_secs_f64(),
            frame_ms: frame.as_secs_f32() * 1000.0,
            sim_ms: t.elapsed().as_secs_f32() * 1000.0,
            step_us: if a.steps > 0 { a.step_us / a.steps as f32 } else { 0.0 },
            steps: a.steps,
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
        let rate = self.world().config().rate_hz as f32;
        let warm = self.started.elapsed() > Duration::from_secs(2);
        let running = !self.replay_finished();
        running
            && (self.world().is_behind()
                || self.dropped
                || (warm && self.timing.steps_per_second() < 0.9 * rate))
    }

    /// Whether a replay has played everything.
    pub fn replay_finished(&self) -> bool {
        matches!(self.driver, Driver::Replay { .. }) && self.episode.finished()
    }

    /// One line about the session for the status bar.
    pub fn status(&self) -> String {
        match (&self.driver, self.episode.recorder()) {
            (Driver::Live { .. }, Some(r)) => {
                format!("REC {} ({} commands)", r.path().display(), self.episode.recorded())
            }
            (Driver::Live { .. }, None) => "not recording".to_string(),
            (Driver::Replay { label, commands }, _) => format!(
                "REPLAY {label} ({commands} commands){}",
                if self.episode.finished() { " — finished" } else { "" }
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
        self.assessor().map(|a| a.assessment(self.world()))
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
        changed && self.reload()
    }

    /// Loads the scene again (from its file, or the built-in text): on success the world restarts (and
    /// a new recording begins); on failure the error is kept for display and the running scene stays.
    pub fn reload(&mut self) -> bool {
        if !self.input_enabled() {
            return false;
        }
        let loaded = match &self.watch {
            Some(w) => Scene::load_with_source(&w.path),
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
        let episode = match build(&scene, &self.scene_label, Source::Live) {
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
        self.episode = episode;
        self.episode.snapshot_into(&mut self.snapshot);
        self.picker_step = None;
        self.scene_error = None;
        self.start_recording();
        self.say(format!("reloaded {}", self.scene_label));
        true
    }

    /// Writes `<recording>.report.json` and `<recording>.report.png` (next to the recording, or in the
    /// current folder) when the scene has goals.
    pub fn write_report(&mut self) -> Option<ReportSummary> {
        let assessor = self.episode.assessor()?;
        let assessment = assessor.assessment(self.episode.world());
        let base = self.recording_path().unwrap_or_else(|| PathBuf::from("session.ron"));
        let json = base.with_extension("report.json");
        let png = base.with_extension("report.png");
        let report =
            assessor.report(self.episode.world(), &self.scene.title, crate::training::utc_now_string());
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
            println!(
                "dissect: replay ended at step {}; {commands} commands played",
                self.world().step_count()
            );
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
        let steps = live.world().step_count();
        assert_eq!(steps, 8);
        live.finish();
        let mut replay = Session::replay(&rec).expect("replay");
        for _ in 0..10 {
            replay.advance(Duration::from_millis(5));
        }
        assert_eq!(replay.world().step_count(), steps);
        assert_eq!(replay.world().instrument().target, [0.002, 0.01, 0.0]);
        assert!(replay.replay_finished());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
