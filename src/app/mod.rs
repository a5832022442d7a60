//! The desktop trainer: two windows (the trainee's and the observers') from one winit event loop, one
//! GPU device and one scene renderer, a fixed-step simulation driven by the trainee's mouse and keys
//! (recorded) or by a recording (replayed), egui panels, screenshots and scene hot reload.
//!
//! The only module that imports winit. It may import `ui`, `render`, `simulation`, `scene`, `runner`,
//! `training` and `instrument`, and reaches the engine only through [`World`](crate::simulation::World)'s
//! public API and the snapshot.

mod events;
mod input;
mod session;
mod window;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec2;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::render::{Gpu, OrbitCamera, SceneRenderer, Style, render_to_image, save_png};
use crate::simulation::{Command, InstrumentKind};
use crate::ui::{Action, Frame, ObserverUi, TraineeUi};
use events::HandDrive;
use input::{CameraRig, Hand};
use session::Session;
pub use session::default_recording_path;
use window::ViewWindow;

/// Title of the trainee's window (scripts look for it).
pub const TRAINEE_TITLE: &str = "dissect — trainee";
/// Title of the observers' window.
pub const OBSERVER_TITLE: &str = "dissect — observer";
/// Printed once the first frame of every window has been presented.
pub const FIRST_FRAME_LINE: &str = "dissect: first frame drawn";

/// What the app fails with.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// The scene or recording cannot be read or built (the message names the file).
    #[error("{0}")]
    Scene(String),
    /// No window or event loop (no display?).
    #[error("cannot open a window: {0}")]
    Window(String),
    /// The GPU refused something.
    #[error("graphics: {0}")]
    Gpu(String),
}

/// Where the world's commands come from.
#[derive(Clone, Debug)]
pub enum Source {
    /// The trainee's mouse and keys, recorded.
    Live,
    /// A recording, played with input disabled.
    Replay(PathBuf),
    /// A script played like a recording (for demonstrations and screenshots).
    Demo(PathBuf),
}

/// How the app is opened.
#[derive(Clone, Debug)]
pub struct AppOptions {
    /// The scene file; `None` for the built-in scene (then no hot reload).
    pub scene: Option<PathBuf>,
    /// Both views side by side in one window.
    pub single_window: bool,
    /// Exit after this many frames (smoke tests).
    pub frames: Option<u64>,
    /// Where the recording goes (default: `recordings/<date>_<time>.ron`).
    pub record: Option<PathBuf>,
    /// Where screenshots go (default: `screenshots/`).
    pub screenshot_dir: Option<PathBuf>,
    /// Live, replay or demo.
    pub source: Source,
    /// The haptic device (`mouse`, `inverse3`).
    pub haptic: String,
    /// Educator mode: the material and simulation panels are shown in the trainee's window and work
    /// (without it a trainee cannot soften the tissue mid-assessment).
    pub educator: bool,
}

/// Opens the windows and runs until the trainee's window is closed (or `frames` have been drawn).
pub fn run(options: AppOptions) -> Result<(), AppError> {
    let session = match &options.source {
        Source::Live => {
            // The device (or the one line saying why there is none) before the first step.
            let (device, message) = crate::haptics::open(&options.haptic);
            if let Some(m) = &message {
                println!("dissect: {m}");
            }
            let mut session = Session::live_with(
                options.scene.as_deref(),
                options.record.clone().unwrap_or_else(default_recording_path),
                Some(crate::haptics::HapticLink::new(device)),
            )?;
            if let Some(m) = message {
                session.say(m);
            }
            session
        }
        Source::Replay(path) => Session::replay(path)?,
        Source::Demo(script) => Session::demo(options.scene.as_deref(), script)?,
    };
    // How the simulation thread is scheduled (`runner::priority`), in one line, once.
    eprintln!("dissect: {}", session.scheduling());
    let event_loop = EventLoop::new().map_err(|e| AppError::Window(e.to_string()))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App { options, session, state: None, error: None, finished: false };
    let result = event_loop.run_app(&mut app).map_err(|e| AppError::Window(e.to_string()));
    app.finish();
    match app.error {
        Some(e) => Err(e),
        None => result,
    }
}

