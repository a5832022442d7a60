//! Live figures from the training assessment: completion, damage, stretch, time, motion, score.

use super::{Action, Frame, View};

/// The assessment panel.
#[derive(Default)]
pub struct AssessmentPanel;

impl View for AssessmentPanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) {
        let Some(a) = frame.assessment else {
            ui.label("This scene sets no goals, so there is no score. Add `goals: (target: ...)` to the scene to assess the exercise.");
            ui.label(format!("Peak stretch now: {:.2}", frame.world.max_stretch()));
            return;
        };
        let limit = frame.scene.goals.as_ref().map(|g| g.stretch_limit).unwrap_or(f32::INFINITY);
        ui.add(
            egui::ProgressBar::new(a.completion).text(format!("completion {:.0} %", 100.0 * a.completion)),
        );
        egui::Grid::new("assessment").num_columns(2).striped(true).show(ui, |ui| {
            let warn = egui::Color32::from_rgb(255, 140, 100);
            let mut row = |k: &str, v: String, bad: bool| {
                ui.label(k);
                if bad {
                    ui.colored_label(warn, v);
                } else {
                    ui.label(v);
                }
                ui.end_row();
            };
            if let Some(i) = a.incision {
                row("incision cut", format!("{:.0} %", 100.0 * i), false);
            }
            let target = format!("{:.0} % of {:.0} mm²", 100.0 * a.fibres, 1e6 * a.target_m2);
            row("target fibres cut", target, false);
            row("separation", format!("{:.1} mm", tenths(1000.0 * a.separation_m)), false);
            let fibres_out = format!("{:.1} mm²", 1e6 * a.connective_cut_outside_m2);
            row("fibres cut outside", fibres_out, a.connective_cut_outside > 0);
            let elsewhere = if a.incision.is_some() { "layers cut off the line" } else { "layers cut" };
            row(elsewhere, a.amount(a.layer_cut, 0.0), a.layer_links_cut > 0);
            let forbidden = a.amount(a.forbidden_layer, a.forbidden_connective_m2);
            row("forbidden broken", forbidden, a.forbidden_links_broken > 0);
            row("torn", a.amount(a.layer_torn, a.connective_torn_m2), a.links_torn > 0);
            row("peak stretch", format!("{:.2} (limit {limit:.2})", a.peak_stretch), a.peak_stretch > limit);
            row("time above limit", format!("{:.2} s", a.time_above_limit_s), a.time_above_limit_s > 0.0);
            row("elapsed", format!("{:.1} s", a.elapsed_s), a.over_time);
            row("path length", format!("{:.0} mm", 1000.0 * a.path_length_m), false);
            row("grasps", a.grasps.to_string(), false);
        });
        let pass = frame.scene.goals.as_ref().map(|g| g.pass).unwrap_or_default();
        ui.horizontal(|ui| {
            ui.label(egui::RichText::new(format!("score {:.1}", a.score)).heading());
            let (text, colour) = if a.passed {
                ("pass", egui::Color32::from_rgb(120, 220, 120))
            } else {
                ("not passed yet", egui::Color32::from_rgb(255, 170, 60))
            };
            ui.colored_label(colour, text);
        });
        ui.label(format!(
            "to pass: score {:.0}, completion {:.0} %, nothing broken in a forbidden region",
            pass.score,
            100.0 * pass.completion
        ));
        ui.label(egui::RichText::new("To improve").strong());
        for f in &a.feedback {
            ui.label(format!("• {f}"));
        }
        for item in &a.breakdown {
            ui.label(format!("  {:+.1}  {}", item.points, item.label));
        }
        if frame.input_enabled && ui.button("Report (R)").clicked() {
            actions.push(Action::Report);
        }
    }
}

/// `x` rounded to a tenth, a negative zero made positive: a separation a few micrometres under rest
/// reads "0.0 mm", not "-0.0 mm" (the advice beside it says "0.0 mm apart").
fn tenths(x: f32) -> f32 {
    (10.0 * x).round() / 10.0 + 0.0
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_separation_just_under_rest_reads_zero() {
        assert_eq!(format!("{:.1}", super::tenths(-0.004)), "0.0");
        assert_eq!(format!("{:.1}", super::tenths(-0.06)), "-0.1");
        assert_eq!(format!("{:.1}", super::tenths(1.26)), "1.3");
    }
}
