//! Training: the exercise's goals, the live assessment of how the trainee is doing, and the session
//! report. Surgical simulators score this kind of task by completion, tissue damage, force and economy
//! of motion; here the force proxy is the tissue's stretch.
//!
//! Must not import wgpu, winit or egui.

mod coach;
mod force;
mod goals;
mod plot;
mod report;
mod tally;

pub use coach::{Advice, AdviceLevel};
pub use force::{ForceAssessment, ForceStats, InstrumentForce};
pub use goals::{DEFAULT_FORCE_LIMIT, Goals, PassMark, Region, Step, StepCheck};
pub use report::{
    REPORT_SAMPLES, Report, ReportError, report_json, utc_date_time, utc_now_string, write_plot, write_report,
};

use glam::Vec2;
use serde::{Deserialize, Serialize};

use crate::chainmail::LinkId;
use crate::simulation::{InstrumentKind, World};
use crate::tissue::{LinkKind, Tissue};

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
    /// The score, higher is better (0 to 100).
    pub score: f32,
    /// Whether the session passes the goals' pass mark so far.
    pub passed: bool,
    /// The two things to improve most (or a word that nothing is), plain sentences.
    pub feedback: Vec<String>,
    /// Share of the task done, `0` to `1`: the target's fibres cut, averaged with the planned incision's
    /// share cut when the exercise has one.
    pub completion: f32,
    /// Share of the planned incision cut, `0` to `1` (`None` when the exercise has no incision).
    pub incision: Option<f32>,
    /// Share of the target's connective links cut, `0` to `1`.
    pub fibres: f32,
    /// Connective links in the target.
    pub target_links: u32,
    /// Of those, cut.
    pub target_links_cut: u32,
    /// The area of the layers' interface under the target that its fibres hold, square metres (the
    /// same at every resolution, where `target_links` is not).
    #[serde(default)]
    pub target_m2: f32,
    /// Mean separation of the layers over the target beyond their rest gap, metres.
    pub separation_m: f32,
    /// In-layer links cut away from the planned incision: collateral damage. A count of links, so it
    /// grows with the resolution; the score uses [`Assessment::layer_cut`].
    pub layer_links_cut: u64,
    /// How much of the layers was cut away from the planned incision: metres of cut line on a
    /// surface (square metres in a volume), the same for the same slip at every resolution.
    #[serde(default)]
    pub layer_cut: f32,
    /// Connective links cut outside the target: collateral damage (a count; the score uses
    /// [`Assessment::connective_cut_outside_m2`]).
    pub connective_cut_outside: u32,
    /// Area of connective tissue cut outside the target, square metres.
    #[serde(default)]
    pub connective_cut_outside_m2: f32,
    /// Links broken (cut or torn) inside a forbidden region (a count: any fails the session).
    pub forbidden_links_broken: u32,
    /// How much of the layers inside a forbidden region was broken: metres of cut or tear line on a
    /// surface (square metres in a volume).
    #[serde(default)]
    pub forbidden_layer: f32,
    /// Area of connective tissue broken inside a forbidden region, square metres.
    #[serde(default)]
    pub forbidden_connective_m2: f32,
    /// Links torn by over-stretching (a count).
    pub links_torn: u64,
    /// How much of the layers tore: metres of tear line on a surface (square metres in a volume).
    #[serde(default)]
    pub layer_torn: f32,
    /// Area of connective tissue torn, square metres.
    #[serde(default)]
    pub connective_torn_m2: f32,
    /// Whether the layers' amounts above are areas (a volume) rather than lengths (a surface).
    #[serde(default)]
    pub layers_are_areas: bool,
    /// Highest stretch seen since the clock started (the force proxy).
    pub peak_stretch: f32,
    /// Time spent with the stretch above the limit, seconds.
    pub time_above_limit_s: f32,
    /// Time since the first instrument action, seconds of simulation (0 until then).
    pub elapsed_s: f32,
    /// Whether the clock has started (the first grasp, cut or push).
    pub started: bool,
    /// Whether the time limit has passed.
    pub over_time: bool,
    /// Distance the instrument tip travelled since the clock started, metres.
    pub path_length_m: f32,
    /// Number of grasps.
    pub grasps: u32,
    /// Which of the goals' steps are done, in order.
    pub steps_done: Vec<bool>,
    /// How the score was made.
    pub breakdown: Vec<ScoreItem>,
    /// Forces on the instruments and on the forbidden region.
    pub force: ForceAssessment,
}

