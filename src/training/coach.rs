//! The coach: one plain sentence about what stops the trainee now ("held by 12 uncut fibres",
//! "stretch 1.52 of 1.60: ease off", a tear explained), read from the world and the assessment.

use serde::{Deserialize, Serialize};

use super::Assessor;
use crate::chainmail::LinkId;
use crate::simulation::{InstrumentKind, World};

/// How urgent a piece of advice is.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdviceLevel {
    /// Why the tissue does not follow.
    Info,
    /// Close to hurting the tissue.
    Warn,
    /// The tissue is being hurt (over the limit, or it tore).
    Alarm,
}

/// One thing to tell the trainee now.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct Advice {
    /// The sentence.
    pub text: String,
    /// How urgent.
    pub level: AdviceLevel,
}

/// Forceps whose tip lags the hand by more than this are held back by the tissue, metres.
const STALL_M: f32 = 0.002;
/// A fibre stretched by more than this beyond its rest gap is holding a lifted layer, metres.
const HOLDING_M: f32 = 0.0005;
/// A warning is given from this share of the stretch limit.
const WARN_SHARE: f32 = 0.9;

impl Assessor {
    /// Intact connective fibres under the target stretched by a lift (their upper end pulled away from
    /// the lower): the ones the trainee is to cut. Fibres outside the target are not counted: cutting
    /// them is damage, so the coach never asks for it.
    fn holding<'a>(&'a self, world: &'a World) -> impl Iterator<Item = LinkId> + 'a {
        let body = world.tissue().body();
        let p = body.positions();
        self.target.iter().zip(&self.target_pairs).filter_map(move |(&l, &(a, b))| {
            (body.link_intact(l) && p[b as usize][2] - p[a as usize][2] - self.rest_gap > HOLDING_M)
                .then_some(l)
        })
    }

    /// How many fibres under the target hold a lifted layer: intact, stretched by a lift.
    pub fn holding_fibres(&self, world: &World) -> u32 {
        self.holding(world).count() as u32
    }

    /// The area of the layers' interface those fibres stand for, square metres: the same at every
    /// resolution.
    pub fn holding_area_m2(&self, world: &World) -> f32 {
        self.holding(world).fold(0.0, |sum, l| sum + world.tissue().link_extent(l))
    }

    /// What stops the trainee now, if anything: a tear in the last few seconds, a stretch near or over
    /// the limit, or a lift that the tissue holds back (and what holds it).
    pub fn advice(&self, world: &World) -> Option<Advice> {
        let tissue = world.tissue();
        let limit = self.goals.stretch_limit;
        let upper = tissue.layers().first().map_or("tissue", |l| l.name.as_str());
        if let Some((at, [layer, fibre])) = self.last_tear
            && self.steps.saturating_sub(at) < self.coach_window()
        {
            let what = super::amount_text(layer, fibre, self.layers_are_areas);
            return Some(Advice {
                text: format!(
                    "The tissue tore ({what}): it was stretched until it gave way. Pull more gently, and cut what holds it first."
                ),
                level: AdviceLevel::Alarm,
            });
        }
        let stretch = tissue.max_stretch();
        if stretch > limit {
            return Some(Advice {
                text: format!("stretch {stretch:.2} is over the limit {limit:.2}: ease off now"),
                level: AdviceLevel::Alarm,
            });
        }
        if stretch >= 1.0 + WARN_SHARE * (limit - 1.0) {
            return Some(Advice {
                text: format!("stretch {stretch:.2} of {limit:.2}: ease off"),
                level: AdviceLevel::Warn,
            });
        }
        let inst = world.instrument();
        if inst.kind == InstrumentKind::Forceps && inst.grasped.is_some() {
            let (t, p) = (inst.target, inst.tip);
            let lag = ((t[0] - p[0]).powi(2) + (t[1] - p[1]).powi(2) + (t[2] - p[2]).powi(2)).sqrt();
            if lag > STALL_M {
                let held = self.holding_area_m2(world) * 1e6;
                let text = if self.incision_share(tissue).is_some_and(|s| s < 0.95) {
                    format!("held by the uncut {upper}: finish the incision first (2, then U)")
                } else if held > 0.0 {
                    format!(
                        "held by uncut fibres under the target ({held:.0} mm² of them): cut them between the layers (2 for the scalpel, B for the depth)"
                    )
                } else {
                    format!("the {upper} is held beyond the target: it will not come further this way")
                };
                return Some(Advice { text, level: AdviceLevel::Info });
            }
        }
        None
    }
}
