//! What an exercise asks of the trainee, as the scene's `goals` give it: the target, the forbidden
//! regions, the planned incision, the limits, the pass mark and the steps of the checklist.

use serde::{Deserialize, Serialize};

use crate::snapshot::{RegionKind, RegionShape, SurfaceRegion};

/// A region of the tissue's surface, in fractions of the `u` and `v` extents (`0` to `1`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Region {
    /// A rectangle: `u` from `u.0` to `u.1`, `v` from `v.0` to `v.1`.
    Rect {
        /// Range of `u`, fractions.
        u: (f32, f32),
        /// Range of `v`, fractions.
        v: (f32, f32),
    },
    /// A disc around `center` of `radius`, all in fractions.
    Disc {
        /// Centre `(u, v)`, fractions.
        center: (f32, f32),
        /// Radius, a fraction.
        radius: f32,
    },
}

impl Region {
    /// Whether the point `(u, v)` (fractions) lies in the region.
    pub fn contains(&self, u: f32, v: f32) -> bool {
        match *self {
            Region::Rect { u: (u0, u1), v: (v0, v1) } => u >= u0 && u <= u1 && v >= v0 && v <= v1,
            Region::Disc { center: (cu, cv), radius } => {
                (u - cu).powi(2) + (v - cv).powi(2) <= radius * radius
            }
        }
    }

    /// The same region as the snapshot carries it for drawing.
    pub fn shape(&self) -> RegionShape {
        match *self {
            Region::Rect { u, v } => RegionShape::Rect { u: [u.0, u.1], v: [v.0, v.1] },
            Region::Disc { center, radius } => RegionShape::Disc { center: [center.0, center.1], radius },
        }
    }

    /// Checks that the numbers are finite fractions.
    pub fn validate(&self) -> Result<(), String> {
        let nums: Vec<f32> = match *self {
            Region::Rect { u, v } => vec![u.0, u.1, v.0, v.1],
            Region::Disc { center, radius } => vec![center.0, center.1, radius],
        };
        if nums.iter().any(|x| !x.is_finite() || *x < 0.0 || *x > 1.0) {
            return Err("expected fractions between 0 and 1".into());
        }
        if let Region::Rect { u, v } = *self
            && (u.0 >= u.1 || v.0 >= v.1)
        {
            return Err("expected each range's start below its end".into());
        }
        Ok(())
    }
}

/// When a step of the checklist counts as done (it stays ticked once it is).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub enum StepCheck {
    /// The forceps have held the tissue at least once after the `Incision` steps listed before this
    /// one were done (so "lift the flap" ticks only once the incision has freed it).
    Grasp,
    /// At least this share (`0` to `1`) of the planned incision is cut.
    Incision(f32),
    /// At least this share (`0` to `1`) of the target's fibres is cut.
    Fibres(f32),
    /// The layers are at least this far apart over the target, metres (beyond their rest gap).
    Separation(f32),
}

/// One step of the exercise, shown as a line of the on-screen checklist.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Step {
    /// What to do, in the trainee's words, e.g. "Cut the U through the dura".
    pub text: String,
    /// When it is done.
    pub done: StepCheck,
}

/// What passing takes. A session also fails when anything in a forbidden region is broken.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PassMark {
    /// Lowest passing score, 0 to 100. Default 60.
    #[serde(default = "default_pass_score")]
    pub score: f32,
    /// Lowest passing completion, `0` to `1`. Default 0.9.
    #[serde(default = "default_pass_completion")]
    pub completion: f32,
}

impl Default for PassMark {
    fn default() -> Self {
        Self { score: default_pass_score(), completion: default_pass_completion() }
    }
}

fn default_pass_score() -> f32 {
    60.0
}

fn default_pass_completion() -> f32 {
    0.9
}

/// What the exercise asks of the trainee.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Goals {
    /// The region whose connective fibres must be cut so that the layers separate there.
    pub target: Region,
    /// Regions where nothing may be cut or torn. Default: none.
    #[serde(default)]
    pub forbidden: Vec<Region>,
    /// The incision asked for through the upper layer, a line through `(u, v)` points (fractions).
    /// Cutting the upper layer along it is the task, not damage. Default: none.
    #[serde(default)]
    pub incision: Vec<(f32, f32)>,
    /// Stretch (world length over rest length) above which the tissue is hurt. Default 1.6.
    #[serde(default = "default_stretch_limit")]
    pub stretch_limit: f32,
    /// Mean separation of the layers over the target that counts as separated, metres. Default 0.004.
    #[serde(default = "default_separation")]
    pub separation: f32,
    /// Path the instrument needs for a careful session, metres: the economy score is this over the
    /// path travelled. Default 0.3.
    #[serde(default = "default_path_reference")]
    pub path_reference_m: f32,
    /// Time allowed, seconds from the first instrument action. Default: none.
    #[serde(default)]
    pub time_limit_s: Option<f32>,
    /// Force on an instrument above which the tissue is handled too roughly, newtons. Default
    /// [`DEFAULT_FORCE_LIMIT`].
    #[serde(default = "default_force_limit")]
    pub force_limit: f32,
    /// What passing takes. Default: score 60, completion 0.9.
    #[serde(default)]
    pub pass: PassMark,
    /// The exercise's steps, shown as a checklist. Default: none.
    #[serde(default)]
    pub steps: Vec<Step>,
}

impl Goals {
    /// Goals with this target and every other field at its default.
    pub fn new(target: Region) -> Self {
        Self {
            target,
            forbidden: Vec::new(),
            incision: Vec::new(),
            stretch_limit: default_stretch_limit(),
            separation: default_separation(),
            path_reference_m: default_path_reference(),
            time_limit_s: None,
            force_limit: DEFAULT_FORCE_LIMIT,
            pass: PassMark::default(),
            steps: Vec::new(),
        }
    }
}

impl Goals {
    /// The target and the forbidden regions, to be drawn on the tissue.
    pub fn surface_regions(&self) -> Vec<SurfaceRegion> {
        std::iter::once(SurfaceRegion { kind: RegionKind::Target, shape: self.target.shape() })
            .chain(
                self.forbidden
                    .iter()
                    .map(|r| SurfaceRegion { kind: RegionKind::Forbidden, shape: r.shape() }),
            )
            .collect()
    }
}

/// Default force limit, newtons.
pub const DEFAULT_FORCE_LIMIT: f32 = 1.0;

fn default_force_limit() -> f32 {
    DEFAULT_FORCE_LIMIT
}

fn default_stretch_limit() -> f32 {
    1.6
}

fn default_path_reference() -> f32 {
    0.3
}

fn default_separation() -> f32 {
    0.004
}