impl Assessment {
    /// How much tissue an amount is, in the trainee's words: "2.5 mm of layer and 3.0 mm² of
    /// fibres" for a layer's amount in metres (square metres in a volume) and a fibres' in square
    /// metres.
    pub fn amount(&self, layer: f32, fibre_m2: f32) -> String {
        amount_text(layer * layer_unit(self.layers_are_areas), fibre_m2 * 1e6, self.layers_are_areas)
    }
}

/// A point of the session's history, for the report's plot.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
pub struct Sample {
    /// Seconds since the clock started.
    pub t: f32,
    /// Completion then.
    pub completion: f32,
    /// The highest stretch since the sample before (so the plot's peak is the assessment's).
    pub stretch: f32,
    /// Force on the instrument in hand (or the clamp) then, newtons.
    #[serde(default)]
    pub force_n: f32,
}

/// History is sampled every this many seconds.
const SAMPLE_EVERY_S: f32 = 0.01;
/// Upper-layer links cut within this many element spacings of the planned incision are the task, not
/// damage (a hand does not follow a line exactly), and at least within this many
/// [`INCISION_SPACING_M`]: a finer mesh does not ask for a steadier hand.
const INCISION_ALLOWANCE: f32 = 1.5;
/// A point of the planned incision counts as cut when an upper-layer link within this many spacings
/// of it is cut (at least within this many [`INCISION_SPACING_M`]).
const INCISION_REACH: f32 = 1.0;
/// The spacing the incision's allowance and reach are counted in on finer meshes, metres: the
/// default exercise's at 64 × 48 (1.27 mm), rounded down so that those keep their own.
const INCISION_SPACING_M: f32 = 0.00125;
/// The planned incision is checked at points this many spacings apart.
const INCISION_STEP: f32 = 0.5;

/// What damage costs, per millimetre of a layer cut or torn (per square millimetre in a volume) and
/// per square millimetre of connective tissue: physical amounts, so the same slip costs the same at
/// every resolution. Set so that the default exercise at 64 × 48 (a layer link 1.27 mm wide, a fibre
/// for 3.2 mm² of interface) scores as it did when each link cost points: 2 a layer link cut, 1 a
/// fibre cut outside the target, 5 a link broken in a forbidden region, 2 a link torn.
#[derive(Clone, Copy, Debug)]
struct Rates {
    /// A layer cut away from the planned incision.
    layer_cut: f32,
    /// Connective tissue cut outside the target.
    fibre_cut: f32,
    /// A layer, then connective tissue, broken in a forbidden region.
    forbidden: [f32; 2],
    /// A layer, then connective tissue, torn.
    torn: [f32; 2],
}

const RATES: Rates = Rates { layer_cut: 1.6, fibre_cut: 0.3, forbidden: [4.0, 1.5], torn: [1.6, 0.6] };

/// "2.5 mm of layer and 3.0 mm² of fibres" for a layer's amount in millimetres (square millimetres
/// when `areas`) and a fibres' in square millimetres, leaving out a part that is nothing ("none" when
/// both are).
pub(crate) fn amount_text(layer: f32, fibre: f32, areas: bool) -> String {
    let lu = if areas { "mm²" } else { "mm" };
    match (layer > 0.0, fibre > 0.0) {
        (true, true) => format!("{layer:.1} {lu} of layer and {fibre:.1} mm² of fibres"),
        (false, true) => format!("{fibre:.1} mm² of fibres"),
        (true, false) => format!("{layer:.1} {lu} of layer"),
        (false, false) => "none".into(),
    }
}

/// The linear map from lattice coordinates to surface fractions, and back.
#[derive(Clone, Copy, Debug)]
struct Fractions {
    /// Lattice coordinates of fraction (0, 0).
    lo: Vec2,
    /// Metres per unit fraction along u and v.
    span: Vec2,
    /// Index of the lattice coordinate that `v` runs along (1 on a surface, 2 in a volume).
    kv: usize,
}

impl Fractions {
    fn of(tissue: &Tissue) -> Self {
        let f0 = tissue.surface_fractions([0.0; 3]);
        let f1 = tissue.surface_fractions([1.0; 3]);
        let kv = if tissue.surface_fractions([0.0, 1.0, 0.0]).1 != f0.1 { 1 } else { 2 };
        let span = Vec2::new(1.0 / (f1.0 - f0.0), 1.0 / (f1.1 - f0.1));
        Self { lo: -Vec2::new(f0.0, f0.1) * span, span, kv }
    }

    /// Lattice (u, v) coordinates, metres, of a fraction pair.
    fn lattice(&self, (u, v): (f32, f32)) -> Vec2 {
        self.lo + Vec2::new(u, v) * self.span
    }

