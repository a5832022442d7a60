//! The in-place sweep of a disturbed region (`Tissue::relax_region`): damped Gauss-Seidel in the
//! region's order, each element moved to [`Body::relaxed_into_boxes`] of it with the moves of the
//! elements before it already made. Where the body's rows have the common widths (a sheet: 4 links
//! and no normal pairs; two layers: 5 links and 4 pairs) the element's link and pair rows are read as
//! fixed-width arrays, so that the kernel unrolls and keeps its sums in registers; other widths take
//! the plain kernel. Both make the same operations in the same order: the same positions and moves,
//! bit for bit (tested below).

use super::kernel::relaxed_bounded;
use crate::chainmail::body::{Body, FIXED};
use crate::chainmail::coords::clamp;
use crate::chainmail::ids::ElementId;
use crate::chainmail::simd::{Prefetch, SimdLevel};

impl Body {
    /// One sweep over the elements of `part` (the first slice, then the second) in place: returns the
    /// largest coordinate move and writes each element's to `last_move`. The fixed-width rows are compiled for the widest vectors `simd` and the machine allow (pulp
    /// picks at run time): the same operations, shorter code.
    pub(crate) fn sweep_region(
        &mut self,
        simd: SimdLevel,
        part: [&[ElementId]; 2],
        last_move: &mut [f32],
    ) -> f32 {
        self.refresh_elastic();
        if self.has_elastic() {
            return self.sweep_region_plain(part, last_move);
        }
        match (self.width, self.pairs.width) {
            (5, 4) => simd.arch().dispatch(Sweep::<5, 4> { body: self, simd, part, last_move }),
            (4, 0) => simd.arch().dispatch(Sweep::<4, 0> { body: self, simd, part, last_move }),
            _ => self.sweep_region_plain(part, last_move),
        }
    }

    /// [`Body::sweep_region`] through the plain kernel, element by element: the reference.
    pub(crate) fn sweep_region_plain(&mut self, part: [&[ElementId]; 2], last_move: &mut [f32]) -> f32 {
        let mut change = 0.0f32;
        for &e in part.into_iter().flatten() {
            let i = e.index();
            let p = self.pos[i];
            let q = self.relaxed_into_boxes(i);
            let m = move_of(p, q);
            if let Some(l) = last_move.get_mut(i) {
                *l = m;
            }
            change = change.max(m);
            self.pos[i] = q;
        }
        change
    }

    /// [`Body::sweep_region_plain`] for link rows `W` wide and pair rows `P` wide.
    #[inline(always)]
    fn sweep_region_rows<const W: usize, const P: usize>(
        &mut self,
        simd: SimdLevel,
        part: [&[ElementId]; 2],
        last_move: &mut [f32],
    ) -> f32 {
        let n = self.pos.len();
        let (flags, rest, classes) = (&self.flags[..n], &self.lattice.rest[..n], &self.classes[..]);
        let (slot_nbr, slot_class) = (&self.slot_nbr[..], &self.slot_class[..]);
        let (pair_nbr, pair_class, pairs) = (&self.pairs.nbr[..], &self.pairs.class[..], &self.pairs);
        let pos = &mut self.pos[..];
        let mut change = 0.0f32;
        let fetch = Prefetch::new(simd);
        for (k, list, &e) in part.into_iter().flat_map(|l| l.iter().enumerate().map(move |(k, e)| (k, l, e)))
        {
            let i = e.index();
            // The region's elements lie apart in memory: their rows are asked for ahead.
            if let Some(f) = list.get(k + Prefetch::AHEAD) {
                let f = f.index();
                fetch.at(slot_nbr, f * W);
                fetch.at(slot_class, f * W);
                fetch.at(pos, f);
                fetch.at(rest, f);
                if P > 0 {
                    fetch.at(pair_nbr, f * P);
                }
            }
            let p = pos[i];
            let q = if flags[i] & FIXED != 0 {
                p
            } else {
                let row = i * W..(i + 1) * W;
                let (Ok(nb), Ok(cl)) =
                    (<&[u32; W]>::try_from(&slot_nbr[row.clone()]), <&[u32; W]>::try_from(&slot_class[row]))
                else {
                    continue;
                };
                // `relaxed_bounded` over arrays: the loops over the row unroll.
                let (mut q, mut lo, mut hi) =
                    relaxed_bounded(|j| pos[j], p, rest[i], &nb[..], &cl[..], classes, |_, j| rest[j]);
                // `relaxed_bounded_in`: the normal pairs' bounds on the third coordinate. (Its lines
                // again, not a function shared with it: one over the rows as slices took 8 % more
                // instructions in this sweep.)
                if P > 0 {
                    let prow = i * P..(i + 1) * P;
                    let (Ok(pn), Ok(pc)) = (
                        <&[u32; P]>::try_from(&pair_nbr[prow.clone()]),
                        <&[u32; P]>::try_from(&pair_class[prow]),
                    ) else {
                        continue;
                    };
                    for k in 0..P {
                        let z = pos[pn[k] as usize][2];
                        let [blo, bhi] = pairs.bounds_of(pc[k]);
                        lo[2] = lo[2].max(z + blo);
                        hi[2] = hi[2].min(z + bhi);
                    }
                    let floor = if lo[2] < p[2] { lo[2] } else { p[2] };
                    let ceil = if hi[2] > p[2] { hi[2] } else { p[2] };
                    q[2] = clamp(q[2], floor, ceil);
                }
                // `relaxed_into_boxes`.
                for c in 0..3 {
                    if lo[c] <= hi[c] {
                        q[c] = q[c].clamp(lo[c], hi[c]);
                    }
                }
                q
            };
            let m = move_of(p, q);
            if let Some(l) = last_move.get_mut(i) {
                *l = m;
            }
            change = change.max(m);
            pos[i] = q;
        }
        change
    }
}

