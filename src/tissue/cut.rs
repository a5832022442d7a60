//! Cutting: a blade path removes every link it crosses. Cuts are queued during the step and applied
//! together in the cut phase.

use serde::{Deserialize, Serialize};

use super::{Geometry, LinkKind, Tissue};
use crate::chainmail::{BreakReason, LinkId};

/// How deep the blade runs.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum CutDepth {
    /// Through the upper layer: an incision that opens (in-layer links).
    Upper,
    /// Between the layers: the connective fibres.
    #[default]
    Between,
    /// Through the lower layer.
    Lower,
}

/// One straight piece of a blade path, world coordinates (metres).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct CutSegment {
    /// Start of the piece.
    pub from: [f32; 3],
    /// End of the piece.
    pub to: [f32; 3],
    /// Depth of the blade.
    pub depth: CutDepth,
}

#[inline]
fn orient(a: [f32; 2], b: [f32; 2], c: [f32; 2]) -> f32 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether 2D segments `ab` and `cd` cross (touching counts).
#[inline]
fn segments_cross(a: [f32; 2], b: [f32; 2], c: [f32; 2], d: [f32; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 <= 0.0 && o3 * o4 <= 0.0 && !(o1 == 0.0 && o2 == 0.0)
}

#[inline]
fn point_segment_dist(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f32 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = [a[0] + t * ab[0] - p[0], a[1] + t * ab[1] - p[1]];
    (q[0] * q[0] + q[1] * q[1]).sqrt()
}

/// Whether the 3D segment `pq` crosses the quad `a, b, b + down, a + down` (the blade's swept face).
fn crosses_blade(p: [f32; 3], q: [f32; 3], a: [f32; 3], b: [f32; 3], depth: f32) -> bool {
    // Plane of the blade: spanned by (b - a) and the vertical.
    let e = [b[0] - a[0], 0.0, b[2] - a[2]];
    let n = [-e[2], 0.0, e[0]];
    let side = |x: [f32; 3]| (x[0] - a[0]) * n[0] + (x[2] - a[2]) * n[2];
    let (sp, sq) = (side(p), side(q));
    if sp * sq > 0.0 || sp == sq {
        return false;
    }
    let t = sp / (sp - sq);
    let x = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), p[2] + t * (q[2] - p[2])];
    let len2 = e[0] * e[0] + e[2] * e[2];
    if len2 <= 0.0 {
        return false;
    }
    let s = ((x[0] - a[0]) * e[0] + (x[2] - a[2]) * e[2]) / len2;
    let top = a[1] + s * (b[1] - a[1]);
    (0.0..=1.0).contains(&s) && x[1] <= top + 1e-6 && x[1] >= top - depth
}

impl Tissue {
    /// Queues a blade segment; it is applied in the next [`Tissue::apply_cuts`].
    pub fn queue_cut(&mut self, segment: CutSegment) {
        self.cut_queue.push(segment);
    }

    /// How far any element has moved from rest across the surface (largest of `|du|`, `|dv|`, lattice
    /// units). Kept up to date step by step from the disturbed region, which holds every element a
    /// step moves; measured over the whole body again only after moves made outside the steps
    /// (`drift_at` is `None` then).
    pub(crate) fn drift(&mut self) -> f32 {
        let motion = self.body.motion();
        if self.drift_at == Some(motion) {
            return self.drift_max;
        }
        self.drift_max = match self.drift_bound() {
            Some(d) => d,
            None => {
                let (pos, rest) = (self.body.positions(), self.body.lattice().rest_positions());
                (0..pos.len()).fold(0.0f32, |m, i| m.max(drift_of(pos, rest, i)))
            }
        };
        self.drift_at = Some(motion);
        self.drift_max
    }

