//! Plays the meninges exercise with the careful script at a resolution and prints one line per step
//! (tab separated: step, total µs, each phase's µs, elements moved by each pass, relaxation sweeps,
//! the disturbed region's size, the step's wall and CPU time, the moves of the repair that keeps the
//! links within their limits), for finding which steps of a session cost what:
//! `target/release/examples/exercise_trace 256 192 > trace.tsv`; another layered scene and script
//! after the resolution: `exercise_trace 128 96 scenes/durotomy.ron scenes/scripts/durotomy_careful.ron`.
//!
//! To profile a window of steps (the careful script's final lift at 256 × 192 is steps 1370 to
//! 1470): `TRACE_WINDOW=1370,1470` runs those steps through `window_step`, which a profiler can
//! single out (`valgrind --tool=callgrind --toggle-collect='*window_step*'`), and with
//! `PERF_CTL=FIFO` also writes `enable` and `disable` to that control FIFO around them
//! (`perf record -D -1 --control fifo:FIFO`).
use std::time::Instant;

use dissect::runner::Player;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv) = (arg(1, 256), arg(2, 192));
    let (scene, script) = common::exercise(nu, nv)?;
    // The steps run as the trainer's simulation thread, `dissect run` and the exercise bench run them:
    // on a worker of a pool of its own (`dissect::chainmail::worker_pool`). `TRACE_POOL=global` steps
    // beside rayon's global pool instead, which the product never does: there a large region's split
    // scan waits for a helper from outside the pool, and on the Intel machine of 2026-11-28 the final
    // lift's normal pass at 256 x 192 took 405-418 us a step there against 376-383 on its own pool.
    let _pool = match std::env::var("TRACE_POOL").as_deref() {
        Ok("global") => {
            let _ = rayon::current_num_threads(); // the global pool's threads start now
            None
        }
        _ => Some(dissect::chainmail::worker_pool("trace")?),
    };
    // `TRACE_WAIT_MS`: a pause before the steps (to change the thread's scheduling from outside).
    if let Some(ms) = std::env::var("TRACE_WAIT_MS").ok().and_then(|m| m.parse().ok()) {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
    let mut world = scene.build_world(false)?;
    let mut player = Player::new(script.0.clone());
    println!(
        "step\ttotal_us\tinput\tchain\tnormal\trelax\tcontact\tcuts\tforces\tmoved_chain\tmoved_normal\tsweeps\tactive\twall_us\tcpu_us\trepairs"
    );
    let window: Vec<u64> = std::env::var("TRACE_WINDOW")
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_default();
    let window = match window[..] {
        [a, b] => a..b,
        _ => 0..0,
    };
    let fifo = std::env::var("PERF_CTL").ok();
    loop {
        let next = world.step_count() + 1;
        if let Some(f) = &fifo
            && (next == window.start || next == window.end)
        {
            let say = if next == window.start { "enable\n" } else { "disable\n" };
            std::fs::write(f, say)?;
        }
        player.feed(&mut world);
        if player.finished() && world.pending().is_empty() {
            break;
        }
        let (t, cpu) = (Instant::now(), cpu_time::ThreadTime::now());
        let c = if window.contains(&next) { window_step(&mut world) } else { world.step() };
        let wall = t.elapsed().as_secs_f32() * 1e6;
        // The thread's own CPU time: what the step costs without the time other processes took
        // the core (a busy machine's preemptions otherwise make the p99).
        let cpu = cpu.elapsed().as_secs_f32() * 1e6;
        let ph: Vec<String> = c.phase_us.iter().map(|p| format!("{p:.1}")).collect();
        println!(
            "{}\t{:.1}\t{}\t{}\t{}\t{}\t{}\t{:.1}\t{:.1}\t{}",
            c.step,
            c.total_us(),
            ph.join("\t"),
            c.moved_chain,
            c.moved_normal,
            c.relax_sweeps,
            world.tissue().active_count(),
            wall,
            cpu,
            c.limit_repairs
        );
    }
    Ok(())
}

/// One step of the profiled window (kept out of line so that a profiler can tell it apart).
#[inline(never)]
fn window_step(world: &mut dissect::simulation::World) -> dissect::simulation::StepCounters {
    world.step()
}
