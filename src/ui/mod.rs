//! The trainer's panels, drawn with egui: one type per panel, each implementing [`View`].
//!
//! Owns what the panels show and how; it reads the world only through a [`WorldView`] (a copy of its figures) and the
//! numbers the app hands in ([`Frame`]), and it changes nothing itself: every control returns an
//! [`Action`] that the app carries out (so that instrument commands are recorded and replayed). May
//! import egui and the simulation side's public types; never winit or wgpu.

mod assessment;
mod exercise;
mod force;
mod help;
mod instruments;
mod materials;
mod monitor;
mod report;
mod simulation;
mod timing;

pub use assessment::AssessmentPanel;
pub use exercise::{ExercisePanel, tool_hint, view_overlay};
pub use force::ForcePanel;
pub use help::{BINDINGS, HelpOverlay};
pub use instruments::{InstrumentBar, ToolState};
pub use materials::MaterialPanel;
pub use monitor::MonitorPanel;
pub use report::{ReportSummary, ReportWindow};
pub use simulation::SimulationPanel;
pub use timing::{FrameSample, ThreadPace, Timing};

use crate::chainmail::{Material, MaterialId};
use crate::scene::Scene;
use crate::simulation::{InstrumentKind, WorldView};
use crate::tissue::CutDepth;
use crate::training::{Advice, Assessment};

/// What a control asks the app to do.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Take another instrument.
    Select(InstrumentKind),
    /// Set the scalpel's depth.
    SetDepth(CutDepth),
    /// Set the roll about the instrument's axis, degrees.
    SetRoll(f32),
    /// Set the tilt of the instrument's axis away from vertical, degrees.
    SetTilt(f32),
    /// Set the insert depth (forceps: along the view direction; probe: into the surface), millimetres.
    SetInsert(f32),
    /// Replace a material of the tissue.
    SetMaterial(MaterialId, Material),
    /// Set the most relaxation sweeps per step.
    SetSweeps(u32),
    /// Reload the scene (from its file, or the built-in scene afresh).
    Reload,
    /// Write the session report and show it.
    Report,
    /// Save both views as PNG files.
    Screenshot,
    /// Show or hide the help overlay.
    ToggleHelp,
    /// Put the cameras back where the scene has them.
    ResetCameras,
    /// Show or hide the exercise's regions drawn on the tissue.
    ToggleRegions,
    /// The scene file changed: reload it and restart the session (the answer to the question).
    ConfirmReload,
    /// The scene file changed: keep the running session (the answer to the question).
    KeepSession,
    /// Replay: pause (true) or play on.
    ReplayPause(bool),
    /// Replay: go to this step (a step behind plays the recording again from the start, quickly).
    ReplaySeek(u64),
    /// Replay: play at this multiple of real time.
    ReplaySpeed(f32),
    /// Replay: show the trainee's view through the trainee's camera as recorded (true) or a free one.
    ReplayFollowCamera(bool),
}

/// Where a replay stands, for its control bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplayState {
    /// The step shown.
    pub step: u64,
    /// The recording's last step.
    pub last_step: u64,
    /// The simulation's rate, steps per second (to show times).
    pub rate_hz: f32,
    /// Paused.
    pub paused: bool,
    /// Playing at this multiple of real time.
    pub speed: f32,
    /// The step a seek is heading for, while the simulation thread runs up to it.
    pub seeking: Option<u64>,
    /// The recording has the trainee's camera.
    pub has_camera: bool,
    /// The trainee's view follows the recorded camera.
    pub follow_camera: bool,
}

/// Everything a panel may read in one frame.
pub struct Frame<'a> {
    /// The world as of the last step the windows were handed (a copy: the world itself may be
    /// stepping on its own thread).
    pub world: &'a WorldView,
    /// The scene running.
    pub scene: &'a Scene,
    /// The hand: instrument, depth, roll, tilt, insert.
    pub tool: &'a ToolState,
    /// Frame and step times.
    pub timing: &'a Timing,
    /// The live assessment, when the scene has goals.
    pub assessment: Option<&'a Assessment>,
    /// The simulation ran slower than real time in the last frame.
    pub behind: bool,
    /// Input may change the world (false while replaying).
    pub input_enabled: bool,
    /// One line about the session (recording path, replay progress).
    pub status: &'a str,
    /// The last scene error (a failed reload), shown until the next good load.
    pub scene_error: Option<&'a str>,
    /// A transient message (screenshot saved, material refused).
    pub message: Option<&'a str>,
    /// What stops the trainee now, if anything (held by fibres, stretch near the limit, a tear).
    pub advice: Option<&'a Advice>,
    /// The scene file changed while a session runs: the trainee is asked before it restarts.
    pub reload_pending: bool,
    /// The replay's position and controls, when replaying.
    pub replay: Option<ReplayState>,
    /// Educator mode: the material and simulation panels are shown and work.
    pub educator: bool,
}

/// A panel: draws itself into `ui` from `frame` and reports what the user asked for in `actions`.
pub trait View {
    /// Draws the panel.
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>);
}

