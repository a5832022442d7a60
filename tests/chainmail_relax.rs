//! Relaxation: energy never rises from sweep to sweep, and with nothing held a deformed body returns to
//! its rest shape up to a rigid motion; held elements stay put.

use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

fn deformed_sheet() -> (Body, Workspace) {
    deformed(Lattice::sheet(10, 8, 0.01).expect("sheet"), 44, 5)
}

/// The bodies the sweeps are checked on: the small sheet (generic rows only), and a sheet and a
/// volume wide enough for the grid fast path's vectors (AVX-512 needs runs of sixteen), deformed
/// near the middle and near a corner. Returns each with the element it deformed first.
fn bodies() -> Vec<(Body, Workspace, u32)> {
    let sheet = Lattice::sheet(64, 40, 0.01).expect("sheet");
    let volume = Lattice::volume(40, 20, 6, 0.01).expect("volume");
    let (mut small, ws) = deformed_sheet();
    let mut all = vec![];
    small.set_held(ElementId(44), false).expect("free");
    all.push((small, ws, 44));
    let (body, ws) = deformed(sheet, 64 * 20 + 30, 70);
    all.push((body, ws, 64 * 20 + 30));
    let (body, ws) = deformed(volume, 40 * 20 * 3 + 40 * 10 + 20, 45);
    all.push((body, ws, 40 * 20 * 3 + 40 * 10 + 20));
    all
}

fn deformed(lattice: Lattice, a: u32, b: u32) -> (Body, Workspace) {
    let mut body = Body::new(lattice, Material::relative(1.3, 0.7, 0.4)).expect("body");
    let mut ws = Workspace::new(&body);
    let (pa, pb) = (body.position(ElementId(a)).expect("a"), body.position(ElementId(b)).expect("b"));
    body.deform(&mut ws, ElementId(a), [pa[0] + 0.03, pa[1] + 0.03, pa[2] + 0.02], Pass::All)
        .expect("deform");
    body.deform(&mut ws, ElementId(b), [pb[0] + 0.02, pb[1] - 0.02, pb[2] - 0.01], Pass::All)
        .expect("deform");
    (body, ws)
}

#[test]
fn energy_never_rises() {
    for (mut body, mut ws, held) in bodies() {
        body.set_held(ElementId(held), true).expect("hold");
        let mut e = body.energy();
        assert!(e > 0.0);
        for _ in 0..300 {
            body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All);
            let next = body.energy();
            assert!(next <= e * (1.0 + 1e-6) + 1e-12, "energy rose from {e} to {next}");
            e = next;
        }
    }
}

#[test]
fn free_body_returns_to_rest_up_to_a_rigid_motion() {
    for (mut body, mut ws, _) in bodies() {
        // On the larger bodies the sweeps stop a little short of rest: where a link's box keeps an
        // element from stepping toward its target, the box clamps the sweep (as it is meant to).
        // Their slowest modes also take tens of thousands of sweeps, which run to the end: a
        // tolerance under the rounding of the coordinates is never met, so none is set.
        let small = body.element_count() < 100;
        let (tolerance, off, energy) = if small { (1e-9, 1e-5, 1e-9) } else { (0.0, 5e-5, 1e-8) };
        let report = body.relax(
            &mut ws,
            RelaxBudget { max_sweeps: 30_000, max_time: None, tolerance },
            RelaxRegion::All,
        );
        assert!(report.sweeps > 1);
        assert!(report.converged || !small, "no convergence in {} sweeps", report.sweeps);
        let rest = body.lattice().rest_positions();
        let p = body.positions();
        let t = [0, 1, 2].map(|k| p[0][k] - rest[0][k]);
        for (q, r) in p.iter().zip(rest) {
            for k in 0..3 {
                let gap = q[k] - r[k] - t[k];
                assert!(gap.abs() < off, "{} elements: off a rigid translation by {gap}", p.len());
            }
        }
        assert!(body.energy() < energy, "{} elements: energy {} left", p.len(), body.energy());
    }
}

#[test]
fn held_and_pinned_elements_stay_put() {
    let (mut body, mut ws) = deformed_sheet();
    body.set_held(ElementId(44), true).expect("hold");
    body.set_pinned(ElementId(0), true).expect("pin");
    let (a, b) = (body.position(ElementId(44)).expect("a"), body.position(ElementId(0)).expect("b"));
    body.relax(&mut ws, RelaxBudget::sweeps(50), RelaxRegion::All);
    body.deform(&mut ws, ElementId(70), [0.03, 0.09, 0.0], Pass::All).expect("deform");
    body.relax(&mut ws, RelaxBudget::sweeps(50), RelaxRegion::Moved);
    assert_eq!(body.position(ElementId(44)).expect("a"), a);
    assert_eq!(body.position(ElementId(0)).expect("b"), b);
}

#[test]
fn cut_links_carry_no_energy_and_no_motion() {
    let lattice = Lattice::sheet(6, 1, 0.01).expect("chain");
    let mut body = Body::new(lattice, Material::relative(1.1, 0.9, 0.1)).expect("body");
    let mut ws = Workspace::new(&body);
    let cut = body
        .lattice()
        .neighbours(ElementId(2))
        .find(|(n, _)| *n == ElementId(3))
        .map(|(_, l)| l)
        .expect("link 2-3");
    body.break_link(cut, dissect::chainmail::BreakReason::Cut).expect("cut");
    body.deform(&mut ws, ElementId(5), [0.2, 0.0, 0.0], Pass::All).expect("pull");
    for i in 0..3 {
        assert_eq!(body.position(ElementId(i)).expect("left"), body.lattice().rest_positions()[i as usize]);
    }
    assert!(body.position(ElementId(3)).expect("right")[0] > 0.1);
}

/// Relaxation spreads a poke out of the plane along a long strip (the grid fast path): ahead of the
/// disturbance the out-of-plane coordinate is a tiny power of the distance, and it must never be a
/// subnormal float, on which every operation is a hundred times slower.
#[test]
fn no_coordinate_becomes_subnormal() {
    strip_stays_normal(|body, ws, _| {
        body.relax(ws, RelaxBudget::sweeps(1), RelaxRegion::All);
    });
}

/// The same through the generic path (`relax_elements`, which the tissue uses).
#[test]
fn no_coordinate_becomes_subnormal_on_the_generic_path() {
    strip_stays_normal(|body, ws, all| {
        body.relax_elements(ws, RelaxBudget::sweeps(1), all);
    });
}

fn strip_stays_normal(mut sweep: impl FnMut(&mut Body, &mut Workspace, &[ElementId])) {
    let (nx, ny) = (800u32, 20u32);
    let lattice = Lattice::sheet(nx as usize, ny as usize, 0.01).expect("sheet");
    let mut body = Body::new(lattice, Material::relative(1.3, 0.7, 0.4)).expect("body");
    let mut ws = Workspace::new(&body);
    let all: Vec<ElementId> = (0..nx * ny).map(ElementId).collect();
    let c = ElementId(ny / 2 * nx + 1);
    let p = body.position(c).expect("c");
    body.deform(&mut ws, c, [p[0], p[1], 0.05], Pass::All).expect("deform");
    body.set_held(c, true).expect("hold");
    for _ in 0..300 {
        sweep(&mut body, &mut ws, &all);
        let subnormal = body.positions().iter().flatten().filter(|c| c.is_subnormal()).count();
        assert_eq!(subnormal, 0, "subnormal coordinates");
    }
}
