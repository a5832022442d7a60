//! Hostile and malformed input (issue 17): one regression test per class of input that once made the
//! program panic, hang, eat the machine or overwrite a file. Each test is named for its class; what
//! the program must do instead is in its comment. The fuzz target over the same files is
//! `scene_fuzz.rs`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use dissect::scene::{Recording, Scene, SceneError, Script};

fn dissect() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dissect"))
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile_input").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn text(out: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// A one-layer plane with the given resolution and extra fields.
fn plane(res: (u32, u32), extra: &str) -> String {
    format!(
        "Scene(\n  title: \"t\",\n  tissue: Layers((\n    surface: Plane(width: 0.06, depth: 0.06),\n    \
         resolution: ({}, {}),\n    layers: [(name: \"skin\")],\n  )),\n{extra})",
        res.0, res.1
    )
}

/// The position of an error, which every refusal of a file's content has.
fn located(e: &SceneError) -> (usize, usize) {
    e.line_column().unwrap_or_else(|| panic!("no line and column: {e}"))
}

fn script_error(src: &str) -> String {
    let e = Script::from_str(src, "s.ron").expect_err("refused");
    let (line, _) = located(&e);
    assert!(line >= 1);
    e.to_string()
}

// 1. The documented maximum runs: a scene at the stated element limit passes `check`, builds, steps
//    and renders (the renderer's buffers stay within every device's 256 MiB), and one element more
//    is refused by `check` with the limit.
#[test]
fn class01_documented_maximum_builds_steps_and_renders() {
    let max = dissect::scene::MAX_SCENE_ELEMENTS as u32;
    let side = (max as f64).sqrt() as u32;
    assert_eq!(side * side, max, "the maximum is a square sheet");
    let src = plane((side, side), "  simulation: (relax_sweeps: 1),\n");
    let scene = Scene::from_str(&src, "max.ron").expect("the documented maximum is valid");
    let mut world = scene.build_world(false).expect("builds");
    for _ in 0..3 {
        world.step();
    }
    let over = plane((side, side + 1), "");
    let e = Scene::from_str(&over, "over.ron").expect_err("over the maximum");
    assert!(e.to_string().contains(&max.to_string()), "{e}");
    // Rendered offscreen (small picture: the buffers are the scene's, not the picture's).
    let Ok(gpu) = dissect::render::Gpu::headless() else {
        eprintln!("no GPU adapter: the rendering half of this test is skipped");
        return;
    };
    let mut snapshot = dissect::simulation::Snapshot::default();
    world.snapshot_into(&mut snapshot);
    let camera = dissect::render::OrbitCamera::from_spec(&scene.trainee_camera());
    let image = dissect::render::render_to_image(&gpu, &snapshot, &camera, 64, 48).expect("renders");
    assert_eq!(image.dimensions(), (64, 48));
}

// 2. Guards that overflow: the node product of `compare` no longer wraps to 0; the value is refused at
//    once, and the library's own guards saturate.
#[test]
fn class02_size_products_do_not_wrap() {
    let out = dissect().args(["compare", "--nodes", "8796093022208"]).output().expect("runs");
    assert!(!out.status.success());
    assert!(text(&out).contains("--nodes"), "{}", text(&out));
    let huge = 1usize << 43;
    let mesh = dissect::fem::TetMesh::block([huge; 3], 0.005, dissect::fem::Split::Six);
    assert!(matches!(mesh, Err(dissect::fem::FemError::TooBig { .. })));
}

