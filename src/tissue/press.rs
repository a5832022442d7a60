//! The probe: a ball of the scene's `probe_radius` pressing the outermost layer (or the top of a
//! volume) along the normal.
//!
//! On a surface of ChainMail the ball presses its whole footprint: every free element of the outer
//! layer within the ball's radius of its centre, across the surface, goes down to the ball's lower
//! surface above it (`R - sqrt(R² - l²)` above the ball's lowest point, `l` the element's distance
//! across the surface from the centre), and the rest of the tissue to the highest heights at or below
//! where it was that meet every bound along the normal. That is a cone of least distances from the
//! footprint, as the forceps' lift is (`chainmail::ConeLift::pressing`, `docs/implicit-lift.md`): kept
//! while the footprint stays the same, grown by the ring the press reaches, written a block at a
//! time. The dent's size and depth, and the force (the pull of the links leaving the footprint), are
//! then the same in metres at every element spacing, and a press costs about what a lift does.
//!
//! Until 2026-11-30 the ball pressed one element, the one nearest its centre, through the chain
//! reaction: that element went below its neighbours by a shear limit each, so the nearest element
//! changed from step to step and the dent's elements were moved one by one, every step (a session
//! pressing 1.5 mm into the meninges' dura and sliding took 0.9 ms a step at 512 × 384, a search of
//! every element 0.65 ms of it; pressed 6 mm in, 7.1 to 8.0 ms), and the force was one element's
//! links, which shrink with the spacing. A ChainMail volume's ball presses its top face's footprint
//! by one chain reaction of the group (`press_volume`), and a finite-element volume's holds every node
//! it meets on its surface through the condensed model (`press_fem`, since 2026-11-30: before, it
//! pressed the node nearest its centre, and the force fell from 24 to 14 mN from 8³ to 16³).
//!
//! Finding the footprint touches only it: the element under the ball's centre is found by a walk
//! across the outer layer from where the last one was (downhill in the distance across the surface),
//! the footprint by a fill from there over the layer's links, whatever their state (a cut does not
//! move the elements). The first contact of a tissue searches every surface element once.

use crate::chainmail::{ElementId, Pass, Press, RelaxBudget, RelaxReport};

use super::{Geometry, Model, Tissue};

/// The footprint's offsets may drift this share of an element spacing from the cone's before the cone
/// is started again: a thousandth (0.16 µm at 512 × 384), far below what a trainee sees.
const DRIFT: f32 = 1e-3;

/// A grid volume's top face round the ball ([`Tissue::top_window`]): the lattice's first two sizes,
/// the window's element ranges along `x` and `z`, and the element nearest the ball's centre and its
/// distance across the face.
struct TopWindow {
    nx: usize,
    ny: usize,
    i: (usize, usize),
    k: (usize, usize),
    centre: u32,
    across: f32,
    /// The ball.
    tip: [f32; 3],
    radius: f32,
}

impl TopWindow {
    /// The window's elements, row by row.
    fn elements(&self) -> impl Iterator<Item = u32> + '_ {
        let (nx, ny) = (self.nx, self.ny);
        (self.k.0..=self.k.1)
            .flat_map(move |k| (self.i.0..=self.i.1).map(move |i| (i + nx * ((ny - 1) + ny * k)) as u32))
    }

    /// How far `p` lies from the ball's centre across the face.
    fn across(&self, p: [f32; 3]) -> f32 {
        ((self.tip[0] - p[0]).powi(2) + (self.tip[2] - p[2]).powi(2)).sqrt()
    }

    /// The ball's lower surface over element `e` at `p`, `None` beyond its radius (the centre's taken
    /// within the ball whatever its distance: the ball may touch the face between elements).
    fn surface(&self, e: u32, p: [f32; 3]) -> Option<f32> {
        let (l, r) = (self.across(p), self.radius);
        let l = if e == self.centre { l.min(0.7 * r) } else { l };
        (l < r).then(|| self.tip[1] - (r * r - l * l).sqrt())
    }
}

