//! What the broken links count for in the assessment, taken in as they break. Links never mend, and
//! the body lists them in the order they broke (`Body::broken_links`), so the assessor reads only what
//! broke since it last looked: the assessment costs what was cut or torn, not the sheet's million
//! links. It is read every step (the checklist, the history) and every frame the trainer publishes.
//! [`Tally::scan`] is the plain path beside it, every link read in order; a test holds them together.
//!
//! Must not import wgpu, winit or egui.

use std::borrow::Cow;

use crate::chainmail::{BreakReason, LinkId};
use crate::tissue::Tissue;

/// A connective link under the target.
pub(super) const TARGET: u8 = 1;
/// A connective link outside the target (cutting it is damage).
pub(super) const OUTSIDE: u8 = 2;
/// A layer's link in a forbidden region.
pub(super) const FORBIDDEN_LAYER: u8 = 4;
/// A connective link in a forbidden region.
pub(super) const FORBIDDEN_FIBRE: u8 = 8;
/// A layer's link whose cutting is damage (all but the upper layer's along the planned incision).
pub(super) const PENALISED: u8 = 16;
/// An upper-layer link whose cut counts for a point of the planned incision.
pub(super) const INCISION: u8 = 32;
/// A connective link (its amount is an area of the layers' interface).
pub(super) const CONNECTIVE: u8 = 64;

/// What each link counts for, fixed when the assessor is made.
#[derive(Clone, Debug, Default)]
pub(super) struct Roles {
    /// The bits above, one byte a link.
    pub(super) bits: Vec<u8>,
    /// Each point of the planned incision a link counts for, as (link, point), in link order.
    pub(super) incision: Vec<(u32, u32)>,
    /// Points of the planned incision.
    pub(super) points: usize,
    /// Millimetres per metre of a layer's amount (square millimetres per square metre in a volume).
    pub(super) layer_unit: f32,
}

impl Roles {
    /// How much tissue a link stands for: millimetres of a layer (square millimetres in a volume), or
    /// square millimetres of fibres.
    pub(super) fn amount(&self, tissue: &Tissue, l: LinkId, bits: u8) -> f32 {
        tissue.link_extent(l) * if bits & CONNECTIVE != 0 { 1e6 } else { self.layer_unit }
    }
}

/// How many links of each kind have broken, and how much tissue they stand for.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Tally {
    /// Which body's links these are (`Body::shape`), and how many of its broken links are taken in.
    body: u64,
    seen: usize,
    /// Connective links under the target broken (cut or torn).
    pub(super) target: u32,
    /// Layer links cut where cutting is damage, and their amount.
    pub(super) layer_cut: (u32, f64),
    /// Connective links broken outside the target, and their area (mm²).
    pub(super) outside: (u32, f64),
    /// Links broken in a forbidden region: a layer's, then connective ones, with their amounts.
    pub(super) forbidden: [(u32, f64); 2],
    /// Whether each point of the planned incision has a link cut.
    incision_cut: Vec<bool>,
    /// How many points of the planned incision have a link cut.
    pub(super) incision: u32,
}

impl Tally {
    fn new(roles: &Roles, body: u64) -> Self {
        Self { body, incision_cut: vec![false; roles.points], ..Self::default() }
    }

    /// Takes in the links broken since the last call. A different body (a new world) starts again.
    pub(super) fn absorb(&mut self, roles: &Roles, tissue: &Tissue) {
        let body = tissue.body();
        let broken = body.broken_links();
        if self.body != body.shape || broken.len() < self.seen || self.incision_cut.len() != roles.points {
            *self = Self::new(roles, body.shape);
        }
        for &l in broken.get(self.seen..).unwrap_or(&[]) {
            self.take(roles, tissue, l);
        }
        self.seen = broken.len();
    }

    /// This tally with what broke since taken in: itself if nothing did.
    pub(super) fn now<'a>(&'a self, roles: &Roles, tissue: &Tissue) -> Cow<'a, Self> {
        let body = tissue.body();
        if self.body == body.shape && self.seen == body.broken_links().len() {
            Cow::Borrowed(self)
        } else {
            let mut t = self.clone();
            t.absorb(roles, tissue);
            Cow::Owned(t)
        }
    }

    /// The plain path: every link read in order, each kind summed on its own, and each point of the
    /// incision looked up through its links.
    #[cfg(test)]
    pub(super) fn scan(roles: &Roles, tissue: &Tissue) -> Self {
        let body = tissue.body();
        let mut t = Self::new(roles, body.shape);
        let sum = |role: u8, reason: Option<BreakReason>| {
            let mut out = (0u32, 0.0f64);
            for (l, &bits) in roles.bits.iter().enumerate() {
                let l = LinkId(l as u32);
                let broken = body.link_broken(l);
                if bits & role != 0 && broken.is_some() && (reason.is_none() || broken == reason) {
                    out.0 += 1;
                    out.1 += f64::from(roles.amount(tissue, l, bits));
                }
            }
            out
        };
        t.target = sum(TARGET, None).0;
        t.outside = sum(OUTSIDE, None);
        t.forbidden = [sum(FORBIDDEN_LAYER, None), sum(FORBIDDEN_FIBRE, None)];
        t.layer_cut = sum(PENALISED, Some(BreakReason::Cut));
        for &(l, p) in &roles.incision {
            if body.link_broken(LinkId(l)) == Some(BreakReason::Cut) {
                t.incision_cut[p as usize] = true;
            }
        }
        t.incision = t.incision_cut.iter().filter(|&&c| c).count() as u32;
        t.seen = body.broken_links().len();
        t
    }

    /// Counts one broken link.
    fn take(&mut self, roles: &Roles, tissue: &Tissue, l: LinkId) {
        let bits = roles.bits.get(l.index()).copied().unwrap_or(0);
        if bits & !CONNECTIVE == 0 {
            return;
        }
        let cut = tissue.body().link_broken(l) == Some(BreakReason::Cut);
        let amount = f64::from(roles.amount(tissue, l, bits));
        let add = |(n, sum): &mut (u32, f64)| {
            *n += 1;
            *sum += amount;
        };
        if bits & TARGET != 0 {
            self.target += 1;
        }
        if bits & OUTSIDE != 0 {
            add(&mut self.outside);
        }
        if bits & FORBIDDEN_LAYER != 0 {
            add(&mut self.forbidden[0]);
        }
        if bits & FORBIDDEN_FIBRE != 0 {
            add(&mut self.forbidden[1]);
        }
        if cut && bits & PENALISED != 0 {
            add(&mut self.layer_cut);
        }
        if cut && bits & INCISION != 0 {
            let from = roles.incision.partition_point(|&(m, _)| m < l.0);
            for &(_, p) in roles.incision[from..].iter().take_while(|&&(m, _)| m == l.0) {
                if let Some(done) = self.incision_cut.get_mut(p as usize)
                    && !*done
                {
                    *done = true;
                    self.incision += 1;
                }
            }
        }
    }
}
