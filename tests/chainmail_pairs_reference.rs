//! The normal pass's completion over normal pairs (`chainmail/reaction/complete.rs`): its fast path
//! (the usual widths: 4 link slots on a sheet, 5 on two layers joined by fibres, 4 pair slots; bounds
//! widened once, one branch-free test per element) against its plain path (any widths, every bound
//! read where it lies), which `Workspace::set_plain_pairs` selects. On sheets with both diagonals of
//! every cell as pairs and on two-layer tissues (plane, cylinder: a wrapped axis), with pins, holds,
//! cuts and soft or stiff shear, random lifts and pushes of one element or of a group, some blocked
//! by the pins, and relaxation between them, both must give the same positions (compared with `==`),
//! the same moved elements in the same order, the same sponsors and the same shares of the moves.

mod common;

use dissect::chainmail::{
    Body, BreakReason, ElementId, Lattice, Limits, LinkId, Material, NormalPair, Pass, RelaxBudget,
    RelaxRegion, Workspace,
};
use dissect::surface::Surface;
use dissect::tissue::{Pinning, Tissue, TissueSpec};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Case {
    kind: u8,
    n: usize,
    shear: f32,
    pins: Vec<u32>,
    holds: Vec<u32>,
    cuts: Vec<u32>,
    moves: Vec<(u32, f32, u8)>,
}

fn case() -> impl Strategy<Value = Case> {
    (0u8..3, 4usize..24, prop_oneof![Just(0.25f32), 0.05f32..0.6])
        .prop_flat_map(|(kind, n, shear)| {
            (
                Just(kind),
                Just(n),
                Just(shear),
                proptest::collection::vec(0u32..100_000, 0..4),
                proptest::collection::vec(0u32..100_000, 0..2),
                proptest::collection::vec(0u32..100_000, 0..30),
                proptest::collection::vec((0u32..100_000, -0.02f32..0.02, 0u8..4), 1..6),
            )
        })
        .prop_map(|(kind, n, shear, pins, holds, cuts, moves)| Case {
            kind,
            n,
            shear,
            pins,
            holds,
            cuts,
            moves,
        })
}

/// A sheet of `n × n` (spacing 1 mm) with both diagonals of every cell as normal pairs.
fn sheet(n: usize, shear: f32) -> Body {
    let mut body =
        Body::new(Lattice::sheet(n, n, 0.001).expect("sheet"), Material::relative(1.2, 0.8, shear))
            .expect("body");
    let link = |body: &Body, a: usize, b: usize| {
        let l = body.lattice().neighbours(ElementId(a as u32)).find(|&(e, _)| e.index() == b);
        l.map(|(_, l)| l).expect("link")
    };
    let id = |x: usize| ElementId(x as u32);
    let mut pairs = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, e) = (i + n * j, i + 1 + n * j, i + 1 + n * (j + 1), i + n * (j + 1));
            let (ab, bc, ec, ae) =
                (link(&body, a, b), link(&body, b, c), link(&body, e, c), link(&body, a, e));
            pairs.push(NormalPair { a: id(a), b: id(c), paths: [[ab, bc], [ae, ec]] });
            pairs.push(NormalPair { a: id(b), b: id(e), paths: [[ab, ae], [bc, ec]] });
        }
    }
    body.set_normal_pairs(&pairs).expect("pairs");
    body
}

/// A two-layer tissue's body (its builder gives every layer's cells their diagonals as pairs).
fn layers(n: usize, surface: Surface, shear: f32) -> Body {
    let mut spec = common::two_layers(n, surface, Pinning::None);
    for l in &mut spec.layers {
        l.material.limits = Limits::Relative { max_stretch: 1.15, min_compress: 0.85, max_shear: shear };
    }
    let tissue = Tissue::build(&TissueSpec::Layered(spec)).expect("tissue");
    tissue.body().clone()
}

