//! What the tissue looks like: world-space triangle meshes per layer (triangles that span a broken link
//! left out, so a cut opens as a gap), the connective fibres as segments, refilled in place.

use super::{Geometry, LinkKind, Tissue};
use crate::chainmail::{BreakReason, LinkId};
use crate::snapshot::{BrokenFibre, LayerMesh, SurfacePattern};

/// Drawn thickness of the outermost layer (a dura is about half a millimetre to a millimetre), metres.
const OUTER_THICKNESS: f32 = 0.0006;
/// Drawn thickness of the layers under it (an arachnoid is thinner), metres.
const INNER_THICKNESS: f32 = 0.0003;

/// What turns the meshes [`Tissue::fill_meshes_raw`] filled into what [`Tissue::fill_meshes`] fills:
/// the lattice's map to the world and each layer's caps. It never changes for a tissue, so a thread
/// that reads frames the simulation thread filled raw can finish them itself
/// ([`crate::runner::Published`]): the simulation thread then only copies positions.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshRecipe {
    geometry: Geometry,
    /// Per layer, each cap's ring as vertex indices of that layer's mesh.
    caps: Vec<Vec<Vec<u32>>>,
    /// The connective fibres, in the order drawn.
    fibres: Vec<FibreRecipe>,
}

/// A connective fibre as the recipe draws it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FibreRecipe {
    link: LinkId,
    /// Its ends as (layer, vertex of that layer's mesh), the lower layer's first: a fibre joins two
    /// elements the meshes already carry.
    ends: [[u32; 2]; 2],
    /// Its rest length, world metres.
    rest: f32,
    /// Where it stands at rest (see [`BrokenFibre::site`]).
    site: [f32; 4],
}

/// A raw fibre's state (see [`Tissue::fill_fibres_raw`]): intact, cut or torn.
const FIBRE_INTACT: f32 = 0.0;
const FIBRE_CUT: f32 = 1.0;
const FIBRE_TORN: f32 = 2.0;

impl MeshRecipe {
    /// A recipe of nothing, until the tissue is built.
    pub(crate) fn empty(geometry: Geometry) -> Self {
        Self { geometry, caps: Vec::new(), fibres: Vec::new() }
    }

    /// The recipe of a tissue's meshes (its fibres' sites already found).
    pub(crate) fn new(tissue: &Tissue) -> Self {
        let caps = tissue
            .layers
            .iter()
            .map(|layer| {
                layer.caps.iter().map(|cap| cap.ring.iter().map(|&e| e - layer.first).collect()).collect()
            })
            .collect();
        let fibres = tissue
            .fibre_sites
            .iter()
            .filter_map(|&(link, site)| {
                let [a, b] = tissue.body.lattice().link_ends(link)?;
                let [a, b] = if tissue.layer_of(a) < tissue.layer_of(b) { [b, a] } else { [a, b] };
                let rest = tissue.rest_len.get(link.index()).copied()?.max(f32::MIN_POSITIVE);
                let end = |e: crate::chainmail::ElementId| {
                    let k = tissue.layer_of(e)?;
                    Some([k as u32, e.0 - tissue.layers[k].first])
                };
                Some(FibreRecipe { link, ends: [end(a)?, end(b)?], rest, site })
            })
            .collect();
        Self { geometry: tissue.geometry, caps, fibres }
    }

    /// Finishes a snapshot filled raw ([`crate::simulation::World::snapshot_raw_into`]): its layers'
    /// meshes ([`MeshRecipe::finish`]), then its fibres from them (what [`Tissue::fill_fibres`] fills).
    pub fn finish_snapshot(&self, snapshot: &mut crate::snapshot::Snapshot) {
        self.finish(&mut snapshot.layers);
        let s = snapshot;
        self.finish_fibres(
            &s.layers,
            &mut s.fibres,
            &mut s.fibre_stretch,
            &mut s.fibre_sites,
            &mut s.broken_fibres,
        );
    }

