//! The bundled meninges exercise scores a careful dissection (only the target's fibres cut, layers
//! separated) above a careless one (cuts through the dura and outside the target), with the damage
//! counted where it happened.

use std::path::PathBuf;

use dissect::runner;
use dissect::scene::{Scene, Script};
use dissect::training::Assessment;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn assess(script: &str) -> Assessment {
    let scene = Scene::load(root().join("scenes/meninges.ron")).expect("scene");
    let script = Script::load(root().join("scenes/scripts").join(script)).expect("script");
    let out = runner::run(&scene, "meninges.ron", &script, "script", None, None).expect("run");
    out.metrics.assessment.expect("the meninges scene has goals")
}

#[test]
fn careful_beats_careless() {
    let careful = assess("meninges_careful.ron");
    let careless = assess("meninges_careless.ron");
    assert!(
        careful.score > careless.score + 30.0,
        "careful {} vs careless {}",
        careful.score,
        careless.score
    );
    assert!(careful.completion > 0.95, "careful completion {}", careful.completion);
    assert!(careful.separation_m >= 0.004, "careful separation {}", careful.separation_m);
    assert_eq!(careful.layer_links_cut, 0);
    assert_eq!(careful.connective_cut_outside, 0);
    assert_eq!(careful.forbidden_links_broken, 0);
    assert!(careless.layer_links_cut > 0, "the careless script cut through the dura");
    assert!(careless.connective_cut_outside > 0, "and fibres outside the target");
    assert!(careless.forbidden_links_broken > 0, "and into the forbidden strip");
    assert!(careless.completion < careful.completion);
}
