//! The scene data: what an exercise contains, as the RON file spells it. Pure data with defaults;
//! the checks are in `validate.rs`.
//!
//! ## Where things are (for whoever builds the tissue)
//! Metres, Y up. The base surface `X(u, v)` is parametrised by fractions `u, v ∈ [0, 1]`, and a layer
//! sits at `X(u, v) + offset · N(u, v)` with `N` the outward unit normal.
//! - `Plane` / `Box`: the plane `y = 0`, centred on the origin; `u` runs along x over `width`
//!   (`x = (u − ½)·width`), `v` along z over `depth` (`z = (v − ½)·depth`); `N = +y`. A `Box` also has a
//!   rigid block under the layers filling `y ∈ [−height, 0]`.
//! - `Cylinder`: axis along x, centred on the origin; `v` runs along the axis (`x = (v − ½)·length`),
//!   `u` goes once around it (wraps): `y = −r·cos 2πu`, `z = r·sin 2πu`, so `u = 0` is underneath
//!   (the seam), `u = 0.25` faces the camera (+z) and `u = 0.5` is on top; `N` points away from the axis.
//! - `Sphere`: centred on the origin; `v` runs from the south pole to the north pole
//!   (`y = −r·cos πv`, ring radius `ρ = r·sin πv`), `u` is the longitude (wraps):
//!   `x = −ρ·sin 2πu`, `z = −ρ·cos 2πu`, so the seam is at the back and `u = 0.5` faces +z. By default
//!   no element sits on a pole (see [`LayerTissue::v_fractions`]). `N` points outward.
//! - `Volume`: a block of `size` whose base face lies on `y = 0`, centred in x and z. Script points
//!   `Surface(u, v, h)` lie on its top face: `x = (u − ½)·size.x`, `z = (v − ½)·size.z`, `y = size.y + h`.

use serde::{Deserialize, Serialize};

use crate::chainmail::Material;
pub use crate::instrument::InstrumentSizes;
use crate::snapshot::{CameraSpec, InstrumentKind};

/// One training exercise: the tissue, the instruments offered, the cameras and the clock.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name shown in the window title and the report. Required, not empty.
    pub title: String,
    /// What the trainee is asked to do, shown in the instructions panel. Default: empty.
    #[serde(default)]
    pub instructions: String,
    /// The tissue: surface layers or a volume. Required.
    pub tissue: Tissue,
    /// The instruments the trainee may pick, in toolbar order; at least one, no repeats.
    /// Default: `[Forceps, Scalpel, Probe]`.
    #[serde(default = "all_instruments")]
    pub instruments: Vec<InstrumentKind>,
    /// Cameras. Default: both placed from the tissue's size, see [`Scene::trainee_camera`].
    #[serde(default)]
    pub cameras: Cameras,
    /// The fixed-step clock and the relaxation effort. Default: see [`SimulationSettings`].
    #[serde(default)]
    pub simulation: SimulationSettings,
    /// The exercise's goals, for the live assessment and the report. Default: none.
    #[serde(default)]
    pub goals: Option<crate::training::Goals>,
    /// The instruments' physical sizes (jaw, blade, probe), metres. Default: see [`InstrumentSizes`].
    #[serde(default)]
    pub instrument_sizes: InstrumentSizes,
}

fn all_instruments() -> Vec<InstrumentKind> {
    vec![InstrumentKind::Forceps, InstrumentKind::Scalpel, InstrumentKind::Probe]
}

/// The tissue of a scene.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub enum Tissue {
    /// One or two surface layers over a base surface (SurfaceChainMail). RON: `Layers((...))`.
    Layers(LayerTissue),
    /// A solid block (3D ChainMail, or a finite-element model). RON: `Volume((...))`.
    Volume(VolumeTissue),
}

/// One or two layers of tissue over a base surface, optionally joined by connective fibres.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LayerTissue {
    /// The base surface the layers follow. Required.
    pub surface: Surface,
    /// Elements along `u` and `v` in each layer; at least 2 each (3 along a wrapped axis).
    /// Default `(48, 48)`.
    #[serde(default = "default_resolution")]
    pub resolution: [u32; 2],
    /// Explicit element positions along `u` as fractions, strictly increasing, in `[0, 1]` (in `[0, 1)`
    /// on a wrapped axis), as many as `resolution.0`. Default: `None`, evenly spaced (`i/(n−1)`, or
    /// `i/n` on a wrapped axis).
    #[serde(default)]
    pub u_coords: Option<Vec<f32>>,
    /// Explicit element positions along `v`, as for `u_coords`. Default: `None`, evenly spaced (on a
    /// sphere: cell centres, no element on a pole).
    #[serde(default)]
    pub v_coords: Option<Vec<f32>>,
    /// The layers, upper (outer) first: one or two.
    pub layers: Vec<Layer>,
    /// Fibres joining layer 0 to layer 1. Only with two layers. Default: `None`.
    #[serde(default)]
    pub connective: Option<Connective>,
    /// Which elements are held fixed, in every layer. Default: `Boundary`.
    #[serde(default)]
    pub pinned: Pinning,
}

