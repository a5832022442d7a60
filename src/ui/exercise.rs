//! The exercise as the trainee sees it: the instructions, the steps as a checklist ticked as they are
//! done, the clock (from the first instrument action) and the pass mark; and, over the view, the coach's
//! sentence about what stops the trainee, a hint for the instrument in hand and a stretch gauge beside
//! the instrument.

use super::{Action, Frame, View};
use crate::simulation::InstrumentKind;
use crate::tissue::CutDepth;
use crate::training::AdviceLevel;

/// The exercise panel.
#[derive(Default)]
pub struct ExercisePanel;

impl View for ExercisePanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, _actions: &mut Vec<Action>) {
        if !frame.scene.instructions.is_empty() {
            ui.add(egui::Label::new(&frame.scene.instructions).wrap());
        }
        let Some(goals) = &frame.scene.goals else { return };
        let done = frame.assessment.map(|a| a.steps_done.as_slice()).unwrap_or(&[]);
        if !goals.steps.is_empty() {
            ui.add_space(4.0);
            for (k, step) in goals.steps.iter().enumerate() {
                let ticked = done.get(k).copied().unwrap_or(false);
                let next = !ticked && done.iter().take(k).all(|d| *d);
                let mark = if ticked {
                    "[x]"
                } else if next {
                    "[ ] >"
                } else {
                    "[ ]"
                };
                let rich = egui::RichText::new(format!("{mark} {}. {}", k + 1, step.text));
                let rich = if ticked {
                    rich.color(egui::Color32::from_rgb(130, 210, 130))
                } else if next {
                    rich.strong()
                } else {
                    rich.weak()
                };
                ui.add(egui::Label::new(rich).wrap());
            }
        }
        ui.add_space(4.0);
        let line = match frame.assessment {
            Some(a) if a.started => {
                let limit = goals.time_limit_s.map(|t| format!(" of {t:.0} s")).unwrap_or_default();
                format!("time {:.1} s{limit}", a.elapsed_s)
            }
            _ => "the clock starts at your first grasp, cut or push".to_string(),
        };
        ui.label(line);
    }
}

/// A one-line hint for the instrument in hand.
pub fn tool_hint(frame: &Frame<'_>) -> String {
    let inst = frame.world.instrument();
    match frame.tool.kind {
        InstrumentKind::Forceps if inst.grasped.is_some() => "forceps holding: drag to pull · wheel with the button held: along the view · hold Ctrl as you let go to keep them clamped".into(),
        InstrumentKind::Forceps => {
            "forceps: press on the tissue to grasp, drag to pull · hold Ctrl as you let go to keep them clamped"
                .into()
        }
        InstrumentKind::Scalpel => {
            let depth = match frame.tool.depth {
                CutDepth::Upper => "U, through the upper layer",
                CutDepth::Between => "B, the fibres between the layers",
                CutDepth::Lower => "L, through the lower layer",
            };
            format!("scalpel: drag to cut · depth {depth} (U / B / L to change)")
        }
        InstrumentKind::Probe => "probe: drag on the tissue to push it · wheel with the button held: deeper".into(),
    }
}

/// Draws the coach's advice and the tool hint along the bottom of the view `rect`, and the stretch
/// gauge beside the instrument at `gauge_at` (points), when it is in the view.
pub fn view_overlay(ui: &egui::Ui, rect: egui::Rect, frame: &Frame<'_>, gauge_at: Option<egui::Pos2>) {
    if !rect.is_positive() {
        return;
    }
    let painter = ui.painter_at(rect);
    let mut y = rect.bottom() - 10.0;
    let wrap = (rect.width() - 24.0).max(40.0);
    if frame.input_enabled {
        let galley = painter.layout(
            tool_hint(frame),
            egui::FontId::proportional(13.0),
            egui::Color32::from_gray(230),
            wrap,
        );
        let at = egui::pos2(rect.center().x - galley.size().x / 2.0, y - galley.size().y);
        painter.rect_filled(
            egui::Rect::from_min_size(at, galley.size()).expand(4.0),
            4.0,
            egui::Color32::from_black_alpha(150),
        );
        y = at.y - 12.0;
        painter.galley(at, galley, egui::Color32::WHITE);
    }
    if let Some(advice) = frame.advice {
        let colour = match advice.level {
            AdviceLevel::Info => egui::Color32::from_rgb(150, 210, 255),
            AdviceLevel::Warn => egui::Color32::from_rgb(255, 190, 80),
            AdviceLevel::Alarm => egui::Color32::from_rgb(255, 110, 100),
        };
        let galley = painter.layout(advice.text.clone(), egui::FontId::proportional(16.0), colour, wrap);
        let at = egui::pos2(rect.center().x - galley.size().x / 2.0, y - galley.size().y);
        painter.rect_filled(
            egui::Rect::from_min_size(at, galley.size()).expand(6.0),
            5.0,
            egui::Color32::from_black_alpha(190),
        );
        painter.galley(at, galley, colour);
    }
    // The stretch gauge: a short bar beside the instrument, filled to the stretch now against the limit
    // (the white tick), green, orange from 90 % of the way, red over it.
    let Some(p) = gauge_at.filter(|p| rect.shrink(40.0).contains(*p)) else { return };
    let limit = frame.scene.goals.as_ref().map_or(1.6, |g| g.stretch_limit);
    let stretch = frame.world.max_stretch();
    let share = ((stretch - 1.0) / (limit - 1.0).max(1e-3)).clamp(0.0, 1.2);
    let bar = egui::Rect::from_min_size(p + egui::vec2(24.0, -56.0), egui::vec2(10.0, 60.0));
    painter.rect_filled(bar.expand(2.0), 2.0, egui::Color32::from_black_alpha(170));
    let fill = bar.height() * share / 1.2;
    let colour = if share > 1.0 {
        egui::Color32::from_rgb(255, 90, 80)
    } else if share >= 0.9 {
        egui::Color32::from_rgb(255, 180, 60)
    } else {
        egui::Color32::from_rgb(120, 210, 120)
    };
    painter.rect_filled(
        egui::Rect::from_min_max(egui::pos2(bar.left(), bar.bottom() - fill), bar.max),
        1.0,
        colour,
    );
    let limit_y = bar.bottom() - bar.height() / 1.2;
    painter.hline(bar.x_range().expand(3.0), limit_y, egui::Stroke::new(1.5, egui::Color32::WHITE));
    let text = format!("stretch {stretch:.2}\nlimit {limit:.2}");
    let galley =
        painter.layout_no_wrap(text, egui::FontId::proportional(12.0), egui::Color32::from_gray(240));
    let at = egui::pos2(bar.right() + 6.0, bar.center().y - galley.size().y / 2.0);
    painter.rect_filled(
        egui::Rect::from_min_size(at, galley.size()).expand(3.0),
        3.0,
        egui::Color32::from_black_alpha(150),
    );
    painter.galley(at, galley, egui::Color32::from_gray(240));
}
