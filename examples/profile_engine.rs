//! Runs the engine's two hot loops on a 512 x 512 sheet and prints their speed, for profiling:
//! `perf record target/release/examples/profile_engine 200 [SIDE]`, or with one repetition under
//! `valgrind --tool=callgrind` for instruction counts.
use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reps: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1);
    let n: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(512);
    let mut body = Body::new(Lattice::sheet(n, n, 0.001)?, Material::rigid())?;
    let mut ws = Workspace::new(&body);
    let src = ElementId((n * n / 2) as u32);
    let t = std::time::Instant::now();
    let mut moved = 0;
    for k in 0..reps {
        let s = if k % 2 == 0 { 0.002 } else { -0.002 };
        let p = body.position(src)?;
        moved += body.deform(&mut ws, src, [p[0] + s, p[1] + s, 0.0], Pass::All)?.moved;
    }
    let t1 = t.elapsed();
    let mut body = Body::new(Lattice::sheet(n, n, 0.001)?, Material::relative(1.2, 0.8, 0.3))?;
    let p = body.position(src)?;
    body.deform(&mut ws, src, [p[0] + 0.01, p[1] + 0.01, 0.005], Pass::All)?;
    let t = std::time::Instant::now();
    body.relax(&mut ws, RelaxBudget::sweeps(reps), RelaxRegion::All);
    let t2 = t.elapsed();
    println!(
        "chain reaction: {:.2} ns per moved element; one sweep: {:.2} ns per element",
        t1.as_nanos() as f64 / moved as f64,
        t2.as_nanos() as f64 / (reps as f64 * (n * n) as f64)
    );
    Ok(())
}
