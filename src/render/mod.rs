//! Drawing the simulation with wgpu: the device ([`Gpu`]), the scene pipelines and their buffers
//! ([`SceneRenderer`], [`SceneView`]), the orbit camera and picking rays ([`OrbitCamera`]), the procedural
//! instrument models ([`mesh`]), the procedural tissue texture ([`texture`]), what is derived from a
//! snapshot on the CPU (cut-edge walls, fibre instances: [`geometry`]), a synthetic test scene
//! ([`demo`]) and headless capture to PNG ([`Offscreen`], [`render_to_image`]).
//!
//! It reads only a [`Snapshot`](crate::snapshot::Snapshot) and a
//! [`CameraSpec`](crate::snapshot::CameraSpec); it never reaches into the engine. It may import wgpu,
//! glam, bytemuck, image and `crate::snapshot`; never winit or egui (the app owns windows and passes
//! a surface-compatible [`Gpu`] in). The render path itself uses no files or threads, so it can run in a
//! browser later; only [`save_png`] and the blocking helpers touch the OS, and they are native-only.
//!
//! Shaders live in `shaders/*.wgsl`; `common.wgsl` (camera and object uniforms) is prepended to each.

pub mod camera;
mod capture;
pub mod demo;
mod error;
pub mod geometry;
mod gpu;
pub mod mesh;
mod scene;
pub mod texture;

pub use camera::OrbitCamera;
pub use capture::{OFFSCREEN_FORMAT, Offscreen};
#[cfg(not(target_arch = "wasm32"))]
pub use capture::{render_to_image, save_png};
pub use error::RenderError;
pub use gpu::Gpu;
pub use scene::{SceneRenderer, SceneView, Style, UploadStats};
