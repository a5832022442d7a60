//! The simulation thread: an [`Episode`] stepped on a thread of its own at its world's rate, each step
//! started at its deadline (a native sleep finished by a short spin, `spin_sleep`), whatever the windows'
//! frame rate. The thread asks for real-time scheduling where the system grants it, and gives it up
//! while it could hold a core (see [`super::priority`]). Native only: the browser has no threads here
//! and steps its episode in the frame loop.
//!
//! Input reaches the thread through a channel ([`Input`], `crossbeam-channel`), each batch stamped with
//! the step its sender last saw; the thread gives it to the world before its next step, and the
//! episode's recorder writes it with the step it was given at, so a session recorded through the
//! thread replays bit for bit however late the input came. The windows read the latest [`Published`]
//! frame (snapshot, world view, assessment, pace) through a wait-free triple buffer (`triple_buffer`):
//! the thread never waits for them, and refills the frame every sixtieth of a second, in the gap
//! between two steps when the fill fits there (so a frame read is at most that old, plus
//! [`PUBLISH_WAIT`] and a step). Messages for the window (a device dropped, a recording that
//! stopped, a notice of the tissue) come back as [`Event`]s.
//!
//! Must not import wgpu, winit or egui.

use std::path::PathBuf;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use hdrhistogram::Histogram;

use super::Episode;
use super::priority::{Grant, MAX_UNBLOCKED, Outcome, Scheduler};
use crate::haptics::HapticLink;
use crate::instrument::Hit;
use crate::simulation::{Command, WorldView};
use crate::snapshot::Snapshot;
use crate::tissue::MeshRecipe;
use crate::training::{Assessment, Report};

/// How often the thread refills the published frame while it steps.
pub const PUBLISH_EVERY: Duration = Duration::from_micros(16_667);
/// How long past its time a frame may wait for a gap between two steps that it fits in (the last fill
/// took less than what is left before the next deadline), so that filling it holds no step back; a
/// frame that has waited this long is filled at once.
pub const PUBLISH_WAIT: Duration = Duration::from_millis(8);
/// How late the thread may fall before it gives up the steps it missed (it then runs behind real
/// time, and says so, instead of running a burst of steps to catch up).
pub const MAX_LAG: Duration = Duration::from_millis(50);
/// How long an idle thread (paused, or a replay that has ended) waits for input between looks.
const IDLE_WAIT: Duration = Duration::from_millis(20);
/// How long before a deadline the thread stops sleeping and spins: the scheduler's wake-up is not
/// exact (a normal thread's timer slack is 50 µs, then the time to be scheduled), spinning is.
const SPIN: Duration = Duration::from_micros(125);
/// The same for a real-time thread (no timer slack, scheduled at once): less time spinning, which is
/// time the windows do not get.
const SPIN_REALTIME: Duration = Duration::from_micros(50);
/// How long a real-time thread behind its deadlines sleeps when it has not blocked for
/// [`MAX_UNBLOCKED`] (long enough that the sleep does block).
const BLOCK: Duration = Duration::from_micros(50);
/// A real-time thread whose steps took this share of their period on average over a second gives up
/// real-time scheduling for the next second (it would hold a core the windows need).
const REALTIME_MAX_LOAD: f64 = 0.75;

/// One thing given to the world: a command, or a grasp to resolve against the world the thread has.
#[derive(Clone, Debug, PartialEq)]
pub enum Given {
    /// A command for the next step.
    Command(Command),
    /// Forceps: close on the element under a pick (resolved by [`World::element_at`] on the thread,
    /// recorded as the element grasped).
    ///
    /// [`World::element_at`]: crate::simulation::World::element_at
    GraspAt(Hit),
    /// Where the trainee's camera looks from the next step on (recorded, changes nothing in the world).
    View(crate::snapshot::CameraSpec),
}