    /// [`Tissue::drift`] where it costs no more than the region: kept, or followed from the region
    /// since it was kept; `None` after moves made outside the steps (the whole body must be measured).
    pub(crate) fn drift_bound(&self) -> Option<f32> {
        if self.drift_at == Some(self.body.motion()) {
            return Some(self.drift_max);
        }
        let (pos, rest) = (self.body.positions(), self.body.lattice().rest_positions());
        let region = |m: f32| self.active.iter().fold(m, |m, e| m.max(drift_of(pos, rest, e.index())));
        match (self.drift_at, self.scan()) {
            // The limits' repair's scan of the region measured it (the plain loop beside it in debug
            // builds, so that every test's steps compare them).
            (Some(_), Some(s)) => {
                let d = self.drift_max.max(s.drift);
                #[cfg(all(debug_assertions, not(feature = "count-allocations")))]
                debug_assert_eq!(d.to_bits(), region(self.drift_max).to_bits(), "the scan's drift differs");
                Some(d)
            }
            (Some(_), None) => Some(region(self.drift_max)),
            (None, _) => None,
        }
    }

    /// Applies every queued cut; returns how many links it severed.
    pub fn apply_cuts(&mut self) -> u32 {
        if let super::Model::Fem(_) = self.model {
            if !self.cut_queue.is_empty() {
                self.cut_queue.clear();
                self.notice = Some(super::FEM_CUT_REFUSED.to_string());
            }
            return 0;
        }
        let mut count = 0;
        let queue = std::mem::take(&mut self.cut_queue);
        for seg in &queue {
            count += self.cut_segment(seg);
        }
        // Give the buffer back so the next step does not allocate.
        self.cut_queue = queue;
        self.cut_queue.clear();
        count
    }

    fn cut_segment(&mut self, seg: &CutSegment) -> u32 {
        let mut cut = 0;
        match self.geometry {
            Geometry::Surface(surface) => {
                let a = surface.to_lattice(seg.from, 0.0);
                let b = surface.to_lattice(seg.to, a[0]);
                let (a2, b2) = ([a[0], a[1]], [b[0], b[1]]);
                let period = surface.u_period();
                let mid_u = 0.5 * (a[0] + b[0]);
                let nl = self.layers.len() as u8;
                let want = match seg.depth {
                    CutDepth::Upper => LinkKind::Layer(0),
                    CutDepth::Lower => LinkKind::Layer(nl - 1),
                    CutDepth::Between if nl == 2 => LinkKind::Connective,
                    CutDepth::Between => return 0,
                };
                // Fibres whose middle lies within the blade's half-width of the stroke (metres, the
                // same at every element spacing).
                let reach = self.blade_half_width;
                // Only links that come within the blade's reach of the stroke's bounding box can be hit.
                let slack = reach;
                let (lo, hi) = (
                    [a2[0].min(b2[0]) - slack, a2[1].min(b2[1]) - slack],
                    [a2[0].max(b2[0]) + slack, a2[1].max(b2[1]) + slack],
                );
                let Some(grid) = self.kind_links.iter().position(|(k, _)| *k == want) else { return 0 };
                let drift = self.drift();
                let mut ids = std::mem::take(&mut self.cut_candidates);
                ids.clear();
                self.kind_links[grid].1.near(lo, hi, drift, &mut ids);
                // In id order, as a scan of every link of the kind would cut them.
                ids.sort_unstable();
                for &l in &ids {
                    let id = LinkId(l);
                    if !self.body.link_intact(id) {
                        continue;
                    }
                    let (Some([ea, _]), Some(off)) =
                        (self.body.lattice().link_ends(id), self.body.link_offset(id))
                    else {
                        continue;
                    };
                    let pa = self.body.positions()[ea.index()];
                    // Bring the link next to the blade across a wrap seam.
                    let shift = period.map(|p| ((mid_u - pa[0]) / p).round() * p).unwrap_or(0.0);
                    let p = [pa[0] + shift, pa[1]];
                    let q = [p[0] + off[0], p[1] + off[1]];
                    if p[0].max(q[0]) < lo[0]
                        || p[0].min(q[0]) > hi[0]
                        || p[1].max(q[1]) < lo[1]
                        || p[1].min(q[1]) > hi[1]
                    {
                        continue;
                    }
                    let hit = if want == LinkKind::Connective {
                        point_segment_dist([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])], a2, b2) <= reach
                    } else {
                        segments_cross(p, q, a2, b2)
                    };
                    if hit && self.break_link(id, BreakReason::Cut) {
                        cut += 1;
                    }
                }
                self.cut_candidates = ids;
            }
            Geometry::Volume => {
                let height = self
                    .body
                    .lattice()
                    .rest_positions()
                    .iter()
                    .fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
                let h = height.1 - height.0;
                let depth = match seg.depth {
                    CutDepth::Upper => h / 3.0,
                    CutDepth::Between => 2.0 * h / 3.0,
                    CutDepth::Lower => h * 1.01,
                };
                for l in 0..self.body.link_count() {
                    let id = LinkId(l as u32);
                    if !self.body.link_intact(id) {
                        continue;
                    }
                    let Some([ea, eb]) = self.body.lattice().link_ends(id) else { continue };
                    let (pa, pb) = (self.body.positions()[ea.index()], self.body.positions()[eb.index()]);
                    if crosses_blade(pa, pb, seg.from, seg.to, depth) && self.break_link(id, BreakReason::Cut)
                    {
                        cut += 1;
                    }
                }
            }
        }
        cut
    }
}

