//! Guards the window path of the renderer: an instance made with the event loop's display handle, a
//! surface, `Gpu::request` with that surface, a non-sRGB surface format (as egui wants: the shader then
//! encodes sRGB itself), frames presented. Needs an X server, so it is ignored by default:
//! `xvfb-run -a -s "-screen 0 1280x800x24" cargo test --test render_window -- --ignored`.
//! It also saves a screenshot of the X root window to `target/render-test/window.png` (ImageMagick).

use std::sync::Arc;

use dissect::render::{Gpu, OrbitCamera, SceneRenderer, Style, demo};
use dissect::simulation::CameraSpec;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::platform::x11::EventLoopBuilderExtX11;
use winit::window::{Window, WindowId};

#[derive(Default)]
struct App {
    frames: u32,
    result: Option<Result<String, String>>,
}

impl App {
    fn run(&mut self, event_loop: &ActiveEventLoop) -> Result<String, String> {
        let window: Arc<Window> = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes().with_inner_size(PhysicalSize::new(640u32, 400u32)),
                )
                .map_err(|e| e.to_string())?,
        );
        let instance = Gpu::instance_for_display(Box::new(event_loop.owned_display_handle()));
        let surface = instance.create_surface(window.clone()).map_err(|e| e.to_string())?;
        let gpu = pollster::block_on(Gpu::request(instance, Some(&surface))).map_err(|e| e.to_string())?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps.formats.iter().copied().find(|f| !f.is_srgb()).unwrap_or(caps.formats[0]);
        let mut config =
            surface.get_default_config(&gpu.adapter, size.width, size.height).ok_or("surface unsupported")?;
        config.format = format;
        surface.configure(&gpu.device, &config);

        let mut renderer = SceneRenderer::new(&gpu, format, Style::default());
        renderer.update(&gpu, &demo::two_layers(32, 32, 2)).map_err(|e| e.to_string())?;
        let view = renderer.create_view(&gpu, config.width, config.height).map_err(|e| e.to_string())?;
        let camera = OrbitCamera::from_spec(&CameraSpec {
            eye: [0.0, 0.078, 0.078],
            target: [0.0; 3],
            fov_y_deg: 45.0,
        });
        for _ in 0..3 {
            let frame = match surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
                other => return Err(format!("no surface texture: {other:?}")),
            };
            let target = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            renderer.render(&gpu, &mut encoder, &view, &target, &camera);
            gpu.queue.submit([encoder.finish()]);
            gpu.queue.present(frame);
            self.frames += 1;
        }
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
        std::thread::sleep(std::time::Duration::from_millis(300));
        let shot = concat!(env!("CARGO_MANIFEST_DIR"), "/target/render-test/window.png");
        let _ = std::fs::create_dir_all(concat!(env!("CARGO_MANIFEST_DIR"), "/target/render-test"));
        let _ = std::process::Command::new("import").args(["-window", "root", shot]).status();
        Ok(format!("{} on {format:?}, {} samples", gpu.describe(), renderer.sample_count()))
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.result.is_none() {
            self.result = Some(self.run(event_loop));
        }
        event_loop.exit();
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, _: WindowEvent) {}
}

#[test]
#[ignore = "needs an X server: run under xvfb-run with --ignored"]
fn renders_into_a_window() {
    let event_loop =
        EventLoop::builder().with_any_thread(true).build().expect("event loop (is DISPLAY set?)");
    let mut app = App::default();
    event_loop.run_app(&mut app).expect("run");
    match app.result {
        Some(Ok(info)) => eprintln!("presented {} frames: {info}", app.frames),
        Some(Err(e)) => panic!("window rendering failed: {e}"),
        None => panic!("the event loop never resumed"),
    }
    assert_eq!(app.frames, 3);
}
