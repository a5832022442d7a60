//! Window events both front ends translate alike, the desktop's windows and the browser's canvas
//! (`web` compiles this file too, as it does `input.rs` and `window.rs`): the cursor and the buttons
//! on a window's views, the wheel's zoom, the keys both offer, the views' captions, and the actions
//! both carry out alike (the hand's, the regions shown or hidden, the cameras reset). What follows
//! for the session (reload, report, replay, tuning) stays with each front end.

use glam::Vec2;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{Key, ModifiersState, NamedKey};

use super::input::{self, Hand};
use super::window::ViewWindow;
use crate::render::{OrbitCamera, SceneRenderer};
use crate::simulation::{Command, InstrumentKind};
use crate::tissue::CutDepth;
use crate::ui::Action;

/// What a pointer event asks of the trainee's hand once [`pointer_event`] has followed it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HandDrive {
    /// Nothing.
    Rest,
    /// The instrument follows the cursor (a stroke, or hovering).
    Follow,
    /// The left button went down in the trainee's view: grasp, start a cut or a push.
    Press,
}

/// The modifier keys, the cursor, the buttons and the wheel on a window, alike in both front ends:
/// the views' cameras and pointers follow them (see [`cursor_moved`], [`button`], [`zoom`]); the left
/// button's release lets go of the tissue (`ctrl` keeps forceps clamped; the commands go to `out`)
/// and the wheel moves a held instrument. `live`: the window shows the trainee's view and the session
/// takes input (else only the cameras move); `consumed`: the panels took the event. Other events are
/// left alone.
pub(crate) fn pointer_event(
    win: &mut ViewWindow,
    hand: &mut Hand,
    modifiers: &mut ModifiersState,
    event: &WindowEvent,
    live: bool,
    consumed: bool,
    out: &mut Vec<Command>,
) -> HandDrive {
    match event {
        WindowEvent::ModifiersChanged(m) => *modifiers = m.state(),
        WindowEvent::CursorMoved { position, .. } => {
            let cursor = Vec2::new(position.x as f32, position.y as f32);
            let camera_drag = cursor_moved(win, cursor, modifiers.shift_key());
            if live && !camera_drag && (hand.busy() || win.view_at(cursor) == Some(0)) && !consumed {
                return HandDrive::Follow;
            }
        }
        WindowEvent::MouseInput { state, button: b, .. } => {
            let pressed = *state == ElementState::Pressed;
            if button(win, *b, pressed, consumed) && *b == MouseButton::Left && live {
                if pressed && win.drag_view == 0 {
                    return HandDrive::Press;
                } else if !pressed {
                    hand.release(modifiers.control_key(), out);
                }
            }
        }
        WindowEvent::MouseWheel { delta, .. } if !consumed => {
            let notches = notches(*delta);
            if !(live && hand.busy() && hand.wheel(notches)) {
                zoom(win, notches);
            }
        }
        _ => {}
    }
    HandDrive::Rest
}

/// The cursor moved to `cursor` (window pixels): both views' pointers follow it, and a right or
/// middle drag turns or pans the camera of the view it started in (`shift` pans). Returns whether
/// such a camera drag is on (the hand then leaves the cursor alone).
pub(crate) fn cursor_moved(win: &mut ViewWindow, cursor: Vec2, shift: bool) -> bool {
    let delta = cursor - win.cursor;
    win.cursor = cursor;
    win.pointer.pos = cursor - Vec2::new(win.rect[0], win.rect[1]);
    win.second_pointer.pos = cursor - Vec2::new(win.second_rect[0], win.second_rect[1]);
    let (pointer, rig) = if win.drag_view == 1 {
        (win.second_pointer, win.second_camera.as_mut())
    } else {
        (win.pointer, Some(&mut win.camera))
    };
    let camera_drag = pointer.right || pointer.middle;
    if let Some(rig) = rig.filter(|_| camera_drag) {
        input::drag_camera(rig, &pointer, shift, delta);
    }
    camera_drag
}

/// A mouse button went down or up: a press outside the views, or one the panels took (`consumed`),
/// is ignored (returns false); otherwise the pointer of the view the drag started in records it.
pub(crate) fn button(win: &mut ViewWindow, button: MouseButton, pressed: bool, consumed: bool) -> bool {
    if pressed {
        if consumed {
            return false;
        }
        let Some(view) = win.view_at(win.cursor) else { return false };
        win.drag_view = view;
    }
    let pointer = if win.drag_view == 1 { &mut win.second_pointer } else { &mut win.pointer };
    match button {
        MouseButton::Left => pointer.left = pressed,
        MouseButton::Right => pointer.right = pressed,
        MouseButton::Middle => pointer.middle = pressed,
        _ => {}
    }
    true
}

