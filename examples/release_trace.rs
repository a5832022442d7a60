//! Lifts the meninges' dura 5 mm at its centre with the forceps (in 0.5 s), holds it 0.5 s, lets go
//! and prints how far the grasped element stands from rest, the disturbed region's size and the step
//! times over the next 5 s: `target/release/examples/release_trace 256 192` (a resolution; `1`
//! after it drags the dura 5 mm sideways instead of lifting it).
use std::time::Instant;

use dissect::scene::Scene;
use dissect::simulation::{Command, InstrumentKind, World};

const MENINGES: &str = include_str!("../scenes/meninges.ron");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, d: u32| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (nu, nv, drag) = (arg(1, 128), arg(2, 96), arg(3, 0) == 1);
    // The steps run on a worker of a pool of their own, as the trainer's simulation thread and
    // `dissect run` run them (see `exercise_trace`).
    let _pool = dissect::chainmail::worker_pool("trace")?;
    let scene = Scene::from_str(MENINGES, "scenes/meninges.ron")?.with_resolution(nu, nv);
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
    let slow: Option<f64> = std::env::var("RELEASE_SLOW").ok().and_then(|t| t.parse().ok());
    // Each phase's time summed over the settling steps.
    let mut phases = [0f64; 7];
    // `PERF_CTL=FIFO RELEASE_WINDOW=a,b`: writes `enable` and `disable` to that control FIFO around
    // steps a..b after the release (`perf record -D -1 --control fifo:FIFO`).
    let fifo = std::env::var("PERF_CTL").ok();
    let window: Vec<u32> = std::env::var("RELEASE_WINDOW")
        .map(|w| w.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_default();
    for s in 1..=5000u32 {
        if let (Some(f), [a, b]) = (&fifo, &window[..])
            && (s == *a || s == *b)
        {
            std::fs::write(f, if s == *a { "enable\n" } else { "disable\n" })?;
        }
        let t0 = Instant::now();
        let c = world.step();
        let us = t0.elapsed().as_secs_f64() * 1e6;
        times.push(us);
        // `RELEASE_SLOW=us`: the phases of each step longer than that.
        if slow.is_some_and(|t| us > t) {
            let ph: Vec<String> = c.phase_us.iter().map(|p| format!("{p:.0}")).collect();
            println!(
                "slow step {s}: {us:.0} us, phases {}, region {}",
                ph.join(" "),
                world.tissue().active_count()
            );
        }
        if settled.is_none() {
            for (sum, &p) in phases.iter_mut().zip(&c.phase_us) {
                *sum += f64::from(p);
            }
        }
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
    let steps = f64::from(settled.unwrap_or(5000));
    let each: Vec<String> = dissect::simulation::PHASES
        .iter()
        .zip(phases)
        .map(|(name, sum)| format!("{name} {:.0}", sum / steps))
        .collect();
    println!("settling steps' phases (mean us): {}", each.join(", "));
    // The longest steps, with their numbers (after the release).
    let mut longest: Vec<(usize, f64)> = times.iter().copied().enumerate().map(|(i, t)| (i + 1, t)).collect();
    longest.sort_by(|a, b| b.1.total_cmp(&a.1));
    let top: Vec<String> = longest.iter().take(12).map(|(s, t)| format!("{s}: {t:.0}")).collect();
    println!("longest steps (step: us): {}", top.join(", "));
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
