//! The help overlay: every key and mouse binding, toggled with F1 or `?`.

use super::{Action, Frame, View};

/// The bindings, as `(keys, what they do)`; the app implements exactly these.
pub const BINDINGS: &[(&str, &str)] = &[
    ("1 / 2 / 3", "forceps / scalpel / probe (the scene's instrument order)"),
    ("left drag", "use the instrument: grasp and pull / cut / push"),
    ("wheel + left held", "forceps: move along the view (up: towards you); probe: push (down: deeper)"),
    ("Ctrl + release left", "forceps stay clamped on the tissue (take another instrument, come back with 1)"),
    ("U / B / L", "scalpel depth: upper layer / between layers / lower layer"),
    ("[ / ]", "roll the instrument by 15°"),
    ("right drag", "orbit the camera"),
    ("middle drag, shift + right drag", "pan the camera"),
    ("wheel", "zoom (when no instrument is held down)"),
    ("Home", "reset the cameras"),
    ("G", "show or hide the target and forbidden regions and the planned incision on the tissue"),
    ("F5", "reload the scene (asks first once the session has started)"),
    ("Space", "replay: pause / play"),
    ("- / +", "replay: slower / faster (0.25× to 4×)"),
    ("F12 / P", "save both views as PNG"),
    ("R", "write the session report"),
    ("F1 / ?", "this help"),
    ("Esc", "close help and report"),
];

/// The overlay listing [`BINDINGS`].
#[derive(Default)]
pub struct HelpOverlay {
    /// Whether it is shown.
    pub open: bool,
}

impl View for HelpOverlay {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &Frame<'_>, actions: &mut Vec<Action>) {
        if !self.open {
            return;
        }
        let mut open = true;
        egui::Window::new("Help — keys and mouse")
            .open(&mut open)
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ui.ctx(), |ui| {
                if !frame.scene.instructions.is_empty() {
                    ui.label(egui::RichText::new(&frame.scene.instructions).italics());
                    ui.separator();
                }
                egui::Grid::new("bindings").striped(true).show(ui, |ui| {
                    for (keys, what) in BINDINGS {
                        ui.strong(*keys);
                        ui.label(*what);
                        ui.end_row();
                    }
                });
                if !frame.input_enabled {
                    ui.separator();
                    ui.label("Replaying: instruments follow the recording; the cameras still move.");
                }
            });
        if !open {
            actions.push(Action::ToggleHelp);
        }
    }
}
