//! A deformable body: a lattice with current positions, pins, materials and broken links.

use rustc_hash::FxHashMap;

use super::coords::{norm, sub};
use super::error::{ChainMailError, finite};
use super::ids::{ElementId, LinkId, MaterialId};
use super::lattice::Lattice;
use super::material::Material;

/// An empty memo of interned classes: no class has these bits (a NaN weight).
const NO_MEMO: [([u32; 8], u32); MEMO] = [([u32::MAX; 8], 0); MEMO];

/// How many interned classes [`Body::intern`] remembers.
const MEMO: usize = 8;

/// Element flag: pinned by the scene (held by surrounding anatomy); never moved.
pub(crate) const PINNED: u8 = 1;
/// Element flag: held by an instrument; moved only as the grasp's source.
pub(crate) const HELD: u8 = 2;
/// Either flag: the element is not moved by the chain reaction of another element, nor by relaxation.
pub(crate) const FIXED: u8 = PINNED | HELD;

/// Link state: intact.
pub(crate) const INTACT: u8 = 0;

/// Why a link broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum BreakReason {
    /// Cut by an instrument.
    Cut = 1,
    /// Torn by over-stretching.
    Tear = 2,
}

/// A lattice with state: what moves.
#[derive(Clone, Debug)]
pub struct Body {
    pub(crate) lattice: Lattice,
    pub(crate) pos: Vec<[f32; 3]>,
    pub(crate) flags: Vec<u8>,
    /// The pinned elements, in the order they were pinned (kept with the flags by
    /// [`Body::set_pinned`], so that what asks about the pins reads them, not every element).
    pinned: Vec<ElementId>,
    pub(crate) materials: Vec<Material>,
    pub(crate) link_material: Vec<MaterialId>,
    /// Constraint box `[lo, hi]` on `p[b] - p[a]`, with the wrap jump folded in.
    pub(crate) link_box: Vec<[[f32; 3]; 2]>,
    pub(crate) link_state: Vec<u8>,
    /// Width of the fixed-width (ELL) adjacency below: the lattice's largest degree (at least 1).
    /// Element `i` owns slots `i * width .. (i + 1) * width`: its lattice adjacency entries in the
    /// lattice's order, then padding slots that point back at `i` itself. A constant trip count
    /// lets the hot loops run without per-element bounds and unroll on grids (width 4 or 6).
    pub(crate) width: usize,
    /// Neighbour of each slot (the owner itself for padding).
    pub(crate) slot_nbr: Vec<u32>,
    /// Class of each slot: an index into `classes`. Slots share classes (a uniform grid has a handful),
    /// so the hot loops read 8 bytes per slot and find the boxes in cache.
    pub(crate) slot_class: Vec<u32>,
    /// For each slot column `t` (`class_words` words each, the last one spare), one bit per element:
    /// set where the element's class in slot `t` differs from the previous element's, and for
    /// element 0. Elements in a row whose links through a slot are alike read as clear bits, so the
    /// chain reaction checks sixteen elements' classes with one load rather than sixteen strided ones.
    pub(crate) class_change: Vec<u64>,
    pub(crate) class_words: usize,
    /// The distinct slot classes; entry 0 is [`SlotClass::FREE`].
    pub(crate) classes: Vec<SlotClass>,
    /// Where each class sits in `classes`, by its bits.
    class_index: FxHashMap<[u32; 8], u32>,
    /// The last classes interned, by their bits, the newest first (see [`Body::intern`]).
    class_memo: [([u32; 8], u32); MEMO],
    /// Which lattice this body was built on: a number no other body's lattice has (clones share it).
    /// A workspace keeps tables of the lattice it last served under this number.
    pub(crate) shape: u64,
    /// Which pins, holds, cuts and materials the body has: a new number on each change, shared only
    /// by clones with the same ones. A workspace's grid tables are rebuilt when it changes.
    pub(crate) revision: u64,
    /// A fresh number whenever a link's box, its slots' classes or its material may have changed (and
    /// the class table renumbered): what a cache of them (the tear scan's table) is keyed by. Cuts
    /// and tears leave it be (they change the broken link's slots only, which no cache reads).
    pub(crate) boxes_epoch: u64,
    /// How often positions changed: a new count whenever any element may have moved (a chain
    /// reaction that kept moves, a relaxation, a direct write). What a blocked pull measured stays
    /// true while it and the revision stay the same.
    pub(crate) motion: u64,
    /// How often positions changed other than by the in-place relaxation of a region (see
    /// [`Body::shifts`]).
    pub(crate) shifts: u64,
    /// Elements whose normal offset is bounded without a link between them (see `pairs.rs`).
    pub(crate) pairs: super::pairs::Pairs,
    /// The elastic cells of a volume whose material has a Poisson's ratio (`relax/elastic.rs`).
    pub(crate) elastic: super::relax::Elastic,
    /// How many links have broken (links never mend): with `boxes_epoch`, what the elastic cells
    /// depend on.
    pub(crate) broken: u64,
    /// The broken links, in the order they broke (see [`Body::broken_links`]).
    broken_links: Vec<LinkId>,
}

