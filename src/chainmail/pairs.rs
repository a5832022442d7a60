//! Normal pairs: two elements that share no link but whose offset along the third coordinate (the
//! surface normal `h` of a SurfaceChainMail lattice) is bounded all the same, so that the slope limit
//! is the same in every direction and not only along the links.
//!
//! A grid's links bound the normal offset between neighbours along `u` and `v` separately: the least
//! lift of one element is then a square pyramid (a diamond in the L1 metric: at the same distance the
//! surface stands lower along the diagonals than along the axes). A cell's two diagonals, as pairs
//! bounded by the hypotenuse of the two links' normal limits (a slope limit `s` on links of lengths
//! `du` and `dv` bounds the diagonal by `s·√(du² + dv²)`), make the least lift an octagon, under
//! 8.2 % from round in any direction.
//!
//! A pair names the two paths of two links between its ends (a cell's two sides); it holds while
//! either path is intact, with the intersection of what the intact paths allow. Its bounds follow the
//! links' boxes (materials tuned live) and their breaking (cuts, tears). Pairs are given as element
//! pairs and link paths, not as grid arithmetic, so that other meshes can state theirs.

use rustc_hash::FxHashMap;

use super::body::{Body, INTACT, fresh_number};
use super::error::ChainMailError;
use super::ids::{ElementId, LinkId, MaterialId};

/// A pair as given to [`Body::set_normal_pairs`]: ends `a` and `b` and the two paths of two links
/// from `a` to `b` (`[a–m, m–b]` each).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NormalPair {
    /// First end.
    pub a: ElementId,
    /// Second end.
    pub b: ElementId,
    /// Two paths from `a` to `b`, two links each, in order from `a`.
    pub paths: [[LinkId; 2]; 2],
}

/// The body's normal pairs as fixed-width rows beside the links' (a row per element, padded with
/// the element itself and infinite bounds).
#[derive(Clone, Debug, Default)]
pub(crate) struct Pairs {
    /// Pair slots per element (0: the body has no pairs).
    pub(crate) width: usize,
    /// Partner of each slot (the owner itself for padding).
    pub(crate) nbr: Vec<u32>,
    /// Class of each slot: where its bounds `[lo, hi]` on `p[owner][2] - p[nbr][2]` sit in `table`
    /// (0, infinite, for padding and for a pair with no intact path). Slots share bounds (a uniform
    /// sheet has a few hundred), so the hot loops read 4 bytes a slot and find the bounds in cache,
    /// as they do the links' classes.
    pub(crate) class: Vec<u32>,
    /// The distinct bounds; entry 0 is [`FREE`].
    pub(crate) table: Vec<[f32; 2]>,
    /// Where each bound sits in `table`, by its bits.
    index: FxHashMap<[u32; 2], u32>,
    /// A new number whenever `table` changes (an entry added, or the table compacted): what a copy
    /// of it (the completion's widened table) is keyed by.
    pub(crate) epoch: u64,
    /// The table's length at which it is next compacted (at least [`TABLE_MAX`]; twice what the
    /// last compaction kept, so that a table mostly in use is not compacted at every new entry).
    compact_at: usize,
    /// How far outside a normal pass left a bound of an element it moved (see
    /// `reaction/complete.rs`): the limits' repair reads it ([`Body::take_pairs_unmet`]).
    pub(crate) unmet: f32,
    list: Vec<NormalPair>,
    /// Each pair's slot in its `a` end's row and in its `b` end's row.
    slots: Vec<[u32; 2]>,
    /// The pairs whose paths use each link: `link_pairs[link_start[l]..link_start[l + 1]]`.
    link_start: Vec<u32>,
    link_pairs: Vec<u32>,
}

/// Infinite bounds: a padding slot's, or a pair's with no intact path.
pub(crate) const FREE: [f32; 2] = [f32::NEG_INFINITY, f32::INFINITY];

/// Most entries the bounds' table holds before it is compacted to the bounds in use (materials
/// edited live again and again leave old bounds behind).
const TABLE_MAX: usize = 1 << 16;

