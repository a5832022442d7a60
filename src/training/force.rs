//! Force in the assessment: per instrument the peak and mean force, the time above the goal's
//! `force_limit`, the force bandwidth, and the largest tension carried by the forbidden region's links.
//! NeuroTouch's tier 2 and 3 metrics: novices exert about a quarter more force than experts, and more
//! abruptly.
//!
//! The **bandwidth** is how fast the force changes, as a frequency: `rms(dF/dt) / (2π · rms(F))` over the
//! steps in contact (for a force oscillating at f hertz it is f). A smooth pull has a low one, jerks a
//! high one.
//!
//! Must not import wgpu, winit or egui.

use serde::{Deserialize, Serialize};

use crate::chainmail::ElementId;
use crate::simulation::{Forces, InstrumentKind, World};
use crate::tissue::{LinkKind, Tissue};

/// Force figures of one instrument (or of whichever was in hand), newtons and seconds.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct ForceStats {
    /// Largest force, newtons.
    pub peak_n: f32,
    /// Mean force over the steps in contact, newtons.
    pub mean_n: f32,
    /// Time spent above the goal's force limit, seconds.
    pub time_above_limit_s: f32,
    /// How abruptly the force changed, hertz (see the module docs).
    pub bandwidth_hz: f32,
    /// Time in contact (force above zero), seconds.
    pub contact_s: f32,
}

/// One instrument's force figures.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct InstrumentForce {
    /// Which instrument.
    pub instrument: InstrumentKind,
    /// Its figures.
    #[serde(flatten)]
    pub stats: ForceStats,
}

/// The force part of the assessment (`assessment.force` in `metrics.json` and `report.json`).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct ForceAssessment {
    /// Over all instruments: the force on the one in hand, or on the forceps' grasp while clamped.
    #[serde(flatten)]
    pub total: ForceStats,
    /// The goal's limit, newtons.
    pub limit_n: f32,
    /// Largest tension in a link of a forbidden region, newtons. One link's share, so it falls as the
    /// resolution rises; [`ForceAssessment::forbidden_peak_n_per_m`] does not.
    pub forbidden_peak_n: f32,
    /// Largest tension per unit width across a layer in a forbidden region: a layer link's tension
    /// over its tributary width ([`Tissue::link_extent`]), newtons per metre on a surface (pascals in
    /// a volume).
    #[serde(default)]
    pub forbidden_peak_n_per_m: f32,
    /// Per instrument: forceps, scalpel, probe.
    pub instruments: Vec<InstrumentForce>,
}

/// Sums behind one [`ForceStats`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Accumulator {
    peak: f32,
    sum: f64,
    contact_steps: u64,
    above_steps: u64,
    sum_sq: f64,
    rate_sq: f64,
    last: [f32; 3],
}

impl Accumulator {
    fn add(&mut self, f: [f32; 3], limit: f32, dt: f32) {
        let m = Forces::magnitude(f);
        let was = Forces::magnitude(self.last) > 0.0;
        if m > 0.0 || was {
            let d = [f[0] - self.last[0], f[1] - self.last[1], f[2] - self.last[2]];
            let rate = Forces::magnitude(d) / dt;
            self.rate_sq += f64::from(rate) * f64::from(rate);
            self.sum_sq += f64::from(m) * f64::from(m);
        }
        if m > 0.0 {
            self.contact_steps += 1;
            self.sum += f64::from(m);
        }
        if m > limit {
            self.above_steps += 1;
        }
        self.peak = self.peak.max(m);
        self.last = f;
    }

    fn stats(&self, dt: f32) -> ForceStats {
        let bandwidth = if self.sum_sq > 0.0 {
            ((self.rate_sq / self.sum_sq).sqrt() / std::f64::consts::TAU) as f32
        } else {
            0.0
        };
        ForceStats {
            peak_n: self.peak,
            mean_n: if self.contact_steps > 0 { (self.sum / self.contact_steps as f64) as f32 } else { 0.0 },
            time_above_limit_s: self.above_steps as f32 * dt,
            bandwidth_hz: bandwidth,
            contact_s: self.contact_steps as f32 * dt,
        }
    }
}

const KINDS: [InstrumentKind; 3] = [InstrumentKind::Forceps, InstrumentKind::Scalpel, InstrumentKind::Probe];

/// Watches the forces step by step.
#[derive(Clone, Debug)]
pub(crate) struct ForceMeter {
    limit: f32,
    dt: f32,
    total: Accumulator,
    per: [Accumulator; 3],
    /// Per element: in a forbidden region.
    forbidden: Vec<bool>,
    /// Largest link tension, then largest tension over width of a layer link.
    forbidden_peak: [f32; 2],
}

impl ForceMeter {
    /// A meter for `limit` newtons, with the elements of the forbidden regions marked.
    pub(crate) fn new(limit: f32, dt: f32, forbidden: Vec<bool>) -> Self {
        Self {
            limit,
            dt,
            total: Accumulator::default(),
            per: [Accumulator::default(); 3],
            forbidden,
            forbidden_peak: [0.0; 2],
        }
    }