/// The probe's state between steps.
#[derive(Clone, Debug, Default)]
pub(crate) struct Probe {
    /// The element under the ball's centre at the last push that touched the tissue.
    pub(crate) contact: Option<ElementId>,
    /// The footprint's elements the ball touched at the last push (what its force is summed over),
    /// and at the push before.
    pub(crate) patch: Vec<ElementId>,
    last: Vec<ElementId>,
    /// Where the next walk to the ball's centre starts.
    near: Option<ElementId>,
    /// The press's cone.
    pub(crate) cone: crate::chainmail::ConeLift,
    /// Presses take the chain reaction's path, one element at a time (for tests that compare).
    pub(crate) no_cone: bool,
    /// What the ball touches is held for this step's relaxation (`Tissue::relax_under_probe`).
    pub(crate) holding: bool,
    /// Where the ball was and its radius at the last press that touched the tissue, to press again
    /// after relaxation ([`Tissue::hold_press`]).
    ball: Option<([f32; 3], f32)>,
    /// The last press's footprint (ids and offsets above the ball's lowest point, `bottom`, in lattice
    /// coordinates), and the fill's marks and queue (scratch).
    seeds: Vec<u32>,
    offs: Vec<f32>,
    bottom: f32,
    marks: Vec<u64>,
    queue: Vec<u32>,
    /// A volume's press: the top face's elements the ball moves and where to (scratch).
    group: Vec<ElementId>,
    goals: Vec<[f32; 3]>,
    /// A finite-element volume's press: the top face's nodes under the ball with its surface over
    /// each, and those held there with their displacements (scratch).
    footprint: Vec<(u32, f32)>,
    imposed: Vec<(ElementId, [f32; 3])>,
}

impl Probe {
    /// A probe that has touched nothing yet.
    pub(crate) fn new() -> Self {
        Self { cone: crate::chainmail::ConeLift::pressing(), ..Self::default() }
    }
}

impl Tissue {
    /// The probe: a ball of `radius` at world point `tip` pushes the surface of the outermost layer
    /// (layered) or the top of a volume where it meets it. Returns the elements moved.
    pub fn push(&mut self, tip: [f32; 3], radius: f32) -> u32 {
        let touched = self.probe.contact.take();
        std::mem::swap(&mut self.probe.patch, &mut self.probe.last);
        self.probe.patch.clear();
        let moved = match self.geometry {
            Geometry::Volume if self.is_fem() => self.press_fem(tip, radius),
            _ if self.is_fem() || self.probe.no_cone => self.push_one(tip, radius),
            Geometry::Surface(_) => self.press(tip, radius, true),
            Geometry::Volume => self.press_volume(tip, radius),
        };
        // What the probe pressed in and no longer touches settles back (`settle.rs`).
        if let (Some(e), None) = (touched, self.probe.contact) {
            let last = std::mem::take(&mut self.probe.last);
            self.settle_from(last.iter().copied().chain([e]));
            self.probe.last = last;
        }
        moved
    }

    /// The elements the ball touched at the last push (empty when it touched nothing): the probe's
    /// force is the pull of the links leaving them.
    pub fn probe_patch(&self) -> &[ElementId] {
        &self.probe.patch
    }

    /// The step's relaxation while the probe is in hand: what the ball touches is held where it is
    /// (relaxation would lift a dent back toward rest, into the ball), and the ball then presses again
    /// whatever else of its footprint relaxation raised into it ([`Tissue::hold_press`]), so that a
    /// step leaves the tissue under the ball, as the forceps' jaws leave what they hold where they
    /// hold it. Held, the touched elements let the region round the dent settle, as round a lift.
    /// Returns the relaxation's report and the elements the second press moved.
    pub fn relax_under_probe(&mut self, budget: RelaxBudget) -> (RelaxReport, u32) {
        // (Held for the relaxation only, without a new revision: the sweeps read the flags as they
        // are, and the holds are gone before anything else looks; the patch holds free elements.)
        let patch = std::mem::take(&mut self.probe.patch);
        for &e in &patch {
            self.body.set_held_for_pull(e, true);
        }
        self.probe.holding = !patch.is_empty();
        let report = self.relax(budget);
        self.probe.holding = false;
        for &e in &patch {
            self.body.set_held_for_pull(e, false);
        }
        self.probe.patch = patch;
        (report, self.hold_press())
    }

