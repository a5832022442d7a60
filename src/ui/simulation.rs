//! The simulation panel: relaxation sweeps per step, scene reload, and a plot of frame time and
//! simulation time per frame over the last seconds.

use super::timing::WINDOW_S;
use super::{Action, Frame, View};

/// The simulation panel.
#[derive(Default)]
pub struct SimulationPanel;

const FRAME_COLOR: egui::Color32 = egui::Color32::from_rgb(120, 200, 255);
const SIM_COLOR: egui::Color32 = egui::Color32::from_rgb(255, 180, 90);

/// Draws frame time and simulation time per frame (milliseconds) over the last six seconds.
pub fn time_plot(ui: &mut egui::Ui, frame: &Frame<'_>) {
    let samples = frame.timing.samples();
    let width = ui.available_width().max(120.0);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 90.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_gray(18));
    let Some(last) = samples.back() else { return };
    let top = samples.iter().map(|s| s.frame_ms.max(s.sim_ms)).fold(20.0f32, f32::max).min(250.0);
    let x = |t: f64| rect.right() - ((last.t - t) / WINDOW_S) as f32 * rect.width();
    let y = |v: f32| rect.bottom() - (v / top).clamp(0.0, 1.0) * rect.height();
    // Reference lines at 16.7 ms (60 fps) and 33.3 ms (30 fps).
    let crowded = y(1000.0 / 60.0) - y(1000.0 / 30.0) < 12.0;
    for (ms, label) in [(1000.0 / 60.0, "60 fps"), (1000.0 / 30.0, "30 fps")] {
        if ms < top && !(crowded && ms < 20.0) {
            painter.hline(rect.x_range(), y(ms), egui::Stroke::new(1.0, egui::Color32::from_gray(60)));
            painter.text(
                egui::pos2(rect.left() + 2.0, y(ms)),
                egui::Align2::LEFT_BOTTOM,
                label,
                egui::FontId::proportional(10.0),
                egui::Color32::from_gray(120),
            );
        }
    }
    for (color, value) in [
        (FRAME_COLOR, (|s: &super::FrameSample| s.frame_ms) as fn(&super::FrameSample) -> f32),
        (SIM_COLOR, |s| s.sim_ms),
    ] {
        let points: Vec<egui::Pos2> = samples.iter().map(|s| egui::pos2(x(s.t), y(value(s)))).collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.5, color)));
    }
    painter.text(
        rect.right_top() + egui::vec2(-2.0, 2.0),
        egui::Align2::RIGHT_TOP,
        format!("{top:.0} ms"),
        egui::FontId::proportional(10.0),
        egui::Color32::from_gray(140),
    );
}

impl View for SimulationPanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) {
        let t = frame.timing;
        ui.label(format!(
            "{:.0} fps · {:.0} steps/s (target {:.0}) · step {:.0} µs",
            t.fps(),
            t.steps_per_second(),
            frame.world.config().rate_hz,
            t.mean_step_us()
        ));
        if let Some(p) = t.pace() {
            ui.label(format!("own thread · worst jitter {:.0} µs", p.worst_jitter_us));
        }
        if frame.behind {
            ui.colored_label(egui::Color32::from_rgb(255, 170, 60), "slower than real time");
        }
        time_plot(ui, frame);
        ui.horizontal(|ui| {
            ui.colored_label(FRAME_COLOR, "— frame");
            ui.colored_label(SIM_COLOR, "— simulation per frame");
        });
        ui.add_enabled_ui(frame.input_enabled, |ui| {
            let mut sweeps = frame.world.config().relax.max_sweeps;
            // A short slider text: the side panel is narrow, and a row wider than it would be clipped.
            ui.label("relaxation sweeps per step");
            if ui.add(egui::Slider::new(&mut sweeps, 0..=64).text("sweeps")).changed() {
                actions.push(Action::SetSweeps(sweeps));
            }
            if let Some(budget) = frame.world.config().relax.max_time {
                ui.label(format!("relaxation budget {} µs per step", budget.as_micros()));
            }
            if ui.button("Reload scene (F5)").clicked() {
                actions.push(Action::Reload);
            }
        });
    }
}
