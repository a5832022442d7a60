//! Scripts: a list of timed instrument actions, executed in order, one simulation step at a time.
//! Used to reproduce an exercise without a person (tests, figures, benchmarks) and to record one.
//!
//! Timing: every action starts when the one before it ends. `Select`, `Grasp` and `Release` take no
//! steps; `MoveTo`, `Cut` and `Push` take `steps`; `Wait(n)` takes `n`; `At(n)` waits until step `n`
//! (counted from 0 at the start of the run) and takes no time if that step has passed.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::snapshot::{CameraSpec, InstrumentKind};

use super::error::{FieldPath, Problem, SceneError, parse_error, problem};
use super::validate::{finite, within};

/// Longest script or recording, in steps: its last action must end by step 10 000 000 (2.8 hours at
/// 1000 steps per second). `dissect run --steps` takes at most as many.
pub const MAX_SCRIPT_STEPS: u64 = 10_000_000;

/// A script: actions executed in order. RON: `Script([ Select(Forceps), ... ])`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Script(pub Vec<Action>);

/// A place the instrument goes to.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub enum Point {
    /// `Surface(u, v, offset)`: on the scene's base surface at fractions `u, v` in `[0, 1]`, then
    /// `offset` metres along the outward normal (e.g. a layer's offset to touch that layer).
    Surface(f32, f32, f32),
    /// `World(x, y, z)`: a position in world space, metres.
    World(f32, f32, f32),
}

pub use crate::tissue::CutDepth;

/// One action of a script.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Action {
    /// Take up an instrument. No time. Tissue the forceps hold stays clamped where it is while another
    /// instrument is in use (the paper's two-handed teasing apart); selecting the forceps again takes
    /// it back, and only `Release` lets it go.
    Select(InstrumentKind),
    /// Forceps: move to the point at once and close the jaws on the nearest element. No time.
    Grasp(Point),
    /// Move the instrument (and what it holds) in a straight line to `to` over `steps` steps.
    MoveTo {
        /// Where to.
        to: Point,
        /// Duration in steps, at least 1.
        steps: u32,
    },
    /// Forceps: open the jaws. No time.
    Release,
    /// Scalpel: draw a stroke through the points (at least 2) over `steps` steps, cutting the links it
    /// crosses at the given depth.
    Cut {
        /// The stroke, at least 2 points.
        path: Vec<Point>,
        /// Which tissue is cut.
        depth: CutDepth,
        /// Duration in steps, at least 1.
        steps: u32,
    },
    /// Probe: touch down at `at`, then push (or pull) the tissue there to `to` over `steps` steps.
    Push {
        /// Where the probe touches the tissue.
        at: Point,
        /// Where it pushes that point to.
        to: Point,
        /// Duration in steps, at least 1.
        steps: u32,
    },
    /// Do nothing for this many steps (at least 1).
    Wait(u32),
    /// Wait until this absolute step (from 0); values never decrease along a script.
    At(u64),
    /// Forceps: close the jaws on this element (what a recording writes for a pick). No time.
    GraspElement(u32),
    /// A raw world command, applied at once (what a recording writes for live input). No time.
    Command(crate::simulation::Command),
    /// Where the trainee's camera looked from here on (what a recording writes as the trainee moves it,
    /// so that a replay can show the session through it). Changes nothing in the world. No time.
    View(CameraSpec),
}

impl Action {
    /// How many steps the action lasts by itself (`At` is 0 here: it depends on when it starts).
    pub fn steps(&self) -> u64 {
        match self {
            Action::MoveTo { steps, .. } | Action::Cut { steps, .. } | Action::Push { steps, .. } => {
                u64::from(*steps)
            }
            Action::Wait(n) => u64::from(*n),
            Action::Select(_)
            | Action::Grasp(_)
            | Action::Release
            | Action::At(_)
            | Action::GraspElement(_)
            | Action::Command(_)
            | Action::View(_) => 0,
        }
    }
}

/// When an action runs: `start..end` in steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timed {
    /// Index of the action in the script.
    pub index: usize,
    /// First step of the action.
    pub start: u64,
    /// Step at which it is done (equal to `start` for actions that take no time).
    pub end: u64,
}

impl Script {
    /// Reads, parses and validates a script file.
    pub fn load(path: impl AsRef<Path>) -> Result<Script, SceneError> {
        let path = path.as_ref();
        let src = super::read(path)?;
        Self::from_str(&src, path)
    }

