//! The report window: the summary of the session report just written, and where it went.

use std::path::PathBuf;

use super::{Action, Frame, View};
use crate::training::Assessment;

/// A written report.
#[derive(Clone, Debug)]
pub struct ReportSummary {
    /// The assessment at the time of writing.
    pub assessment: Assessment,
    /// Where `report.json` went.
    pub json: PathBuf,
    /// Where the plot went.
    pub png: PathBuf,
}

/// The window showing the last report.
#[derive(Default)]
pub struct ReportWindow {
    /// The report shown, if any.
    pub summary: Option<ReportSummary>,
    /// Whether the window is open.
    pub open: bool,
}

impl View for ReportWindow {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &Frame<'_>, _actions: &mut Vec<Action>) {
        let Some(s) = &self.summary else { return };
        if !self.open {
            return;
        }
        let mut open = self.open;
        egui::Window::new("Session report").open(&mut open).resizable(false).show(ui.ctx(), |ui| {
            let a = &s.assessment;
            let verdict = if a.passed { "passed" } else { "not passed" };
            ui.label(egui::RichText::new(format!("score {:.1} · {verdict}", a.score)).heading());
            for f in &a.feedback {
                ui.label(format!("• {f}"));
            }
            ui.label(format!(
                "completion {:.0} % · peak stretch {:.2} · {:.1} s · path {:.0} mm · {} grasps",
                100.0 * a.completion,
                a.peak_stretch,
                a.elapsed_s,
                1000.0 * a.path_length_m,
                a.grasps
            ));
            for item in &a.breakdown {
                ui.label(format!("{:+.1}  {}", item.points, item.label));
            }
            ui.separator();
            ui.label(format!("written to {}", s.json.display()));
            ui.label(format!("plot in {}", s.png.display()));
        });
        self.open = open;
    }
}