/// Wheel notches of a scroll (a pixel scroll counts 40 pixels a notch).
pub(crate) fn notches(delta: MouseScrollDelta) -> f32 {
    match delta {
        MouseScrollDelta::LineDelta(_, y) => y,
        MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
    }
}

/// Zooms the camera of the view under the cursor by `notches`.
pub(crate) fn zoom(win: &mut ViewWindow, notches: f32) {
    match win.view_at(win.cursor) {
        Some(1) => {
            if let Some(rig) = win.second_camera.as_mut() {
                input::zoom_camera(rig, notches);
            }
        }
        Some(_) => input::zoom_camera(&mut win.camera, notches),
        None => {}
    }
}

/// The roll `[` and `]` ask for from `roll_deg`, degrees in `[-180, 180)`.
pub(crate) fn roll(key: &Key, roll_deg: f32) -> Option<Action> {
    let d = match key {
        Key::Character(s) if s == "[" => -15.0,
        Key::Character(s) if s == "]" => 15.0,
        _ => return None,
    };
    Some(Action::SetRoll((roll_deg + d + 180.0).rem_euclid(360.0) - 180.0))
}

/// The keys both front ends offer: help, cameras, the report, the regions, the cutting depth, the
/// instruments.
pub(crate) fn key_action(key: &Key, instruments: &[InstrumentKind]) -> Option<Action> {
    match key {
        Key::Named(NamedKey::F1) => Some(Action::ToggleHelp),
        Key::Named(NamedKey::Home) => Some(Action::ResetCameras),
        Key::Character(s) => match s.as_str() {
            "?" => Some(Action::ToggleHelp),
            "r" | "R" => Some(Action::Report),
            "g" | "G" => Some(Action::ToggleRegions),
            "u" | "U" => Some(Action::SetDepth(CutDepth::Upper)),
            "b" | "B" => Some(Action::SetDepth(CutDepth::Between)),
            "l" | "L" => Some(Action::SetDepth(CutDepth::Lower)),
            "1" | "2" | "3" => {
                let i = s.parse::<usize>().ok()?.checked_sub(1)?;
                instruments.get(i).copied().map(Action::Select)
            }
            _ => None,
        },
        _ => None,
    }
}

/// Carries out what `action` asks of the hand, as both front ends do while the session takes input:
/// the instrument, the scalpel's depth, the roll, the tilt (relative to `camera`, the trainee's) and
/// the insertion; the commands it makes are appended to `out`. Returns false for any other action.
pub(crate) fn hand_action(
    hand: &mut Hand,
    camera: &OrbitCamera,
    action: &Action,
    out: &mut Vec<Command>,
) -> bool {
    match action {
        Action::Select(kind) => hand.select(*kind, out),
        Action::SetDepth(d) => hand.set_depth(*d, out),
        Action::SetRoll(deg) => {
            hand.tool.roll_deg = *deg;
            out.push(Command::Roll(deg.to_radians()));
        }
        Action::SetTilt(deg) => {
            hand.tool.tilt_deg = *deg;
            out.push(Command::SetAxis(hand.axis(camera)));
        }
        Action::SetInsert(mm) => hand.tool.insert_mm = *mm,
        _ => return false,
    }
    true
}

/// Shows or hides the exercise's regions and planned incision (G); returns what to tell the trainee.
pub(crate) fn toggle_regions(renderer: &mut SceneRenderer) -> &'static str {
    let mut style = *renderer.style();
    style.show_regions = !style.show_regions;
    renderer.set_style(style);
    if style.show_regions { "regions shown (G hides them)" } else { "regions hidden (G shows them)" }
}

/// Puts the window's cameras (both views of a single window) back where the scene sets them (Home).
pub(crate) fn reset_cameras(win: &mut ViewWindow) {
    win.camera.reset();
    if let Some(c) = win.second_camera.as_mut() {
        c.reset();
    }
}

/// A view's caption in its top-left corner.
pub(crate) fn caption(ui: &egui::Ui, rect: egui::Rect, text: &str) {
    if rect.is_positive() {
        ui.painter().text(
            rect.min + egui::vec2(8.0, 6.0),
            egui::Align2::LEFT_TOP,
            text,
            egui::FontId::proportional(14.0),
            egui::Color32::from_white_alpha(170),
        );
    }
}
