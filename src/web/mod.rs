//! The trainer in a web browser (wasm32 only): one canvas with the trainee's view and the observers'
//! side by side (as `--single-window`), the instrument bar, panels, assessment and report; WebGPU where
//! the browser has it, WebGL2 otherwise (chosen at start, named in the status line); the engine
//! single-threaded, stepped in the frame loop.
//!
//! Scenes come from the page: the default is embedded, the bundled ones are in a menu, a file can be
//! picked or dropped (errors at `file:line:column`, as natively); `?scene=NAME&script=NAME` plays a
//! bundled script as `dissect run` does and writes its figures into `<pre id="result">`. The session's
//! recording and report download from the page.
//!
//! The window glue, the pure input logic and the window events both translate alike are the desktop
//! app's own files (`app/window.rs`, `app/input.rs`, `app/events.rs`), compiled here too; what the
//! events do to the page's session is this module's.

#[path = "../app/events.rs"]
mod events;
#[path = "../app/input.rs"]
mod input;
mod page;
mod session;
// (Screenshots to files are the desktop's: `shots` is unused here.)
#[allow(dead_code)]
#[path = "../app/window.rs"]
mod window;

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use web_time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::platform::web::{EventLoopExtWebSys, WindowAttributesExtWebSys};
use winit::window::{Window, WindowId};

use crate::render::{Gpu, OrbitCamera, SceneRenderer, Style};
use crate::simulation::Command;
use crate::ui::{Action, Frame, TraineeUi};
use events::HandDrive;
use input::{CameraRig, Hand};
use page::{Params, Request, Requests};
use session::{SCENES, SCRIPTS, Session, bundled};
use window::ViewWindow;

/// What the shared window code fails with (as the desktop app's error).
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// The GPU refused something.
    #[error("graphics: {0}")]
    Gpu(String),
}

/// Starts the trainer in the page's `<canvas id="dissect">`.
pub fn start() {
    std::panic::set_hook(Box::new(|info| page::show_error(&format!("dissect stopped: {info}"))));
    let params = Params::from_url();
    let requests: Requests = Rc::default();
    let (session, error) = first_session(&params);
    let current = params.scene.clone().unwrap_or_else(|| SCENES[0].0.into());
    page::wire(&SCENES.iter().map(|(n, _)| *n).collect::<Vec<_>>(), &current, &requests);
    let Some(session) = session else { return };
    if let Some(e) = &error {
        page::show_error(e);
    }
    let event_loop = match EventLoop::new() {
        Ok(l) => l,
        Err(e) => return page::show_error(&format!("cannot start: {e}")),
    };
    let app = WebApp {
        session,
        educator: params.educator,
        scene_error: error,
        requests,
        pending_gpu: Rc::default(),
        state: None,
        started: false,
        first_frame: false,
        result_written: false,
        last_stats: Instant::now(),
    };
    event_loop.spawn_app(app);
}

/// The session the URL asks for, and the error to show (a broken scene runs the default instead).
fn first_session(params: &Params) -> (Option<Session>, Option<String>) {
    let (source, label) = match (&params.source, &params.scene) {
        (Some(text), _) => (text.clone(), "scene.ron".to_string()),
        (None, Some(name)) => match bundled(SCENES, name) {
            Some(s) => (s.to_string(), format!("scenes/{name}.ron")),
            None => {
                let names: Vec<_> = SCENES.iter().map(|(n, _)| *n).collect();
                let e = format!("no bundled scene `{name}`: expected one of {}", names.join(", "));
                return fallback(e);
            }
        },
        (None, None) => {
            (crate::scene::DEFAULT_SCENE.to_string(), crate::scene::DEFAULT_SCENE_PATH.to_string())
        }
    };
    let mut session = match Session::new(&source, &label) {
        Ok(s) => s,
        Err(e) => return fallback(e),
    };
    if let Some(name) = &params.script {
        let played = match bundled(SCRIPTS, name) {
            Some(text) => session.play(text, name),
            None => Err(format!("no bundled script `{name}`")),
        };
        if let Err(e) = played {
            page::set_result(&format!("error: {e}"));
            return (Some(session), Some(e));
        }
    }
    (Some(session), None)
}

fn fallback(error: String) -> (Option<Session>, Option<String>) {
    match Session::new(crate::scene::DEFAULT_SCENE, crate::scene::DEFAULT_SCENE_PATH) {
        Ok(s) => (Some(s), Some(error)),
        Err(e) => {
            page::show_error(&format!("{error}\n{e}"));
            (None, Some(error))
        }
    }
}

