//! A point lift's tent is rounded (issue 14, point 4): the forceps lift the dura of the meninges
//! scene at its centre by 5 mm and hold it while the tissue settles; the dura's height at one radius
//! (8 mm, inside the tent) in 16 directions must vary by less than 10 % of its mean.
//!
//! ChainMail's links bound the normal offset along the lattice's axes only: alone they made a lift
//! whose slope reaches the shear limit a square pyramid (3.00 mm high 8 mm out along the axes and
//! 2.17 mm along the diagonals at 64 x 48, 32 % apart), and relaxation, which never moves an element
//! out of its links' boxes, could not round it. The cells' diagonals bound it too (normal pairs,
//! `chainmail/pairs.rs`): the least lift is an octagon, under 8.2 % from round.

mod common;

use dissect::chainmail::ElementId;
use dissect::simulation::{Command, InstrumentKind, World};

fn world(nu: u32, nv: u32) -> World {
    common::meninges(nu, nv)
}

/// The dura's height above rest, bilinear between its elements, at lattice point `(u, v)`.
fn height(world: &World, nu: usize, nv: usize, u: f32, v: f32) -> f32 {
    let t = world.tissue();
    let first = t.layers()[0].first as usize;
    let rest = t.body().lattice().rest_positions();
    let pos = t.body().positions();
    let at = |i: usize, j: usize| first + j * nu + i;
    // The grid's coordinates along u (first row) and v (first column).
    let us: Vec<f32> = (0..nu).map(|i| rest[at(i, 0)][0]).collect();
    let vs: Vec<f32> = (0..nv).map(|j| rest[at(0, j)][1]).collect();
    let cell = |c: &[f32], x: f32| c.partition_point(|&y| y <= x).clamp(1, c.len() - 1) - 1;
    let (i, j) = (cell(&us, u), cell(&vs, v));
    let fu = (u - us[i]) / (us[i + 1] - us[i]);
    let fv = (v - vs[j]) / (vs[j + 1] - vs[j]);
    let h = |i: usize, j: usize| pos[at(i, j)][2] - rest[at(i, j)][2];
    (1.0 - fv) * ((1.0 - fu) * h(i, j) + fu * h(i + 1, j))
        + fv * ((1.0 - fu) * h(i, j + 1) + fu * h(i + 1, j + 1))
}

/// Grasps the dura at its centre and lifts it by `lift` metres in `steps` steps; returns the world,
/// holding it up there, and the grasped element's rest position.
fn lift_centre(nu: u32, nv: u32, lift: f32, steps: u32) -> (World, [f32; 3]) {
    let mut world = world(nu, nv);
    let t = world.tissue();
    let dura =
        t.surface_point(0.5, 0.5, t.body().lattice().rest_positions()[t.layers()[0].first as usize][2]);
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(dura));
    world.push(Command::Grasp);
    world.step();
    let e = world.instrument().grasped.expect("the forceps hold the dura");
    let start = world.tissue().world_position(e).expect("grasped element");
    let centre = world.tissue().body().lattice().rest_positions()[e.index()];
    assert!(world.tissue().layer_of(ElementId(e.0)) == Some(0), "grasped the dura");
    for s in 1..=steps {
        let f = s as f32 / steps as f32;
        world.push(Command::MoveTo([start[0], start[1] + f * lift, start[2]]));
        world.step();
    }
    (world, centre)
}

/// Lifts the dura's centre by `lift` metres and returns its heights at `radius` in `D` directions
/// (evenly spaced, the first along `u`).
fn tent<const D: usize>(nu: u32, nv: u32, lift: f32, radius: f32) -> [f32; D] {
    // Up by `lift` in 1 s, then held for 2 s while the tissue settles.
    let (mut world, centre) = lift_centre(nu, nv, lift, 1000);
    for _ in 0..2000 {
        world.step();
    }
    let (nu, nv) = (nu as usize, nv as usize);
    std::array::from_fn(|k| {
        let a = k as f32 * std::f32::consts::TAU / D as f32;
        height(&world, nu, nv, centre[0] + radius * a.cos(), centre[1] + radius * a.sin())
    })
}

fn spread(h: &[f32]) -> f32 {
    let mean = h.iter().sum::<f32>() / h.len() as f32;
    let (lo, hi) = h.iter().fold((f32::MAX, f32::MIN), |(l, u), &x| (l.min(x), u.max(x)));
    (hi - lo) / mean
}