fn build(c: &Case) -> Body {
    let mut body = match c.kind {
        0 => sheet(c.n, c.shear),
        1 => layers(c.n, Surface::Plane { width: 0.02, depth: 0.02 }, c.shear),
        _ => layers(c.n, Surface::Cylinder { radius: 0.01, length: 0.02 }, c.shear),
    };
    assert!(body.normal_pair_count() > 0);
    let n = body.element_count() as u32;
    for &p in &c.pins {
        body.set_pinned(ElementId(p % n), true).expect("pin");
    }
    for &p in &c.holds {
        body.set_held(ElementId(p % n), true).expect("hold");
    }
    for &l in &c.cuts {
        let l = l % body.link_count() as u32;
        body.break_link(LinkId(l), BreakReason::Cut).expect("cut");
    }
    body
}

fn same(a: &[[f32; 3]], b: &[[f32; 3]]) -> bool {
    a.iter().zip(b).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits))
}

fn run(c: &Case) -> Result<(), TestCaseError> {
    let mut bodies = [build(c), build(c)];
    let mut wss = bodies.each_ref().map(Workspace::new);
    wss[1].set_plain_pairs(true);
    let n = bodies[0].element_count() as u32;
    let mut moved_total = 0;
    for (k, &(e, dz, how)) in c.moves.iter().enumerate() {
        let e = ElementId(e % n);
        let mut results = Vec::new();
        for (body, ws) in bodies.iter_mut().zip(&mut wss) {
            let p = body.positions()[e.index()];
            let r = match how {
                // A group: the element and its link neighbours, up or down together.
                0 => {
                    let mut group = vec![e];
                    group.extend(body.lattice().neighbours(e).map(|(x, _)| x));
                    let goals: Vec<[f32; 3]> = group
                        .iter()
                        .map(|&x| body.positions()[x.index()])
                        .map(|q| [q[0], q[1], q[2] + dz])
                        .collect();
                    body.deform_group(ws, &group, &goals, Pass::Normal).expect("group")
                }
                // A move in the plane first (the normal pass then starts from a sheared state).
                1 => {
                    body.deform(ws, e, [p[0] + 0.5 * dz, p[1] - 0.3 * dz, p[2]], Pass::Plane).expect("plane");
                    body.deform(ws, e, [p[0], p[1], p[2] + dz], Pass::Normal).expect("normal")
                }
                _ => body.deform(ws, e, [p[0], p[1], p[2] + dz], Pass::Normal).expect("normal"),
            };
            let moved: Vec<ElementId> = ws.moved().collect();
            let sponsors: Vec<Option<ElementId>> = moved.iter().map(|&m| ws.sponsor(m)).collect();
            results.push((r, moved, sponsors));
            if how == 3 {
                body.relax(ws, RelaxBudget::sweeps(2), RelaxRegion::All);
            }
        }
        prop_assert_eq!(&results[0].0, &results[1].0, "move {}: the deformations differ", k);
        prop_assert_eq!(&results[0].1, &results[1].1, "move {}: the moved elements differ", k);
        prop_assert_eq!(&results[0].2, &results[1].2, "move {}: the sponsors differ", k);
        prop_assert!(same(bodies[0].positions(), bodies[1].positions()), "move {}: positions differ", k);
        moved_total += results[0].1.len();
    }
    let _ = moved_total;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(64)))]

    #[test]
    fn fast_and_plain_completions_agree(c in case()) {
        run(&c)?;
    }
}

