//! Lifts the meninges' dura 5 mm at its centre with the forceps (in 0.5 s), holds it 0.5 s, lets go
//! and prints how far the grasped element stands from rest, the disturbed region's size and the step
//! times over the next 5 s: `target/release/examples/release_trace 256 192` (a resolution; `1`
//! after it drags the dura 5 mm sideways instead of lifting it).
use std::time::Instant;

use dissect::scene::{Scene, Tissue as SceneTissue};
use dissect::simulation::{Command, InstrumentKind, World};

const MENINGES: &str = include_str!("../scenes/meninges.ron");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv, drag) = (arg(1, 128), arg(2, 96), arg(3, 0) == 1);
    let mut scene = Scene::from_str(MENINGES, "scenes/meninges.ron")?;
    if let SceneTissue::Layers(l) = &mut scene.tissue {
        l.resolution = [nu, nv];
    }
    let mut world = scene.build_world(false)?;
    let t = world.tissue();
    let first = t.layers().first().ok_or("no layer")?.first as usize;
    let h = t.body().lattice().rest_positions().get(first).ok_or("no element")?[2];
    let dura = t.surface_point(0.5, 0.5, h);
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(dura));
    world.push(Command::Grasp);
    world.step();
    let e = world.instrument().grasped.ok_or("the forceps hold nothing")?;
    let start = world.tissue().world_position(e).ok_or("grasped element")?;
    let from_rest = |w: &World| {
        let t = w.tissue();
        let (p, r) = (t.body().positions()[e.index()], t.body().lattice().rest_positions()[e.index()]);
        1e3 * (0..3).map(|c| (p[c] - r[c]).powi(2)).sum::<f32>().sqrt()
    };
    for s in 1..=500 {
        let f = 0.005 * s as f32 / 500.0;
        let goal = if drag { [start[0] + f, start[1], start[2]] } else { [start[0], start[1] + f, start[2]] };
        world.push(Command::MoveTo(goal));
        world.step();
    }
    for _ in 0..500 {
        world.step();
    }
    println!("held: {:.3} mm from rest, region {}", from_rest(&world), world.tissue().active_count());
    world.push(Command::Release);
    println!("step\tmm_from_rest\tregion\tstep_us");
    let mut times = Vec::with_capacity(5000);
    let mut settled = None;
    for s in 1..=5000u32 {
        let t0 = Instant::now();
        world.step();
        let us = t0.elapsed().as_secs_f64() * 1e6;
        times.push(us);
        if settled.is_none() && world.tissue().active_count() == 0 {
            settled = Some(s);
        }
        if s <= 10 || s % 50 == 0 {
            println!("{s}\t{:.4}\t{}\t{us:.0}", from_rest(&world), world.tissue().active_count());
        }
    }
    match settled {
        Some(s) => println!("settled (the region empty) at step {s}"),
        None => println!("still settling after 5 000 steps: {} elements", world.tissue().active_count()),
    }
    // The steps while the tissue settled.
    let settling = &mut times[..settled.map_or(5000, |s| s as usize - 1)];
    settling.sort_by(f64::total_cmp);
    let n = settling.len().max(1);
    println!(
        "settling steps: mean {:.0} us, p50 {:.0}, p99 {:.0}",
        settling.iter().sum::<f64>() / n as f64,
        settling.get(n / 2).copied().unwrap_or(0.0),
        settling.get((n - 1) * 99 / 100).copied().unwrap_or(0.0)
    );
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((times.len() - 1) as f64 * p) as usize];
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    println!("release steps: mean {mean:.0} us, p50 {:.0}, p99 {:.0}, max {:.0}", q(0.5), q(0.99), q(1.0));
    Ok(())
}
