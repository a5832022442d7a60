//! Plays the meninges exercise with the careful script at a resolution and prints one line per step
//! (tab separated: step, total µs, each phase's µs, elements moved by each pass, relaxation sweeps,
//! the disturbed region's size), for finding which steps of a session cost what:
//! `target/release/examples/exercise_trace 256 192 > trace.tsv`.
use std::time::Instant;

use dissect::runner::Player;
use dissect::scene::{Scene, Script, Tissue as SceneTissue};

const MENINGES: &str = include_str!("../scenes/meninges.ron");
const CAREFUL: &str = include_str!("../scenes/scripts/meninges_careful.ron");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv) = (arg(1, 256), arg(2, 192));
    let mut scene = Scene::from_str(MENINGES, "scenes/meninges.ron")?;
    if let SceneTissue::Layers(l) = &mut scene.tissue {
        l.resolution = [nu, nv];
    }
    let script = Script::from_str(CAREFUL, "meninges_careful.ron")?;
    let mut world = scene.build_world(false)?;
    let mut player = Player::new(script.0.clone());
    println!(
        "step\ttotal_us\tinput\tchain\tnormal\trelax\tcontact\tcuts\tforces\tmoved_chain\tmoved_normal\tsweeps\tactive\twall_us"
    );
    loop {
        player.feed(&mut world);
        if player.finished() && world.pending().is_empty() {
            break;
        }
        let t = Instant::now();
        let c = world.step();
        let wall = t.elapsed().as_secs_f32() * 1e6;
        let ph: Vec<String> = c.phase_us.iter().map(|p| format!("{p:.1}")).collect();
        println!(
            "{}\t{:.1}\t{}\t{}\t{}\t{}\t{}\t{:.1}",
            c.step,
            c.total_us(),
            ph.join("\t"),
            c.moved_chain,
            c.moved_normal,
            c.relax_sweeps,
            world.tissue().active_count(),
            wall
        );
    }
    Ok(())
}
