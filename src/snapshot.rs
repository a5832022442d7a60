//! The vocabulary every floor shares: what the renderer and the panels may see of the world (plain
//! arrays, refilled in place each frame), which instrument is drawn and how it is held, a camera as
//! the scene gives it.
//!
//! A leaf: imports nothing of this crate, so tissue, instrument, simulation and render all import it
//! downward. Must not import wgpu, winit or egui.

use serde::{Deserialize, Serialize};

/// Everything needed to draw one moment of the simulation.
///
/// The world refills a snapshot in place (`clear` + `extend`), so that after the first frame no
/// allocation happens unless the topology grows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// Simulation step this snapshot was taken at.
    pub step: u64,
    /// One triangle mesh per tissue layer, upper layer first.
    pub layers: Vec<LayerMesh>,
    /// Intact connective fibres between the layers, as line segments (world space, metres).
    pub fibres: Vec<[[f32; 3]; 2]>,
    /// The instrument, if one is in use.
    pub instrument: Option<InstrumentPose>,
    /// The scalpel stroke being drawn right now (world space), empty when none.
    pub cut_path: Vec<[f32; 3]>,
}

/// A layer's current surface as triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerMesh {
    /// Name from the scene, for panels.
    pub name: String,
    /// Linear RGBA colour, each channel in `[0, 1]`.
    pub color: [f32; 4],
    /// Vertex positions in world space (metres).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals (the side facing away from the other layer).
    pub normals: Vec<[f32; 3]>,
    /// Triangles as vertex indices. Triangles that would span a broken link are left out.
    pub triangles: Vec<[u32; 3]>,
    /// Bumped whenever `triangles` changes (a cut or a tear), so index buffers are rebuilt only then.
    pub topology_version: u64,
}

/// Which instrument is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum InstrumentKind {
    /// A blunt probe that pushes the tissue.
    #[default]
    Probe,
    /// Forceps that grasp and pull.
    Forceps,
    /// A scalpel that cuts along a path.
    Scalpel,
}

/// Where the instrument is and how it is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstrumentPose {
    /// Which instrument.
    pub kind: InstrumentKind,
    /// Tip position, world space (metres).
    pub tip: [f32; 3],
    /// Unit vector from the tip towards the handle.
    pub axis: [f32; 3],
    /// Rotation about the axis, radians.
    pub roll: f32,
    /// Forceps jaws closed (grasping).
    pub closed: bool,
}

/// A camera as the scene describes it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Eye position, world space (metres).
    pub eye: [f32; 3],
    /// Point looked at, world space (metres).
    pub target: [f32; 3],
    /// Vertical field of view, degrees. Default 45.
    #[serde(default = "default_fov")]
    pub fov_y_deg: f32,
}

fn default_fov() -> f32 {
    45.0
}

impl Default for CameraSpec {
    fn default() -> Self {
        Self { eye: [0.0, 0.08, 0.12], target: [0.0, 0.0, 0.0], fov_y_deg: default_fov() }
    }
}