    /// The in-surface part of a lattice point, metres.
    fn plane(&self, p: [f32; 3]) -> Vec2 {
        Vec2::new(p[0], p[self.kv])
    }
}

/// Distance from `p` to the segment from `a` to `b`.
fn point_segment_dist(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 { ((p - a).dot(ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    p.distance(a + t * ab)
}

/// Watches a world step by step and assesses it against the goals.
#[derive(Clone, Debug)]
pub struct Assessor {
    goals: Goals,
    dt: f32,
    /// Connective links whose foot lies in the target.
    target: Vec<LinkId>,
    /// The area they hold, square metres.
    target_m2: f32,
    /// Element pairs (lower, upper) in the target, for the separation.
    target_pairs: Vec<(u32, u32)>,
    /// What each link counts for: under the target, outside it, in a forbidden region, damage when
    /// cut, a point of the planned incision.
    roles: tally::Roles,
    /// What the links broken so far count for, taken in every step.
    tally: tally::Tally,
    /// Whether a layer's amounts are areas (a volume) rather than lengths (a surface).
    layers_are_areas: bool,
    rest_gap: f32,
    /// Steps observed.
    steps: u64,
    /// The step (of those observed) at which the clock started.
    started_at: Option<u64>,
    peak_stretch: f32,
    interval_peak: f32,
    steps_above: u64,
    path_length: f32,
    last_tip: Option<[f32; 3]>,
    grasping: bool,
    grasps: u32,
    /// The forceps held the tissue at some step since the last sample (for the checklist's `Grasp`).
    held_since_sample: bool,
    history: Vec<Sample>,
    next_sample: f32,
    force: force::ForceMeter,
    steps_done: Vec<bool>,
    /// Links torn so far, and how much of the layers and fibres (mm or mm², then mm²) they stand for.
    torn_seen: (u64, [f32; 2]),
    /// When links last tore (steps observed) and how much tore then (mm or mm² of layer, mm² of fibres).
    last_tear: Option<(u64, [f32; 2])>,
}

/// Millimetres per metre of a layer's amounts on a surface, square millimetres per square metre in
/// a volume.
fn layer_unit(areas: bool) -> f32 {
    if areas { 1e6 } else { 1e3 }
}

impl Assessor {
    /// How much tore so far: millimetres of layer (square millimetres in a volume), then square
    /// millimetres of fibres.
    fn torn(&self, damage: &crate::tissue::Damage) -> [f32; 2] {
        [damage.layer_torn * layer_unit(self.layers_are_areas), damage.connective_torn_m2 * 1e6]
    }

    /// An assessor for `goals` on `world`'s tissue, reading time from the world's step length.
    pub fn new(goals: Goals, world: &World) -> Self {
        let tissue = world.tissue();
        let rest = tissue.body().lattice().rest_positions();
        let frac = Fractions::of(tissue);
        let spacing = tissue.spacing();
        // Where the incision is judged, spacings in metres no finer than INCISION_SPACING_M.
        let judged = spacing.max(INCISION_SPACING_M);
        let line: Vec<Vec2> = goals.incision.iter().map(|&p| frac.lattice(p)).collect();
        let mut points = Vec::new();
        for w in line.windows(2) {
            let len = w[0].distance(w[1]);
            let n = ((len / (INCISION_STEP * spacing)).ceil() as usize).max(1);
            for k in 0..n {
                let t = k as f32 / n as f32;
                points.push(w[0].lerp(w[1], t));
            }
        }
        if let Some(&last) = line.last() {
            points.push(last);
        }
        // Layers count from the upper one.
        let upper = LinkKind::Layer(0);
        let (mut target, mut target_pairs) = (vec![], vec![]);
        let layers_are_areas = matches!(tissue.geometry(), crate::tissue::Geometry::Volume);
        let mut roles = tally::Roles {
            bits: vec![0; tissue.body().link_count()],
            incision: Vec::new(),
            points: points.len(),
            layer_unit: layer_unit(layers_are_areas),
        };
        let mut rest_gap = 0.0;
        for (l, bits) in roles.bits.iter_mut().enumerate() {
            let id = LinkId(l as u32);
            let Some([a, b]) = tissue.body().lattice().link_ends(id) else { continue };
            let (pa, pb) = (rest[a.index()], rest[b.index()]);
            let mid = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])];
            let (u, v) = tissue.surface_fractions(mid);
            let connective = tissue.link_kind(id) == Some(LinkKind::Connective);
            if goals.forbidden.iter().any(|r| r.contains(u, v)) {
                *bits |= if connective { tally::FORBIDDEN_FIBRE } else { tally::FORBIDDEN_LAYER };
            }
            match tissue.link_kind(id) {
                Some(LinkKind::Connective) => {
                    *bits |= tally::CONNECTIVE;
                    if goals.target.contains(u, v) {
                        *bits |= tally::TARGET;
                        target.push(id);
                        target_pairs.push((a.0, b.0));
                        rest_gap = (pb[2] - pa[2]).abs();
                    } else {
                        *bits |= tally::OUTSIDE;
                    }
                }
                Some(kind) => {
                    let m = frac.plane(mid);
                    let near = kind == upper
                        && line
                            .windows(2)
                            .any(|w| point_segment_dist(m, w[0], w[1]) <= INCISION_ALLOWANCE * judged);
                    if !near {
                        *bits |= tally::PENALISED;
                    }
                    if kind == upper {
                        for (k, p) in points.iter().enumerate() {
                            if m.distance_squared(*p) <= (INCISION_REACH * judged).powi(2) {
                                *bits |= tally::INCISION;
                                roles.incision.push((id.0, k as u32));
                            }
                        }
                    }
                }
                None => {}
            }
        }
        let mut tally = tally::Tally::default();
        tally.absorb(&roles, tissue);
        let target_m2 = target.iter().fold(0.0, |sum, &l| sum + tissue.link_extent(l));
        let tissue = world.tissue();
        let in_forbidden =
            force::elements_in(tissue, |u, v| goals.forbidden.iter().any(|r| r.contains(u, v)));
        let force = force::ForceMeter::new(goals.force_limit, world.step_seconds() as f32, in_forbidden);
        let steps_done = vec![false; goals.steps.len()];
        Self {
            goals,
            dt: world.step_seconds() as f32,
            target,
            target_m2,
            target_pairs,
            roles,
            tally,
            layers_are_areas,
            rest_gap,
            steps: 0,
            started_at: None,
            peak_stretch: 1.0,
            interval_peak: 1.0,
            steps_above: 0,
            path_length: 0.0,
            last_tip: None,
            grasping: false,
            grasps: 0,
            held_since_sample: false,
            history: Vec::new(),
            next_sample: 0.0,
            force,
            steps_done,
            torn_seen: (0, [0.0; 2]),
            last_tear: None,
        }
    }

    /// The goals.
    pub fn goals(&self) -> &Goals {
        &self.goals
    }

    /// Seconds since the clock started (0 until the first instrument action).
    pub fn elapsed_s(&self) -> f32 {
        self.started_at.map_or(0.0, |s| (self.steps - s) as f32 * self.dt)
    }

    /// Whether the clock has started: the first grasp, cut or push.
    pub fn started(&self) -> bool {
        self.started_at.is_some()
    }

    /// Call after every step.
    pub fn observe(&mut self, world: &World) {
        self.steps += 1;
        self.tally.absorb(&self.roles, world.tissue());
        let inst = world.instrument();
        if self.started_at.is_none() {
            let pushing = inst.kind == InstrumentKind::Probe && world.last_step().moved_chain > 0;
            if inst.grasped.is_none() && !inst.cutting && !pushing {
                return;
            }
            self.started_at = Some(self.steps - 1);
        }
        let stretch = world.tissue().max_stretch();
        self.peak_stretch = self.peak_stretch.max(stretch);
        self.interval_peak = self.interval_peak.max(stretch);
        if stretch > self.goals.stretch_limit {
            self.steps_above += 1;
        }
        if let Some(last) = self.last_tip {
            self.path_length += glam::Vec3::from(inst.target).distance(glam::Vec3::from(last));
        }
        self.last_tip = Some(inst.target);
        let grasping = inst.grasped.is_some();
        if grasping && !self.grasping {
            self.grasps += 1;
        }
        self.grasping = grasping;
        self.held_since_sample |= grasping;
        self.force.observe(world);
        let damage = world.tissue().damage();
        if damage.links_torn > self.torn_seen.0 {
            let amount = self.torn(&damage);
            let before = self
                .last_tear
                .filter(|(s, _)| self.steps - s < self.coach_window())
                .map_or([0.0; 2], |t| t.1);
            let seen = self.torn_seen.1;
            let new = [0, 1].map(|k| before[k] + amount[k] - seen[k]);
            self.last_tear = Some((self.steps, new));
            self.torn_seen = (damage.links_torn, amount);
        }
        let t = self.elapsed_s();
        if t >= self.next_sample {
            self.next_sample = t + SAMPLE_EVERY_S;
            let (completion, _, _, _) = self.completion(world.tissue());
            self.history.push(Sample {
                t,
                completion,
                stretch: self.interval_peak,
                force_n: self.force.last(),
            });
            self.interval_peak = 1.0;
            if self.steps_done.iter().any(|d| !d) {
                let separation = self.separation(world.tissue());
                for (k, step) in self.goals.steps.iter().enumerate() {
                    if self.steps_done[k] {
                        continue;
                    }
                    self.steps_done[k] = match step.done {
                        // A lift counts once the incision steps listed above it are done (the flap is
                        // free): the dura grasped and lifted before the U is cut is not that step.
                        StepCheck::Grasp => {
                            self.held_since_sample
                                && self.goals.steps[..k]
                                    .iter()
                                    .zip(&self.steps_done)
                                    .all(|(s, &done)| done || !matches!(s.done, StepCheck::Incision(_)))
                        }
                        StepCheck::Incision(x) => self.incision_share(world.tissue()).is_some_and(|s| s >= x),
                        StepCheck::Fibres(x) => self.fibre_share(world.tissue()).0 >= x,
                        StepCheck::Separation(x) => separation >= x,
                    };
                }
            }
            self.held_since_sample = false;
        }
    }

    /// Steps within which tears are reported together by the coach (3 seconds).
    fn coach_window(&self) -> u64 {
        (3.0 / self.dt) as u64
    }

    /// What the links broken so far count for, with anything broken since the last step.
    fn tally(&self, tissue: &Tissue) -> std::borrow::Cow<'_, tally::Tally> {
        self.tally.now(&self.roles, tissue)
    }

    /// The share of the target's fibres cut, and how many.
    fn fibre_share(&self, tissue: &Tissue) -> (f32, u32) {
        let cut = self.tally(tissue).target;
        let share = if self.target.is_empty() { 0.0 } else { cut as f32 / self.target.len() as f32 };
        (share, cut)
    }

    fn incision_share(&self, tissue: &Tissue) -> Option<f32> {
        Self::incision_of(&self.tally(tissue), self.roles.points)
    }

    fn incision_of(tally: &tally::Tally, points: usize) -> Option<f32> {
        (points > 0).then(|| tally.incision as f32 / points as f32)
    }

    /// (completion, incision share, fibre share, target fibres cut).
    fn completion(&self, tissue: &Tissue) -> (f32, Option<f32>, f32, u32) {
        let (fibres, cut) = self.fibre_share(tissue);
        let incision = self.incision_share(tissue);
        let completion = incision.map_or(fibres, |i| 0.5 * (i + fibres));
        (completion, incision, fibres, cut)
    }

    fn separation(&self, tissue: &Tissue) -> f32 {
        if self.target_pairs.is_empty() {
            return 0.0;
        }
        let p = tissue.body().positions();
        let sum: f32 =
            self.target_pairs.iter().map(|&(a, b)| p[b as usize][2] - p[a as usize][2] - self.rest_gap).sum();
        sum / self.target_pairs.len() as f32
    }

    /// The history so far (one sample per 10 ms of simulation since the clock started).
    pub fn history(&self) -> &[Sample] {
        &self.history
    }

    /// Every figure, the score with its breakdown, pass or fail, and the feedback.
    pub fn assessment(&self, world: &World) -> Assessment {
        let tissue = world.tissue();
        let (completion, incision, fibres, cut) = self.completion(tissue);
        let separation = self.separation(tissue);
        let damage = tissue.damage();
        // Links broken, and the same damage in physical amounts (mm of a layer on a surface, mm²
        // otherwise).
        let tally = self.tally(tissue);
        let amount_of = |(n, sum): (u32, f64)| (n, sum as f32);
        let (layer_cut, layer_mm) = amount_of(tally.layer_cut);
        let (outside, outside_mm2) = amount_of(tally.outside);
        let [(forbidden_layer, forbidden_layer_mm), (forbidden_fibres, forbidden_fibres_mm2)] =
            tally.forbidden.map(amount_of);
        let (forbidden, forbidden_mm) =
            (forbidden_layer + forbidden_fibres, [forbidden_layer_mm, forbidden_fibres_mm2]);
        let torn_mm = self.torn(&damage);
        let (areas, layer_unit) = (self.layers_are_areas, layer_unit(self.layers_are_areas));
        let lu = if areas { "mm²" } else { "mm" };
        let r = RATES;
        let forbidden_points = r.forbidden[0] * forbidden_mm[0] + r.forbidden[1] * forbidden_mm[1];
        let torn_points = r.torn[0] * torn_mm[0] + r.torn[1] * torn_mm[1];
        let amount = |[layer, fibre]: [f32; 2]| amount_text(layer, fibre, areas);
        let elapsed = self.elapsed_s();
        let above = self.steps_above as f32 * self.dt;
        let over_time = self.goals.time_limit_s.is_some_and(|l| elapsed > l);
        let g = &self.goals;
        let sep_share = (separation / g.separation).clamp(0.0, 1.0);
        let economy = if self.path_length > 0.0 {
            (g.path_reference_m / self.path_length).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let task = if incision.is_some() {
            "completion (60 x share of the incision and the target fibres cut)"
        } else {
            "completion (60 x share of target fibres cut)"
        };
        let mut breakdown = vec![
            ScoreItem { label: task.into(), points: 60.0 * completion },
            ScoreItem {
                label: "separation (20 x layer separation over the target up to the goal, x completion)"
                    .into(),
                points: 20.0 * sep_share * completion,
            },
            ScoreItem {
                label: "economy (20 x reference path over path length, x completion)".into(),
                points: 20.0 * economy * completion,
            },
            ScoreItem {
                label: if incision.is_some() {
                    format!("layers cut off the planned incision (-{} per {lu})", r.layer_cut)
                } else {
                    format!("layers cut (-{} per {lu})", r.layer_cut)
                },
                points: 0.0 - r.layer_cut * layer_mm,
            },
            ScoreItem {
                label: format!("fibres cut outside the target (-{} per mm²)", r.fibre_cut),
                points: 0.0 - r.fibre_cut * outside_mm2,
            },
            ScoreItem {
                label: format!(
                    "tissue broken in a forbidden region (-{} per {lu} of layer, -{} per mm² of fibres)",
                    r.forbidden[0], r.forbidden[1]
                ),
                points: 0.0 - forbidden_points,
            },
            ScoreItem {
                label: format!(
                    "tissue torn (-{} per {lu} of layer, -{} per mm² of fibres)",
                    r.torn[0], r.torn[1]
                ),
                points: 0.0 - torn_points,
            },
            ScoreItem {
                label: "time above the stretch limit (-10 per second)".into(),
                // (`0.0 -`: no time above reads +0.0, where `-10.0 * 0.0` is -0.0.)
                points: 0.0 - 10.0 * above,
            },
        ];
        if over_time {
            breakdown.push(ScoreItem { label: "over the time limit".into(), points: -10.0 });
        }
        let score = breakdown.iter().map(|i| i.points).sum::<f32>().clamp(0.0, 100.0);
        let passed = score >= g.pass.score && completion >= g.pass.completion && forbidden == 0;

        // What cost the most points, in the trainee's words.
        let upper = tissue.layers().first().map_or("upper layer", |l| l.name.as_str());
        let fibre_weight = if incision.is_some() { 30.0 } else { 60.0 };
        let mut lost: Vec<(f32, String)> = Vec::new();
        if let Some(i) = incision {
            lost.push((
                30.0 * (1.0 - i),
                format!(
                    "Finish the incision: {:.0} % of the planned line through the {upper} is cut (see the exercise's steps).",
                    100.0 * i
                ),
            ));
        }
        lost.push((
            fibre_weight * (1.0 - fibres),
            format!(
                "Cut the fibres under the target: {:.0} % of its {:.0} mm² cut (scalpel at depth B, under the lifted {upper}).",
                100.0 * fibres,
                1e6 * self.target_m2
            ),
        ));
        lost.push((
            20.0 * (1.0 - sep_share) * completion.max(0.25),
            separation_advice(upper, separation, g.separation),
        ));
        lost.push((
            20.0 * (1.0 - economy) * completion,
            format!(
                "Move more economically: the instrument travelled {:.0} mm; a careful session needs about {:.0} mm.",
                1000.0 * self.path_length,
                1000.0 * g.path_reference_m
            ),
        ));
        lost.push((
            r.layer_cut * layer_mm,
            if incision.is_some() {
                format!(
                    "Cut only along the planned incision, at depth U: {layer_mm:.1} {lu} of the layers cut elsewhere."
                )
            } else {
                format!(
                    "Do not cut through the layers (depth B cuts only the fibres): {layer_mm:.1} {lu} of them cut."
                )
            },
        ));
        lost.push((
            r.fibre_cut * outside_mm2,
            format!("Keep the fibre cuts under the target: {outside_mm2:.1} mm² of fibres cut outside it."),
        ));
        lost.push((
            forbidden_points,
            format!(
                "Stay clear of the forbidden region (the vessel): {} broken there.",
                amount(forbidden_mm)
            ),
        ));
        lost.push((
            torn_points,
            format!(
                "Pull more gently, and cut what holds the tissue first: {} stretched until it tore.",
                amount(torn_mm)
            ),
        ));
        lost.push((
            10.0 * above,
            format!("Ease off sooner: {above:.1} s above the stretch limit of {:.2}.", g.stretch_limit),
        ));
        if over_time {
            lost.push((
                10.0,
                format!("Work faster: over the time limit of {:.0} s.", g.time_limit_s.unwrap_or(0.0)),
            ));
        }
        lost.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut feedback: Vec<String> =
            lost.into_iter().filter(|(p, _)| *p >= 0.5).take(2).map(|(_, s)| s).collect();
        if feedback.is_empty() {
            feedback.push("Nothing to improve: a clean, complete dissection.".into());
        }
        Assessment {
            score,
            passed,
            feedback,
            completion,
            incision,
            fibres,
            target_links: self.target.len() as u32,
            target_links_cut: cut,
            target_m2: self.target_m2,
            separation_m: separation,
            layer_links_cut: layer_cut.into(),
            layer_cut: layer_mm / layer_unit,
            connective_cut_outside: outside,
            connective_cut_outside_m2: outside_mm2 * 1e-6,
            forbidden_links_broken: forbidden,
            forbidden_layer: forbidden_mm[0] / layer_unit,
            forbidden_connective_m2: forbidden_mm[1] * 1e-6,
            links_torn: damage.links_torn,
            layer_torn: damage.layer_torn,
            connective_torn_m2: damage.connective_torn_m2,
            layers_are_areas: areas,
            peak_stretch: self.peak_stretch,
            time_above_limit_s: above,
            elapsed_s: elapsed,
            started: self.started(),
            over_time,
            path_length_m: self.path_length,
            grasps: self.grasps,
            steps_done: self.steps_done.clone(),
            breakdown,
            force: self.force.assessment(),
        }
    }

    /// The session report: the assessment first, then the goals and the history sampled to at most
    /// [`REPORT_SAMPLES`] points (each keeping the highest stretch of the samples it stands for, so the
    /// plot's peak is the assessment's).
    pub fn report(&self, world: &World, title: &str, date: String) -> Report {
        let assessment = self.assessment(world);
        let mut history = self.history.clone();
        if self.started() && self.interval_peak > 1.0 {
            // The stretch since the last sample, so no peak is left out.
            let (completion, ..) = self.completion(world.tissue());
            history.push(Sample {
                t: self.elapsed_s(),
                completion,
                stretch: self.interval_peak,
                force_n: self.force.last(),
            });
        }
        Report {
            title: title.to_string(),
            date,
            passed: assessment.passed,
            score: assessment.score,
            feedback: assessment.feedback.clone(),
            goals: self.goals.clone(),
            assessment,
            history: report::downsample(&history, REPORT_SAMPLES),
        }
    }
}

