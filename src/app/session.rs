//! The session: the scene, the episode it runs on the simulation thread (`runner::SimThread`: the
//! world at the scene's rate, the commands given to it and recorded, or read from a recording and
//! replayed, the assessment), what the thread last published, the scene file watch. No windows here.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use super::AppError;
use crate::chainmail::{Material, MaterialId};
use crate::instrument::Picker;
use crate::runner::priority::{Grant, HOW_TO_GRANT};
use crate::runner::{Episode, Event, Given, Input, Player, Published, SimThread, Source};
use crate::scene::{Action as ScriptAction, DEFAULT_SCENE, DEFAULT_SCENE_PATH, Recorder, Recording, Scene};
use crate::simulation::{CameraSpec, Command, InstrumentKind, Snapshot, WorldView};
use crate::tissue::CutDepth;
use crate::training::{Advice, Assessment, Assessor, Report};
use crate::ui::{FrameSample, ReplayState, ReportSummary, ThreadPace, Timing};
/// How often the scene file's modification time is checked.
const WATCH_EVERY: Duration = Duration::from_millis(500);
/// The trainee's camera is recorded at most this often while it moves.
const VIEW_EVERY: Duration = Duration::from_millis(100);

/// Who drives the session's episode.
pub enum Driver {
    /// The trainee: commands gathered per frame, handed to the thread for its next step and recorded.
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
        /// The actions played (kept to play again from the start when seeking back).
        actions: Vec<ScriptAction>,
        /// The last step the recording reaches.
        last_step: u64,
        /// The trainee's camera as recorded: from each step on, where it looked.
        views: Vec<(u64, CameraSpec)>,
    },
}

