//! A lift's cone: the least distance `D` over the bounds along the third coordinate from a set of
//! seeds (the held elements), the first part of a lift kept as a distance field
//! (`docs/implicit-lift.md`).
//!
//! Along the normal every bound a body keeps is a difference constraint on two heights: a link slot's
//! box bounds `z[owner] - z[nbr]` by `hi`, so `z[nbr] >= z[owner] - hi`, and a normal pair's the same
//! way. Read each as an edge from the owner to the neighbour weighing `hi` (a negative `hi` is taken
//! as zero: the distance is then an upper bound of the true one, and the cone below still a bound).
//! With `D[j]` the least distance from the seeds to `j` over these edges, every state whose bounds
//! hold has `z[j] >= A - D[j]` (`A` the seeds' common height), and a lift of the seeds to `A'` is
//! `max(z_before, A' - D)`: the test `tissue::grasp::tests::a_lift_is_a_distance_field_from_the_held_elements`
//! holds both on the careful exercise. Nothing here reads positions: `D` stays true for as long as the
//! seeds, the cuts and the materials stay as they were.
//!
//! [`Cone::grow`] settles elements in order of distance (Dijkstra, with a binary heap of keys that
//! pack an element's distance above its index) and only as far as asked, so that a lift can grow its
//! cone by the ring its rise reaches in a step. Its scratch is kept between calls: after the first
//! cone of a body, starting and growing one allocates nothing. [`distances_plain`] is the reference it
//! is compared with: label-correcting sweeps over every element until nothing changes.
//!
//! The distances are found over the body's own rows (slots and pairs), not a grid: the same cone
//! serves any topology the body has.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::body::Body;
use super::ids::ElementId;

/// The least distances over a body's bounds along the third coordinate from a set of seeds, settled
/// in order of distance as far as [`Cone::grow`] is asked to go.
#[derive(Clone, Debug, Default)]
pub struct Cone {
    /// Each element's best distance so far (infinite where not reached): final for settled elements.
    dist: Vec<f32>,
    /// Elements in the order they were settled (their distances in that order never fall).
    settled: Vec<u32>,
    /// Elements whose distance was set, to be reset by the next [`Cone::start`].
    touched: Vec<u32>,
    /// Reached, not settled: the distance's bits above the element's index, least first.
    heap: BinaryHeap<Reverse<u64>>,
    /// Each slot class's upper bound along the third coordinate, as an edge weight (see the module).
    class_hi: Vec<f32>,
    /// Every element within this distance is settled.
    radius: f32,
}

/// An edge's weight from a bound's `hi`: not below zero; `None` for a slot that bounds nothing (a
/// broken link's or a padding slot's infinite box).
#[inline(always)]
fn weight(hi: f32) -> Option<f32> {
    hi.is_finite().then_some(hi.max(0.0))
}

#[inline(always)]
fn key(d: f32, e: u32) -> u64 {
    // A distance is never below zero (nor NaN), so its bits order as it does.
    (u64::from(d.to_bits()) << 32) | u64::from(e)
}

impl Cone {
    /// An empty cone: no seeds, nothing settled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a cone from `seeds` (at distance zero; indices outside the body are skipped), forgetting
    /// the last one. Nothing is settled until [`Cone::grow`].
    pub fn start(&mut self, body: &Body, seeds: &[ElementId]) {
        let n = body.pos.len();
        if self.dist.len() != n {
            self.dist.clear();
            self.dist.resize(n, f32::INFINITY);
            self.touched.clear();
        }
        for &e in &self.touched {
            if let Some(d) = self.dist.get_mut(e as usize) {
                *d = f32::INFINITY;
            }
        }
        self.touched.clear();
        self.settled.clear();
        self.heap.clear();
        self.radius = f32::NEG_INFINITY;
        self.class_hi.clear();
        self.class_hi.extend(body.classes.iter().map(|c| c.bounds[1][2]));
        for s in seeds {
            let e = s.0;
            if let Some(d) = self.dist.get_mut(e as usize)
                && *d > 0.0
            {
                *d = 0.0;
                self.touched.push(e);
                self.heap.push(Reverse(key(0.0, e)));
            }
        }
    }