/// A number no earlier call returned (for [`Body::shape`] and [`Body::revision`]).
pub(crate) fn fresh_number() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// What a slot's link demands, as seen from the slot's owner.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct SlotClass {
    /// Constraint box `[lo, hi]` on `p[owner] - p[nbr]`, wrap jump folded in.
    pub(crate) bounds: [[f32; 3]; 2],
    /// Relaxation weight: the link's stiffness.
    pub(crate) w: f32,
}

impl SlotClass {
    /// Broken links and padding slots: an infinite box and no weight, so such a slot neither pulls a
    /// candidate nor bounds or drives a relaxation step.
    pub(crate) const FREE: Self = Self { bounds: [[f32::NEG_INFINITY; 3], [f32::INFINITY; 3]], w: 0.0 };

    fn key(&self) -> [u32; 8] {
        let [lo, hi] = self.bounds;
        [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], self.w, 0.0].map(f32::to_bits)
    }
}

impl Body {
    /// A body at rest with every link of `material`.
    pub fn new(lattice: Lattice, material: Material) -> Result<Self, ChainMailError> {
        material.validate()?;
        let n = lattice.element_count();
        let m = lattice.link_count();
        let width = (0..n)
            .map(|i| (lattice.adj_start[i + 1] - lattice.adj_start[i]) as usize)
            .max()
            .unwrap_or(0)
            .max(1);
        let mut slot_nbr = Vec::with_capacity(n * width);
        for i in 0..n {
            let (s0, s1) = (lattice.adj_start[i] as usize, lattice.adj_start[i + 1] as usize);
            slot_nbr.extend_from_slice(&lattice.adj_nbr[s0..s1]);
            slot_nbr.resize((i + 1) * width, i as u32);
        }
        // Every slot starts in class 0, so only element 0's bits are set.
        let class_words = n.div_ceil(64) + 1;
        let mut class_change = vec![0; width * class_words];
        for t in 0..width {
            class_change[t * class_words] = 1;
        }
        let mut body = Self {
            width,
            class_change,
            class_words,
            slot_class: vec![0; slot_nbr.len()],
            classes: vec![SlotClass::FREE],
            class_index: FxHashMap::from_iter([(SlotClass::FREE.key(), 0)]),
            class_memo: NO_MEMO,
            slot_nbr,
            pos: lattice.rest.clone(),
            flags: vec![0; n],
            pinned: Vec::new(),
            materials: vec![material],
            link_material: vec![MaterialId(0); m],
            link_box: vec![[[0.0; 3]; 2]; m],
            link_state: vec![INTACT; m],
            lattice,
            shape: fresh_number(),
            revision: 0,
            boxes_epoch: 0,
            motion: 0,
            shifts: 0,
            pairs: Default::default(),
            elastic: Default::default(),
            broken: 0,
            broken_links: Vec::new(),
        };
        for l in 0..m {
            body.update_link_box(l);
        }
        body.touch();
        Ok(body)
    }