    /// After the step's relaxation: the ball presses again what relaxation raised into it (its
    /// footprint's free elements). Searches only through what moves, unless the press's cone is kept.
    /// Returns the elements moved.
    pub fn hold_press(&mut self) -> u32 {
        match (self.probe.ball, self.geometry) {
            (Some((tip, radius)), Geometry::Surface(_)) if self.probe.contact.is_some() => {
                self.press(tip, radius, false)
            }
            (Some((tip, radius)), Geometry::Volume) if self.probe.contact.is_some() => {
                self.press_volume(tip, radius)
            }
            _ => 0,
        }
    }

    /// The ball presses its footprint by the cone (see the module); `whole`: see
    /// `Body::press_by_cone`.
    fn press(&mut self, tip: [f32; 3], radius: f32, whole: bool) -> u32 {
        self.probe.ball = None;
        let Some(layer) = self.layers.first() else { return 0 };
        let (first, count) = (layer.first, layer.count);
        let in_layer = |e: u32| e >= first && e - first < count;
        let start = match self.probe.near.filter(|e| in_layer(e.0)) {
            Some(e) => e,
            None => match self.nearest_element(tip, Some(0)) {
                Some(e) => e,
                None => return 0,
            },
        };
        let centre = self.walk_across(start, tip, first, count);
        self.probe.near = Some(centre);
        let Ok(c) = self.body.position(centre) else { return 0 };
        let t = self.geometry.to_lattice(tip, c[0]);
        // (The ball's centre in lattice coordinates taken near each element, so that a footprint
        // across a wrapped surface's seam is whole.)
        let geometry = self.geometry;
        let across = |p: [f32; 3]| {
            let t = geometry.to_lattice(tip, p[0]);
            ((t[0] - p[0]).powi(2) + (t[1] - p[1]).powi(2)).sqrt()
        };
        if across(c) >= radius + self.spacing {
            return 0;
        }
        // The footprint: a fill over the layer's links from the centre, within the radius.
        let n = self.body.element_count();
        let Probe { seeds, offs, marks, queue, bottom: ball_bottom, .. } = &mut self.probe;
        seeds.clear();
        offs.clear();
        queue.clear();
        marks.resize(n.div_ceil(64), 0);
        let pos = self.body.positions();
        let lattice = self.body.lattice();
        let mark = |marks: &mut Vec<u64>, e: u32| {
            let (w, b) = (e as usize / 64, 1u64 << (e % 64));
            let fresh = marks.get(w).is_some_and(|x| x & b == 0);
            if let Some(x) = marks.get_mut(w) {
                *x |= b;
            }
            fresh
        };
        mark(marks, centre.0);
        queue.push(centre.0);
        let mut next = 0;
        let mut touching = false;
        // The ball's lowest point; each element's goal lies `R - sqrt(R² - l²)` above it.
        let bottom = t[2] - radius;
        *ball_bottom = bottom;
        while let Some(&e) = queue.get(next) {
            next += 1;
            let Some(&p) = pos.get(e as usize) else { continue };
            let l = across(p);
            // (The centre is kept whatever its distance: the ball may touch between elements.)
            let l = if e == centre.0 { l.min(0.7 * radius) } else { l };
            if l >= radius {
                continue;
            }
            let off = radius - (radius * radius - l * l).sqrt();
            if !(self.body.is_pinned(ElementId(e)) || self.body.is_held(ElementId(e))) {
                seeds.push(e);
                offs.push(off);
                touching |= p[2] >= bottom + off - 0.01 * self.spacing;
            }
            for (m, _) in lattice.neighbours(ElementId(e)) {
                if in_layer(m.0) && mark(marks, m.0) {
                    queue.push(m.0);
                }
            }
        }
        for &e in queue.iter() {
            if let Some(x) = marks.get_mut(e as usize / 64) {
                *x = 0;
            }
        }
        if !touching {
            return 0;
        }
        let tolerance = DRIFT * self.spacing;
        let (seeds, offs) = (std::mem::take(&mut self.probe.seeds), std::mem::take(&mut self.probe.offs));
        let ball = Press { seeds: &seeds, offs: &offs, goal: bottom, tolerance, whole };
        let moved = self.body.press_by_cone(&mut self.ws, &mut self.probe.cone, &ball);
        if moved.is_some_and(|m| m > 0) {
            self.activate_moved();
        }
        // In contact: the footprint's elements now on the ball's surface (within a hundredth of a
        // spacing).
        self.probe.contact = Some(centre);
        self.probe.ball = Some((tip, radius));
        self.probe.patch.clear();
        let pos = self.body.positions();
        for (&e, &o) in seeds.iter().zip(&offs) {
            if pos.get(e as usize).is_some_and(|p| p[2] >= bottom + o - 0.01 * self.spacing) {
                self.probe.patch.push(ElementId(e));
            }
        }
        self.probe.seeds = seeds;
        self.probe.offs = offs;
        moved.unwrap_or(0)
    }

