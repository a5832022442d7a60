//! The world that advances in fixed steps, and the [`Snapshot`] it hands to whoever draws it.
//!
//! Must not import wgpu, winit or egui: the renderer reads a [`Snapshot`] and never reaches into the
//! engine.

mod clock;
mod command;
mod force;
mod view;
mod world;

pub use clock::{FixedClock, MAX_FRAME_DELTA};
pub use command::Command;
pub use force::{CUT_WINDOW_S, Forces};
pub use view::WorldView;
pub use world::{PHASES, StepCounters, World, WorldConfig};

// The snapshot vocabulary lives one floor down, in `crate::snapshot`; re-exported for the app side.
pub use crate::snapshot::{
    BrokenFibre, CameraSpec, InstrumentKind, InstrumentPose, LayerMesh, RegionKind, RegionShape, Snapshot,
    SurfacePattern, SurfaceRegion,
};
