//! Property tests of the chain reaction over random grids, materials, pins and moves: after every
//! deformation each intact link between a moved element and its sponsor holds its limits, no element
//! moved twice, nothing is NaN, pinned elements are untouched, and the same moves give the same bits.

mod common;

use std::collections::HashSet;

use dissect::chainmail::{
    Body, BreakReason, ElementId, Lattice, LinkId, Material, Pass, RelaxBudget, RelaxRegion, Workspace,
};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Case {
    dims: [usize; 3],
    material: (f32, f32, f32),
    pins: Vec<u32>,
    cuts: Vec<u32>,
    moves: Vec<(u32, [f32; 3])>,
}

fn case() -> impl Strategy<Value = Case> {
    (2usize..9, 2usize..9, prop_oneof![Just(1usize), 2usize..5])
        .prop_flat_map(|(nx, ny, nz)| {
            let n = (nx * ny * nz) as u32;
            (
                Just([nx, ny, nz]),
                (1.0f32..2.0, 0.3f32..1.0, 0.0f32..0.8),
                proptest::collection::vec(0..n, 0..4),
                proptest::collection::vec(0u32..10_000, 0..6),
                proptest::collection::vec((0..n, proptest::array::uniform3(-0.05f32..0.05)), 1..6),
            )
        })
        .prop_map(|(dims, material, pins, cuts, moves)| Case { dims, material, pins, cuts, moves })
}

fn build(c: &Case) -> Body {
    let lattice = Lattice::volume(c.dims[0], c.dims[1], c.dims[2], 0.01).expect("lattice");
    let (s, m, sh) = c.material;
    let mut body = Body::new(lattice, Material::relative(s, m, sh)).expect("body");
    // A stiffer region: one body can be soft here and stiff there.
    let stiff = body.add_material(Material::relative(1.05, 0.95, 0.05)).expect("material");
    body.set_material_where(stiff, |a, b| a[0] < 0.015 && b[0] < 0.015).expect("region");
    for &p in &c.pins {
        body.set_pinned(ElementId(p), true).expect("pin");
    }
    for &l in &c.cuts {
        let l = l % body.link_count().max(1) as u32;
        body.break_link(LinkId(l), BreakReason::Cut).expect("cut");
    }
    body
}

fn run(c: &Case) -> Result<Vec<[f32; 3]>, TestCaseError> {
    let mut body = build(c);
    let mut ws = Workspace::new(&body);
    let pinned: Vec<(u32, [f32; 3])> =
        c.pins.iter().map(|&p| (p, body.position(ElementId(p)).expect("pin"))).collect();
    for &(e, d) in &c.moves {
        let p = body.position(ElementId(e)).expect("source");
        let r = body
            .deform(&mut ws, ElementId(e), [p[0] + d[0], p[1] + d[1], p[2] + d[2]], Pass::All)
            .expect("deform");
        prop_assert!((0.0..=1.0).contains(&r.fraction));
        let moved: Vec<ElementId> = ws.moved().collect();
        let unique: HashSet<ElementId> = moved.iter().copied().collect();
        prop_assert_eq!(unique.len(), moved.len(), "an element moved twice");
        prop_assert_eq!(moved.len(), r.moved as usize);
        for &m in &moved {
            let s = ws.sponsor(m).expect("sponsor");
            if s == m {
                continue;
            }
            let (pm, ps) = (body.position(m).expect("m"), body.position(s).expect("s"));
            let link = body
                .lattice()
                .neighbours(m)
                .find(|&(n, l)| n == s && body.link_intact(l))
                .map(|(_, l)| l)
                .expect("sponsor link");
            let [a, _] = body.lattice().link_ends(link).expect("ends");
            let d = if a == s {
                [pm[0] - ps[0], pm[1] - ps[1], pm[2] - ps[2]]
            } else {
                [ps[0] - pm[0], ps[1] - pm[1], ps[2] - pm[2]]
            };
            let [lo, hi] = body.link_limits(link).expect("limits");
            for k in 0..3 {
                let tol = 1e-5 * (hi[k].abs().max(lo[k].abs()).max(0.01));
                prop_assert!(d[k] >= lo[k] - tol && d[k] <= hi[k] + tol, "link to sponsor out of limits");
            }
        }
        body.relax(&mut ws, RelaxBudget::sweeps(3), RelaxRegion::Moved);
        body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All);
        prop_assert!(body.positions().iter().all(|p| p.iter().all(|x| x.is_finite())), "NaN");
        for &(p, at) in &pinned {
            prop_assert_eq!(body.position(ElementId(p)).expect("pin"), at, "a pinned element moved");
        }
    }
    Ok(body.positions().to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(200)))]
    #[test]
    fn deformations_keep_the_invariants(c in case()) {
        let first = run(&c)?;
        let second = run(&c)?;
        let same = first.iter().zip(&second).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits));
        prop_assert!(same, "same moves gave different bits");
    }
}
