//! One OS window: its surface, its egui context and painter, and the 3D views it shows (one, or two
//! side by side with `--single-window`, the second drawn into a texture that egui paints).

use std::sync::Arc;

use winit::window::Window;

use super::AppError;
use super::input::{CameraRig, Pointer};
use crate::render::{Gpu, SceneRenderer, SceneView};

/// A 3D view drawn into a texture and shown by egui (the observer's half of a single window).
struct TextureView {
    texture: wgpu::Texture,
    view: SceneView,
    id: egui::TextureId,
}

/// A window with a surface, egui, and one or two cameras on the scene.
pub struct ViewWindow {
    /// The OS window.
    pub window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    scene_view: SceneView,
    /// The window's egui context.
    pub egui_ctx: egui::Context,
    /// egui's winit glue (input in, cursor and clipboard out).
    pub egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    second: Option<TextureView>,
    /// The main view's camera.
    pub camera: CameraRig,
    /// The second view's camera (single-window mode).
    pub second_camera: Option<CameraRig>,
    /// The main view's area, physical pixels `[x, y, w, h]`.
    pub rect: [f32; 4],
    /// The second view's area, physical pixels.
    pub second_rect: [f32; 4],
    /// Pointer state in the main view.
    pub pointer: Pointer,
    /// Pointer state in the second view.
    pub second_pointer: Pointer,
    /// Which view the current drag started in (0 main, 1 second).
    pub drag_view: usize,
    /// Cursor in window pixels.
    pub cursor: glam::Vec2,
    /// Frames presented.
    pub presented: u64,
}

/// The surface format: non-sRGB if offered (egui wants it; the scene shader encodes sRGB itself).
pub fn pick_format(surface: &wgpu::Surface<'_>, gpu: &Gpu) -> Result<wgpu::TextureFormat, AppError> {
    let caps = surface.get_capabilities(&gpu.adapter);
    caps.formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or_else(|| caps.formats.first().copied())
        .ok_or_else(|| AppError::Gpu("the surface offers no format".into()))
}

fn configure(
    surface: &wgpu::Surface<'_>,
    gpu: &Gpu,
    format: wgpu::TextureFormat,
    width: u32,
    height: u32,
) -> Result<wgpu::SurfaceConfiguration, AppError> {
    let mut config = surface
        .get_default_config(&gpu.adapter, width.max(1), height.max(1))
        .ok_or_else(|| AppError::Gpu("the surface does not work with this adapter".into()))?;
    config.format = format;
    // Do not wait for a vertical blank that a virtual X server may never send; the simulation clock
    // paces itself.
    let modes = surface.get_capabilities(&gpu.adapter).present_modes;
    if modes.contains(&wgpu::PresentMode::Mailbox) {
        config.present_mode = wgpu::PresentMode::Mailbox;
    } else if modes.contains(&wgpu::PresentMode::Immediate) {
        config.present_mode = wgpu::PresentMode::Immediate;
    }
    surface.configure(&gpu.device, &config);
    Ok(config)
}

