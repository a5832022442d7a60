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
    /// Stretch of each intact fibre (world length over rest length), in the order of `fibres`.
    pub fibre_stretch: Vec<f32>,
    /// Where each intact fibre stands at rest, in the order of `fibres` (see [`BrokenFibre::site`]):
    /// the renderer draws the fibres at a physical density from these, whatever the resolution.
    pub fibre_sites: Vec<[f32; 4]>,
    /// Stretch at which the fibres tear (their material's tear ratio); `0` when they never tear.
    pub fibre_tear_stretch: f32,
    /// Connective fibres that were cut or torn, with their two ends where they are now.
    pub broken_fibres: Vec<BrokenFibre>,
    /// The forceps left clamped on the tissue while another instrument is in hand, if any.
    pub clamped: Option<InstrumentPose>,
    /// Regions of the exercise to draw on the tissue's surface (from the scene's goals).
    pub regions: Vec<SurfaceRegion>,
    /// The planned incision through the upper layer, a line through `(u, v)` points in surface
    /// fractions (from the scene's goals), drawn on that layer as a surgeon's marker line.
    pub incision: Vec<[f32; 2]>,
}

/// A connective fibre that no longer holds: its two ends (world space, metres; the lower layer's first)
/// and how it broke.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BrokenFibre {
    /// Where its ends are now: on the lower layer, then on the upper.
    pub ends: [[f32; 3]; 2],
    /// Cut by the scalpel (`true`) or torn by over-stretching (`false`).
    pub cut: bool,
    /// Where it stood at rest: its lower end's element's rest position along the surface's `u` and `v`
    /// (metres from the surface's first corner), then that element's spacing to its neighbours along
    /// `u` and `v` (metres): the share of the surface the fibre stands for.
    pub site: [f32; 4],
}

/// What a region drawn on the tissue means.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RegionKind {
    /// Where the trainee should work.
    #[default]
    Target,
    /// Where nothing may be cut or torn.
    Forbidden,
}

/// A region of the surface in fractions of its `u` and `v` extents (as goals give them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RegionShape {
    /// `u` from `u[0]` to `u[1]`, `v` from `v[0]` to `v[1]`.
    Rect {
        /// Range of `u`, fractions.
        u: [f32; 2],
        /// Range of `v`, fractions.
        v: [f32; 2],
    },
    /// A disc around `center` of `radius`, fractions.
    Disc {
        /// Centre `(u, v)`, fractions.
        center: [f32; 2],
        /// Radius, a fraction.
        radius: f32,
    },
}

/// A region drawn on the tissue's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceRegion {
    /// Target or forbidden.
    pub kind: RegionKind,
    /// Where, in surface fractions.
    pub shape: RegionShape,
}

/// The procedural texture a layer is drawn with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SurfacePattern {
    /// A fibrous membrane (the dura): fine grain along `u`.
    #[default]
    Grain,
    /// A thin membrane with vessels on it (the arachnoid).
    Vessels,
    /// No pattern (volumes, finite-element blocks).
    Plain,
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
    /// A new number whenever `triangles` changes (a link between two of this layer's elements cut or
    /// torn; a fibre's leaves it), one no other layer or tissue has: index buffers are rebuilt only then.
    pub topology_version: u64,
    /// Where each vertex sits on the surface at rest, fractions of the `u` and `v` extents (textures
    /// and regions are drawn in these coordinates, so they move with the tissue). One per position.
    pub uv: Vec<[f32; 2]>,
    /// The surface's extent along `u` and `v`, metres (the scale of the texture).
    pub uv_size: [f32; 2],
    /// Thickness of the layer, metres: cut edges are drawn this deep, towards the other layer.
    pub thickness: f32,
    /// The texture it is drawn with.
    pub pattern: SurfacePattern,
    /// `Some([nu, nv])` when the first `nu × nv` vertices are a grid in rows along `u` (vertex
    /// `i + nu · j`) and the triangles are its quads' (two per quad) plus any joining other vertices:
    /// the renderer may then draw several quads as one cell where nothing is cut.
    pub grid: Option<[u32; 2]>,
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
