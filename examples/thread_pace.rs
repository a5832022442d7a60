//! The simulation thread's timing while a trainee works: an exercise's script played on the thread
//! (`runner::SimThread`) at 1 kHz, at a resolution, while this thread takes the published frame
//! sixty times a second and finishes it as the windows do. Prints the lateness of the steps' starts
//! after their deadlines over the whole session (p99 and worst), what the thread reports, and the
//! score. The careful meninges script by default: `target/release/examples/thread_pace 512 384`;
//! another layered scene and script after the resolution:
//! `thread_pace 256 192 scenes/durotomy.ron scenes/scripts/durotomy_careful.ron`. Publishing a frame
//! is the thread's work too, so this is where its cost shows; the exercise benches and `dissect run`
//! step without publishing.
use std::time::{Duration, Instant};

use dissect::runner::SimThread;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv) = (arg(1, 256), arg(2, 192));
    let mut sim = SimThread::spawn(common::exercise_episode(nu, nv)?)?;
    let (t, mut frames) = (Instant::now(), 0u32);
    let trace = std::env::var_os("TRACE").is_some();
    // READ_EVERY=n: the reader looks only at every n-th frame time (1 as the windows do), to see what
    // its finishing of frames on the other core costs the thread.
    let every = std::env::var("READ_EVERY").ok().and_then(|v| v.parse().ok()).unwrap_or(1u32).max(1);
    loop {
        frames += 1;
        if !frames.is_multiple_of(every) {
            std::thread::sleep(Duration::from_millis(16));
            continue;
        }
        if sim.latest().finished {
            break;
        }
        if trace {
            let f = sim.latest();
            eprintln!(
                "{} {:.0} {:.0} {}",
                f.view.step_count(),
                f.pace.worst_late_us,
                f.pace.p99_late_us,
                f.pace.realtime
            );
        }
        if t.elapsed() > Duration::from_secs(120) {
            return Err("the session did not end within two minutes".into());
        }
        std::thread::sleep(Duration::from_millis(16));
    }
    let frame = sim.latest();
    let (pace, score) = (frame.pace, frame.assessment.as_ref().map_or(0.0, |a| a.score));
    println!(
        "{nu} x {nv}: {} steps in {:.2} s, lateness of a step's start p99 {:.0} µs (last second: p99 {:.0}, worst {:.0} µs), \
         mean step {:.0} µs, {frames} frames read, score {score:.2}, {}",
        pace.total_steps,
        t.elapsed().as_secs_f64(),
        pace.total_p99_late_us,
        pace.p99_late_us,
        pace.worst_late_us,
        pace.mean_step_us,
        sim.scheduling()
    );
    let _ = sim.stop();
    Ok(())
}
