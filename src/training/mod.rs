//! Training: the exercise's goals, the live assessment of how the trainee is doing, and the session
//! report. Surgical simulators score this kind of task by completion, tissue damage, force and economy
//! of motion; here the force proxy is the tissue's stretch.
//!
//! Must not import wgpu, winit or egui.

mod report;

pub use report::{ReportError, write_plot, write_report};

use serde::{Deserialize, Serialize};

use crate::chainmail::LinkId;
use crate::simulation::World;
use crate::tissue::{LinkKind, Tissue};

/// A region of the tissue's surface, in fractions of the `u` and `v` extents (`0` to `1`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
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

/// What the exercise asks of the trainee.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Goals {
    /// The region whose connective fibres must be cut so that the layers separate there.
    pub target: Region,
    /// Regions where nothing may be cut or torn. Default: none.
    #[serde(default)]
    pub forbidden: Vec<Region>,
    /// Stretch (world length over rest length) above which the tissue is hurt. Default 1.6.
    #[serde(default = "default_stretch_limit")]
    pub stretch_limit: f32,
    /// Mean separation of the layers over the target that counts as separated, metres. Default 0.004.
    #[serde(default = "default_separation")]
    pub separation: f32,
    /// Time allowed, seconds. Default: none.
    #[serde(default)]
    pub time_limit_s: Option<f32>,
}

fn default_stretch_limit() -> f32 {
    1.6
}

fn default_separation() -> f32 {
    0.004
}

/// One line of the score's breakdown.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct ScoreItem {
    /// What was scored.
    pub label: String,
    /// Points, positive or negative.
    pub points: f32,
}

/// How the trainee is doing, every figure of the report.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Assessment {
    /// Share of the target's connective links cut, `0` to `1`.
    pub completion: f32,
    /// Connective links in the target.
    pub target_links: u32,
    /// Of those, cut.
    pub target_links_cut: u32,
    /// Mean separation of the layers over the target beyond their rest gap, metres.
    pub separation_m: f32,
    /// In-layer links cut (incisions in a layer): collateral damage.
    pub layer_links_cut: u64,
    /// Connective links cut outside the target: collateral damage.
    pub connective_cut_outside: u32,
    /// Links broken (cut or torn) inside a forbidden region.
    pub forbidden_links_broken: u32,
    /// Links torn by over-stretching.
    pub links_torn: u64,
    /// Highest stretch seen (the force proxy).
    pub peak_stretch: f32,
    /// Time spent with the stretch above the limit, seconds.
    pub time_above_limit_s: f32,
    /// Time since the start, seconds of simulation.
    pub elapsed_s: f32,
    /// Whether the time limit has passed.
    pub over_time: bool,
    /// Distance the instrument tip travelled, metres.
    pub path_length_m: f32,
    /// Number of grasps.
    pub grasps: u32,
    /// The score, higher is better (0 to 100).
    pub score: f32,
    /// How the score was made.
    pub breakdown: Vec<ScoreItem>,
}

/// A point of the session's history, for the report's plot.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Sample {
    /// Seconds of simulation.
    pub t: f32,
    /// Completion then.
    pub completion: f32,
    /// Stretch then.
    pub stretch: f32,
}

/// Reference path length for the economy score, metres: a careful session needs about this much.
const REFERENCE_PATH_M: f32 = 0.3;
/// History is sampled every this many seconds.
const SAMPLE_EVERY_S: f32 = 0.01;

/// Watches a world step by step and assesses it against the goals.
#[derive(Clone, Debug)]
pub struct Assessor {
    goals: Goals,
    dt: f32,
    /// Connective links whose foot lies in the target.
    target: Vec<LinkId>,
    /// Element pairs (lower, upper) in the target, for the separation.
    target_pairs: Vec<(u32, u32)>,
    /// Connective links outside the target.
    outside: Vec<LinkId>,
    /// Links (any kind) in a forbidden region.
    forbidden: Vec<LinkId>,
    rest_gap: f32,
    steps: u64,
    peak_stretch: f32,
    steps_above: u64,
    path_length: f32,
    last_tip: Option<[f32; 3]>,
    grasping: bool,
    grasps: u32,
    history: Vec<Sample>,
    next_sample: f32,
}