// 3. Unbounded reads: devices, pipes and files over the size limit are refused before they are read.
#[test]
fn class03_reads_are_bounded() {
    for dev in ["/dev/zero", "/dev/urandom"] {
        if !Path::new(dev).exists() {
            continue;
        }
        for e in [
            Scene::load(dev).map(drop).expect_err("scene"),
            Script::load(dev).map(drop).expect_err("script"),
            Recording::load(dev).map(drop).expect_err("recording"),
        ] {
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let out = dissect().arg("check").arg(dev).output().expect("runs");
        assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    }
    let dir = tmp("class03");
    let big = dir.join("big.ron");
    let f = std::fs::File::create(&big).expect("create");
    f.set_len(dissect::scene::MAX_FILE_BYTES + 1).expect("sparse file");
    let e = Scene::load(&big).expect_err("too long");
    assert!(e.to_string().contains("more than the limit"), "{e}");
    // A long list with an error at its end: the position finder keeps a bounded tree.
    let n = 300_000;
    let coords: Vec<String> = (0..n).map(|i| format!("{}", i as f64 / n as f64)).collect();
    let mut coords = coords.join(", ");
    coords.push_str(", 2.0");
    let src = plane((n + 1, 2), "").replace("layers:", &format!("u_coords: Some([{coords}]),\n    layers:"));
    let e = Scene::from_str(&src, "long.ron").expect_err("2.0 is no fraction");
    assert!(e.to_string().contains("u_coords[300000]"), "{e}");
    // Invalid UTF-8 is located.
    let bad = dir.join("latin1.ron");
    std::fs::write(&bad, b"Scene(\n  title: \"caf\xe9\",\n)").expect("write");
    let e = Scene::load(&bad).expect_err("not UTF-8");
    assert_eq!(e.line_column(), Some((2, 14)), "{e}");
}

// 4. Valid-looking scripts that never end: every script ends by `MAX_SCRIPT_STEPS`, `--steps` is
//    bounded the same way and stops when the script ends.
#[test]
fn class04_scripts_end_within_the_stated_length() {
    for src in [
        "Script([At(18446744073709551615)])",
        "Script([Wait(4294967295)])",
        "Script([Select(Probe), MoveTo(to: World(0.0, 0.0, 0.0), steps: 4000000000)])",
        "Script([Wait(9000000), Wait(1000001)])",
    ] {
        let e = script_error(src);
        assert!(e.contains(&dissect::scene::MAX_SCRIPT_STEPS.to_string()), "{e}");
    }
    Script::from_str("Script([Wait(9000000), Wait(1000000)])", "s.ron").expect("exactly the maximum");
    let out = dissect()
        .arg("run")
        .arg(root().join("scenes/volume.ron"))
        .args(["--script", "x.ron", "--out", "x", "--steps", "18446744073709551615"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2), "clap refuses it: {}", text(&out));
    // `--steps` past the script's end stops at its end.
    let dir = tmp("class04");
    let script = dir.join("short.ron");
    std::fs::write(&script, "Script([Select(Probe), Wait(40)])").expect("write");
    let out = dissect()
        .arg("run")
        .arg(root().join("scenes/volume.ron"))
        .arg("--script")
        .arg(&script)
        .arg("--out")
        .arg(dir.join("out"))
        .args(["--steps", "5000"])
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", text(&out));
    let metrics: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/metrics.json")).expect("metrics")).expect("json");
    assert_eq!(metrics["steps"], 40);
}

// 5. Unknown fields inside enum variants are errors, pointed at, like everywhere else.
#[test]
fn class05_unknown_fields_inside_enums_are_errors() {
    let cases = [
        plane((8, 8), "").replace("depth: 0.06)", "depth: 0.06, height: 0.02)"),
        plane((8, 8), "").replace(
            "(name: \"skin\")",
            "(name: \"skin\", material: (limits: Relative(max_stretch: 1.2, min_compress: 0.8, max_shear: 0.3, tear_ratio: 1.0)))",
        ),
        plane((8, 8), "  goals: Some((target: Rect(u: (0.4, 0.6), v: (0.4, 0.6), radius: 0.5))),\n"),
        plane((8, 8), "").replace("layers:", "pinned: Patch(u: (0.0, 1.0), v: (0.0, 0.1), w: (0.0, 1.0)),\n    layers:"),
    ];
    for (src, field) in cases.iter().zip(["height", "tear_ratio", "radius", "w"]) {
        let e = Scene::from_str(src, "u.ron").expect_err("unknown field");
        let (line, column) = located(&e);
        let at: String = src.lines().nth(line - 1).expect("line").chars().skip(column - 1).collect();
        assert!(at.starts_with(field), "{e} points at {at:?}");
        assert!(e.to_string().contains(&format!("unknown field `{field}`")), "{e}");
    }
}

// 6. Raw `Command(...)` actions are checked like the actions: finite and in range, materials valid,
//    and against the scene: instruments offered, depths possible, elements and materials it has.
#[test]
fn class06_raw_commands_are_checked() {
    for (src, says) in [
        ("Script([Command(MoveTo((NaN, 0.0, 0.0)))])", "finite"),
        ("Script([Command(MoveTo((0.0, inf, 0.0)))])", "finite"),
        ("Script([Command(SetAxis((0.0, 0.0, 0.0)))])", "direction"),
        ("Script([Command(Roll(NaN))])", "finite"),
        ("Script([Command(SetRelaxSweeps(5000))])", "1000"),
        (
            "Script([Command(SetMaterial((0), (limits: Relative(max_stretch: 0.5, min_compress: 0.8, max_shear: 0.3))))])",
            "max_stretch",
        ),
    ] {
        let e = script_error(src);
        assert!(e.contains(says), "{src}: {e}");
    }
    let one_layer =
        Scene::from_str(&plane((8, 8), "  instruments: [Forceps, Probe],\n"), "p.ron").expect("scene");
    for (src, says) in [
        ("Script([Command(Select(Scalpel)), Command(BeginCut)])", "does not offer"),
        ("Script([Command(SetDepth(Lower))])", "one layer"),
        ("Script([Command(GraspElement((64)))])", "64 elements"),
        ("Script([Select(Forceps), GraspElement(1000)])", "64 elements"),
        (
            "Script([Command(SetMaterial((3), (limits: Relative(max_stretch: 1.5, min_compress: 0.8, max_shear: 0.3))))])",
            "1 material",
        ),
    ] {
        let script = Script::from_str(src, "s.ron").expect("valid alone");
        let e = script.check_against(&one_layer).expect_err("not on this scene");
        assert!(e.contains(says), "{src}: {e}");
    }
    // The player never keeps a non-finite target, whatever reaches it (a script built in code).
    let mut world = one_layer.build_world(false).expect("world");
    let mut player = dissect::runner::Player::new(vec![
        dissect::scene::Action::Command(dissect::simulation::Command::MoveTo([f32::NAN, 0.0, 0.0])),
        dissect::scene::Action::MoveTo { to: dissect::scene::Point::World(0.0, 0.01, 0.0), steps: 20 },
    ]);
    for _ in 0..25 {
        player.feed(&mut world);
        world.step();
    }
    let t = world.instrument().target;
    assert!(t.iter().all(|x| x.is_finite()) && (t[1] - 0.01).abs() < 1e-6, "{t:?}");
}

// 7. A recording cut anywhere in its action list (after a comma inside a tuple too) is read up to its
//    last complete line.
#[test]
fn class07_cut_recordings_read_to_their_last_complete_line() {
    let dir = tmp("class07");
    let path = dir.join("rec.ron");
    let mut rec =
        dissect::scene::Recorder::create(&path, "scenes/meninges.ron", dissect::scene::DEFAULT_SCENE)
            .expect("recorder");
    use dissect::simulation::Command as C;
    let commands = [
        C::Select(dissect::simulation::InstrumentKind::Forceps),
        C::MoveTo([0.0, 0.01, 0.0]),
        C::Grasp,
        C::MoveTo([0.001, 0.012, -0.002]),
        C::SetAxis([0.3, 0.9, 0.3]),
        C::Release,
    ];
    for (i, c) in commands.iter().enumerate() {
        rec.record(10 * i as u64, c).expect("record");
    }
    rec.finish(100).expect("finish");
    let full = std::fs::read_to_string(&path).expect("read");
    let whole = Recording::from_str(&full, "rec.ron").expect("whole recording");
    let start = full.find("actions: [").expect("actions") + "actions: [\n".len();
    for cut in start..full.len() {
        if !full.is_char_boundary(cut) {
            continue;
        }
        let r = Recording::from_str(&full[..cut], "rec.ron")
            .unwrap_or_else(|e| panic!("cut at byte {cut} ({:?}): {e}", &full[cut.saturating_sub(20)..cut]));
        assert!(r.actions.len() <= whole.actions.len());
        assert_eq!(r.actions[..], whole.actions[..r.actions.len()]);
    }
}

// 8. `check` is authoritative: what building the tissue would refuse is refused by `check`, with a
//    line and column; `check --script` checks a recording's scene and its actions against it.
#[test]
fn class08_check_refuses_what_the_build_would() {
    let cases = [
        plane((8, 8), "").replace("width: 0.06", "width: 1e38"),
        "Scene(title: \"c\", tissue: Layers((surface: Cylinder(radius: 0.02, length: 0.1),\n layers: [(name: \"a\", offset: 1e30)])))".to_owned(),
        plane((3, 2), "").replace("layers:", "u_coords: Some([0.0, 1e-40, 1.0]),\n    layers:"),
        "Scene(title: \"f\", tissue: Volume((size: (0.03, 0.06, 0.03), resolution: (8, 8, 8),\n model: Fem(()))))".to_owned(),
        "Scene(title: \"f\", tissue: Volume((size: (0.1, 0.1, 0.1), resolution: (30, 30, 30),\n model: Fem(()))))".to_owned(),
        plane((8, 8), "  cameras: (trainee: Some((eye: (0.0, 1e30, 0.0), target: (0.0, 0.0, 0.0)))),\n"),
    ];
    for src in &cases {
        let e = Scene::from_str(src, "c.ron").expect_err(src);
        located(&e);
    }
    // Whatever passes `check` near those edges builds.
    for src in [
        plane((8, 8), "").replace("width: 0.06", "width: 100.0"),
        plane((3, 2), "").replace("layers:", "u_coords: Some([0.0, 0.001, 1.0]),\n    layers:"),
        "Scene(title: \"f\", tissue: Volume((size: (0.03, 0.03, 0.03), resolution: (6, 6, 6),\n model: Fem(()))))".to_owned(),
    ] {
        let scene = Scene::from_str(&src, "ok.ron").expect("valid");
        scene.build_world(false).unwrap_or_else(|e| panic!("{src}: passes check but does not build: {e}"));
    }
    // A recording whose scene has no scalpel but whose actions select one.
    let dir = tmp("class08");
    let scene_source = plane((8, 8), "  instruments: [Forceps],\n");
    let rec = format!(
        "Recording(\n    scene: \"p.ron\",\n    scene_source: {},\n    actions: [\n        At(0), Command(Select(Scalpel)),\n        At(5),\n    ],\n)\n",
        ron::to_string(&scene_source).expect("quote")
    );
    let path = dir.join("rec.ron");
    std::fs::write(&path, &rec).expect("write");
    let out = dissect().args(["check", "--script"]).arg(&path).output().expect("runs");
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("rec.ron:5:"), "{}", text(&out));
    let bad_scene = rec.replace("resolution: (8, 8)", "resolution: (1, 8)");
    std::fs::write(&path, &bad_scene).expect("write");
    let out = dissect().args(["check", "--script"]).arg(&path).output().expect("runs");
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("scene_source"), "{}", text(&out));
}