/// The status strip at the top of a window: scene title, session status, warnings and errors.
pub fn status_bar(ui: &mut egui::Ui, frame: &Frame<'_>, role: &str) {
    ui.horizontal_wrapped(|ui| {
        ui.strong(format!("{} — {role}", frame.scene.title));
        ui.separator();
        ui.label(format!("step {}", frame.world.step_count()));
        ui.separator();
        ui.label(frame.status);
        if frame.behind {
            ui.separator();
            ui.colored_label(egui::Color32::from_rgb(255, 170, 60), "simulation slower than real time");
        }
    });
    if let Some(e) = frame.scene_error {
        ui.colored_label(egui::Color32::from_rgb(255, 110, 110), format!("scene not reloaded: {e}"));
    }
    if let Some(m) = frame.message {
        ui.colored_label(egui::Color32::from_rgb(150, 210, 255), m);
    }
}

/// The trainee window's panels: instrument bar on the left, the exercise and the figures on the right
/// (the material and simulation panels too in educator mode), status on top (and the replay's controls
/// at the bottom), the coach, the tool's hint and the stretch gauge over the view, help, report and the
/// reload question on demand.
#[derive(Default)]
pub struct TraineeUi {
    /// Instrument bar.
    pub instruments: InstrumentBar,
    /// Instructions, checklist, clock.
    pub exercise: ExercisePanel,
    /// Material sliders (educator mode).
    pub materials: MaterialPanel,
    /// Relaxation, reload, timing plot (educator mode).
    pub simulation: SimulationPanel,
    /// Live figures.
    pub assessment: AssessmentPanel,
    /// Force on the instrument in hand, live.
    pub force: ForcePanel,
    /// Step counters per phase (shown here only in single-window mode).
    pub monitor: MonitorPanel,
    /// Key bindings.
    pub help: HelpOverlay,
    /// The last report.
    pub report: ReportWindow,
    /// Where the instrument's tip is on screen (points), for the stretch gauge.
    pub gauge_at: Option<egui::Pos2>,
}

/// Width of the trainee window's side panel, points: fixed, so that its contents are laid out to it and
/// never spill past its edge.
const SIDE_WIDTH: f32 = 270.0;

impl TraineeUi {
    /// Draws the panels; returns the area left for the 3D view (points). With `with_monitor`, the
    /// monitor panel joins the right-hand column (one window showing both views).
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        frame: &Frame<'_>,
        with_monitor: bool,
        actions: &mut Vec<Action>,
    ) -> egui::Rect {
        egui::Panel::top("trainee-status").show(ui, |ui| status_bar(ui, frame, "trainee"));
        if let Some(r) = frame.replay {
            egui::Panel::bottom("replay-bar").show(ui, |ui| replay_bar(ui, r, actions));
        }
        egui::Panel::left("instrument-bar").resizable(false).exact_size(170.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.instruments.ui(ui, frame, actions));
        });
        egui::Panel::right("trainee-side").resizable(false).exact_size(SIDE_WIDTH).show(ui, |ui| {
            ui.spacing_mut().slider_width = 80.0;
            egui::ScrollArea::vertical().show(ui, |ui| {
                egui::CollapsingHeader::new("Exercise")
                    .default_open(true)
                    .show(ui, |ui| self.exercise.ui(ui, frame, actions));
                egui::CollapsingHeader::new("Assessment")
                    .default_open(true)
                    .show(ui, |ui| self.assessment.ui(ui, frame, actions));
                egui::CollapsingHeader::new("Force")
                    .default_open(!with_monitor)
                    .show(ui, |ui| self.force.ui(ui, frame, actions));
                if frame.educator {
                    egui::CollapsingHeader::new("Simulation")
                        .default_open(true)
                        .show(ui, |ui| self.simulation.ui(ui, frame, actions));
                    ui.collapsing("Materials", |ui| self.materials.ui(ui, frame, actions));
                }
                if with_monitor {
                    ui.collapsing("Monitor", |ui| self.monitor.ui(ui, frame, actions));
                }
            });
        });
        let rect = ui.available_rect_before_wrap();
        let view = if with_monitor {
            egui::Rect::from_min_max(rect.min, egui::pos2(rect.center().x, rect.max.y))
        } else {
            rect
        };
        view_overlay(ui, view, frame, self.gauge_at);
        self.help.ui(ui, frame, actions);
        self.report.ui(ui, frame, actions);
        if frame.reload_pending {
            reload_question(ui, actions);
        }
        rect
    }
}

/// Asks whether to restart the running session on the scene as it is now (its file changed, or F5).
fn reload_question(ui: &egui::Ui, actions: &mut Vec<Action>) {
    egui::Window::new("Reload the scene?")
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .show(ui.ctx(), |ui| {
            ui.label(
                "The scene changed on disk, or F5 was pressed. Reloading restarts the session: the tissue, \
                 the clock and the score start again, and a new recording begins.",
            );
            ui.horizontal(|ui| {
                if ui.button("Reload and restart").clicked() {
                    actions.push(Action::ConfirmReload);
                }
                if ui.button("Keep the session").clicked() {
                    actions.push(Action::KeepSession);
                }
            });
        });
}

