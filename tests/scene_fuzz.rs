//! The loader never panics: random bytes and random mutations of the bundled scenes, scripts and a
//! recording (byte flips, deletions, duplications, number replacements) either load or give an error;
//! what loads also runs (small scenes are built and stepped, scripts and recordings played for a few
//! hundred steps on a small scene) without a panic or a non-finite position. The case count is fixed,
//! so `cargo test` (and `.ci/run`) runs it in bounded time; `FUZZ_CASES=N` runs more.

use std::sync::OnceLock;

use dissect::scene::{Recording, Scene, Script};
use proptest::prelude::*;

const SCENES: [&str; 4] = [
    include_str!("../scenes/meninges.ron"),
    include_str!("../scenes/cylinder.ron"),
    include_str!("../scenes/sphere.ron"),
    include_str!("../scenes/volume.ron"),
];
const SCRIPTS: [&str; 4] = [
    include_str!("../scenes/scripts/meninges.ron"),
    include_str!("../scenes/scripts/cylinder.ron"),
    include_str!("../scenes/scripts/sphere.ron"),
    include_str!("../scenes/scripts/volume.ron"),
];

/// Numbers that probe the range checks.
const NUMBERS: [&str; 14] = [
    "0",
    "-1",
    "1e30",
    "-1e-30",
    "NaN",
    "inf",
    "-inf",
    "4294967296",
    "0.5",
    "1",
    "100000",
    "-0.0",
    "1.0e",
    "18446744073709551616",
];

#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, byte: u8 },
    Delete { at: usize, len: usize },
    Duplicate { at: usize, len: usize, to: usize },
    Number { nth: usize, with: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), 1usize..80, any::<usize>()).prop_map(|(at, len, to)| Mutation::Duplicate {
            at,
            len,
            to
        }),
        (any::<usize>(), 0..NUMBERS.len()).prop_map(|(nth, with)| Mutation::Number { nth, with }),
    ]
}

fn apply(src: &[u8], m: &Mutation) -> Vec<u8> {
    let mut out = src.to_vec();
    let n = out.len().max(1);
    match *m {
        Mutation::Flip { at, byte } => {
            if !out.is_empty() {
                out[at % n] = byte;
            }
        }
        Mutation::Delete { at, len } => {
            let a = at % n;
            let b = (a + len).min(out.len());
            out.drain(a..b);
        }
        Mutation::Duplicate { at, len, to } => {
            let a = at % n;
            let b = (a + len).min(out.len());
            let piece = out[a..b].to_vec();
            let t = to % (out.len() + 1);
            out.splice(t..t, piece);
        }
        Mutation::Number { nth, with } => {
            // Replace the nth run of digits (with its sign, point and exponent).
            let text = String::from_utf8_lossy(&out).into_owned();
            let runs: Vec<(usize, usize)> = number_runs(&text);
            if !runs.is_empty() {
                let (a, b) = runs[nth % runs.len()];
                let mut s = text;
                s.replace_range(a..b, NUMBERS[with]);
                out = s.into_bytes();
            }
        }
    }
    out
}

fn number_runs(s: &str) -> Vec<(usize, usize)> {
    let bytes = s.as_bytes();
    let mut runs = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = if i > 0 && bytes[i - 1] == b'-' { i - 1 } else { i };
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.' || bytes[i] == b'e') {
                i += 1;
            }
            runs.push((start, i));
        } else {
            i += 1;
        }
    }
    runs
}

/// A recording of the default exercise's script, made once by a headless run.
fn recording() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| {
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scene_fuzz");
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join(format!("recording-{}.ron", std::process::id()));
        let scene = Scene::from_str(SCENES[0], "meninges.ron").expect("bundled scene");
        let script = Script::from_str(SCRIPTS[0], "meninges.ron").expect("bundled script");
        let rec =
            dissect::scene::Recorder::create(&path, "scenes/meninges.ron", SCENES[0]).expect("recorder");
        let mut out =
            dissect::runner::run(&scene, "meninges.ron", &script, "script.ron", Some(400), Some(rec))
                .expect("runs");
        let rec = out.recorder.take().expect("the recorder comes back");
        rec.finish(out.world.step_count()).expect("finish");
        let text = std::fs::read_to_string(&path).expect("read");
        let _ = std::fs::remove_file(&path);
        text
    })
}

