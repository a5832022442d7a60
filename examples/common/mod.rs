//! What several examples share: the careful meninges exercise at a resolution, as the trainer plays it.
use dissect::runner::{Episode, Player, Source};
use dissect::scene::{Scene, Script};

/// The default meninges scene at `nu × nv` per layer and the careful script, as an episode that plays
/// the script and assesses it against the scene's goals.
pub fn careful_episode(nu: u32, nv: u32) -> Result<Episode, Box<dyn std::error::Error>> {
    let scene = Scene::from_str(include_str!("../../scenes/meninges.ron"), "scenes/meninges.ron")?
        .with_resolution(nu, nv);
    let script =
        Script::from_str(include_str!("../../scenes/scripts/meninges_careful.ron"), "meninges_careful.ron")?;
    let world = scene.build_world(false)?;
    let assessor = scene.goals.clone().map(|g| dissect::training::Assessor::new(g, &world));
    Ok(Episode::new(world, assessor, Source::Script(Player::new(script.0))))
}
