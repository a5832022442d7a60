//! Analytic cases the chain reaction must reproduce exactly: a rigid body translates as one, a pulled
//! chain follows the closed form, and a move blocked by a pin is bisected to what the pin allows.

use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, Workspace};

#[test]
fn rigid_material_translates_the_whole_body_exactly() {
    let lattice = Lattice::volume(6, 5, 4, 0.01).expect("lattice");
    let mut body = Body::new(lattice, Material::rigid()).expect("body");
    let mut ws = Workspace::new(&body);
    let src = ElementId(37);
    let before: Vec<[f32; 3]> = body.positions().to_vec();
    let p = body.position(src).expect("source");
    let d = [0.0125f32, -0.003, 0.0071];
    let r = body.deform(&mut ws, src, [p[0] + d[0], p[1] + d[1], p[2] + d[2]], Pass::All).expect("deform");
    assert_eq!(r.fraction, 1.0);
    assert_eq!(r.moved as usize, body.element_count());
    for (a, b) in before.iter().zip(body.positions()) {
        for k in 0..3 {
            assert!(
                (b[k] - a[k] - d[k]).abs() < 1e-6,
                "element moved by {:?}, expected {d:?}",
                [b[0] - a[0]]
            );
        }
    }
}

#[test]
fn pulled_chain_follows_the_closed_form() {
    let (n, h, s) = (20usize, 0.01f32, 1.25f32);
    let lattice = Lattice::sheet(n, 1, h).expect("chain");
    let mut body = Body::new(lattice, Material::relative(s, 0.8, 0.3)).expect("body");
    let mut ws = Workspace::new(&body);
    let d = 0.031f32;
    let end = ElementId((n - 1) as u32);
    let p = body.position(end).expect("end");
    body.deform(&mut ws, end, [p[0] + d, p[1], p[2]], Pass::All).expect("deform");
    for k in 0..n {
        let e = ElementId((n - 1 - k) as u32);
        let moved = body.position(e).expect("element")[0] - body.lattice().rest_positions()[e.index()][0];
        let expected = (d - k as f32 * (s - 1.0) * h).max(0.0);
        assert!(
            (moved - expected).abs() < 1e-6,
            "element {k} from the end moved {moved}, expected {expected}"
        );
    }
}

#[test]
fn blocked_move_is_bisected_to_the_permissible_length() {
    let (n, h, s) = (10usize, 0.01f32, 1.2f32);
    let lattice = Lattice::sheet(n, 1, h).expect("chain");
    let mut body = Body::new(lattice, Material::relative(s, 0.8, 0.3)).expect("body");
    body.set_pinned(ElementId(0), true).expect("pin");
    let mut ws = Workspace::new(&body);
    let end = ElementId((n - 1) as u32);
    let p = body.position(end).expect("end");
    // The chain of 9 links can stretch by 9 (s - 1) h = 0.018 before the pin would have to move.
    let allowed = (n - 1) as f32 * (s - 1.0) * h;
    let r = body.deform(&mut ws, end, [p[0] + 0.05, p[1], p[2]], Pass::All).expect("deform");
    assert!(r.fraction < 1.0 && r.attempts > 1);
    let went = r.achieved[0] - p[0];
    assert!((went - allowed).abs() < 1e-4, "went {went}, allowed {allowed}");
    assert_eq!(body.position(ElementId(0)).expect("pin"), [0.0, 0.0, 0.0]);
    for l in 0..body.link_count() {
        let v = body.link_violation(dissect::chainmail::LinkId(l as u32)).expect("link");
        assert!(v < 1e-5, "link {l} violated by {v}");
    }
}

#[test]
fn unblocked_move_toward_rest_is_not_refused_by_a_pin() {
    let lattice = Lattice::sheet(5, 1, 0.01).expect("chain");
    let mut body = Body::new(lattice, Material::relative(1.2, 0.8, 0.3)).expect("body");
    body.set_pinned(ElementId(0), true).expect("pin");
    let mut ws = Workspace::new(&body);
    let end = ElementId(4);
    let r = body.deform(&mut ws, end, [0.05, 0.0, 0.0], Pass::All).expect("pull");
    assert!(r.fraction < 1.0);
    let back = body.deform(&mut ws, end, [0.041, 0.0, 0.0], Pass::All).expect("back");
    assert_eq!(back.fraction, 1.0);
}

#[test]
fn plane_and_normal_passes_touch_only_their_coordinates() {
    let lattice = Lattice::sheet(8, 8, 0.01).expect("sheet");
    let mut body = Body::new(lattice, Material::relative(1.1, 0.9, 0.2)).expect("body");
    let mut ws = Workspace::new(&body);
    let src = ElementId(27);
    body.deform(&mut ws, src, [0.05, 0.05, 0.04], Pass::Plane).expect("plane");
    assert!(body.positions().iter().all(|p| p[2] == 0.0));
    let before: Vec<[f32; 3]> = body.positions().to_vec();
    body.deform(&mut ws, src, [0.0, 0.0, 0.04], Pass::Normal).expect("normal");
    for (a, b) in before.iter().zip(body.positions()) {
        assert_eq!((a[0], a[1]), (b[0], b[1]));
    }
    assert!((body.position(src).expect("src")[2] - 0.04).abs() < 1e-7);
    assert!(body.positions().iter().filter(|p| p[2] > 0.0).count() > 1);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let lattice = Lattice::sheet(4, 4, 0.01).expect("sheet");
    let mut body = Body::new(lattice, Material::default()).expect("body");
    let mut ws = Workspace::new(&body);
    assert!(body.deform(&mut ws, ElementId(16), [0.0; 3], Pass::All).is_err());
    assert!(body.deform(&mut ws, ElementId(1), [f32::NAN, 0.0, 0.0], Pass::All).is_err());
    assert!(body.set_pinned(ElementId(99), true).is_err());
    assert!(Body::new(Lattice::sheet(2, 2, 1.0).expect("l"), Material::relative(0.5, 0.8, 0.1)).is_err());
    assert!(Lattice::sheet(2, 2, f32::NAN).is_err());
}