fn default_resolution() -> [u32; 2] {
    [48, 48]
}

pub use crate::surface::Surface;

pub use crate::tissue::{ConnectiveSpec as Connective, Edge, LayerSpec as Layer, Pinning};

fn default_color() -> [f32; 4] {
    [0.8, 0.6, 0.55, 1.0]
}

/// A solid block of tissue.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VolumeTissue {
    /// Extent along x, y, z, metres, each positive. Required.
    pub size: [f32; 3],
    /// Elements along x, y, z, at least 2 each. Default `(16, 16, 16)`.
    #[serde(default = "default_volume_resolution")]
    pub resolution: [u32; 3],
    /// ChainMail material of the links (used by the `ChainMail` model). Default: [`Material::default`].
    #[serde(default)]
    pub material: Material,
    /// Linear RGBA colour, each channel in `[0, 1]`. Default `(0.8, 0.6, 0.55, 1.0)`.
    #[serde(default = "default_color")]
    pub color: [f32; 4],
    /// What is held in place. Default: `Base`.
    #[serde(default)]
    pub pinned: VolumePinning,
    /// The deformation model. Default: `ChainMail`.
    #[serde(default)]
    pub model: VolumeModel,
}

fn default_volume_resolution() -> [u32; 3] {
    [16, 16, 16]
}

/// Which elements of a volume are held in place.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum VolumePinning {
    /// Nothing.
    None,
    /// The base face, `y = 0` (the block rests on a table).
    #[default]
    Base,
}

/// How a volume deforms.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub enum VolumeModel {
    /// Gibson's 3D ChainMail with relaxation, using the volume's `material`.
    #[default]
    ChainMail,
    /// Linear finite elements. RON: `Fem((young_modulus: 3000.0, ...))`.
    Fem(FemParams),
}

/// Parameters of the finite-element model.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FemParams {
    /// Young's modulus E, pascals, positive. Default 3000 (soft brain-like tissue).
    #[serde(default = "default_young")]
    pub young_modulus: f32,
    /// Poisson's ratio ν, in `(−1, 0.5)` (0.5 would be incompressible). Default 0.45.
    #[serde(default = "default_poisson")]
    pub poisson_ratio: f32,
    /// Mass density, kg/m³, positive. Default 1000.
    #[serde(default = "default_density")]
    pub density: f32,
    /// Damping, 1/s (Rayleigh mass damping), 0 or more. Default 0.1.
    #[serde(default = "default_damping")]
    pub damping: f32,
    /// Static (equilibrium each step) or dynamic (integrated in time). Default `Static`.
    #[serde(default)]
    pub mode: FemMode,
}

fn default_young() -> f32 {
    3000.0
}
fn default_poisson() -> f32 {
    0.45
}
fn default_density() -> f32 {
    1000.0
}
fn default_damping() -> f32 {
    0.1
}

impl Default for FemParams {
    fn default() -> Self {
        Self {
            young_modulus: default_young(),
            poisson_ratio: default_poisson(),
            density: default_density(),
            damping: default_damping(),
            mode: FemMode::default(),
        }
    }
}

/// How the finite-element model advances.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FemMode {
    /// Solve for equilibrium every step (no inertia).
    #[default]
    Static,
    /// Integrate in time with mass and damping.
    Dynamic,
}

/// The two views of the paper's figure 5: the trainee's and the observers'.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Cameras {
    /// The trainee's camera. Default: placed from the tissue's size ([`Scene::trainee_camera`]).
    #[serde(default)]
    pub trainee: Option<CameraSpec>,
    /// The observers' camera. Default: placed from the tissue's size ([`Scene::observer_camera`]).
    #[serde(default)]
    pub observer: Option<CameraSpec>,
}

