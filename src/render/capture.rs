//! Headless capture: render into a texture, copy it to a buffer (rows padded to 256 bytes), map it and
//! unpad it into an [`image::RgbaImage`]. Used by `dissect run --out DIR` and by the golden-image tests.

use super::camera::OrbitCamera;
use super::scene::{SceneRenderer, SceneView};
use super::{Gpu, RenderError};

/// Colour format of offscreen images: 8-bit sRGB RGBA, the bytes a PNG stores.
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// An offscreen render target with its own [`SceneView`] and a readback buffer.
#[derive(Debug)]
pub struct Offscreen {
    texture: wgpu::Texture,
    target: wgpu::TextureView,
    view: SceneView,
    readback: wgpu::Buffer,
    padded_row: u32,
}

impl Offscreen {
    /// A `width` × `height` target for `renderer` (which must use [`OFFSCREEN_FORMAT`]).
    pub fn new(gpu: &Gpu, renderer: &SceneRenderer, width: u32, height: u32) -> Result<Self, RenderError> {
        let view = renderer.create_view(gpu, width, height)?;
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: renderer.format(),
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let target = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let padded_row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("offscreen readback"),
            size: u64::from(padded_row) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(Self { texture, target, view, readback, padded_row })
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.view.size()
    }

    /// Renders the renderer's current scene through `camera` and submits it, without reading back.
    pub fn render(&self, gpu: &Gpu, renderer: &SceneRenderer, camera: &OrbitCamera) -> wgpu::SubmissionIndex {
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("offscreen") });
        self.record(gpu, renderer, &mut encoder, camera);
        gpu.queue.submit([encoder.finish()])
    }

    /// Renders into `rect` = `[x, y, width, height]` of the image only (see
    /// [`SceneRenderer::render_in`]) and submits.
    pub fn render_in(
        &self,
        gpu: &Gpu,
        renderer: &SceneRenderer,
        camera: &OrbitCamera,
        rect: [f32; 4],
    ) -> wgpu::SubmissionIndex {
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("offscreen") });
        renderer.render_in(gpu, &mut encoder, &self.view, &self.target, camera, rect);
        gpu.queue.submit([encoder.finish()])
    }

    /// Records the scene pass into `encoder` without submitting (several offscreen views can share one
    /// submission: each has its own camera uniform).
    pub fn record(
        &self,
        gpu: &Gpu,
        renderer: &SceneRenderer,
        encoder: &mut wgpu::CommandEncoder,
        camera: &OrbitCamera,
    ) {
        renderer.render(gpu, encoder, &self.view, &self.target, camera);
    }

    /// Copies the last rendered frame back to the CPU. Blocks until the GPU is done (native only: in a
    /// browser `device.poll` does not wait).
    pub fn read(&self, gpu: &Gpu) -> Result<image::RgbaImage, RenderError> {
        let (width, height) = self.size();
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        let index = gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        self.readback.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = tx.send(result);
        });
        gpu.device.poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })?;
        match rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(RenderError::Readback(e.to_string())),
            Err(_) => return Err(RenderError::Readback("the map callback never ran".into())),
        }
        let row = (width * 4) as usize;
        let mut pixels = Vec::with_capacity(row * height as usize);
        {
            let mapped =
                self.readback.get_mapped_range(..).map_err(|e| RenderError::Readback(e.to_string()))?;
            for chunk in mapped.chunks(self.padded_row as usize).take(height as usize) {
                pixels.extend_from_slice(&chunk[..row]);
            }
        }
        self.readback.unmap();
        image::RgbaImage::from_raw(width, height, pixels)
            .ok_or_else(|| RenderError::Readback("pixel count does not match the image size".into()))
    }
}

/// Renders `snapshot` through `camera` into a `width` × `height` image with a fresh renderer (builds
/// the pipelines each call: for many frames keep a [`SceneRenderer`] and an [`Offscreen`] instead).
#[cfg(not(target_arch = "wasm32"))]
pub fn render_to_image(
    gpu: &Gpu,
    snapshot: &crate::snapshot::Snapshot,
    camera: &OrbitCamera,
    width: u32,
    height: u32,
) -> Result<image::RgbaImage, RenderError> {
    let mut renderer = SceneRenderer::new(gpu, OFFSCREEN_FORMAT, super::Style::default());
    renderer.update(gpu, snapshot)?;
    let offscreen = Offscreen::new(gpu, &renderer, width, height)?;
    offscreen.render(gpu, &renderer, camera);
    offscreen.read(gpu)
}

/// Writes `image` as a PNG at `path`.
#[cfg(not(target_arch = "wasm32"))]
pub fn save_png(image: &image::RgbaImage, path: impl AsRef<std::path::Path>) -> Result<(), RenderError> {
    let path = path.as_ref();
    image
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|source| RenderError::Image { path: path.to_path_buf(), source })
}