/// A run that would take very long if it were simulated: its outputs must be refused first.
fn long_script(dir: &Path) -> PathBuf {
    let script = dir.join("long.ron");
    std::fs::write(&script, "Script([Select(Probe), Wait(9000000)])").expect("write");
    script
}

// 9. `--out` onto a file, or into a place that cannot be written, fails before the simulation.
#[test]
fn class09_outputs_are_checked_before_simulating() {
    let dir = tmp("class09");
    let script = long_script(&dir);
    let file = dir.join("a_file");
    std::fs::write(&file, "keep").expect("write");
    for out_dir in [file.clone(), file.join("below")] {
        let out = dissect()
            .arg("run")
            .arg(root().join("scenes/volume.ron"))
            .arg("--script")
            .arg(&script)
            .arg("--out")
            .arg(&out_dir)
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(1), "{}", text(&out));
        assert!(!text(&out).contains("steps,"), "nothing simulated: {}", text(&out));
    }
    assert_eq!(std::fs::read_to_string(&file).expect("still there"), "keep");
}

// 10. `--record` onto the scene or the script (under any name) is refused; the input is unchanged.
#[test]
fn class10_record_refuses_an_input_path() {
    let dir = tmp("class10");
    let script = dir.join("s.ron");
    std::fs::write(&script, "Script([Select(Probe), Wait(10)])").expect("write");
    let scene = dir.join("volume.ron");
    std::fs::copy(root().join("scenes/volume.ron"), &scene).expect("copy");
    let before = (std::fs::read(&scene).expect("scene"), std::fs::read(&script).expect("script"));
    let alias = dir.join(".").join("s.ron");
    for record in [&scene, &script, &alias] {
        let out = dissect()
            .arg("run")
            .arg(&scene)
            .arg("--script")
            .arg(&script)
            .arg("--out")
            .arg(dir.join("out"))
            .arg("--record")
            .arg(record)
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(1), "{}", text(&out));
        assert!(text(&out).contains("--record would overwrite"), "{}", text(&out));
    }
    assert_eq!(before, (std::fs::read(&scene).expect("scene"), std::fs::read(&script).expect("script")));
}

