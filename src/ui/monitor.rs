//! The monitor: what the last step did, phase by phase ([`PHASES`]), for the observers.

use super::{Action, Frame, View};
use crate::simulation::PHASES;

/// The step-counter panel.
#[derive(Default)]
pub struct MonitorPanel;

impl View for MonitorPanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, _actions: &mut Vec<Action>) {
        let c = frame.world.last_step();
        let t = frame.timing;
        ui.label(format!(
            "step {} · {:.0} fps · {:.0} steps/s{}",
            c.step,
            t.fps(),
            t.steps_per_second(),
            if frame.behind { " · behind" } else { "" }
        ));
        if let Some(p) = t.pace() {
            ui.label(format!(
                "simulation thread, {}{}: {:.0} steps/s · worst jitter {:.0} µs · p99 late {:.0} µs · input lag {} steps",
                p.priority,
                // Granted, but given up for now (a seek, or steps too long for their period).
                if p.how_to_grant.is_none() && !p.realtime { ", off for now" } else { "" },
                p.steps_per_second,
                p.worst_jitter_us,
                p.p99_late_us,
                p.input_lag_steps
            ));
            if let Some(how) = p.how_to_grant {
                // The how-to is long for this narrow panel: on hover (the log has it in full).
                ui.small("steps may start milliseconds late while the windows draw (hover: how to grant real-time)")
                    .on_hover_ui(|ui| {
                        // Narrow enough to stay inside the observer's window.
                        ui.set_max_width(260.0);
                        ui.label(how);
                    });
            }
        }
        let total = c.total_us().max(f32::MIN_POSITIVE);
        egui::Grid::new("phases").striped(true).num_columns(3).show(ui, |ui| {
            ui.strong("phase");
            ui.strong("µs");
            ui.strong("share");
            ui.end_row();
            for (name, us) in PHASES.iter().zip(c.phase_us) {
                ui.label(*name);
                ui.label(format!("{us:.1}"));
                ui.add(egui::ProgressBar::new(us / total).desired_width(70.0));
                ui.end_row();
            }
            ui.strong("total");
            ui.strong(format!("{:.1}", c.total_us()));
            ui.end_row();
        });
        egui::Grid::new("counters").num_columns(2).show(ui, |ui| {
            let rows: [(&str, String); 8] = [
                ("moved (chain)", c.moved_chain.to_string()),
                ("moved (normal)", c.moved_normal.to_string()),
                ("relax sweeps", c.relax_sweeps.to_string()),
                ("contact fixes", c.contact_fixes.to_string()),
                ("links cut", c.links_cut.to_string()),
                ("links torn", c.links_torn.to_string()),
                ("grasp allowed", format!("{:.0} %", 100.0 * c.grasp_fraction)),
                ("moved in total", frame.world.elements_moved_total().to_string()),
            ];
            for (k, v) in rows {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            }
        });
        let d = frame.world.damage();
        ui.label(format!(
            "damage: {} layer links cut, {} fibres cut, {} torn",
            d.layer_links_cut, d.connective_links_cut, d.links_torn
        ));
    }
}
