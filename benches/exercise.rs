//! The exercises themselves, at a given resolution, played with their careful scripts step by step, as
//! a trainee's session runs them: `exercise/meninges_careful/...` (the meninges scene, the layers
//! lifted and the fibres cut under them), `exercise/meninges_probe/...` (the same scene, the probe
//! pressing the dura, held, slid across and held) and `exercise/durotomy_careful/...` (the default
//! exercise: a U-shaped flap cut in the dura, reflected, the arachnoid freed under it), and
//! `exercise/volume/{16x16,24x24,32x32}` (the bundled volume of elastic cells at n³, pressed by the
//! probe and a corner pulled up by the forceps).
//!
//! Criterion reports the mean step; p50 and p99 of the steps timed are printed after each bench
//! (a step's cost depends on where in the script it falls, so the tail matters as much as the mean),
//! with the p99 of the steps' CPU time (the thread's own: on a busy machine the wall time's tail is
//! mostly other processes taking the core). After each exercise, how many times its mean step grows
//! from one resolution to the next (issue 14's budget: under 2 from 256 x 192 to 512 x 384). When the
//! script ends the world is rebuilt outside the timed region and the script starts again. The steps
//! run as the trainer's simulation thread runs them: on a worker of a rayon pool of its own
//! (`dissect::chainmail::worker_pool`).

use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dissect::runner::{Player, TimeStats};
use dissect::scene::{Scene, Script, Tissue as SceneTissue};
use dissect::simulation::World;

const MENINGES: &str = include_str!("../scenes/meninges.ron");
const CAREFUL: &str = include_str!("../scenes/scripts/meninges_careful.ron");
const PROBE: &str = include_str!("../scenes/scripts/meninges_probe.ron");
const DUROTOMY: &str = include_str!("../scenes/durotomy.ron");
const DUROTOMY_CAREFUL: &str = include_str!("../scenes/scripts/durotomy_careful.ron");
const VOLUME: &str = include_str!("../scenes/volume.ron");
const VOLUME_SCRIPT: &str = include_str!("../scenes/scripts/volume.ron");

/// The scene at `nu × nv` per layer; a volume at `nu × nu × nu` (`nv` unused).
fn scene_at(text: &str, nu: u32, nv: u32) -> Scene {
    Scene::from_str(text, "scene").expect("scene").with_resolution(nu, nv)
}

/// The elements of `scene` at that size: two layers, or a volume's cube.
fn elements(scene: &str, nu: u32, nv: u32) -> u64 {
    match scene_at(scene, nu, nv).tissue {
        SceneTissue::Volume(_) => u64::from(nu).pow(3),
        _ => 2 * u64::from(nu) * u64::from(nv),
    }
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

    /// One step of the script, timed (wall and the thread's CPU time); restarts the script (untimed)
    /// when it has ended, and says so (the session before this step was played to its end).
    fn step(&mut self) -> (Duration, Duration, bool) {
        self.player.feed(&mut self.world);
        let restarted = self.player.finished() && self.world.pending().is_empty();
        if restarted {
            self.world = self.scene.build_world(false).expect("world");
            self.player = Player::new(self.script.0.clone());
            self.player.feed(&mut self.world);
        }
        let (t, cpu) = (Instant::now(), cpu_time::ThreadTime::now());
        self.world.step();
        (t.elapsed(), cpu.elapsed(), restarted)
    }
}

fn exercise_benches(c: &mut Criterion) {
    // Stepped as the trainer's simulation thread steps: a worker of a pool of its own.
    let _pool = dissect::chainmail::worker_pool("bench").ok();
    let meninges = Script::from_str(CAREFUL, "meninges_careful.ron").expect("careful script");
    exercise(c, "meninges_careful", MENINGES, &meninges, &[(128, 96), (256, 192), (512, 384)]);
    let probe = Script::from_str(PROBE, "meninges_probe.ron").expect("probe script");
    exercise(c, "meninges_probe", MENINGES, &probe, &[(128, 96), (256, 192), (512, 384)]);
    let durotomy = Script::from_str(DUROTOMY_CAREFUL, "durotomy_careful.ron").expect("careful script");
    exercise(c, "durotomy_careful", DUROTOMY, &durotomy, &[(64, 48), (128, 96), (256, 192)]);
    // The volume of elastic cells, pressed by the probe and pulled up by the forceps, at 16³ (the
    // scene's), 24³ and 32³.
    let volume = Script::from_str(VOLUME_SCRIPT, "volume.ron").expect("volume script");
    exercise(c, "volume", VOLUME, &volume, &[(16, 16), (24, 24), (32, 32)]);
}

fn exercise(c: &mut Criterion, name: &str, scene: &str, script: &Script, sizes: &[(u32, u32)]) {
    let mut group = c.benchmark_group(format!("exercise/{name}"));
    // Each size's mean step over whole sessions, for the growth from one size to the next (issue 14's
    // budget: 512 x 384's mean under twice 256 x 192's).
    let mut means: Vec<((u32, u32), f32)> = Vec::new();
    group.sample_size(10).measurement_time(Duration::from_secs(10)).warm_up_time(Duration::from_secs(2));
    for &(nu, nv) in sizes {
        // Built on first use: a bench the filter leaves out builds no world.
        let mut session: Option<Session> = None;
        let (mut samples, mut cpu): (Vec<f32>, Vec<f32>) = (Vec::new(), Vec::new());
        // The samples of the sessions played to their end: the statistics printed are over whole
        // sessions, as a trainee plays them. (Criterion stops within a session: at 512 x 384 about
        // nine sessions are timed, and an unfinished last one, its quiet end missing, raised the
        // printed mean by several per cent.)
        let mut whole = 0usize;
        group.throughput(Throughput::Elements(elements(scene, nu, nv)));
        group.bench_function(format!("{nu}x{nv}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                let session =
                    session.get_or_insert_with(|| Session::new(scene_at(scene, nu, nv), script.clone()));
                for _ in 0..iters {
                    let (d, c, restarted) = session.step();
                    if restarted {
                        whole = samples.len();
                    }
                    samples.push(d.as_secs_f32() * 1e6);
                    cpu.push(c.as_secs_f32() * 1e6);
                    total += d;
                }
                total
            })
        });
        if samples.is_empty() {
            continue;
        }
        // (All the samples if not one session was played to its end.)
        let n = if whole > 0 { whole } else { samples.len() };
        let (samples, cpu) = (&mut samples[..n], &mut cpu[..n]);
        let s = TimeStats::of(samples);
        let c = TimeStats::of(cpu);
        println!(
            "exercise/{name}/{nu}x{nv}: {} steps ({}), mean {:.0} µs, p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs; CPU time p99 {:.0} µs, max {:.0} µs",
            samples.len(),
            if whole > 0 { "whole sessions" } else { "no session played to its end" },
            s.mean,
            s.p50,
            s.p99,
            s.max,
            c.p99,
            c.max
        );
        means.push(((nu, nv), s.mean));
    }
    group.finish();
    for pair in means.windows(2) {
        let [((u0, v0), m0), ((u1, v1), m1)] = [pair[0], pair[1]];
        if m0 > 0.0 {
            println!("exercise/{name}: the mean step grows {:.2} times from {u0}x{v0} to {u1}x{v1}", m1 / m0);
        }
    }
}

criterion_group!(benches, exercise_benches);
criterion_main!(benches);
