//! The simulation thread's timing: the default exercise (the dural flap) stepped on its thread at 1 kHz
//! (`runner::SimThread`) with the hand idle (as the trainer measured in the README), while this
//! thread reads the published frame sixty times a second as the windows do.
//!
//! `simulation/thread/jitter`: criterion's figure is the wall time per step the thread kept while
//! this thread waited for a batch of `iters` steps (1 ms when it keeps 1 kHz; a batch ends at the first
//! frame published after its last step, so short batches read high); the 99th percentile of
//! the lateness of a step's start after its deadline over every step of the run (the budget:
//! 200 µs on the 2-core machine), the worst step-to-step jitter of the last second, the achieved
//! steps per second and how the thread was scheduled (real-time where the system grants it,
//! `runner::priority`) are printed after the bench. Run it beside the trainer's windows
//! (`dissect --frames 100000` under Xvfb) to measure the case.

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use dissect::runner::{Episode, SimThread, Source};
use dissect::scene::Scene;
use dissect::training::Assessor;

fn episode() -> Episode {
    let scene = Scene::default_scene().expect("default scene");
    let world = scene.build_world(false).expect("world");
    let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
    Episode::new(world, assessor, Source::Live)
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
    group.sample_size(10).measurement_time(Duration::from_secs(6)).warm_up_time(Duration::from_secs(1));
    group.bench_function("jitter", |b| {
        b.iter_custom(|iters| {
            let first = sim.latest().pace.total_steps;
            let t = Instant::now();
            read_until(&mut sim, |f| f.pace.total_steps >= first + iters);
            t.elapsed()
        });
    });
    group.finish();
    let pace = sim.latest().pace;
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "simulation/thread/jitter: p99 lateness of a step's start {:.0} µs over {} steps at {:.0} Hz \
         ({:.0} steps/s overall; last second: {:.0} steps/s, worst lateness {:.0} µs, worst jitter {:.0} µs; {})",
        pace.total_p99_late_us,
        pace.total_steps,
        pace.rate_hz,
        pace.total_steps as f64 / seconds,
        pace.steps_per_second,
        pace.worst_late_us,
        pace.worst_jitter_us,
        sim.scheduling()
    );
    let _ = sim.stop();
}

criterion_group!(benches, thread_benches);
criterion_main!(benches);