    /// Parses and validates a script from text; `path` is used only in error messages.
    /// A recording ([`super::Recording`]) is accepted too: its actions are the script.
    pub fn from_str(src: &str, path: impl AsRef<Path>) -> Result<Script, SceneError> {
        let path = path.as_ref();
        if super::recording::is_recording(src) {
            return super::Recording::from_str(src, path).map(|r| r.script());
        }
        let script: Script = super::ron_options().from_str(src).map_err(|e| parse_error(path, src, &e))?;
        script.check(&FieldPath::default().inner()).map_err(|p| p.into_error(path, src))?;
        Ok(script)
    }

    /// Checks the script's values (as [`Script::load`] does), for scripts built in code (recordings).
    pub fn validate(&self) -> Result<(), SceneError> {
        self.check(&FieldPath::default().inner()).map_err(|p| p.into_error(Path::new("<script>"), ""))
    }

    /// What `dissect check --script` does: reads and checks a script or recording file; a recording's
    /// scene (`scene_source`) is checked as a scene, and its actions against that scene.
    pub fn check_file(path: impl AsRef<Path>) -> Result<(), SceneError> {
        let path = path.as_ref();
        let src = super::read(path)?;
        if !super::recording::is_recording(&src) {
            return Self::from_str(&src, path).map(|_| ());
        }
        let (rec, located) = super::Recording::parse(&src, path)?;
        let scene_name = format!("{} (its scene_source)", path.display());
        let scene = super::Scene::from_str(&rec.scene_source, scene_name)?;
        rec.script()
            .against(&scene, &FieldPath::default().f("actions"))
            .map_err(|p| p.into_error(path, &located))
    }

    /// The script as pretty RON (one action per line), which [`Script::from_str`] reads back to an
    /// equal script.
    pub fn to_ron_string(&self) -> Result<String, ron::Error> {
        let config = ron::ser::PrettyConfig::default().struct_names(true).depth_limit(2);
        ron::ser::to_string_pretty(self, config)
    }

    /// Start and end step of every action, in order.
    pub fn timeline(&self) -> Vec<Timed> {
        let mut t = 0u64;
        self.0
            .iter()
            .enumerate()
            .map(|(index, a)| {
                let start = t;
                t = match a {
                    Action::At(n) => t.max(*n),
                    other => t.saturating_add(other.steps()),
                };
                Timed { index, start, end: t }
            })
            .collect()
    }

    /// Steps until the last action is done.
    pub fn duration_steps(&self) -> u64 {
        self.timeline().last().map_or(0, |t| t.end)
    }

    /// The instruments the script selects, in first-use order.
    pub fn instruments(&self) -> Vec<InstrumentKind> {
        let mut out = Vec::new();
        for a in &self.0 {
            if let Action::Select(k) = a
                && !out.contains(k)
            {
                out.push(*k);
            }
        }
        out
    }

    /// Checks that the script fits a scene: every instrument it selects is offered by the scene, and
    /// cuts at `Between` or `Lower` have two layers to cut. The message names the action (from 1).
    /// Raw commands (`Command(..)`, `GraspElement`) are held to the same rules: an element or material
    /// the scene has, a depth it can cut.
    pub fn check_against(&self, scene: &super::Scene) -> Result<(), String> {
        self.against(scene, &FieldPath::default().inner())
            .map_err(|p| format!("{} {}", p.at.text(), p.message))
    }

    /// [`Script::check_against`], naming the action by its path under `list` (for line and column).
    pub(crate) fn against(&self, scene: &super::Scene, list: &FieldPath) -> Result<(), Problem> {
        use crate::simulation::Command as C;
        let layers = match &scene.tissue {
            super::Tissue::Layers(l) => l.layers.len(),
            super::Tissue::Volume(_) => 1,
        };
        let materials = match &scene.tissue {
            super::Tissue::Layers(l) => {
                l.layers.len() + usize::from(l.layers.len() == 2 && l.connective.is_some())
            }
            super::Tissue::Volume(_) => 1,
        };
        let elements = scene.element_count();
        let title = &scene.title;
        for (i, a) in self.0.iter().enumerate() {
            let at = list.i(i).with_text(format!("action {} ({})", i + 1, name(a)));
            let fem = matches!(&scene.tissue, super::Tissue::Volume(v) if matches!(v.model, super::VolumeModel::Fem(_)));
            let select = match a {
                Action::Select(k) | Action::Command(C::Select(k)) => Some(*k),
                _ => None,
            };
            let depth = match a {
                Action::Cut { depth, .. } | Action::Command(C::SetDepth(depth)) => Some(*depth),
                _ => None,
            };
            let element = match a {
                Action::GraspElement(e)
                | Action::Command(C::GraspElement(crate::chainmail::ElementId(e))) => Some(*e),
                _ => None,
            };
            if let Some(k) = select
                && !scene.instruments.contains(&k)
            {
                return problem(
                    &at,
                    format!(
                        "selects the {k:?}, which the scene \"{title}\" does not offer (it offers {:?})",
                        scene.instruments
                    ),
                );
            }
            if matches!(a, Action::Cut { .. }) && fem {
                return problem(&at, format!("cuts: {}", crate::tissue::FEM_CUT_REFUSED));
            }
            if let Some(d @ (CutDepth::Between | CutDepth::Lower)) = depth
                && layers < 2
            {
                return problem(
                    &at,
                    format!("cuts at depth {d:?}, but the scene \"{title}\" has one layer; expected `Upper`"),
                );
            }
            if let Some(e) = element
                && u128::from(e) >= elements
            {
                return problem(
                    &at,
                    format!(
                        "grasps element {e}, but the scene \"{title}\" has {elements} elements (0 to {})",
                        elements.saturating_sub(1)
                    ),
                );
            }
            if let Action::Command(C::SetMaterial(id, _)) = a
                && usize::from(id.0) >= materials
            {
                return problem(
                    &at,
                    format!(
                        "sets material {}, but the scene \"{title}\" has {materials} material(s) (0 to {})",
                        id.0,
                        materials - 1
                    ),
                );
            }
        }
        Ok(())
    }

