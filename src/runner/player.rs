//! The script player: timed actions in, one batch of instrument commands per step out.

use crate::scene::{Action, Point};
use crate::simulation::Command;
use crate::simulation::World;
use crate::snapshot::InstrumentKind;

/// The world position of a script point in `world`'s tissue.
pub fn resolve(p: &Point, world: &World) -> [f32; 3] {
    match *p {
        Point::World(x, y, z) => [x, y, z],
        Point::Surface(u, v, h) => world.tissue().surface_point(u, v, h),
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Motion {
    path: Vec<[f32; 3]>,
    /// Cumulative length at each path point.
    lengths: Vec<f32>,
    steps: u32,
    done: u32,
    end_cut: bool,
}

impl Motion {
    fn new(path: Vec<[f32; 3]>, steps: u32, end_cut: bool) -> Self {
        let mut lengths = vec![0.0];
        for w in path.windows(2) {
            let d = glam::Vec3::from(w[1]).distance(glam::Vec3::from(w[0]));
            lengths.push(lengths.last().copied().unwrap_or(0.0) + d);
        }
        Self { path, lengths, steps: steps.max(1), done: 0, end_cut }
    }

    fn at(&self, f: f32) -> [f32; 3] {
        let total = self.lengths.last().copied().unwrap_or(0.0);
        let s = f * total;
        for k in 1..self.path.len() {
            if s <= self.lengths[k] || k + 1 == self.path.len() {
                let seg = (self.lengths[k] - self.lengths[k - 1]).max(f32::MIN_POSITIVE);
                let t = ((s - self.lengths[k - 1]) / seg).clamp(0.0, 1.0);
                let (a, b) = (self.path[k - 1], self.path[k]);
                return [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
            }
        }
        self.path.first().copied().unwrap_or([0.0; 3])
    }
}

/// Plays a script into a world, one step at a time.
#[derive(Clone, Debug)]
pub struct Player {
    actions: Vec<Action>,
    next: usize,
    motion: Option<Motion>,
    wait_until: Option<u64>,
    /// The instrument and tip as this player last commanded them (commands queued this step are not
    /// applied yet, so the world cannot tell).
    kind: Option<InstrumentKind>,
    tip: Option<[f32; 3]>,
}

impl Player {
    /// A player at the start of `actions`.
    pub fn new(actions: Vec<Action>) -> Self {
        Self { actions, next: 0, motion: None, wait_until: None, kind: None, tip: None }
    }

    /// Whether every action has been played.
    pub fn finished(&self) -> bool {
        self.next >= self.actions.len() && self.motion.is_none() && self.wait_until.is_none()
    }

    /// Queues this step's commands into `world` (call before [`World::step`]).
    pub fn feed(&mut self, world: &mut World) {
        loop {
            let step = world.step_count();
            if let Some(until) = self.wait_until {
                if step < until {
                    return;
                }
                self.wait_until = None;
            }
            if let Some(m) = &mut self.motion {
                m.done += 1;
                let p = m.at(m.done as f32 / m.steps as f32);
                world.push(Command::MoveTo(p));
                self.tip = Some(p);
                if m.done >= m.steps {
                    if m.end_cut {
                        world.push(Command::EndCut);
                    }
                    self.motion = None;
                }
                return;
            }
            let Some(action) = self.actions.get(self.next).cloned() else { return };
            self.next += 1;
            self.start(action, world);
        }
    }

    fn ensure(&mut self, world: &mut World, kind: InstrumentKind) {
        if self.kind.unwrap_or(world.instrument().kind) != kind {
            self.select(world, kind);
        }
    }

    fn select(&mut self, world: &mut World, kind: InstrumentKind) {
        world.push(Command::Select(kind));
        self.kind = Some(kind);
        // Forceps taken back up where they hold the tissue: the next move starts there, not where
        // the last instrument was (the world puts the forceps' target on what they hold).
        if kind == InstrumentKind::Forceps
            && let Some(p) = world.instrument().grasped.and_then(|e| world.tissue().world_position(e))
        {
            self.tip = Some(p);
        }
    }

    fn move_to(&mut self, world: &mut World, p: [f32; 3]) {
        world.push(Command::MoveTo(p));
        self.tip = Some(p);
    }

    fn start(&mut self, action: Action, world: &mut World) {
        let step = world.step_count();
        match action {
            Action::Select(k) => self.select(world, k),
            Action::Grasp(p) => {
                self.ensure(world, InstrumentKind::Forceps);
                let p = resolve(&p, world);
                self.move_to(world, p);
                world.push(Command::Grasp);
            }
            Action::GraspElement(e) => {
                self.ensure(world, InstrumentKind::Forceps);
                world.push(Command::GraspElement(crate::chainmail::ElementId(e)));
            }
            Action::MoveTo { to, steps } => {
                let from = self.tip.unwrap_or(world.instrument().target);
                self.motion = Some(Motion::new(vec![from, resolve(&to, world)], steps, false));
            }
            Action::Release => world.push(Command::Release),
            Action::Cut { path, depth, steps } => {
                let pts: Vec<[f32; 3]> = path.iter().map(|p| resolve(p, world)).collect();
                let Some(&first) = pts.first() else { return };
                self.ensure(world, InstrumentKind::Scalpel);
                world.push(Command::SetDepth(depth));
                self.move_to(world, first);
                world.push(Command::BeginCut);
                self.motion = Some(Motion::new(pts, steps, true));
            }
            Action::Push { at, to, steps } => {
                self.ensure(world, InstrumentKind::Probe);
                let a = resolve(&at, world);
                self.move_to(world, a);
                self.motion = Some(Motion::new(vec![a, resolve(&to, world)], steps, false));
            }
            Action::Wait(n) => self.wait_until = Some(step + n as u64),
            Action::At(n) => self.wait_until = Some(n),
            Action::Command(c) => {
                match &c {
                    Command::Select(k) => self.kind = Some(*k),
                    // The world ignores a point that is not finite; so does the player, which
                    // would otherwise start its next move from it.
                    Command::MoveTo(p) if p.iter().all(|x| x.is_finite()) => self.tip = Some(*p),
                    _ => {}
                }
                world.push(c)
            }
            // The trainee's camera: for whoever shows the replay, nothing for the world.
            Action::View(_) => {}
        }
    }
}