    /// Call after every step.
    pub(crate) fn observe(&mut self, world: &World) {
        let forces = world.forces();
        for (acc, kind) in self.per.iter_mut().zip(KINDS) {
            acc.add(forces.on(kind), self.limit, self.dt);
        }
        // What the hand feels: the instrument in hand, or the clamp while nothing else touches.
        let mut f = forces.in_hand();
        if Forces::magnitude(f) == 0.0 {
            f = forces.forceps;
        }
        self.total.add(f, self.limit, self.dt);
        let [link, width] = self.forbidden_tension(world.tissue());
        self.forbidden_peak = [self.forbidden_peak[0].max(link), self.forbidden_peak[1].max(width)];
    }

    /// The largest tension in a forbidden link touching the disturbed region (links elsewhere have not
    /// moved since they were last looked at), then the largest tension over its width of such a link
    /// of a layer.
    fn forbidden_tension(&self, tissue: &Tissue) -> [f32; 2] {
        let (mut peak, mut per_width) = (0.0f32, 0.0f32);
        for &e in tissue.active_elements() {
            if !self.forbidden.get(e.index()).copied().unwrap_or(false) {
                continue;
            }
            for (n, l) in tissue.body().lattice().neighbours(e) {
                if self.forbidden.get(n.index()).copied().unwrap_or(false) {
                    let t = tissue.link_tension(l);
                    peak = peak.max(t);
                    let width = tissue.link_extent(l);
                    if tissue.link_kind(l) != Some(LinkKind::Connective) && width > 0.0 {
                        per_width = per_width.max(t / width);
                    }
                }
            }
        }
        [peak, per_width]
    }

    /// The force on what the hand feels in the last step, newtons (for the history).
    pub(crate) fn last(&self) -> f32 {
        Forces::magnitude(self.total.last)
    }

    /// The figures so far.
    pub(crate) fn assessment(&self) -> ForceAssessment {
        ForceAssessment {
            total: self.total.stats(self.dt),
            limit_n: self.limit,
            forbidden_peak_n: self.forbidden_peak[0],
            forbidden_peak_n_per_m: self.forbidden_peak[1],
            instruments: KINDS
                .iter()
                .zip(&self.per)
                .map(|(&instrument, acc)| InstrumentForce { instrument, stats: acc.stats(self.dt) })
                .collect(),
        }
    }
}

/// The elements whose surface fractions fall in any of `regions`.
pub(crate) fn elements_in(tissue: &Tissue, contains: impl Fn(f32, f32) -> bool) -> Vec<bool> {
    let rest = tissue.body().lattice().rest_positions();
    (0..rest.len())
        .map(|i| {
            let (u, v) = tissue.surface_fractions(rest[ElementId(i as u32).index()]);
            contains(u, v)
        })
        .collect()
}

/// The force's colour in `report.png`.
pub(crate) const FORCE_COLOUR: plotters::style::RGBColor = plotters::style::RGBColor(30, 140, 60);

/// Draws the force on the instrument over time against the limit, dashed in `limit_colour` (the lower
/// part of `report.png`; its legend is drawn with the upper chart's, under both).
pub(crate) fn draw_force<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    history: &[super::Sample],
    limit: f32,
    limit_colour: plotters::style::RGBColor,
) -> Result<(), String> {
    use super::plot::{Layout, limit_and_line, mesh, time_chart};
    let t_max = history.last().map(|s| s.t).unwrap_or(1.0).max(0.01);
    let f_max = history.iter().map(|s| s.force_n).fold(limit, f32::max) * 1.1;
    let layout = Layout { caption: "Force on the instrument", caption_size: 18, x_label_area: 30 };
    let mut chart = time_chart(area, &layout, t_max, 0f32..f_max.max(1e-3))?;
    mesh(&mut chart, "force (N)")?;
    limit_and_line(
        &mut chart,
        t_max,
        (limit, limit_colour),
        history.iter().map(|s| (s.t, s.force_n)),
        FORCE_COLOUR,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bandwidth_of_a_sine_is_its_frequency() {
        let dt = 1e-3;
        let mut a = Accumulator::default();
        for i in 0..2000 {
            let t = i as f32 * dt;
            a.add([1.0 - (std::f32::consts::TAU * 5.0 * t).cos(), 0.0, 0.0], 10.0, dt);
        }
        // 1 N and a 5 Hz cosine of 1 N: rms(dF/dt) = 2π·5/√2, rms(F) = √1.5.
        let s = a.stats(dt);
        let expected = 5.0 / (2.0f32.sqrt() * 1.5f32.sqrt());
        assert!((s.bandwidth_hz - expected).abs() < 0.1, "{s:?}");
        assert!((s.peak_n - 2.0).abs() < 1e-3);
    }

    #[test]
    fn time_above_the_limit_counts_steps() {
        let mut a = Accumulator::default();
        for i in 0..100 {
            a.add([if i < 30 { 2.0 } else { 0.5 }, 0.0, 0.0], 1.0, 0.001);
        }
        let s = a.stats(0.001);
        assert!((s.time_above_limit_s - 0.03).abs() < 1e-6);
        assert!((s.mean_n - (30.0 * 2.0 + 70.0 * 0.5) / 100.0).abs() < 1e-6);
    }
}