// 11. A closed pipe on the standard output ends the command quietly, without a panic.
#[test]
fn class11_broken_pipe_ends_quietly() {
    let scenes: Vec<PathBuf> = (0..200).map(|_| root().join("scenes/volume.ron")).collect();
    let mut child = dissect()
        .arg("check")
        .args(&scenes)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawns");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("waits");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(out.status.code(), Some(101), "{err}");
}

// 12. A scene whose steps will cost far more than its rate allows gets a warning from `check` (and the
//     trainer); it stays valid. The bundled scenes get none.
#[test]
fn class12_costly_scenes_are_warned_about() {
    let dir = tmp("class12");
    let path = dir.join("slow.ron");
    std::fs::write(&path, plane((1024, 1024), "  simulation: (relax_sweeps: 1000),\n")).expect("write");
    let out = dissect().arg("check").arg(&path).output().expect("runs");
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning") && err.contains("relax_sweeps"), "{err}");
    for name in ["meninges", "cylinder", "sphere", "volume", "fem_block"] {
        let scene = Scene::load(root().join(format!("scenes/{name}.ron"))).expect("bundled");
        assert_eq!(scene.cost_warning(), None, "{name}");
    }
}

// 13. Points so far away that their arithmetic overflows are refused with their position.
#[test]
fn class13_far_points_are_refused() {
    for src in [
        "Script([Select(Probe), MoveTo(to: World(3e38, 3e38, -3e38), steps: 10)])",
        "Script([Select(Forceps), Grasp(Surface(0.5, 0.5, 1e30))])",
        "Script([Command(MoveTo((3e38, 0.0, 0.0)))])",
    ] {
        let e = script_error(src);
        assert!(e.contains("100 metres"), "{e}");
    }
}

