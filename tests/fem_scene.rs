//! A volume can choose the finite-element model in its scene: the bundled FEM block runs its script
//! (the probe pushes, the forceps pull a corner, letting go returns it to rest), and cutting it is
//! refused with a message that says why.

use std::path::PathBuf;

use dissect::runner;
use dissect::scene::{Action, Point, Scene, Script};
use dissect::simulation::Command;
use dissect::simulation::InstrumentKind;
use dissect::tissue::{CutDepth, FEM_CUT_REFUSED};

fn scene() -> Scene {
    Scene::load(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/fem_block.ron")).expect("scene")
}

#[test]
fn the_fem_block_is_grasped_and_pushed_and_returns_to_rest() {
    let scene = scene();
    let script = Script::load(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/scripts/fem_block.ron"))
        .expect("script");
    let pushed = runner::run(&scene, "scene", &script, "script", Some(350), None).expect("run");
    assert!(pushed.world.tissue().is_fem());
    let rest = pushed.world.tissue().body().lattice().rest_positions().to_vec();
    let moved = |w: &dissect::simulation::World| {
        w.tissue()
            .body()
            .positions()
            .iter()
            .zip(&rest)
            .map(|(p, r)| (p[1] - r[1]).abs())
            .fold(0.0f32, f32::max)
    };
    let mut w = pushed.world;
    let notice = w.tissue_mut().take_notice();
    assert!(moved(&w) > 0.003, "the probe did not dent the block ({notice:?})");
    let done = runner::run(&scene, "scene", &script, "script", None, None).expect("run");
    assert!(moved(&done.world) < 1e-6, "the block did not return to rest after the release");
}

#[test]
fn cutting_a_fem_block_is_refused_with_the_reason() {
    let scene = scene();
    let cut = Script(vec![
        Action::Select(InstrumentKind::Scalpel),
        Action::Cut {
            path: vec![Point::Surface(0.2, 0.5, 0.0), Point::Surface(0.8, 0.5, 0.0)],
            depth: CutDepth::Upper,
            steps: 10,
        },
    ]);
    let Err(e) = runner::run(&scene, "scene", &cut, "script", None, None) else {
        panic!("a cut script on a FEM block was accepted")
    };
    assert!(e.to_string().contains("fixed topology"), "{e}");
    // Live input gets the same answer, as a notice, and nothing is cut.
    let mut world = scene.build_world(false).expect("world");
    world.push(Command::Select(InstrumentKind::Scalpel));
    world.push(Command::MoveTo([-0.01, 0.035, 0.0]));
    world.push(Command::BeginCut);
    world.step();
    world.push(Command::MoveTo([0.01, 0.035, 0.0]));
    world.step();
    assert_eq!(world.tissue().damage().layer_links_cut, 0);
    assert_eq!(world.tissue_mut().take_notice().as_deref(), Some(FEM_CUT_REFUSED));
}
