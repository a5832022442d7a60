//! Instruments: the probe that pushes, the forceps that grasp and pull, the scalpel that cuts. Each
//! holds a pose; the world turns its commands (`simulation::Command`) into what the instrument does to
//! the tissue. Picking (a ray
//! from the cursor against the current tissue triangles) uses parry3d.
//!
//! Must not import wgpu, winit or egui.

mod pick;

pub use pick::{Hit, Picker};

use crate::chainmail::ElementId;
use crate::snapshot::{InstrumentKind, InstrumentPose};
use crate::tissue::CutDepth;

/// Radius of the probe's ball tip, metres.
pub const PROBE_RADIUS: f32 = 0.003;
/// Forceps grasp the nearest element within this distance of their tip, metres.
pub const GRASP_REACH: f32 = 0.01;

/// An instrument's state.
#[derive(Clone, Debug, PartialEq)]
pub struct Instrument {
    /// Which instrument is in hand.
    pub kind: InstrumentKind,
    /// Where the hand puts the tip (world, metres).
    pub target: [f32; 3],
    /// Where the tip is: the target, or where the tissue stopped a grasp.
    pub tip: [f32; 3],
    /// Unit vector from the tip towards the handle.
    pub axis: [f32; 3],
    /// Rotation about the axis, radians.
    pub roll: f32,
    /// The element the forceps hold.
    pub grasped: Option<ElementId>,
    /// The scalpel's depth.
    pub depth: CutDepth,
    /// The scalpel is pressed: moving it cuts.
    pub cutting: bool,
    /// The stroke being cut (world points), for drawing.
    pub stroke: Vec<[f32; 3]>,
}

impl Default for Instrument {
    fn default() -> Self {
        Self {
            kind: InstrumentKind::Forceps,
            target: [0.0, 0.03, 0.0],
            tip: [0.0, 0.03, 0.0],
            axis: [0.3, 0.9, 0.3],
            roll: 0.0,
            grasped: None,
            depth: CutDepth::Between,
            cutting: false,
            stroke: Vec::new(),
        }
    }
}

impl Instrument {
    /// The pose to draw.
    pub fn pose(&self) -> InstrumentPose {
        let a = glam::Vec3::from(self.axis);
        InstrumentPose {
            kind: self.kind,
            tip: self.tip,
            axis: (a / a.length().max(1e-9)).to_array(),
            roll: self.roll,
            closed: self.grasped.is_some() && self.kind == InstrumentKind::Forceps,
        }
    }
}
