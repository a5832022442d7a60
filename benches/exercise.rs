//! The exercise itself: the meninges scene at a given resolution, played with the careful
//! script (`scenes/scripts/meninges_careful.ron`) step by step, as a trainee's session runs it.
//!
//! Criterion reports the mean step; p50 and p99 of the steps timed are printed after each bench
//! (a step's cost depends on where in the script it falls, so the tail matters as much as the mean).
//! When the script ends the world is rebuilt outside the timed region and the script starts again.

use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dissect::runner::{Player, TimeStats};
use dissect::scene::{Scene, Script, Tissue as SceneTissue};
use dissect::simulation::World;

const MENINGES: &str = include_str!("../scenes/meninges.ron");
const CAREFUL: &str = include_str!("../scenes/scripts/meninges_careful.ron");

fn scene_at(nu: u32, nv: u32) -> Scene {
    let mut scene = Scene::from_str(MENINGES, "scenes/meninges.ron").expect("meninges scene");
    if let SceneTissue::Layers(l) = &mut scene.tissue {
        l.resolution = [nu, nv];
    }
    scene
}

struct Session {
    scene: Scene,
    script: Script,
    world: World,
    player: Player,
}

impl Session {
    fn new(scene: Scene, script: Script) -> Self {
        let world = scene.build_world(false).expect("world");
        let player = Player::new(script.0.clone());
        Self { scene, script, world, player }
    }

    /// One step of the script, timed; restarts the script (untimed) when it has ended.
    fn step(&mut self) -> Duration {
        self.player.feed(&mut self.world);
        if self.player.finished() && self.world.pending().is_empty() {
            self.world = self.scene.build_world(false).expect("world");
            self.player = Player::new(self.script.0.clone());
            self.player.feed(&mut self.world);
        }
        let t = Instant::now();
        self.world.step();
        t.elapsed()
    }
}

fn exercise_benches(c: &mut Criterion) {
    let script = Script::from_str(CAREFUL, "meninges_careful.ron").expect("careful script");
    let mut group = c.benchmark_group("exercise/meninges_careful");
    group.sample_size(10).measurement_time(Duration::from_secs(10)).warm_up_time(Duration::from_secs(2));
    for (nu, nv) in [(128u32, 96u32), (256, 192), (512, 384)] {
        let mut session = Session::new(scene_at(nu, nv), script.clone());
        let mut samples: Vec<f32> = Vec::new();
        group.throughput(Throughput::Elements(2 * u64::from(nu) * u64::from(nv)));
        group.bench_function(format!("{nu}x{nv}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let d = session.step();
                    samples.push(d.as_secs_f32() * 1e6);
                    total += d;
                }
                total
            })
        });
        let s = TimeStats::of(&mut samples);
        println!(
            "exercise/meninges_careful/{nu}x{nv}: {} steps, mean {:.0} µs, p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs",
            samples.len(),
            s.mean,
            s.p50,
            s.p99,
            s.max
        );
    }
    group.finish();
}

criterion_group!(benches, exercise_benches);
criterion_main!(benches);
