//! The world: a tissue and an instrument, advanced one fixed step at a time in named, ordered phases,
//! on a clock of its own.

use std::time::Duration;

use glam::Vec3;
use serde::Serialize;
use web_time::Instant;

use super::force::{ForceGauge, Forces};
use super::{Command, FixedClock};
use crate::chainmail::{ElementId, RelaxBudget};
use crate::instrument::{GRASP_REACH, Hit, Instrument, InstrumentSizes};
use crate::snapshot::{InstrumentKind, InstrumentPose, Snapshot, SurfaceRegion};
use crate::tissue::{CutSegment, Tissue, TissueError, TissueSpec};

/// The phases of a step, in the order they run.
pub const PHASES: [&str; 7] =
    ["input", "chain reaction", "normal pass", "relaxation", "contact", "cuts and tears", "forces"];

/// Settings of the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldConfig {
    /// Steps per second: the one place the step length is set (the clock, a dynamic finite-element
    /// model and the assessment read it from the world). Default 1000.
    pub rate_hz: f64,
    /// Relaxation per step. Deterministic runs give sweeps only, no time limit.
    pub relax: RelaxBudget,
    /// Most steps one [`World::due_steps`] hands out: real time beyond that is dropped (the simulation
    /// falls behind instead of freezing its caller). Default 100.
    pub max_steps_per_advance: u32,
    /// The instruments' physical sizes, metres.
    pub sizes: InstrumentSizes,
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            relax: RelaxBudget::sweeps(4),
            max_steps_per_advance: 100,
            sizes: InstrumentSizes::default(),
        }
    }
}

impl WorldConfig {
    /// Length of one step, seconds (1 ms if the rate is not a positive number).
    pub fn step_seconds(&self) -> f64 {
        let rate = if self.rate_hz.is_finite() && self.rate_hz > 0.0 { self.rate_hz } else { 1000.0 };
        1.0 / rate
    }

    fn clock(&self) -> FixedClock {
        FixedClock::new(self.rate_hz, self.max_steps_per_advance)
    }
}

/// What one step did, phase by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StepCounters {
    /// The step's number (1 for the first step).
    pub step: u64,
    /// Wall time of each phase, microseconds, in the order of [`PHASES`].
    pub phase_us: [f32; 7],
    /// Elements moved by the in-plane (or volume) chain reaction, probe pushes included.
    pub moved_chain: u32,
    /// Elements moved by the normal pass.
    pub moved_normal: u32,
    /// Relaxation sweeps.
    pub relax_sweeps: u32,
    /// Layer pairs pushed apart by the contact phase.
    pub contact_fixes: u32,
    /// Element moves that brought links the step left outside their limits back inside (timed with
    /// contact).
    pub limit_repairs: u32,
    /// Links cut.
    pub links_cut: u32,
    /// Links torn.
    pub links_torn: u32,
    /// Share of the requested grasp move the tissue allowed (1 when nothing held it back).
    pub grasp_fraction: f32,
}

impl StepCounters {
    /// Total wall time of the step, microseconds.
    pub fn total_us(&self) -> f32 {
        self.phase_us.iter().sum()
    }
}

/// A tissue, an instrument, and the clockwork between them.
pub struct World {
    tissue: Tissue,
    instrument: Instrument,
    config: WorldConfig,
    clock: FixedClock,
    commands: Vec<Command>,
    step: u64,
    last: StepCounters,
    elements_moved_total: u64,
    /// The regions of the exercise, copied into every snapshot for drawing.
    regions: Vec<SurfaceRegion>,
    /// The planned incision (surface fractions), copied into every snapshot for drawing.
    incision: Vec<[f32; 2]>,
    /// Axis and roll of the forceps when another instrument was taken up while they held the tissue
    /// (they are drawn clamped where they were left).
    clamp_axis: ([f32; 3], f32),
    gauge: ForceGauge,
    forces: Forces,
}

fn ms(t: Instant) -> f32 {
    t.elapsed().as_secs_f32() * 1e6
}

impl World {
    /// A world around a tissue.
    pub fn new(mut tissue: Tissue, config: WorldConfig) -> Self {
        tissue.set_blade_width(config.sizes.blade_width);
        Self {
            tissue,
            instrument: Instrument::default(),
            clock: config.clock(),
            config,
            commands: Vec::with_capacity(64),
            step: 0,
            last: StepCounters::default(),
            elements_moved_total: 0,
            regions: Vec::new(),
            incision: Vec::new(),
            clamp_axis: ([0.0, 1.0, 0.0], 0.0),
            gauge: ForceGauge::default(),
            forces: Forces::default(),
        }
    }