/// What the thread is told.
pub enum Input {
    /// What to give the world before its next step, in order; `seen` is the step of the last frame the
    /// sender had read (the stamp: the thread counts how many steps late input comes).
    Give {
        /// The step the sender last saw.
        seen: u64,
        /// Commands and grasps, in the order given.
        items: Vec<Given>,
    },
    /// A haptic device drives the instrument from the next step.
    Haptic(HapticLink),
    /// Replaces the episode (a reload or a restart): the old one comes back as [`Event::Replaced`],
    /// with the haptic device moved to the new one.
    Replace(Box<Episode>),
    /// Asks for the session report now (scene title, date): it comes back as [`Event::Report`].
    Report {
        /// The scene's title.
        title: String,
        /// The date to write in it.
        date: String,
    },
    /// Stops stepping (`true`) or goes on (`false`).
    Pause(bool),
    /// Steps at this multiple of the world's rate from now on (a replay at 0.5×, 2×, 4×); 1 is real
    /// time. Values are clamped to 1/16 to 64.
    Speed(f64),
    /// Steps as fast as the machine goes, without deadlines, until the world reaches this step (or its
    /// script ends), publishing as it goes, then takes up the clock again: a replay's seek, after an
    /// [`Input::Replace`] with the episode from its start. A pause holds only after it.
    FastForward(u64),
}

/// What the thread says back.
pub enum Event {
    /// The episode an [`Input::Replace`] replaced, to finish its recording.
    Replaced(Box<Episode>),
    /// A message for the window and the log.
    Message(String),
    /// The session report asked for, when the scene has goals.
    Report(Option<Box<Report>>),
}

/// The pace the thread kept over the last full second (and, for the totals, since it started).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pace {
    /// The rate the thread steps at, steps per second: the world's rate times the speed.
    pub rate_hz: f64,
    /// Steps run in the last full second.
    pub steps_per_second: f32,
    /// Worst deviation of the interval between two step starts from the step length, microseconds.
    pub worst_jitter_us: f32,
    /// Worst lateness of a step's start after its deadline, microseconds.
    pub worst_late_us: f32,
    /// 99th percentile of that lateness, microseconds.
    pub p99_late_us: f32,
    /// Mean step time, microseconds.
    pub mean_step_us: f32,
    /// Whether the thread gave up deadlines it could not keep in that second.
    pub behind: bool,
    /// Whether the thread runs with real-time scheduling now (see [`super::priority`]).
    pub realtime: bool,
    /// How it was granted real-time scheduling when it started (normal: it was not).
    pub grant: Grant,
    /// Steps between the frame a batch of input was given on and the step it reached the world.
    pub input_lag_steps: u64,
    /// Steps run since the thread started (or since the episode was replaced).
    pub total_steps: u64,
    /// Their lateness summed, seconds.
    pub total_late_s: f64,
    /// 99th percentile of the lateness of all those steps, microseconds.
    pub total_p99_late_us: f32,
}

/// The frame the windows read: the world as of a step, and what goes with it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Published {
    /// The world's snapshot, to draw and pick against.
    pub snapshot: Snapshot,
    /// The world's figures for the panels.
    pub view: WorldView,
    /// The live assessment, when the scene has goals.
    pub assessment: Option<Assessment>,
    /// What stops the trainee now, if anything (the coach's sentence).
    pub advice: Option<crate::training::Advice>,
    /// The thread's pace.
    pub pace: Pace,
    /// Commands recorded since recording began.
    pub recorded: u64,
    /// Where the episode records, if it does.
    pub recording: Option<PathBuf>,
    /// Whether a script or recording has played everything.
    pub finished: bool,
    /// Whether the thread is paused.
    pub paused: bool,
    /// The multiple of the world's rate the thread steps at (1: real time).
    pub speed: f64,
    /// The step a fast-forward (a seek) is heading for, while it runs.
    pub seeking: Option<u64>,
    /// What finishes the snapshot's meshes while [`Published::fill`] has left them raw (lattice
    /// positions, no normals): [`Published::finish`] does it, [`SimThread::latest`] for its reader.
    pub unfinished: Option<std::sync::Arc<MeshRecipe>>,
}

impl Published {
    /// Refills the frame from `episode` (reusing its allocations), with the snapshot's meshes raw: the
    /// simulation thread copies the elements' positions, and whoever reads the frame maps them to the
    /// world and sums the normals ([`Published::finish`]). Finishing on the thread that steps cost
    /// 1.25 ms at 256 × 192 and 5 ms at 512 × 384, sixty times a second, five deadlines of 1 kHz.
    pub fn fill(&mut self, episode: &Episode) {
        let world = episode.world();
        world.snapshot_raw_into(&mut self.snapshot);
        self.unfinished = Some(std::sync::Arc::clone(world.tissue().mesh_recipe()));
        world.view_into(&mut self.view);
        self.assessment = episode.assessor().map(|a| a.assessment(world));
        self.advice = episode.assessor().and_then(|a| a.advice(world));
        self.recorded = episode.recorded();
        self.recording = episode.recorder().map(|r| r.path().to_path_buf());
        self.finished = episode.finished();
    }

