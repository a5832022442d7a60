//! Material sliders that act live: each layer's material and the connective fibres'.

use super::{Action, Frame, View};
use crate::chainmail::{Limits, Material, MaterialId};

/// The material sliders. The values shown are read from the world every frame, so what is displayed
/// is what the engine uses (a refused change springs back).
#[derive(Default)]
pub struct MaterialPanel;

/// The tissue's materials with a name each: the layers' (outer first) and the connective fibres'.
pub fn named_materials(frame: &Frame<'_>) -> Vec<(String, MaterialId)> {
    let mut out: Vec<(String, MaterialId)> = frame.world.layers().to_vec();
    for k in 0..frame.world.materials().len() {
        let id = MaterialId(k as u16);
        if !out.iter().any(|(_, m)| *m == id) {
            out.push(("connective".to_string(), id));
        }
    }
    out
}

fn slider(ui: &mut egui::Ui, label: &str, value: &mut f32, range: std::ops::RangeInclusive<f32>) -> bool {
    ui.add(egui::Slider::new(value, range).text(label).max_decimals(3)).changed()
}

impl View for MaterialPanel {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) {
        ui.label("Limits relative to rest length: stretch ≤ max, compress ≥ min, shear ≤ max.");
        ui.add_enabled_ui(frame.input_enabled, |ui| {
            for (name, id) in named_materials(frame) {
                let Some(current) = frame.world.material(id).copied() else { continue };
                let mut m: Material = current;
                ui.label(egui::RichText::new(name).strong());
                let mut changed = false;
                match &mut m.limits {
                    Limits::Relative { max_stretch, min_compress, max_shear } => {
                        changed |= slider(ui, "stretch ≤", max_stretch, 1.0..=3.0);
                        changed |= slider(ui, "compress ≥", min_compress, 0.1..=1.0);
                        changed |= slider(ui, "shear ≤", max_shear, 0.0..=1.5);
                    }
                    Limits::Absolute { min_dist, max_dist, max_shear } => {
                        changed |= slider(ui, "dist ≥ (m)", min_dist, 0.0..=0.01);
                        changed |= slider(ui, "dist ≤ (m)", max_dist, 0.0..=0.02);
                        changed |= slider(ui, "shear ≤ (m)", max_shear, 0.0..=0.01);
                    }
                }
                changed |= slider(ui, "stiffness", &mut m.stiffness, 0.05..=5.0);
                if changed && m != current {
                    actions.push(Action::SetMaterial(id, m));
                }
                ui.add_space(4.0);
            }
        });
    }
}
