//! Errors at the renderer's boundary.

use std::path::PathBuf;

/// Why rendering could not start or a frame could not be produced.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No adapter on any backend tried (Vulkan, then GL).
    #[error(
        "no graphics adapter found (tried {tried}); install a driver, e.g. `apt-get install \
         mesa-vulkan-drivers libvulkan1` for software Vulkan (lavapipe): {source}"
    )]
    NoAdapter {
        /// The backends asked, in order.
        tried: String,
        /// The last error from `request_adapter`.
        source: wgpu::RequestAdapterError,
    },
    /// The adapter was found but refused to open a device.
    #[error("could not open the graphics device: {0}")]
    Device(#[from] wgpu::RequestDeviceError),
    /// A layer of the snapshot is inconsistent (normals missing, an index out of range).
    #[error("snapshot layer {layer}: {what}")]
    InvalidSnapshot {
        /// Index of the layer in `Snapshot::layers`.
        layer: usize,
        /// What is wrong.
        what: String,
    },
    /// A render target of zero size, or larger than the device allows.
    #[error("render target {width}x{height} is empty or larger than the device limit {max}")]
    BadSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// The device's `max_texture_dimension_2d`.
        max: u32,
    },
    /// Waiting for the GPU failed.
    #[error("waiting for the GPU failed: {0}")]
    Poll(#[from] wgpu::PollError),
    /// Mapping the readback buffer failed.
    #[error("reading the frame back failed: {0}")]
    Readback(String),
    /// Writing an image file failed.
    #[error("writing {path}: {source}")]
    Image {
        /// The file being written.
        path: PathBuf,
        /// The encoder's or the file system's error.
        source: image::ImageError,
    },
}
