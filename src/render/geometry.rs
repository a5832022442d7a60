//! What the renderer derives from a snapshot on the CPU before upload, in plain arrays (no GPU types):
//! the open edges of each layer (where a cut or the sheet's border is), the walls that give a cut edge
//! the layer's thickness, and the line instances for fibres (with their stretch), the stubs of broken
//! fibres and the marks where fibres were cut.

use glam::Vec3;

use crate::snapshot::{BrokenFibre, LayerMesh};

/// One line instance as the line shader reads it: two end points and a stretch.
pub type LineInstance = [f32; 7];

/// A stub of a broken fibre is this share of the fibre's length, at most [`STUB_MAX_M`].
pub const STUB_SHARE: f32 = 0.3;
/// Longest stub drawn, metres.
pub const STUB_MAX_M: f32 = 0.0012;

/// The open edges of a layer's triangles: `[a, b, c]` where the edge `a`–`b` belongs to one triangle
/// only and `c` is that triangle's third vertex (so the wall can face away from it). Edges along the
/// sheet's original border (both ends on the same side of the surface's `u`–`v` square) are left
/// out: only cuts and tears open edges worth drawing. Refills `out`; `scratch` is reused.
pub fn open_edges(layer: &LayerMesh, scratch: &mut Vec<(u64, u32)>, out: &mut Vec<[u32; 3]>) {
    scratch.clear();
    out.clear();
    for t in &layer.triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            scratch.push((key, c));
        }
    }
    scratch.sort_unstable_by_key(|e| e.0);
    let on_border = |a: u32, b: u32| {
        let (Some(p), Some(q)) = (layer.uv.get(a as usize), layer.uv.get(b as usize)) else { return false };
        let edge = |x: f32| !(1e-4..=1.0 - 1e-4).contains(&x);
        (edge(p[0]) && edge(q[0]) && (p[0] - q[0]).abs() < 1e-4)
            || (edge(p[1]) && edge(q[1]) && (p[1] - q[1]).abs() < 1e-4)
    };
    let mut i = 0;
    while i < scratch.len() {
        let mut j = i + 1;
        while j < scratch.len() && scratch[j].0 == scratch[i].0 {
            j += 1;
        }
        if j - i == 1 {
            let (key, c) = scratch[i];
            let (a, b) = ((key >> 32) as u32, key as u32);
            if !on_border(a, b) {
                out.push([a, b, c]);
            }
        }
        i = j;
    }
}

/// Appends the walls along `edges` (from [`open_edges`]): a quad per edge from the surface down to
/// `depth` metres along each vertex's normal (negative: against it), two triangles, six vertices,
/// each with the wall's outward normal.
pub fn edge_walls(
    layer: &LayerMesh,
    edges: &[[u32; 3]],
    depth: f32,
    positions: &mut Vec<[f32; 3]>,
    normals: &mut Vec<[f32; 3]>,
) {
    positions.clear();
    normals.clear();
    let at = |v: u32| Vec3::from(layer.positions.get(v as usize).copied().unwrap_or_default());
    let normal = |v: u32| Vec3::from(layer.normals.get(v as usize).copied().unwrap_or([0.0, 1.0, 0.0]));
    for &[a, b, c] in edges {
        let (pa, pb, pc) = (at(a), at(b), at(c));
        let (na, nb) = (normal(a), normal(b));
        let n = (na + nb).normalize_or(Vec3::Y);
        let mut w = (pb - pa).cross(n).normalize_or(Vec3::ZERO);
        if w.dot(pc - pa) > 0.0 {
            w = -w;
        }
        let (qa, qb) = (pa + depth * na, pb + depth * nb);
        for p in [pa, pb, qb, pa, qb, qa] {
            positions.push(p.to_array());
            normals.push(w.to_array());
        }
    }
}

/// Refills `out` with the intact fibres and their stretch (1 where `stretch` is short).
pub fn fibre_instances(fibres: &[[[f32; 3]; 2]], stretch: &[f32], out: &mut Vec<LineInstance>) {
    out.clear();
    out.extend(fibres.iter().enumerate().map(|(i, [a, b])| {
        let s = stretch.get(i).copied().unwrap_or(1.0);
        [a[0], a[1], a[2], b[0], b[1], b[2], s]
    }));
}