struct State {
    gpu: Gpu,
    renderer: SceneRenderer,
    trainee: ViewWindow,
    observer: Option<ViewWindow>,
    trainee_ui: TraineeUi,
    observer_ui: ObserverUi,
    hand: Hand,
    modifiers: ModifiersState,
    last_frame: Instant,
    opened: Instant,
    frames: u64,
    announced: bool,
    replay_done: bool,
    /// In a replay, the trainee's view follows the trainee's camera as recorded.
    follow_camera: bool,
}

struct App {
    options: AppOptions,
    session: Session,
    state: Option<State>,
    error: Option<AppError>,
    finished: bool,
}

fn camera_rigs(session: &Session) -> (CameraRig, CameraRig) {
    (
        CameraRig::new(OrbitCamera::from_spec(&session.scene.trainee_camera())),
        CameraRig::new(OrbitCamera::from_spec(&session.scene.observer_camera())),
    )
}

impl App {
    fn finish(&mut self) {
        if !self.finished {
            self.finished = true;
            let seconds = self.state.as_ref().map(|s| s.opened.elapsed().as_secs_f64());
            let episode = self.session.finish();
            if let (Some(state), Some(seconds)) = (&self.state, seconds) {
                let steps = episode.map_or(self.session.world().step_count(), |e| e.world().step_count());
                let pace = self.session.published().pace;
                println!(
                    "dissect: {} frames in {seconds:.1} s ({:.1} fps), {steps} steps ({:.0} steps/s); \
                     simulation thread, last second: {:.0} steps/s, worst jitter {:.0} µs, p99 late {:.0} µs; \
                     whole run: p99 late {:.0} µs over {} steps",
                    state.frames,
                    state.frames as f64 / seconds.max(1e-9),
                    steps as f64 / seconds.max(1e-9),
                    pace.steps_per_second,
                    pace.worst_jitter_us,
                    pace.p99_late_us,
                    pace.total_p99_late_us,
                    pace.total_steps
                );
            }
        }
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<State, AppError> {
        let screen = event_loop.primary_monitor().map(|m| m.size()).unwrap_or(PhysicalSize::new(1280, 800));
        let (sw, sh) = (screen.width.max(800), screen.height.max(600));
        let single = self.options.single_window;
        let trainee_w = if single { sw } else { sw * 18 / 25 };
        let height = sh.saturating_sub(20).max(480);
        let create = |title: &str, w: u32, x: u32| -> Result<Arc<Window>, AppError> {
            let attributes = Window::default_attributes()
                .with_title(title)
                .with_inner_size(PhysicalSize::new(w, height))
                .with_position(PhysicalPosition::new(x as i32, 0));
            event_loop.create_window(attributes).map(Arc::new).map_err(|e| AppError::Window(e.to_string()))
        };
        let trainee_window =
            create(if single { "dissect — trainee and observer" } else { TRAINEE_TITLE }, trainee_w, 0)?;
        let observer_window =
            if single { None } else { Some(create(OBSERVER_TITLE, sw - trainee_w, trainee_w)?) };

        let instance = Gpu::instance_for_display(Box::new(event_loop.owned_display_handle()));
        let surface = instance
            .create_surface(trainee_window.clone())
            .map_err(|e| AppError::Gpu(format!("no surface: {e}")))?;
        let gpu = pollster::block_on(Gpu::request(instance, Some(&surface)))
            .map_err(|e| AppError::Gpu(e.to_string()))?;
        let format = window::pick_format(&surface, &gpu)?;
        // On a CPU rasteriser 4x MSAA costs about 3.5x a frame: draw windows single-sampled there.
        let samples = if gpu.is_software() { 1 } else { 4 };
        let mut renderer = SceneRenderer::with_samples(&gpu, format, Style::default(), samples);
        renderer.update(&gpu, self.session.snapshot()).map_err(|e| AppError::Gpu(e.to_string()))?;
        println!("dissect: {} on {} ({samples}x MSAA, {format:?})", self.session.scene.title, gpu.describe());

        let (trainee_rig, observer_rig) = camera_rigs(&self.session);
        let trainee = ViewWindow::new(
            trainee_window,
            surface,
            &gpu,
            &renderer,
            trainee_rig,
            single.then_some(observer_rig),
        )?;
        let observer = match observer_window {
            Some(w) => {
                let surface = gpu
                    .instance
                    .create_surface(w.clone())
                    .map_err(|e| AppError::Gpu(format!("no surface: {e}")))?;
                if !surface.get_capabilities(&gpu.adapter).formats.contains(&format) {
                    return Err(AppError::Gpu(format!("the observer window cannot show {format:?}")));
                }
                Some(ViewWindow::new(w, surface, &gpu, &renderer, observer_rig, None)?)
            }
            None => None,
        };
        let mut hand = Hand::default();
        (hand.tool.kind, hand.tool.depth) = self.session.start_tool();
        Ok(State {
            gpu,
            renderer,
            trainee,
            observer,
            trainee_ui: TraineeUi::default(),
            observer_ui: ObserverUi::default(),
            hand,
            modifiers: ModifiersState::empty(),
            last_frame: Instant::now(),
            opened: Instant::now(),
            frames: 0,
            announced: false,
            replay_done: false,
            follow_camera: true,
        })
    }

    /// One frame: input already gathered, hot reload, steps, both windows drawn, UI actions carried out.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<(), AppError> {
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        let session = &mut self.session;
        let now = Instant::now();
        let dt = now - state.last_frame;
        state.last_frame = now;

        if session.poll_reload() {
            let mut dropped = Vec::new();
            state.hand.release(true, &mut dropped);
            state.hand.tool.kind = session.start_tool().0;
        }
        // A held stroke follows the cursor every frame (also when only the camera or insert changed).
        if state.hand.busy() && session.input_enabled() {
            drive_hand(state, session, false);
        }
        session.advance(dt);
        state.renderer.update(&state.gpu, session.snapshot()).map_err(|e| AppError::Gpu(e.to_string()))?;
        // The trainee's camera: recorded as it moves in a live session; in a replay, the recorded one
        // is shown (unless the viewer turned that off).
        if session.input_enabled() {
            session.note_view(state.trainee.camera.camera.to_spec());
        } else if state.follow_camera
            && let Some(spec) = session.replay_view()
        {
            state.trainee.camera.camera = OrbitCamera::from_spec(&spec);
            state.trainee.camera.moved = true;
        }

        let mut actions = Vec::new();
        let assessment = session.assessment();
        let status = session.status();
        let frame = Frame {
            world: session.world(),
            scene: &session.scene,
            tool: &state.hand.tool,
            timing: &session.timing,
            assessment: assessment.as_ref(),
            behind: session.behind(),
            input_enabled: session.input_enabled(),
            status: &status,
            scene_error: session.scene_error.as_deref(),
            message: session.message(),
            advice: session.advice(),
            reload_pending: session.reload_pending,
            replay: session.replay_state(state.follow_camera),
            educator: self.options.educator,
        };
        let replaying = !frame.input_enabled;

        // The trainee's window (with the observer's view beside it in single-window mode).
        {
            let win = &mut state.trainee;
            let single = win.second_camera.is_some();
            let second = win.second_texture();
            // The instrument's tip on screen (points), for the stretch gauge beside it.
            let ppp = win.egui_ctx.pixels_per_point();
            let tip = glam::Vec3::from(session.world().instrument().tip);
            state.trainee_ui.gauge_at = win
                .camera
                .camera
                .project(tip, Vec2::new(win.rect[2], win.rect[3]))
                .filter(|(_, depth)| (0.0..=1.0).contains(depth))
                .map(|(px, _)| egui::pos2((win.rect[0] + px.x) / ppp, (win.rect[1] + px.y) / ppp));
            let raw = win.egui_state.take_egui_input(&win.window);
            let mut area = egui::Rect::NOTHING;
            let ui_state = &mut state.trainee_ui;
            let output = win.egui_ctx.clone().run_ui(raw, |ui| {
                area = ui_state.show(ui, &frame, single, &mut actions);
                let (left, right) = split(area, single);
                events::caption(ui, left, if replaying { "trainee · replay" } else { "trainee" });
                if let (Some(right), Some(id)) = (right, second) {
                    let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                    ui.painter().image(id, right, uv, egui::Color32::WHITE);
                    events::caption(ui, right, "observer");
                }
            });
            win.set_area(area);
            win.draw(&state.gpu, &state.renderer, output)?;
        }
        if let Some(win) = state.observer.as_mut() {
            let raw = win.egui_state.take_egui_input(&win.window);
            let mut area = egui::Rect::NOTHING;
            let ui_state = &mut state.observer_ui;
            let output = win.egui_ctx.clone().run_ui(raw, |ui| {
                area = ui_state.show(ui, &frame, &mut actions);
                events::caption(ui, area, "observer");
            });
            win.set_area(area);
            win.draw(&state.gpu, &state.renderer, output)?;
        }
        state.frames += 1;

        for action in actions {
            apply(state, session, &self.options, action);
        }
        if !state.announced
            && state.trainee.presented > 0
            && state.observer.as_ref().is_none_or(|w| w.presented > 0)
        {
            state.announced = true;
            println!("{FIRST_FRAME_LINE}");
        }
        if !state.replay_done && session.replay_finished() {
            state.replay_done = true;
            println!("dissect: replay finished at step {}", session.world().step_count());
        }
        if self.options.frames.is_some_and(|n| state.frames >= n) {
            event_loop.exit();
        }
        Ok(())
    }
}