    /// Finishes the snapshot's meshes if [`Published::fill`] left them raw: the snapshot is then what
    /// [`Episode::snapshot_into`] gives.
    pub fn finish(&mut self) {
        if let Some(recipe) = self.unfinished.take() {
            recipe.finish_snapshot(&mut self.snapshot);
        }
    }
}

/// Lateness histograms: nanoseconds, up to ten seconds, two significant digits.
fn histogram() -> Option<Histogram<u64>> {
    Histogram::new_with_bounds(1, 10_000_000_000, 2).ok()
}

fn p99_us(h: Option<&Histogram<u64>>) -> f32 {
    h.map_or(0.0, |h| h.value_at_quantile(0.99) as f32 * 1e-3)
}

/// Counts steps and their timing over one second at a time, and in total.
#[derive(Debug)]
struct PaceMeter {
    period: Duration,
    since: Instant,
    steps: u32,
    step_us: f64,
    worst_jitter: Duration,
    worst_late: Duration,
    late: Option<Histogram<u64>>,
    total_late: Option<Histogram<u64>>,
    behind: bool,
    last_start: Option<Instant>,
    done: Pace,
}

impl PaceMeter {
    fn new(period: Duration, rate_hz: f64) -> Self {
        Self {
            period,
            since: Instant::now(),
            steps: 0,
            step_us: 0.0,
            worst_jitter: Duration::ZERO,
            worst_late: Duration::ZERO,
            late: histogram(),
            total_late: histogram(),
            behind: false,
            last_start: None,
            done: Pace { rate_hz, ..Pace::default() },
        }
    }

    /// Counts a step; true when it closed a second (its figures are then in `done`).
    fn step(&mut self, start: Instant, deadline: Instant, took: Duration) -> bool {
        self.steps += 1;
        self.step_us += took.as_secs_f64() * 1e6;
        let late = start.saturating_duration_since(deadline);
        self.worst_late = self.worst_late.max(late);
        let ns = u64::try_from(late.as_nanos()).unwrap_or(u64::MAX).max(1);
        for h in [self.late.as_mut(), self.total_late.as_mut()].into_iter().flatten() {
            h.saturating_record(ns);
        }
        self.done.total_steps += 1;
        self.done.total_late_s += late.as_secs_f64();
        if let Some(last) = self.last_start {
            let interval = start - last;
            self.worst_jitter = self.worst_jitter.max(interval.abs_diff(self.period));
        }
        self.last_start = Some(start);
        let elapsed = start - self.since;
        if elapsed >= Duration::from_secs(1) {
            let secs = elapsed.as_secs_f64();
            self.done = Pace {
                steps_per_second: (f64::from(self.steps) / secs) as f32,
                worst_jitter_us: self.worst_jitter.as_secs_f32() * 1e6,
                worst_late_us: self.worst_late.as_secs_f32() * 1e6,
                p99_late_us: p99_us(self.late.as_ref()),
                mean_step_us: (self.step_us / f64::from(self.steps.max(1))) as f32,
                behind: self.behind,
                total_p99_late_us: p99_us(self.total_late.as_ref()),
                ..self.done
            };
            self.since = start;
            self.steps = 0;
            self.step_us = 0.0;
            self.worst_jitter = Duration::ZERO;
            self.worst_late = Duration::ZERO;
            self.behind = false;
            if let Some(h) = self.late.as_mut() {
                h.reset();
            }
            return true;
        }
        false
    }

    /// The thread stopped stepping for a while (paused, idle): intervals across the pause are not jitter.
    fn idle(&mut self) {
        self.last_start = None;
    }
}

/// An episode stepping on its own thread, and the ends of its channels.
pub struct SimThread {
    input: Sender<Input>,
    events: Receiver<Event>,
    output: triple_buffer::Output<Published>,
    handle: Option<JoinHandle<Episode>>,
    scheduling: Outcome,
}