/// The case the exercise plays most: a point lift of a two-layer plane, tens of elements across,
/// with its border pinned (the lift blocks at the pins and the search shortens it).
#[test]
fn a_pinned_point_lift_completes_alike() {
    let spec = common::two_layers(40, Surface::Plane { width: 0.04, depth: 0.04 }, Pinning::Boundary);
    let tissue = Tissue::build(&TissueSpec::Layered(spec)).expect("tissue");
    let mut bodies = [tissue.body().clone(), tissue.body().clone()];
    let mut wss = bodies.each_ref().map(Workspace::new);
    wss[1].set_plain_pairs(true);
    let e = ElementId((20 * 40 + 20) as u32);
    for step in 1..=40 {
        let mut moved = [0, 0];
        for (k, (body, ws)) in bodies.iter_mut().zip(&mut wss).enumerate() {
            let p = body.positions()[e.index()];
            let r = body.deform(ws, e, [p[0], p[1], p[2] + 0.0005], Pass::Normal).expect("lift");
            moved[k] = r.moved;
            body.relax(ws, RelaxBudget::sweeps(4), RelaxRegion::Moved);
        }
        assert_eq!(moved[0], moved[1], "step {step}");
        assert!(same(bodies[0].positions(), bodies[1].positions()), "step {step}: positions differ");
    }
}

/// A lift that raises its rigid elements at once (`Workspace::set_rigid_blocks`, as a tissue's
/// workspace does) against the same lift taken element by element: a jaw-sized patch of a two-layer
/// plane, its border pinned, rising step after step. The raise must engage, every link must stay
/// within its box, and the heights must agree to rounding (the raise adds the seeds' rise where the
/// completion adds each bound to its neighbour's height). Both completions with the raise, fast and
/// plain, agree bit for bit.
#[test]
fn rigid_blocks_lift_as_the_elements_do() {
    let n = 64;
    let spec = common::two_layers(n, Surface::Plane { width: 0.04, depth: 0.04 }, Pinning::Boundary);
    let patch: Vec<ElementId> =
        (31..34).flat_map(|j| (31..34).map(move |i| ElementId((i + n * j) as u32))).collect();
    let (raised, worst) = lift_both_ways(spec, &patch, 45);
    // The patch rose 4.5 mm (further, the pins stop it); its tent spans most of the sheet.
    assert!(raised > 5_000, "the raise lifted only {raised} elements in all");
    assert!(worst <= 2e-7, "the heights differ by up to {worst} m");
}

/// The same on a cylinder, whose `u` axis wraps: the patch straddles the seam, where the grid's
/// first and last columns are neighbours (not at the offsets the raise finds neighbours at: it
/// queues a grid's edge elements as its rim), and its tent spreads round it.
#[test]
fn rigid_elements_lift_across_a_wrapped_seam_as_the_elements_do() {
    let n = 48;
    let spec = common::two_layers(n, Surface::Cylinder { radius: 0.01, length: 0.04 }, Pinning::Boundary);
    let patch: Vec<ElementId> = (23..26)
        .flat_map(|j| [n - 1, 0, 1].into_iter().map(move |i| ElementId((i + n * j) as u32)))
        .collect();
    let (raised, worst) = lift_both_ways(spec, &patch, 45);
    assert!(raised > 1_000, "the raise lifted only {raised} elements in all");
    assert!(worst <= 2e-7, "the heights differ by up to {worst} m");
}

