//! Recordings: a recorded session replays to a bit-identical final state with identical assessment
//! figures, and a session killed part way leaves a recording that still loads and replays.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use dissect::runner::{self, State};
use dissect::scene::{Recorder, Recording, Scene, Script};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("recording_replay");
    std::fs::create_dir_all(&d).expect("tmp dir");
    d.join(name)
}

#[test]
fn a_recording_replays_bit_for_bit() {
    let scene_path = root().join("scenes/meninges.ron");
    let scene = Scene::load(&scene_path).expect("scene");
    let script = Script::load(root().join("scenes/scripts/meninges_careful.ron")).expect("script");
    let path = tmp("careful.ron");
    let source = std::fs::read_to_string(&scene_path).expect("scene text");
    let recorder = Recorder::create(&path, "scenes/meninges.ron", &source).expect("recorder");
    let mut live = runner::run(&scene, "scene", &script, "script", None, Some(recorder)).expect("live run");
    live.recorder.take().expect("recorder back").finish(live.world.step_count()).expect("finish");

    let recording = Recording::load(&path).expect("recording loads");
    let replay_scene = Scene::from_str(&recording.scene_source, "recorded scene").expect("recorded scene");
    let replay =
        runner::run(&replay_scene, "scene", &recording.script(), "recording", None, None).expect("replay");
    assert_eq!(live.world.step_count(), replay.world.step_count());
    let (a, b) = (State::of(live.world.tissue(), 0), State::of(replay.world.tissue(), 0));
    let bits = |s: &State| -> Vec<u32> {
        s.layers.iter().flat_map(|l| l.positions.iter().flat_map(|p| p.map(f32::to_bits))).collect()
    };
    assert!(bits(&a) == bits(&b), "replayed positions differ");
    assert_eq!(a.broken_links, b.broken_links);
    assert_eq!(live.metrics.assessment, replay.metrics.assessment);
    // The same recording is accepted as a script by `dissect run`.
    let as_script = Script::load(&path).expect("a recording is a script");
    assert_eq!(as_script, recording.script());
}

#[test]
fn a_killed_session_leaves_a_recording_that_replays() {
    let rec = tmp("killed.ron");
    let _ = std::fs::remove_file(&rec);
    let mut child = Command::new(env!("CARGO_BIN_EXE_dissect"))
        .arg("run")
        .arg(root().join("scenes/meninges.ron"))
        .arg("--script")
        .arg(root().join("scenes/scripts/meninges_careful.ron"))
        .arg("--out")
        .arg(tmp("killed_out"))
        .arg("--record")
        .arg(&rec)
        .spawn()
        .expect("start dissect run");
    // Wait until the recorder has flushed some actions (it flushes every second), then kill it.
    let started = Instant::now();
    loop {
        let lines = std::fs::read_to_string(&rec).map(|s| s.matches("Command(").count()).unwrap_or(0);
        if lines >= 20 || started.elapsed() > Duration::from_secs(60) {
            break;
        }
        if child.try_wait().ok().flatten().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    let text = std::fs::read_to_string(&rec).expect("recording written");
    assert!(text.matches("Command(").count() >= 3, "too little was recorded: {text}");
    let recording = Recording::load(&rec).expect("a cut-off recording loads");
    let scene = Scene::from_str(&recording.scene_source, "recorded scene").expect("scene");
    let replay = runner::run(&scene, "scene", &recording.script(), "recording", None, None).expect("replays");
    assert!(replay.world.step_count() > 0);
}