/// A table of bounds holding [`FREE`] alone, as class 0, and its index.
fn free_table() -> (Vec<[f32; 2]>, FxHashMap<[u32; 2], u32>) {
    (vec![FREE], FxHashMap::from_iter([(FREE.map(f32::to_bits), 0)]))
}

impl Pairs {
    /// The bounds of class `c` (infinite for one out of range).
    #[inline(always)]
    pub(crate) fn bounds_of(&self, c: u32) -> [f32; 2] {
        self.table.get(c as usize).copied().unwrap_or(FREE)
    }

    /// The bounds of slot `k`.
    pub(crate) fn bound(&self, k: usize) -> [f32; 2] {
        self.class.get(k).map_or(FREE, |&c| self.bounds_of(c))
    }

    /// The class of `bounds`, added to the table if new.
    fn intern(&mut self, bounds: [f32; 2]) -> u32 {
        let key = bounds.map(f32::to_bits);
        if let Some(&c) = self.index.get(&key) {
            return c;
        }
        if self.table.len() >= self.compact_at.max(TABLE_MAX) {
            self.compact();
        }
        let c = self.table.len() as u32;
        self.table.push(bounds);
        self.index.insert(key, c);
        self.epoch = fresh_number();
        c
    }

    /// Keeps only the bounds some slot has (renumbering the slots' classes).
    fn compact(&mut self) {
        let (mut table, mut index) = free_table();
        for c in &mut self.class {
            let b = self.table.get(*c as usize).copied().unwrap_or(FREE);
            *c = *index.entry(b.map(f32::to_bits)).or_insert_with(|| {
                table.push(b);
                (table.len() - 1) as u32
            });
        }
        (self.table, self.index) = (table, index);
        self.compact_at = 2 * self.table.len();
        self.epoch = fresh_number();
    }

    /// Whether the body has any pair.
    #[inline(always)]
    pub(crate) fn any(&self) -> bool {
        self.width > 0
    }

    /// The pair slots of element `i`: partners and bounds on `p[i][2] - p[partner][2]`.
    #[inline(always)]
    pub(crate) fn row(&self, i: usize) -> impl Iterator<Item = (u32, [f32; 2])> + '_ {
        let r = i * self.width..(i + 1) * self.width;
        let (nbr, class) =
            (self.nbr.get(r.clone()).unwrap_or_default(), self.class.get(r).unwrap_or_default());
        nbr.iter().zip(class).map(|(&y, &c)| (y, self.bounds_of(c)))
    }
}

impl Body {
    /// Sets the body's normal pairs (replacing any it had): each bounds the offset of its ends along
    /// the third coordinate by what its two-link paths allow there, combined as across a right angle
    /// (centres added, half-widths as the hypotenuse). Fails on an element or link out of range, or a
    /// path that does not lead from `a` to `b`.
    pub fn set_normal_pairs(&mut self, pairs: &[NormalPair]) -> Result<(), ChainMailError> {
        for p in pairs {
            self.check_element(p.a)?;
            self.check_element(p.b)?;
            for path in &p.paths {
                for &l in path {
                    if l.index() >= self.link_state.len() {
                        return Err(ChainMailError::LinkOutOfRange { id: l.0, count: self.link_state.len() });
                    }
                }
                if self.path_offset(p.a, p.b, *path).is_none() {
                    return Err(ChainMailError::BadCoordinates {
                        axis: 2,
                        reason: format!(
                            "normal pair {}-{}: path {path:?} does not lead from a to b",
                            p.a.0, p.b.0
                        ),
                    });
                }
            }
        }
        let n = self.pos.len();
        let mut degree = vec![0u32; n];
        for p in pairs {
            degree[p.a.index()] += 1;
            degree[p.b.index()] += 1;
        }
        let width = if pairs.is_empty() { 0 } else { degree.iter().copied().max().unwrap_or(0) as usize };
        let mut nbr: Vec<u32> = (0..n * width).map(|k| (k / width.max(1)) as u32).collect();
        let class = vec![0u32; n * width];
        let mut fill = vec![0u32; n];
        let mut slots = Vec::with_capacity(pairs.len());
        for p in pairs {
            let (a, b) = (p.a.index(), p.b.index());
            let (sa, sb) = (a * width + fill[a] as usize, b * width + fill[b] as usize);
            fill[a] += 1;
            fill[b] += 1;
            nbr[sa] = b as u32;
            nbr[sb] = a as u32;
            slots.push([sa as u32, sb as u32]);
        }
        let m = self.link_state.len();
        let mut link_start = vec![0u32; m + 1];
        for p in pairs {
            for l in p.paths.iter().flatten() {
                link_start[l.index() + 1] += 1;
            }
        }
        for l in 0..m {
            link_start[l + 1] += link_start[l];
        }
        let mut at = link_start.clone();
        let mut link_pairs = vec![0u32; link_start[m] as usize];
        for (k, p) in pairs.iter().enumerate() {
            for l in p.paths.iter().flatten() {
                link_pairs[at[l.index()] as usize] = k as u32;
                at[l.index()] += 1;
            }
        }
        let (table, index) = free_table();
        self.pairs = Pairs {
            width,
            nbr,
            class,
            table,
            index,
            epoch: fresh_number(),
            compact_at: TABLE_MAX,
            unmet: 0.0,
            list: pairs.to_vec(),
            slots,
            link_start,
            link_pairs,
        };
        for k in 0..pairs.len() {
            self.update_pair(k);
        }
        self.touch_pairs();
        Ok(())
    }

