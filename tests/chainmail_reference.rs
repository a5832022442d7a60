//! The engine's fast paths against a plain reference: a straightforward chain reaction (Gibson's per-direction
//! candidate lists of `(candidate, link, sponsor)` entries, each checked against its sponsor through the link's box,
//! from one source or several; when a fixed element blocks, the move shortened by what the fixed elements would have
//! had to move, then bisected) and a straightforward Jacobi sweep, both written here with
//! the public API only. On random grids, wrapped grids and irregular link lists, with pins, holds, cuts
//! and two materials, the engine must give the same positions (compared with `==`), the same moved
//! elements in the same order, and the same sponsors.

mod common;

use dissect::chainmail::{
    Body, BreakReason, ElementId, GridSpec, Lattice, LinkId, LinkSpec, Material, Pass, RelaxBudget,
    RelaxRegion, SimdLevel, Workspace,
};
use proptest::prelude::*;

const OMEGA: f32 = 0.9;
/// 2^-60, added to and taken from every relaxed coordinate: relaxation rounds values under 2^-36 to
/// multiples of 2^-83, so that no coordinate is subnormal.
const FLUSH: f32 = 8.673617e-19;

fn mask(pass: Pass) -> [bool; 3] {
    match pass {
        Pass::All => [true; 3],
        Pass::Plane => [true, true, false],
        Pass::Normal => [false, false, true],
    }
}

