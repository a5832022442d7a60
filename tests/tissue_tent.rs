//! A point lift's tent is rounded (issue 14, point 4): the forceps lift the dura of the meninges
//! scene at its centre by 5 mm and hold it while the tissue settles; the dura's height at one radius
//! (8 mm, inside the tent) in 8 directions must vary by less than 10 % of its mean.
//!
//! ChainMail's limits are boxes along the lattice's axes: a lift whose slope reaches the shear limit
//! spreads as a square pyramid (straight ridges along the axes, lower along the diagonals), and
//! relaxation, which never moves an element out of its links' boxes, cannot round it.

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

/// Lifts the dura's centre by `lift` metres and returns its heights at `radius` in 8 directions.
fn tent(nu: u32, nv: u32, lift: f32, radius: f32) -> [f32; 8] {
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
    // Up by `lift` in 1 s, then held for 2 s while the tissue settles.
    let steps = 1000;
    for s in 1..=steps {
        let f = s as f32 / steps as f32;
        world.push(Command::MoveTo([start[0], start[1] + f * lift, start[2]]));
        world.step();
    }
    for _ in 0..2000 {
        world.step();
    }
    let (nu, nv) = (nu as usize, nv as usize);
    std::array::from_fn(|k| {
        let a = k as f32 * std::f32::consts::FRAC_PI_4;
        height(&world, nu, nv, centre[0] + radius * a.cos(), centre[1] + radius * a.sin())
    })
}

fn spread(h: &[f32; 8]) -> f32 {
    let mean = h.iter().sum::<f32>() / 8.0;
    let (lo, hi) = h.iter().fold((f32::MAX, f32::MIN), |(l, u), &x| (l.min(x), u.max(x)));
    (hi - lo) / mean
}

#[test]
#[ignore = "fails today: the tent is a square pyramid (the dura lifted 5 mm at 128 x 96 stands 3.16 mm high 8 mm out along the axes and 2.49 mm along the diagonals: 23.8 % apart; 3.00 and 2.17 mm, 32 %, at 64 x 48); relaxation stops at the links' boxes (issue 14, point 4)"]
fn a_point_lift_is_rounded() {
    let h = tent(128, 96, 0.005, 0.008);
    let s = spread(&h);
    eprintln!("128 x 96: heights at 8 mm {h:?}, spread {:.1} %", 100.0 * s);
    assert!(s < 0.10, "heights at 8 mm in 8 directions {h:?} vary by {:.1} % of their mean", 100.0 * s);
}

/// What the tent is today, so that a change in its shape is seen: higher along the axes than along
/// the diagonals, and inside the lift.
#[test]
fn a_point_lift_rises_around_the_forceps() {
    let h = tent(64, 48, 0.005, 0.008);
    for (k, &x) in h.iter().enumerate() {
        assert!(x > 0.0 && x < 0.005, "direction {k}: {x} m ({h:?})");
    }
    let (axes, diagonals) = ([h[0], h[2], h[4], h[6]], [h[1], h[3], h[5], h[7]]);
    let min_axis = axes.iter().fold(f32::MAX, |m, &x| m.min(x));
    let max_diagonal = diagonals.iter().fold(f32::MIN, |m, &x| m.max(x));
    eprintln!("heights at 8 mm: {h:?}, spread {:.1} %", 100.0 * spread(&h));
    assert!(min_axis >= max_diagonal, "axes {axes:?} diagonals {diagonals:?}");
}
