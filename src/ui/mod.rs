//! The trainer's panels, drawn with egui: one type per panel, each implementing [`View`].
//!
//! Owns what the panels show and how; it reads the world only through a [`WorldView`] (a copy of its figures) and the
//! numbers the app hands in ([`Frame`]), and it changes nothing itself: every control returns an
//! [`Action`] that the app carries out (so that instrument commands are recorded and replayed). May
//! import egui and the simulation side's public types; never winit or wgpu.

mod assessment;
mod force;
mod help;
mod instruments;
mod materials;
mod monitor;
mod report;
mod simulation;
mod timing;

pub use assessment::AssessmentPanel;
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
use crate::training::Assessment;

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

/// The trainee window's panels: instrument bar on the left, tuning and figures on the right, status on
/// top, help and report on demand.
#[derive(Default)]
pub struct TraineeUi {
    /// Instrument bar.
    pub instruments: InstrumentBar,
    /// Material sliders.
    pub materials: MaterialPanel,
    /// Relaxation, reload, timing plot.
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
}

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
        egui::Panel::left("instrument-bar").resizable(false).exact_size(170.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.instruments.ui(ui, frame, actions));
        });
        egui::Panel::right("trainee-side").resizable(true).default_size(250.0).max_size(290.0).show(
            ui,
            |ui| {
                ui.spacing_mut().slider_width = 90.0;
                egui::ScrollArea::vertical().show(ui, |ui| {
                    egui::CollapsingHeader::new("Assessment")
                        .default_open(true)
                        .show(ui, |ui| self.assessment.ui(ui, frame, actions));
                    egui::CollapsingHeader::new("Force")
                        .default_open(true)
                        .show(ui, |ui| self.force.ui(ui, frame, actions));
                    egui::CollapsingHeader::new("Simulation")
                        .default_open(true)
                        .show(ui, |ui| self.simulation.ui(ui, frame, actions));
                    ui.collapsing("Materials", |ui| self.materials.ui(ui, frame, actions));
                    if with_monitor {
                        ui.collapsing("Monitor", |ui| self.monitor.ui(ui, frame, actions));
                    }
                });
            },
        );
        let rect = ui.available_rect_before_wrap();
        self.help.ui(ui, frame, actions);
        self.report.ui(ui, frame, actions);
        rect
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
    /// Key bindings.
    pub help: HelpOverlay,
}

impl ObserverUi {
    /// Draws the panels; returns the area left for the 3D view (points).
    pub fn show(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) -> egui::Rect {
        egui::Panel::top("observer-status").show(ui, |ui| status_bar(ui, frame, "observer"));
        egui::Panel::bottom("observer-monitor").resizable(true).default_size(330.0).show(ui, |ui| {
            ui.columns(2, |cols| {
                egui::ScrollArea::vertical().id_salt("monitor").show(&mut cols[0], |ui| {
                    ui.heading("Monitor");
                    self.monitor.ui(ui, frame, actions);
                });
                egui::ScrollArea::vertical().id_salt("assessment").show(&mut cols[1], |ui| {
                    ui.heading("Force");
                    self.force.ui(ui, frame, actions);
                    ui.heading("Assessment");
                    self.assessment.ui(ui, frame, actions);
                });
            });
        });
        let rect = ui.available_rect_before_wrap();
        self.help.ui(ui, frame, actions);
        rect
    }
}