    /// Settles every element within `radius` of the seeds (and no further); returns how many this call
    /// settled. The body must have the slots, pairs and classes it had at [`Cone::start`].
    pub fn grow(&mut self, body: &Body, radius: f32) -> usize {
        let before = self.settled.len();
        let w = body.width;
        let (slot_nbr, slot_class, pairs) = (&body.slot_nbr[..], &body.slot_class[..], &body.pairs);
        let Self { dist, settled, touched, heap, class_hi, .. } = self;
        while let Some(&Reverse(k)) = heap.peek() {
            let (du, u) = (f32::from_bits((k >> 32) as u32), k as u32 as usize);
            if du > radius {
                break;
            }
            heap.pop();
            if dist.get(u).is_none_or(|&d| du > d) {
                continue; // a stale entry: `u` was reached closer since
            }
            settled.push(u as u32);
            let mut relax = |y: u32, hi: f32| {
                let Some(wt) = weight(hi) else { return };
                let nd = du + wt;
                if let Some(d) = dist.get_mut(y as usize)
                    && nd < *d
                {
                    if d.is_infinite() {
                        touched.push(y);
                    }
                    *d = nd;
                    heap.push(Reverse(key(nd, y)));
                }
            };
            let slots = u * w..(u + 1) * w;
            if let (Some(nbrs), Some(cls)) = (slot_nbr.get(slots.clone()), slot_class.get(slots)) {
                for (&y, &c) in nbrs.iter().zip(cls) {
                    if y as usize != u {
                        relax(y, class_hi.get(c as usize).copied().unwrap_or(f32::INFINITY));
                    }
                }
            }
            for (y, [_, hi]) in pairs.row(u) {
                if y as usize != u {
                    relax(y, hi);
                }
            }
        }
        self.radius = self.radius.max(radius);
        self.settled.len() - before
    }

    /// The least distance from the seeds to `e`, if `e` is settled (reachable, and within the radius
    /// grown to).
    pub fn distance(&self, e: ElementId) -> Option<f32> {
        let d = *self.dist.get(e.index())?;
        (d <= self.radius && d.is_finite()).then_some(d)
    }

    /// The elements settled so far, in order of distance.
    pub fn settled(&self) -> impl ExactSizeIterator<Item = ElementId> + '_ {
        self.settled.iter().map(|&e| ElementId(e))
    }
}

