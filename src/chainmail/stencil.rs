//! The grid fast path of a whole-body relaxation sweep.
//!
//! On a grid lattice most elements are *regular*: free, with every neighbour at a fixed offset in the
//! flat arrays (`i ± 1`, `i ± nx`, `i ± nx·ny`, in the adjacency's slot order) and every link of the
//! class its direction has at that grid coordinate (on a rectilinear grid of one material an x-link's
//! box depends only on its x coordinate, a y-link's only on y, a z-link's only on z). Runs of eight
//! regular elements along x are relaxed as one block over flat `f32` streams, which the compiler turns
//! into SIMD: the same arithmetic, in the same order, as the generic row loop, so the result is bit
//! for bit the same. Everything else (borders, wrap seams, cut links, pins, held elements, other
//! materials, curvilinear grids) goes through the generic row loop.

use super::body::{Body, FIXED, SlotClass};

/// Elements per block on wide grids: sixteen, 48 floats, three AVX-512 registers per stream. Grids
/// of 10 to 17 elements along x take blocks of eight.
const BLOCK: usize = 16;
const LANES: usize = 3 * BLOCK;
const SMALL_LANES: usize = LANES / 2;

type Lanes<const L: usize = LANES> = [f32; L];

/// What the fast path knows of a grid body; rebuilt when pins, cuts or materials change.
#[derive(Clone, Debug, Default)]
pub(crate) struct Stencil {
    /// Grid dimensions.
    dims: [usize; 3],
    /// Flat offset of the neighbour in each adjacency slot of an interior element.
    pub(crate) offs: Vec<isize>,
    /// 1 where an element's slots hold exactly the neighbours at `offs` (a fact of the lattice: not a
    /// border, not a wrap seam). The chain reaction finds those neighbours by adding the offset.
    pub(crate) interior: Vec<u8>,
    /// Grid axis of each slot.
    slot_axis: Vec<usize>,
    /// For each slot, the class a regular element has there, by grid coordinate along the slot's
    /// axis (the class most elements have).
    pattern: Vec<Vec<u32>>,
    /// 1 where an element is regular.
    regular: Vec<u8>,
    /// For the x slots (0 and 1): bounds and weight of each element's link, as flat streams of
    /// three floats per element (lo, hi, w per slot).
    x_lo: [Vec<f32>; 2],
    x_hi: [Vec<f32>; 2],
    x_w: [Vec<f32>; 2],
    /// For the y and z slots, whose class is constant along a row: the blocks of bounds and weight
    /// (lo, hi, w) of each class the patterns use, and for each slot and coordinate which one.
    row_blocks: Vec<[Lanes; 3]>,
    row_block_of: Vec<Vec<u32>>,
    /// `OMEGA / Σ w` of every regular element when all their links weigh the same (one stiffness, the
    /// usual case), computed as the generic path computes it: blocks then skip the division.
    uniform_inv: Option<f32>,
    /// Whether `regular` and the streams describe the body as it is.
    pub(crate) fresh: bool,
}

impl Stencil {
    /// The stencil of a grid body, if the body has the grid's slot layout (two slots per axis of more
    /// than one element, x first), else `None`.
    pub(crate) fn for_body(body: &Body) -> Option<Self> {
        let dims = body.lattice.dims?;
        let [nx, ny, _] = dims;
        let strides = [1isize, nx as isize, (nx * ny) as isize];
        let mut offs = Vec::new();
        let mut slot_axis = Vec::new();
        for (axis, &len) in dims.iter().enumerate() {
            if len >= 2 {
                offs.extend([-strides[axis], strides[axis]]);
                slot_axis.extend([axis, axis]);
            }
        }
        if offs.len() != body.width || slot_axis.first() != Some(&0) {
            return None;
        }
        let w = body.width;
        let n = body.pos.len();
        let interior = (0..n)
            .map(|i| {
                let row = &body.slot_nbr[i * w..(i + 1) * w];
                let at = |t: usize| i as isize + offs[t];
                row.iter().enumerate().all(|(t, &j)| (0..n as isize).contains(&at(t)) && j as isize == at(t))
                    as u8
            })
            .collect();
        let pattern = slot_axis.iter().map(|&a| vec![0; dims[a]]).collect();
        Some(Self { dims, offs, interior, slot_axis, pattern, ..Self::default() })
    }