/// How far element `i` lies from where it rests across the surface (largest of `|du|`, `|dv|`).
fn drift_of(pos: &[[f32; 3]], rest: &[[f32; 3]], i: usize) -> f32 {
    (pos[i][0] - rest[i][0]).abs().max((pos[i][1] - rest[i][1]).abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_segments() {
        assert!(segments_cross([0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]));
        assert!(!segments_cross([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]));
        assert!(!segments_cross([0.0, 0.0], [1.0, 0.0], [2.0, -1.0], [2.0, 1.0]));
    }

    #[test]
    fn blade_face() {
        let (a, b) = ([0.0, 1.0, 0.0], [1.0, 1.0, 0.0]);
        assert!(crosses_blade([0.5, 0.8, -0.1], [0.5, 0.8, 0.1], a, b, 0.5));
        assert!(!crosses_blade([0.5, 0.2, -0.1], [0.5, 0.2, 0.1], a, b, 0.5));
        assert!(!crosses_blade([1.5, 0.8, -0.1], [1.5, 0.8, 0.1], a, b, 0.5));
    }

    /// The link grid visits every link a stroke can reach: after random pulls (which move elements
    /// far from rest across the plane), random strokes of every depth cut exactly the links a scan
    /// of every link cuts (the plain path: one cell holding them all). The element grids find the
    /// element nearest a point exactly as a scan of every element does.
    #[test]
    fn strokes_cut_what_a_scan_of_every_link_cuts() {
        use crate::chainmail::{ElementId, Material, Pass, RelaxBudget};
        use crate::surface::Surface;
        use crate::tissue::{ConnectiveSpec, LayerSpec, LayeredSpec, Pinning, TissueSpec};
        let layer = |name: &str, offset: f32| LayerSpec {
            name: name.into(),
            color: [1.0; 4],
            offset,
            material: Material { tear_ratio: None, ..Material::relative(1.3, 0.8, 0.4) },
        };
        let spec = TissueSpec::Layered(LayeredSpec {
            surface: Surface::Plane { width: 0.04, depth: 0.03 },
            resolution: [81, 61],
            u_coords: None,
            v_coords: None,
            layers: vec![layer("upper", 0.002), layer("lower", 0.0)],
            connective: Some(ConnectiveSpec {
                material: Material::relative(2.0, 0.5, 0.5),
                density: 1.0,
                min_gap: 0.0,
                spacing: 0.0,
            }),
            pinned: Pinning::Boundary,
        });
        let mut seed = 7u64;
        let mut rng = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 40) as f32) / ((1u64 << 24) as f32)
        };
        for round in 0..6 {
            let mut fast = Tissue::build(&spec).unwrap_or_else(|e| panic!("{e}"));
            let mut plain = fast.clone();
            for (t, wrapped, per_cell) in [(&mut plain, true, 1.0), (&mut fast, false, 2.0)] {
                for (_, grid) in &mut t.kind_links {
                    let mut all = Vec::new();
                    grid.near([0.0; 2], [0.0; 2], f32::INFINITY, &mut all);
                    *grid =
                        super::super::link_grid::LinkGrid::with_cells_of(&t.body, &all, wrapped, per_cell);
                }
                // Cells of two elements: the nearest element's search must widen past the drift.
                for grid in &mut t.layer_elements {
                    let mut all = Vec::new();
                    grid.near([0.0; 2], [0.0; 2], f32::INFINITY, &mut all);
                    *grid = super::super::link_grid::LinkGrid::of_elements_in_cells_of(
                        &t.body, &all, wrapped, per_cell,
                    );
                }
            }
            let n = fast.body.element_count();
            let mut pulled = Vec::new();
            for _ in 0..20 {
                let e = ElementId((rng() * n as f32) as u32 % n as u32);
                pulled.push(e);
                let p = fast.body.position(e).unwrap_or_else(|e| panic!("{e}"));
                let goal = [p[0] + 0.02 * (rng() - 0.5), p[1] + 0.02 * (rng() - 0.5), p[2] + 0.004 * rng()];
                for t in [&mut fast, &mut plain] {
                    if round % 2 == 0 {
                        // Moves outside the steps: the drift is measured over the whole body.
                        let _ = t.body.deform(&mut t.ws, e, goal, Pass::All);
                        t.relax_all(RelaxBudget::sweeps(3));
                    } else {
                        // Steps: the drift follows the disturbed region.
                        let world = t.geometry.to_world(goal);
                        for pass in [Pass::Plane, Pass::Normal] {
                            t.pull_pass(e, world, pass);
                        }
                        t.relax(RelaxBudget::sweeps(3));
                        t.end_step();
                    }
                }
            }
            // The nearest element's search by cells answers as a scan of every element does, near
            // what was pulled (elements far from rest) and anywhere over the sheet.
            assert_eq!(fast.layer_elements.len(), 2);
            assert!(fast.layer_elements.iter().all(|g| !g.is_whole()));
            let odd =
                [[f32::NAN, 0.0, 0.0], [f32::INFINITY, 0.0, 0.01], [1e30, 0.0, -1e30], [0.0, -1e6, 0.0]];
            for k in 0..60 + odd.len() {
                let p = if k >= 60 {
                    odd[k - 60]
                } else if k % 2 == 0 {
                    let e = pulled[(rng() * pulled.len() as f32) as usize % pulled.len()];
                    let at = fast.world_position(e).unwrap_or_else(|| panic!("element {e:?}"));
                    [at[0] + 0.004 * (rng() - 0.5), 0.006 * rng() - 0.001, at[2] + 0.004 * (rng() - 0.5)]
                } else {
                    [0.05 * rng() - 0.025, 0.01 * rng() - 0.002, 0.04 * rng() - 0.02]
                };
                for layer in [None, Some(0), Some(1)] {
                    let mut want: Option<(f32, u32)> = None;
                    for (li, l) in fast.layers.iter().enumerate().rev() {
                        if layer.is_some_and(|x| x != li) {
                            continue;
                        }
                        if let Some((d, i)) = fast.nearest_of(l.first..l.first + l.count, p)
                            && want.is_none_or(|(bd, _)| d < bd)
                        {
                            want = Some((d, i));
                        }
                    }
                    let want = want.map(|(_, i)| ElementId(i));
                    assert_eq!(
                        fast.nearest_element(p, layer),
                        want,
                        "round {round}, point {k} {p:?}, layer {layer:?}"
                    );
                }
            }
            for k in 0..30 {
                let depth = [CutDepth::Upper, CutDepth::Between, CutDepth::Lower][k % 3];
                // Short strokes where pulled elements are now: the links there lie far from where
                // they rest.
                let e = pulled[(rng() * pulled.len() as f32) as usize % pulled.len()];
                let at = fast.world_position(e).unwrap_or_else(|| panic!("element {e:?}"));
                let a = [at[0] + 0.001 * (rng() - 0.5), 0.0015, at[2] + 0.001 * (rng() - 0.5)];
                let b = [a[0] + 0.002 * (rng() - 0.5), 0.0015, a[2] + 0.002 * (rng() - 0.5)];
                let (cf, cp) = (
                    fast.cut_segment(&CutSegment { from: a, to: b, depth }),
                    plain.cut_segment(&CutSegment { from: a, to: b, depth }),
                );
                assert_eq!(cf, cp, "round {round}, stroke {k}: links cut");
            }
            assert!(
                fast.damage().connective_links_cut + fast.damage().layer_links_cut > 0,
                "round {round}: nothing cut"
            );
            assert_eq!(fast.events, plain.events, "round {round}: the same links in the same order");
        }
    }
}