    /// Builds the tissue `spec` describes and a world around it, stepped as `config` says (a dynamic
    /// finite-element model integrates over the world's step).
    pub fn build(spec: &TissueSpec, config: WorldConfig) -> Result<Self, TissueError> {
        let tissue = Tissue::build_stepped(spec, config.step_seconds() as f32)?;
        Ok(Self::new(tissue, config))
    }

    /// The tissue.
    pub fn tissue(&self) -> &Tissue {
        &self.tissue
    }

    /// The tissue, to tune materials live.
    pub fn tissue_mut(&mut self) -> &mut Tissue {
        &mut self.tissue
    }

    /// The instrument.
    pub fn instrument(&self) -> &Instrument {
        &self.instrument
    }

    /// Settings.
    pub fn config(&self) -> &WorldConfig {
        &self.config
    }

    /// Changes the settings (relaxation budget, rate; a new rate restarts the clock).
    pub fn set_config(&mut self, config: WorldConfig) {
        if (config.rate_hz, config.max_steps_per_advance)
            != (self.config.rate_hz, self.config.max_steps_per_advance)
        {
            self.clock = config.clock();
        }
        self.tissue.set_blade_width(config.sizes.blade_width);
        self.config = config;
    }

    /// Steps run so far.
    pub fn step_count(&self) -> u64 {
        self.step
    }

    /// Length of one step, seconds.
    pub fn step_seconds(&self) -> f64 {
        self.config.step_seconds()
    }

    /// Simulated time so far, seconds.
    pub fn time_seconds(&self) -> f64 {
        self.step as f64 * self.step_seconds()
    }

    /// Adds `elapsed` real time to the world's clock; returns how many steps are due now (at most
    /// [`WorldConfig::max_steps_per_advance`]). For callers that do something between steps (an
    /// episode feeds and assesses each); [`World::advance`] runs them itself.
    pub fn due_steps(&mut self, elapsed: Duration) -> u32 {
        self.clock.advance(elapsed)
    }

    /// Advances the world by `elapsed` real time: runs the steps due; returns how many ran.
    pub fn advance(&mut self, elapsed: Duration) -> u32 {
        let due = self.due_steps(elapsed);
        for _ in 0..due {
            self.step();
        }
        due
    }

    /// Whether the last [`World::due_steps`] had to drop time (the simulation is slower than real time).
    pub fn is_behind(&self) -> bool {
        self.clock.is_behind()
    }

    /// How far real time has gone into the next step, in `[0, 1)`, for interpolation.
    pub fn step_alpha(&self) -> f32 {
        self.clock.alpha()
    }

    /// What the last step did.
    pub fn last_step(&self) -> &StepCounters {
        &self.last
    }

    /// The forces the tissue exerted on the instruments in the last step, newtons.
    pub fn forces(&self) -> &Forces {
        &self.forces
    }

    /// Elements moved by every chain reaction so far.
    pub fn elements_moved_total(&self) -> u64 {
        self.elements_moved_total
    }

    /// Commands queued for the next step (what a recorder writes down).
    pub fn pending(&self) -> &[Command] {
        &self.commands
    }

    /// Sets the regions drawn on the tissue (the exercise's target and forbidden areas).
    pub fn set_regions(&mut self, regions: Vec<SurfaceRegion>) {
        self.regions = regions;
    }

    /// Sets the planned incision drawn on the upper layer, `(u, v)` points in surface fractions.
    pub fn set_incision(&mut self, points: Vec<[f32; 2]>) {
        self.incision = points;
    }

    /// Queues a command for the next step.
    pub fn push(&mut self, command: Command) {
        self.commands.push(command);
    }

    /// The element under a picking hit (the hit's layer is the snapshot's, upper first): the element of
    /// that layer nearest the hit point (the picker's vertex is not always the nearest: when parry does
    /// not name the triangle hit it reports vertex 0, a corner), or the picked vertex if that fails.
    pub fn element_at(&self, hit: &Hit) -> Option<ElementId> {
        let layer = self.tissue.layers().get(hit.layer)?;
        self.tissue
            .nearest_element(hit.point, Some(hit.layer))
            .or_else(|| (hit.vertex < layer.count).then_some(ElementId(layer.first + hit.vertex)))
    }