/// The heights at 8 mm in 16 directions (every 22.5 degrees: a pyramid is lowest at the diagonals,
/// an octagon at the 8 directions between its corners and the middles of its sides) vary by less than
/// 10 % of their mean.
fn assert_rounded(nu: u32, nv: u32) {
    let h = tent::<16>(nu, nv, 0.005, 0.008);
    let s = spread(&h);
    eprintln!("{nu} x {nv}: heights at 8 mm (mm) {:.3?}, spread {:.1} %", h.map(|x| 1e3 * x), 100.0 * s);
    assert!(s < 0.10, "heights at 8 mm in 16 directions {h:?} vary by {:.1} % of their mean", 100.0 * s);
}

#[test]
fn a_point_lift_is_rounded() {
    assert_rounded(128, 96);
}

#[test]
fn a_point_lift_is_rounded_at_64_x_48() {
    assert_rounded(64, 48);
}

/// The tent rises around the forceps, inside the lift, and along the lattice's axes it stands where
/// the dura's slope limit puts it (`max_shear` 0.25: 5 mm less a quarter of 8 mm, 3 mm; the pyramid
/// of the links alone stood 3.00 mm at 64 x 48 and 3.16 mm at 128 x 96): rounding the tent raises
/// the diagonals, it does not lower the axes.
#[test]
fn a_point_lift_rises_around_the_forceps() {
    for (nu, nv) in [(64, 48), (128, 96)] {
        let h = tent::<8>(nu, nv, 0.005, 0.008);
        for (k, &x) in h.iter().enumerate() {
            assert!(x > 0.0 && x < 0.005, "{nu} x {nv}, direction {k}: {x} m ({h:?})");
        }
        for k in [0, 2, 4, 6] {
            assert!((h[k] - 0.003).abs() < 0.0003, "{nu} x {nv}, axis {k}: {} mm ({h:?})", 1e3 * h[k]);
        }
    }
}

/// A lift let go comes back down, at every resolution: with the forceps released nothing holds the
/// dura up, and the relaxation takes it back to rest. What the lift displaced joins the disturbed
/// region when the jaws open (everything joined to them through elements displaced more than a
/// micrometre), and the region's relaxation adds a coarse-grid correction until it settles
/// (`chainmail/relax/coarse.rs`): Gauss-Seidel sweeps alone need four times the sweeps at each
/// doubling of the resolution (5 mm to 0.17 mm in 1 000 whole-body sweeps at 64 x 48), and before
/// 2026-11-29 the region emptied within ten steps of the release and the tent stood 5 mm up for good.
/// Measured on the release build (2026-11-29, the nineteenth session on issue 14,
/// `examples/release_trace`): the grasped element is 2 µm from rest 10 steps after the release at
/// 64 x 48, 0.0024 mm after 50 at 128 x 96 and 0.0042 mm after 300 at 256 x 192; the test allows 1 mm after 1 s, and asks that the settling has ended (the
/// region empty) and the centre is within 0.1 mm of rest after 5 s.
fn released_lift_comes_back_down(nu: u32, nv: u32) {
    let (mut world, centre) = lift_centre(nu, nv, 0.005, 500);
    world.push(Command::Release);
    for _ in 0..1_000 {
        world.step();
    }
    let at_centre = height(&world, nu as usize, nv as usize, centre[0], centre[1]);
    assert!(at_centre.abs() < 0.001, "1 s after the release the dura stands {} mm up", 1e3 * at_centre);
    for _ in 0..4_000 {
        world.step();
    }
    let at_centre = height(&world, nu as usize, nv as usize, centre[0], centre[1]);
    assert!(at_centre.abs() < 1e-4, "5 s after the release the dura stands {} mm up", 1e3 * at_centre);
    assert_eq!(world.tissue().active_count(), 0, "5 s after the release the tissue still settles");
}

#[test]
fn a_released_lift_comes_back_down() {
    released_lift_comes_back_down(64, 48);
}

#[test]
fn a_released_lift_comes_back_down_at_128_x_96() {
    released_lift_comes_back_down(128, 96);
}

/// A dent the probe pressed comes back out once the probe leaves it: the last element it touched
/// settles as a release does (64 x 48; the dent is 3 mm deep).
#[test]
fn a_probe_dent_comes_back_out() {
    let (nu, nv) = (64, 48);
    let mut world = world(nu, nv);
    let t = world.tissue();
    let first = t.layers()[0].first as usize;
    let centre =
        t.body().lattice().rest_positions()[first + (nv as usize / 2) * nu as usize + nu as usize / 2];
    let top = t.surface_point(0.5, 0.5, t.body().lattice().rest_positions()[first][2]);
    world.push(Command::Select(InstrumentKind::Probe));
    for s in 0..=300 {
        let f = s as f32 / 300.0;
        world.push(Command::MoveTo([top[0], top[1] + 0.002 - f * 0.005, top[2]]));
        world.step();
    }
    let pressed = height(&world, nu as usize, nv as usize, centre[0], centre[1]);
    assert!(pressed < -0.002, "the probe pressed the dura {} mm", 1e3 * pressed);
    world.push(Command::MoveTo([top[0], top[1] + 0.01, top[2]]));
    for _ in 0..1_000 {
        world.step();
    }
    let after = height(&world, nu as usize, nv as usize, centre[0], centre[1]);
    assert!(after.abs() < 1e-4, "1 s after the probe left, the dent is {} mm deep", -1e3 * after);
}

