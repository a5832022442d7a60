//! The probe on a volume presses with its radius, in metres (issue 14, point 2): the bundled volume
//! (a 4 cm block of elastic cells, ν = 0.45) pressed at the centre of its top by the 3 mm ball.
//!
//! Measured 2026-11-30 (held 250 steps, 2 mm in). The top 3 mm out is 0.38, 1.04 and 1.20 mm down at
//! 12³, 18³ and 24³, 12 mm out 0.10, 0.16 and 0.04 mm, and the force 6.8, 8.7 and 5.9 N (Hertz's
//! for a rigid 3 mm ball 2 mm into an elastic half-space of E = 1 MPa and ν = 0.45: 8.2 N).
//! - When the ball pressed only the element nearest its centre, elements lay 0.23, 0.83 and 0.93 mm
//!   inside it, and its force fell from 7.9 to 4.2 and 2.5 N.
//! - Before the region of an elastic volume grew by what relaxation moves (`settle.rs`), the dent
//!   stopped where the chain reaction did: 12 mm out the top had not moved at all, and the force was
//!   18.6, 17.2 and 9.6 N.
//!
//! The dent is not yet the same at every resolution, and that is not asserted below. The contact is
//! under-resolved where an element is wider than the ball's contact radius (`√(R δ)` = 2.4 mm).
//! Relaxation of cells converges more slowly on a finer grid: 250 steps do not settle 24³.

mod common;

use dissect::scene::{Scene, Tissue as SceneTissue};
use dissect::simulation::{Command, InstrumentKind, World};

fn volume(n: u32) -> World {
    let mut scene =
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/volume.ron")).expect("volume scene");
    if let SceneTissue::Volume(v) = &mut scene.tissue {
        v.resolution = [n; 3];
    }
    scene.build_world(false).expect("world")
}

/// The top face's height above rest, bilinear between its elements, at `(x, z)`.
fn height(world: &World, n: usize, x: f32, z: f32) -> f32 {
    let body = world.tissue().body();
    let (rest, pos) = (body.lattice().rest_positions(), body.positions());
    let at = |i: usize, k: usize| i + n * ((n - 1) + n * k);
    let xs: Vec<f32> = (0..n).map(|i| rest[at(i, 0)][0]).collect();
    let zs: Vec<f32> = (0..n).map(|k| rest[at(0, k)][2]).collect();
    let cell = |c: &[f32], x: f32| c.partition_point(|&y| y <= x).clamp(1, c.len() - 1) - 1;
    let (i, k) = (cell(&xs, x), cell(&zs, z));
    let (fx, fz) = ((x - xs[i]) / (xs[i + 1] - xs[i]), (z - zs[k]) / (zs[k + 1] - zs[k]));
    let h = |i: usize, k: usize| pos[at(i, k)][1] - rest[at(i, k)][1];
    (1.0 - fz) * ((1.0 - fx) * h(i, k) + fx * h(i + 1, k))
        + fz * ((1.0 - fx) * h(i, k + 1) + fx * h(i + 1, k + 1))
}

/// The ball resting on the top centre, pressed `depth` in over 150 steps and held for 250; returns
/// the top's height at 0, 3, .. 12 mm from the centre along x, the force on the probe, the elements
/// the ball touches, and how far the top face's elements lie inside the ball at most (metres).
fn dent(n: u32, depth: f32) -> (Vec<f32>, [f32; 3], usize, f32) {
    let mut world = volume(n);
    let r = 0.003;
    let top = world.tissue().surface_point(0.5, 0.5, r);
    world.push(Command::Select(InstrumentKind::Probe));
    let ball = [top[0], top[1] - depth, top[2]];
    for s in 0..400 {
        let f = (s as f32 / 150.0).min(1.0);
        world.push(Command::MoveTo([top[0], top[1] - f * depth, top[2]]));
        world.step();
    }
    let profile = (0..5).map(|k| height(&world, n as usize, top[0] + 0.003 * k as f32, top[2])).collect();
    let pos = world.tissue().body().positions();
    let n = n as usize;
    let inside = common::deepest_inside_ball(pos, n, ball, r);
    (profile, world.forces().probe, world.tissue().probe_patch().len(), inside)
}

/// At 12³, 18³ and 24³ (3.6, 2.4 and 1.7 mm apart; the ball's radius is 3 mm) the ball pressed 2 mm
/// in: no element of the top face lies inside the ball by more than a hundredth of a millimetre (the
/// ball presses every element under it; before, only the one nearest its centre), it touches more
/// than one, its force points up, and the dent spreads as an elastic solid's does: 3 mm out the top is
/// down by more than a tenth of the press, and 12 mm out by more than a hundredth.
#[test]
fn the_ball_presses_every_element_under_it() {
    let depth = 0.002;
    for n in [12, 18, 24] {
        let (profile, f, touched, inside) = dent(n, depth);
        println!(
            "{n}: {:?} mm, force {f:?} N, {touched} touched, {} mm inside",
            profile.iter().map(|h| 1e3 * h).collect::<Vec<_>>(),
            1e3 * inside
        );
        assert!(inside < 1e-5, "{n}: an element lies {} mm inside the ball", 1e3 * inside);
        assert!(touched >= 2, "{n}: the ball touches {touched} elements");
        assert!(f[1] > 1.0 && f[0].abs().max(f[2].abs()) < 0.15 * f[1], "{n}: the probe's force {f:?}");
        assert!(profile[1] < -0.1 * depth, "{n}: 3 mm out the top is {} mm down", -1e3 * profile[1]);
        assert!(profile[4] < -0.01 * depth, "{n}: 12 mm out the top is {} mm down", -1e3 * profile[4]);
    }
}