impl Driver {
    /// A replay of `actions`.
    fn replay(actions: Vec<ScriptAction>, label: String) -> Self {
        let commands = actions.iter().filter(|a| matches!(a, ScriptAction::Command(_))).count();
        let script = crate::scene::Script(actions);
        let views = script
            .timeline()
            .into_iter()
            .filter_map(|t| match &script.0[t.index] {
                ScriptAction::View(c) => Some((t.start, *c)),
                _ => None,
            })
            .collect();
        Driver::Replay { commands, label, last_step: script.duration_steps(), actions: script.0, views }
    }
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
    /// The episode (world on its clock, assessment, recording, command source), stepping on its own
    /// thread at the scene's rate; the windows read what it publishes.
    sim: SimThread,
    /// What the frame gives the world, gathered until the frame hands it to the thread.
    pending: Vec<Given>,
    /// The last move handed to the thread (a move to the same place is not sent again).
    last_target: Option<[f32; 3]>,
    /// The instrument and cutting depth the running world started with.
    start_tool: (InstrumentKind, CutDepth),
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
    last_step: u64,
    /// The scene file changed (or F5) while the session ran: waiting for the trainee's answer.
    pub reload_pending: bool,
    /// The trainee's camera as last recorded, and when.
    last_view: Option<(CameraSpec, Instant)>,
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
    // thread that cannot keep up gives up deadlines instead (see `runner::thread::MAX_LAG`).
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
        Self::from_episode(scene, scene_source, scene_label, driver, episode)
    }

    /// A live session on the scene at `path` (watched for changes) or the built-in scene, recorded to
    /// `record`, driven by the mouse alone.
    #[cfg(test)]
    pub fn live(path: Option<&Path>, record: PathBuf) -> Result<Self, AppError> {
        Self::live_with(path, record, None)
    }

    /// A live session driven, besides the mouse, by a haptic device from its first step.
    pub fn live_with(
        path: Option<&Path>,
        record: PathBuf,
        haptic: Option<crate::haptics::HapticLink>,
    ) -> Result<Self, AppError> {
        let (scene, source, label) = read_scene(path)?;
        let mut driver = Driver::Live { record_base: record, recordings: 0 };
        // The episode is built with its recorder and device before the thread takes it, so that
        // nothing of the first steps goes unrecorded.
        let mut episode = build(&scene, &label, Source::Live)?;
        let mut said = None;
        match start_recording(&mut driver, &label, &source) {
            Ok(Some(r)) => episode.record_to(r),
            Ok(None) => {}
            Err(m) => said = Some(m),
        }
        if let Some(link) = haptic {
            episode.set_haptic(link);
        }
        let mut session = Self::from_episode(scene, source, label, driver, episode)?;
        if let Some(m) = said {
            session.say(m);
        }
        session.watch = path.map(Watch::new);
        Ok(session)
    }

    fn from_episode(
        scene: Scene,
        scene_source: String,
        scene_label: String,
        driver: Driver,
        episode: Episode,
    ) -> Result<Self, AppError> {
        let start_tool = tool_of(&episode);
        let warning = scene.cost_warning().map(|w| {
            eprintln!("dissect: {scene_label}: warning: {w}");
            (format!("warning: {w}"), Instant::now())
        });
        let sim = SimThread::spawn(episode)
            .map_err(|e| AppError::Scene(format!("cannot start the simulation thread: {e}")))?;
        Ok(Self {
            scene,
            scene_source,
            scene_label,
            sim,
            pending: Vec::with_capacity(64),
            last_target: None,
            start_tool,
            picker: Picker::default(),
            picker_step: None,
            driver,
            timing: Timing::default(),
            watch: None,
            scene_error: None,
            message: warning,
            started: Instant::now(),
            last_step: 0,
            reload_pending: false,
            last_view: None,
        })
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
        let source = Source::Script(Player::new(recording.actions.clone()));
        let driver = Driver::replay(recording.actions, path.display().to_string());
        Self::with(scene, recording.scene_source, recording.scene, driver, source)
    }

    /// Plays a script on a scene (the hidden `--demo-script`, for screenshots and demonstrations).
    pub fn demo(scene_path: Option<&Path>, script_path: &Path) -> Result<Self, AppError> {
        let script = crate::scene::Script::load(script_path).map_err(|e| AppError::Scene(e.to_string()))?;
        let (scene, source, label) = read_scene(scene_path)?;
        script
            .check_against(&scene)
            .map_err(|e| AppError::Scene(format!("{}: {e}", script_path.display())))?;
        let player = Player::new(script.0.clone());
        let driver = Driver::replay(script.0, script_path.display().to_string());
        let mut session = Self::with(scene, source, label, driver, Source::Script(player))?;
        session.watch = scene_path.map(Watch::new);
        Ok(session)
    }

    /// Ends a recording (at its episode's step), printing its path.
    fn finish_recording(episode: &mut Episode) {
        let step = episode.world().step_count();
        let recorded = episode.recorded();
        if let Some(r) = episode.take_recorder() {
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

    /// How the simulation thread was scheduled when it started: real-time and how, or why not.
    pub fn scheduling(&self) -> &crate::runner::priority::Outcome {
        self.sim.scheduling()
    }

    /// What the thread published last (the world as of a recent step).
    pub fn published(&self) -> &Published {
        self.sim.current()
    }

    /// The world's snapshot as of the last frame taken from the thread.
    pub fn snapshot(&self) -> &Snapshot {
        &self.sim.current().snapshot
    }

    /// The recording's path, if recording.
    pub fn recording_path(&self) -> Option<PathBuf> {
        self.published().recording.clone()
    }

    /// The world's figures as of the last frame taken from the thread.
    pub fn world(&self) -> &WorldView {
        &self.sim.current().view
    }

    /// Whether the scene sets goals (and so has an assessment and a report).
    pub fn has_goals(&self) -> bool {
        self.scene.goals.is_some()
    }

    /// The instrument and cutting depth the running world started with.
    pub fn start_tool(&self) -> (InstrumentKind, CutDepth) {
        self.start_tool
    }

    /// Whether user input reaches the world.
    pub fn input_enabled(&self) -> bool {
        matches!(self.driver, Driver::Live { .. })
    }

    /// Gathers a command for the next step (ignored while replaying). Consecutive moves collapse into
    /// the last one; a move to where the last move went, with nothing else pending, is dropped.
    pub fn queue(&mut self, command: Command) {
        if !self.input_enabled() {
            return;
        }
        if let Command::MoveTo(p) = &command {
            if self.pending.is_empty() && self.last_target == Some(*p) {
                return;
            }
            if let Some(Given::Command(Command::MoveTo(last))) = self.pending.last_mut() {
                *last = *p;
                return;
            }
        }
        self.pending.push(Given::Command(command));
    }

    /// Forceps: close on the element under `hit` at the next step (the thread finds it in its world).
    pub fn grasp_at(&mut self, hit: crate::instrument::Hit) {
        if self.input_enabled() {
            self.pending.push(Given::GraspAt(hit));
        }
    }

    /// Hands the frame's input to the simulation thread (stamped with the step last seen) and takes
    /// the latest frame it published; `frame` is the real time since the last frame. The steps run on
    /// the thread at the scene's rate whatever the frame rate.
    pub fn advance(&mut self, frame: Duration) {
        let t = Instant::now();
        if let Some(Given::Command(Command::MoveTo(p))) =
            self.pending.iter().rev().find(|g| matches!(g, Given::Command(Command::MoveTo(_))))
        {
            self.last_target = Some(*p);
        }
        self.sim.give(std::mem::take(&mut self.pending));
        let published = self.sim.latest();
        let step = published.view.step_count();
        let pace = published.pace;
        let steps = step.saturating_sub(self.last_step) as u32;
        self.last_step = step;
        for event in self.sim.events() {
            self.on_event(event);
        }
        self.timing.set_pace(ThreadPace {
            steps_per_second: pace.steps_per_second,
            mean_step_us: pace.mean_step_us,
            worst_jitter_us: pace.worst_jitter_us,
            p99_late_us: pace.p99_late_us,
            input_lag_steps: pace.input_lag_steps,
            behind: pace.behind,
            realtime: pace.realtime,
            priority: pace.grant.label(),
            how_to_grant: (pace.grant == Grant::Normal).then_some(HOW_TO_GRANT),
        });
        self.timing.push(FrameSample {
            t: self.started.elapsed().as_secs_f64(),
            frame_ms: frame.as_secs_f32() * 1000.0,
            sim_ms: t.elapsed().as_secs_f32() * 1000.0,
            step_us: pace.mean_step_us,
            steps,
        });
    }

    fn on_event(&mut self, event: Event) {
        match event {
            Event::Replaced(mut old) => Self::finish_recording(&mut old),
            Event::Message(m) => {
                eprintln!("dissect: {m}");
                self.say(m);
            }
            Event::Report(..) => {}
        }
    }

    /// Rebuilds the picker if the snapshot moved on since it was last built.
    pub fn refresh_picker(&mut self) {
        let snapshot = &self.sim.current().snapshot;
        if self.picker_step != Some(snapshot.step) {
            self.picker.refresh(snapshot);
            self.picker_step = Some(snapshot.step);
        }
    }

    /// Whether the simulation runs slower than real time (or than the replay's speed): the thread gave
    /// up deadlines, or ran fewer than 90 % of the steps asked over its last full second.
    pub fn behind(&self) -> bool {
        let p = &self.published().pace;
        let warm = self.started.elapsed() > Duration::from_secs(2);
        let running =
            !self.replay_finished() && !self.published().paused && self.published().seeking.is_none();
        // No count yet (0) for a second after a new episode or speed.
        let slow = warm && p.steps_per_second > 0.0 && p.steps_per_second < 0.9 * p.rate_hz as f32;
        running && (p.behind || slow)
    }

    /// Whether a replay has played everything.
    pub fn replay_finished(&self) -> bool {
        matches!(self.driver, Driver::Replay { .. }) && self.published().finished
    }

    /// One line about the session for the status bar.
    pub fn status(&self) -> String {
        let p = self.published();
        match (&self.driver, &p.recording) {
            (Driver::Live { .. }, Some(path)) => {
                format!("REC {} ({} commands)", path.display(), p.recorded)
            }
            (Driver::Live { .. }, None) => "not recording".to_string(),
            (Driver::Replay { label, commands, .. }, _) => {
                format!("REPLAY {label} ({commands} commands){}", if p.finished { " — finished" } else { "" })
            }
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

    /// The assessment as of the last frame taken from the thread.
    pub fn assessment(&self) -> Option<Assessment> {
        self.published().assessment.clone()
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

    /// Checks the scene file; reloads it if it changed (or asks first, see
    /// [`Session::request_reload`]). Returns true when a new scene runs.
    pub fn poll_reload(&mut self) -> bool {
        let changed = self.watch.as_mut().is_some_and(Watch::changed);
        changed && self.request_reload()
    }

    /// Whether a reload would throw work away: the exercise's clock has started, or commands were
    /// recorded.
    pub fn running(&self) -> bool {
        let p = self.published();
        p.assessment.as_ref().is_some_and(|a| a.started) || p.recorded > 0
    }

    /// Reloads at once when nothing would be lost; otherwise asks first (`reload_pending`, answered by
    /// [`Session::reload`] or [`Session::keep_session`]). Returns true when a new scene runs.
    pub fn request_reload(&mut self) -> bool {
        if !self.input_enabled() {
            return false;
        }
        if self.running() {
            self.reload_pending = true;
            return false;
        }
        self.reload()
    }

    /// The answer "keep the session" to the reload question.
    pub fn keep_session(&mut self) {
        self.reload_pending = false;
        self.say("kept the session; F5 reloads the scene when you are ready");
    }

    /// What stops the trainee now, as of the last frame taken from the thread.
    pub fn advice(&self) -> Option<&Advice> {
        self.published().advice.as_ref()
    }

    /// Records the trainee's camera when it changed (at most every [`VIEW_EVERY`] while it moves), so
    /// that a replay can show the session through it.
    pub fn note_view(&mut self, camera: CameraSpec) {
        if !self.input_enabled() {
            return;
        }
        let due = match &self.last_view {
            None => true,
            Some((last, at)) => *last != camera && at.elapsed() >= VIEW_EVERY,
        };
        if due {
            self.pending.push(Given::View(camera));
            self.last_view = Some((camera, Instant::now()));
        }
    }

    /// Where a replay stands, for its controls (`None` when live).
    pub fn replay_state(&self, follow_camera: bool) -> Option<ReplayState> {
        let Driver::Replay { last_step, views, .. } = &self.driver else { return None };
        Some(ReplayState {
            step: self.world().step_count(),
            last_step: *last_step,
            rate_hz: self.world().config().rate_hz as f32,
            paused: self.published().paused,
            speed: self.published().speed as f32,
            seeking: self.published().seeking,
            has_camera: !views.is_empty(),
            follow_camera,
        })
    }

    /// The trainee's camera as recorded at the step shown, when the replay has it.
    pub fn replay_view(&self) -> Option<CameraSpec> {
        let Driver::Replay { views, .. } = &self.driver else { return None };
        let step = self.world().step_count();
        // Before the first recorded view, the trainee looked through that one (it is recorded once
        // the live session's first step has run).
        let k = views.partition_point(|(s, _)| *s <= step).max(1);
        views.get(k - 1).map(|(_, c)| *c)
    }

    /// Replay: pause or play on.
    pub fn set_paused(&mut self, pause: bool) {
        if matches!(self.driver, Driver::Replay { .. }) {
            self.sim.send(Input::Pause(pause));
        }
    }

    /// Replay: plays on at `speed` times the scene's rate (0.5, 2, 4...; 1 is real time).
    pub fn set_speed(&mut self, speed: f32) {
        if matches!(self.driver, Driver::Replay { .. }) {
            self.sim.send(Input::Speed(f64::from(speed)));
        }
    }

    /// Replay: goes to step `target`. A step ahead is reached by stepping on; one behind by the
    /// recording played again from the start (the simulation is deterministic, so the same steps give
    /// the same tissue). Either way the simulation thread runs the steps as fast as the machine goes,
    /// publishing as it goes, so the windows stay live and show the progress
    /// ([`ReplayState::seeking`]); then it takes up the clock again (paused if it was).
    pub fn seek(&mut self, target: u64) {
        let Driver::Replay { actions, last_step, .. } = &self.driver else { return };
        let target = target.min(*last_step);
        if target < self.world().step_count() {
            let player = Player::new(actions.clone());
            let episode = match build(&self.scene, &self.scene_label, Source::Script(player)) {
                Ok(e) => e,
                Err(e) => return self.say(e.to_string()),
            };
            self.sim.send(Input::Replace(Box::new(episode)));
        }
        self.sim.send(Input::FastForward(target));
        self.picker_step = None;
    }

    /// Loads the scene again (from its file, or the built-in text): on success the world restarts on
    /// the thread (and a new recording begins; the old one is finished when the thread hands its
    /// episode back); on failure the error is kept for display and the running scene stays.
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
        let mut episode = match build(&scene, &self.scene_label, Source::Live) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("{e}");
                self.scene_error = Some(e.to_string());
                return false;
            }
        };
        match start_recording(&mut self.driver, &self.scene_label, &source) {
            Ok(Some(r)) => episode.record_to(r),
            Ok(None) => {}
            Err(m) => self.say(m),
        }
        self.start_tool = tool_of(&episode);
        self.scene = scene;
        self.scene_source = source;
        // Input gathered for the old world does not reach the new one.
        self.pending.clear();
        self.last_target = None;
        self.sim.send(Input::Replace(Box::new(episode)));
        self.picker_step = None;
        self.last_step = 0;
        self.scene_error = None;
        self.reload_pending = false;
        self.last_view = None;
        self.say(format!("reloaded {}", self.scene_label));
        true
    }

    /// Writes `<recording>.report.json` and `<recording>.report.png` (next to the recording, or in the
    /// current folder) when the scene has goals, from the report the thread makes of its world now.
    pub fn write_report(&mut self) -> Option<ReportSummary> {
        if !self.has_goals() {
            return None;
        }
        let (title, date) = (self.scene.title.clone(), crate::training::utc_now_string());
        self.sim.send(Input::Report { title, date });
        let t = Instant::now();
        let report = loop {
            match self.sim.wait_event(Duration::from_millis(100)) {
                Some(Event::Report(report)) => break report?,
                Some(other) => self.on_event(other),
                None if t.elapsed() > Duration::from_secs(5) => {
                    self.say("report not written: the simulation thread did not answer");
                    return None;
                }
                None => {}
            }
        };
        let base = self.recording_path().unwrap_or_else(|| PathBuf::from("session.ron"));
        self.write_report_files(&report, &base)
    }

    fn write_report_files(&mut self, report: &Report, base: &Path) -> Option<ReportSummary> {
        let json = base.with_extension("report.json");
        let png = base.with_extension("report.png");
        let result = crate::training::write_report(&json, report)
            .and_then(|()| crate::training::write_plot(&png, report));
        match result {
            Ok(()) => {
                println!("dissect: report written to {} and {}", json.display(), png.display());
                Some(ReportSummary { assessment: report.assessment.clone(), json, png })
            }
            Err(e) => {
                self.say(format!("report not written: {e}"));
                None
            }
        }
    }

    /// Ends the session: the thread stops, the report (with goals) and the recordings are written.
    /// Returns the episode as it ended (`None` when it already ended).
    pub fn finish(&mut self) -> Option<Episode> {
        let (episode, events) = self.sim.stop();
        for event in events {
            self.on_event(event);
        }
        let mut episode = episode?;
        if self.input_enabled()
            && let Some(assessor) = episode.assessor()
        {
            let report =
                assessor.report(episode.world(), &self.scene.title, crate::training::utc_now_string());
            let base = episode
                .recorder()
                .map(|r| r.path().to_path_buf())
                .unwrap_or_else(|| PathBuf::from("session.ron"));
            self.write_report_files(&report, &base);
        }
        if let Driver::Replay { commands, .. } = &self.driver {
            println!(
                "dissect: replay ended at step {}; {commands} commands played",
                episode.world().step_count()
            );
        }
        Self::finish_recording(&mut episode);
        Some(episode)
    }
}

/// The scene at `path` (or the built-in one), its text and its label.
fn read_scene(path: Option<&Path>) -> Result<(Scene, String, String), AppError> {
    let (source, label) = match path {
        Some(p) => {
            (crate::scene::read_file(p).map_err(|e| AppError::Scene(e.to_string()))?, p.display().to_string())
        }
        None => (DEFAULT_SCENE.to_string(), DEFAULT_SCENE_PATH.to_string()),
    };
    let scene = Scene::from_str(&source, &label).map_err(|e| AppError::Scene(e.to_string()))?;
    Ok((scene, source, label))
}

/// The tool the episode's world starts with.
fn tool_of(episode: &Episode) -> (InstrumentKind, CutDepth) {
    let i = episode.world().instrument();
    (i.kind, i.depth)
}

/// Opens the next recording of a live driver: `Ok(None)` when recording is off (an empty path), an
/// error message when the file cannot be created.
fn start_recording(driver: &mut Driver, label: &str, source: &str) -> Result<Option<Recorder>, String> {
    let Driver::Live { record_base, recordings } = driver else {
        return Ok(None);
    };
    if record_base.as_os_str().is_empty() {
        return Ok(None);
    }
    *recordings += 1;
    let path = numbered(record_base, *recordings);
    match Recorder::create(&path, label, source) {
        Ok(r) => {
            println!("dissect: recording to {}", path.display());
            Ok(Some(r))
        }
        Err(e) => {
            let m = format!("cannot record to {}: {e}", path.display());
            eprintln!("dissect: {m}");
            Err(m)
        }
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
    fn a_live_session_on_its_thread_replays_to_the_same_state() {
        use crate::runner::State;
        let dir = std::env::temp_dir().join(format!("dissect-session-{}", std::process::id()));
        let rec = dir.join("r.ron");
        let mut live = Session::live(None, rec.clone()).expect("live session");
        live.queue(Command::Select(InstrumentKind::Scalpel));
        live.queue(Command::MoveTo([0.0, 0.01, 0.0]));
        live.queue(Command::MoveTo([0.001, 0.01, 0.0]));
        live.advance(Duration::from_millis(5));
        std::thread::sleep(Duration::from_millis(30));
        live.queue(Command::MoveTo([0.002, 0.01, 0.0]));
        live.advance(Duration::from_millis(30));
        std::thread::sleep(Duration::from_millis(30));
        live.advance(Duration::from_millis(30));
        let ended = live.finish().expect("the live episode");
        assert!(live.finish().is_none(), "a session ends once");
        let steps = ended.world().step_count();
        assert!(steps > 0);
        let mut replay = Session::replay(&rec).expect("replay");
        let t = Instant::now();
        while !replay.replay_finished() {
            assert!(t.elapsed() < Duration::from_secs(30), "the replay does not end");
            replay.advance(Duration::from_millis(5));
            std::thread::sleep(Duration::from_millis(5));
        }
        let replayed = replay.finish().expect("the replayed episode");
        assert_eq!(replayed.world().step_count(), steps);
        assert_eq!(replayed.world().instrument().target, [0.002, 0.01, 0.0]);
        let state = |e: &Episode| {
            serde_json::to_string(&State::of(e.world().tissue(), e.world().step_count())).expect("json")
        };
        assert_eq!(state(&replayed), state(&ended));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Takes frames until `done` holds (or fails after 30 s).
    fn until(session: &mut Session, what: &str, done: impl Fn(&Session) -> bool) {
        let t = Instant::now();
        while !done(session) {
            assert!(t.elapsed() < Duration::from_secs(30), "{what}");
            session.advance(Duration::from_millis(5));
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_reload_asks_first_once_the_session_has_started() {
        let dir = std::env::temp_dir().join(format!("dissect-reload-{}", std::process::id()));
        let mut live = Session::live(None, dir.join("r.ron")).expect("live session");
        // Nothing done yet: a reload goes ahead at once.
        assert!(live.request_reload());
        assert!(!live.reload_pending);
        live.queue(Command::Select(InstrumentKind::Scalpel));
        live.advance(Duration::from_millis(5));
        until(&mut live, "the command is not recorded", |s| s.published().recorded > 0);
        // Work would be lost: the trainee is asked, and the session runs on.
        assert!(!live.request_reload());
        assert!(live.reload_pending);
        live.keep_session();
        assert!(!live.reload_pending);
        assert!(live.published().recorded > 0, "the session ran on");
        // The answer "reload" restarts it.
        assert!(!live.request_reload());
        assert!(live.reload());
        assert!(!live.reload_pending);
        until(&mut live, "the new episode does not start", |s| s.published().recorded == 0);
        live.finish();
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_replay_shows_the_trainees_camera_pauses_and_seeks() {
        let dir = std::env::temp_dir().join(format!("dissect-seek-{}", std::process::id()));
        let rec = dir.join("r.ron");
        let mut live = Session::live(None, rec.clone()).expect("live session");
        let view = CameraSpec { eye: [0.0, 0.05, 0.05], target: [0.0; 3], fov_y_deg: 40.0 };
        live.note_view(view);
        live.queue(Command::Select(InstrumentKind::Forceps));
        live.queue(Command::MoveTo([0.0, 0.01, 0.0]));
        live.advance(Duration::from_millis(5));
        std::thread::sleep(Duration::from_millis(30));
        live.queue(Command::MoveTo([0.003, 0.008, 0.001]));
        live.advance(Duration::from_millis(5));
        std::thread::sleep(Duration::from_millis(30));
        live.advance(Duration::from_millis(5));
        let ended = live.finish().expect("the live episode");
        let end = ended.world().step_count();

        let mut replay = Session::replay(&rec).expect("replay");
        let state = replay.replay_state(true).expect("a replay");
        assert_eq!(state.last_step, end);
        assert!(state.has_camera);
        assert_eq!(replay.replay_view(), Some(view));
        replay.seek(end);
        until(&mut replay, "the seek does not arrive", |s| s.world().step_count() >= end);
        assert_eq!(replay.world().instrument().target, [0.003, 0.008, 0.001]);
        replay.seek(0);
        until(&mut replay, "the seek back does not arrive", |s| s.world().step_count() < end);
        replay.set_paused(true);
        until(&mut replay, "the pause does not arrive", |s| s.published().paused);
        let at = replay.world().step_count();
        std::thread::sleep(Duration::from_millis(50));
        replay.advance(Duration::from_millis(5));
        assert_eq!(replay.world().step_count(), at, "paused");
        replay.finish();
        let _ = std::fs::remove_dir_all(&dir);
    }
}
