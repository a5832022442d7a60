//! The instrument bar: which instrument is in hand, the scalpel's depth, roll, tilt and insert depth.

use super::{Action, Frame, View};
use crate::simulation::InstrumentKind;
use crate::tissue::CutDepth;

/// The hand: what the trainee holds and how. The app owns it and changes it when it carries out an
/// [`Action`]; the bar only displays it.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolState {
    /// The instrument in hand.
    pub kind: InstrumentKind,
    /// The scalpel's depth.
    pub depth: CutDepth,
    /// Roll about the instrument's axis, degrees.
    pub roll_deg: f32,
    /// Tilt of the axis away from vertical, towards the viewer, degrees.
    pub tilt_deg: f32,
    /// Forceps: how far the grasp point is moved along the view direction; probe: how deep it pushes
    /// past the surface. Millimetres.
    pub insert_mm: f32,
}

impl Default for ToolState {
    fn default() -> Self {
        Self {
            kind: InstrumentKind::Forceps,
            depth: CutDepth::Between,
            roll_deg: 0.0,
            tilt_deg: 20.0,
            insert_mm: 0.0,
        }
    }
}

/// Name shown for an instrument.
pub fn instrument_name(kind: InstrumentKind) -> &'static str {
    match kind {
        InstrumentKind::Forceps => "Forceps",
        InstrumentKind::Scalpel => "Scalpel",
        InstrumentKind::Probe => "Probe",
    }
}

/// The instrument bar.
#[derive(Default)]
pub struct InstrumentBar;

impl View for InstrumentBar {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) {
        let tool = frame.tool;
        ui.heading("Instruments");
        ui.add_enabled_ui(frame.input_enabled, |ui| {
            for (i, &kind) in frame.scene.instruments.iter().enumerate() {
                let label = format!("{}  {}", i + 1, instrument_name(kind));
                if ui.selectable_label(tool.kind == kind, label).clicked() && tool.kind != kind {
                    actions.push(Action::Select(kind));
                }
            }
            ui.separator();
            let inst = frame.world.instrument();
            let state = match (inst.kind, inst.grasped.is_some(), inst.cutting) {
                (InstrumentKind::Forceps, true, _) => "holding tissue",
                (InstrumentKind::Forceps, false, _) if inst.grasped.is_some() => "holding",
                (InstrumentKind::Scalpel, _, true) => "cutting",
                // (The force panel's figure: the probe feels the tissue only while it presses it.)
                (InstrumentKind::Probe, _, _) if frame.world.forces().probe != [0.0; 3] => "pressing",
                (_, true, _) => "forceps clamped",
                _ => "free",
            };
            ui.label(format!("{}: {state}", instrument_name(inst.kind)));
            if frame.world.last_step().grasp_fraction < 0.999 && inst.grasped.is_some() {
                ui.colored_label(egui::Color32::from_rgb(255, 170, 60), "tissue resists");
            }

            ui.separator();
            ui.label("Scalpel depth");
            for (depth, name, key) in [
                (CutDepth::Upper, "Upper layer", "U"),
                (CutDepth::Between, "Between", "B"),
                (CutDepth::Lower, "Lower layer", "L"),
            ] {
                if ui.radio(tool.depth == depth, format!("{key}  {name}")).clicked() && tool.depth != depth {
                    actions.push(Action::SetDepth(depth));
                }
            }

            ui.separator();
            let mut roll = tool.roll_deg;
            ui.label("Roll (°)  [ ]");
            if ui.add(egui::Slider::new(&mut roll, -180.0..=180.0).step_by(1.0)).changed() {
                actions.push(Action::SetRoll(roll));
            }
            let mut tilt = tool.tilt_deg;
            ui.label("Tilt (°)");
            if ui.add(egui::Slider::new(&mut tilt, 0.0..=70.0).step_by(1.0)).changed() {
                actions.push(Action::SetTilt(tilt));
            }
            let mut insert = tool.insert_mm;
            ui.label("Insert (mm)  wheel");
            if ui.add(egui::Slider::new(&mut insert, -20.0..=20.0).step_by(0.1)).changed() {
                actions.push(Action::SetInsert(insert));
            }
        });
        ui.separator();
        if ui.button("Help (F1)").clicked() {
            actions.push(Action::ToggleHelp);
        }
        if ui.button("Screenshot (F12)").clicked() {
            actions.push(Action::Screenshot);
        }
        if ui.button("Reset cameras (Home)").clicked() {
            actions.push(Action::ResetCameras);
        }
    }
}