/// What to do about the layers' separation over the target (`separation` and `goal` in metres), with
/// the figure the assessment panel shows: below the rest gap (the lifted layer pushed towards the one
/// under it) it says so, rather than "0.0 mm apart" beside a panel's "-1.1 mm".
fn separation_advice(upper: &str, separation: f32, goal: f32) -> String {
    let (mm, goal_mm) = (1000.0 * separation, 1000.0 * goal);
    if (10.0 * mm).round() < 0.0 {
        format!(
            "Lift the {upper} clear: it is pressed {:.1} mm closer to the layer under it than at rest \
             over the target (separation {mm:.1} mm), the goal is {goal_mm:.1} mm apart.",
            -mm
        )
    } else {
        let mm = mm.max(0.0);
        format!(
            "Lift the {upper} clear: the layers are {mm:.1} mm apart over the target, the goal is {goal_mm:.1} mm."
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amounts_read_in_millimetres_and_leave_out_what_is_nothing() {
        let surface = Assessment::default();
        assert_eq!(surface.amount(0.0, 0.0), "none");
        assert_eq!(surface.amount(0.005, 0.0), "5.0 mm of layer");
        assert_eq!(surface.amount(0.0, 2.5e-6), "2.5 mm² of fibres");
        assert_eq!(surface.amount(0.0125, 3e-5), "12.5 mm of layer and 30.0 mm² of fibres");
        let volume = Assessment { layers_are_areas: true, ..Assessment::default() };
        assert_eq!(volume.amount(4e-6, 0.0), "4.0 mm² of layer");
    }

    /// The tally the assessor takes in as links break (each step reading only what broke since) is
    /// what reading every link finds, every 10 steps of sessions that cut the target's fibres, cut
    /// an incision, slip into a forbidden region and tear; and nothing broken reads as zero, not
    /// negative zero (shown as "-0.0" otherwise).
    #[test]
    fn the_tally_taken_in_as_links_break_is_what_reading_every_link_finds() {
        use crate::chainmail::BreakReason;
        use crate::runner::{Episode, Player, Source};
        use crate::scene::{Scene, Script};
        let near = |x: (u32, f64), y: (u32, f64)| x.0 == y.0 && (x.1 - y.1).abs() <= 1e-9 * y.1.abs();
        let same = |kept: &tally::Tally, read: &tally::Tally| {
            kept.target == read.target
                && kept.incision == read.incision
                && near(kept.layer_cut, read.layer_cut)
                && near(kept.outside, read.outside)
                && near(kept.forbidden[0], read.forbidden[0])
                && near(kept.forbidden[1], read.forbidden[1])
        };
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut seen = tally::Tally::default();
        let mut most = |t: &tally::Tally| {
            seen.target = seen.target.max(t.target);
            seen.incision = seen.incision.max(t.incision);
            let [f0, f1] = &mut seen.forbidden;
            for (m, x) in [
                (&mut seen.layer_cut, t.layer_cut),
                (&mut seen.outside, t.outside),
                (f0, t.forbidden[0]),
                (f1, t.forbidden[1]),
            ] {
                m.0 = m.0.max(x.0);
            }
        };
        for (scene, script) in [
            ("meninges", "meninges_careful"),
            ("meninges", "meninges_careless"),
            ("meninges", "meninges_slips"),
            ("durotomy", "durotomy_careful"),
            ("durotomy", "durotomy_careless"),
        ] {
            let scene = Scene::load(dir.join(format!("{scene}.ron"))).expect("scene").with_resolution(48, 36);
            let script = Script::load(dir.join(format!("scripts/{script}.ron"))).expect("script");
            let world = scene.build_world(false).expect("world");
            let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
            let mut episode = Episode::new(world, assessor, Source::Script(Player::new(script.0)));
            let zero = episode.assessor().expect("goals").assessment(episode.world());
            assert!(zero.layer_cut.is_sign_positive() && zero.connective_cut_outside_m2.is_sign_positive());
            let mut steps = 0;
            loop {
                let done = episode.step().is_none();
                steps += 1;
                if done || steps % 10 == 0 {
                    let a = episode.assessor().expect("goals");
                    let tissue = episode.world().tissue();
                    let (kept, read) = (a.tally(tissue), tally::Tally::scan(&a.roles, tissue));
                    assert!(same(&kept, &read), "step {steps}: {kept:?} against {read:?}");
                    most(&read);
                }
                if done {
                    break;
                }
            }
            // Then tears and cuts everywhere, as no script makes them: a tear along the incision or
            // where cutting is damage counts for neither (the scripts tear nothing now).
            for (every, reason) in [(7, BreakReason::Tear), (11, BreakReason::Cut)] {
                let body = episode.world_mut().tissue_mut().body_mut();
                for l in (0..body.link_count()).step_by(every) {
                    body.break_link(LinkId(l as u32), reason).expect("a link");
                }
                let a = episode.assessor().expect("goals");
                let tissue = episode.world().tissue();
                let (kept, read) = (a.tally(tissue), tally::Tally::scan(&a.roles, tissue));
                assert!(same(&kept, &read), "{reason:?}: {kept:?} against {read:?}");
            }
        }
        // Every kind of damage and progress was there to count.
        assert!(
            seen.target > 0
                && seen.incision > 0
                && seen.layer_cut.0 > 0
                && seen.outside.0 > 0
                && seen.forbidden.iter().any(|f| f.0 > 0),
            "{seen:?}"
        );
    }

    /// The separation's advice states the panel's figure, pressed together included.
    #[test]
    fn separation_advice_states_the_panels_figure() {
        assert_eq!(
            separation_advice("dura", 0.0021, 0.004),
            "Lift the dura clear: the layers are 2.1 mm apart over the target, the goal is 4.0 mm."
        );
        assert_eq!(
            separation_advice("dura", -0.0011, 0.004),
            "Lift the dura clear: it is pressed 1.1 mm closer to the layer under it than at rest \
             over the target (separation -1.1 mm), the goal is 4.0 mm apart."
        );
        // What rounds to zero reads as zero apart, not as pressed by 0.0 mm.
        assert!(separation_advice("dura", -1e-5, 0.004).contains("are 0.0 mm apart"));
    }
}