fn clamp(p: [f32; 3], lo: [f32; 3], hi: [f32; 3], m: [bool; 3]) -> [f32; 3] {
    let mut q = p;
    for k in 0..3 {
        if m[k] {
            q[k] = p[k].max(lo[k]).min(hi[k]);
        }
    }
    q
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// How a reference chain reaction ended: the elements moved and their sponsors, or blocked with the
/// most any fixed element would have had to move, per coordinate (rolled back).
type Reaction = Result<(Vec<usize>, Vec<usize>), [f32; 3]>;

/// The reference chain reaction on `pos` from `seeds` (element, goal), each its own sponsor. A blocked
/// reaction runs to its end (fixed elements stay) and is rolled back.
fn reference_reaction(
    body: &Body,
    pos: &mut [[f32; 3]],
    seeds: &[(usize, [f32; 3])],
    m: [bool; 3],
) -> Reaction {
    let lat = body.lattice();
    let n = pos.len();
    let mut moved_flag = vec![false; n];
    let mut old = vec![[0.0f32; 3]; n];
    let (mut moved, mut sponsors) = (Vec::new(), Vec::new());
    // Gibson's candidate lists, one per direction (the index of the link in an element's adjacency).
    let width = (0..n).map(|i| lat.neighbours(ElementId(i as u32)).count()).max().unwrap_or(0);
    let mut lists: Vec<Vec<(usize, LinkId, usize)>> = vec![Vec::new(); width];
    let push = |lists: &mut Vec<Vec<(usize, LinkId, usize)>>, moved_flag: &[bool], s: usize| {
        for (t, (nb, l)) in lat.neighbours(ElementId(s as u32)).enumerate() {
            if !moved_flag[nb.index()] && body.link_intact(l) {
                lists[t].push((nb.index(), l, s));
            }
        }
    };
    for &(src, goal) in seeds {
        if moved_flag[src] {
            continue;
        }
        old[src] = pos[src];
        pos[src] = goal;
        moved_flag[src] = true;
        moved.push(src);
        sponsors.push(src);
    }
    // Every seed enters the lists before any candidate is checked (a seed's neighbour that is
    // another seed has moved already).
    for &src in &moved.clone() {
        push(&mut lists, &moved_flag, src);
    }
    let mut excess: Option<[f32; 3]> = None;
    let mut heads = vec![0usize; width];
    loop {
        let mut progressed = false;
        for t in 0..width {
            while heads[t] < lists[t].len() {
                progressed = true;
                let (c, l, s) = lists[t][heads[t]];
                heads[t] += 1;
                if moved_flag[c] {
                    continue;
                }
                let [lo, hi] = body.link_limits(l).expect("limits");
                let ps = pos[s];
                let s_is_a = lat.link_ends(l).expect("ends")[0].index() == s;
                let (blo, bhi) = if s_is_a {
                    ([0, 1, 2].map(|k| ps[k] + lo[k]), [0, 1, 2].map(|k| ps[k] + hi[k]))
                } else {
                    ([0, 1, 2].map(|k| ps[k] - hi[k]), [0, 1, 2].map(|k| ps[k] - lo[k]))
                };
                let pc = pos[c];
                let q = clamp(pc, blo, bhi, m);
                if q == pc {
                    continue;
                }
                let e = ElementId(c as u32);
                if body.is_pinned(e) || body.is_held(e) {
                    let po = old[s];
                    let shift = [0, 1, 2].map(|k| po[k] - ps[k]);
                    let before = clamp(
                        pc,
                        [0, 1, 2].map(|k| blo[k] + shift[k]),
                        [0, 1, 2].map(|k| bhi[k] + shift[k]),
                        m,
                    );
                    let scale = (hi[0] - lo[0]).abs().max((hi[1] - lo[1]).abs()).max((hi[2] - lo[2]).abs())
                        + (lo[0].abs() + lo[1].abs() + lo[2].abs());
                    if dist(q, pc) > dist(before, pc) + 1e-5 * scale {
                        // How much further than before the fixed element would have to go.
                        let x = excess.get_or_insert([0.0; 3]);
                        for k in 0..3 {
                            x[k] = x[k].max(((q[k] - pc[k]).abs() - (before[k] - pc[k]).abs()).max(0.0));
                        }
                    }
                    continue;
                }
                old[c] = pc;
                pos[c] = q;
                moved_flag[c] = true;
                moved.push(c);
                sponsors.push(s);
                push(&mut lists, &moved_flag, c);
            }
        }
        if !progressed {
            break;
        }
    }
    if let Some(x) = excess {
        for &i in &moved {
            pos[i] = old[i];
        }
        return Err(x);
    }
    Ok((moved, sponsors))
}

/// The reference deformation of one element: returns `(fraction, moved, sponsors)`.
fn reference_deform(
    body: &Body,
    pos: &mut [[f32; 3]],
    src: usize,
    target: [f32; 3],
    pass: Pass,
) -> (f32, Vec<usize>, Vec<usize>) {
    reference_group(body, pos, &[(src, target)], pass)
}

/// The reference deformation of a group, each seed toward its target: the whole move if nothing
/// blocks; else the share at which the fixed elements would just stay (the move cut by the most a
/// fixed element would have had to go, over the largest move of a seed), tried up to three times,
/// nothing when it leaves no room, and bisection after that. Returns `(fraction, moved, sponsors)`.
fn reference_group(
    body: &Body,
    pos: &mut [[f32; 3]],
    seeds: &[(usize, [f32; 3])],
    pass: Pass,
) -> (f32, Vec<usize>, Vec<usize>) {
    let m = mask(pass);
    let mut free = Vec::new();
    let mut delta = [0.0f32; 3];
    for &(e, target) in seeds {
        let start = pos[e];
        let goal = [0, 1, 2].map(|k| if m[k] { target[k] } else { start[k] });
        if !body.is_pinned(ElementId(e as u32)) && goal != start {
            free.push((e, start, goal));
            for k in 0..3 {
                delta[k] = delta[k].max((goal[k] - start[k]).abs());
            }
        }
    }
    if free.is_empty() {
        return (0.0, vec![], vec![]);
    }
    let size = delta.iter().fold(0.0f32, |a, &d| a.max(d));
    let at = |t: f32| -> Vec<(usize, [f32; 3])> {
        free.iter()
            .map(|&(e, s, g)| (e, if t >= 1.0 { g } else { [0, 1, 2].map(|k| s[k] + t * (g[k] - s[k])) }))
            .collect()
    };
    let cut =
        |x: [f32; 3]| (0..3).filter(|&k| delta[k] > 0.0).map(|k| x[k] / delta[k]).fold(0.0f32, f32::max);
    let mut next = match reference_reaction(body, pos, &at(1.0), m) {
        Ok((mv, sp)) => return (1.0, mv, sp),
        Err(x) => 1.0 - cut(x),
    };
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..3 {
        if next >= hi {
            break;
        }
        if (next - lo) * size <= 1e-7 {
            return (0.0, vec![], vec![]);
        }
        match reference_reaction(body, pos, &at(next), m) {
            Ok((mv, sp)) => return (next, mv, sp),
            Err(x) => {
                hi = next;
                next = (next - cut(x)).min(hi);
            }
        }
    }
    for _ in 0..20 {
        if (hi - lo) * size <= 1e-7 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let mut trial = pos.to_vec();
        if reference_reaction(body, &mut trial, &at(mid), m).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if lo > 0.0
        && let Ok((mv, sp)) = reference_reaction(body, pos, &at(lo), m)
    {
        return (lo, mv, sp);
    }
    (0.0, vec![], vec![])
}

/// One reference Jacobi sweep over `elements` (all when `None`).
fn reference_sweep(body: &Body, pos: &mut [[f32; 3]], elements: Option<&[usize]>) {
    let lat = body.lattice();
    let rest = lat.rest_positions();
    let all: Vec<usize> = (0..pos.len()).collect();
    let list = elements.unwrap_or(&all);
    let mut next = pos.to_vec();
    for &i in list {
        let e = ElementId(i as u32);
        if body.is_pinned(e) || body.is_held(e) {
            continue;
        }
        let (mut acc, mut wsum) = ([0.0f32; 3], 0.0f32);
        let (mut lo, mut hi) = ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
        for (nb, l) in lat.neighbours(e) {
            if !body.link_intact(l) {
                continue;
            }
            let w = body.material(body.link_material(l).expect("mat")).expect("mat").stiffness;
            let j = nb.index();
            let (p, r) = (pos[j], rest[j]);
            let [blo, bhi] = body.link_limits(l).expect("limits");
            let i_is_b = lat.link_ends(l).expect("ends")[1].index() == i;
            for c in 0..3 {
                acc[c] += w * (p[c] - r[c]);
                let (a, b) =
                    if i_is_b { (p[c] + blo[c], p[c] + bhi[c]) } else { (p[c] - bhi[c], p[c] - blo[c]) };
                lo[c] = lo[c].max(a);
                hi[c] = hi[c].min(b);
            }
            wsum += w;
        }
        if wsum <= 0.0 {
            continue;
        }
        let (p, r) = (pos[i], rest[i]);
        let inv = OMEGA / wsum;
        for c in 0..3 {
            let target = p[c] + (acc[c] * inv - OMEGA * (p[c] - r[c]));
            let q = target.max(lo[c].min(p[c])).min(hi[c].max(p[c]));
            next[i][c] = (q + FLUSH) - FLUSH;
        }
    }
    pos.copy_from_slice(&next);
}

#[derive(Clone, Debug)]
struct Case {
    kind: u8,
    dims: [usize; 3],
    material: (f32, f32, f32),
    pins: Vec<u32>,
    holds: Vec<u32>,
    cuts: Vec<u32>,
    moves: Vec<(u32, [f32; 3], u8)>,
}

fn case() -> impl Strategy<Value = Case> {
    // Some grids wide enough for the chain reaction's runs to fill whole chunks (16 elements), and
    // some rigid materials, which carry a move across the whole grid.
    let side = || prop_oneof![3 => 2usize..8, 1 => 17usize..40];
    (0u8..4, side(), side(), prop_oneof![Just(1usize), 2usize..4])
        .prop_flat_map(|(kind, nx, ny, nz)| {
            let n = (nx * ny * nz) as u32;
            (
                Just(kind),
                Just([nx, ny, nz]),
                prop_oneof![3 => (1.0f32..1.6, 0.5f32..1.0, 0.0f32..0.5), 1 => Just((1.0, 1.0, 0.0))],
                proptest::collection::vec(0..n, 0..3),
                proptest::collection::vec(0..n, 0..2),
                proptest::collection::vec(0u32..10_000, 0..40),
                proptest::collection::vec((0..n, proptest::array::uniform3(-0.04f32..0.04), 0u8..3), 1..5),
            )
        })
        .prop_map(|(kind, dims, material, pins, holds, cuts, moves)| Case {
            kind,
            dims,
            material,
            pins,
            holds,
            cuts,
            moves,
        })
}

/// Kind 0: a grid; 1: a grid wrapped along x; 2: a grid with diagonal links in every x-y cell (an
/// irregular link list of degree up to 8 in a sheet); 3: a curvilinear grid.
fn lattice(c: &Case) -> Lattice {
    let h = 0.01;
    let [nx, ny, nz] = c.dims;
    match c.kind {
        0 => Lattice::volume(nx, ny, nz, h).expect("grid"),
        1 => {
            let mut spec = GridSpec::uniform(c.dims, h);
            spec.wrap[0] = Some(nx as f32 * h + 0.5 * h);
            Lattice::grid(&spec).expect("wrapped")
        }
        2 => {
            let grid = Lattice::volume(nx, ny, nz, h).expect("grid");
            let rest = grid.rest_positions().to_vec();
            let mut links: Vec<LinkSpec> = (0..grid.link_count())
                .map(|l| {
                    let l = LinkId(l as u32);
                    let [a, b] = grid.link_ends(l).expect("ends");
                    let r = grid.link_rest(l).expect("rest");
                    LinkSpec { a, b, rest: r, scale: [h; 3] }
                })
                .collect();
            for k in 0..nz {
                for j in 0..ny - 1 {
                    for i in 0..nx - 1 {
                        let a = grid.element_at(i, j, k).expect("a");
                        let b = grid.element_at(i + 1, j + 1, k).expect("b");
                        let r = [h, h, 0.0];
                        links.push(LinkSpec { a, b, rest: r, scale: [h * 1.5; 3] });
                    }
                }
            }
            Lattice::from_links(rest, &links).expect("links")
        }
        _ => {
            let grid = Lattice::volume(nx, ny, nz, h).expect("grid");
            let rest = grid
                .rest_positions()
                .iter()
                .map(|p| [p[0] + 0.1 * p[1] * p[1], p[1] * (1.0 + p[0]), p[2] + 0.2 * p[0]])
                .collect();
            Lattice::curvilinear(c.dims, rest).expect("curvilinear")
        }
    }
}

fn build(c: &Case) -> Body {
    let (s, m, sh) = c.material;
    let dressing =
        Dressing { stiffness: 3.0, region_x: 0.015, pins: &c.pins, holds: &c.holds, cuts: &c.cuts };
    dress(lattice(c), Material::relative(s, m, sh), &dressing)
}

/// What a test body carries beyond its lattice and first material: a stiffer material below
/// `region_x`, pins, holds and cuts (ids taken modulo the element and link counts).
struct Dressing<'a> {
    stiffness: f32,
    region_x: f32,
    pins: &'a [u32],
    holds: &'a [u32],
    cuts: &'a [u32],
}

fn dress(lattice: Lattice, material: Material, d: &Dressing<'_>) -> Body {
    let mut body = Body::new(lattice, material).expect("body");
    let mut stiff = Material::relative(1.05, 0.95, 0.05);
    stiff.stiffness = d.stiffness;
    let stiff = body.add_material(stiff).expect("material");
    body.set_material_where(stiff, |a, b| a[0] < d.region_x && b[0] < d.region_x).expect("region");
    let n = body.element_count() as u32;
    for &p in d.pins {
        body.set_pinned(ElementId(p % n), true).expect("pin");
    }
    for &p in d.holds {
        body.set_held(ElementId(p % n), true).expect("hold");
    }
    for &l in d.cuts {
        let l = l % body.link_count().max(1) as u32;
        body.break_link(LinkId(l), BreakReason::Cut).expect("cut");
    }
    body
}

fn same(a: &[[f32; 3]], b: &[[f32; 3]]) -> bool {
    a.iter().zip(b).all(|(p, q)| p == q)
}

/// Puts the first body on the second one's positions, so that the next move starts both alike: a soft
/// chain reaction can turn a difference in the last bits into a different sponsor, and so a different
/// shape.
fn take_positions([to, from]: &mut [Body; 2]) {
    for (i, &q) in from.positions().iter().enumerate() {
        to.set_position(ElementId(i as u32), q).expect("position");
    }
}

/// The largest coordinate difference between two sets of positions.
fn largest_gap(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter().flatten().zip(b.iter().flatten()).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// The SIMD levels the fast paths are checked at (each capped at what the machine has).
const LEVELS: [SimdLevel; 3] = [SimdLevel::Avx512, SimdLevel::Avx2, SimdLevel::Scalar];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(300)))]
    #[test]
    fn engine_matches_the_reference(c in case(), level in 0..LEVELS.len()) {
        let mut body = build(&c);
        let mut ws = Workspace::new(&body);
        // Each SIMD level's paths (capped at what this machine has) against the same reference.
        ws.set_simd(LEVELS[level]);
        let mut pos = body.positions().to_vec();
        for (step, &(e, d, pass)) in c.moves.iter().enumerate() {
            let pass = [Pass::All, Pass::Plane, Pass::Normal][pass as usize];
            let p = pos[e as usize];
            let target = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
            let (r, (fraction, moved, sponsors)) = if step % 3 == 2 {
                // A group: the element and its neighbours, each moved by a third of the move.
                let mut ids = vec![ElementId(e)];
                ids.extend(body.lattice().neighbours(ElementId(e)).map(|(n, _)| n));
                ids.dedup();
                let goals: Vec<[f32; 3]> =
                    ids.iter().map(|i| { let q = pos[i.index()]; [0, 1, 2].map(|k| q[k] + d[k] / 3.0) }).collect();
                let r = body.deform_group(&mut ws, &ids, &goals, pass).expect("group");
                let seeds: Vec<(usize, [f32; 3])> = ids.iter().map(|i| i.index()).zip(goals).collect();
                (r, reference_group(&body, &mut pos, &seeds, pass))
            } else {
                let r = body.deform(&mut ws, ElementId(e), target, pass).expect("deform");
                (r, reference_deform(&body, &mut pos, e as usize, target, pass))
            };
            prop_assert_eq!(r.fraction, fraction);
            prop_assert!(same(body.positions(), &pos), "positions differ after deformation {}", step);
            let got: Vec<usize> = ws.moved().map(|m| m.index()).collect();
            prop_assert_eq!(&got, &moved);
            for (&m, &s) in moved.iter().zip(&sponsors) {
                prop_assert_eq!(ws.sponsor(ElementId(m as u32)), Some(ElementId(s as u32)));
            }
            if step % 2 == 0 {
                body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::All);
                reference_sweep(&body, &mut pos, None);
                reference_sweep(&body, &mut pos, None);
                // Whole-body sweeps on wide grids (on any grid with single-float "vectors") take the
                // stencil's fast path, which agrees with the reference up to rounding (see
                // `grid_sweeps_match_the_generic_path`): checked to that tolerance, then the reference
                // takes the engine's positions, so that the next deformation starts alike and is
                // again compared bit for bit.
                if c.dims.iter().any(|&d| d >= 8) || ws.simd() == SimdLevel::Scalar {
                    let extent = c.dims.iter().max().copied().unwrap_or(1) as f32 * 0.01;
                    let tolerance = 64.0 * f32::EPSILON * extent;
                    let gap = largest_gap(body.positions(), &pos);
                    prop_assert!(gap <= tolerance, "sweeps differ by {} (tolerance {})", gap, tolerance);
                    pos.copy_from_slice(body.positions());
                }
            } else {
                body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::Moved);
                reference_sweep(&body, &mut pos, Some(&moved));
                reference_sweep(&body, &mut pos, Some(&moved));
                let list: Vec<ElementId> = (0..pos.len() as u32).step_by(3).map(ElementId).collect();
                body.relax_elements(&mut ws, RelaxBudget::sweeps(1), &list);
                let list: Vec<usize> = list.iter().map(|e| e.index()).collect();
                reference_sweep(&body, &mut pos, Some(&list));
            }
            prop_assert!(same(body.positions(), &pos), "positions differ after relaxation {}", step);
        }
    }
}

