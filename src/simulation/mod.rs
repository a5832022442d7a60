//! The world that advances in fixed steps, and the [`Snapshot`] it hands to whoever draws it.
//!
//! Must not import wgpu, winit or egui: the renderer reads a [`Snapshot`] and never reaches into the
//! engine.

mod clock;
mod snapshot;
mod world;

pub use clock::{FixedClock, MAX_FRAME_DELTA};
pub use world::{PHASES, StepCounters, World, WorldConfig};

pub use snapshot::{CameraSpec, InstrumentKind, InstrumentPose, LayerMesh, Snapshot};
