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
}

impl MeshRecipe {
    pub(crate) fn new(geometry: Geometry, layers: &[super::Layer]) -> Self {
        let caps = layers
            .iter()
            .map(|layer| {
                layer.caps.iter().map(|cap| cap.ring.iter().map(|&e| e - layer.first).collect()).collect()
            })
            .collect();
        Self { geometry, caps }
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
            if slot.topology_version != self.topology_version || slot.triangles.is_empty() {
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
                slot.topology_version = self.topology_version;
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
    /// `broken` with the fibres cut or torn.
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
        let mut ratio = 0.0f32;
        for (l, kind) in self.link_kind.iter().enumerate() {
            if *kind != LinkKind::Connective {
                continue;
            }
            let m = self.body.link_material(LinkId(l as u32)).and_then(|m| self.body.material(m));
            if let Some(r) = m.and_then(|m| m.tear_ratio) {
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
