//! Instruments: the probe that pushes, the forceps that grasp and pull, the scalpel that cuts. Each
//! holds a pose; the world turns its commands (`simulation::Command`) into what the instrument does to
//! the tissue. Picking (a ray from the cursor against the current tissue triangles) uses parry3d.
//!
//! Must not import wgpu, winit or egui.

mod pick;

pub use pick::{Hit, Picker};

use serde::{Deserialize, Serialize};

use crate::chainmail::ElementId;
use crate::snapshot::{InstrumentKind, InstrumentPose};
use crate::tissue::CutDepth;

/// Radius of the probe's ball tip, metres (the default of [`InstrumentSizes::probe_radius`]).
pub const PROBE_RADIUS: f32 = 0.003;
/// Width of the forceps' jaws, metres (the default of [`InstrumentSizes::jaw_width`]).
pub const JAW_WIDTH: f32 = 0.002;
/// Width of the scalpel's blade, metres (the default of [`InstrumentSizes::blade_width`]).
pub const BLADE_WIDTH: f32 = 0.001;

/// The instruments' physical sizes, metres: what they hold, cut and push does not depend on the
/// element spacing. RON: `instrument_sizes: (jaw_width: 0.002, blade_width: 0.001, probe_radius: 0.003)`.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InstrumentSizes {
    /// The forceps hold every element of the grasped layer within half this width of the grasp
    /// point (measured across the surface, at rest), metres. Default 0.002.
    #[serde(default = "default_jaw")]
    pub jaw_width: f32,
    /// The scalpel severs the connective fibres within half this width of its stroke, metres; in-layer
    /// links are cut where the stroke crosses them. Default 0.001.
    #[serde(default = "default_blade")]
    pub blade_width: f32,
    /// Radius of the probe's ball tip, metres. Default 0.003.
    #[serde(default = "default_probe")]
    pub probe_radius: f32,
}

fn default_jaw() -> f32 {
    JAW_WIDTH
}
fn default_blade() -> f32 {
    BLADE_WIDTH
}
fn default_probe() -> f32 {
    PROBE_RADIUS
}

impl Default for InstrumentSizes {
    fn default() -> Self {
        Self { jaw_width: JAW_WIDTH, blade_width: BLADE_WIDTH, probe_radius: PROBE_RADIUS }
    }
}
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