    /// From `start`, the element of the layer `first .. first + count` nearest the point `tip` across
    /// the surface: each step goes to the neighbour (along any of the layer's links) nearest it, until
    /// none is nearer.
    fn walk_across(&self, start: ElementId, tip: [f32; 3], first: u32, count: u32) -> ElementId {
        let pos = self.body.positions();
        let lattice = self.body.lattice();
        let across = |e: ElementId| {
            pos.get(e.index()).map_or(f32::INFINITY, |&p| {
                let t = self.geometry.to_lattice(tip, p[0]);
                (t[0] - p[0]).powi(2) + (t[1] - p[1]).powi(2)
            })
        };
        let (mut at, mut d) = (start, across(start));
        // (Each step is strictly nearer: the walk ends, at most once through the layer.)
        for _ in 0..count {
            let best = lattice
                .neighbours(at)
                .filter(|(m, _)| m.0 >= first && m.0 - first < count)
                .map(|(m, _)| (across(m), m))
                .fold(None, |b: Option<(f32, ElementId)>, x| match b {
                    Some(b) if b.0 <= x.0 => Some(b),
                    _ => Some(x),
                });
            match best {
                Some((dm, m)) if dm < d => (at, d) = (m, dm),
                _ => break,
            }
        }
        at
    }

    /// A ball pressing a volume's top face (`y` up, lattice coordinates are world coordinates): every
    /// free element of the face within the ball's radius of its centre across the face (`x`, `z`) and
    /// above the ball's lower surface there goes down to it, together, by one chain reaction of the
    /// group. The face is a grid, so the footprint is read from the elements whose rest position lies
    /// within the radius and two spacings (the face's elements move across it by no more than their
    /// shear limits allow): the work is the footprint's and what it moves, at any resolution. The
    /// element nearest the centre is pressed whatever its distance within a spacing past the radius,
    /// as on a surface: a ball smaller than the spacing touches the face between elements.
    fn press_volume(&mut self, tip: [f32; 3], radius: f32) -> u32 {
        self.probe.ball = None;
        let Some(w) = self.top_window(tip, radius) else { return self.push_one(tip, radius) };
        if w.across >= radius + self.spacing {
            return 0;
        }
        let pos = self.body.positions();
        // The ball's lower surface over a free element of its footprint.
        let surface = |body: &crate::chainmail::Body, e: u32, p: [f32; 3]| {
            let free = !(body.is_pinned(ElementId(e)) || body.is_held(ElementId(e)));
            free.then(|| w.surface(e, p)).flatten()
        };
        // In contact: within a hundredth of a spacing of it.
        let reach = 0.01 * self.spacing;
        let Probe { group, goals, patch, .. } = &mut self.probe;
        group.clear();
        goals.clear();
        patch.clear();
        let mut touching = false;
        for e in w.elements() {
            let Some(&p) = pos.get(e as usize) else { continue };
            let Some(limit) = surface(&self.body, e, p) else { continue };
            touching |= p[1] >= limit - reach;
            if p[1] > limit {
                group.push(ElementId(e));
                goals.push([p[0], limit, p[2]]);
            }
        }
        if !touching {
            return 0;
        }
        let (group, goals) = (std::mem::take(&mut self.probe.group), std::mem::take(&mut self.probe.goals));
        let mut moved = 0;
        if !group.is_empty()
            && let Ok(d) = self.body.deform_group(&mut self.ws, &group, &goals, Pass::All)
        {
            moved = d.moved;
            self.activate_moved();
        }
        self.probe.group = group;
        self.probe.goals = goals;
        // In contact: the footprint's elements now on the ball's surface.
        self.probe.contact = Some(ElementId(w.centre));
        self.probe.ball = Some((tip, radius));
        let body = &self.body;
        let pos = body.positions();
        for e in w.elements() {
            if let Some(&p) = pos.get(e as usize)
                && surface(body, e, p).is_some_and(|limit| p[1] >= limit - reach)
            {
                self.probe.patch.push(ElementId(e));
            }
        }
        moved
    }