/// The same lattice without its grid structure: the same links in the same order, so the same
/// adjacency, but no grid dimensions, so every sweep takes the generic path.
fn without_grid(grid: &Lattice) -> Lattice {
    let links: Vec<LinkSpec> = (0..grid.link_count())
        .map(|l| {
            let l = LinkId(l as u32);
            let [a, b] = grid.link_ends(l).expect("ends");
            let rest = grid.link_rest(l).expect("rest");
            let len = rest.iter().fold(0.0f32, |m, x| m.max(x.abs()));
            LinkSpec { a, b, rest, scale: [len; 3] }
        })
        .collect();
    Lattice::from_links(grid.rest_positions().to_vec(), &links).expect("links")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(60)))]
    /// Whole-body sweeps on grids take the stencil fast path; they must give what the generic path
    /// gives on the same links, with pins, holds, cuts, two materials and wrapped rows. Not bit for
    /// bit: the fast path takes the rest offsets of a uniform grid as cancelling and a relative
    /// material's boxes as one where they differ only by the rounding of the rest coordinates, and
    /// uses fused multiply-adds. The difference stays at the rounding of the coordinates.
    #[test]
    fn grid_sweeps_match_the_generic_path(
        dims in (10usize..40, 3usize..12, prop_oneof![Just(1usize), 3usize..6]),
        wrapped in any::<bool>(),
        one_stiffness in any::<bool>(),
        pins in proptest::collection::vec(0u32..100_000, 0..6),
        holds in proptest::collection::vec(0u32..100_000, 0..3),
        cuts in proptest::collection::vec(0u32..100_000, 0..20),
        moves in proptest::collection::vec((0u32..100_000, proptest::array::uniform3(-0.03f32..0.03)), 1..4),
    ) {
        let (nx, ny, nz) = dims;
        let h = 0.01;
        let mut spec = GridSpec::uniform([nx, ny, nz], h);
        if wrapped {
            spec.wrap[0] = Some(nx as f32 * h);
        }
        let grid = Lattice::grid(&spec).expect("grid");
        let plain = without_grid(&grid);
        // One stiffness (the blocks' division-free path) or two.
        let stiffness = if one_stiffness { 1.0 } else { 3.0 };
        let dressing = Dressing { stiffness, region_x: 0.035, pins: &pins, holds: &holds, cuts: &cuts };
        let mut bodies =
            [grid, plain].map(|lattice| dress(lattice, Material::relative(1.2, 0.8, 0.3), &dressing));
        let n = bodies[0].element_count() as u32;
        for &(e, d) in &moves {
            let e = ElementId(e % n);
            let mut reports = Vec::new();
            for body in &mut bodies {
                let mut ws = Workspace::new(body);
                let p = body.position(e).expect("e");
                body.deform(&mut ws, e, [p[0] + d[0], p[1] + d[1], p[2] + d[2]], Pass::All).expect("deform");
                reports.push(body.relax(&mut ws, RelaxBudget::sweeps(3), RelaxRegion::All));
            }
            // The generic path can land on an exact fixed point and stop early (no change at all);
            // the fast path's rounding keeps moving by units in the last place.
            prop_assert!(reports[0].sweeps == reports[1].sweeps || reports[1].last_change == 0.0);
            let tolerance = 64.0 * f32::EPSILON * (nx.max(ny).max(nz) as f32 * h);
            prop_assert!((reports[0].last_change - reports[1].last_change).abs() <= tolerance);
            let gap = largest_gap(bodies[0].positions(), bodies[1].positions());
            prop_assert!(gap <= tolerance, "stencil and generic sweeps differ by {gap} (tolerance {tolerance})");
            take_positions(&mut bodies);
        }
    }
}

