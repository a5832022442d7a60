//! Runs the engine's two hot loops on a 512 x 512 sheet (the benches' bodies) and prints their speed,
//! for profiling:
//! `perf record target/release/examples/profile_engine 200 [SIDE [chain|sweep]]`, or with one repetition under
//! `valgrind --tool=callgrind` for instruction counts. `SRC=i` moves element `i` rather than the
//! bench's source (`SIDE² / 2`, the first element of the middle row).
use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reps: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1);
    let n: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(512);
    // A third argument names the one loop to run: `chain` or `sweep`.
    let only = std::env::args().nth(3);
    let run = |name: &str| only.as_deref().is_none_or(|o| o == name);
    let mut body = Body::new(Lattice::sheet(n, n, 0.001)?, Material::rigid())?;
    let mut ws = Workspace::new(&body);
    let src = ElementId(std::env::var("SRC").ok().and_then(|s| s.parse().ok()).unwrap_or(n * n / 2) as u32);
    let t = std::time::Instant::now();
    let mut moved = 0;
    for k in 0..if run("chain") { reps } else { 0 } {
        let s = if k % 2 == 0 { 0.002 } else { -0.002 };
        let p = body.position(src)?;
        moved += body.deform(&mut ws, src, [p[0] + s, p[1] + s, 0.0], Pass::All)?.moved;
    }
    let t1 = t.elapsed();
    // The sweep bench's body: a soft sheet after 200 seeded random pokes.
    let mut body = Body::new(Lattice::sheet(n, n, 0.001)?, Material::relative(1.2, 0.8, 0.3))?;
    let mut seed = 11u64;
    let mut rng = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 40) as f32) / ((1u64 << 24) as f32)
    };
    for _ in 0..200 {
        let e = ElementId((rng() * (n * n) as f32) as u32);
        let p = body.position(e)?;
        let t = [p[0] + 0.01 * (rng() - 0.5), p[1] + 0.01 * (rng() - 0.5), 0.005 * rng()];
        body.deform(&mut ws, e, t, Pass::All)?;
    }
    // Each sweep timed on its own; the median is reported beside the mean (a shared machine's noise
    // only ever adds time, in bursts).
    let mut times = Vec::with_capacity(reps as usize);
    let t = std::time::Instant::now();
    for _ in 0..if run("sweep") { reps } else { 0 } {
        let t = std::time::Instant::now();
        body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All);
        times.push(t.elapsed());
    }
    let t2 = t.elapsed();
    times.sort();
    let median = times.get(times.len() / 2).copied().unwrap_or_default();
    println!(
        "chain reaction: {:.2} ns per moved element; one sweep: {:.2} ns per element (median {:.2})",
        t1.as_nanos() as f64 / moved as f64,
        t2.as_nanos() as f64 / (reps as f64 * (n * n) as f64),
        median.as_nanos() as f64 / (n * n) as f64,
    );
    Ok(())
}