impl SimThread {
    /// Starts stepping `episode` on a new thread named `dissect-sim`.
    pub fn spawn(episode: Episode) -> std::io::Result<Self> {
        let mut first = Published::default();
        first.fill(&episode);
        first.finish();
        first.pace.rate_hz = episode.world().config().rate_hz;
        first.speed = 1.0;
        let (publisher, output) = triple_buffer::triple_buffer(&first);
        let (input, inputs) = crossbeam_channel::unbounded();
        let (say, events) = crossbeam_channel::unbounded();
        let (told, scheduled) = crossbeam_channel::bounded(1);
        let handle = std::thread::Builder::new().name("dissect-sim".into()).spawn(move || {
            // The thread is a worker of a pool of its own, so that a step that shares its work with a
            // helper thread (a large region's tear scan, a whole-body sweep) never waits for a helper
            // the scheduler has not yet given a core (`chainmail::worker_pool`). Made before the thread
            // asks for real-time scheduling: the helpers keep normal priority. Without it (a failure
            // to start threads) the steps use rayon's global pool, as before.
            let _pool = crate::chainmail::worker_pool("dissect-sim")
                .map_err(|e| {
                    log::warn!("simulation thread: no pool of its own ({e}); using rayon's global pool")
                })
                .ok();
            let (scheduler, outcome) = Scheduler::acquire();
            let _ = told.send(outcome);
            run(episode, &inputs, &say, publisher, scheduler)
        })?;
        // RealtimeKit answers over D-Bus, whose calls time out after 10 s.
        let scheduling = scheduled.recv_timeout(Duration::from_secs(15)).unwrap_or_else(|_| Outcome {
            grant: Grant::Normal,
            refused: vec![(Grant::Normal, "the simulation thread did not say how it is scheduled".into())],
        });
        Ok(Self { input, events, output, handle: Some(handle), scheduling })
    }

    /// How the thread was scheduled when it started: real-time and how, or why not.
    pub fn scheduling(&self) -> &Outcome {
        &self.scheduling
    }

    /// Sends the thread an input (dropped if the thread has ended).
    pub fn send(&self, input: Input) {
        let _ = self.input.send(input);
    }

    /// Gives the world `items` before its next step, stamped with the step last seen.
    pub fn give(&self, items: Vec<Given>) {
        if !items.is_empty() {
            let seen = self.output.output_buffer().view.step_count();
            self.send(Input::Give { seen, items });
        }
    }

    /// Takes the latest published frame, if a newer one is there, and returns the current one, its
    /// meshes finished here ([`Published::finish`]).
    pub fn latest(&mut self) -> &Published {
        self.output.update();
        let frame = self.output.output_buffer_mut();
        frame.finish();
        frame
    }

    /// The frame last taken by [`SimThread::latest`] (no update).
    pub fn current(&self) -> &Published {
        self.output.output_buffer()
    }

    /// What the thread has said since the last call.
    pub fn events(&self) -> Vec<Event> {
        self.events.try_iter().collect()
    }

    /// Waits up to `timeout` for the next event.
    pub fn wait_event(&self, timeout: Duration) -> Option<Event> {
        self.events.recv_timeout(timeout).ok()
    }

    /// Stops the thread after its current step and returns the episode (`None` if the thread
    /// panicked or was already stopped), with any events not yet read. The last frame taken stays
    /// readable.
    pub fn stop(&mut self) -> (Option<Episode>, Vec<Event>) {
        // Closing the channel is the signal to stop.
        let (dead, _) = crossbeam_channel::unbounded();
        drop(std::mem::replace(&mut self.input, dead));
        let episode = self.handle.take().and_then(|h| h.join().ok());
        (episode, self.events.try_iter().collect())
    }
}

impl Drop for SimThread {
    fn drop(&mut self) {
        if let Some(h) = self.handle.take() {
            let (dead, _) = crossbeam_channel::unbounded();
            drop(std::mem::replace(&mut self.input, dead));
            let _ = h.join();
        }
    }
}

/// What the thread's loop keeps between inputs besides the episode.
#[derive(Debug)]
struct Control {
    paused: bool,
    lag: u64,
    speed: f64,
    fast_forward: Option<u64>,
    /// The thread's real-time scheduling: how it was granted, whether it holds it now.
    scheduler: Scheduler,
}

impl Control {
    /// Takes or gives up real-time scheduling (when it was granted at all); a failure is said to the
    /// window (a refusal to take it back is final, [`Scheduler::resume`]).
    fn set_realtime(&mut self, on: bool, say: &Sender<Event>) {
        if let Err(why) = if on { self.scheduler.resume() } else { self.scheduler.release() } {
            let _ = say.send(Event::Message(why));
        }
    }
}

