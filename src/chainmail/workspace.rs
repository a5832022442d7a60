//! Scratch for the chain reaction and relaxation, sized once per body so that no step allocates,
//! and the grid tables both loops read (rebuilt when the body's pins, holds, cuts or materials
//! change). Never serialized.

use super::body::Body;
use super::ids::ElementId;
use super::simd::SimdLevel;
use super::stencil::Stencil;

/// Scratch for deformations and relaxation. Sized once per body; no step allocates.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    /// `stamp[i] == generation` when element `i` moved in the current deformation.
    pub(crate) stamp: Vec<u32>,
    pub(crate) generation: u32,
    /// Position before the current deformation, valid where stamped (but for the elements a lift
    /// raised and nothing moved again: their heights before are in `lift.old_z`).
    pub(crate) old: Vec<[f32; 3]>,
    /// The sponsor of each moved element (itself for the source), valid where stamped.
    pub(crate) sponsor: Vec<u32>,
    /// Elements moved by the current deformation, in the order they moved.
    pub(crate) moved: Vec<u32>,
    /// Gibson's candidate lists, one per adjacency slot (a direction on grids: x-, x+, y-, y+, z-,
    /// z+): list `t` occupies `lists[t * n..(t + 1) * n]` and holds moved elements whose neighbour
    /// through slot `t` is still to be checked. Each moved element enters each list once.
    pub(crate) lists: Vec<u32>,
    /// Heads and tails of the candidate lists for widths without a specialised path.
    pub(crate) list_ends: Vec<usize>,
    /// A group deformation's seeds and their goals, as asked.
    pub(crate) seeds: Vec<u32>,
    pub(crate) seed_full: Vec<[f32; 3]>,
    /// The search for the largest move allowed.
    pub(crate) search: SearchScratch,
    /// The normal pairs' completion of a normal pass (`reaction/complete.rs`): a bit per element
    /// waiting to be checked, the links' normal bounds per slot class (widened and as they are, padded
    /// to a power of two) and the body's revision and class count they were made for.
    pub(crate) pair_bits: Vec<u64>,
    pub(crate) class_z: Vec<[f32; 4]>,
    pub(crate) class_z_key: (u64, usize),
    /// The normal pairs' bounds per class as the completion reads them (widened and as they are,
    /// padded to a power of two), and the pairs' table epoch they were made for.
    pub(crate) pair_z: Vec<[f32; 4]>,
    pub(crate) pair_z_key: u64,
    /// The completion takes its plain path whatever the widths (for the tests that compare the two).
    pub(crate) plain_pairs: bool,

    /// A lift's rigid elements (`reaction/lift.rs`).
    pub(crate) lift: super::reaction::Lift,

    /// Relaxation's second buffer.
    pub(crate) next: Vec<[f32; 3]>,
    /// The grid tables of the body last fitted (`None` for other lattices), and the body's
    /// [`Body::shape`] they were built for.
    pub(crate) stencil: Option<Stencil>,
    shape: u64,
    /// The widest SIMD the loops use.
    simd: SimdLevel,
}

impl Workspace {
    /// A workspace sized for `body`, at the environment's SIMD level ([`SimdLevel::from_env`]).
    pub fn new(body: &Body) -> Self {
        let mut ws = Self::default();
        ws.fit(body);
        ws
    }

    /// Resizes for `body` if needed (allocates only when the body grew or is another body).
    pub fn fit(&mut self, body: &Body) {
        let n = body.element_count();
        if self.stamp.len() != n {
            self.stamp = touched(n, 0);
            self.generation = 0;
            self.old = touched(n, [0.0; 3]);
            self.sponsor = touched(n, 0);
            self.next = touched(n, [0.0; 3]);
            // (Written and emptied: its capacity is mapped now, not as the steps push.)
            self.moved = touched(n, 0);
            self.moved.clear();
        }
        if self.lists.len() != n * body.width {
            self.lists = touched(n * body.width, 0);
        }
        self.lift.fit(body);
        if self.shape != body.shape {
            self.stencil = Stencil::for_body(body);
            self.shape = body.shape;
        }
    }

    /// The SIMD level the loops use with this workspace.
    pub fn simd(&self) -> SimdLevel {
        self.simd
    }