/// Bodies this large sweep in bands, one per thread, each with copies of the slabs beyond its ends;
/// split two and four ways, the sweep must still match the generic path.
#[test]
fn banded_sweeps_match_the_generic_path() {
    for dims in [[230, 160, 1], [40, 32, 30]] {
        for threads in [2, 4] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            let grid = Lattice::grid(&GridSpec::uniform(dims, 0.01)).expect("grid");
            let plain = without_grid(&grid);
            let n = grid.element_count() as u32;
            let dressing = Dressing {
                stiffness: 3.0,
                region_x: 0.035,
                pins: &[n / 3, n / 2 + 7],
                holds: &[],
                cuts: &[n, 3 * n],
            };
            let mut bodies =
                [grid, plain].map(|lattice| dress(lattice, Material::relative(1.2, 0.8, 0.3), &dressing));
            // Moves near the bands' ends (the middle slab) and elsewhere.
            let middle = n / 2 + dims[0] as u32 / 2;
            for (e, d) in
                [(middle, [0.02, 0.01, 0.03]), (n / 5, [-0.03, 0.02, 0.0]), (middle + 3, [0.0, -0.02, 0.01])]
            {
                for body in &mut bodies {
                    let mut ws = Workspace::new(body);
                    let p = body.position(ElementId(e)).expect("e");
                    body.deform(&mut ws, ElementId(e), [p[0] + d[0], p[1] + d[1], p[2] + d[2]], Pass::All)
                        .expect("deform");
                    pool.install(|| body.relax(&mut ws, RelaxBudget::sweeps(2), RelaxRegion::All));
                }
                let gap = largest_gap(bodies[0].positions(), bodies[1].positions());
                let tolerance = 64.0 * f32::EPSILON * (dims[0].max(dims[1]) as f32 * 0.01);
                assert!(
                    gap <= tolerance,
                    "{dims:?} on {threads} threads: differ by {gap} (tolerance {tolerance})"
                );
                take_positions(&mut bodies);
            }
        }
    }
}

