//! A simulated haptic device coupled to every bundled scene for 10 s of simulated time: the coupled
//! system gives the hand no energy (passivity), the force sent never exceeds the device's limit, and a
//! device that sends a NaN pose or disappears is dropped with a clear message while the world goes on.

use dissect::haptics::{DeviceError, DeviceState, HapticLink, SimulatedDevice};
use dissect::scene::Scene;
use dissect::simulation::Command;
use dissect::simulation::{InstrumentKind, World};

const LIMIT: f32 = 3.0;

/// Down onto the surface, grasp, lift 8 mm and sideways, back down, let go; then the probe presses
/// 3 mm in and out. Device coordinates: metres from where it starts.
fn path(step: u64, rate: f64) -> DeviceState {
    let t = step as f64 / rate;
    let s = |a: f64, b: f64| ((t - a) / (b - a)).clamp(0.0, 1.0) as f32;
    let down = -0.004 * s(0.0, 1.0);
    let lift = 0.008 * (s(1.5, 3.5) - s(4.0, 6.0));
    let side = 0.005 * (s(2.0, 3.0) - s(4.5, 5.5));
    let press = -0.003 * ((std::f64::consts::PI * s(7.0, 9.5) as f64).sin() as f32);
    let buttons = u32::from((1.2..6.5).contains(&t));
    DeviceState { position: [side, down + lift + press, 0.0], buttons }
}

fn run(scene_path: &str) {
    let scene = Scene::load(scene_path).unwrap_or_else(|e| panic!("{e}"));
    let rate = f64::from(scene.simulation.rate_hz);
    let mut world: World = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
    // Start 4 mm above the tissue's centre.
    let mut start = world.tissue().surface_point(0.5, 0.5, 0.0);
    if let Some(e) = world.tissue().nearest_element(start, None)
        && let Some(p) = world.tissue().world_position(e)
    {
        start = p;
    }
    start[1] += 0.004;
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(start));
    world.step();
    let mut link = HapticLink::new(Box::new(SimulatedDevice::new(LIMIT, move |step| Some(path(step, rate)))));
    let steps = (10.0 * rate) as u64;
    let mut peak = 0.0f32;
    let mut sent = 0.0f32;
    let mut max_energy = f64::MIN;
    // The largest move of the hand in one step, metres: the controller damps a surplus at the next
    // step, so what the last moving step gave the hand can stay (the hand then stands still).
    let mut max_move = 0.0f32;
    for step in 0..steps {
        let (a, b) = (path(step, rate).position, path(step + 1, rate).position);
        max_move = max_move.max([0, 1, 2].map(|k| (b[k] - a[k]).powi(2)).iter().sum::<f32>().sqrt());
        if step == (6.8 * rate) as u64 {
            world.push(Command::Select(InstrumentKind::Probe));
        }
        let commands = link.exchange(&world).unwrap_or_else(|e| panic!("{scene_path}: {e}"));
        for c in commands {
            world.push(c);
        }
        world.step();
        let c = link.coupling().unwrap_or_else(|| panic!("coupled"));
        max_energy = max_energy.max(c.energy());
        let d = link.last_force();
        sent = sent.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        let f = world.forces().in_hand();
        peak = peak.max((f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt());
    }
    let c = link.coupling().unwrap_or_else(|| panic!("coupled"));
    eprintln!(
        "{scene_path}: tissue peak {peak:.3} N, sent {sent:.3} N, energy to the hand {:.2e} J (max {max_energy:.2e})",
        c.energy()
    );
    // Passivity: the energy the coupling gave the hand never exceeds a step's worth of a full-force
    // move (the controller damps any surplus at the next step), and over the session no more than the
    // last step's worth (a surplus the hand's last move made, when it then stands still: the
    // controller damps motion only). The volume ends at 2.4e-6 J (the probe's
    // press ends with the hand stopping while the tissue gives back what it stored).
    let bound = f64::from(LIMIT * max_move);
    assert!(max_energy < 1e-4, "{scene_path}: energy gained {max_energy}");
    assert!(
        c.energy() <= bound,
        "{scene_path}: energy gained over the session {} (bound {bound})",
        c.energy()
    );
    assert!(peak > 0.0, "{scene_path}: the tissue was touched");
    assert!(sent <= LIMIT * (1.0 + 1e-6), "{scene_path}: {sent} N sent, limit {LIMIT}");
    assert!(sent > 0.0, "{scene_path}: the hand felt the tissue");
}

#[test]
fn every_bundled_scene_is_passive_and_within_the_force_limit() {
    for scene in [
        "scenes/meninges.ron",
        "scenes/cylinder.ron",
        "scenes/sphere.ron",
        "scenes/volume.ron",
        "scenes/fem_block.ron",
    ] {
        run(scene);
    }
}

#[test]
fn a_nan_pose_or_a_lost_device_is_an_error_and_the_world_goes_on() {
    let scene = Scene::load("scenes/meninges.ron").unwrap_or_else(|e| panic!("{e}"));
    let mut world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
    let mut link = HapticLink::new(Box::new(SimulatedDevice::new(LIMIT, |step| match step {
        0..10 => Some(DeviceState { position: [0.0, 0.001 * step as f32, 0.0], buttons: 0 }),
        10 => Some(DeviceState { position: [f32::NAN, 0.0, 0.0], buttons: 0 }),
        _ => None,
    })));
    let mut errors = Vec::new();
    for _ in 0..12 {
        match link.exchange(&world) {
            Ok(cs) => cs.into_iter().for_each(|c| world.push(c)),
            Err(e) => errors.push(e),
        }
        world.step();
    }
    assert!(matches!(errors[0], DeviceError::BadInput { .. }), "{errors:?}");
    assert!(errors[0].to_string().contains("not a finite point"), "{}", errors[0]);
    assert!(matches!(errors[1], DeviceError::Lost { .. }), "{errors:?}");
    assert_eq!(world.step_count(), 12);
}