/// Refills `stubs` with two short recoiled ends per broken fibre (a torn one drawn at `torn_stretch`,
/// whitened, a cut one relaxed) and `marks` with a dot at the lower stub's tip of every cut fibre.
pub fn broken_instances(
    broken: &[BrokenFibre],
    torn_stretch: f32,
    stubs: &mut Vec<LineInstance>,
    marks: &mut Vec<LineInstance>,
) {
    stubs.clear();
    marks.clear();
    for f in broken {
        let (lo, hi) = (Vec3::from(f.ends[0]), Vec3::from(f.ends[1]));
        let d = hi - lo;
        let len = d.length();
        let stub = (len * STUB_SHARE).min(STUB_MAX_M);
        let dir = d.normalize_or(Vec3::Y);
        let s = if f.cut { 1.0 } else { torn_stretch.max(1.0) };
        let (lo_tip, hi_tip) = (lo + dir * stub, hi - dir * stub);
        for (from, to) in [(lo, lo_tip), (hi, hi_tip)] {
            stubs.push([from.x, from.y, from.z, to.x, to.y, to.z, s]);
        }
        if f.cut {
            marks.push([lo_tip.x, lo_tip.y, lo_tip.z, lo_tip.x, lo_tip.y, lo_tip.z, 1.0]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 3 vertex grid (2 × 2 quads) in the XZ plane with uv from 0 to 1.
    fn grid() -> LayerMesh {
        let mut m = LayerMesh::default();
        for j in 0..3 {
            for i in 0..3 {
                m.positions.push([i as f32, 0.0, j as f32]);
                m.normals.push([0.0, 1.0, 0.0]);
                m.uv.push([i as f32 / 2.0, j as f32 / 2.0]);
            }
        }
        for j in 0..2u32 {
            for i in 0..2u32 {
                let a = j * 3 + i;
                m.triangles.push([a, a + 3, a + 1]);
                m.triangles.push([a + 1, a + 3, a + 4]);
            }
        }
        m
    }

    #[test]
    fn an_intact_sheet_has_no_open_edges_and_a_hole_has_them() {
        let mut m = grid();
        let (mut scratch, mut edges) = (Vec::new(), Vec::new());
        open_edges(&m, &mut scratch, &mut edges);
        assert!(edges.is_empty(), "border edges are not cut edges: {edges:?}");
        // Remove the two triangles of the first quad: its two inner edges open.
        m.triangles.drain(0..2);
        open_edges(&m, &mut scratch, &mut edges);
        let mut keys: Vec<(u32, u32)> = edges.iter().map(|e| (e[0], e[1])).collect();
        keys.sort();
        assert_eq!(keys, vec![(1, 4), (3, 4)]);
    }

    #[test]
    fn walls_face_away_from_their_triangle_and_go_down_the_normal() {
        let mut m = grid();
        m.triangles.drain(0..2);
        let (mut scratch, mut edges) = (Vec::new(), Vec::new());
        open_edges(&m, &mut scratch, &mut edges);
        let (mut p, mut n) = (Vec::new(), Vec::new());
        edge_walls(&m, &edges, -0.5, &mut p, &mut n);
        assert_eq!(p.len(), 6 * edges.len());
        for (k, e) in edges.iter().enumerate() {
            let c = Vec3::from(m.positions[e[2] as usize]);
            let a = Vec3::from(m.positions[e[0] as usize]);
            assert!(Vec3::from(n[6 * k]).dot(c - a) < 0.0, "wall {k} faces its own triangle");
        }
        assert!(p.iter().any(|q| q[1] == -0.5) && p.iter().all(|q| q[1] <= 0.0));
    }

    #[test]
    fn broken_fibres_leave_short_stubs_and_cut_ones_a_mark() {
        let broken = [
            BrokenFibre { ends: [[0.0, 0.0, 0.0], [0.0, 0.004, 0.0]], cut: true },
            BrokenFibre { ends: [[1.0, 0.0, 0.0], [1.0, 0.001, 0.0]], cut: false },
        ];
        let (mut stubs, mut marks) = (Vec::new(), Vec::new());
        broken_instances(&broken, 4.0, &mut stubs, &mut marks);
        assert_eq!((stubs.len(), marks.len()), (4, 1));
        let len = |s: &LineInstance| Vec3::new(s[3] - s[0], s[4] - s[1], s[5] - s[2]).length();
        assert!((len(&stubs[0]) - STUB_MAX_M).abs() < 1e-6);
        assert!((len(&stubs[2]) - 0.0003).abs() < 1e-6);
        assert_eq!((stubs[0][6], stubs[2][6]), (1.0, 4.0));
        assert!((marks[0][1] - STUB_MAX_M).abs() < 1e-6);
    }
}