/// While a released lift settles at 256 x 192 (a tent of about 19 500 elements, more than four times
/// a step's sweep), a step in which only the sweep moved part of the region checks contact and tears
/// over the links it moved, not the whole tent's (`Tissue::scan_sweep_window`); in debug builds each
/// such step also scans the whole region and asserts that it finds no tear the swept elements' check
/// missed and no larger stretch. The settling tears nothing, and most of its steps are such steps.
#[test]
fn a_settling_checks_what_its_sweeps_moved() {
    let (mut world, _) = lift_centre(256, 192, 0.005, 500);
    world.push(Command::Release);
    let mut torn = 0;
    for _ in 0..300 {
        torn += world.step().links_torn;
    }
    assert_eq!(torn, 0, "the settling tore links");
    let checks = world.tissue().swept_checks();
    assert!(checks > 150, "{checks} of 300 settling steps checked only what their sweep moved");
}

/// The probe's ball (3 mm radius) resting on the dura at the centre, pressed 1.5 mm in over 150 steps
/// and held for 100; returns the dura's height above rest at 0, 2, .. 12 mm from the centre along `u`,
/// and the force on the probe.
fn probe_dent(nu: u32, nv: u32) -> (Vec<f32>, [f32; 3]) {
    let mut world = world(nu, nv);
    let t = world.tissue();
    let first = t.layers()[0].first as usize;
    let rest = t.body().lattice().rest_positions();
    let centre = rest[first + (nv as usize / 2) * nu as usize + nu as usize / 2];
    let (cu, cv) = t.surface_fractions(centre);
    let r = 0.003;
    let top = t.surface_point(cu, cv, rest[first][2] + r);
    world.push(Command::Select(InstrumentKind::Probe));
    for s in 0..250 {
        let f = (s as f32 / 150.0).min(1.0);
        world.push(Command::MoveTo([top[0], top[1] - f * 0.0015, top[2]]));
        world.step();
    }
    let profile = (0..7)
        .map(|k| height(&world, nu as usize, nv as usize, centre[0] + 0.002 * k as f32, centre[1]))
        .collect();
    (profile, world.forces().probe)
}

/// The probe's dent is the same in metres at every resolution (issue 14, points 2 and 5): the ball
/// (3 mm) pressed 1.5 mm into the dura and held there keeps the dura 1.5 mm down under its centre
/// (relaxation does not lift it back into the ball), and the dura's height 2, 4 and 6 mm out differs
/// by under 5 % of the press between 64 x 48, 128 x 96 and 256 x 192, as does its edge 8 to 12 mm out
/// (nothing there). Measured 2026-11-30: -1.50, -1.04 / -1.09 / -1.09, -0.54 / -0.59 / -0.59 and
/// -0.12 / -0.09 / -0.09 mm. (Pressed the same way but not held through the step's relaxation, the
/// centre came out 0.79, 1.13 and 1.24 mm down: relaxation lifts a dent faster on a coarser sheet.)
/// The force on the probe pushes it back up, across the surface by under a thousandth of that.
#[test]
fn a_probe_dent_is_the_same_at_every_resolution() {
    let dents: Vec<(Vec<f32>, [f32; 3])> =
        [(64, 48), (128, 96), (256, 192)].map(|(u, v)| probe_dent(u, v)).into();
    for (k, (dent, f)) in dents.iter().enumerate() {
        assert!((dent[0] + 0.0015).abs() < 1e-5, "resolution {k}: the dent's centre is {} mm", 1e3 * dent[0]);
        assert!(
            f[1] > 0.01 && f[0].abs().max(f[2].abs()) < 1e-3 * f[1],
            "resolution {k}: the probe's force {f:?}"
        );
    }
    for pair in dents.windows(2) {
        for (d, (a, b)) in pair[0].0.iter().zip(&pair[1].0).enumerate() {
            assert!((a - b).abs() < 0.05 * 0.0015, "{} mm out: {} mm against {} mm", 2 * d, 1e3 * a, 1e3 * b);
        }
    }
}
