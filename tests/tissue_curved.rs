//! Cylinder and sphere: a grasp near the wrap seam (and a push near a pole) deforms the surface across
//! the seam smoothly; no seam link is torn or stretched past its limits, and nothing is NaN.

mod common;

use dissect::chainmail::{ElementId, LinkId, RelaxBudget};
use dissect::simulation::Command;
use dissect::simulation::{InstrumentKind, World, WorldConfig};
use dissect::surface::Surface;
use dissect::tissue::{Pinning, Tissue, TissueSpec};

fn seam_links(t: &Tissue, nu: usize) -> Vec<LinkId> {
    (0..t.body().link_count() as u32)
        .map(LinkId)
        .filter(|&l| {
            let [a, b] = t.body().lattice().link_ends(l).expect("ends");
            let (ia, ib) = (a.index() % nu, b.index() % nu);
            (ia == nu - 1 && ib == 0) || (ia == 0 && ib == nu - 1)
        })
        .collect()
}

fn pull_at(
    surface: Surface,
    pinned: Pinning,
    grasp_u: usize,
    grasp_v: usize,
    by: [f32; 3],
) -> (Tissue, usize) {
    let n = 24;
    let spec = common::two_layers(n, surface, pinned);
    let tissue = Tissue::build(&TissueSpec::Layered(spec)).expect("tissue");
    let e = ElementId(tissue.layers()[0].first + (grasp_u + n * grasp_v) as u32);
    let start = tissue.world_position(e).expect("start");
    let mut world =
        World::new(tissue, WorldConfig { relax: RelaxBudget::sweeps(3), ..WorldConfig::default() });
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::GraspElement(e));
    world.step();
    for s in 1..=80 {
        let f = s as f32 / 80.0;
        world.push(Command::MoveTo([start[0] + f * by[0], start[1] + f * by[1], start[2] + f * by[2]]));
        world.step();
    }
    let moved = world.tissue().world_position(e).expect("end");
    assert!(
        (moved[0] - start[0]).abs() + (moved[1] - start[1]).abs() + (moved[2] - start[2]).abs() > 0.004,
        "the grasp did not move the surface"
    );
    (world.tissue().clone(), n)
}

fn check_seam(t: &Tissue, nu: usize) {
    let seam = seam_links(t, nu);
    assert!(!seam.is_empty());
    for &l in &seam {
        assert!(t.body().link_intact(l), "seam link {l:?} broke");
        assert!(t.body().link_violation(l).expect("link") < 1e-4, "seam link {l:?} outside its limits");
        // Across the seam the surface is as stretched as on either side of it: no discontinuity.
        let [a, b] = t.body().lattice().link_ends(l).expect("ends");
        let beside = |e: ElementId, step: isize| {
            let row = e.index() - e.index() % nu;
            let i = (e.index() % nu) as isize;
            let f = ElementId((row + (i + step).rem_euclid(nu as isize) as usize) as u32);
            let link =
                t.body().lattice().neighbours(e).find(|&(n, _)| n == f).map(|(_, l)| l).expect("beside");
            t.world_stretch(link)
        };
        let (left, right) = (beside(a, -1), beside(b, 1));
        let s = t.world_stretch(l);
        let (lo, hi) = (left.min(right), left.max(right));
        assert!(
            s.is_finite() && s >= 0.8 * lo && s <= 1.25 * hi,
            "seam link stretch {s}, beside it {left} and {right}"
        );
    }
    assert!(t.body().positions().iter().all(|p| p.iter().all(|x| x.is_finite())));
}

#[test]
fn cylinder_deforms_across_its_seam() {
    let s = Surface::Cylinder { radius: 0.02, length: 0.08 };
    // Grasp on the seam (u = 0) halfway up and pull outwards and sideways.
    let (t, nu) = pull_at(s, Pinning::Boundary, 0, 12, [0.004, 0.0, 0.008]);
    check_seam(&t, nu);
    // Elements on both sides of the seam moved.
    let layer = &t.layers()[0];
    let side = |i: usize| {
        let e = ElementId(layer.first + (i + nu * 12) as u32);
        let p = t.body().position(e).expect("p");
        let r = t.body().lattice().rest_positions()[e.index()];
        (p[0] - r[0]).abs() + (p[2] - r[2]).abs()
    };
    assert!(side(1) > 1e-4 && side(nu - 1) > 1e-4, "the deformation stopped at the seam");
}

#[test]
fn sphere_deforms_across_its_seam_and_near_a_pole() {
    let s = Surface::Sphere { radius: 0.025 };
    let (t, nu) = pull_at(s, Pinning::None, 0, 1, [0.002, 0.008, 0.004]);
    check_seam(&t, nu);
    // The poles are not lattice rows, but the drawn surface is closed: a fan round each pole.
    let mut meshes = Vec::new();
    t.fill_meshes(&mut meshes);
    let nv = t.layers()[0].count as usize / nu;
    assert_eq!(meshes[0].triangles.len(), 2 * nu * (nv - 1) + 2 * nu, "a hole at a pole");
    // The row nearest the pole stays a ring: no link of it collapsed or flew apart.
    let layer = &t.layers()[0];
    for i in 0..nu {
        let a = ElementId(layer.first + i as u32);
        let b = ElementId(layer.first + ((i + 1) % nu) as u32);
        let link =
            t.body().lattice().neighbours(a).find(|&(n, _)| n == b).map(|(_, l)| l).expect("ring link");
        let st = t.world_stretch(link);
        assert!(st > 0.2 && st < 2.0, "pole ring link stretched to {st}");
    }
}