/// The view area and, in single-window mode, its right half for the second view (points).
fn split(area: egui::Rect, single: bool) -> (egui::Rect, Option<egui::Rect>) {
    if !single {
        return (area, None);
    }
    let mid = area.center().x;
    (
        egui::Rect::from_min_max(area.min, egui::pos2(mid, area.max.y)),
        Some(egui::Rect::from_min_max(egui::pos2(mid, area.min.y), area.max)),
    )
}

/// Feeds the cursor to the hand: a press (`press`) or a drag/hover in the trainee's view.
fn drive_hand(state: &mut State, session: &mut Session, press: bool) {
    let camera = state.trainee.camera.camera;
    let pointer = state.trainee.pointer;
    // The tissue under the cursor, where the hand reads it (a pull or a push need not refresh the picker).
    let (ray, hit) = if press || state.hand.reads_tissue(session.world()) {
        session.refresh_picker();
        input::pick(&session.picker, session.snapshot(), &camera, &pointer)
    } else {
        (camera.ray(pointer.pos, pointer.size), None)
    };
    let mut out = Vec::new();
    if press {
        if let Some(hit) = state.hand.press(session.world(), &camera, ray, hit, &mut out) {
            session.grasp_at(hit);
        }
    } else {
        state.hand.drag(session.world(), ray, hit, &mut out);
    }
    for c in out {
        session.queue(c);
    }
}