    /// Finds the common class of each slot by grid coordinate (Boyer-Moore majority vote), marks the
    /// regular elements, and lays out the x streams.
    pub(crate) fn refresh(&mut self, body: &Body) {
        let [nx, ny, nz] = self.dims;
        let n = body.pos.len();
        let w = body.width;
        // Element `i` sits at grid coordinates `at`; slot `t` runs along axis `slot_axis[t]`.
        let mut count: Vec<Vec<u32>> = self.pattern.iter().map(|p| vec![0; p.len()]).collect();
        let mut i = 0;
        for k in 0..nz {
            for j in 0..ny {
                for x in 0..nx {
                    let at = [x, j, k];
                    for t in 0..w {
                        let c = at[self.slot_axis[t]];
                        let class = body.slot_class[i * w + t];
                        let (pattern, count) = (&mut self.pattern[t][c], &mut count[t][c]);
                        if *count == 0 {
                            *pattern = class;
                            *count = 1;
                        } else if *pattern == class {
                            *count += 1;
                        } else {
                            *count -= 1;
                        }
                    }
                    i += 1;
                }
            }
        }
        self.regular.resize(n, 0);
        let mut i = 0;
        for k in 0..nz {
            for j in 0..ny {
                for x in 0..nx {
                    let at = [x, j, k];
                    let row = &body.slot_class[i * w..(i + 1) * w];
                    let mut ok = self.interior[i] == 1 && body.flags[i] & FIXED == 0;
                    for (t, &class) in row.iter().enumerate() {
                        let expected = self.pattern[t][at[self.slot_axis[t]]];
                        ok &= class == expected && class != 0;
                    }
                    self.regular[i] = ok as u8;
                    i += 1;
                }
            }
        }
        for t in 0..2 {
            let (lo, hi, wt) = (&mut self.x_lo[t], &mut self.x_hi[t], &mut self.x_w[t]);
            lo.clear();
            hi.clear();
            wt.clear();
            for &class in &self.pattern[t] {
                let SlotClass { bounds: [l, h], w } = body.classes[class as usize];
                lo.extend(l);
                hi.extend(h);
                wt.extend([w; 3]);
            }
        }
        let mut block_of_class = std::collections::HashMap::new();
        self.row_blocks.clear();
        self.row_block_of.clear();
        for pattern in self.pattern.iter().skip(2) {
            let mut of = Vec::with_capacity(pattern.len());
            for &class in pattern {
                let index = *block_of_class.entry(class).or_insert_with(|| {
                    let SlotClass { bounds: [l, h], w } = body.classes[class as usize];
                    let lanes = |f: &dyn Fn(usize) -> f32| std::array::from_fn(|e| f(e % 3));
                    self.row_blocks.push([lanes(&|c| l[c]), lanes(&|c| h[c]), [w; LANES]]);
                    self.row_blocks.len() as u32 - 1
                });
                of.push(index);
            }
            self.row_block_of.push(of);
        }
        // One weight for every class a regular element can have (the non-free pattern classes)?
        let mut weights =
            self.pattern.iter().flatten().filter(|&&c| c != 0).map(|&c| body.classes[c as usize].w);
        self.uniform_inv = match weights.next() {
            Some(w) if w > 0.0 && weights.all(|x| x.to_bits() == w.to_bits()) => {
                let wsum = (0..self.offs.len()).fold(0.0f32, |s, _| s + w);
                Some(super::relax::OMEGA / wsum)
            }
            _ => None,
        };
        self.fresh = true;
    }
}

/// The per-direction inputs of one block: neighbour positions and rest positions, bounds, weights.
#[derive(Clone, Copy)]
struct Dir<'a, const L: usize> {
    p: &'a Lanes<L>,
    r: &'a Lanes<L>,
    lo: &'a Lanes<L>,
    hi: &'a Lanes<L>,
    w: &'a Lanes<L>,
}