    /// Advances one fixed step: input, chain reaction, normal pass, relaxation, contact, cuts and tears,
    /// bookkeeping.
    pub fn step(&mut self) -> StepCounters {
        let mut c = StepCounters { step: self.step + 1, grasp_fraction: 1.0, ..StepCounters::default() };

        // Input: consume the commands gathered since the last step.
        let t = Instant::now();
        let mut commands = std::mem::take(&mut self.commands);
        for command in commands.drain(..) {
            self.apply(command);
        }
        self.commands = commands;
        c.phase_us[0] = ms(t);

        // Chain reaction (in the surface plane, or in 3D for a volume), then the normal pass.
        let passes = self.tissue.passes();
        let inst = &mut self.instrument;
        match (inst.kind, inst.grasped) {
            (InstrumentKind::Forceps, Some(e)) => {
                let t = Instant::now();
                let (moved, f) = self.tissue.pull_pass(e, inst.target, passes[0]);
                c.moved_chain = moved;
                c.grasp_fraction = f;
                c.phase_us[1] = ms(t);
                if let Some(&normal) = passes.get(1) {
                    let t = Instant::now();
                    let (moved, f) = self.tissue.pull_pass(e, inst.target, normal);
                    c.moved_normal = moved;
                    c.grasp_fraction = c.grasp_fraction.min(f);
                    c.phase_us[2] = ms(t);
                }
                inst.tip = self.tissue.world_position(e).unwrap_or(inst.target);
            }
            (InstrumentKind::Probe, _) => {
                let t = Instant::now();
                c.moved_chain = self.tissue.push(inst.target, self.config.sizes.probe_radius);
                inst.tip = inst.target;
                c.phase_us[1] = ms(t);
            }
            _ => inst.tip = inst.target,
        }

        // Relaxation within its budget.
        let t = Instant::now();
        // (The probe's ball keeps what it presses under it: `tissue/press.rs`.)
        c.relax_sweeps = if self.instrument.kind == InstrumentKind::Probe {
            let (report, moved) = self.tissue.relax_under_probe(self.config.relax);
            c.moved_chain += moved;
            report.sweeps
        } else {
            self.tissue.relax(self.config.relax).sweeps
        };
        c.phase_us[3] = ms(t);

        // Contact between the layers.
        let t = Instant::now();
        c.contact_fixes = self.tissue.enforce_contact();
        c.limit_repairs = self.tissue.restore_limits();
        c.phase_us[4] = ms(t);

        // Cuts and tears: the one place the topology changes.
        let t = Instant::now();
        c.links_cut = self.tissue.apply_cuts();
        c.links_torn = self.tissue.apply_tears();
        if let Some(e) = self.instrument.grasped
            && !self.tissue.body().lattice().neighbours(e).any(|(_, l)| self.tissue.body().link_intact(l))
        {
            // The grasped element tore free: nothing left to hold.
            self.release();
        }
        self.tissue.end_step();
        c.phase_us[5] = ms(t);

        // Forces on the instruments, from the links of what they touch.
        let t = Instant::now();
        let dt = self.step_seconds() as f32;
        self.forces = self.gauge.measure(&mut self.tissue, &self.instrument, self.config.sizes.jaw_width, dt);
        c.phase_us[6] = ms(t);

        // Bookkeeping.
        self.step += 1;
        self.elements_moved_total += (c.moved_chain + c.moved_normal) as u64;
        self.last = c;
        c
    }

    fn release(&mut self) {
        if let Some(e) = self.instrument.grasped.take() {
            self.tissue.release_grasp();
            self.tissue.set_held(e, false);
        }
    }