fn queue_all(session: &mut Session, commands: Vec<Command>) {
    for c in commands {
        session.queue(c);
    }
}

/// Carries out what a panel or a key asked for.
fn apply(state: &mut State, session: &mut Session, options: &AppOptions, action: Action) {
    let live = session.input_enabled();
    let mut out = Vec::new();
    if live && events::hand_action(&mut state.hand, &state.trainee.camera.camera, &action, &mut out) {
        queue_all(session, out);
        return;
    }
    match action {
        // Tuning is for educators: a trainee cannot soften the tissue mid-assessment.
        Action::SetMaterial(id, m) if live && options.educator => session.set_material(id, m),
        Action::SetSweeps(n) if live && options.educator => session.set_sweeps(n),
        Action::Reload if live && session.request_reload() => {
            state.hand.release(true, &mut Vec::new());
            state.hand.tool.kind = session.start_tool().0;
        }
        Action::ConfirmReload if live && session.reload() => {
            state.hand.release(true, &mut Vec::new());
            state.hand.tool.kind = session.start_tool().0;
        }
        Action::KeepSession => session.keep_session(),
        Action::ReplayPause(p) => session.set_paused(p),
        Action::ReplaySeek(step) => session.seek(step),
        Action::ReplaySpeed(speed) => session.set_speed(speed),
        Action::ReplayFollowCamera(on) => {
            state.follow_camera = on;
            if !on {
                state.trainee.camera.reset();
            }
        }
        Action::Report => match session.write_report() {
            Some(summary) => {
                state.trainee_ui.report.summary = Some(summary);
                state.trainee_ui.report.open = true;
            }
            None if !session.has_goals() => session.say("this scene sets no goals: nothing to report"),
            None => {}
        },
        Action::Screenshot => screenshot(state, session, options),
        Action::ToggleHelp => {
            let open = !state.trainee_ui.help.open;
            state.trainee_ui.help.open = open;
            state.observer_ui.help.open = open;
        }
        Action::ToggleRegions => session.say(events::toggle_regions(&mut state.renderer)),
        Action::ResetCameras => {
            events::reset_cameras(&mut state.trainee);
            if let Some(w) = state.observer.as_mut() {
                w.camera.reset();
            }
        }
        _ => {}
    }
}

