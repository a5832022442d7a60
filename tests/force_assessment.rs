//! Forces in newtons on the default exercise: the tissue at rest pushes nothing, a careful dissection
//! handles it with much less force than a careless one, and the figures reach `metrics.json`'s
//! `assessment.force`.

use dissect::runner::run;
use dissect::scene::{Scene, Script};
use dissect::simulation::Command;
use dissect::simulation::{Forces, InstrumentKind};

fn scene() -> Scene {
    Scene::load("scenes/meninges.ron").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_grasp_at_rest_feels_nothing() {
    let scene = scene();
    let mut world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
    let p = world.tissue().surface_point(0.5, 0.5, 0.003);
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(p));
    world.push(Command::Grasp);
    for _ in 0..20 {
        world.step();
    }
    let f = Forces::magnitude(world.forces().forceps);
    assert!(world.instrument().grasped.is_some());
    assert!(f < 1e-3, "{f} N at rest");
    // Lifting by a millimetre pulls back down.
    let q = world.tissue().surface_point(0.5, 0.5, 0.004);
    world.push(Command::MoveTo(q));
    for _ in 0..50 {
        world.step();
    }
    let f = world.forces().forceps;
    assert!(f[1] < 0.0, "{f:?}");
}

fn peak(script: &str) -> dissect::training::ForceAssessment {
    let scene = scene();
    let script = Script::load(script).unwrap_or_else(|e| panic!("{e}"));
    let out = run(&scene, "meninges", &script, "script", None, None).unwrap_or_else(|e| panic!("{e}"));
    out.metrics.assessment.unwrap_or_else(|| panic!("no assessment")).force
}

#[test]
fn careful_hands_use_far_less_force_than_careless_ones() {
    let careful = peak("scenes/scripts/meninges_careful.ron");
    let careless = peak("scenes/scripts/meninges_careless.ron");
    eprintln!("careful {careful:?}\ncareless {careless:?}");
    assert!(careful.total.peak_n < 0.5 * careless.total.peak_n, "{careful:?}\n{careless:?}");
    assert_eq!(careful.instruments.len(), 3);
}

/// Forceps held still on a lifted dura: the force is read again while nothing moves (the same
/// figure every step, the sum over the held elements' links as they lie), and is measured afresh
/// the step the tissue changes (a stiffer material is felt at once).
#[test]
fn a_still_grasp_feels_the_tissue_as_it_is() {
    let scene = scene();
    let mut world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(world.tissue().surface_point(0.5, 0.5, 0.003)));
    world.push(Command::Grasp);
    world.push(Command::MoveTo(world.tissue().surface_point(0.5, 0.5, 0.005)));
    for _ in 0..400 {
        world.step();
    }
    let held: Vec<_> = world.tissue().held().collect();
    assert!(held.len() > 1, "the jaws hold {} elements", held.len());
    let pull = world.tissue().force_on(&held);
    let f = world.forces().forceps;
    assert!(Forces::magnitude(f) > 1e-3, "{f:?}: nothing felt");
    world.step();
    assert_eq!(world.forces().forceps, f, "a still step felt another force");
    assert_eq!(world.tissue().force_on(&held), pull, "the tissue moved");
    // Every material twice as stiff (Young's modulus): the same shape pulls twice as hard.
    let materials = world.tissue().body().materials().to_vec();
    for (k, m) in materials.into_iter().enumerate() {
        let id = dissect::chainmail::MaterialId(k as u16);
        world.push(Command::SetMaterial(
            id,
            dissect::chainmail::Material { young_modulus: 2.0 * m.young_modulus, ..m },
        ));
    }
    world.step();
    let stiffer = world.forces().forceps;
    assert!(Forces::magnitude(stiffer) > 1.5 * Forces::magnitude(f), "{stiffer:?} against {f:?}");
}