// 14. The smallest layers `check` accepts build and play: two layers 2 elements wide have their
//     fibres in one row, and the grid that finds links near a cut had a cell of 1e-19 m there (a
//     grid of 10^17 cells: the build aborted on the allocation). A grasp, a lift and a release each.
#[test]
fn class14_the_smallest_layers_build_and_play() {
    use dissect::simulation::{Command as C, InstrumentKind};
    for (nu, nv) in [(2, 2), (3, 2), (2, 5)] {
        let mut scene = Scene::load(root().join("scenes/meninges.ron")).expect("bundled");
        if let dissect::scene::Tissue::Layers(l) = &mut scene.tissue {
            l.resolution = [nu, nv];
        }
        let mut world = scene.build_world(false).expect("builds");
        let t = world.tissue();
        let top = t.body().lattice().rest_positions()[t.layers()[0].first as usize][2];
        let dura = t.surface_point(0.5, 0.5, top);
        world.push(C::Select(InstrumentKind::Forceps));
        world.push(C::MoveTo(dura));
        world.push(C::Grasp);
        for s in 0..50 {
            world.push(C::MoveTo([dura[0], dura[1] + 0.0001 * s as f32, dura[2]]));
            world.step();
        }
        world.push(C::Release);
        for _ in 0..50 {
            world.step();
        }
    }
}
