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

/// Spacing of the fibres drawn, metres along the surface at rest: a fibre is drawn where its element is
/// the one nearest a point of a square lattice of this pitch (one element per point along each axis),
/// so the picture shows the same density of fibres at every resolution. Just under the default
/// exercise's 64 × 48 spacing (1.27 mm along `u`, 1.28 mm along `v`), which draws every fibre there.
pub const FIBRE_PITCH_M: f32 = 0.00125;

/// How far an element's share is shifted along the axis for [`fibre_drawn`], a fraction of it.
const SHARE_SHIFT: f32 = 1e-3;

/// Whether the fibre standing at `site` (`[u, v, du, dv]`: rest position and element spacing along the
/// surface, metres; see [`crate::snapshot::BrokenFibre::site`]) is drawn at `pitch`: along each axis its
/// element's share `[x − d/2, x + d/2)` holds a point of the lattice `k · pitch`. An element coarser
/// than the pitch always holds one (every fibre is drawn); a finer one holds at most one, so exactly one
/// element per lattice point is drawn. A fibre with no site (`None`) is drawn.
pub fn fibre_drawn(site: Option<&[f32; 4]>, pitch: f32) -> bool {
    let Some(&[u, v, du, dv]) = site else { return true };
    let holds = |x: f32, d: f32| {
        if d.is_nan() || d >= pitch {
            return true;
        }
        // The lattice point at or after the share's start: inside when it is before the share's end.
        // The share is shifted by a thousandth of itself so that a point halfway between two elements
        // (their shares' common end, computed from each element's own position) falls in one only.
        let start = x - (0.5 - SHARE_SHIFT) * d;
        let point = (start / pitch).ceil() * pitch;
        point < start + d
    };
    holds(u, du) && holds(v, dv)
}

/// Refills `out` with the intact fibres drawn at `pitch` (see [`fibre_drawn`]) and their stretch (1
/// where `stretch` is short). `sites` holds each fibre's site in the order of `fibres`.
pub fn fibre_instances(
    fibres: &[[[f32; 3]; 2]],
    stretch: &[f32],
    sites: &[[f32; 4]],
    pitch: f32,
    out: &mut Vec<LineInstance>,
) {
    out.clear();
    out.extend(fibres.iter().enumerate().filter(|&(i, _)| fibre_drawn(sites.get(i), pitch)).map(
        |(i, [a, b])| {
            let s = stretch.get(i).copied().unwrap_or(1.0);
            [a[0], a[1], a[2], b[0], b[1], b[2], s]
        },
    ));
}