impl ViewWindow {
    /// Wraps a window whose surface was made from `gpu.instance`.
    pub fn new(
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        gpu: &Gpu,
        renderer: &SceneRenderer,
        camera: CameraRig,
        second_camera: Option<CameraRig>,
    ) -> Result<Self, AppError> {
        let size = window.inner_size();
        let config = configure(&surface, gpu, renderer.format(), size.width, size.height)?;
        let scene_view = renderer.create_view(gpu, config.width, config.height).map_err(gpu_err)?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, config.format, egui_wgpu::RendererOptions::default());
        let mut me = Self {
            window,
            surface,
            config,
            scene_view,
            egui_ctx,
            egui_state,
            egui_renderer,
            second: None,
            camera,
            second_camera,
            rect: [0.0, 0.0, size.width as f32, size.height as f32],
            second_rect: [0.0; 4],
            pointer: Pointer::default(),
            second_pointer: Pointer::default(),
            drag_view: 0,
            cursor: glam::Vec2::ZERO,
            presented: 0,
        };
        if me.second_camera.is_some() {
            me.ensure_second(gpu, renderer, 64, 64)?;
        }
        Ok(me)
    }

    /// The egui texture showing the second view, if any.
    pub fn second_texture(&self) -> Option<egui::TextureId> {
        self.second.as_ref().map(|s| s.id)
    }

    fn ensure_second(&mut self, gpu: &Gpu, renderer: &SceneRenderer, w: u32, h: u32) -> Result<(), AppError> {
        let (w, h) = (w.max(1), h.max(1));
        if self.second.as_ref().is_some_and(|s| s.view.size() == (w, h)) {
            return Ok(());
        }
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("second view"),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: renderer.format(),
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let target = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let view = renderer.create_view(gpu, w, h).map_err(gpu_err)?;
        let id = match &self.second {
            Some(s) => {
                self.egui_renderer.update_egui_texture_from_wgpu_texture(
                    &gpu.device,
                    &target,
                    wgpu::FilterMode::Linear,
                    s.id,
                );
                s.id
            }
            None => {
                self.egui_renderer.register_native_texture(&gpu.device, &target, wgpu::FilterMode::Linear)
            }
        };
        self.second = Some(TextureView { texture, view, id });
        Ok(())
    }

    /// Follows a resize of the window.
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), AppError> {
        if width == 0 || height == 0 {
            return Ok(());
        }
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&gpu.device, &self.config);
        self.scene_view.resize(gpu, width, height).map_err(gpu_err)
    }

    /// Sets the views' areas from egui's leftover rectangle (points): the whole of it, or its two
    /// halves with a second view.
    pub fn set_area(&mut self, area: egui::Rect) {
        let ppp = self.egui_ctx.pixels_per_point();
        let [x, y, w, h] = [area.min.x * ppp, area.min.y * ppp, area.width() * ppp, area.height() * ppp];
        if self.second_camera.is_some() {
            let half = (w / 2.0).floor();
            self.rect = [x, y, half, h];
            self.second_rect = [x + half, y, w - half, h];
        } else {
            self.rect = [x, y, w, h];
        }
        self.camera.fit(self.rect[2] / self.rect[3].max(1.0));
        if let Some(c) = self.second_camera.as_mut() {
            c.fit(self.second_rect[2] / self.second_rect[3].max(1.0));
        }
        self.pointer.size = glam::Vec2::new(self.rect[2], self.rect[3]);
        self.second_pointer.size = glam::Vec2::new(self.second_rect[2], self.second_rect[3]);
    }

    /// Which view a window-pixel position falls in: 0 main, 1 second, or none.
    pub fn view_at(&self, p: glam::Vec2) -> Option<usize> {
        let inside = |r: [f32; 4]| p.x >= r[0] && p.y >= r[1] && p.x < r[0] + r[2] && p.y < r[1] + r[3];
        if inside(self.rect) {
            Some(0)
        } else if self.second_camera.is_some() && inside(self.second_rect) {
            Some(1)
        } else {
            None
        }
    }

    /// Draws the scene (as of the renderer's last update) and egui's output, and presents. Returns
    /// whether a frame was presented (not when the surface had to be reconfigured).
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        renderer: &SceneRenderer,
        mut output: egui::FullOutput,
    ) -> Result<bool, AppError> {
        self.egui_state.handle_platform_output(&self.window, std::mem::take(&mut output.platform_output));
        let ppp = output.pixels_per_point;
        let jobs = self.egui_ctx.tessellate(std::mem::take(&mut output.shapes), ppp);
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in &deltas {
                self.egui_renderer.update_texture(&gpu.device, &gpu.queue, id, delta);
            }
        }
        let presented = self.present(gpu, renderer, &jobs, ppp);
        for id in output.textures_delta.free.drain() {
            self.egui_renderer.free_texture(&id);
        }
        presented
    }

    fn present(
        &mut self,
        gpu: &Gpu,
        renderer: &SceneRenderer,
        jobs: &[egui::ClippedPrimitive],
        ppp: f32,
    ) -> Result<bool, AppError> {
        if self.second_camera.is_some() {
            let [_, _, w, h] = self.second_rect;
            self.ensure_second(gpu, renderer, w as u32, h as u32)?;
        }

        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&gpu.device, &self.config);
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                self.surface = gpu
                    .instance
                    .create_surface(self.window.clone())
                    .map_err(|e| AppError::Gpu(format!("cannot recreate the surface: {e}")))?;
                self.surface.configure(&gpu.device, &self.config);
                return Ok(false);
            }
            _ => return Ok(false),
        };
        let target = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("window frame") });
        renderer.render_in(gpu, &mut encoder, &self.scene_view, &target, &self.camera.camera, self.rect);
        if let (Some(second), Some(camera)) = (&self.second, &self.second_camera) {
            let second_target = second.texture.create_view(&wgpu::TextureViewDescriptor::default());
            renderer.render(gpu, &mut encoder, &second.view, &second_target, &camera.camera);
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: ppp,
        };
        let extra = self.egui_renderer.update_buffers(&gpu.device, &gpu.queue, &mut encoder, jobs, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, jobs, &screen);
        }
        gpu.queue.submit(extra.into_iter().chain([encoder.finish()]));
        gpu.queue.present(frame);
        self.presented += 1;
        Ok(true)
    }

    /// The cameras and view sizes, for screenshots: `(camera, width, height)` per view.
    pub fn shots(&self) -> Vec<(crate::render::OrbitCamera, u32, u32)> {
        let mut out = vec![(self.camera.camera, self.rect[2] as u32, self.rect[3] as u32)];
        if let Some(c) = &self.second_camera {
            out.push((c.camera, self.second_rect[2] as u32, self.second_rect[3] as u32));
        }
        out
    }
}

fn gpu_err(e: crate::render::RenderError) -> AppError {
    AppError::Gpu(e.to_string())
}