/// Relaxes one block of regular elements: `relaxed_row` lane by lane, slots in the same order. With
/// `UNIFORM` every link weighs the same and `inv` is `OMEGA / Σ w`, computed once.
#[inline(always)]
fn block<const W: usize, const UNIFORM: bool, const L: usize>(
    p: &Lanes<L>,
    r: &Lanes<L>,
    dirs: &[Dir<'_, L>; W],
    inv: f32,
    out: &mut Lanes<L>,
    change: &mut Lanes<L>,
) {
    for k in 0..L {
        let mut acc = 0.0f32;
        let mut wsum = 0.0f32;
        let mut lo = f32::NEG_INFINITY;
        let mut hi = f32::INFINITY;
        for d in dirs {
            let pj = d.p[k];
            acc += d.w[k] * (pj - d.r[k]);
            let (l, h) = (pj + d.lo[k], pj + d.hi[k]);
            lo = if l > lo { l } else { lo };
            hi = if h < hi { h } else { hi };
            if !UNIFORM {
                wsum += d.w[k];
            }
        }
        let pk = p[k];
        let inv = if UNIFORM { inv } else { super::relax::OMEGA / wsum };
        let target = pk + (acc * inv - super::relax::OMEGA * (pk - r[k]));
        let floor = if lo < pk { lo } else { pk };
        let ceil = if hi > pk { hi } else { pk };
        let t = if target > floor { target } else { floor };
        let q = if t < ceil { t } else { ceil };
        let q = if UNIFORM || wsum > 0.0 { q } else { pk };
        out[k] = q;
        let moved = (q - pk).abs();
        change[k] = if moved > change[k] { moved } else { change[k] };
    }
}

/// One stencil sweep as an operation for [`pulp::Arch::dispatch`].
struct Sweep<'a, const W: usize, const L: usize> {
    body: &'a Body,
    stencil: &'a Stencil,
    next: &'a mut [[f32; 3]],
}

impl<const W: usize, const L: usize> pulp::WithSimd for Sweep<'_, W, L> {
    type Output = Option<f32>;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Option<f32> {
        self.body.sweep_stencil_w::<W, L>(self.stencil, self.next)
    }
}

/// The block of a stream starting at `at`. Regular elements have all their neighbours inside the
/// grid, so blocks are always whole; an empty block (never taken) keeps this free of panics.
#[inline(always)]
fn lanes<const L: usize>(s: &[f32], at: usize) -> &Lanes<L> {
    let block = s.get(at..at + L).and_then(|s| s.try_into().ok());
    debug_assert!(block.is_some(), "block at {at} of {}", s.len());
    block.unwrap_or(&const { [0.0; L] })
}

impl Body {
    /// One Jacobi sweep over every element through the grid fast path; `None` if this body has no
    /// stencil. Writes `next` for every element and returns the largest move.
    pub(crate) fn sweep_stencil(&mut self, next: &mut [[f32; 3]]) -> Option<f32> {
        let nx = self.stencil.as_ref()?.dims[0];
        if nx < SMALL_LANES / 3 + 2 {
            return None;
        }
        let wide = nx >= BLOCK + 2;
        let mut stencil = self.stencil.take()?;
        if !stencil.fresh {
            stencil.refresh(self);
        }
        // The sweep is compiled once per instruction set and the widest the CPU has is chosen at run
        // time (AVX2 on most x86-64 machines); the arithmetic, and so the result, is the same.
        let arch = pulp::Arch::new();
        let change = match (stencil.offs.len(), wide) {
            (4, true) => arch.dispatch(Sweep::<4, LANES> { body: self, stencil: &stencil, next }),
            (6, true) => arch.dispatch(Sweep::<6, LANES> { body: self, stencil: &stencil, next }),
            (4, false) => arch.dispatch(Sweep::<4, SMALL_LANES> { body: self, stencil: &stencil, next }),
            (6, false) => arch.dispatch(Sweep::<6, SMALL_LANES> { body: self, stencil: &stencil, next }),
            _ => None,
        };
        self.stencil = Some(stencil);
        change
    }