    pub(crate) fn check(&self, list: &FieldPath) -> Result<(), Problem> {
        let mut last_at: Option<u64> = None;
        let mut held: Option<InstrumentKind> = None;
        // When the action before this one ends, in steps.
        let mut t = 0u64;
        for (i, a) in self.0.iter().enumerate() {
            let at = list.i(i).with_text(format!("action {} ({})", i + 1, name(a)));
            t = match a {
                Action::At(n) => t.max(*n),
                other => t.saturating_add(other.steps()),
            };
            if t > MAX_SCRIPT_STEPS {
                return problem(
                    &at.inner(),
                    format!(
                        "ends at step {t}, expected at most {MAX_SCRIPT_STEPS}: the longest script or recording \
                         (see scenes/README.md)"
                    ),
                );
            }
            let need = |kind: InstrumentKind, held: Option<InstrumentKind>| {
                if held == Some(kind) {
                    Ok(())
                } else {
                    problem(
                        &at,
                        format!(
                            "uses the {kind:?} while {}, expected `Select({kind:?})` before it",
                            held.map_or("no instrument is selected".to_owned(), |h| format!(
                                "the {h:?} is selected"
                            ))
                        ),
                    )
                }
            };
            match a {
                Action::Select(k) => held = Some(*k),
                Action::Grasp(p) => {
                    need(InstrumentKind::Forceps, held)?;
                    point(&at.inner(), p)?;
                }
                Action::MoveTo { to, steps } => {
                    if held.is_none() {
                        return problem(&at, "moves no instrument, expected `Select(..)` before it");
                    }
                    point(&at.f("to"), to)?;
                    steps_at_least_1(&at.f("steps"), *steps)?;
                }
                Action::Release | Action::GraspElement(_) => need(InstrumentKind::Forceps, held)?,
                Action::Command(c) => {
                    if let crate::simulation::Command::Select(k) = c {
                        held = Some(*k);
                    }
                    command(&at.inner(), c)?;
                }
                Action::Cut { path, steps, .. } => {
                    need(InstrumentKind::Scalpel, held)?;
                    let pa = at.f("path");
                    if path.len() < 2 {
                        return problem(&pa, format!("has {} point(s), expected at least 2", path.len()));
                    }
                    for (j, p) in path.iter().enumerate() {
                        point(&pa.i(j), p)?;
                    }
                    steps_at_least_1(&at.f("steps"), *steps)?;
                }
                Action::Push { at: from, to, steps } => {
                    need(InstrumentKind::Probe, held)?;
                    point(&at.f("at"), from)?;
                    point(&at.f("to"), to)?;
                    steps_at_least_1(&at.f("steps"), *steps)?;
                }
                Action::Wait(n) => steps_at_least_1(&at.inner(), *n)?,
                Action::View(c) => super::validate::camera(&at.inner(), c)?,
                Action::At(n) => {
                    if let Some(prev) = last_at
                        && *n < prev
                    {
                        return problem(
                            &at.inner(),
                            format!(
                                "is step {n}, expected at least {prev} (the `At` before it): time only goes forward"
                            ),
                        );
                    }
                    last_at = Some(*n);
                }
            }
        }
        Ok(())
    }
}

fn name(a: &Action) -> &'static str {
    match a {
        Action::Select(_) => "Select",
        Action::Grasp(_) => "Grasp",
        Action::MoveTo { .. } => "MoveTo",
        Action::Release => "Release",
        Action::Cut { .. } => "Cut",
        Action::Push { .. } => "Push",
        Action::Wait(_) => "Wait",
        Action::At(_) => "At",
        Action::GraspElement(_) => "GraspElement",
        Action::Command(_) => "Command",
        Action::View(_) => "View",
    }
}

