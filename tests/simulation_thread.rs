//! The simulation thread (`runner::SimThread`): a live episode stepped on its own thread, given input
//! from another thread at whatever steps it happens to arrive, records what it was given with the step
//! it reached the world; replaying that recording headless, step by step, gives the same state bit for
//! bit. A haptic device that sends a pose that is not a number, or that vanishes mid-session, is
//! dropped with one clear message, the mouse's input goes on reaching the world, and nothing is lost
//! from the recording (the replay still matches).

use std::path::Path;
use std::time::{Duration, Instant};

use dissect::haptics::{DeviceState, HapticLink, SimulatedDevice};
use dissect::instrument::Hit;
use dissect::runner::{Episode, Event, Given, Input, Player, SimThread, Source, State};
use dissect::scene::{Recorder, Recording, Scene};
use dissect::simulation::{Command, InstrumentKind};
use dissect::training::Assessor;

fn live_episode(scene: &Scene, record: &Path) -> Episode {
    let world = scene.build_world(false).expect("world");
    let assessor = scene.goals.clone().map(|g| Assessor::new(g, &world));
    let mut episode = Episode::new(world, assessor, Source::Live);
    let source = dissect::scene::DEFAULT_SCENE;
    episode
        .record_to(Recorder::create(record, dissect::scene::DEFAULT_SCENE_PATH, source).expect("recorder"));
    episode
}

fn state_of(episode: &Episode) -> String {
    let w = episode.world();
    serde_json::to_string(&State::of(w.tissue(), w.step_count())).expect("state as JSON")
}

/// Ends the thread, finishes the recording, replays it headless and checks the two states are one.
fn stop_and_replay(mut sim: SimThread, record: &Path) -> (Episode, Vec<Event>) {
    let (episode, events) = sim.stop();
    let mut episode = episode.expect("the thread ended cleanly");
    let step = episode.world().step_count();
    episode.take_recorder().expect("still recording").finish(step).expect("recording finished");
    let recording = Recording::load(record).unwrap_or_else(|e| panic!("{e}"));
    let scene = Scene::from_str(&recording.scene_source, &recording.scene).expect("recorded scene");
    let mut replay = Episode::new(
        scene.build_world(false).expect("world"),
        None,
        Source::Script(Player::new(recording.actions)),
    );
    while replay.step().is_some() {}
    assert_eq!(replay.world().step_count(), step, "the replay runs as long as the session");
    assert_eq!(replay.world().instrument().target, episode.world().instrument().target);
    assert!(state_of(&replay) == state_of(&episode), "the replay's state differs from the live session's");
    (episode, events)
}