    /// Gives the body a new revision: pins, holds, cuts or materials changed.
    fn touch(&mut self) {
        self.revision = fresh_number();
    }

    fn update_link_box(&mut self, l: usize) {
        self.set_link_box(l);
        self.update_pairs_of_link(l);
    }

    /// [`Body::update_link_box`] but for the normal pairs through the link.
    fn set_link_box(&mut self, l: usize) {
        self.touch();
        self.boxes_epoch = self.revision;
        let lat = &self.lattice;
        let mat = &self.materials[self.link_material[l].index()];
        let (lo, hi) = mat.link_box(lat.rest_offset[l], lat.axis[l] as usize, lat.scale[l]);
        let j = lat.jump[l];
        let [lo, hi] = [sub(lo, j), sub(hi, j)];
        self.link_box[l] = [lo, hi];
        if self.link_state[l] == INTACT {
            let [sa, sb] = self.slots_of(l);
            // `a`'s slot bounds `p[a] - p[b]`, the negated box; `b`'s slot bounds `p[b] - p[a]`.
            let w = mat.stiffness;
            let ca = self.intern(SlotClass { bounds: [hi.map(|x| -x), lo.map(|x| -x)], w });
            self.set_slot_class(sa, ca);
            let cb = self.intern(SlotClass { bounds: [lo, hi], w });
            self.set_slot_class(sb, cb);
        }
    }

    /// Sets slot `k`'s class and the change bits of its owner and the owner's successor (the class
    /// table's rebuild renumbers classes but keeps which slots share one, so it leaves the bits be).
    fn set_slot_class(&mut self, k: usize, class: u32) {
        self.slot_class[k] = class;
        let (w, n) = (self.width, self.pos.len());
        let (i, t) = (k / w, k % w);
        for e in [i, i + 1] {
            if e < n {
                let differ = e == 0 || self.slot_class[e * w + t] != self.slot_class[(e - 1) * w + t];
                let (word, bit) = (t * self.class_words + e / 64, e % 64);
                self.class_change[word] = self.class_change[word] & !(1 << bit) | (differ as u64) << bit;
            }
        }
    }

    /// The index of `class` in the class table, added if new. Classes no slot uses any more (after
    /// material changes) are dropped by rebuilding the table once it holds more than twice the
    /// classes the slots could need.
    fn intern(&mut self, class: SlotClass) -> u32 {
        // The last classes interned: a link's two slots, and the next links', usually among them.
        let key = class.key();
        if let Some(&(_, i)) = self.class_memo.iter().find(|m| m.0 == key) {
            return i;
        }
        let i = self.intern_new(class, key);
        self.class_memo.rotate_right(1);
        self.class_memo[0] = (key, i);
        i
    }

    /// [`Body::intern`] past its memo.
    fn intern_new(&mut self, class: SlotClass, key: [u32; 8]) -> u32 {
        if let Some(&i) = self.class_index.get(&key) {
            return i;
        }
        if self.classes.len() > 2 * self.slot_class.len() + 16 {
            self.rebuild_classes();
            if let Some(&i) = self.class_index.get(&key) {
                return i;
            }
        }
        let i = self.classes.len() as u32;
        self.classes.push(class);
        self.class_index.insert(key, i);
        i
    }

    /// Rebuilds the class table with only the classes in use.
    fn rebuild_classes(&mut self) {
        self.class_memo = NO_MEMO;
        let old = std::mem::replace(&mut self.classes, vec![SlotClass::FREE]);
        self.class_index = FxHashMap::from_iter([(SlotClass::FREE.key(), 0)]);
        for k in 0..self.slot_class.len() {
            let c = old[self.slot_class[k] as usize];
            let i = match self.class_index.get(&c.key()) {
                Some(&i) => i,
                None => {
                    self.classes.push(c);
                    let i = self.classes.len() as u32 - 1;
                    self.class_index.insert(c.key(), i);
                    i
                }
            };
            self.slot_class[k] = i;
        }
    }