    fn apply(&mut self, command: Command) {
        match command {
            Command::SetMaterial(id, m) => match self.tissue.body_mut().set_material(id, m) {
                // Links may now lie outside their new boxes: this step's repair checks them all.
                Ok(()) => self.tissue.limits_changed(),
                Err(e) => self.tissue.notice = Some(format!("material refused: {e}")),
            },
            Command::SetRelaxSweeps(n) => self.config.relax.max_sweeps = n,
            Command::Select(kind) => {
                // What the forceps hold stays clamped while another instrument is in use (two-handed
                // teasing apart); taking the forceps back takes up the grasp where it is.
                self.instrument.cutting = false;
                self.instrument.stroke.clear();
                if self.instrument.kind == InstrumentKind::Forceps && kind != InstrumentKind::Forceps {
                    self.clamp_axis = (self.instrument.axis, self.instrument.roll);
                }
                self.instrument.kind = kind;
                if kind == InstrumentKind::Forceps
                    && let Some(p) = self.instrument.grasped.and_then(|e| self.tissue.world_position(e))
                {
                    self.instrument.target = p;
                    self.instrument.tip = p;
                }
            }
            Command::MoveTo(p) => {
                if !p.iter().all(|x| x.is_finite()) {
                    return;
                }
                let from = self.instrument.target;
                self.instrument.target = p;
                if self.instrument.kind == InstrumentKind::Scalpel && self.instrument.cutting && from != p {
                    self.tissue.queue_cut(CutSegment { from, to: p, depth: self.instrument.depth });
                    self.instrument.stroke.push(p);
                }
            }
            Command::Grasp => {
                if self.instrument.kind != InstrumentKind::Forceps || self.instrument.grasped.is_some() {
                    return;
                }
                let tip = self.instrument.target;
                let top = (!self.tissue.layers().is_empty()).then_some(0);
                // The outermost layer first; the lower one where the upper is out of reach (cut away).
                let pick = [top, None].into_iter().find_map(|layer| {
                    let e = self.tissue.nearest_element(tip, layer)?;
                    let p = self.tissue.world_position(e)?;
                    (Vec3::from(p).distance(Vec3::from(tip)) <= GRASP_REACH).then_some(e)
                });
                if let Some(e) = pick {
                    self.grasp(e);
                }
            }
            Command::GraspElement(e) => {
                if self.instrument.kind == InstrumentKind::Forceps
                    && self.instrument.grasped.is_none()
                    && self.tissue.world_position(e).is_some()
                {
                    self.grasp(e);
                }
            }
            Command::Release => self.release(),
            Command::SetDepth(d) => self.instrument.depth = d,
            Command::BeginCut => {
                if self.instrument.kind == InstrumentKind::Scalpel {
                    self.instrument.cutting = true;
                    self.instrument.stroke.clear();
                    self.instrument.stroke.push(self.instrument.target);
                }
            }
            Command::EndCut => self.instrument.cutting = false,
            Command::Roll(r) => {
                if r.is_finite() {
                    self.instrument.roll = r;
                }
            }
            Command::SetAxis(a) => {
                let a = Vec3::from(a);
                let l = a.length();
                if l.is_finite() && l > 0.0 {
                    self.instrument.axis = (a / l).to_array();
                }
            }
        }
    }

    fn grasp(&mut self, e: ElementId) {
        self.instrument.grasped = Some(e);
        if self.tissue.is_fem() {
            self.tissue.set_held(e, true);
        } else {
            self.tissue.grasp(e, self.config.sizes.jaw_width);
        }
        if let Some(p) = self.tissue.world_position(e) {
            self.instrument.target = p;
            self.instrument.tip = p;
        }
    }

    /// Refills a snapshot in place.
    pub fn snapshot_into(&self, out: &mut Snapshot) {
        self.snapshot_raw_into(out);
        self.tissue.mesh_recipe().finish_snapshot(out);
    }

    /// [`World::snapshot_into`] with the layers' meshes and the fibres filled raw
    /// ([`Tissue::fill_meshes_raw`], [`Tissue::fill_fibres_raw`]): what the simulation thread
    /// publishes, finished by whoever reads it with
    /// [`MeshRecipe::finish_snapshot`](crate::tissue::MeshRecipe::finish_snapshot) (the tissue's
    /// [`Tissue::mesh_recipe`](crate::tissue::Tissue::mesh_recipe)), off the thread that steps.
    pub fn snapshot_raw_into(&self, out: &mut Snapshot) {
        out.step = self.step;
        self.tissue.fill_meshes_raw(&mut out.layers);
        self.tissue.fill_fibres_raw(&mut out.fibre_stretch);
        out.fibre_tear_stretch = self.tissue.fibre_tear_stretch();
        out.instrument = Some(self.instrument.pose());
        out.clamped = None;
        if self.instrument.kind != InstrumentKind::Forceps
            && let Some(tip) = self.instrument.grasped.and_then(|e| self.tissue.world_position(e))
        {
            let (axis, roll) = self.clamp_axis;
            out.clamped =
                Some(InstrumentPose { kind: InstrumentKind::Forceps, tip, axis, roll, closed: true });
        }
        out.regions.clone_from(&self.regions);
        out.incision.clone_from(&self.incision);
        out.cut_path.clear();
        if self.instrument.cutting {
            out.cut_path.extend_from_slice(&self.instrument.stroke);
        }
    }
}