/// Hands an input to the episode (or to the loop's control).
fn take(episode: &mut Episode, input: Input, say: &Sender<Event>, control: &mut Control) {
    match input {
        Input::Give { seen, items } => {
            control.lag = episode.world().step_count().saturating_sub(seen);
            for item in items {
                match item {
                    Given::Command(c) => episode.push(c),
                    Given::GraspAt(hit) => {
                        if let Some(e) = episode.world().element_at(&hit) {
                            episode.push(Command::GraspElement(e));
                        }
                    }
                    Given::View(camera) => episode.record_view(&camera),
                }
            }
        }
        Input::Haptic(link) => episode.set_haptic(link),
        Input::Replace(mut next) => {
            if let Some(link) = episode.take_haptic() {
                next.set_haptic(link);
            }
            let old = std::mem::replace(episode, *next);
            let _ = say.send(Event::Replaced(Box::new(old)));
        }
        Input::Report { title, date } => {
            let report = episode.assessor().map(|a| Box::new(a.report(episode.world(), &title, date)));
            let _ = say.send(Event::Report(report));
        }
        Input::Pause(p) => control.paused = p,
        Input::Speed(x) => control.speed = if x.is_finite() { x.clamp(1.0 / 16.0, 64.0) } else { 1.0 },
        Input::FastForward(step) => control.fast_forward = Some(step),
    }
}

/// Says what the last step left to say.
fn messages(episode: &mut Episode, say: &Sender<Event>) {
    if let Some((path, e)) = episode.take_record_error() {
        let _ = say.send(Event::Message(format!("recording stopped: {path}: {e}")));
    }
    if let Some(m) = episode.take_haptic_error() {
        let _ = say.send(Event::Message(m));
    }
    if let Some(m) = episode.world_mut().tissue_mut().take_notice() {
        let _ = say.send(Event::Message(m));
    }
}

/// Whether a thread that kept `pace` over its last second may be real-time for the next: only while its
/// steps leave the core free most of the time and it gave up no deadline.
fn keeps_realtime(pace: &Pace, period: Duration) -> bool {
    let load = f64::from(pace.mean_step_us) * 1e-6 / period.as_secs_f64();
    !pace.behind && load < REALTIME_MAX_LOAD
}

/// The step period and a fresh pace meter for the episode's rate at `speed` (a replay's 0.25× to 4×).
fn pace(episode: &Episode, speed: f64) -> (Duration, PaceMeter) {
    let rate_hz = episode.world().config().rate_hz * speed;
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    (period, PaceMeter::new(period, rate_hz))
}

/// Takes one input; when it brings a new world or a new speed, the step period and the pace meter
/// are those of its own rate, and the answer is `true`.
fn receive(
    episode: &mut Episode,
    input: Input,
    say: &Sender<Event>,
    control: &mut Control,
    speed: &mut f64,
    (period, meter): (&mut Duration, &mut PaceMeter),
) -> bool {
    let replace = matches!(input, Input::Replace(_));
    take(episode, input, say, control);
    if !replace && control.speed == *speed {
        return false;
    }
    *speed = control.speed;
    (*period, *meter) = pace(episode, *speed);
    true
}