/// A small two-layer scene that every bundled instrument and depth fits, for playing mutated scripts.
fn small_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| {
        // The bundled scene at 16 x 12 (set on the parsed scene: a text replacement silently missed once
        // the bundled resolution changed).
        let mut scene = Scene::from_str(SCENES[0], "small.ron").expect("small scene");
        let dissect::scene::Tissue::Layers(layers) = &mut scene.tissue else { panic!("a layered scene") };
        layers.resolution = [16, 12];
        scene
    })
}

fn cases() -> u32 {
    std::env::var("FUZZ_CASES").ok().and_then(|n| n.parse().ok()).unwrap_or(256)
}

/// Plays a script for at most `steps` steps on `scene`; positions stay finite.
fn play(scene: &Scene, script: &Script, steps: u64) {
    if script.check_against(scene).is_err() {
        return;
    }
    let Ok(mut world) = scene.build_world(false) else { return };
    let mut player = dissect::runner::Player::new(script.0.clone());
    for _ in 0..steps.min(script.duration_steps()) {
        player.feed(&mut world);
        world.step();
    }
    let t = world.tissue();
    for layer in t.layers() {
        for e in layer.first..layer.first + layer.count {
            if let Some(p) = t.world_position(dissect::chainmail::ElementId(e)) {
                assert!(p.iter().all(|x| x.is_finite()), "element {e} at {p:?}");
            }
        }
    }
}

/// Loads as a scene, a script and a recording; what loads runs. Only a panic (or a non-finite
/// position) fails.
fn feed(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    match Scene::from_str(&text, "fuzz.ron") {
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("fuzz.ron:"), "{msg}");
        }
        Ok(scene) if scene.element_count() <= 5000 => {
            let probe = Script::from_str("Script([Select(Probe), Push(at: Surface(0.5, 0.5, 0.0), to: Surface(0.5, 0.5, -0.005), steps: 20)])", "p.ron").expect("probe");
            play(&scene, &probe, 30);
        }
        Ok(_) => {}
    }
    match Script::from_str(&text, "fuzz.ron") {
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("fuzz.ron:"), "{msg}");
        }
        Ok(script) => play(small_scene(), &script, 300),
    }
    if let Ok(rec) = Recording::from_str(&text, "fuzz.ron")
        && let Ok(scene) = Scene::from_str(&rec.scene_source, "fuzz.ron (scene_source)")
        && scene.element_count() <= 5000
    {
        play(&scene, &rec.script(), 300);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn mutated_recordings_never_panic(ms in proptest::collection::vec(mutation(), 1..6)) {
        let mut src = recording().as_bytes().to_vec();
        for m in &ms {
            src = apply(&src, m);
        }
        feed(&src);
    }

    #[test]
    fn recordings_cut_anywhere_never_panic(at in any::<usize>()) {
        let text = recording();
        let mut cut = at % (text.len() + 1);
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        feed(&text.as_bytes()[..cut]);
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        feed(&bytes);
    }

    #[test]
    fn mutated_scenes_never_panic(which in 0..SCENES.len(), ms in proptest::collection::vec(mutation(), 1..6)) {
        let mut src = SCENES[which].as_bytes().to_vec();
        for m in &ms {
            src = apply(&src, m);
        }
        feed(&src);
    }

    #[test]
    fn mutated_scripts_never_panic(which in 0..SCRIPTS.len(), ms in proptest::collection::vec(mutation(), 1..6)) {
        let mut src = SCRIPTS[which].as_bytes().to_vec();
        for m in &ms {
            src = apply(&src, m);
        }
        feed(&src);
    }

    #[test]
    fn single_number_replacements_never_panic(which in 0..SCENES.len(), nth in any::<usize>(), with in 0..NUMBERS.len()) {
        let src = apply(SCENES[which].as_bytes(), &Mutation::Number { nth, with });
        feed(&src);
    }
}

/// Deep nesting must be refused, not overflow the stack (RON has a recursion limit; so has the
/// position finder).
#[test]
fn deep_nesting_is_an_error() {
    let deep = format!("{}{}", "(".repeat(100_000), ")".repeat(100_000));
    feed(deep.as_bytes());
    let deep = format!("Scene(title: \"x\", tissue: {}", "[".repeat(100_000));
    feed(deep.as_bytes());
}
