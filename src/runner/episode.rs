//! One episode: a world, its assessment, the recording of what it is told, and where its commands come
//! from (the trainee's live input, or a script or recording played step by step). `dissect run`, the
//! trainer's session and the tests all drive an episode, so the loop "feed the step's commands, record
//! them, step, assess" is written once, here.
//!
//! An episode is `Send` and talks through plain values (commands in, a [`Snapshot`] out), so that it can
//! run on a thread of its own; its timing uses `web_time`, which is std's on native and the browser's
//! clock on the web.

use std::time::Duration;

use web_time::Instant;

use super::Player;
use crate::scene::Recorder;
use crate::simulation::{Command, StepCounters, World};
use crate::snapshot::Snapshot;
use crate::training::Assessor;

/// Where an episode's commands come from.
#[derive(Clone, Debug)]
pub enum Source {
    /// Commands given as they come ([`Episode::push`]), handed to the world before the next step.
    Live,
    /// A script or a recording, played step by step; [`Episode::push`] is ignored.
    Script(Player),
}

/// What [`Episode::advance`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Advance {
    /// Steps run.
    pub steps: u32,
    /// Steps the clock called for that were dropped because the time budget ran out.
    pub dropped: bool,
    /// Wall time of the steps run, microseconds, summed.
    pub step_us: f32,
}

/// A world, its assessor, the recording of its commands and their source.
pub struct Episode {
    world: World,
    assessor: Option<Assessor>,
    recorder: Option<Recorder>,
    recorded: u64,
    record_error: Option<(String, String)>,
    source: Source,
    /// Live commands gathered since the last step.
    pending: Vec<Command>,
    /// After a script has ended, keep stepping without input (a run of a given number of steps).
    run_past_end: bool,
    /// A haptic device driving the instrument of a live episode (with the mouse: none).
    haptic: Option<crate::haptics::HapticLink>,
    haptic_error: Option<String>,
}

impl Episode {
    /// An episode of `world` driven by `source`, assessed by `assessor` when the scene has goals.
    pub fn new(world: World, assessor: Option<Assessor>, source: Source) -> Self {
        Self {
            world,
            assessor,
            recorder: None,
            recorded: 0,
            record_error: None,
            source,
            pending: Vec::with_capacity(64),
            run_past_end: false,
            haptic: None,
            haptic_error: None,
        }
    }

    /// Lets a haptic device drive the instrument of a live episode, read and written every step.
    pub fn set_haptic(&mut self, link: crate::haptics::HapticLink) {
        self.haptic = Some(link);
    }

    /// Takes the haptic device away (to hand it to the episode that replaces this one).
    pub fn take_haptic(&mut self) -> Option<crate::haptics::HapticLink> {
        self.haptic.take()
    }

    /// Why the haptic device was dropped (it went away or reported nonsense), taken.
    pub fn take_haptic_error(&mut self) -> Option<String> {
        self.haptic_error.take()
    }

    /// Records every command given to the world from now on.
    pub fn record_to(&mut self, recorder: Recorder) {
        self.recorder = Some(recorder);
        self.recorded = 0;
    }

    /// Stops recording and hands the recorder back (to finish it).
    pub fn take_recorder(&mut self) -> Option<Recorder> {
        self.recorder.take()
    }

    /// The recorder, if recording.
    pub fn recorder(&self) -> Option<&Recorder> {
        self.recorder.as_ref()
    }

    /// Commands recorded since recording began.
    pub fn recorded(&self) -> u64 {
        self.recorded
    }

    /// Why recording stopped, if writing failed: the recording's path and the cause (taken).
    pub fn take_record_error(&mut self) -> Option<(String, String)> {
        self.record_error.take()
    }

    /// Records where the trainee's camera looks from the next step on, when recording (a view changes
    /// nothing in the world; a replay shows the session through it).
    pub fn record_view(&mut self, camera: &crate::snapshot::CameraSpec) {
        if let Some(r) = &mut self.recorder
            && let Err(e) = r.record_view(self.world.step_count(), camera)
        {
            self.record_error = Some((r.path().display().to_string(), e.to_string()));
            self.recorder = None;
        }
    }