    /// The window of a grid volume's top face round a ball at `tip` of `radius`: the elements whose
    /// rest position lies within the radius and two spacings across the face (the face's elements move
    /// across it by no more than their limits allow), and the one of them nearest the ball's centre
    /// across the face now. `None` for a lattice that is not a grid.
    fn top_window(&self, tip: [f32; 3], radius: f32) -> Option<TopWindow> {
        let [nx, ny, nz] = self.body.lattice().dims()?;
        let rest = self.body.lattice().rest_positions();
        let (&r0, &rx, &rz) =
            (rest.first()?, rest.get(1.min(nx - 1))?, rest.get((nx * ny).min(rest.len() - 1))?);
        let (dx, dz) = ((rx[0] - r0[0]).max(f32::MIN_POSITIVE), (rz[2] - r0[2]).max(f32::MIN_POSITIVE));
        let window = |t: f32, lo: f32, d: f32, n: usize| {
            let a = ((t - radius - lo) / d).floor() - 2.0;
            let b = ((t + radius - lo) / d).ceil() + 2.0;
            let clip = |x: f32| if x.is_finite() { x.clamp(0.0, (n - 1) as f32) as usize } else { 0 };
            (clip(a), clip(b))
        };
        let (i, k) = (window(tip[0], r0[0], dx, nx), window(tip[2], r0[2], dz, nz));
        let mut w = TopWindow { nx, ny, i, k, centre: 0, across: f32::INFINITY, tip, radius };
        let pos = self.body.positions();
        let mut centre: Option<(u32, f32)> = None;
        for e in w.elements() {
            let d = pos.get(e as usize).map_or(f32::INFINITY, |&p| w.across(p));
            if centre.is_none_or(|(_, c)| d < c) {
                centre = Some((e, d));
            }
        }
        (w.centre, w.across) = centre?;
        Some(w)
    }