    /// The two slots of link `l` (in its `a` end's row, in its `b` end's row).
    fn slots_of(&self, l: usize) -> [usize; 2] {
        let lat = &self.lattice;
        let [a, b] = lat.ends[l];
        let [ea, eb] = lat.link_slots[l];
        [
            a as usize * self.width + (ea - lat.adj_start[a as usize]) as usize,
            b as usize * self.width + (eb - lat.adj_start[b as usize]) as usize,
        ]
    }

    /// The lattice this body is built on.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.pos.len()
    }

    /// Number of links.
    pub fn link_count(&self) -> usize {
        self.link_state.len()
    }

    /// Current positions, lattice coordinates.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.pos
    }

    /// Current position of one element.
    pub fn position(&self, e: ElementId) -> Result<[f32; 3], ChainMailError> {
        self.check_element(e)?;
        Ok(self.pos[e.index()])
    }

    /// Sets an element's position directly, without a chain reaction (for set-up and tests).
    pub fn set_position(&mut self, e: ElementId, p: [f32; 3]) -> Result<(), ChainMailError> {
        self.check_element(e)?;
        for &x in &p {
            finite("position", x)?;
        }
        self.pos[e.index()] = p;
        self.note_motion();
        Ok(())
    }

    /// Puts every element back at its rest position (broken links stay broken).
    pub fn reset_to_rest(&mut self) {
        self.pos.copy_from_slice(&self.lattice.rest);
        self.note_motion();
    }

    /// Counts a change of positions (see [`Body::motion`] and [`Body::shifts`]).
    pub(crate) fn note_motion(&mut self) {
        self.motion = self.motion.wrapping_add(1);
        self.shifts = self.shifts.wrapping_add(1);
    }

    /// Counts a change of positions made by the in-place relaxation of a region
    /// (`Body::sweep_region`), which moves free elements only, each into the boxes around its
    /// neighbours as they are, so that every bound that held still holds: a new [`Body::motion`],
    /// the same [`Body::shifts`].
    pub(crate) fn note_relaxation(&mut self) {
        self.motion = self.motion.wrapping_add(1);
    }

    /// The body's motion count: it changes whenever any element may have moved, so two equal
    /// counts (with equal revisions) mean the same positions.
    pub fn motion(&self) -> u64 {
        self.motion
    }

    /// The body's count of moves but those of a region's in-place relaxation (`Tissue::relax`): two
    /// equal counts (with equal revisions) mean that no pinned or held element has moved, and no
    /// free one other than by relaxing within the boxes around its neighbours.
    ///
    /// What a pull asks of a fixed element depends on these alone: the bounds on each coordinate of
    /// the elements' positions are difference constraints (along the normal `z[x] - z[y]` within
    /// `[lo, hi]`), so a source raised to `z` asks each element to reach at least `z` less the
    /// shortest chain of upper bounds from the source to it (the least heights that meet the bounds
    /// the reaction's moves disturb, which Gibson's lists and the completion find:
    /// `reaction/complete.rs`), and likewise along each axis of the surface. The positions of the
    /// free elements in between add nothing to that while the bounds between them hold, which
    /// relaxation keeps: a pull blocked by pinned or held elements with no room at all stays blocked
    /// however the region between relaxes (`tissue::grasp::BlockedPull`).
    pub fn shifts(&self) -> u64 {
        self.shifts
    }

    /// The body's revision: it changes whenever pins, holds, cuts or materials change.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    pub(crate) fn check_element(&self, e: ElementId) -> Result<(), ChainMailError> {
        if e.index() < self.pos.len() {
            Ok(())
        } else {
            Err(ChainMailError::ElementOutOfRange { id: e.0, count: self.pos.len() })
        }
    }

    fn check_link(&self, l: LinkId) -> Result<(), ChainMailError> {
        if l.index() < self.link_state.len() {
            Ok(())
        } else {
            Err(ChainMailError::LinkOutOfRange { id: l.0, count: self.link_state.len() })
        }
    }

    /// Pins or unpins an element: a pinned element never moves, and a deformation that would have to
    /// move it is cut back to what it allows.
    pub fn set_pinned(&mut self, e: ElementId, pinned: bool) -> Result<(), ChainMailError> {
        let was = self.is_pinned(e);
        self.set_flag(e, PINNED, pinned)?;
        if pinned && !was {
            self.pinned.push(e);
        } else if !pinned && was {
            self.pinned.retain(|&p| p != e);
        }
        Ok(())
    }

    /// The pinned elements, in the order they were pinned.
    pub fn pinned_elements(&self) -> &[ElementId] {
        &self.pinned
    }

    /// Marks an element as held by an instrument: it moves only as the source of a deformation.
    pub fn set_held(&mut self, e: ElementId, held: bool) -> Result<(), ChainMailError> {
        self.set_flag(e, HELD, held)
    }

    /// Releases or restores a hold for the length of one pull, without a new revision: the caller
    /// puts every hold back before anything else reads the body (the forceps' jaws move their centre
    /// with the rest released, then the rest with the centre held). Chain reactions read the flags
    /// directly; only the relaxation's tables follow the revision, and no relaxation runs meanwhile.
    pub(crate) fn set_held_for_pull(&mut self, e: ElementId, held: bool) {
        if let Some(f) = self.flags.get_mut(e.index()) {
            if held { *f |= HELD } else { *f &= !HELD }
        }
    }

    fn set_flag(&mut self, e: ElementId, flag: u8, on: bool) -> Result<(), ChainMailError> {
        self.check_element(e)?;
        self.touch();
        let f = &mut self.flags[e.index()];
        if on {
            *f |= flag
        } else {
            *f &= !flag
        }
        Ok(())
    }

    /// Whether an element is pinned.
    pub fn is_pinned(&self, e: ElementId) -> bool {
        self.flags.get(e.index()).is_some_and(|f| f & PINNED != 0)
    }

    /// Whether an element is held by an instrument.
    pub fn is_held(&self, e: ElementId) -> bool {
        self.flags.get(e.index()).is_some_and(|f| f & HELD != 0)
    }

    /// Adds a material to the body's table.
    pub fn add_material(&mut self, material: Material) -> Result<MaterialId, ChainMailError> {
        material.validate()?;
        if self.materials.len() > u16::MAX as usize {
            return Err(ChainMailError::TooManyMaterials(u16::MAX as usize + 1));
        }
        self.materials.push(material);
        Ok(MaterialId((self.materials.len() - 1) as u16))
    }

    /// A material of the table.
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.materials.get(id.index())
    }

    /// All materials, indexed by [`MaterialId`].
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Replaces a material's parameters, for every link that uses it (live tuning).
    pub fn set_material(&mut self, id: MaterialId, material: Material) -> Result<(), ChainMailError> {
        material.validate()?;
        let count = self.materials.len();
        let slot = self
            .materials
            .get_mut(id.index())
            .ok_or(ChainMailError::MaterialOutOfRange { id: id.0, count })?;
        *slot = material;
        // Every link's box first, then each normal pair through one of them once (a pair's bounds
        // are those of its paths' boxes, however many of its links changed).
        for l in 0..self.link_material.len() {
            if self.link_material[l] == id {
                self.set_link_box(l);
            }
        }
        self.update_pairs_of_material(id);
        Ok(())
    }

    /// The material of a link.
    pub fn link_material(&self, l: LinkId) -> Option<MaterialId> {
        self.link_material.get(l.index()).copied()
    }

    /// Gives one link another material.
    pub fn set_link_material(&mut self, l: LinkId, id: MaterialId) -> Result<(), ChainMailError> {
        self.check_link(l)?;
        if id.index() >= self.materials.len() {
            return Err(ChainMailError::MaterialOutOfRange { id: id.0, count: self.materials.len() });
        }
        self.link_material[l.index()] = id;
        self.update_link_box(l.index());
        Ok(())
    }

    /// Gives material `id` to every link whose two ends' rest positions satisfy `region`: one body can
    /// be soft here and stiff there. Returns how many links changed.
    pub fn set_material_where(
        &mut self,
        id: MaterialId,
        mut region: impl FnMut([f32; 3], [f32; 3]) -> bool,
    ) -> Result<usize, ChainMailError> {
        if id.index() >= self.materials.len() {
            return Err(ChainMailError::MaterialOutOfRange { id: id.0, count: self.materials.len() });
        }
        let mut changed = 0;
        for l in 0..self.link_material.len() {
            let [a, b] = self.lattice.ends[l];
            if region(self.lattice.rest[a as usize], self.lattice.rest[b as usize]) {
                self.link_material[l] = id;
                self.update_link_box(l);
                changed += 1;
            }
        }
        Ok(changed)
    }

    /// Breaks a link (a cut or a tear). Returns `true` if it was intact.
    pub fn break_link(&mut self, l: LinkId, reason: BreakReason) -> Result<bool, ChainMailError> {
        self.check_link(l)?;
        let i = l.index();
        if self.link_state[i] != INTACT {
            return Ok(false);
        }
        self.link_state[i] = reason as u8;
        self.broken += 1;
        self.broken_links.push(l);
        self.touch();
        for s in self.slots_of(i) {
            self.set_slot_class(s, 0);
        }
        self.update_pairs_of_link(i);
        Ok(true)
    }

    /// Every broken link, in the order they broke. Links never mend, so what was here stays, and what
    /// breaks next is pushed on the end: a reader that keeps how many it has taken in reads only what
    /// broke since (what the assessment does every step).
    pub fn broken_links(&self) -> &[LinkId] {
        &self.broken_links
    }

    /// Whether a link is broken, and why.
    pub fn link_broken(&self, l: LinkId) -> Option<BreakReason> {
        match self.link_state.get(l.index()) {
            Some(1) => Some(BreakReason::Cut),
            Some(2) => Some(BreakReason::Tear),
            _ => None,
        }
    }

    /// Whether a link is intact.
    pub fn link_intact(&self, l: LinkId) -> bool {
        self.link_state.get(l.index()) == Some(&INTACT)
    }

    /// The current offset `p[b] - p[a]` of a link, unwrapped across seams, in lattice coordinates.
    pub fn link_offset(&self, l: LinkId) -> Option<[f32; 3]> {
        let &[a, b] = self.lattice.ends.get(l.index())?;
        let d = sub(self.pos[b as usize], self.pos[a as usize]);
        let j = self.lattice.jump[l.index()];
        Some([d[0] + j[0], d[1] + j[1], d[2] + j[2]])
    }

    /// A link's length over its rest length, in lattice coordinates.
    pub fn link_stretch(&self, l: LinkId) -> Option<f32> {
        let d = self.link_offset(l)?;
        Some(norm(d) / norm(self.lattice.rest_offset[l.index()]))
    }

    /// How far a link's current offset lies outside its constraint box (0 when it holds).
    pub fn link_violation(&self, l: LinkId) -> Option<f32> {
        let &[a, b] = self.lattice.ends.get(l.index())?;
        let d = sub(self.pos[b as usize], self.pos[a as usize]);
        let [lo, hi] = self.link_box[l.index()];
        let mut s = 0.0f32;
        for k in 0..3 {
            let e = if d[k] < lo[k] {
                lo[k] - d[k]
            } else if d[k] > hi[k] {
                d[k] - hi[k]
            } else {
                0.0
            };
            s += e * e;
        }
        Some(s.sqrt())
    }

    /// The constraint box of a link on `p[b] - p[a]`, lattice coordinates.
    pub fn link_limits(&self, l: LinkId) -> Option<[[f32; 3]; 2]> {
        self.link_box.get(l.index()).copied()
    }

    /// Relaxation energy: half the sum over intact links of stiffness times the squared distance
    /// between the link's current and rest offsets.
    pub fn energy(&self) -> f64 {
        let lat = &self.lattice;
        let mut e = 0.0f64;
        for (l, &[a, b]) in lat.ends.iter().enumerate() {
            if self.link_state[l] != INTACT {
                continue;
            }
            let w = self.materials[self.link_material[l].index()].stiffness as f64;
            let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
            let (ra, rb) = (lat.rest[a as usize], lat.rest[b as usize]);
            let mut s = 0.0f64;
            for k in 0..3 {
                let d = (pb[k] - rb[k]) as f64 - (pa[k] - ra[k]) as f64;
                s += d * d;
            }
            e += 0.5 * w * s;
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list of pinned elements follows the flags: pinned twice counts once, unpinned leaves it,
    /// and it holds exactly the elements `is_pinned` names.
    #[test]
    fn the_pinned_list_follows_the_flags() {
        let mut body =
            Body::new(Lattice::sheet(5, 4, 0.01).expect("sheet"), Material::default()).expect("body");
        for (e, on) in
            [(3, true), (7, true), (3, true), (11, true), (7, false), (19, true), (0, false), (11, false)]
        {
            body.set_pinned(ElementId(e), on).expect("pin");
            let flagged: Vec<ElementId> =
                (0..body.positions().len() as u32).map(ElementId).filter(|&x| body.is_pinned(x)).collect();
            let mut listed = body.pinned_elements().to_vec();
            listed.sort();
            assert_eq!(listed, flagged);
        }
        assert_eq!(body.pinned_elements(), &[ElementId(3), ElementId(19)]);
        assert!(body.set_pinned(ElementId(20), true).is_err());
        assert_eq!(body.pinned_elements().len(), 2);
    }

    #[test]
    fn class_table_stays_small_under_live_tuning() {
        let lattice = Lattice::sheet(6, 5, 0.01).expect("sheet");
        let mut body = Body::new(lattice, Material::default()).expect("body");
        // A uniform sheet: the free class and one per (axis, side), a few more where the f32 spacing
        // rounds differently.
        assert!(body.classes.len() < 16, "{} classes", body.classes.len());
        for k in 0..500 {
            let m = Material::relative(1.0 + k as f32 * 1e-3, 0.8, 0.3);
            body.set_material(MaterialId(0), m).expect("tune");
        }
        assert!(body.classes.len() <= 2 * body.slot_class.len() + 17);
        for (s, &c) in body.slot_class.iter().enumerate() {
            let i = s / body.width;
            let class = body.classes[c as usize];
            if body.slot_nbr[s] as usize == i {
                assert_eq!(class, SlotClass::FREE, "padding slot");
            } else {
                assert!(class.w == 1.0 && class.bounds[1][0] - class.bounds[0][0] > 0.0);
            }
        }
        assert_change_bits(&body);
    }

    /// Every change bit says whether the element's class in that slot differs from the previous
    /// element's.
    fn assert_change_bits(body: &Body) {
        let (w, n) = (body.width, body.pos.len());
        for t in 0..w {
            for e in 0..n {
                let differ = e == 0 || body.slot_class[e * w + t] != body.slot_class[(e - 1) * w + t];
                let bit = body.class_change[t * body.class_words + e / 64] >> (e % 64) & 1;
                assert_eq!(bit == 1, differ, "slot {t}, element {e}");
            }
        }
    }

    #[test]
    fn change_bits_follow_cuts_and_materials() {
        let lattice = Lattice::volume(70, 3, 2, 0.01).expect("volume");
        let mut body = Body::new(lattice, Material::relative(1.2, 0.8, 0.3)).expect("body");
        assert_change_bits(&body);
        let stiff = body.add_material(Material::relative(1.05, 0.95, 0.1)).expect("material");
        let links = body.lattice().link_count() as u32;
        for l in (0..links).step_by(7) {
            body.break_link(LinkId(l), BreakReason::Cut).expect("cut");
        }
        for l in (3..links).step_by(5) {
            body.set_link_material(LinkId(l), stiff).expect("material");
        }
        assert_change_bits(&body);
    }
}