/// Pause, seek and camera for a replay.
fn replay_bar(ui: &mut egui::Ui, r: ReplayState, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        if ui.button(if r.paused { "play (space)" } else { "pause (space)" }).clicked() {
            actions.push(Action::ReplayPause(!r.paused));
        }
        if r.has_camera {
            let mut follow = r.follow_camera;
            if ui.checkbox(&mut follow, "trainee's camera").changed() {
                actions.push(Action::ReplayFollowCamera(follow));
            }
        }
        ui.separator();
        for speed in REPLAY_SPEEDS {
            let label = if speed < 1.0 { format!("{speed}×") } else { format!("{speed:.0}×") };
            if ui.selectable_label(r.speed == speed, label).clicked() && r.speed != speed {
                actions.push(Action::ReplaySpeed(speed));
            }
        }
        ui.separator();
        let last = r.last_step.max(1);
        let rate = r.rate_hz.max(1.0);
        let mut step = r.step.min(last);
        let label = match r.seeking {
            // The thread runs the steps up to the target as fast as it goes; the bar shows how far.
            Some(target) => format!("going to {:.1} s… {:.1} s", target as f32 / rate, step as f32 / rate),
            None => format!("{:.1} s of {:.1} s", step as f32 / rate, last as f32 / rate),
        };
        ui.spacing_mut().slider_width = (ui.available_width() - 200.0).max(80.0);
        let slider = egui::Slider::new(&mut step, 0..=last).show_value(false).text(label);
        let response = ui.add(slider);
        if response.drag_stopped() || (response.changed() && !response.dragged()) {
            actions.push(Action::ReplaySeek(step));
        }
    });
}

/// The replay speeds offered, multiples of real time.
pub const REPLAY_SPEEDS: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// The replay speed a key gives from `speed`: `-` the next slower of [`REPLAY_SPEEDS`], `+` (or `=`, the
/// same key unshifted) the next faster; `None` for any other key or past either end.
pub fn next_replay_speed(speed: f32, key: &str) -> Option<f32> {
    match key {
        "-" => REPLAY_SPEEDS.iter().rev().copied().find(|&s| s < speed),
        "+" | "=" => REPLAY_SPEEDS.iter().copied().find(|&s| s > speed),
        _ => None,
    }
}

/// The observer window's panels: the monitor and the assessment on the right, status on top.
#[derive(Default)]
pub struct ObserverUi {
    /// Step counters per phase.
    pub monitor: MonitorPanel,
    /// Live figures.
    pub assessment: AssessmentPanel,
    /// Force on the instrument in hand, live.
    pub force: ForcePanel,
    /// Instructions, checklist, clock.
    pub exercise: ExercisePanel,
    /// Key bindings.
    pub help: HelpOverlay,
}

impl ObserverUi {
    /// Draws the panels; returns the area left for the 3D view (points).
    pub fn show(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) -> egui::Rect {
        egui::Panel::top("observer-status").show(ui, |ui| status_bar(ui, frame, "observer"));
        egui::Panel::bottom("observer-monitor").resizable(true).default_size(330.0).show(ui, |ui| {
            ui.columns(2, |cols| {
                // Columns lay out top-down *justified*, and egui then justifies wrapped text too (the
                // words spread over the whole line, the text looking stretched): left-aligned instead.
                let left = egui::Layout::top_down(egui::Align::Min);
                cols[0].with_layout(left, |ui| {
                    egui::ScrollArea::vertical().id_salt("monitor").show(ui, |ui| {
                        ui.heading("Monitor");
                        self.monitor.ui(ui, frame, actions);
                    });
                });
                cols[1].with_layout(left, |ui| {
                    egui::ScrollArea::vertical().id_salt("assessment").show(ui, |ui| {
                        ui.heading("Exercise");
                        self.exercise.ui(ui, frame, actions);
                        ui.heading("Force");
                        self.force.ui(ui, frame, actions);
                        ui.heading("Assessment");
                        self.assessment.ui(ui, frame, actions);
                    });
                });
            });
        });
        let rect = ui.available_rect_before_wrap();
        self.help.ui(ui, frame, actions);
        rect
    }
}

#[cfg(test)]
mod replay_speed_tests {
    use super::next_replay_speed;

    #[test]
    fn minus_and_plus_step_through_the_replay_speeds() {
        assert_eq!(next_replay_speed(1.0, "-"), Some(0.5));
        assert_eq!(next_replay_speed(1.0, "+"), Some(2.0));
        assert_eq!(next_replay_speed(2.0, "="), Some(4.0));
        assert_eq!(next_replay_speed(0.25, "-"), None);
        assert_eq!(next_replay_speed(4.0, "+"), None);
        assert_eq!(next_replay_speed(1.0, "x"), None);
    }
}