/// Saves every view as `<date>_<time>-trainee.png` / `...-observer.png` (never overwriting an earlier
/// one), rendered offscreen from each view's camera at its size.
fn screenshot(state: &mut State, session: &mut Session, options: &AppOptions) {
    let dir = options.screenshot_dir.clone().unwrap_or_else(|| PathBuf::from("screenshots"));
    if let Err(e) = std::fs::create_dir_all(&dir) {
        session.say(format!("cannot create {}: {e}", dir.display()));
        return;
    }
    let mut views = state.trainee.shots();
    if let Some(w) = &state.observer {
        views.extend(w.shots());
    }
    let mut saved = Vec::new();
    let stem = session::date_time_stem();
    let free = |n: u32| {
        let tag = if n <= 1 { stem.clone() } else { format!("{stem}-{n}") };
        ["trainee", "observer"].map(|name| dir.join(format!("{tag}-{name}.png")))
    };
    let mut n = 1;
    while free(n).iter().any(|p| p.exists()) {
        n += 1;
    }
    for ((camera, w, h), path) in views.into_iter().zip(free(n)) {
        let result = render_to_image(&state.gpu, session.snapshot(), &camera, w.max(16), h.max(16))
            .and_then(|image| save_png(&image, &path));
        match result {
            Ok(()) => saved.push(path.display().to_string()),
            Err(e) => {
                session.say(format!("screenshot failed: {e}"));
                return;
            }
        }
    }
    println!("dissect: saved {}", saved.join(", "));
    session.say(format!("saved {}", saved.join(", ")));
}