/// The reference for [`Cone`]: each element's least distance from `seeds` over the same edges, found
/// by sweeping every element's edges until no distance falls (infinite where unreachable).
pub fn distances_plain(body: &Body, seeds: &[ElementId]) -> Vec<f32> {
    let n = body.pos.len();
    let mut d = vec![f32::INFINITY; n];
    for s in seeds {
        if let Some(x) = d.get_mut(s.index()) {
            *x = 0.0;
        }
    }
    let mut changed = true;
    while changed {
        changed = false;
        for u in 0..n {
            let du = d[u];
            if du.is_infinite() {
                continue;
            }
            let slots = (u * body.width..(u + 1) * body.width)
                .map(|k| (body.slot_nbr[k], body.classes[body.slot_class[k] as usize].bounds[1][2]));
            for (y, hi) in slots.chain(body.pairs.row(u).map(|(y, [_, hi])| (y, hi))) {
                let Some(wt) = weight(hi) else { continue };
                let (y, nd) = (y as usize, du + wt);
                if y != u && y < n && nd < d[y] {
                    d[y] = nd;
                    changed = true;
                }
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::super::{Body, BreakReason, ElementId, Lattice, LinkId, Material};
    use super::{Cone, distances_plain};

    /// A soft sheet of `n × n`, spacing `d`, shear limit `shear`.
    fn sheet(n: usize, d: f32, shear: f32) -> Body {
        Body::new(Lattice::sheet(n, n, d).expect("sheet"), Material::relative(1.2, 0.8, shear)).expect("body")
    }

    /// The meninges' two layers at `res` (links, fibres and normal pairs, two materials), with the
    /// links crossing a line cut.
    fn meninges(res: [u32; 2]) -> Body {
        let mut scene =
            crate::scene::Scene::from_str(include_str!("../../scenes/meninges.ron"), "meninges.ron")
                .expect("scene");
        if let crate::scene::Tissue::Layers(l) = &mut scene.tissue {
            l.resolution = res;
        }
        let world = scene.build_world(false).expect("world");
        let mut body = world.tissue().body().clone();
        let nx = res[0] as usize;
        for l in 0..body.link_count() {
            let id = LinkId(l as u32);
            let [a, b] = body.lattice().link_ends(id).expect("link");
            let (ia, ib) = (a.index() % nx, b.index() % nx);
            let (ja, jb) = (a.index() / nx, b.index() / nx);
            // A cut across a third of the first layer, a quarter of the way along.
            if a.index() < body.element_count() / 2
                && ia.min(ib) < nx / 4
                && ia.max(ib) >= nx / 4
                && ja.min(jb) > res[1] as usize / 3
            {
                body.break_link(id, BreakReason::Cut).expect("cut");
            }
        }
        body
    }

    /// Every element the cone settles within a radius has the reference's distance, to the bit, and
    /// every element the reference puts within the radius is settled; grown in pieces, the cone settles
    /// the same elements with the same distances as grown at once.
    #[test]
    fn the_cone_is_the_plain_distances() {
        let body = meninges([40, 30]);
        let n = body.element_count();
        for seeds in [vec![n / 4 + 20], vec![n / 4 + 20, n / 4 + 21, n / 4 + 60, n / 4 + 61], vec![0, n - 1]]
        {
            let seeds: Vec<ElementId> = seeds.into_iter().map(|e| ElementId(e as u32)).collect();
            let plain = distances_plain(&body, &seeds);
            let far = plain.iter().copied().filter(|d| d.is_finite()).fold(0.0f32, f32::max);
            assert!(far > 0.0, "the seeds reach something");
            let mut cone = Cone::new();
            for radius in [0.0, far / 3.0, far] {
                cone.start(&body, &seeds);
                let settled = cone.grow(&body, radius);
                let within = plain.iter().filter(|&&d| d <= radius).count();
                assert_eq!(settled, within, "radius {radius}: settled against the reference's count");
                for (e, &d) in plain.iter().enumerate() {
                    let got = cone.distance(ElementId(e as u32));
                    assert_eq!(
                        got,
                        (d <= radius && d.is_finite()).then_some(d),
                        "element {e}, radius {radius}"
                    );
                }
                let order: Vec<f32> = cone.settled().map(|e| plain[e.index()]).collect();
                assert!(order.is_sorted(), "settled in order of distance");
            }
            let mut pieces = Cone::new();
            pieces.start(&body, &seeds);
            let mut total = 0;
            for k in 1..=7 {
                total += pieces.grow(&body, far * k as f32 / 7.0);
            }
            assert_eq!(total, n - plain.iter().filter(|d| d.is_infinite()).count());
            let whole: Vec<_> = cone.settled().collect();
            assert_eq!(pieces.settled().collect::<Vec<_>>(), whole, "grown in pieces");
        }
    }

    /// On a uniform sheet (no pairs) an element `k` links from the seed along an axis is `k` shear
    /// limits away, and one `i` and `j` links off along both is `i + j` of them (the lattice's own
    /// metric); a cut link is no way through, and a cone started again forgets the last one.
    #[test]
    fn a_sheet_s_cone_is_its_lattice_metric() {
        let (n, d, shear) = (21usize, 0.001f32, 0.3f32);
        let mut body = sheet(n, d, shear);
        let c = n / 2 + n * (n / 2);
        let mut cone = Cone::new();
        cone.start(&body, &[ElementId(c as u32)]);
        cone.grow(&body, f32::INFINITY);
        let step = shear * d;
        for (i, j) in [(1, 0), (0, 3), (4, 4), (10, 2)] {
            let e = ElementId((c + i + n * j) as u32);
            let want = (i + j) as f32 * step;
            let got = cone.distance(e).expect("settled");
            assert!((got - want).abs() <= 1e-6 * want.max(step), "({i}, {j}): {got} against {want}");
        }
        // Cut every link from the seed's row to the next: the rows above are out of reach.
        let row = c / n;
        for l in 0..body.link_count() {
            let id = LinkId(l as u32);
            let [a, b] = body.lattice().link_ends(id).expect("link");
            if (a.index() / n).min(b.index() / n) == row && a.index() / n != b.index() / n {
                body.break_link(id, BreakReason::Cut).expect("cut");
            }
        }
        cone.start(&body, &[ElementId(c as u32)]);
        cone.grow(&body, f32::INFINITY);
        assert_eq!(cone.distance(ElementId((c + n) as u32)), None, "no way across a whole cut row");
        let plain = distances_plain(&body, &[ElementId(c as u32)]);
        assert!(plain[c + n].is_infinite());
        assert_eq!(cone.distance(ElementId((c + 1) as u32)), Some(plain[c + 1]));
    }
}