type GpuSlot = Rc<RefCell<Option<Result<(Gpu, wgpu::Surface<'static>, Arc<Window>), String>>>>;

struct State {
    gpu: Gpu,
    renderer: SceneRenderer,
    win: ViewWindow,
    ui: TraineeUi,
    hand: Hand,
    modifiers: ModifiersState,
    backend: &'static str,
    last_frame: Instant,
}

struct WebApp {
    session: Session,
    /// Educator mode (`?educator`): the material and simulation panels.
    educator: bool,
    /// The last scene that failed to load (shown until a good one).
    scene_error: Option<String>,
    requests: Requests,
    pending_gpu: GpuSlot,
    state: Option<State>,
    started: bool,
    first_frame: bool,
    result_written: bool,
    last_stats: Instant,
}

fn rigs(session: &Session) -> (CameraRig, CameraRig) {
    (
        CameraRig::new(OrbitCamera::from_spec(&session.scene.trainee_camera())),
        CameraRig::new(OrbitCamera::from_spec(&session.scene.observer_camera())),
    )
}

impl WebApp {
    fn open(
        &mut self,
        gpu: Gpu,
        surface: wgpu::Surface<'static>,
        window: Arc<Window>,
    ) -> Result<State, AppError> {
        let format = window::pick_format(&surface, &gpu)?;
        let webgpu = gpu.adapter.get_info().backend == wgpu::Backend::BrowserWebGpu;
        let backend = if webgpu { "WebGPU" } else { "WebGL2" };
        // WebGL2 in a software rasteriser pays for every sample: single-sampled there.
        let samples = if webgpu { 4 } else { 1 };
        let mut renderer = SceneRenderer::with_samples(&gpu, format, Style::default(), samples);
        renderer.update(&gpu, &self.session.snapshot).map_err(|e| AppError::Gpu(e.to_string()))?;
        page::set_text("backend", &format!("{backend} · {}", gpu.describe()));
        let (trainee, observer) = rigs(&self.session);
        let win = ViewWindow::new(window, surface, &gpu, &renderer, trainee, Some(observer))?;
        let mut hand = Hand::default();
        hand.tool.kind = self.session.world().instrument().kind;
        hand.tool.depth = self.session.world().instrument().depth;
        Ok(State {
            gpu,
            renderer,
            win,
            ui: TraineeUi::default(),
            hand,
            modifiers: ModifiersState::empty(),
            backend,
            last_frame: Instant::now(),
        })
    }

    /// Runs a new session (from the menu or a file); on failure the running one stays and the error
    /// shows.
    fn switch(&mut self, source: &str, label: &str) {
        match Session::new(source, label) {
            Ok(s) => {
                self.session = s;
                self.scene_error = None;
                page::clear_error();
                if let Some(state) = self.state.as_mut() {
                    let (t, o) = rigs(&self.session);
                    state.win.camera = t;
                    state.win.second_camera = Some(o);
                    state.hand = Hand::default();
                    state.hand.tool.kind = self.session.world().instrument().kind;
                    state.hand.tool.depth = self.session.world().instrument().depth;
                }
            }
            Err(e) => {
                page::show_error(&e);
                self.scene_error = Some(e);
            }
        }
    }

    fn handle_requests(&mut self) {
        let requests: Vec<Request> = self.requests.borrow_mut().drain(..).collect();
        for r in requests {
            match r {
                Request::Bundled(name) => {
                    if let Some(s) = bundled(SCENES, &name) {
                        self.switch(s, &format!("scenes/{name}.ron"));
                    }
                }
                Request::File { name, text } => self.switch(&text, &name),
                Request::DownloadRecording => match self.session.recording_text() {
                    Ok(t) => self.downloaded(page::download("recording.ron", "text/plain", t.as_bytes())),
                    Err(e) => self.session.say(format!("recording not written: {e}")),
                },
                Request::DownloadReport => self.report(),
            }
        }
    }

    fn report(&mut self) {
        match self.session.report_text() {
            Some(Ok(t)) => self.downloaded(page::download("report.json", "application/json", t.as_bytes())),
            Some(Err(e)) => self.session.say(format!("report not written: {e}")),
            None => self.session.say("this scene sets no goals: nothing to report"),
        }
    }

    fn downloaded(&mut self, result: Result<(), String>) {
        if let Err(e) = result {
            self.session.say(e);
        }
    }

    fn frame(&mut self) -> Result<(), AppError> {
        self.handle_requests();
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        let session = &mut self.session;
        let now = Instant::now();
        let dt = now - state.last_frame;
        state.last_frame = now;
        if state.hand.busy() && session.input_enabled() {
            drive_hand(state, session, false);
        }
        session.advance(dt);
        state.renderer.update(&state.gpu, &session.snapshot).map_err(|e| AppError::Gpu(e.to_string()))?;

        let mut actions = Vec::new();
        let assessment = session.assessor().map(|a| a.assessment(session.world()));
        let advice = session.assessor().and_then(|a| a.advice(session.world()));
        let status = format!("{} · {}", state.backend, session.status());
        let frame = Frame {
            world: &session.view,
            scene: &session.scene,
            tool: &state.hand.tool,
            timing: &session.timing,
            assessment: assessment.as_ref(),
            behind: session.behind(),
            input_enabled: session.input_enabled(),
            status: &status,
            scene_error: self.scene_error.as_deref(),
            message: session.message(),
            advice: advice.as_ref(),
            reload_pending: false,
            replay: None,
            educator: self.educator,
        };
        let win = &mut state.win;
        let second = win.second_texture();
        let raw = win.egui_state.take_egui_input(&win.window);
        let mut area = egui::Rect::NOTHING;
        let ui_state = &mut state.ui;
        let replaying = !frame.input_enabled;
        let output = win.egui_ctx.clone().run_ui(raw, |ui| {
            area = ui_state.show(ui, &frame, true, &mut actions);
            let mid = area.center().x;
            let left = egui::Rect::from_min_max(area.min, egui::pos2(mid, area.max.y));
            let right = egui::Rect::from_min_max(egui::pos2(mid, area.min.y), area.max);
            events::caption(ui, left, if replaying { "trainee · script" } else { "trainee" });
            if let Some(id) = second {
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                ui.painter().image(id, right, uv, egui::Color32::WHITE);
                events::caption(ui, right, "observer");
            }
        });
        win.set_area(area);
        let presented = win.draw(&state.gpu, &state.renderer, output)?;
        for action in actions {
            self.apply(action);
        }
        if presented && !self.first_frame {
            self.first_frame = true;
            page::mark_first_frame(page::now_ms());
        }
        if presented && let Some(state) = &self.state {
            page::set_views(&[state.win.rect, state.win.second_rect]);
        }
        if !self.result_written && self.session.script_done() {
            self.result_written = true;
            let metrics = self.session.metrics_json().unwrap_or_default();
            page::set_result(&metrics);
        }
        if presented {
            let world = self.session.world();
            let d = world.tissue().damage();
            page::set_live(&format!(
                "{{\"instrument\":\"{:?}\",\"grasped\":{},\"moved\":{},\"links_cut\":{}}}",
                world.instrument().kind,
                world.instrument().grasped.is_some(),
                world.elements_moved_total(),
                d.layer_links_cut + d.connective_links_cut
            ));
        }
        if self.last_stats.elapsed().as_secs_f32() >= 1.0 {
            self.last_stats = Instant::now();
            let t = &self.session.timing;
            page::set_text(
                "stats",
                &format!(
                    "{:.0} fps · {:.0} steps/s (scene rate {} Hz) · step {}",
                    t.fps(),
                    t.steps_per_second(),
                    self.session.scene.simulation.rate_hz,
                    self.session.world().step_count()
                ),
            );
        }
        Ok(())
    }

    fn apply(&mut self, action: Action) {
        let Some(state) = self.state.as_mut() else { return };
        let session = &mut self.session;
        let live = session.input_enabled();
        let mut out = Vec::new();
        if live && events::hand_action(&mut state.hand, &state.win.camera.camera, &action, &mut out) {
            for c in out {
                session.queue(c);
            }
            return;
        }
        match action {
            Action::SetMaterial(id, m) if live && self.educator => match m.validate() {
                Ok(()) => session.queue(Command::SetMaterial(id, m)),
                Err(e) => session.say(format!("material refused: {e}")),
            },
            Action::SetSweeps(n) if live && self.educator => session.queue(Command::SetRelaxSweeps(n)),
            Action::Reload if live => {
                let (source, label) = (session.source.clone(), session.label.clone());
                self.switch(&source, &label);
            }
            Action::Report => self.report(),
            Action::Screenshot => session.say("in the browser: use the browser's own screenshot"),
            Action::ToggleHelp => state.ui.help.open = !state.ui.help.open,
            Action::ToggleRegions => session.say(events::toggle_regions(&mut state.renderer)),
            Action::ResetCameras => events::reset_cameras(&mut state.win),
            _ => {}
        }
    }
}

fn drive_hand(state: &mut State, session: &mut Session, press: bool) {
    let camera = state.win.camera.camera;
    let pointer = state.win.pointer;
    // The tissue under the cursor, where the hand reads it (a pull or a push need not refresh the picker).
    let (ray, hit) = if press || state.hand.reads_tissue(&session.view) {
        session.refresh_picker();
        input::pick(&session.picker, &session.snapshot, &camera, &pointer)
    } else {
        (camera.ray(pointer.pos, pointer.size), None)
    };
    let mut out = Vec::new();
    if press {
        // The browser steps its world in the frame loop: the grasp is resolved here at once.
        if let Some(hit) = state.hand.press(&session.view, &camera, ray, hit, &mut out)
            && let Some(e) = session.world().element_at(&hit)
        {
            session.queue(Command::GraspElement(e));
        }
    } else {
        state.hand.drag(&session.view, ray, hit, &mut out);
    }
    for c in out {
        session.queue(c);
    }
}

impl ApplicationHandler for WebApp {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.started {
            return;
        }
        self.started = true;
        let canvas = web_sys::window()
            .and_then(|w| w.document())
            .and_then(|d| d.get_element_by_id("dissect"))
            .and_then(|e| wasm_bindgen::JsCast::dyn_into::<web_sys::HtmlCanvasElement>(e).ok());
        let attributes = Window::default_attributes()
            .with_title("dissect — trainee and observer")
            .with_canvas(canvas)
            .with_append(false)
            .with_prevent_default(true)
            .with_focusable(true);
        let window = match event_loop.create_window(attributes) {
            Ok(w) => Arc::new(w),
            Err(e) => return page::show_error(&format!("cannot open the canvas: {e}")),
        };
        let slot = self.pending_gpu.clone();
        wasm_bindgen_futures::spawn_local(async move {
            // WebGPU if the browser offers an adapter, WebGL2 otherwise.
            let instance = wgpu::util::new_instance_with_webgpu_detection(
                wgpu::InstanceDescriptor::new_without_display_handle(),
            )
            .await;
            let result = match instance.create_surface(window.clone()) {
                Ok(surface) => match Gpu::request(instance, Some(&surface)).await {
                    Ok(gpu) => Ok((gpu, surface, window.clone())),
                    Err(e) => Err(format!("no graphics adapter (neither WebGPU nor WebGL2): {e}")),
                },
                Err(e) => Err(format!("cannot draw into the canvas: {e}")),
            };
            *slot.borrow_mut() = Some(result);
            window.request_redraw();
        });
    }

    fn window_event(&mut self, _event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.state.is_none() {
            let ready = self.pending_gpu.borrow_mut().take();
            match ready {
                Some(Ok((gpu, surface, window))) => {
                    match self.open(gpu, surface, window.clone()) {
                        Ok(s) => self.state = Some(s),
                        Err(e) => return page::show_error(&e.to_string()),
                    }
                    window.request_redraw();
                }
                Some(Err(e)) => return page::show_error(&e),
                None => return,
            }
        }
        let Some(state) = self.state.as_mut() else { return };
        let session = &mut self.session;
        let win = &mut state.win;
        let consumed = win.egui_state.on_window_event(&win.window, &event).consumed;
        let live = session.input_enabled();
        match event {
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame() {
                    page::show_error(&e.to_string());
                }
                if let Some(s) = &self.state {
                    s.win.window.request_redraw();
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
                let drive = events::pointer_event(win, hand, modifiers, &event, live, consumed, &mut out);
                for c in out {
                    session.queue(c);
                }
                match drive {
                    HandDrive::Follow => drive_hand(state, session, false),
                    HandDrive::Press => drive_hand(state, session, true),
                    HandDrive::Rest => {}
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if consumed || event.state != ElementState::Pressed || event.repeat {
                    return;
                }
                if event.logical_key == Key::Named(NamedKey::Escape) {
                    state.ui.help.open = false;
                    state.ui.report.open = false;
                    return;
                }
                let action = events::roll(&event.logical_key, state.hand.tool.roll_deg)
                    .or_else(|| events::key_action(&event.logical_key, &session.scene.instruments));
                if let Some(a) = action {
                    self.apply(a);
                }
            }
            _ => {}
        }
    }
}
