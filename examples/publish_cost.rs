//! What publishing a frame costs the simulation thread, and what finishing it costs the reader: plays
//! the careful meninges script at a resolution and, every 16 steps (the thread publishes every sixtieth
//! of a second at 1 kHz), times `Published::fill` (on the thread that steps), `Published::finish` (on
//! the window's thread), and the parts of the fill: the raw snapshot (and within it the fibres and
//! their tear stretch), the assessment and the coach's advice. Prints mean, p50, p99 and max of each, microseconds:
//! `target/release/examples/publish_cost 512 384`; another layered scene and script after the
//! resolution, as for `thread_pace`.
use std::time::Instant;

use dissect::runner::Published;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv) = (arg(1, 256), arg(2, 192));
    let _pool = dissect::chainmail::worker_pool("publish")?;
    let mut episode = common::exercise_episode(nu, nv)?;
    let (mut frame, mut scratch) = (Published::default(), Published::default());
    let names =
        ["step", "fill", "finish", "raw snapshot", " of it fibres", " tear stretch", "assessment", "advice"];
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let us = |t: Instant| t.elapsed().as_secs_f64() * 1e6;
    loop {
        let t = Instant::now();
        if episode.step().is_none() {
            break;
        }
        times[0].push(us(t));
        if !episode.world().step_count().is_multiple_of(16) {
            continue;
        }
        let t = Instant::now();
        frame.fill(&episode);
        times[1].push(us(t));
        let t = Instant::now();
        frame.finish();
        times[2].push(us(t));
        let t = Instant::now();
        episode.world().snapshot_raw_into(&mut scratch.snapshot);
        times[3].push(us(t));
        let t = Instant::now();
        let s = &mut scratch.snapshot;
        episode.world().tissue().fill_fibres_raw(&mut s.fibre_stretch);
        times[4].push(us(t));
        let t = Instant::now();
        std::hint::black_box(episode.world().tissue().fibre_tear_stretch());
        times[5].push(us(t));
        let t = Instant::now();
        std::hint::black_box(episode.assessor().map(|a| a.assessment(episode.world())));
        times[6].push(us(t));
        let t = Instant::now();
        std::hint::black_box(episode.assessor().and_then(|a| a.advice(episode.world())));
        times[7].push(us(t));
    }
    let fibres = scratch.snapshot.fibre_stretch.len();
    println!("{nu} x {nv} ({fibres} fibres): microseconds (mean, p50, p99, max)");
    for (name, v) in names.iter().zip(&mut times) {
        v.sort_by(|a, b| a.total_cmp(b));
        let n = v.len().max(1);
        let at = |q: f64| v.get(((n - 1) as f64 * q) as usize).copied().unwrap_or(0.0);
        let mean = v.iter().sum::<f64>() / n as f64;
        println!(
            "{name:>13}: {mean:8.1} {:8.1} {:8.1} {:8.1}  ({} samples)",
            at(0.5),
            at(0.99),
            at(1.0),
            v.len()
        );
    }
    Ok(())
}