    /// Finishes fibres filled raw ([`Tissue::fill_fibres_raw`]) from the finished `layers`: `out` gets
    /// the intact fibres' ends in the world, `stretch` (which held each fibre's state) their world
    /// stretch and `sites` where they stand; the fibres cut or torn go to `broken`. What
    /// [`Tissue::fill_fibres`] fills.
    fn finish_fibres(
        &self,
        layers: &[LayerMesh],
        out: &mut Vec<[[f32; 3]; 2]>,
        stretch: &mut Vec<f32>,
        sites: &mut Vec<[f32; 4]>,
        broken: &mut Vec<BrokenFibre>,
    ) {
        out.clear();
        sites.clear();
        broken.clear();
        let at = |[k, v]: [u32; 2]| layers.get(k as usize).and_then(|m| m.positions.get(v as usize)).copied();
        let mut kept = 0;
        // In place: the intact fibres' stretch moves down over the states read.
        for (i, f) in self.fibres.iter().enumerate() {
            let (Some(pa), Some(pb), Some(&state)) = (at(f.ends[0]), at(f.ends[1]), stretch.get(i)) else {
                break;
            };
            if state == FIBRE_INTACT {
                let d = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2) + (pb[2] - pa[2]).powi(2)).sqrt();
                out.push([pa, pb]);
                stretch[kept] = d / f.rest;
                sites.push(f.site);
                kept += 1;
            } else {
                broken.push(BrokenFibre { ends: [pa, pb], cut: state == FIBRE_CUT, site: f.site });
            }
        }
        stretch.truncate(kept);
    }

    /// Finishes meshes filled raw: their positions (lattice coordinates) mapped to the world, each
    /// cap's pole vertex added, and the vertex normals. Meshes beyond the recipe's layers are left.
    pub fn finish(&self, layers: &mut [LayerMesh]) {
        for (slot, caps) in layers.iter_mut().zip(&self.caps) {
            for p in &mut slot.positions {
                *p = self.geometry.to_world(*p);
            }
            // Each cap's pole vertex follows the elements: the ring's centroid pushed out to the ring's
            // mean distance from the centre of the surface.
            for ring in caps {
                let (mut c, mut r) = ([0.0f32; 3], 0.0f32);
                for &v in ring {
                    let p = slot.positions[v as usize];
                    c = [c[0] + p[0], c[1] + p[1], c[2] + p[2]];
                    r += (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                }
                let m = ring.len().max(1) as f32;
                let len = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt().max(f32::MIN_POSITIVE);
                let s = r / m / len;
                slot.positions.push([c[0] * s, c[1] * s, c[2] * s]);
            }
            slot.normals.clear();
            slot.normals.resize(slot.positions.len(), [0.0; 3]);
            for t in &slot.triangles {
                let [a, b, c] = t.map(|v| slot.positions[v as usize]);
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let f = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                for &v in t {
                    let m = &mut slot.normals[v as usize];
                    m[0] += f[0];
                    m[1] += f[1];
                    m[2] += f[2];
                }
            }
            normalize_all(&mut slot.normals);
        }
    }
}

impl Tissue {
    /// Refills `out` with one mesh per layer, the upper layer first. Buffers are reused; triangles are
    /// rebuilt only when the topology changed since the mesh was last filled.
    pub fn fill_meshes(&self, out: &mut Vec<LayerMesh>) {
        self.fill_meshes_raw(out);
        self.mesh_recipe.finish(out);
    }

    /// What finishes the meshes [`Tissue::fill_meshes_raw`] fills.
    pub fn mesh_recipe(&self) -> &std::sync::Arc<MeshRecipe> {
        &self.mesh_recipe
    }

    /// [`Tissue::fill_meshes`] but for what [`MeshRecipe::finish`] does: the positions are the elements'
    /// lattice coordinates (a copy), without the caps' poles, and the normals are left as they were.
    /// Triangles, surface coordinates and the rest are filled.
    pub fn fill_meshes_raw(&self, out: &mut Vec<LayerMesh>) {
        let nl = self.layers.len();
        out.truncate(nl);
        while out.len() < nl {
            out.push(LayerMesh { topology_version: u64::MAX, ..LayerMesh::default() });
        }
        let volume = matches!(self.geometry, Geometry::Volume) || self.is_fem();
        for (k, (slot, layer)) in out.iter_mut().zip(&self.layers).enumerate() {
            if slot.name != layer.name {
                slot.name.clone_from(&layer.name);
            }
            slot.color = layer.color;
            slot.grid = layer.grid;
            let outer = k == 0;
            slot.thickness = if outer { OUTER_THICKNESS } else { INNER_THICKNESS };
            slot.pattern = match (volume, outer) {
                (true, _) => SurfacePattern::Plain,
                (false, true) => SurfacePattern::Grain,
                (false, false) => SurfacePattern::Vessels,
            };
            let k2 = if volume { 2 } else { 1 };
            slot.uv_size = [self.extent_span[0].abs(), self.extent_span[k2].abs()];
            let first = layer.first as usize;
            let n = layer.count as usize;
            slot.positions.clear();
            slot.positions.extend_from_slice(&self.body.positions()[first..first + n]);
            if slot.topology_version != layer.version || slot.triangles.is_empty() {
                slot.triangles.clear();
                slot.triangles.extend(
                    layer
                        .triangles
                        .iter()
                        .filter(|(_, links)| {
                            links.iter().all(|&l| l == u32::MAX || self.body.link_intact(LinkId(l)))
                        })
                        .map(|&(t, _)| t.map(|v| v - layer.first)),
                );
                for (c, cap) in layer.caps.iter().enumerate() {
                    let pole = (n + c) as u32;
                    let m = cap.ring.len();
                    for i in 0..m {
                        if cap.links[i] != u32::MAX && !self.body.link_intact(LinkId(cap.links[i])) {
                            continue;
                        }
                        let (a, b) = (cap.ring[i] - layer.first, cap.ring[(i + 1) % m] - layer.first);
                        slot.triangles.push(if cap.flip { [pole, b, a] } else { [pole, a, b] });
                    }
                }
                slot.topology_version = layer.version;
            }
            if slot.uv.len() != n + layer.caps.len() {
                // Rest positions never change: the surface coordinates are filled once.
                let rest = &self.body.lattice().rest_positions()[first..first + n];
                slot.uv.clear();
                slot.uv.extend(rest.iter().map(|&r| {
                    let (u, v) = self.surface_fractions(r);
                    [u, v]
                }));
                for cap in &layer.caps {
                    let m = cap.ring.len().max(1) as f32;
                    let sum = cap.ring.iter().fold([0.0f32; 2], |acc, &e| {
                        let uv = slot.uv[(e - layer.first) as usize];
                        [acc[0] + uv[0], acc[1] + uv[1]]
                    });
                    slot.uv.push([sum[0] / m, sum[1] / m]);
                }
            }
        }
    }