/// The action a key asks for, if any.
fn key_action(key: &Key, instruments: &[InstrumentKind]) -> Option<Action> {
    match key {
        Key::Named(NamedKey::F5) => Some(Action::Reload),
        Key::Named(NamedKey::F12) => Some(Action::Screenshot),
        Key::Character(s) if matches!(s.as_str(), "p" | "P") => Some(Action::Screenshot),
        _ => events::key_action(key, instruments),
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(state) => self.state = Some(state),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, id: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else { return };
        let session = &mut self.session;
        let is_trainee = state.trainee.window.id() == id;
        let win = if is_trainee {
            &mut state.trainee
        } else {
            match state.observer.as_mut() {
                Some(w) if w.window.id() == id => w,
                _ => return,
            }
        };
        let consumed = win.egui_state.on_window_event(&win.window, &event).consumed;
        let live = session.input_enabled();
        match event {
            WindowEvent::CloseRequested => {
                if is_trainee {
                    event_loop.exit();
                } else {
                    state.observer = None;
                }
            }
            WindowEvent::Resized(size) => {
                if let Err(e) = win.resize(&state.gpu, size.width, size.height) {
                    session.say(e.to_string());
                }
            }
            WindowEvent::ModifiersChanged(_)
            | WindowEvent::CursorMoved { .. }
            | WindowEvent::MouseInput { .. }
            | WindowEvent::MouseWheel { .. } => {
                let mut out = Vec::new();
                let (hand, modifiers) = (&mut state.hand, &mut state.modifiers);
                let drive = events::pointer_event(
                    win,
                    hand,
                    modifiers,
                    &event,
                    is_trainee && live,
                    consumed,
                    &mut out,
                );
                queue_all(session, out);
                match drive {
                    HandDrive::Follow => drive_hand(state, session, false),
                    HandDrive::Press => drive_hand(state, session, true),
                    HandDrive::Rest => {}
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if consumed || event.state != ElementState::Pressed {
                    return;
                }
                if event.logical_key == Key::Named(NamedKey::Space)
                    && let Some(r) = session.replay_state(state.follow_camera)
                {
                    session.set_paused(!r.paused);
                    return;
                }
                // In a replay, - and + (or =) step through the replay bar's speeds.
                if let Key::Character(c) = &event.logical_key
                    && let Some(r) = session.replay_state(state.follow_camera)
                    && let Some(speed) = crate::ui::next_replay_speed(r.speed, c.as_str())
                {
                    session.set_speed(speed);
                    return;
                }
                if event.logical_key == Key::Named(NamedKey::Escape) {
                    state.trainee_ui.help.open = false;
                    state.observer_ui.help.open = false;
                    state.trainee_ui.report.open = false;
                    return;
                }
                let action = match events::roll(&event.logical_key, state.hand.tool.roll_deg) {
                    Some(roll) => Some(roll),
                    None if event.repeat => None,
                    None => key_action(&event.logical_key, &session.scene.instruments),
                };
                if let Some(a) = action {
                    apply(state, session, &self.options, a);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.frame(event_loop) {
            eprintln!("dissect: {e}");
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tissue::CutDepth;

    #[test]
    fn keys_map_to_the_actions_the_help_lists() {
        let instruments = [InstrumentKind::Forceps, InstrumentKind::Scalpel, InstrumentKind::Probe];
        let key = |s: &str| Key::Character(s.into());
        assert_eq!(key_action(&key("2"), &instruments), Some(Action::Select(InstrumentKind::Scalpel)));
        assert_eq!(key_action(&key("3"), &instruments[..2]), None);
        assert_eq!(key_action(&key("b"), &instruments), Some(Action::SetDepth(CutDepth::Between)));
        assert_eq!(key_action(&key("?"), &instruments), Some(Action::ToggleHelp));
        assert_eq!(key_action(&Key::Named(NamedKey::F12), &instruments), Some(Action::Screenshot));
        assert_eq!(key_action(&Key::Named(NamedKey::F5), &instruments), Some(Action::Reload));
        assert_eq!(key_action(&key("G"), &instruments), Some(Action::ToggleRegions));
        assert_eq!(key_action(&key("p"), &instruments), Some(Action::Screenshot));
        // The keys the browser shares (G too): the desktop's own ones are not among them.
        assert_eq!(events::key_action(&key("g"), &instruments), Some(Action::ToggleRegions));
        assert_eq!(events::key_action(&key("p"), &instruments), None);
        assert_eq!(events::key_action(&key("r"), &instruments), Some(Action::Report));
        assert_eq!(events::roll(&key("]"), 170.0), Some(Action::SetRoll(-175.0)));
        assert_eq!(events::roll(&key("["), 0.0), Some(Action::SetRoll(-15.0)));
        assert_eq!(events::roll(&key("x"), 0.0), None);
    }

    #[test]
    fn a_single_window_splits_its_view_area_in_halves() {
        let area = egui::Rect::from_min_max(egui::pos2(100.0, 20.0), egui::pos2(900.0, 620.0));
        let (left, right) = split(area, true);
        assert_eq!(left.max.x, 500.0);
        assert_eq!(right.map(|r| r.min.x), Some(500.0));
        assert_eq!(split(area, false), (area, None));
    }
}