    /// The ball on a finite-element volume: every node of the top face it meets is held on the ball's
    /// lower surface (where it was across the face), all at once, by the condensed model. Contact is
    /// one-sided: a node the ball would have to pull up to hold there is let go, and a node the dent
    /// brings into the ball joins, until neither happens (a few rounds). The force on the probe is the
    /// sum of the forces that hold them. When the ball no longer touches the block, the block goes
    /// back to rest. Returns the surface nodes written.
    fn press_fem(&mut self, tip: [f32; 3], radius: f32) -> u32 {
        /// Rounds of letting go and taking in.
        const ROUNDS: usize = 8;
        self.probe.ball = None;
        let Some(w) = self.top_window(tip, radius) else { return self.push_one(tip, radius) };
        let reach = 0.01 * self.spacing;
        let (rest, pos) = (self.body.lattice().rest_positions(), self.body.positions());
        let Model::Fem(fem) = &mut self.model else { return 0 };
        let Probe { footprint, imposed, last, .. } = &mut self.probe;
        // The nodes under the ball and its surface over each; those it meets now (in contact, or
        // inside it) are held there.
        footprint.clear();
        imposed.clear();
        if w.across < radius + self.spacing {
            for e in w.elements() {
                if let Some(&p) = pos.get(e as usize)
                    && let Some(limit) = w.surface(e, p)
                {
                    footprint.push((e, limit));
                }
            }
        }
        let at = |e: u32, limit: f32, d: [f32; 3]| (ElementId(e), [d[0], limit - rest[e as usize][1], d[2]]);
        for &(e, limit) in footprint.iter() {
            let (p, r) = (pos[e as usize], rest[e as usize]);
            if p[1] >= limit - reach {
                imposed.push(at(e, limit, [p[0] - r[0], p[1] - r[1], p[2] - r[2]]));
            }
        }
        if imposed.is_empty() && last.is_empty() {
            return 0; // not pressing, and was not
        }
        let mut error = None;
        // Whether the last solve was of the set now held.
        let mut solved = false;
        for _ in 0..ROUNDS {
            if imposed.is_empty() {
                break;
            }
            let forces = match fem.impose_many(imposed, false) {
                Ok(f) => f,
                Err(e) => {
                    error = Some(e.to_string());
                    break;
                }
            };
            // A ball pushes: what it would have to pull up is let go.
            let before = imposed.len();
            let mut kept = forces.iter().map(|f| f[1] <= 0.0);
            imposed.retain(|_| kept.next().unwrap_or(false));
            solved = imposed.len() == before;
            // What the dent brings into the ball joins.
            for &(e, limit) in footprint.iter() {
                if imposed.iter().any(|&(n, _)| n.0 == e) {
                    continue;
                }
                if let Some(d) = fem.displacement(ElementId(e))
                    && rest[e as usize][1] + d[1] > limit + reach
                {
                    imposed.push(at(e, limit, d));
                    solved = false;
                }
            }
            if solved {
                break;
            }
        }
        if imposed.is_empty() {
            // Let go: the block goes back to rest.
            return fem.release(&mut self.body);
        }
        // The set held, solved (again, where the rounds ended on a change) and a dynamic block's step.
        if (!solved || fem.is_dynamic())
            && let Err(e) = fem.impose_many(imposed, true)
        {
            error = Some(e.to_string());
        }
        if let Some(e) = error {
            self.notice = Some(e);
        }
        self.probe.contact = Some(ElementId(w.centre));
        self.probe.patch.extend(self.probe.imposed.iter().map(|&(e, _)| e));
        fem.write_into(&mut self.body)
    }

    /// A ball pressing the one element nearest its centre by the chain reaction (a lattice that is
    /// not a grid, and tests comparing with the cone).
    fn push_one(&mut self, tip: [f32; 3], radius: f32) -> u32 {
        let Some(e) = self.nearest_element(tip, Some(0)) else { return 0 };
        let Ok(p) = self.body.position(e) else { return 0 };
        let t = self.geometry.to_lattice(tip, p[0]);
        let (axis, pass) = match self.geometry {
            Geometry::Surface(_) => (2, Pass::Normal),
            Geometry::Volume => (1, Pass::All),
        };
        // In contact when the element lies inside the ball, measured across the surface.
        let lateral = match self.geometry {
            Geometry::Surface(_) => ((t[0] - p[0]).powi(2) + (t[1] - p[1]).powi(2)).sqrt(),
            Geometry::Volume => ((t[0] - p[0]).powi(2) + (t[2] - p[2]).powi(2)).sqrt(),
        };
        // The ball touches the surface between elements too: the nearest element carries the push.
        if lateral >= radius + self.spacing {
            return 0;
        }
        let l = lateral.min(0.7 * radius);
        let depth = (radius * radius - l * l).sqrt();
        let limit = t[axis] - depth;
        if p[axis] >= limit - 0.01 * self.spacing {
            self.probe.contact = Some(e);
            self.probe.patch.clear();
            self.probe.patch.push(e);
        }
        if p[axis] <= limit {
            return 0;
        }
        let mut goal = p;
        goal[axis] = limit;
        self.displace(e, goal, pass).0
    }
}

#[cfg(test)]
mod tests {
    use crate::chainmail::{ElementId, RelaxBudget, press_plain};
    use crate::tissue::Tissue;

    fn meninges(res: [u32; 2]) -> Tissue {
        let scene = crate::scene::Scene::from_str(include_str!("../../scenes/meninges.ron"), "meninges.ron")
            .expect("scene")
            .with_resolution(res[0], res[1]);
        scene.build_world(false).expect("world").tissue().clone()
    }