    /// Keeps stepping without input once a script has ended (instead of finishing).
    pub fn run_past_end(&mut self, on: bool) {
        self.run_past_end = on;
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to change it between steps (materials tuned live are commands instead).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The assessor, when the scene has goals.
    pub fn assessor(&self) -> Option<&Assessor> {
        self.assessor.as_ref()
    }

    /// Where commands come from.
    pub fn source(&self) -> &Source {
        &self.source
    }

    /// Takes commands from `source` from now on (live commands not yet stepped are dropped).
    pub fn set_source(&mut self, source: Source) {
        self.pending.clear();
        self.source = source;
    }

    /// Whether input given through [`Episode::push`] reaches the world.
    pub fn is_live(&self) -> bool {
        matches!(self.source, Source::Live)
    }

    /// Live commands gathered for the next step.
    pub fn pending(&self) -> &[Command] {
        &self.pending
    }

    /// Gathers a live command for the next step (ignored while a script plays).
    pub fn push(&mut self, command: Command) {
        if self.is_live() {
            self.pending.push(command);
        }
    }

    /// The last live command gathered, to merge a new one into it.
    pub fn last_pending_mut(&mut self) -> Option<&mut Command> {
        self.pending.last_mut()
    }

    /// Whether a script has played everything (a live episode never finishes, nor one told to run
    /// past its script's end: [`Episode::step`] goes on stepping it).
    pub fn finished(&self) -> bool {
        match &self.source {
            Source::Live => false,
            Source::Script(player) => {
                !self.run_past_end && player.finished() && self.world.pending().is_empty()
            }
        }
    }

    /// Runs one step: the source's commands for it (recorded with the step's number), the step, the
    /// assessment. Returns `None`, without stepping, once a script has played everything (unless told
    /// to run past its end).
    pub fn step(&mut self) -> Option<StepCounters> {
        match &mut self.source {
            Source::Live => {
                for c in self.pending.drain(..) {
                    self.world.push(c);
                }
                // The device's commands for this step go the same way (and are recorded below).
                if let Some(h) = &mut self.haptic {
                    match h.exchange(&self.world) {
                        Ok(commands) => commands.into_iter().for_each(|c| self.world.push(c)),
                        Err(e) => {
                            self.haptic_error = Some(format!("haptic device dropped: {e}; the mouse drives"));
                            self.haptic = None;
                        }
                    }
                }
            }
            Source::Script(player) => {
                player.feed(&mut self.world);
                if !self.run_past_end && player.finished() && self.world.pending().is_empty() {
                    return None;
                }
            }
        }
        if let Some(r) = &mut self.recorder {
            let step = self.world.step_count();
            for c in self.world.pending() {
                if let Err(e) = r.record(step, c) {
                    self.record_error = Some((r.path().display().to_string(), e.to_string()));
                    self.recorder = None;
                    break;
                }
                self.recorded += 1;
            }
        }
        let counters = self.world.step();
        if let Some(a) = &mut self.assessor {
            a.observe(&self.world);
        }
        Some(counters)
    }

    /// Runs the steps that `elapsed` real time calls for on the world's clock, stopping early when a
    /// script ends or (with a `budget`) when the steps have taken longer than it (the rest are dropped:
    /// the simulation falls behind real time instead of its caller freezing).
    pub fn advance(&mut self, elapsed: Duration, budget: Option<Duration>) -> Advance {
        let due = self.world.due_steps(elapsed);
        let t = Instant::now();
        let mut out = Advance::default();
        for _ in 0..due {
            if budget.is_some_and(|b| t.elapsed() > b) {
                out.dropped = true;
                break;
            }
            let Some(c) = self.step() else { break };
            out.step_us += c.total_us();
            out.steps += 1;
        }
        out
    }

    /// Refills a snapshot of the world in place.
    pub fn snapshot_into(&self, out: &mut Snapshot) {
        self.world.snapshot_into(out);
    }

    /// The episode's parts, when it is over.
    pub fn into_parts(self) -> (World, Option<Assessor>, Option<Recorder>) {
        (self.world, self.assessor, self.recorder)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scripted(actions: Vec<crate::scene::Action>) -> Episode {
        let scene = crate::scene::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/volume.ron"))
            .unwrap_or_else(|e| panic!("{e}"));
        let world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
        Episode::new(world, None, Source::Script(Player::new(actions)))
    }

    #[test]
    fn finished_agrees_with_step_past_the_end() {
        let actions = vec![crate::scene::Action::Wait(3)];
        // Without running past the end: finished once the script is played, and no step then.
        let mut e = scripted(actions.clone());
        assert!(!e.finished());
        while e.step().is_some() {}
        assert!(e.finished());
        assert!(e.step().is_none());
        // Running past the end: steps go on, so it is never finished.
        let mut e = scripted(actions);
        e.run_past_end(true);
        for _ in 0..10 {
            assert!(e.step().is_some());
            assert!(!e.finished(), "step {}", e.world().step_count());
        }
        // Told to stop running past it, it is finished at once.
        e.run_past_end(false);
        assert!(e.finished());
    }

    #[test]
    fn an_episode_can_move_to_another_thread() {
        fn send<T: Send>() {}
        send::<Episode>();
    }
}