/// Grasps in the middle of wide rows: the lists across rows then carry runs up the row (right of the
/// grasp) and down it (left of it), long enough for the chain reaction's whole chunks both ways, with
/// rigid, soft and two-material bodies, cuts and a pin, at every SIMD level. Moves, their order and
/// sponsors must be the reference's.
#[test]
fn grasps_mid_row_match_the_reference() {
    for (dims, level) in [[70, 40, 1], [40, 20, 4]].into_iter().flat_map(|d| LEVELS.map(|l| (d, l))) {
        for (material, cuts) in [
            (Material::rigid(), &[][..]),
            (Material::relative(1.1, 0.9, 0.2), &[][..]),
            (Material::relative(1.2, 0.8, 0.3), &[5, 900, 1234, 2222, 4000][..]),
        ] {
            let lattice = Lattice::grid(&GridSpec::uniform(dims, 0.01)).expect("grid");
            let n = lattice.element_count() as u32;
            let dressing = Dressing { stiffness: 2.0, region_x: 0.05, pins: &[n - 3], holds: &[], cuts };
            let mut body = dress(lattice, material, &dressing);
            let mut ws = Workspace::new(&body);
            ws.set_simd(level);
            let mut pos = body.positions().to_vec();
            let [nx, ny, nz] = dims;
            let middle = (nz / 2 * ny + ny / 2) * nx + nx / 2;
            for (step, (e, d)) in [
                (middle, [0.02, 0.015, 0.004]),
                (middle + 7, [-0.03, 0.01, -0.002]),
                (middle - nx + 20, [0.0, -0.025, 0.01]),
            ]
            .into_iter()
            .enumerate()
            {
                let p = pos[e];
                let target = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
                let r = body.deform(&mut ws, ElementId(e as u32), target, Pass::All).expect("deform");
                let (fraction, moved, sponsors) = reference_deform(&body, &mut pos, e, target, Pass::All);
                assert_eq!(r.fraction, fraction, "{dims:?} {level:?} step {step}");
                assert!(
                    same(body.positions(), &pos),
                    "{dims:?} {level:?}: positions differ after move {step}"
                );
                let got: Vec<usize> = ws.moved().map(|m| m.index()).collect();
                assert_eq!(got, moved, "{dims:?} {level:?}: order of moves {step}");
                for (&m, &s) in moved.iter().zip(&sponsors) {
                    assert_eq!(
                        ws.sponsor(ElementId(m as u32)),
                        Some(ElementId(s as u32)),
                        "{dims:?} {level:?} step {step}"
                    );
                }
            }
        }
    }
}
