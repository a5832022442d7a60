//! What the renderer derives from a snapshot on the CPU before upload, in plain arrays (no GPU types):
//! the open edges of each layer (where a cut or the sheet's border is), the walls that give a cut edge
//! the layer's thickness, the line instances for fibres (with their stretch), the stubs of broken
//! fibres and the marks where fibres were cut, and lines drawn on a surface (the planned incision):
//! clipped to the layer's triangles in surface coordinates when the topology changes
//! ([`surface_pieces`]), placed on the deformed surface every frame ([`dashed_instances`]).

use glam::{Vec2, Vec3};

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

/// The part of a line on a surface that lies in one triangle of the layer: the triangle's vertices,
/// both ends as barycentric weights of them, and how far along the line the ends are (surface
/// fractions from its first point). Valid until the layer's topology changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePiece {
    /// The triangle's vertices.
    pub vertices: [u32; 3],
    /// The ends as barycentric weights of `vertices`.
    pub ends: [[f32; 3]; 2],
    /// Distance of each end along the line from its first point, surface fractions.
    pub along: [f32; 2],
}

/// Refills `out` with the pieces of the polyline `line` (all its points, `(u, v)` surface fractions)
/// over the layer's triangles, found by their surface coordinates: each segment clipped to each
/// triangle whose bounding box meets the segment's; a piece along an edge two triangles share is kept
/// once, by the triangle left of the line. A layer without surface coordinates has none.
/// Cost: triangles × segments box checks, run when the topology or the line changes, not per frame.
pub fn surface_pieces(layer: &LayerMesh, line: &[[f32; 2]], out: &mut Vec<SurfacePiece>) {
    out.clear();
    if layer.uv.len() != layer.positions.len() || line.len() < 2 {
        return;
    }
    // Each segment with its start along the line and its bounding box.
    let mut start = 0.0;
    let segments: Vec<(Vec2, Vec2, f32, Vec2, Vec2)> = line
        .windows(2)
        .map(|w| {
            let (p, q) = (Vec2::from(w[0]), Vec2::from(w[1]));
            let s = (p, q, start, p.min(q), p.max(q));
            start += p.distance(q);
            s
        })
        .collect();
    let (lo, hi) =
        segments.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), s| (lo.min(s.3), hi.max(s.4)));
    for t in &layer.triangles {
        let Some(uv) =
            t.iter().map(|&v| layer.uv.get(v as usize).map(|&c| Vec2::from(c))).collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let (a, b, c) = (uv[0], uv[1], uv[2]);
        let (t_lo, t_hi) = (a.min(b).min(c), a.max(b).max(c));
        if t_hi.cmplt(lo).any() || t_lo.cmpgt(hi).any() {
            continue;
        }
        let area = (b - a).perp_dot(c - a);
        if area.abs() < 1e-12 {
            continue;
        }
        // Barycentric weights of a point, affine in it.
        let weights = |p: Vec2| {
            let wb = (p - a).perp_dot(c - a) / area;
            let wc = (b - a).perp_dot(p - a) / area;
            Vec3::new(1.0 - wb - wc, wb, wc)
        };
        for &(p, q, along, s_lo, s_hi) in &segments {
            if t_hi.cmplt(s_lo).any() || t_lo.cmpgt(s_hi).any() {
                continue;
            }
            // The weights along the segment are wp + t (wq − wp); inside where all three are ≥ 0.
            let (wp, wq) = (weights(p), weights(q));
            let (mut from, mut to) = (0.0_f32, 1.0_f32);
            for k in 0..3 {
                let (x, y) = (wp[k], wq[k]);
                if x < 0.0 && y < 0.0 {
                    (from, to) = (1.0, 0.0);
                } else if x < 0.0 {
                    from = from.max(x / (x - y));
                } else if y < 0.0 {
                    to = to.min(x / (x - y));
                }
            }
            if to - from <= 1e-6 {
                continue;
            }
            // A piece along an edge (one weight zero at both ends) is in both triangles that share
            // the edge: the triangle to the left of the line keeps it.
            let (ea, eb) = (wp.lerp(wq, from), wp.lerp(wq, to));
            let on_edge = (0..3).any(|k| ea[k].abs() < 1e-5 && eb[k].abs() < 1e-5);
            if on_edge && (q - p).perp_dot((a + b + c) / 3.0 - p) < 0.0 {
                continue;
            }
            let len = p.distance(q);
            out.push(SurfacePiece {
                vertices: *t,
                ends: [ea.to_array(), eb.to_array()],
                along: [along + from * len, along + to * len],
            });
        }
    }
}

