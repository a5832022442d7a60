//! The simulation thread's timing: the default exercise (the dural flap) stepped on its thread at 1 kHz
//! (`runner::SimThread`), playing the careful script (and, past its end, stepping without input),
//! while this thread reads the published frame sixty times a second as the windows do.
//!
//! `simulation/thread/jitter`: criterion's figure is the mean lateness of a step's start after its
//! deadline (each batch of `iters` steps is timed as the lateness it accumulated, not as wall time);
//! the 99th percentile of that lateness over every step of the run (the budget: 200 µs on the
//! 2-core machine) and the achieved steps per second are printed after the bench.

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use dissect::runner::{Episode, Player, SimThread, Source};
use dissect::scene::{Scene, Script};
use dissect::training::Assessor;

const CAREFUL: &str = include_str!("../scenes/scripts/durotomy_careful.ron");

fn episode() -> Episode {
    let scene = Scene::default_scene().expect("default scene");
    let script = Script::from_str(CAREFUL, "durotomy_careful.ron").expect("careful script");
    let world = scene.build_world(false).expect("world");
    let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
    let mut episode = Episode::new(world, assessor, Source::Script(Player::new(script.0)));
    episode.run_past_end(true);
    episode
}

/// Reads the published frame as a window at 60 fps would, until `until` says stop.
fn read_until(sim: &mut SimThread, mut until: impl FnMut(&dissect::runner::Published) -> bool) {
    loop {
        let frame = sim.latest();
        if until(frame) {
            return;
        }
        std::thread::sleep(Duration::from_millis(16));
    }
}

fn thread_benches(c: &mut Criterion) {
    let mut sim = SimThread::spawn(episode()).expect("simulation thread");
    let rate = sim.latest().pace.rate_hz;
    assert!((rate - 1000.0).abs() < 1e-6, "the default exercise steps at 1 kHz (it says {rate})");
    let started = Instant::now();
    let mut group = c.benchmark_group("simulation/thread");
    group.sample_size(10).measurement_time(Duration::from_secs(10)).warm_up_time(Duration::from_secs(2));
    group.bench_function("jitter", |b| {
        b.iter_custom(|iters| {
            let first = sim.latest().pace;
            read_until(&mut sim, |f| f.pace.total_steps >= first.total_steps + iters);
            let last = sim.latest().pace;
            // The lateness accumulated over the batch, per step as criterion divides it.
            let late = (last.total_late_s - first.total_late_s).max(0.0);
            let steps = (last.total_steps - first.total_steps).max(1);
            Duration::from_secs_f64(late * iters as f64 / steps as f64)
        });
    });
    group.finish();
    let pace = sim.latest().pace;
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "simulation/thread/jitter: p99 lateness of a step's start {:.0} µs over {} steps at {:.0} Hz \
         ({:.0} steps/s overall; last second: {:.0} steps/s, worst lateness {:.0} µs, worst jitter {:.0} µs)",
        pace.total_p99_late_us,
        pace.total_steps,
        pace.rate_hz,
        pace.total_steps as f64 / seconds,
        pace.steps_per_second,
        pace.worst_late_us,
        pace.worst_jitter_us
    );
    let _ = sim.stop();
}

criterion_group!(benches, thread_benches);
criterion_main!(benches);