    /// Refills `out` with the intact connective fibres as world-space segments (the lower layer's end
    /// first), `stretch` with each one's world stretch, `sites` with where each stands at rest, and
    /// `broken` with the fibres cut or torn. The direct path, reading the tissue itself: the reference
    /// that a frame filled raw ([`Tissue::fill_fibres_raw`]) and finished by its reader is compared with.
    pub fn fill_fibres(
        &self,
        out: &mut Vec<[[f32; 3]; 2]>,
        stretch: &mut Vec<f32>,
        sites: &mut Vec<[f32; 4]>,
        broken: &mut Vec<BrokenFibre>,
    ) {
        out.clear();
        stretch.clear();
        sites.clear();
        broken.clear();
        for &(id, site) in &self.fibre_sites {
            let Some([a, b]) = self.body.lattice().link_ends(id) else { continue };
            let (a, b) = if self.layer_of(a) < self.layer_of(b) { (b, a) } else { (a, b) };
            let (Some(pa), Some(pb)) = (self.world_position(a), self.world_position(b)) else { continue };
            match self.body.link_broken(id) {
                None => {
                    out.push([pa, pb]);
                    let d =
                        ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2) + (pb[2] - pa[2]).powi(2)).sqrt();
                    stretch.push(d / self.rest_len[id.index()].max(f32::MIN_POSITIVE));
                    sites.push(site);
                }
                Some(reason) => {
                    broken.push(BrokenFibre { ends: [pa, pb], cut: reason == BreakReason::Cut, site })
                }
            }
        }
    }

    /// What a snapshot filled raw carries of the fibres ([`crate::simulation::World::snapshot_raw_into`]):
    /// `state` gets each fibre's state, 0 intact, 1 cut and 2 torn, in the recipe's order, and
    /// nothing else. Their ends are elements the layers' meshes carry, so the reader draws them from
    /// those ([`MeshRecipe::finish_snapshot`]). (Reading each fibre's link in link order takes 27 µs for
    /// 25 000 fibres; looking up the links broken so far took longer once the target was cut.)
    pub fn fill_fibres_raw(&self, state: &mut Vec<f32>) {
        state.clear();
        state.extend(self.mesh_recipe.fibres.iter().map(|f| match self.body.link_broken(f.link) {
            None => FIBRE_INTACT,
            Some(BreakReason::Cut) => FIBRE_CUT,
            Some(BreakReason::Tear) => FIBRE_TORN,
        }));
    }

    /// The connective fibres in link order with where each stands at rest: its lower layer's element's
    /// rest position along the surface's `u` and `v` (metres from the surface's first corner) and the
    /// spacing of the fibres' sites along each: that element's spacing to its nearest neighbours of the
    /// same layer (metres; the surface's span where it has none) times the fibres' stride.
    pub(crate) fn rest_fibre_sites(&self) -> Vec<(LinkId, [f32; 4])> {
        let lattice = self.body.lattice();
        let rest = lattice.rest_positions();
        let k = match self.geometry {
            Geometry::Surface(_) => 1,
            Geometry::Volume => 2,
        };
        let (lo, span) = (self.extent_lo, self.extent_span);
        let mut out = Vec::new();
        for (l, kind) in self.link_kind.iter().enumerate() {
            let id = LinkId(l as u32);
            if *kind != LinkKind::Connective {
                continue;
            }
            let Some([a, b]) = lattice.link_ends(id) else { continue };
            let a = if self.layer_of(a) < self.layer_of(b) { b } else { a };
            let layer = self.layer_of(a);
            let Some(r) = rest.get(a.index()) else { continue };
            let mut gap = [span[0].abs(), span[k].abs()];
            for (nb, _) in lattice.neighbours(a) {
                if self.layer_of(nb) != layer {
                    continue;
                }
                let Some(q) = rest.get(nb.index()) else { continue };
                for (g, axis) in gap.iter_mut().zip([0, k]) {
                    let d = (q[axis] - r[axis]).abs();
                    if d > 1e-9 {
                        *g = g.min(d);
                    }
                }
            }
            // A site stands for `stride` elements along each axis (`ConnectiveSpec::stride`).
            let [su, sv] = self.fibre_stride.map(|s| s as f32);
            out.push((id, [r[0] - lo[0], r[k] - lo[k], gap[0] * su, gap[1] * sv]));
        }
        out
    }

    /// The stretch at which connective fibres tear (the largest tear ratio of their materials), `0`
    /// when they never tear or there are none.
    pub fn fibre_tear_stretch(&self) -> f32 {
        // Every connective link has a site (`rest_fibre_sites`), and fibres share a few materials: each
        // run of one material is looked up once.
        let (mut ratio, mut last) = (0.0f32, None);
        for &(l, _) in &self.fibre_sites {
            let m = self.body.link_material(l);
            if m == last {
                continue;
            }
            last = m;
            if let Some(r) = m.and_then(|m| self.body.material(m)).and_then(|m| m.tear_ratio) {
                ratio = ratio.max(r);
            }
        }
        ratio
    }

    /// Connected components of the graph of intact links within one layer (0 is the upper), for tests
    /// and reports: a cut straight across a sheet leaves two.
    pub fn layer_components(&self, layer: usize) -> usize {
        let Some(l) = self.layers.get(layer) else { return 0 };
        let (first, n) = (l.first as usize, l.count as usize);
        let mut seen = vec![false; n];
        let mut stack = Vec::new();
        let mut components = 0;
        for start in 0..n {
            if seen[start] {
                continue;
            }
            components += 1;
            seen[start] = true;
            stack.push(start);
            while let Some(i) = stack.pop() {
                for (nb, link) in
                    self.body.lattice().neighbours(crate::chainmail::ElementId((first + i) as u32))
                {
                    let j = nb.index();
                    if j < first || j >= first + n || !self.body.link_intact(link) || seen[j - first] {
                        continue;
                    }
                    seen[j - first] = true;
                    stack.push(j - first);
                }
            }
        }
        components
    }
}

