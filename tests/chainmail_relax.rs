//! Relaxation: energy never rises from sweep to sweep, and with nothing held a deformed body returns to
//! its rest shape up to a rigid motion; held elements stay put.

use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

fn deformed_sheet() -> (Body, Workspace) {
    let lattice = Lattice::sheet(10, 8, 0.01).expect("sheet");
    let mut body = Body::new(lattice, Material::relative(1.3, 0.7, 0.4)).expect("body");
    let mut ws = Workspace::new(&body);
    body.deform(&mut ws, ElementId(44), [0.06, 0.03, 0.02], Pass::All).expect("deform");
    body.deform(&mut ws, ElementId(5), [0.02, -0.02, -0.01], Pass::All).expect("deform");
    (body, ws)
}

#[test]
fn energy_never_rises() {
    let (mut body, mut ws) = deformed_sheet();
    body.set_held(ElementId(44), true).expect("hold");
    let mut e = body.energy();
    assert!(e > 0.0);
    for _ in 0..300 {
        body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All);
        let next = body.energy();
        assert!(next <= e * (1.0 + 1e-6) + 1e-12, "energy rose from {e} to {next}");
        e = next;
    }
}

#[test]
fn free_body_returns_to_rest_up_to_a_rigid_motion() {
    let (mut body, mut ws) = deformed_sheet();
    let report = body.relax(
        &mut ws,
        RelaxBudget { max_sweeps: 20_000, max_time: None, tolerance: 1e-9 },
        RelaxRegion::All,
    );
    assert!(report.sweeps > 1);
    let rest = body.lattice().rest_positions();
    let p = body.positions();
    let t = [0, 1, 2].map(|k| p[0][k] - rest[0][k]);
    for (q, r) in p.iter().zip(rest) {
        for k in 0..3 {
            assert!((q[k] - r[k] - t[k]).abs() < 1e-5, "not a rigid translation of the rest shape");
        }
    }
    assert!(body.energy() < 1e-9);
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
