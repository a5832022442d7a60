//! Runs the engine's two hot loops once each on a 512 x 512 sheet, for instruction-count profiling:
//! `valgrind --tool=callgrind target/release/examples/profile_engine`.
use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n = 512;
    let mut body = Body::new(Lattice::sheet(n, n, 0.001)?, Material::rigid())?;
    let mut ws = Workspace::new(&body);
    let src = ElementId((n * n / 2) as u32);
    let t = std::time::Instant::now();
    let d = body.deform(&mut ws, src, [0.26, 0.26, 0.0], Pass::All)?;
    let t1 = t.elapsed();
    let t = std::time::Instant::now();
    body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All);
    let t2 = t.elapsed();
    println!(
        "moved {} in {:?} ({:.2} ns/elem); one sweep {:?} ({:.2} ns/elem)",
        d.moved,
        t1,
        t1.as_nanos() as f64 / d.moved as f64,
        t2,
        t2.as_nanos() as f64 / (n * n) as f64
    );
    Ok(())
}