impl Assessor {
    /// An assessor for `goals` on `world`'s tissue, reading time from the world's step length.
    pub fn new(goals: Goals, world: &World) -> Self {
        let tissue = world.tissue();
        let rest = tissue.body().lattice().rest_positions();
        let (mut target, mut outside, mut forbidden, mut target_pairs) = (vec![], vec![], vec![], vec![]);
        let mut rest_gap = 0.0;
        for l in 0..tissue.body().link_count() {
            let id = LinkId(l as u32);
            let Some([a, b]) = tissue.body().lattice().link_ends(id) else { continue };
            let (pa, pb) = (rest[a.index()], rest[b.index()]);
            let mid = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])];
            let (u, v) = tissue.surface_fractions(mid);
            if goals.forbidden.iter().any(|r| r.contains(u, v)) {
                forbidden.push(id);
            }
            if tissue.link_kind(id) == Some(LinkKind::Connective) {
                if goals.target.contains(u, v) {
                    target.push(id);
                    target_pairs.push((a.0, b.0));
                    rest_gap = (pb[2] - pa[2]).abs();
                } else {
                    outside.push(id);
                }
            }
        }
        Self {
            goals,
            dt: world.step_seconds() as f32,
            target,
            target_pairs,
            outside,
            forbidden,
            rest_gap,
            steps: 0,
            peak_stretch: 1.0,
            steps_above: 0,
            path_length: 0.0,
            last_tip: None,
            grasping: false,
            grasps: 0,
            history: Vec::new(),
            next_sample: 0.0,
        }
    }

    /// The goals.
    pub fn goals(&self) -> &Goals {
        &self.goals
    }

    /// Call after every step.
    pub fn observe(&mut self, world: &World) {
        self.steps += 1;
        let stretch = world.tissue().max_stretch();
        self.peak_stretch = self.peak_stretch.max(stretch);
        if stretch > self.goals.stretch_limit {
            self.steps_above += 1;
        }
        let inst = world.instrument();
        if let Some(last) = self.last_tip {
            self.path_length += glam::Vec3::from(inst.target).distance(glam::Vec3::from(last));
        }
        self.last_tip = Some(inst.target);
        let grasping = inst.grasped.is_some();
        if grasping && !self.grasping {
            self.grasps += 1;
        }
        self.grasping = grasping;
        let t = self.steps as f32 * self.dt;
        if t >= self.next_sample {
            self.next_sample = t + SAMPLE_EVERY_S;
            let completion = self.completion(world.tissue()).0;
            self.history.push(Sample { t, completion, stretch });
        }
    }

    fn completion(&self, tissue: &Tissue) -> (f32, u32) {
        let cut = self.target.iter().filter(|&&l| !tissue.body().link_intact(l)).count() as u32;
        let share = if self.target.is_empty() { 0.0 } else { cut as f32 / self.target.len() as f32 };
        (share, cut)
    }

    /// The history so far (one sample per 10 ms of simulation).
    pub fn history(&self) -> &[Sample] {
        &self.history
    }

    /// Every figure, and the score with its breakdown.
    pub fn assessment(&self, world: &World) -> Assessment {
        let tissue = world.tissue();
        let (completion, cut) = self.completion(tissue);
        let body = tissue.body();
        let separation = if self.target_pairs.is_empty() {
            0.0
        } else {
            let sum: f32 = self
                .target_pairs
                .iter()
                .map(|&(a, b)| {
                    body.positions()[b as usize][2] - body.positions()[a as usize][2] - self.rest_gap
                })
                .sum();
            sum / self.target_pairs.len() as f32
        };
        let damage = tissue.damage();
        let outside = self.outside.iter().filter(|&&l| body.link_broken(l).is_some()).count() as u32;
        let forbidden = self.forbidden.iter().filter(|&&l| body.link_broken(l).is_some()).count() as u32;
        let elapsed = self.steps as f32 * self.dt;
        let above = self.steps_above as f32 * self.dt;
        let over_time = self.goals.time_limit_s.is_some_and(|l| elapsed > l);
        let mut breakdown = vec![
            ScoreItem {
                label: "completion (60 x share of target fibres cut)".into(),
                points: 60.0 * completion,
            },
            ScoreItem {
                label: "separation (20 x mean layer separation over the target, up to the goal)".into(),
                points: 20.0 * (separation / self.goals.separation).clamp(0.0, 1.0),
            },
            ScoreItem {
                label: "economy (20 x reference path over path length)".into(),
                points: if self.path_length > 0.0 {
                    20.0 * (REFERENCE_PATH_M / self.path_length).clamp(0.0, 1.0)
                } else {
                    0.0
                },
            },
            ScoreItem {
                label: "layer links cut (-2 each)".into(),
                points: -2.0 * damage.layer_links_cut as f32,
            },
            ScoreItem { label: "fibres cut outside the target (-1 each)".into(), points: -(outside as f32) },
            ScoreItem {
                label: "links broken in a forbidden region (-5 each)".into(),
                points: -5.0 * forbidden as f32,
            },
            ScoreItem { label: "links torn (-2 each)".into(), points: -2.0 * damage.links_torn as f32 },
            ScoreItem {
                label: "time above the stretch limit (-10 per second)".into(),
                points: -10.0 * above,
            },
        ];
        if over_time {
            breakdown.push(ScoreItem { label: "over the time limit".into(), points: -10.0 });
        }
        let score = breakdown.iter().map(|i| i.points).sum::<f32>().clamp(0.0, 100.0);
        Assessment {
            completion,
            target_links: self.target.len() as u32,
            target_links_cut: cut,
            separation_m: separation,
            layer_links_cut: damage.layer_links_cut,
            connective_cut_outside: outside,
            forbidden_links_broken: forbidden,
            links_torn: damage.links_torn,
            peak_stretch: self.peak_stretch,
            time_above_limit_s: above,
            elapsed_s: elapsed,
            over_time,
            path_length_m: self.path_length,
            grasps: self.grasps,
            score,
            breakdown,
        }
    }
}