    /// Caps the SIMD level the loops use with this workspace (at what the CPU has): tests and
    /// benches compare the levels with it.
    pub fn set_simd(&mut self, level: SimdLevel) {
        self.simd = level.supported();
    }

    /// Makes the normal pass's completion over normal pairs take its plain path (`true`) or its fast
    /// one where the body's widths have it (`false`, the default): tests compare the two bit for bit.
    pub fn set_plain_pairs(&mut self, plain: bool) {
        self.plain_pairs = plain;
    }

    /// Lets the normal passes of lifts raise rigid elements at once (`reaction/lift.rs`): `true` in a tissue's
    /// workspace; `false` (every element taken one by one) by default.
    pub fn set_rigid_blocks(&mut self, on: bool) {
        self.lift.enabled = on;
    }

    /// Elements the last deformation raised as rigid elements and not otherwise: moved, but not
    /// in [`Workspace::moved`].
    pub fn raised_unlisted(&self) -> usize {
        self.lift.unlisted_count
    }

    /// Elements moved by the last deformation, in the order they moved (the source first); with rigid
    /// blocks on, not those raised with a block and left there ([`Workspace::raised_unlisted`]).
    pub fn moved(&self) -> impl ExactSizeIterator<Item = ElementId> + '_ {
        self.moved.iter().map(|&i| ElementId(i))
    }

    /// The sponsor of an element moved by the last deformation (the source is its own sponsor; none for
    /// an element only raised as a rigid element).
    pub fn sponsor(&self, e: ElementId) -> Option<ElementId> {
        let i = e.index();
        (self.stamp.get(i) == Some(&self.generation) && self.generation != 0 && !self.raised_only(i))
            .then(|| ElementId(self.sponsor[i]))
    }

    /// Whether element `i` was raised as a rigid element and not moved otherwise (it has no sponsor of
    /// its own).
    fn raised_only(&self, i: usize) -> bool {
        super::reaction::has_bit(&self.lift.unlisted, i)
    }

    /// Starts a new deformation: a fresh stamp, an empty moved list.
    pub(crate) fn next_generation(&mut self) {
        if self.generation == u32::MAX {
            self.stamp.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
        self.moved.clear();
        self.lift.clear_reaction();
    }

    /// Puts the elements the current deformation moved back where they were.
    pub(crate) fn rollback(&mut self, pos: &mut [[f32; 3]]) {
        // The raised elements the completion did not list (those it did are in the moved list).
        if self.lift.raised {
            let span = self.lift.unlisted_span;
            for (w, &x) in span.of(&self.lift.unlisted).iter().enumerate() {
                let (w, mut x) = (span.words().start + w, x);
                while x != 0 {
                    let i = w * 64 + x.trailing_zeros() as usize;
                    x &= x - 1;
                    // (Raised along the normal only: the height before is all that changed.)
                    if let (Some(p), Some(&z)) = (pos.get_mut(i), self.lift.old_z.get(i)) {
                        p[2] = z;
                    }
                }
            }
        }
        for &i in &self.moved {
            pos[i as usize] = self.old[i as usize];
        }
        // Forget the moves: a fresh generation unstamps them.
        self.next_generation();
    }
}

/// `n` copies of `value`, every one written now: memory the steps will use is taken from the system
/// while a body is built, not at the first step that reaches it. (`vec![0; n]` asks for zeroed memory,
/// which the system hands over untouched; the first write to each page then stops that step to map
/// it: with huge pages, 2 MiB zeroed at a time, 4 to 20 ms in the first steps of the careful exercise at
/// 512 x 384.)
pub(crate) fn touched<T: Copy>(n: usize, value: T) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    v.resize(n, std::hint::black_box(value));
    v
}

/// Scratch of a deformation's search, kept in the workspace so that no step allocates: the seeds
/// that move, where they started, their goals, and their goals at a share of the move.
#[derive(Clone, Debug, Default)]
pub(crate) struct SearchScratch {
    pub(crate) free: Vec<u32>,
    pub(crate) starts: Vec<[f32; 3]>,
    pub(crate) goals: Vec<[f32; 3]>,
    pub(crate) at: Vec<[f32; 3]>,
}