/// The fixed-step clock and the relaxation effort per step.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulationSettings {
    /// Simulation steps per second, in `[50, 20000]`. Default 1000.
    #[serde(default = "default_rate")]
    pub rate_hz: u32,
    /// Most relaxation sweeps per step, in `[0, 1000]`. Default 4.
    #[serde(default = "default_sweeps")]
    pub relax_sweeps: u32,
    /// Most time spent relaxing per step, microseconds, in `[0, 1000000]`; sweeps stop early when it is
    /// used up. Default 300.
    #[serde(default = "default_budget")]
    pub relax_budget_us: u32,
}

fn default_rate() -> u32 {
    1000
}
fn default_sweeps() -> u32 {
    4
}
fn default_budget() -> u32 {
    300
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self { rate_hz: default_rate(), relax_sweeps: default_sweeps(), relax_budget_us: default_budget() }
    }
}

impl SimulationSettings {
    /// Length of one step, seconds.
    pub fn step_seconds(&self) -> f64 {
        1.0 / f64::from(self.rate_hz.max(1))
    }

    /// The relaxation budget as a duration.
    pub fn relax_budget(&self) -> std::time::Duration {
        std::time::Duration::from_micros(u64::from(self.relax_budget_us))
    }
}

impl Scene {
    /// The centre of the tissue and a radius that contains it (metres).
    pub fn bounds(&self) -> ([f32; 3], f32) {
        match &self.tissue {
            Tissue::Layers(l) => {
                let top = l.layers.iter().map(|x| x.offset).fold(0.0f32, f32::max);
                ([0.0, 0.0, 0.0], l.surface.half_extent() + top.max(0.0))
            }
            Tissue::Volume(v) => {
                let [x, y, z] = v.size;
                ([0.0, 0.5 * y, 0.0], 0.5 * (x * x + y * y + z * z).sqrt())
            }
        }
    }

    /// The trainee's camera: as given, or in front of and above the tissue, looking down at its centre
    /// at about 50° from about 1.5 radii away (45° field of view), so the tissue fills most of the view.
    pub fn trainee_camera(&self) -> CameraSpec {
        self.cameras.trainee.unwrap_or_else(|| {
            let (c, r) = self.bounds();
            CameraSpec { eye: [c[0], c[1] + 1.15 * r, c[2] + 0.95 * r], target: c, ..CameraSpec::default() }
        })
    }

    /// The observers' camera: as given, or from the side and higher than the trainee's.
    pub fn observer_camera(&self) -> CameraSpec {
        self.cameras.observer.unwrap_or_else(|| {
            let (c, r) = self.bounds();
            CameraSpec {
                eye: [c[0] + 2.2 * r, c[1] + 2.6 * r, c[2] + 1.2 * r],
                target: c,
                ..CameraSpec::default()
            }
        })
    }

    /// Number of ChainMail elements the tissue needs (all layers, or the whole volume).
    pub fn element_count(&self) -> u128 {
        match &self.tissue {
            Tissue::Layers(l) => {
                l.layers.len() as u128 * u128::from(l.resolution[0]) * u128::from(l.resolution[1])
            }
            Tissue::Volume(v) => v.resolution.iter().map(|&n| u128::from(n)).product(),
        }
    }
}

impl LayerTissue {
    /// Element positions along `u` as fractions: `u_coords`, or evenly spaced.
    pub fn u_fractions(&self) -> Vec<f32> {
        fractions(self.u_coords.as_deref(), self.resolution[0], self.surface.wraps_u())
    }

    /// Element positions along `v` as fractions: `v_coords`, or evenly spaced from 0 to 1 — except on
    /// a sphere, where they are cell centres `(j + ½)/n` so that no ring collapses onto a pole.
    pub fn v_fractions(&self) -> Vec<f32> {
        if self.v_coords.is_none()
            && let Surface::Sphere { .. } = self.surface
        {
            let n = self.resolution[1].max(1);
            return (0..n).map(|j| (j as f32 + 0.5) / n as f32).collect();
        }
        fractions(self.v_coords.as_deref(), self.resolution[1], false)
    }

    /// The gap between the two layers' offsets (metres), or `None` with one layer.
    pub fn gap(&self) -> Option<f32> {
        match self.layers.as_slice() {
            [upper, lower] => Some(upper.offset - lower.offset),
            _ => None,
        }
    }
}

fn fractions(explicit: Option<&[f32]>, n: u32, wraps: bool) -> Vec<f32> {
    if let Some(c) = explicit {
        return c.to_vec();
    }
    let n = n.max(1);
    let d = if wraps { n as f32 } else { (n.max(2) - 1) as f32 };
    (0..n).map(|i| i as f32 / d).collect()
}