fn normalize_all(normals: &mut [[f32; 3]]) {
    for m in normals {
        let l = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
        *m = if l > 0.0 { [m[0] / l, m[1] / l, m[2] / l] } else { [0.0, 1.0, 0.0] };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chainmail::{BreakReason, LinkId};
    use crate::tissue::scan::tests::tissue;

    /// A fibre cut leaves both layers' triangles and their versions as they were (so neither the
    /// published frame nor the renderer rebuilds them); a layer's cut gives that layer alone a new
    /// version, and a mesh refilled in place then has the triangles a fresh fill has.
    #[test]
    fn only_a_cut_through_a_layer_changes_its_triangles_version() {
        let mut t = tissue();
        let mut kept = Vec::new();
        t.fill_meshes_raw(&mut kept);
        let before: Vec<u64> = kept.iter().map(|m| m.topology_version).collect();
        assert!(before[0] != before[1]);
        let first = |t: &Tissue, kind: LinkKind| {
            (0..t.body().link_count() as u32)
                .map(LinkId)
                .find(|&l| t.link_kind(l) == Some(kind))
                .expect("a link")
        };
        let fibre = first(&t, LinkKind::Connective);
        assert!(t.break_link(fibre, BreakReason::Cut));
        t.fill_meshes_raw(&mut kept);
        assert_eq!(kept.iter().map(|m| m.topology_version).collect::<Vec<_>>(), before);
        for (k, layer) in [(1usize, LinkKind::Layer(1)), (0, LinkKind::Layer(0))] {
            let old: Vec<u64> = kept.iter().map(|m| m.topology_version).collect();
            let drawn = kept[k].triangles.len();
            let l = first(&t, layer);
            assert!(t.break_link(l, BreakReason::Tear));
            t.fill_meshes_raw(&mut kept);
            for (j, m) in kept.iter().enumerate() {
                assert_eq!(m.topology_version != old[j], j == k, "layer {j} after a tear in layer {k}");
            }
            let mut fresh = Vec::new();
            t.fill_meshes_raw(&mut fresh);
            assert_eq!(kept, fresh);
            assert!(kept[k].triangles.len() < drawn, "layer {k}: the torn link's triangles go");
        }
    }
}