    /// The positions after a press against the plain reference from `before`, to 0.1 µm; counts the
    /// presses that touched and those whose search went only through what moved.
    fn check(
        t: &Tissue,
        before: &crate::chainmail::Body,
        step: usize,
        pressed: &mut usize,
        searched: &mut usize,
        blocks: &mut usize,
    ) {
        if t.probe.contact.is_none() {
            return;
        }
        *pressed += 1;
        *searched += usize::from(!t.probe.cone.is_complete());
        let seeds: Vec<(ElementId, f32)> = t
            .probe
            .seeds
            .iter()
            .zip(&t.probe.offs)
            .map(|(&e, &o)| (ElementId(e), t.probe.bottom + o))
            .collect();
        let want = press_plain(before, &seeds);
        let (pos, was) = (t.body().positions(), before.positions());
        // Pinned elements never move; where the reference (which takes them as free) would move one,
        // the press stops short of it, above the reference everywhere.
        let pinned = |j: usize| t.body().is_pinned(ElementId(j as u32));
        let blocked = (0..pos.len()).any(|j| pinned(j) && want[j] < was[j][2] - 1e-9);
        for (j, (p, w)) in pos.iter().zip(&want).enumerate() {
            if pinned(j) {
                assert_eq!(p[2], was[j][2], "step {step}: pinned element {j} moved");
            } else if blocked {
                assert!(
                    p[2] >= w - 1e-7 && p[2] <= was[j][2],
                    "step {step}: element {j} at {} (reference {w})",
                    p[2]
                );
            } else {
                assert!((p[2] - w).abs() <= 1e-7, "step {step}: element {j} at {} against {w}", p[2]);
            }
        }
        *blocks += usize::from(blocked);
    }

    /// Every press by the cone leaves every element where the plain reference puts it (each footprint
    /// element at or under the ball, every bound along the normal pushing down what it must, swept
    /// until nothing falls), to a tenth of a micrometre: pressing in (the cone kept and grown), held
    /// still (started again, then kept), sliding across by a third of a spacing a step (searched
    /// through what moves, by its queue and by the heap), lifted away, then 4 mm deep and sliding back
    /// (stopped short of the pins: there every element at or above the reference, and no pin moved);
    /// each step's press, and its press again after the step's relaxation ([`Tissue::hold_press`]).
    #[test]
    fn a_press_is_the_plain_press() {
        let mut t = meninges([48, 36]);
        let r = 0.003;
        let h = 0.003 + r; // the ball resting on the dura
        let (mut pressed, mut searched, mut blocks) = (0, 0, 0);
        for step in 0..170 {
            let (u, depth) = match step {
                0..40 => (0.5, 0.0015 * step as f32 / 40.0),
                40..60 => (0.5, 0.0015),
                60..120 => (0.5 + (step - 60) as f32 * t.spacing / 3.0 / 0.08, 0.0015),
                120..140 => (0.6, 0.0015 - 0.0001 * (step - 120) as f32),
                // Deep and sliding back: elements reached closer again and again, the search
                // going on by the heap.
                _ => (0.6 - (step - 140) as f32 * t.spacing / 0.08, 0.004),
            };
            let tip = t.surface_point(u, 0.5, h - depth);
            // The step's press, then the press again after its relaxation.
            let before = t.body().clone();
            t.push(tip, r);
            check(&t, &before, step, &mut pressed, &mut searched, &mut blocks);
            // (Relaxation as the step runs it, what the ball touches held, then the press again.)
            let patch = t.probe.patch.clone();
            for &e in &patch {
                t.body.set_held_for_pull(e, true);
            }
            t.relax(RelaxBudget::sweeps(4));
            for &e in &patch {
                t.body.set_held_for_pull(e, false);
            }
            let before = t.body().clone();
            t.hold_press();
            check(&t, &before, step, &mut pressed, &mut searched, &mut blocks);
            for &e in &patch {
                assert!(!t.body().is_held(e), "step {step}: the ball's hold outlived the relaxation");
            }
            t.end_step();
        }
        assert!(pressed > 200 && searched > 60, "{pressed} presses, {searched} searched through what moves");
        let by_heap = t.probe.cone.cone().by_heap_searches;
        assert!(
            by_heap > 0 && (by_heap as usize) < searched,
            "{by_heap} of {searched} searches went on by the heap"
        );
        assert!(blocks > 0, "no press stopped short of a pin");
    }
}