/// Waits (reading frames as a window does) until the thread has run `steps` steps.
fn wait_for_step(sim: &mut SimThread, steps: u64) {
    let t = Instant::now();
    while sim.latest().view.step_count() < steps {
        assert!(t.elapsed() < Duration::from_secs(60), "the thread does not step");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn centre(scene: &Scene) -> [f32; 3] {
    let world = scene.build_world(false).expect("world");
    let mut p = world.tissue().surface_point(0.5, 0.5, 0.0);
    if let Some(e) = world.tissue().nearest_element(p, Some(0))
        && let Some(q) = world.tissue().world_position(e)
    {
        p = q;
    }
    p
}

#[test]
fn a_live_session_recorded_through_the_thread_replays_bit_for_bit() {
    let dir = std::env::temp_dir().join(format!("dissect-thread-{}", std::process::id()));
    let record = dir.join("live.ron");
    let scene = Scene::default_scene().expect("default scene");
    let c = centre(&scene);
    let mut sim = SimThread::spawn(live_episode(&scene, &record)).expect("thread");
    let give = |sim: &SimThread, items: Vec<Given>| sim.give(items);
    let cmd = |c: Command| Given::Command(c);
    // A grasp and a pull, given in small batches at irregular moments (a frame every 3 to 17 ms).
    give(&sim, vec![cmd(Command::Select(InstrumentKind::Forceps)), cmd(Command::MoveTo(c))]);
    wait_for_step(&mut sim, 5);
    give(&sim, vec![Given::GraspAt(Hit { point: c, layer: 0, vertex: 0, distance: 0.0 })]);
    let mut seed = 12345u32;
    for k in 0..40 {
        let lift = 0.0002 * k as f32;
        give(&sim, vec![cmd(Command::MoveTo([c[0] + lift * 0.3, c[1] + lift, c[2]]))]);
        seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        std::thread::sleep(Duration::from_millis(3 + u64::from(seed >> 16) % 15));
        let _ = sim.latest();
    }
    give(&sim, vec![cmd(Command::Release)]);
    let now = sim.latest().view.step_count();
    wait_for_step(&mut sim, now + 20);
    assert!(sim.latest().view.last_step().step > 0);
    let (episode, _) = stop_and_replay(sim, &record);
    assert!(episode.world().step_count() > 100, "the thread kept stepping on its own");
    assert!(episode.recorded() >= 43, "every command given was recorded ({})", episode.recorded());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A device at the tissue's centre that does `fault` from step 200 on, while the mouse moves on.
fn faulty_device(fault: &'static str) {
    let dir = std::env::temp_dir().join(format!("dissect-thread-{fault}-{}", std::process::id()));
    let record = dir.join("device.ron");
    let scene = Scene::default_scene().expect("default scene");
    let c = centre(&scene);
    let mut episode = live_episode(&scene, &record);
    episode.push(Command::Select(InstrumentKind::Probe));
    episode.push(Command::MoveTo([c[0], c[1] + 0.004, c[2]]));
    let device = SimulatedDevice::new(3.0, move |step| {
        let y = -0.002 * (step.min(150) as f32 / 150.0);
        match (step >= 200, fault) {
            (false, _) => Some(DeviceState { position: [0.0, y, 0.0], buttons: 0 }),
            (true, "nan") => Some(DeviceState { position: [f32::NAN, y, 0.0], buttons: 0 }),
            (true, _) => None,
        }
    });
    episode.set_haptic(HapticLink::new(Box::new(device)));
    let mut sim = SimThread::spawn(episode).expect("thread");
    // The device's drop is said once, as an event for the window.
    let t = Instant::now();
    let mut messages = Vec::new();
    while messages.is_empty() {
        assert!(t.elapsed() < Duration::from_secs(60), "the device was never dropped");
        for e in sim.events() {
            if let Event::Message(m) = e {
                messages.push(m);
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(messages.len(), 1, "{messages:?}");
    let m = &messages[0];
    assert!(m.starts_with("haptic device dropped: simulated device"), "{m}");
    assert!(m.ends_with("the mouse drives"), "{m}");
    match fault {
        "nan" => assert!(m.contains("bad input") && m.contains("not a finite point"), "{m}"),
        _ => assert!(m.contains("stopped answering"), "{m}"),
    }
    // The mouse goes on: its moves reach the world and the recording.
    let target = [c[0] + 0.003, c[1] + 0.005, c[2]];
    sim.send(Input::Give { seen: 0, items: vec![Given::Command(Command::MoveTo(target))] });
    let now = sim.latest().view.step_count();
    wait_for_step(&mut sim, now + 30);
    assert_eq!(sim.latest().view.instrument().target, target);
    let (episode, events) = stop_and_replay(sim, &record);
    assert!(events.iter().all(|e| !matches!(e, Event::Message(_))), "said once only");
    assert_eq!(episode.world().instrument().target, target);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_device_sending_nan_is_dropped_once_and_the_mouse_goes_on() {
    faulty_device("nan");
}

#[test]
fn a_device_that_vanishes_is_dropped_once_and_the_mouse_goes_on() {
    faulty_device("vanish");
}