/// Lifts `patch` of a tissue built from `spec` 0.1 mm a step for `steps` steps three ways: raising
/// rigid elements with the fast completion and with the plain one (which must agree bit for bit),
/// and element by element. Every link must stay within its box. Returns the elements raised at once
/// in all, and the largest difference in height from the element-by-element lift.
fn lift_both_ways(spec: dissect::tissue::LayeredSpec, patch: &[ElementId], steps: usize) -> (usize, f32) {
    let tissue = Tissue::build(&TissueSpec::Layered(spec)).expect("tissue");
    let mut bodies = [tissue.body().clone(), tissue.body().clone(), tissue.body().clone()];
    let mut wss = bodies.each_ref().map(Workspace::new);
    wss[0].set_rigid_blocks(true);
    wss[1].set_rigid_blocks(true);
    wss[1].set_plain_pairs(true);
    let (mut raised, mut worst) = (0usize, 0.0f32);
    for step in 1..=steps {
        for (body, ws) in bodies.iter_mut().zip(&mut wss) {
            let goals: Vec<[f32; 3]> = patch
                .iter()
                .map(|&x| body.positions()[x.index()])
                .map(|q| [q[0], q[1], q[2] + 0.0001])
                .collect();
            let r = body.deform_group(ws, patch, &goals, Pass::Normal).expect("lift");
            assert!(r.fraction > 0.0, "step {step}: the lift blocked");
        }
        raised += wss[0].raised_unlisted();
        assert!(same(bodies[0].positions(), bodies[1].positions()), "step {step}: fast and plain differ");
        let body = &bodies[0];
        let violation = (0..body.link_count() as u32)
            .map(LinkId)
            .filter(|&l| body.link_intact(l))
            .map(|l| body.link_violation(l).unwrap_or(0.0))
            .fold(0.0f32, f32::max);
        assert!(violation <= 1e-6, "step {step}: a link lies {violation} m outside its box");
        for (p, q) in bodies[0].positions().iter().zip(bodies[2].positions()) {
            worst = worst.max((p[2] - q[2]).abs());
        }
    }
    (raised, worst)
}

/// A lift whose rigid elements rose first (the last lift from the same seeds went its whole way) and
/// which the pins then block is rolled back exactly: the raise keeps only the raised elements'
/// heights before (`Lift::old_z`), and putting them back must restore every position to the bit.
/// Checked through the search: the blocked reach's share of the move, asked for directly from the
/// same state (on a copy that never tried the blocked reach), gives the same positions.
#[test]
fn a_blocked_raise_rolls_back_exactly() {
    let n = 64;
    let spec = common::two_layers(n, Surface::Plane { width: 0.04, depth: 0.04 }, Pinning::Boundary);
    let tissue = Tissue::build(&TissueSpec::Layered(spec)).expect("tissue");
    let mut body = tissue.body().clone();
    let mut ws = Workspace::new(&body);
    ws.set_rigid_blocks(true);
    let patch: Vec<ElementId> =
        (31..34).flat_map(|j| (31..34).map(move |i| ElementId((i + n * j) as u32))).collect();
    let goals_up = |body: &Body, dz: f32| -> Vec<[f32; 3]> {
        patch.iter().map(|&x| body.positions()[x.index()]).map(|q| [q[0], q[1], q[2] + dz]).collect()
    };
    // Lifts that go their whole way, until the raise moves most of the tent at once.
    for step in 1..=30 {
        let goals = goals_up(&body, 0.0001);
        let r = body.deform_group(&mut ws, &patch, &goals, Pass::Normal).expect("lift");
        assert!(r.fraction >= 1.0, "step {step}: the lift was shortened");
    }
    assert!(ws.raised_unlisted() > 500, "the raise moved only {} elements", ws.raised_unlisted());
    // A reach far past what the pins allow: raised first, blocked, rolled back, shortened.
    let (mut copy, mut copy_ws) = (body.clone(), ws.clone());
    let start: Vec<[f32; 3]> = goals_up(&body, 0.0);
    let goals = goals_up(&body, 0.05);
    let r = body.deform_group(&mut ws, &patch, &goals, Pass::Normal).expect("reach");
    assert!(r.fraction > 0.0 && r.fraction < 1.0, "the reach went {} of its way", r.fraction);
    assert!(r.attempts > 1, "the reach was not tried whole first");
    // The share it went, asked for at once.
    let t = r.fraction;
    let short: Vec<[f32; 3]> =
        start.iter().zip(&goals).map(|(p, g)| [0, 1, 2].map(|c| p[c] + t * (g[c] - p[c]))).collect();
    let q = copy.deform_group(&mut copy_ws, &patch, &short, Pass::Normal).expect("short reach");
    assert_eq!(q.fraction, 1.0, "the short reach was shortened");
    assert!(same(body.positions(), copy.positions()), "the rolled-back raise left positions changed");
}