/// Refills `out` with dashes along `pieces` on the layer's current positions: on for the last `duty`
/// share of every `period` along the line (surface fractions, so the dashes stretch with the tissue),
/// lifted `lift` metres along the surface normal so they lie on the surface's side it points to.
pub fn dashed_instances(
    layer: &LayerMesh,
    pieces: &[SurfacePiece],
    period: f32,
    duty: f32,
    lift: f32,
    out: &mut Vec<LineInstance>,
) {
    out.clear();
    if period <= 0.0 {
        return;
    }
    let at = |v: u32| Vec3::from(layer.positions.get(v as usize).copied().unwrap_or_default());
    let normal = |v: u32| Vec3::from(layer.normals.get(v as usize).copied().unwrap_or_default());
    let gap = (1.0 - duty.clamp(0.0, 1.0)) * period;
    for piece in pieces {
        let [t0, t1] = piece.along;
        if t1 - t0 <= 0.0 {
            continue;
        }
        let [a, b, c] = piece.vertices;
        let (pa, pb, pc) = (at(a), at(b), at(c));
        let n = (normal(a) + normal(b) + normal(c)).normalize_or(Vec3::ZERO);
        let point = |t: f32| {
            let f = (t - t0) / (t1 - t0);
            let w = Vec3::from(piece.ends[0]).lerp(Vec3::from(piece.ends[1]), f);
            pa * w.x + pb * w.y + pc * w.z + n * lift
        };
        let mut k = (t0 / period).floor();
        while k * period < t1 {
            let (on, off) = ((k * period + gap).max(t0), ((k + 1.0) * period).min(t1));
            if off > on {
                let (p, q) = (point(on), point(off));
                out.push([p.x, p.y, p.z, q.x, q.y, q.z, 1.0]);
            }
            k += 1.0;
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

    /// A finer grid for lines: `n` × `n` vertices over uv 0..1, positions (u, 0, v) metres.
    fn fine_grid(n: u32) -> LayerMesh {
        let mut m = LayerMesh::default();
        for j in 0..n {
            for i in 0..n {
                let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
                m.positions.push([u, 0.0, v]);
                m.normals.push([0.0, 1.0, 0.0]);
                m.uv.push([u, v]);
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                m.triangles.push([a, a + n, a + 1]);
                m.triangles.push([a + 1, a + n, a + n + 1]);
            }
        }
        m
    }

    #[test]
    fn every_point_of_a_surface_line_is_covered() {
        let m = fine_grid(9);
        // Nine points, eight segments: each segment's length must be covered by its pieces, the last
        // ones too (the shader once drew only the first six points).
        let line: Vec<[f32; 2]> =
            (0..9).map(|k| [0.1 + 0.1 * k as f32, if k % 2 == 0 { 0.2 } else { 0.7 }]).collect();
        let mut pieces = Vec::new();
        surface_pieces(&m, &line, &mut pieces);
        let mut start = 0.0;
        for w in line.windows(2) {
            let len = Vec2::from(w[0]).distance(Vec2::from(w[1]));
            let covered: f32 =
                pieces.iter().map(|p| (p.along[1].min(start + len) - p.along[0].max(start)).max(0.0)).sum();
            assert!((covered - len).abs() < 1e-4, "segment from {:?}: {covered} of {len} covered", w[0]);
            start += len;
        }
        // Each piece's ends lie on the line where it says (uv of the weights = the line's point).
        for p in &pieces {
            let uv = |w: [f32; 3]| {
                p.vertices
                    .iter()
                    .zip(w)
                    .fold(Vec2::ZERO, |acc, (&v, x)| acc + Vec2::from(m.uv[v as usize]) * x)
            };
            assert!(p.ends.iter().flatten().all(|&x| x > -1e-5), "weights outside the triangle: {p:?}");
            for (end, along) in [(p.ends[0], p.along[0]), (p.ends[1], p.along[1])] {
                let (mut rest, mut at) = (along, Vec2::from(line[0]));
                for w in line.windows(2) {
                    let (a, b) = (Vec2::from(w[0]), Vec2::from(w[1]));
                    let len = a.distance(b);
                    if rest <= len + 1e-6 {
                        at = a + (b - a) * (rest / len);
                        break;
                    }
                    rest -= len;
                }
                assert!(uv(end).distance(at) < 1e-4, "end {:?} is not at {at:?}", uv(end));
            }
        }
        // Cutting triangles away removes the pieces in them; no surface coordinates, no pieces.
        let mut cut = m.clone();
        cut.triangles.retain(|t| t.iter().all(|&v| m.uv[v as usize][1] < 0.5));
        surface_pieces(&cut, &line, &mut pieces);
        assert!(!pieces.is_empty() && pieces.iter().all(|p| p.along.iter().all(|&t| t.is_finite())));
        let mut bare = m.clone();
        bare.uv.clear();
        surface_pieces(&bare, &line, &mut pieces);
        assert!(pieces.is_empty());
    }

    #[test]
    fn dashes_follow_the_deformed_surface_and_their_period() {
        let mut m = fine_grid(9);
        // Along a row of triangle edges: each piece is drawn once, not by both triangles.
        let line = [[0.1, 0.5], [0.9, 0.5]];
        let mut pieces = Vec::new();
        surface_pieces(&m, &line, &mut pieces);
        // Lift the sheet: the dashes go with it, 1 mm above along the normal.
        for p in &mut m.positions {
            p[1] = 0.25;
        }
        let mut dashes = Vec::new();
        dashed_instances(&m, &pieces, 0.1, 0.55, 0.001, &mut dashes);
        assert!(dashes.iter().all(|d| (d[1] - 0.251).abs() < 1e-6 && (d[4] - 0.251).abs() < 1e-6));
        // 0.8 long with a period of 0.1: eight dashes of 0.055 (split where they cross triangles).
        let drawn: f32 =
            dashes.iter().map(|d| Vec3::new(d[3] - d[0], d[4] - d[1], d[5] - d[2]).length()).sum();
        assert!((drawn - 8.0 * 0.055).abs() < 1e-4, "{drawn}");
        assert!(dashes.iter().all(|d| (d[2] - 0.5).abs() < 1e-6));
    }
}
