//! The force panel: the force the tissue exerts on the instrument in hand, in newtons, as a live plot
//! of the last seconds against the goal's force limit, with the session's force figures.

use std::collections::VecDeque;

use super::{Action, Frame, View};
use crate::simulation::Forces;

/// Seconds of history the plot shows.
const WINDOW_S: f32 = 5.0;

/// The force panel.
#[derive(Default)]
pub struct ForcePanel {
    /// `(seconds of simulation, newtons)`, oldest first.
    samples: VecDeque<(f32, f32)>,
    last_step: u64,
}

impl View for ForcePanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, _actions: &mut Vec<Action>) {
        let world = frame.world;
        let forces = world.forces();
        let mut f = forces.in_hand();
        if Forces::magnitude(f) == 0.0 {
            f = forces.forceps;
        }
        let now = Forces::magnitude(f);
        let step = world.step_count();
        let t = step as f32 / world.config().rate_hz as f32;
        if step < self.last_step {
            self.samples.clear(); // a reload restarted the world
        }
        if step != self.last_step {
            self.samples.push_back((t, now));
            self.last_step = step;
        }
        while self.samples.front().is_some_and(|&(s, _)| s < t - WINDOW_S) {
            self.samples.pop_front();
        }
        let limit = frame.scene.goals.as_ref().map(|g| g.force_limit);
        ui.label(format!(
            "{:?}: {now:.2} N{}",
            forces.in_hand,
            limit.map(|l| format!(" (limit {l:.2} N)")).unwrap_or_default()
        ));
        // The plot: force over the last seconds, the limit as a dashed line.
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width().min(260.0), 70.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, egui::Color32::from_gray(24));
        let top = self.samples.iter().map(|&(_, f)| f).fold(limit.unwrap_or(0.1) * 1.25, f32::max).max(1e-3);
        let to_screen = |s: f32, f: f32| {
            egui::pos2(
                rect.left() + rect.width() * (1.0 - (t - s) / WINDOW_S),
                rect.bottom() - rect.height() * (f / top).clamp(0.0, 1.0),
            )
        };
        if let Some(l) = limit {
            let y = to_screen(t, l).y;
            painter.add(egui::Shape::dashed_line(
                &[egui::pos2(rect.left(), y), egui::pos2(rect.right(), y)],
                egui::Stroke::new(1.0, egui::Color32::from_rgb(255, 140, 100)),
                4.0,
                3.0,
            ));
        }
        let points: Vec<egui::Pos2> = self.samples.iter().map(|&(s, f)| to_screen(s, f)).collect();
        painter
            .add(egui::Shape::line(points, egui::Stroke::new(1.5, egui::Color32::from_rgb(120, 200, 255))));
        painter.text(
            rect.left_top() + egui::vec2(4.0, 2.0),
            egui::Align2::LEFT_TOP,
            format!("{top:.2} N"),
            egui::FontId::proportional(10.0),
            egui::Color32::GRAY,
        );
        if let Some(a) = frame.assessment {
            let s = &a.force;
            let warn = s.total.time_above_limit_s > 0.0;
            let text = format!(
                "peak {:.2} N · mean {:.2} N · above limit {:.2} s · bandwidth {:.1} Hz · forbidden {:.0} N/m",
                s.total.peak_n,
                s.total.mean_n,
                s.total.time_above_limit_s,
                s.total.bandwidth_hz,
                s.forbidden_peak_n_per_m
            );
            if warn {
                ui.colored_label(egui::Color32::from_rgb(255, 140, 100), text);
            } else {
                ui.label(text);
            }
        }
    }
}
