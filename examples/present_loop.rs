//! The smallest window loop wgpu can run: one window, each frame cleared to a colour and presented,
//! nothing of dissect in it. Used to tell a leak of the driver from one of the trainer:
//!
//! ```sh
//! cargo build --release --example present_loop
//! xvfb-run -a -s "-screen 0 1280x800x24" target/release/examples/present_loop 600
//! WGPU_BACKEND=gl xvfb-run -a -s "-screen 0 1280x800x24" target/release/examples/present_loop 600
//! ```
//! prints the process's resident memory every 100 frames and exits after the frames asked (default
//! 600). `PRESENT=fifo|mailbox|immediate` picks the present mode (default: the surface's default).

use std::sync::Arc;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

struct App {
    frames: u64,
    limit: u64,
    started: Instant,
    gfx: Option<Gfx>,
}

/// Resident memory of this process, MB (Linux).
fn rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

impl App {
    fn open(event_loop: &ActiveEventLoop) -> Result<Gfx, String> {
        let attributes = Window::default_attributes().with_title("present loop");
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| e.to_string())?);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
            Box::new(event_loop.owned_display_handle()),
        ));
        let surface = instance.create_surface(window.clone()).map_err(|e| e.to_string())?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| e.to_string())?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default()))
            .map_err(|e| e.to_string())?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("no surface configuration")?;
        config.present_mode = match std::env::var("PRESENT").as_deref() {
            Ok("fifo") => wgpu::PresentMode::Fifo,
            Ok("mailbox") => wgpu::PresentMode::Mailbox,
            Ok("immediate") => wgpu::PresentMode::Immediate,
            _ => config.present_mode,
        };
        surface.configure(&device, &config);
        let info = adapter.get_info();
        println!(
            "present_loop: {} ({:?}), {}x{}, {:?}",
            info.name, info.backend, config.width, config.height, config.present_mode
        );
        Ok(Gfx { window, surface, device, queue })
    }

    fn frame(&mut self) -> bool {
        let Some(gfx) = &self.gfx else { return true };
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            _ => return true,
        };
        let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = gfx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let shade = (self.frames % 100) as f64 / 100.0;
        drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: shade, g: 0.2, b: 0.3, a: 1.0 }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        }));
        gfx.queue.submit([encoder.finish()]);
        gfx.queue.present(frame);
        self.frames += 1;
        if self.frames.is_multiple_of(100) {
            let s = self.started.elapsed().as_secs_f64();
            println!(
                "present_loop: {} frames, {s:.1} s, {:.1} fps, RSS {:.0} MB",
                self.frames,
                self.frames as f64 / s,
                rss_mb()
            );
        }
        gfx.window.request_redraw();
        self.frames < self.limit
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none() {
            match Self::open(event_loop) {
                Ok(g) => {
                    self.started = Instant::now();
                    self.gfx = Some(g);
                }
                Err(e) => {
                    eprintln!("present_loop: {e}");
                    event_loop.exit();
                }
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if matches!(event, WindowEvent::CloseRequested) {
            event_loop.exit();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if !self.frame() {
            event_loop.exit();
        }
    }
}

fn main() {
    let limit = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(600);
    let Ok(event_loop) = EventLoop::new() else {
        eprintln!("present_loop: no event loop (no display?)");
        return;
    };
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App { frames: 0, limit, started: Instant::now(), gfx: None };
    if let Err(e) = event_loop.run_app(&mut app) {
        eprintln!("present_loop: {e}");
    }
}