/// Refills `stubs` with two short recoiled ends per broken fibre drawn at `pitch` (see [`fibre_drawn`];
/// a torn one drawn at `torn_stretch`, whitened, a cut one relaxed) and `marks` with a dot at the lower
/// stub's tip of every such fibre that was cut.
pub fn broken_instances(
    broken: &[BrokenFibre],
    torn_stretch: f32,
    pitch: f32,
    stubs: &mut Vec<LineInstance>,
    marks: &mut Vec<LineInstance>,
) {
    stubs.clear();
    marks.clear();
    for f in broken.iter().filter(|f| fibre_drawn(Some(&f.site), pitch)) {
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

/// Spacing of the tissue's drawn mesh, metres along the surface at rest: a layer sampled finer than
/// this is drawn with cells of several grid quads (see [`drawn_triangles`]), so the triangles a frame
/// rasterises stay about what an 8 cm sheet of 64 × 48 elements has, whatever the resolution. The
/// vertices are the simulation's own; only where they are joined changes.
pub const SURFACE_PITCH_M: f32 = 0.00125;

/// How many grid quads along each axis one drawn cell spans for a layer of `grid` vertices over
/// `uv_size` metres at `pitch`: the pitch over the element spacing, rounded (at least 1: every quad).
pub fn cell_quads(grid: [u32; 2], uv_size: [f32; 2], pitch: f32) -> u32 {
    let steps = |n: u32, size: f32| {
        let spacing = size / n.saturating_sub(1).max(1) as f32;
        if spacing > 0.0 && spacing.is_finite() { (pitch / spacing + 0.5).floor().max(1.0) } else { 1.0 }
    };
    steps(grid[0], uv_size[0]).min(steps(grid[1], uv_size[1])).min(64.0) as u32
}

/// Refills `out` with the triangles to draw for `layer`, a grid of `grid` = `[nu, nv]` vertices in
/// rows along `u` (vertex `i + nu · j`; more vertices after them, such as a sphere's poles, and
/// triangles across a wrapped seam are drawn as given). Cells of `step` × `step` quads whose triangles
/// are all there (nothing cut or torn in them) are drawn as two triangles between the cell's corners,
/// or, where a side borders anything but another such cell (a cut, the sheet's border, a seam), as a
/// fan from a vertex inside the cell through every vertex of that side, so that the neighbour's
/// triangles meet it vertex for vertex (no cracks). Every other triangle is drawn as given. `step` 1,
/// or a layer that is not such a grid, draws the triangles as given. `counts` is scratch.
pub fn drawn_triangles(
    layer: &LayerMesh,
    grid: [u32; 2],
    step: u32,
    counts: &mut Vec<u8>,
    out: &mut Vec<[u32; 3]>,
) {
    out.clear();
    let [nu, nv] = grid;
    let grid_vertices = u64::from(nu) * u64::from(nv);
    if step <= 1 || nu < 2 || nv < 2 || grid_vertices > layer.positions.len() as u64 {
        out.extend_from_slice(&layer.triangles);
        return;
    }
    let (qu, qv) = ((nu - 1) as usize, (nv - 1) as usize);
    // The quad a triangle lies in, if it is one of the grid's (not across a seam or to a pole).
    let quad_of = |t: &[u32; 3]| -> Option<usize> {
        if t.iter().any(|&v| u64::from(v) >= grid_vertices) {
            return None;
        }
        let (i, j) = (t.map(|v| v % nu), t.map(|v| v / nu));
        let (i0, i1) = (i.iter().min()?, i.iter().max()?);
        let (j0, j1) = (j.iter().min()?, j.iter().max()?);
        (i1 - i0 <= 1 && j1 - j0 <= 1 && (*i0 as usize) < qu && (*j0 as usize) < qv)
            .then(|| *j0 as usize * qu + *i0 as usize)
    };
    counts.clear();
    counts.resize(qu * qv, 0);
    for t in &layer.triangles {
        if let Some(q) = quad_of(t) {
            counts[q] = counts[q].saturating_add(1);
        }
    }
    let s = step as usize;
    let (cu, cv) = (qu / s, qv / s);
    // Whether cell (a, b) is drawn coarse: every quad in it has both its triangles.
    let whole = |a: usize, b: usize| {
        (b * s..(b + 1) * s).all(|j| (a * s..(a + 1) * s).all(|i| counts[j * qu + i] == 2))
    };
    let mut coarse = vec![false; cu * cv];
    for b in 0..cv {
        for a in 0..cu {
            coarse[b * cu + a] = whole(a, b);
        }
    }
    let in_coarse = |q: usize| {
        let (i, j) = (q % qu / s, q / qu / s);
        i < cu && j < cv && coarse[j * cu + i]
    };
    out.extend(layer.triangles.iter().filter(|t| !quad_of(t).is_some_and(in_coarse)));
    let at = |i: usize, j: usize| (j * nu as usize + i) as u32;
    let mut ring: Vec<u32> = Vec::with_capacity(4 * s);
    for b in 0..cv {
        for a in 0..cu {
            if !coarse[b * cu + a] {
                continue;
            }
            let (i0, j0, i1, j1) = (a * s, b * s, (a + 1) * s, (b + 1) * s);
            let neighbour = |da: isize, db: isize| {
                let (x, y) = (a as isize + da, b as isize + db);
                x >= 0
                    && y >= 0
                    && (x as usize) < cu
                    && (y as usize) < cv
                    && coarse[y as usize * cu + x as usize]
            };
            // The sides in order round the cell, each from its first corner to the next one's.
            let sides = [
                (neighbour(0, -1), (i0, j0), (1isize, 0isize)),
                (neighbour(1, 0), (i1, j0), (0, 1)),
                (neighbour(0, 1), (i1, j1), (-1, 0)),
                (neighbour(-1, 0), (i0, j1), (0, -1)),
            ];
            if sides.iter().all(|side| side.0) {
                let (p, q, r, t) = (at(i0, j0), at(i1, j0), at(i1, j1), at(i0, j1));
                out.push([p, q, r]);
                out.push([p, r, t]);
                continue;
            }
            ring.clear();
            for &(shared, (i, j), (di, dj)) in &sides {
                let steps = if shared { 1 } else { s };
                let stride = if shared { s as isize } else { 1 };
                for k in 0..steps as isize {
                    let (x, y) = (i as isize + di * k * stride, j as isize + dj * k * stride);
                    ring.push(at(x as usize, y as usize));
                }
            }
            let centre = at(i0 + s / 2, j0 + s / 2);
            for k in 0..ring.len() {
                out.push([centre, ring[k], ring[(k + 1) % ring.len()]]);
            }
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
        let site = [0.0, 0.0, 0.002, 0.002];
        let broken = [
            BrokenFibre { ends: [[0.0, 0.0, 0.0], [0.0, 0.004, 0.0]], cut: true, site },
            BrokenFibre { ends: [[1.0, 0.0, 0.0], [1.0, 0.001, 0.0]], cut: false, site },
        ];
        let (mut stubs, mut marks) = (Vec::new(), Vec::new());
        broken_instances(&broken, 4.0, FIBRE_PITCH_M, &mut stubs, &mut marks);
        assert_eq!((stubs.len(), marks.len()), (4, 1));
        let len = |s: &LineInstance| Vec3::new(s[3] - s[0], s[4] - s[1], s[5] - s[2]).length();
        assert!((len(&stubs[0]) - STUB_MAX_M).abs() < 1e-6);
        assert!((len(&stubs[2]) - 0.0003).abs() < 1e-6);
        assert_eq!((stubs[0][6], stubs[2][6]), (1.0, 4.0));
        assert!((marks[0][1] - STUB_MAX_M).abs() < 1e-6);
    }

    /// The fibres of an `n` × `m` sheet of `w` × `d` metres, every element with one: their sites.
    fn sites(n: u32, m: u32, w: f32, d: f32) -> Vec<[f32; 4]> {
        let (du, dv) = (w / (n - 1) as f32, d / (m - 1) as f32);
        (0..m).flat_map(|j| (0..n).map(move |i| [i as f32 * du, j as f32 * dv, du, dv])).collect()
    }

    #[test]
    fn fibres_are_drawn_at_a_physical_density_whatever_the_resolution() {
        let drawn = |sites: &[[f32; 4]]| sites.iter().filter(|s| fibre_drawn(Some(s), FIBRE_PITCH_M)).count();
        // The default exercise's sheet, 8 cm by 6 cm: at 64 × 48 every element is coarser than the
        // pitch, so every fibre is drawn, as before.
        let coarse = sites(64, 48, 0.08, 0.06);
        assert_eq!(drawn(&coarse), coarse.len());
        // Finer: one element per lattice point along each axis, 65 × 49 of them (points from 0 to
        // 80 mm and 60 mm every 1.25 mm), whether the sheet has 128 × 96, 256 × 192 or 200 × 150.
        for (n, m) in [(128, 96), (256, 192), (200, 150), (129, 97)] {
            assert_eq!(drawn(&sites(n, m, 0.08, 0.06)), 65 * 49, "{n} x {m}");
        }
        // Drawn fibres are spread evenly: every 1.25 mm square of the sheet holds one at 256 x 192.
        let fine = sites(256, 192, 0.08, 0.06);
        let mut cells = vec![0u32; 65 * 49];
        for s in fine.iter().filter(|s| fibre_drawn(Some(s), FIBRE_PITCH_M)) {
            let (i, j) = ((s[0] / FIBRE_PITCH_M).round() as usize, (s[1] / FIBRE_PITCH_M).round() as usize);
            cells[j * 65 + i] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{:?}", cells.iter().filter(|&&c| c != 1).count());
        // A fibre without a site (a snapshot that gives none) is drawn; the same rule for broken ones.
        assert!(fibre_drawn(None, FIBRE_PITCH_M));
        let broken: Vec<BrokenFibre> = sites(128, 96, 0.08, 0.06)
            .into_iter()
            .map(|site| BrokenFibre { ends: [[0.0; 3], [0.0, 0.002, 0.0]], cut: true, site })
            .collect();
        let (mut stubs, mut marks) = (Vec::new(), Vec::new());
        broken_instances(&broken, 4.0, FIBRE_PITCH_M, &mut stubs, &mut marks);
        assert_eq!((stubs.len(), marks.len()), (2 * 65 * 49, 65 * 49));
        let (fibres, stretch) = (vec![[[0.0; 3], [0.0, 0.002, 0.0]]; 128 * 96], vec![1.0; 128 * 96]);
        let mut out = Vec::new();
        fibre_instances(&fibres, &stretch, &sites(128, 96, 0.08, 0.06), FIBRE_PITCH_M, &mut out);
        assert_eq!(out.len(), 65 * 49);
    }

    /// Edges used by one triangle only (sorted vertex pairs), and the triangles' total area in uv.
    fn outline(m: &LayerMesh, triangles: &[[u32; 3]]) -> (Vec<(u32, u32)>, f32) {
        let mut edges = std::collections::BTreeMap::new();
        let mut area = 0.0;
        for t in triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
            let [p, q, r] = t.map(|v| Vec2::from(m.uv[v as usize]));
            area += 0.5 * (q - p).perp_dot(r - p).abs();
        }
        (edges.into_iter().filter(|&(_, n)| n == 1).map(|(e, _)| e).collect(), area)
    }

    #[test]
    fn a_fine_grid_is_drawn_in_cells_without_cracks() {
        let n = 13;
        let mut m = fine_grid(n);
        m.uv_size = [0.0075, 0.0075];
        // 0.625 mm between vertices: cells of two quads at the 1.25 mm pitch; four at 2.5 mm.
        assert_eq!(cell_quads([n, n], m.uv_size, SURFACE_PITCH_M), 2);
        assert_eq!(cell_quads([n, n], m.uv_size, 2.0 * SURFACE_PITCH_M), 4);
        assert_eq!(cell_quads([64, 48], [0.08, 0.06], SURFACE_PITCH_M), 1);
        assert_eq!(cell_quads([128, 96], [0.08, 0.06], SURFACE_PITCH_M), 2);
        let (mut counts, mut drawn) = (Vec::new(), Vec::new());
        // Whole: the same outline and area as every quad drawn, in far fewer triangles (the cells at the
        // border are fans through every border vertex, so the outline is the grid's own).
        for step in [2, 3, 4] {
            drawn_triangles(&m, [n, n], step, &mut counts, &mut drawn);
            let ((edges, area), (want_edges, want_area)) = (outline(&m, &drawn), outline(&m, &m.triangles));
            assert_eq!(edges, want_edges, "step {step}");
            assert!((area - want_area).abs() < 1e-5, "step {step}: {area} against {want_area}");
            assert!(drawn.len() < m.triangles.len() / 2, "step {step}: {} triangles", drawn.len());
        }
        // Cut: quads' triangles removed here and there (one of a quad's two, a whole row of quads); the
        // cells holding them are drawn quad by quad and the cells beside them stitched to them: the
        // drawn outline is exactly the cut mesh's (each cut edge drawn once, no T-junction), the area
        // the same, for any step.
        let mut cut = m.clone();
        let row = 5 * (n - 1) as usize * 2;
        cut.triangles.drain(row + 6..row + 14);
        cut.triangles.remove(40);
        cut.triangles.remove(3);
        for step in [1, 2, 3, 4] {
            drawn_triangles(&cut, [n, n], step, &mut counts, &mut drawn);
            let (edges, area) = outline(&cut, &drawn);
            let (want_edges, want_area) = outline(&cut, &cut.triangles);
            assert_eq!(edges, want_edges, "step {step}");
            assert!((area - want_area).abs() < 1e-5, "step {step}: {area} against {want_area}");
        }
        // Not a grid of that size (or step 1): the triangles as given.
        drawn_triangles(&m, [n + 1, n], 2, &mut counts, &mut drawn);
        assert_eq!(drawn, m.triangles);
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
