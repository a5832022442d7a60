//! A step allocates nothing once the session's scratch has grown to what it needs: every bundled scene
//! played with every script written for it (`scripts/<scene>.ron`, `scripts/<scene>_*.ron`), each step
//! of the episode (the script's commands, the world's step and the assessor's observation, as `dissect
//! run` and the trainer's simulation thread step it) counted by a counting allocator. The first step
//! builds what the session keeps; after it, scratch lists grow by doubling the first few times they
//! are used (a grasp's held set, a cone's growth, a cut's strokes, the assessment's history), and a
//! script's action may allocate as it starts, so a step allocates now and then and never every step.
//! The bound below fails on anything that allocates every step or every few steps (a per-step `Vec`, a
//! solve that builds its matrix each call), which is what the rule "no allocation per step" forbids.
//!
//! Runs only with the `count-allocations` feature, which replaces the library's mimalloc with the
//! counting allocator (and leaves out the debug builds' reference checks beside the fast paths, which
//! allocate): `cargo test --features count-allocations --test step_allocations` (CI runs it). What is
//! counted is the stepping thread's allocations.
#![cfg(feature = "count-allocations")]

use std::path::{Path, PathBuf};

use dissect::runner::{Episode, Player, Source};
use dissect::scene::{Scene, Script};
use dissect::training::Assessor;

/// Every bundled scene and the scripts written for it.
fn sessions() -> Vec<(PathBuf, PathBuf)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let ron = |d: &Path| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d)
            .expect("scenes")
            .filter_map(|e| Some(e.ok()?.path()).filter(|p| p.extension().is_some_and(|x| x == "ron")))
            .collect();
        v.sort();
        v
    };
    let scripts = ron(&dir.join("scripts"));
    let stem = |p: &Path| p.file_stem().and_then(|s| s.to_str()).unwrap_or("").to_string();
    let mut out = Vec::new();
    for scene in ron(&dir) {
        let name = stem(&scene);
        for script in &scripts {
            let s = stem(script);
            if s == name || s.strip_prefix(&name).is_some_and(|rest| rest.starts_with('_')) {
                out.push((scene.clone(), script.clone()));
            }
        }
    }
    out
}

#[test]
fn steps_allocate_only_while_their_scratch_grows() {
    let sessions = sessions();
    assert!(sessions.len() >= 10, "{sessions:?}");
    let mut report = Vec::new();
    for (scene_path, script_path) in &sessions {
        let scene = Scene::load(scene_path).unwrap_or_else(|e| panic!("{e}"));
        let script = Script::load(script_path).unwrap_or_else(|e| panic!("{e}"));
        // Stepped as `dissect run` and the trainer step it: an episode with its assessor, which
        // observes every step.
        let world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
        let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
        let mut episode = Episode::new(world, assessor, Source::Script(Player::new(script.0.clone())));
        let (mut steps, mut allocating, mut allocations, mut most) = (0u64, 0u64, 0u64, 0u64);
        loop {
            let mut stepped = false;
            let info = allocation_counter::measure(|| {
                stepped = episode.step().is_some();
            });
            if !stepped {
                break;
            }
            steps += 1;
            if steps > 1 && info.count_total > 0 {
                allocating += 1;
                allocations += info.count_total;
                most = most.max(info.count_total);
            }
        }
        // (A script's action may allocate as it starts: its path, its commands; the trainer's live
        // input comes as commands, which no script turns into more.)
        let actions = script.0.len() as u64;
        let label = format!(
            "{} with {} ({actions} actions): {steps} steps, {allocating} of them allocate after the first ({allocations} allocations, at most {most} in a step)",
            scene_path.file_name().and_then(|s| s.to_str()).unwrap_or(""),
            script_path.file_name().and_then(|s| s.to_str()).unwrap_or("")
        );
        println!("{label}");
        // Growth by doubling: a few dozen steps over a session of thousands, a few dozen allocations
        // in the step that first grasps or cuts.
        let grows = steps >= 100 && allocating <= 64 + actions && allocating * 20 <= steps && most <= 64;
        report.push((grows, label));
    }
    let failed: Vec<&str> = report.iter().filter(|r| !r.0).map(|r| r.1.as_str()).collect();
    assert!(failed.is_empty(), "steps that allocate more than growth does:\n{}", failed.join("\n"));
}

/// A haptic device driving the forceps through the trainer's live episode: each step reads the device,
/// couples it to the instrument, writes its force and steps the world. Down onto the dura, close the
/// forceps, lift 8 mm, let go: after the first step only growth allocates (the simulated device keeps
/// every force it was sent, in a list that doubles).
#[test]
fn a_haptic_device_driving_the_forceps_allocates_only_while_scratch_grows() {
    use dissect::haptics::{DeviceState, HapticLink, SimulatedDevice};
    use dissect::simulation::{Command, InstrumentKind};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meninges.ron");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let rate = f64::from(scene.simulation.rate_hz);
    let mut world = scene.build_world(false).unwrap_or_else(|e| panic!("{e}"));
    let mut start = world.tissue().surface_point(0.5, 0.5, 0.0);
    start[1] += 0.004;
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::MoveTo(start));
    world.step();
    let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
    let mut episode = Episode::new(world, assessor, Source::Live);
    let device = SimulatedDevice::new(3.0, move |step| {
        let t = step as f64 / rate;
        let s = |a: f64, b: f64| ((t - a) / (b - a)).clamp(0.0, 1.0) as f32;
        let y = -0.004 * s(0.0, 0.5) + 0.008 * s(0.7, 2.0);
        Some(DeviceState { position: [0.0, y, 0.0], buttons: u32::from((0.6..2.5).contains(&t)) })
    });
    episode.set_haptic(HapticLink::new(Box::new(device)));
    let steps = (3.0 * rate) as u64;
    let (mut allocating, mut allocations, mut most) = (0u64, 0u64, 0u64);
    let mut held_steps = 0;
    for step in 0..steps {
        let info = allocation_counter::measure(|| {
            episode.step();
        });
        held_steps += u32::from(episode.world().instrument().grasped.is_some());
        if step > 0 && info.count_total > 0 {
            allocating += 1;
            allocations += info.count_total;
            most = most.max(info.count_total);
        }
    }
    assert!(episode.take_haptic_error().is_none());
    assert!(held_steps > 1000, "the forceps held the dura for {held_steps} steps");
    assert!(episode.world().tissue().damage().links_torn == 0);
    let label = format!(
        "{steps} steps, {allocating} of them allocate after the first ({allocations} allocations, at most {most} in a step)"
    );
    println!("haptic forceps: {label}");
    assert!(allocating <= 64 && allocating * 20 <= steps && most <= 64, "{label}");
}