    /// How far outside the normal passes since the last call left a bound of an element they moved (a
    /// pair's or a link's, no worse than before the pass; infinite where a pass reached its cap),
    /// and forgets it.
    pub(crate) fn take_pairs_unmet(&mut self) -> f32 {
        std::mem::take(&mut self.pairs.unmet)
    }

    /// The number of normal pairs.
    pub fn normal_pair_count(&self) -> usize {
        self.pairs.list.len()
    }

    /// The bounds `[lo, hi]` of pair `k` on `p[b][2] - p[a][2]` (infinite when neither path is intact).
    pub fn normal_pair_limits(&self, k: usize) -> Option<(NormalPair, [f32; 2])> {
        let p = *self.pairs.list.get(k)?;
        let [_, sb] = self.pairs.slots[k];
        Some((p, self.pairs.bound(sb as usize)))
    }

    /// Recomputes the pairs whose paths use link `l` (its box or state changed).
    pub(crate) fn update_pairs_of_link(&mut self, l: usize) {
        if !self.pairs.any() {
            return;
        }
        let (s, e) = (self.pairs.link_start[l] as usize, self.pairs.link_start[l + 1] as usize);
        for j in s..e {
            let k = self.pairs.link_pairs[j] as usize;
            self.update_pair(k);
        }
    }

    /// Recomputes every normal pair with a link of material `id` on one of its paths, once.
    pub(crate) fn update_pairs_of_material(&mut self, id: MaterialId) {
        for k in 0..self.pairs.list.len() {
            let through =
                self.pairs.list[k].paths.iter().flatten().any(|l| self.link_material[l.index()] == id);
            if through {
                self.update_pair(k);
            }
        }
    }

    fn touch_pairs(&mut self) {
        // Pairs change what relaxation and the chain reaction read: a new revision, as for links.
        self.revision = super::body::fresh_number();
    }

    /// Recomputes pair `k`'s bounds from the boxes of its intact paths.
    fn update_pair(&mut self, k: usize) {
        let p = self.pairs.list[k];
        let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
        for path in p.paths {
            if path.iter().all(|l| self.link_state[l.index()] == INTACT)
                && let Some((l, h)) = self.path_offset(p.a, p.b, path)
            {
                lo = lo.max(l);
                hi = hi.min(h);
            }
        }
        if lo > hi {
            // Paths that disagree (links of other materials): the looser one's middle, no tighter than
            // either allows.
            let m = 0.5 * (lo + hi);
            (lo, hi) = (m, m);
        }
        let [sa, sb] = self.pairs.slots[k];
        // `b`'s slot bounds `p[b] - p[a]`; `a`'s the negation.
        let (cb, ca) = (self.pairs.intern([lo, hi]), self.pairs.intern([-hi, -lo]));
        if let Some(c) = self.pairs.class.get_mut(sb as usize) {
            *c = cb;
        }
        if let Some(c) = self.pairs.class.get_mut(sa as usize) {
            *c = ca;
        }
    }