/// A sweep of fixed-width rows, for pulp's dispatch.
struct Sweep<'a, const W: usize, const P: usize> {
    body: &'a mut Body,
    simd: SimdLevel,
    part: [&'a [ElementId]; 2],
    last_move: &'a mut [f32],
}

impl<const W: usize, const P: usize> pulp::WithSimd for Sweep<'_, W, P> {
    type Output = f32;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> f32 {
        self.body.sweep_region_rows::<W, P>(self.simd, self.part, self.last_move)
    }
}

/// The largest coordinate move from `p` to `q`.
#[inline(always)]
fn move_of(p: [f32; 3], q: [f32; 3]) -> f32 {
    (q[0] - p[0]).abs().max((q[1] - p[1]).abs()).max((q[2] - p[2]).abs())
}

#[cfg(test)]
mod tests {
    use crate::chainmail::simd::SimdLevel;
    use crate::chainmail::{ElementId, Material, Pass};
    use crate::surface::Surface;
    use crate::tissue::{ConnectiveSpec, LayerSpec, LayeredSpec, Pinning, Tissue, TissueSpec};

    fn tissue(layers: usize) -> Tissue {
        let layer = |name: &str, offset: f32| LayerSpec {
            name: name.into(),
            color: [1.0; 4],
            offset,
            material: Material { tear_ratio: Some(3.0), ..Material::relative(1.15, 0.85, 0.3) },
        };
        let spec = LayeredSpec {
            surface: Surface::Plane { width: 0.06, depth: 0.05 },
            resolution: [24, 20],
            u_coords: None,
            v_coords: None,
            layers: [layer("dura", 0.003), layer("arachnoid", 0.0)].into_iter().take(layers).collect(),
            connective: (layers == 2).then(|| ConnectiveSpec {
                material: Material { stiffness: 0.3, tear_ratio: None, ..Material::relative(2.0, 0.5, 0.5) },
                density: 1.0,
                min_gap: 0.0005,
                spacing: 0.0,
            }),
            pinned: Pinning::Boundary,
        };
        Tissue::build(&TissueSpec::Layered(spec)).expect("tissue")
    }

    /// The fixed-width sweeps (two layers: 5 links and 4 pairs; one layer: 4 links) give the plain
    /// kernel's positions and moves bit for bit, sweep after sweep, over a region that starts in the
    /// middle of the element order and wraps round (as a region larger than a step's updates does),
    /// on a lifted, stretched sheet with a held patch and a cut.
    #[test]
    fn fixed_width_sweeps_are_the_plain_kernel() {
        for layers in [2, 1] {
            let mut t = tissue(layers);
            let n = t.body().element_count();
            let e = t.nearest_element(t.surface_point(0.45, 0.5, 0.003), Some(0)).expect("element");
            t.grasp(e, 0.004);
            for (k, pass) in [Pass::Plane, Pass::Normal].into_iter().cycle().take(8).enumerate() {
                let goal = t.surface_point(0.45 + 0.01 * k as f32, 0.5, 0.003 + 0.001 * k as f32);
                t.pull_pass(e, goal, pass);
            }
            let cut = t.body().lattice().neighbours(ElementId(n as u32 / 3)).next().map(|(_, l)| l);
            if let Some(l) = cut {
                t.break_link(l, crate::chainmail::BreakReason::Cut);
            }
            let ids: Vec<ElementId> = (0..n as u32).map(ElementId).collect();
            let (head, tail) = ids.split_at(n / 3);
            let part = [tail, &head[..n / 5]];
            let (mut fast, mut plain) = (t.body().clone(), t.body().clone());
            let (mut fast_moves, mut plain_moves) = (vec![0.0f32; n], vec![0.0f32; n]);
            for (sweep, level) in
                [SimdLevel::detected(), SimdLevel::Scalar].into_iter().cycle().take(6).enumerate()
            {
                let a = fast.sweep_region(level, part, &mut fast_moves);
                let b = plain.sweep_region_plain(part, &mut plain_moves);
                assert_eq!(a.to_bits(), b.to_bits(), "{layers} layers, sweep {sweep}: largest move");
                assert!(a > 0.0, "{layers} layers, sweep {sweep}: nothing moved");
                for i in 0..n {
                    let (p, q) = (fast.pos[i], plain.pos[i]);
                    assert_eq!(p.map(f32::to_bits), q.map(f32::to_bits), "{layers} layers, element {i}");
                    assert_eq!(fast_moves[i].to_bits(), plain_moves[i].to_bits(), "move of {i}");
                }
            }
        }
    }
}
