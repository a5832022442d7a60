//! `dissect check`: exit 0 and `ok: path` for good scenes; exit 1 and one `path:line:column:` line per
//! bad scene; a missing file is one line and exit 1; never a panic.

use std::path::PathBuf;
use std::process::Command;

fn dissect() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dissect"))
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dissect-cli-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

#[test]
fn good_scenes_pass() {
    let out =
        dissect().arg("check").arg(scene("meninges.ron")).arg(scene("volume.ron")).output().expect("runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(stdout.lines().count(), 2);
    assert!(stdout.lines().all(|l| l.starts_with("ok: ")), "{stdout}");
}

#[test]
fn bad_scene_fails_with_one_line() {
    let good = std::fs::read_to_string(scene("meninges.ron")).expect("read");
    let bad = temp_file("bad.ron", &good.replacen("max_stretch: 1.3", "max_stretch: 0.5", 1));
    let out = dissect().arg("check").arg(scene("meninges.ron")).arg(&bad).output().expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    let want = format!("{}:16:51: tissue.layers[0].material.limits.max_stretch is 0.5", bad.display());
    assert!(lines[0].starts_with(&want), "{}", lines[0]);
    assert!(!stderr.contains("panicked") && !stderr.contains("backtrace"));
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("ok: "));
}

#[test]
fn missing_file_is_one_line() {
    let out = dissect().args(["check", "no/such/scene.ron"]).output().expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("no/such/scene.ron: cannot read the file"), "{stderr}");
}

#[test]
fn scripts_are_checked_with_a_flag() {
    let out =
        dissect().arg("check").arg("--script").arg(scene("scripts/meninges.ron")).output().expect("runs");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn help_has_examples() {
    let out = dissect().arg("--help").output().expect("runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0));
    for cmd in ["check", "run", "replay", "compare", "Examples:"] {
        assert!(stdout.contains(cmd), "{cmd} in {stdout}");
    }
}