    #[inline(always)]
    fn sweep_stencil_w<const W: usize, const L: usize>(
        &self,
        st: &Stencil,
        next: &mut [[f32; 3]],
    ) -> Option<f32> {
        let [nx, ny, nz] = st.dims;
        let n = self.pos.len();
        if next.len() != n || st.regular.len() != n {
            return None;
        }
        let (pos, rest) = (&self.pos[..], &self.lattice.rest[..]);
        let (pf, rf) = (pos.as_flattened(), rest.as_flattened());
        let mut scalar_change = 0.0f32;
        let b = L / 3;
        let mut lane_change = [0.0f32; L];
        let mut generic = |i: usize, next: &mut [[f32; 3]]| {
            let p = pos[i];
            let q = self.relaxed_unless_fixed(i);
            scalar_change = super::relax::max_change(scalar_change, p, q);
            next[i] = q;
        };
        let zero = const { [0.0f32; L] };
        let mut row_block = [[&zero; 3]; W];
        let interior = |c: usize, len: usize| len < 2 || (c > 0 && c + 1 < len);
        for k in 0..nz {
            for j in 0..ny {
                let row = nx * (j + ny * k);
                if !(interior(j, ny) && interior(k, nz)) {
                    for i in row..row + nx {
                        generic(i, next);
                    }
                    continue;
                }
                // The y and z slots' blocks for this row.
                for (t, block) in row_block.iter_mut().enumerate().skip(2) {
                    let c = if st.slot_axis[t] == 1 { j } else { k };
                    let index = st.row_block_of.get(t - 2).and_then(|of| of.get(c));
                    if let Some(lanes) = index.and_then(|&b| st.row_blocks.get(b as usize)) {
                        *block = lanes.each_ref().map(|l| l.first_chunk::<L>().unwrap_or(&zero));
                    }
                }
                generic(row, next);
                // Blocks of `b` elements along the row's interior `1..nx - 1`; the last one is moved back to
                // end at `nx - 1`, overlapping its neighbour (the overlap is computed twice, alike).
                let mut i = 1;
                while i < nx - 1 {
                    let i0 = i.min(nx - 1 - b);
                    let e = row + i0;
                    if st.regular.get(e..e + b) != Some(&[1; BLOCK][..b]) {
                        for e in row + i..row + i0 + b {
                            generic(e, next);
                        }
                        i = i0 + b;
                        continue;
                    }
                    let f = 3 * e;
                    let empty = Dir { p: &zero, r: &zero, lo: &zero, hi: &zero, w: &zero };
                    let mut dirs = [empty; W];
                    for (t, dir) in dirs.iter_mut().enumerate() {
                        let g = (f as isize + 3 * st.offs[t]) as usize;
                        let (lo, hi, w) = if t < 2 {
                            (
                                lanes(&st.x_lo[t], 3 * i0),
                                lanes(&st.x_hi[t], 3 * i0),
                                lanes(&st.x_w[t], 3 * i0),
                            )
                        } else {
                            (row_block[t][0], row_block[t][1], row_block[t][2])
                        };
                        *dir = Dir { p: lanes(pf, g), r: lanes(rf, g), lo, hi, w };
                    }
                    let out: &mut Lanes<L> = match next.as_flattened_mut().get_mut(f..f + L) {
                        Some(s) => match s.try_into() {
                            Ok(s) => s,
                            Err(_) => return None,
                        },
                        None => return None,
                    };
                    let (p, r) = (lanes(pf, f), lanes(rf, f));
                    match st.uniform_inv {
                        Some(inv) => block::<W, true, L>(p, r, &dirs, inv, out, &mut lane_change),
                        None => block::<W, false, L>(p, r, &dirs, 0.0, out, &mut lane_change),
                    }
                    i = i0 + b;
                }
                generic(row + nx - 1, next);
            }
        }
        Some(lane_change.iter().fold(scalar_change, |m, &c| if c > m { c } else { m }))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Body, Lattice, Material, RelaxBudget, RelaxRegion, Workspace};

    #[test]
    fn interior_of_a_plain_sheet_is_regular() {
        let body =
            Body::new(Lattice::sheet(64, 32, 0.001).expect("sheet"), Material::relative(1.2, 0.8, 0.3))
                .expect("body");
        let mut st = body.stencil.clone().expect("stencil");
        st.refresh(&body);
        let regular = st.regular.iter().filter(|&&r| r == 1).count();
        assert_eq!(regular, 62 * 30, "every interior element is regular");
        let mut body = body;
        let mut ws = Workspace::new(&body);
        body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::All);
        assert!(body.stencil.as_ref().is_some_and(|s| s.fresh), "refreshed once, then kept");
    }
}