/// The thread's loop: inputs, wait for the deadline, step, publish now and then.
fn run(
    mut episode: Episode,
    inputs: &Receiver<Input>,
    say: &Sender<Event>,
    mut publisher: triple_buffer::Input<Published>,
    scheduler: Scheduler,
) -> Episode {
    let mut control = Control { paused: false, lag: 0, speed: 1.0, fast_forward: None, scheduler };
    // When the thread last blocked (slept natively or waited for input): a real-time thread must block
    // now and then (`RLIMIT_RTTIME`, see `MAX_UNBLOCKED`).
    let mut blocked = Instant::now();
    let mut speed = control.speed;
    let (mut period, mut meter) = pace(&episode, speed);
    let mut deadline = Instant::now();
    let mut last_publish: Option<Instant> = None;
    // How long the last frame took to fill.
    let mut fill_took = Duration::ZERO;
    let mut dirty = true;
    loop {
        loop {
            match inputs.try_recv() {
                Ok(input) => {
                    if receive(&mut episode, input, say, &mut control, &mut speed, (&mut period, &mut meter))
                    {
                        // A fresh clock and a frame at once.
                        deadline = Instant::now();
                        last_publish = None;
                    }
                    dirty = true;
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return episode,
            }
        }
        if let Some(target) = control.fast_forward {
            // A seek: no deadlines until the target, the frame refilled as it goes (its progress);
            // flat out, so with normal scheduling (the windows keep their share of the cores).
            control.set_realtime(false, say);
            let arrived = episode.world().step_count() >= target || episode.finished();
            if !arrived && episode.step().is_some() {
                messages(&mut episode, say);
                let now = Instant::now();
                if last_publish.is_none_or(|t| now - t >= PUBLISH_EVERY) {
                    publish(&mut publisher, &episode, &meter, &control);
                    last_publish = Some(now);
                }
                continue;
            }
            control.fast_forward = None;
            control.set_realtime(true, say);
            meter.idle();
            deadline = Instant::now();
            publish(&mut publisher, &episode, &meter, &control);
            last_publish = Some(deadline);
            dirty = false;
        }
        if control.paused || episode.finished() {
            // Idle: show the last state, then wait for input without spinning.
            if dirty {
                publish(&mut publisher, &episode, &meter, &control);
                dirty = false;
            }
            meter.idle();
            blocked = Instant::now();
            match inputs.recv_timeout(IDLE_WAIT) {
                Ok(input) => {
                    receive(&mut episode, input, say, &mut control, &mut speed, (&mut period, &mut meter));
                    dirty = true;
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return episode,
            }
            deadline = Instant::now();
            continue;
        }
        // Spinning, not yielding: a yield may hand the core to the renderer's threads for a slice.
        let realtime = control.scheduler.realtime();
        let spin = if realtime { SPIN_REALTIME } else { SPIN };
        let now = Instant::now();
        if deadline.saturating_duration_since(now) > spin + BLOCK {
            // The sleeper sleeps natively (blocks, for at least `BLOCK`) until `spin` before the deadline.
            blocked = now;
        } else if realtime && now - blocked >= MAX_UNBLOCKED {
            // Behind its deadlines a thread never sleeps: a real-time one blocks briefly now and then.
            std::thread::sleep(BLOCK);
            blocked = Instant::now();
        }
        spin_sleep::SpinSleeper::new(spin.as_nanos() as u32)
            .with_spin_strategy(spin_sleep::SpinStrategy::SpinLoopHint)
            .sleep_until(deadline);
        let start = Instant::now();
        let stepped = episode.step().is_some();
        let end = Instant::now();
        if stepped {
            if meter.step(start, deadline, end - start) {
                control.set_realtime(keeps_realtime(&meter.done, period), say);
            }
            dirty = true;
        } else if episode.finished() {
            // The call that found the script played out (its last `At` reached) stepped nothing but
            // ended the episode: the next frame must say so. (Until 2026-11-29 a replay whose last
            // step had just been published never said it had finished: about one run in five of a
            // loaded machine's live-session test waited for it in vain.)
            dirty = true;
        }
        messages(&mut episode, say);
        deadline += period;
        if end > deadline + MAX_LAG {
            deadline = end;
            meter.behind = true;
        }
        // A frame due is filled in the gap before the next deadline if it fits there, or once it has
        // waited `PUBLISH_WAIT` (a thread whose steps leave no such gap).
        let since = last_publish.map(|t| end.saturating_duration_since(t));
        let fits = deadline.saturating_duration_since(Instant::now()) >= fill_took + spin;
        let (due, overdue) = match since {
            None => (true, true),
            Some(s) => (s >= PUBLISH_EVERY, s >= PUBLISH_EVERY + PUBLISH_WAIT),
        };
        if dirty && due && (fits || overdue) {
            let filled = Instant::now();
            publish(&mut publisher, &episode, &meter, &control);
            fill_took = filled.elapsed();
            last_publish = Some(end);
            dirty = false;
        }
    }
}

fn publish(
    publisher: &mut triple_buffer::Input<Published>,
    episode: &Episode,
    meter: &PaceMeter,
    control: &Control,
) {
    let frame = publisher.input_buffer_mut();
    frame.fill(episode);
    frame.pace = Pace {
        realtime: control.scheduler.realtime(),
        grant: control.scheduler.grant(),
        input_lag_steps: control.lag,
        total_p99_late_us: p99_us(meter.total_late.as_ref()),
        ..meter.done
    };
    frame.paused = control.paused;
    frame.speed = control.speed;
    frame.seeking = control.fast_forward;
    publisher.publish();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::Source;
    use crate::scene::{DEFAULT_SCENE, DEFAULT_SCENE_PATH, Scene};

    fn episode() -> Episode {
        let scene = Scene::from_str(DEFAULT_SCENE, DEFAULT_SCENE_PATH).expect("scene");
        let world = scene.build_world(false).expect("world");
        Episode::new(world, None, Source::Live)
    }

    /// A frame filled raw on the simulation thread and finished by its reader is the snapshot the
    /// world gives, bit for bit: on a flat sheet (cut and lifted), a sphere (its caps' poles) and a
    /// volume; into a fresh frame, and into one that was filled and finished before.
    #[test]
    fn a_frame_finished_by_its_reader_is_the_worlds_snapshot() {
        let cases = [
            (
                include_str!("../../scenes/meninges.ron"),
                include_str!("../../scenes/scripts/meninges_careful.ron"),
                1500,
            ),
            (include_str!("../../scenes/sphere.ron"), include_str!("../../scenes/scripts/sphere.ron"), 300),
            (include_str!("../../scenes/volume.ron"), include_str!("../../scenes/scripts/volume.ron"), 300),
        ];
        for (k, (scene, script, steps)) in cases.into_iter().enumerate() {
            let scene = Scene::from_str(scene, "scene.ron").expect("scene");
            let script = crate::scene::Script::from_str(script, "script.ron").expect("script");
            let mut frame = Published::default();
            for at in [steps / 3, steps] {
                let out = crate::runner::run(&scene, "scene.ron", &script, "script.ron", Some(at), None)
                    .expect("run");
                let episode = Episode::new(out.world, None, Source::Live);
                frame.fill(&episode);
                assert!(frame.unfinished.is_some(), "case {k}: filled raw");
                frame.finish();
                assert!(frame.unfinished.is_none(), "case {k}: finished");
                let mut want = Snapshot::default();
                episode.snapshot_into(&mut want);
                assert!(!want.layers.is_empty() && !want.layers[0].normals.is_empty(), "case {k}");
                assert_eq!(frame.snapshot, want, "case {k} at step {at}");
                // And the positions are where the tissue says its elements are.
                let tissue = episode.world().tissue();
                for (layer, mesh) in tissue.layers().iter().zip(&frame.snapshot.layers) {
                    for (i, p) in mesh.positions[..layer.count as usize].iter().enumerate() {
                        let e = crate::chainmail::ElementId(layer.first + i as u32);
                        assert_eq!(Some(*p), tissue.world_position(e), "case {k}");
                    }
                }
                // And the fibres are what the tissue's direct path fills (its reference: each intact
                // fibre between its ends in the world, the lower layer's first, stretched by their
                // distance over its rest length; the others cut or torn), bit for bit.
                let snap = &frame.snapshot;
                let (mut fibres, mut stretch, mut sites, mut broken) = Default::default();
                tissue.fill_fibres(&mut fibres, &mut stretch, &mut sites, &mut broken);
                assert_eq!(snap.fibres, fibres, "case {k}: fibres");
                assert_eq!(snap.fibre_stretch, stretch, "case {k}: stretch");
                assert_eq!(snap.fibre_sites, sites, "case {k}: sites");
                assert_eq!(snap.broken_fibres, broken, "case {k}: broken");
                // And that path reads every connective link: intact ones as fibres, broken ones as
                // cut or torn.
                let states: Vec<_> = (0..tissue.body().link_count() as u32)
                    .map(crate::chainmail::LinkId)
                    .filter(|&l| tissue.link_kind(l) == Some(crate::tissue::LinkKind::Connective))
                    .map(|l| tissue.body().link_broken(l))
                    .collect();
                let cut = states.iter().filter(|s| **s == Some(crate::chainmail::BreakReason::Cut)).count();
                assert_eq!(states.iter().filter(|s| s.is_none()).count(), fibres.len(), "case {k}: intact");
                assert_eq!(states.len() - fibres.len(), broken.len(), "case {k}: broken");
                assert_eq!(broken.iter().filter(|b| b.cut).count(), cut, "case {k}: cut");
                if k == 0 && at == steps {
                    assert!(!fibres.is_empty() && !broken.is_empty(), "the careful script cuts fibres");
                }
            }
        }
    }

    #[test]
    fn the_thread_steps_on_its_own_and_publishes() {
        let mut sim = SimThread::spawn(episode()).expect("thread");
        sim.give(vec![Given::Command(Command::MoveTo([0.0, 0.02, 0.0]))]);
        let t = Instant::now();
        while sim.latest().view.step_count() < 50 {
            assert!(t.elapsed() < Duration::from_secs(20), "the thread does not step");
            std::thread::sleep(Duration::from_millis(5));
        }
        // What the windows read is finished: world positions and unit normals.
        let frame = sim.latest();
        assert!(frame.unfinished.is_none());
        let layer = &frame.snapshot.layers[0];
        assert_eq!(layer.normals.len(), layer.positions.len());
        assert!(layer.normals.iter().all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0).abs() < 1e-3));
        let (episode, _) = sim.stop();
        let episode = episode.expect("the thread ended cleanly");
        assert!(episode.world().step_count() >= 50);
        assert_eq!(episode.world().instrument().target, [0.0, 0.02, 0.0]);
    }

    #[test]
    fn a_slow_speed_steps_slower_and_a_fast_forward_reaches_its_step() {
        let mut sim = SimThread::spawn(episode()).expect("thread");
        sim.send(Input::Speed(0.25));
        let t = Instant::now();
        while sim.latest().speed != 0.25 {
            assert!(t.elapsed() < Duration::from_secs(20), "the speed does not arrive");
            std::thread::sleep(Duration::from_millis(5));
        }
        let a = sim.latest().view.step_count();
        std::thread::sleep(Duration::from_millis(400));
        let b = sim.latest().view.step_count();
        // 100 steps at a quarter of 1000 Hz (400 at full speed); a busy machine only makes fewer.
        assert!(b - a < 200, "{} steps in 0.4 s at 0.25x", b - a);
        // Paused, a fast-forward still goes to its step, and stops there.
        sim.send(Input::Pause(true));
        sim.send(Input::FastForward(b + 3000));
        let t = Instant::now();
        while sim.latest().view.step_count() < b + 3000 || sim.latest().seeking.is_some() {
            assert!(t.elapsed() < Duration::from_secs(60), "the fast-forward does not arrive");
            std::thread::sleep(Duration::from_millis(5));
        }
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(sim.latest().view.step_count(), b + 3000, "paused after the fast-forward");
        let (episode, _) = sim.stop();
        assert_eq!(episode.map(|e| e.world().step_count()), Some(b + 3000));
    }

    #[test]
    fn real_time_is_given_up_by_a_thread_that_would_hold_a_core() {
        let ms = Duration::from_millis(1);
        let pace = |mean_step_us, behind| Pace { mean_step_us, behind, ..Pace::default() };
        assert!(keeps_realtime(&pace(300.0, false), ms));
        assert!(!keeps_realtime(&pace(800.0, false), ms), "steps take most of the period");
        assert!(!keeps_realtime(&pace(300.0, true), ms), "deadlines were given up");
        assert!(keeps_realtime(&pace(300.0, false), ms / 2), "a 2x replay: 60 % of its period");
        assert!(!keeps_realtime(&pace(300.0, false), ms / 4), "a 4x replay: longer than its period");
    }

    #[test]
    fn a_real_time_thread_seeks_with_normal_scheduling() {
        let mut sim = SimThread::spawn(episode()).expect("thread");
        if !sim.scheduling().realtime() {
            eprintln!("skipped where real-time scheduling is not granted: {}", sim.scheduling());
            return;
        }
        let wait = |sim: &mut SimThread, what: &str, until: &dyn Fn(&Published) -> bool| {
            let t = Instant::now();
            while !until(sim.latest()) {
                assert!(t.elapsed() < Duration::from_secs(60), "{what}");
                std::thread::sleep(Duration::from_millis(1));
            }
        };
        wait(&mut sim, "real time at first", &|p| p.pace.realtime && p.view.step_count() > 0);
        let target = sim.latest().view.step_count() + 50_000;
        sim.send(Input::FastForward(target));
        wait(&mut sim, "no real time while seeking", &|p| p.seeking.is_some() && !p.pace.realtime);
        wait(&mut sim, "real time again after", &|p| {
            p.seeking.is_none() && p.pace.realtime && p.view.step_count() >= target
        });
        let _ = sim.stop();
    }

    #[test]
    fn a_paused_thread_does_not_step() {
        let mut sim = SimThread::spawn(episode()).expect("thread");
        sim.send(Input::Pause(true));
        std::thread::sleep(Duration::from_millis(100));
        let a = sim.latest().view.step_count();
        std::thread::sleep(Duration::from_millis(100));
        let b = sim.latest().view.step_count();
        assert_eq!(a, b);
        assert!(sim.latest().paused);
        let (episode, _) = sim.stop();
        assert_eq!(episode.map(|e| e.world().step_count()), Some(b));
    }
}
