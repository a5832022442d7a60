//! What several examples share: an exercise at a resolution, as the trainer plays it.
use dissect::runner::{Episode, Player, Source};
use dissect::scene::{Scene, Script};

/// The exercise named by the command line's third and fourth arguments (a layered scene's file and a
/// script's), else the default meninges scene and its careful script; the scene at `nu × nv` per
/// layer.
pub fn exercise(nu: u32, nv: u32) -> Result<(Scene, Script), Box<dyn std::error::Error>> {
    let (scene, script) = match (std::env::args().nth(3), std::env::args().nth(4)) {
        (Some(scene), Some(script)) => (Scene::load(&scene)?, Script::load(&script)?),
        (Some(_), None) => return Err("a scene's file wants a script's file after it".into()),
        _ => (
            Scene::from_str(include_str!("../../scenes/meninges.ron"), "scenes/meninges.ron")?,
            Script::from_str(
                include_str!("../../scenes/scripts/meninges_careful.ron"),
                "meninges_careful.ron",
            )?,
        ),
    };
    Ok((scene.with_resolution(nu, nv), script))
}

/// [`exercise`] as an episode that plays the script and assesses it against the scene's goals.
#[allow(dead_code)] // not every example that shares this module plays an episode
pub fn exercise_episode(nu: u32, nv: u32) -> Result<Episode, Box<dyn std::error::Error>> {
    let (scene, script) = exercise(nu, nv)?;
    let world = scene.build_world(false)?;
    let assessor = scene.goals.clone().map(|g| dissect::training::Assessor::new(g, &world));
    Ok(Episode::new(world, assessor, Source::Script(Player::new(script.0))))
}
