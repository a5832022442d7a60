//! `dissect run`: every bundled scene runs its script headless; two runs give byte-identical
//! `state.json`; `metrics.json` has the figures educators and CI read; bad paths get one line and exit 1.

use std::path::{Path, PathBuf};
use std::process::Command;

fn dissect() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dissect"))
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(scene: &str, out: &Path, steps: Option<u64>) -> std::process::Output {
    let mut c = dissect();
    c.arg("run")
        .arg(root().join("scenes").join(format!("{scene}.ron")))
        .arg("--script")
        .arg(root().join("scenes/scripts").join(format!("{scene}.ron")))
        .arg("--out")
        .arg(out);
    if let Some(n) = steps {
        c.args(["--steps", &n.to_string()]);
    }
    c.output().expect("runs")
}

#[test]
fn bundled_scenes_run_and_repeat_bit_for_bit() {
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_run");
    for scene in ["durotomy", "meninges", "cylinder", "sphere", "volume", "fem_block"] {
        let (a, b) = (tmp.join(format!("{scene}_a")), tmp.join(format!("{scene}_b")));
        for dir in [&a, &b] {
            let out = run(scene, dir, Some(600));
            assert!(out.status.success(), "{scene}: {}", String::from_utf8_lossy(&out.stderr));
        }
        let sa = std::fs::read(a.join("state.json")).expect("state a");
        let sb = std::fs::read(b.join("state.json")).expect("state b");
        assert!(sa == sb, "{scene}: state.json differs between two runs");
        let metrics: serde_json::Value =
            serde_json::from_slice(&std::fs::read(a.join("metrics.json")).expect("metrics")).expect("json");
        for key in ["steps", "elements_moved_total", "links_cut", "links_torn", "max_stretch"] {
            assert!(metrics.get(key).is_some(), "{scene}: metrics.json lacks {key}");
        }
        for key in ["mean", "p50", "p99", "max"] {
            assert!(metrics["step_time_us"].get(key).is_some(), "{scene}: step_time_us lacks {key}");
        }
        assert_eq!(metrics["steps"], 600);
        let state: serde_json::Value = serde_json::from_slice(&sa).expect("state json");
        assert!(state["layers"].as_array().is_some_and(|l| !l.is_empty()));
    }
}

#[test]
fn missing_and_bad_inputs_get_one_line_and_exit_1() {
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_run_bad");
    let out = dissect()
        .arg("run")
        .arg("no/such/scene.ron")
        .args(["--script", "no/such/script.ron", "--out"])
        .arg(&tmp)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("no/such/scene.ron"), "{err}");

    std::fs::create_dir_all(&tmp).expect("tmp");
    let bad = tmp.join("bad_script.ron");
    std::fs::write(&bad, "Script([ Wait(0) ])").expect("write");
    let out = dissect()
        .arg("run")
        .arg(root().join("scenes/meninges.ron"))
        .arg("--script")
        .arg(&bad)
        .arg("--out")
        .arg(&tmp)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("bad_script.ron:1:"), "{err}");
    assert!(!err.contains("panicked"));
}