fn steps_at_least_1(at: &FieldPath, n: u32) -> Result<(), Problem> {
    if n >= 1 { Ok(()) } else { problem(at, "is 0 steps, expected at least 1") }
}

/// A raw command holds to what the actions hold to: finite points within reach, a usable material, the
/// sweep cap of scenes.
fn command(at: &FieldPath, c: &crate::simulation::Command) -> Result<(), Problem> {
    use crate::simulation::Command as C;
    let inner = at.inner();
    match c {
        C::SetMaterial(_, m) => return super::validate::material(&at.i(1), m),
        C::SetRelaxSweeps(n) if *n > 1000 => {
            return problem(&inner, format!("is {n}, expected at most 1000 sweeps per step"));
        }
        C::SetRelaxSweeps(_) => return Ok(()),
        C::MoveTo(p) => {
            for (k, &x) in p.iter().enumerate() {
                within(&inner.i(k).with_text(format!("{}: {}", at.text(), ["x", "y", "z"][k])), x)?;
            }
        }
        C::SetAxis(a) => {
            for (k, &x) in a.iter().enumerate() {
                finite(&inner.i(k), x)?;
            }
            let l = a.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
            if !(l > 1e-6 && l < 1e6) {
                return problem(
                    at,
                    format!("is an axis of length {l}, expected a direction (length about 1)"),
                );
            }
        }
        C::Roll(r) => {
            finite(&inner, *r)?;
            if r.abs() > 1e3 {
                return problem(&inner, format!("is {r}, expected an angle in radians within ±1000"));
            }
        }
        C::Select(_)
        | C::Grasp
        | C::GraspElement(_)
        | C::Release
        | C::SetDepth(_)
        | C::BeginCut
        | C::EndCut => {}
    }
    Ok(())
}

fn point(at: &FieldPath, p: &Point) -> Result<(), Problem> {
    let t = at.text().to_owned();
    let inner = at.inner();
    match *p {
        Point::Surface(u, v, h) => {
            for (k, (x, what)) in [(u, "u fraction"), (v, "v fraction")].into_iter().enumerate() {
                let a = inner.i(k).with_text(format!("{t}: the {what}"));
                finite(&a, x)?;
                if !(0.0..=1.0).contains(&x) {
                    return problem(&a, format!("is {x}, expected a fraction of the surface in [0, 1]"));
                }
            }
            within(&inner.i(2).with_text(format!("{t}: the normal offset")), h)?;
        }
        Point::World(x, y, z) => {
            for (k, c) in [x, y, z].into_iter().enumerate() {
                within(&inner.i(k).with_text(format!("{t}: {}", ["x", "y", "z"][k])), c)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_ron() {
        let s = Script(vec![
            Action::Select(InstrumentKind::Forceps),
            Action::Grasp(Point::Surface(0.5, 0.5, 0.003)),
            Action::MoveTo { to: Point::World(0.0, 0.02, 0.0), steps: 300 },
            Action::Release,
            Action::Select(InstrumentKind::Scalpel),
            Action::Cut {
                path: vec![Point::Surface(0.3, 0.5, 0.0), Point::Surface(0.7, 0.5, 0.0)],
                depth: CutDepth::Between,
                steps: 200,
            },
            Action::Wait(5),
            Action::At(2000),
        ]);
        let text = s.to_ron_string().expect("serializes");
        assert_eq!(Script::from_str(&text, "x.ron").expect("reads back"), s);
        assert_eq!(s.duration_steps(), 2000);
        assert_eq!(s.timeline()[6], Timed { index: 6, start: 500, end: 505 });
    }

    #[test]
    fn at_going_back_is_refused_at_its_value() {
        let e = Script::from_str("Script([At(5),\n At(3)])", "s.ron").expect_err("At going back");
        assert_eq!(e.line_column(), Some((2, 5)), "{e}");
    }

    #[test]
    fn a_view_takes_no_time_and_its_camera_is_checked() {
        let s = Script::from_str(
            "Script([View((eye: (0.0, 0.06, 0.05), target: (0.0, 0.0, 0.0), fov_y_deg: 45.0)), Wait(10)])",
            "s.ron",
        )
        .expect("a view");
        assert_eq!(s.duration_steps(), 10);
        let e = Script::from_str(
            "Script([\n View((eye: (0.0, 0.06, 0.05), target: (0.0, 0.0, 0.0), fov_y_deg: 0.0))])",
            "s.ron",
        )
        .expect_err("no field of view");
        assert!(e.to_string().contains("field of view"), "{e}");
    }
}