    /// The bounds of `p[b][2] - p[a][2]` along a path of two links from `a` (`None` if the path does
    /// not lead from `a` to `b`): the links' centres added, their half-widths as a right angle's
    /// hypotenuse.
    fn path_offset(&self, a: ElementId, b: ElementId, path: [LinkId; 2]) -> Option<(f32, f32)> {
        let mut at = a.0;
        let (mut centre, mut half2) = (0.0f32, 0.0f32);
        for l in path {
            let [x, y] = *self.lattice.ends.get(l.index())?;
            let [lo, hi] = self.link_box.get(l.index())?;
            // The box bounds `p[y] - p[x]`.
            let (l2, h2, next) = if x == at {
                (lo[2], hi[2], y)
            } else if y == at {
                (-hi[2], -lo[2], x)
            } else {
                return None;
            };
            centre += 0.5 * (l2 + h2);
            half2 += (0.5 * (h2 - l2)).powi(2);
            at = next;
        }
        let half = half2.sqrt();
        (at == b.0).then_some((centre - half, centre + half))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Body, BreakReason, ElementId, Lattice, LinkId, Material, Pass, Workspace};
    use super::NormalPair;

    /// A sheet of `n × n` with both diagonals of every cell as normal pairs.
    fn sheet_with_pairs(n: usize, d: f32, shear: f32) -> Body {
        let mut body =
            Body::new(Lattice::sheet(n, n, d).expect("sheet"), Material::relative(1.2, 0.8, shear))
                .expect("body");
        let link = |a: usize, b: usize| {
            let l = body.lattice().neighbours(ElementId(a as u32)).find(|&(e, _)| e.index() == b);
            l.map(|(_, l)| l).expect("link")
        };
        let mut pairs = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let (a, b, c, e) = (i + n * j, i + 1 + n * j, i + 1 + n * (j + 1), i + n * (j + 1));
                let (ab, bc, ec, ae) = (link(a, b), link(b, c), link(e, c), link(a, e));
                let id = |x: usize| ElementId(x as u32);
                pairs.push(NormalPair { a: id(a), b: id(c), paths: [[ab, bc], [ae, ec]] });
                pairs.push(NormalPair { a: id(b), b: id(e), paths: [[ab, ae], [bc, ec]] });
            }
        }
        body.set_normal_pairs(&pairs).expect("pairs");
        body
    }

    /// A material edited live leaves every slot's box and weight, every link's box and every normal
    /// pair's bounds as a body built with the new material from the start has them (the edit sets
    /// the links' boxes first and each pair once after; the build, link by link).
    #[test]
    fn an_edited_material_is_the_material_built_in() {
        let (n, d) = (9, 0.001f32);
        let (old, new) = (Material::relative(1.1, 0.9, 0.2), Material::relative(1.4, 0.7, 0.45));
        let build = |m: Material| {
            let mut body = sheet_with_pairs(n, d, 0.25);
            let id = body.add_material(m).expect("material");
            // The left half of the sheet and the links crossing into it: pairs with paths of both.
            body.set_material_where(id, |a, b| a[0] + b[0] < 8.0 * d).expect("where");
            (body, id)
        };
        let (mut edited, id) = build(old);
        edited.set_material(id, new).expect("edit");
        let (built, _) = build(new);
        let slot = |b: &Body, k: usize| {
            let c = b.classes[b.slot_class[k] as usize];
            (c.bounds.map(|x| x.map(f32::to_bits)), c.w.to_bits())
        };
        assert_eq!(edited.slot_class.len(), built.slot_class.len());
        for k in 0..built.slot_class.len() {
            assert_eq!(slot(&edited, k), slot(&built, k), "slot {k}");
        }
        let bits = |b: &[[f32; 3]; 2]| b.map(|x| x.map(f32::to_bits));
        for (l, (e, b)) in edited.link_box.iter().zip(&built.link_box).enumerate() {
            assert_eq!(bits(e), bits(b), "link {l}");
        }
        assert_eq!(edited.pairs.class.len(), built.pairs.class.len());
        for k in 0..built.pairs.class.len() {
            let (e, b) = (edited.pairs.bound(k), built.pairs.bound(k));
            assert_eq!(e.map(f32::to_bits), b.map(f32::to_bits), "pair slot {k}");
        }
        assert_ne!(slot(&edited, 0), slot(&sheet_with_pairs(n, d, 0.25), 0), "the edit changed nothing");
    }

    /// The pairs' bounds are interned: slots share a handful of entries, and a compaction (what a
    /// table grown by many edits gets) drops unused entries and keeps every slot's bounds to the bit.
    #[test]
    fn pair_bounds_are_shared_and_survive_a_compaction() {
        let mut body = sheet_with_pairs(9, 0.001, 0.25);
        let slots = body.pairs.class.len();
        let before: Vec<[u32; 2]> = (0..slots).map(|k| body.pairs.bound(k).map(f32::to_bits)).collect();
        assert!(body.pairs.table.len() < 16, "{} entries for {slots} slots", body.pairs.table.len());
        assert_eq!(body.pairs.table[0].map(f32::to_bits), super::FREE.map(f32::to_bits));
        for k in 0..100 {
            body.pairs.intern([k as f32, k as f32 + 1.0]);
        }
        let (grown, epoch) = (body.pairs.table.len(), body.pairs.epoch);
        body.pairs.compact();
        assert!(body.pairs.table.len() + 100 <= grown, "{} of {grown} kept", body.pairs.table.len());
        assert_ne!(body.pairs.epoch, epoch, "a compaction renumbers: copies of the table are stale");
        assert_eq!(body.pairs.compact_at, 2 * body.pairs.table.len(), "the next compaction waits");
        for (k, b) in before.iter().enumerate() {
            assert_eq!(&body.pairs.bound(k).map(f32::to_bits), b, "slot {k}");
        }
    }

    #[test]
    fn a_point_lift_over_pairs_is_an_octagon() {
        let (n, d, s, h) = (41, 0.001f32, 0.25f32, 0.004f32);
        let mut body = sheet_with_pairs(n, d, s);
        let mut ws = Workspace::new(&body);
        let c = n / 2;
        let centre = ElementId((c + n * c) as u32);
        let moved = body.deform(&mut ws, centre, [0.02, 0.02, h], Pass::Normal).expect("lift");
        assert_eq!(moved.fraction, 1.0);
        // The least lift: the centre's height less the slope limit times the octagonal distance.
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f32 - c as f32).abs(), (j as f32 - c as f32).abs());
                let oct = x.max(y) + (2f32.sqrt() - 1.0) * x.min(y);
                let want = (h - s * d * oct).max(0.0);
                let z = body.positions()[i + n * j][2];
                assert!((z - want).abs() < 1e-6, "({i}, {j}): {z} against {want}");
            }
        }
    }

    #[test]
    fn a_pair_holds_while_one_path_is_intact() {
        let mut body = sheet_with_pairs(3, 0.001, 0.25);
        let (p, [lo, hi]) = body.normal_pair_limits(0).expect("pair");
        assert!((hi - 0.25e-3 * 2f32.sqrt()).abs() < 1e-9 && lo == -hi, "{lo} {hi}");
        body.break_link(p.paths[0][0], BreakReason::Cut).expect("cut");
        assert_eq!(body.normal_pair_limits(0).map(|x| x.1), Some([lo, hi]), "the other path holds it");
        body.break_link(p.paths[1][1], BreakReason::Cut).expect("cut");
        let (_, [lo, hi]) = body.normal_pair_limits(0).expect("pair");
        assert!(lo == f32::NEG_INFINITY && hi == f32::INFINITY, "no path left: {lo} {hi}");
        assert!(
            body.set_normal_pairs(&[NormalPair { a: p.a, b: p.b, paths: [[LinkId(0), LinkId(0)]; 2] }])
                .is_err()
        );
    }
}
