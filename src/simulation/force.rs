//! The force gauge: every step, the force the tissue exerts on each instrument, in newtons (see
//! `tissue/force.rs` for the springs behind it).
//!
//! - Forceps: the pull of the links that leave the patch the jaws hold (links within it cancel, so
//!   the force does not depend on how many elements the jaws' width takes at a given spacing), also
//!   while clamped and another instrument is in hand, plus, where the tissue would not follow the
//!   jaws (ChainMail holds every link within its limits, so the patch stops short of the hand), the
//!   tissue's stiffness at the patch times the distance it fell short: the tissue resists being pulled
//!   further than it can stretch. That stiffness is the material's at the scale of the jaws and the
//!   tissue ([`Tissue::patch_stiffness`]), not a sum over the patch's links, whose count grows with
//!   the resolution.
//! - Probe: the push-back of the links of the element it presses on, while it touches the tissue.
//! - Scalpel: the cutting resistance, the energy spent cutting over the distance the blade travelled,
//!   both smoothed over [`CUT_WINDOW_S`] so that links cut one at a time give a steady force; it points
//!   against the blade's motion.
//!
//! Must not import wgpu, winit or egui.

use serde::{Deserialize, Serialize};

use super::InstrumentKind;
use crate::instrument::Instrument;
use crate::tissue::Tissue;

/// Time constant of the scalpel's smoothing, seconds.
pub const CUT_WINDOW_S: f32 = 0.02;

/// The forces of one step, newtons, world axes: what the tissue exerts on each instrument.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Forces {
    /// On the forceps (zero when they hold nothing).
    pub forceps: [f32; 3],
    /// On the probe (zero out of contact or not in hand).
    pub probe: [f32; 3],
    /// On the scalpel (zero when not cutting).
    pub scalpel: [f32; 3],
    /// Which instrument is in hand: its force is what a haptic device renders.
    pub in_hand: InstrumentKind,
}

impl Forces {
    /// The force on an instrument.
    pub fn on(&self, kind: InstrumentKind) -> [f32; 3] {
        match kind {
            InstrumentKind::Forceps => self.forceps,
            InstrumentKind::Probe => self.probe,
            InstrumentKind::Scalpel => self.scalpel,
        }
    }

    /// The force on the instrument in hand.
    pub fn in_hand(&self) -> [f32; 3] {
        self.on(self.in_hand)
    }

    /// Its magnitude, newtons.
    pub fn magnitude(kind_force: [f32; 3]) -> f32 {
        (kind_force[0] * kind_force[0] + kind_force[1] * kind_force[1] + kind_force[2] * kind_force[2]).sqrt()
    }
}

/// Reads the forces step by step; keeps the scalpel's smoothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ForceGauge {
    /// Smoothed energy spent cutting, joules.
    energy: f32,
    /// Smoothed blade travel, metres.
    travel: f32,
    /// Direction of the blade's last move (unit).
    heading: [f32; 3],
    last_target: Option<[f32; 3]>,
    /// The elements the jaws hold (scratch, refilled every step), and a bit per element of the
    /// tissue to mark them while their force is summed (all clear between steps).
    held: Vec<crate::chainmail::ElementId>,
    marks: Vec<u64>,
    /// The tissue's stiffness at the grasped patch, N/m, and the element it was measured around.
    patch: Option<(crate::chainmail::ElementId, f32)>,
    /// The force on the held elements last measured, with the body's motion count and revision then
    /// and the elements held (`memo_held`): a step that moved, cut and tore nothing and holds the same
    /// elements reads it again rather than summing every held element's links.
    memo: Option<(u64, u64, [f32; 3])>,
    memo_held: Vec<crate::chainmail::ElementId>,
}

impl ForceGauge {
    /// The forces after a step of `dt` seconds.
    pub(crate) fn measure(
        &mut self,
        tissue: &mut Tissue,
        inst: &Instrument,
        jaw_width: f32,
        dt: f32,
    ) -> Forces {
        let mut out = Forces { in_hand: inst.kind, ..Forces::default() };
        if let Some(e) = inst.grasped {
            self.held.clear();
            self.held.extend(tissue.held());
            if self.held.is_empty() {
                self.held.push(e);
            }
            let key = (tissue.body().motion(), tissue.body().revision());
            let f = match self.memo {
                Some((motion, revision, f))
                    if (motion, revision) == key && self.memo_held == self.held && !tissue.is_fem() =>
                {
                    f
                }
                _ => {
                    let f = tissue.force_on_many(&self.held, &mut self.marks);
                    self.memo = Some((key.0, key.1, f));
                    self.memo_held.clone_from(&self.held);
                    f
                }
            };
            // Only while the forceps are in hand: a clamp left on the tissue stays where it is.
            let short = if inst.kind == InstrumentKind::Forceps {
                [0, 1, 2].map(|k| inst.target[k] - inst.tip[k])
            } else {
                [0.0; 3]
            };
            let k = if short == [0.0; 3] || tissue.is_fem() {
                0.0
            } else {
                match self.patch {
                    Some((c, k)) if c == e => k,
                    _ => {
                        let k = tissue.patch_stiffness(e, 0.5 * jaw_width);
                        self.patch = Some((e, k));
                        k
                    }
                }
            };
            out.forceps = [0, 1, 2].map(|i| f[i] - k * short[i]);
        }
        if inst.grasped.is_none() {
            // Measured again at the next grasp (materials may have changed meanwhile).
            self.patch = None;
        }
        if inst.kind == InstrumentKind::Probe && tissue.probe_contact().is_some() {
            // The pull of the links leaving what the ball touches (its footprint on a surface).
            out.probe = tissue.force_on_many(tissue.probe_patch(), &mut self.marks);
        }
        // The scalpel: energy over distance, both decaying with the same time constant.
        let energy = tissue.take_cut_energy();
        let decay = (-dt / CUT_WINDOW_S).exp();
        let moved = match self.last_target {
            Some(p) => [inst.target[0] - p[0], inst.target[1] - p[1], inst.target[2] - p[2]],
            None => [0.0; 3],
        };
        self.last_target = Some(inst.target);
        let d = Forces::magnitude(moved);
        if d > 0.0 {
            self.heading = moved.map(|x| x / d);
        }
        if inst.kind == InstrumentKind::Scalpel && inst.cutting {
            // A blade that stops feels its resistance fade: only the energy decays then.
            self.energy = self.energy * decay + energy;
            if d > 0.0 {
                self.travel = self.travel * decay + d;
            }
        } else {
            self.energy = 0.0;
            self.travel = 0.0;
        }
        if self.energy > 0.0 && self.travel > 0.0 {
            let f = self.energy / self.travel;
            out.scalpel = self.heading.map(|x| -f * x);
        }
        out
    }
}
