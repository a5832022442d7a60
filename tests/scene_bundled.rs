//! Every bundled scene and script loads and validates, each script fits its scene, and the default
//! scene built into the binary is the file on disk.

use std::path::{Path, PathBuf};

use dissect::scene::{DEFAULT_SCENE, Scene, Script, Tissue};

fn ron_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    files.sort();
    files
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

#[test]
fn every_bundled_scene_loads() {
    let files = ron_files(&scenes_dir());
    assert!(files.len() >= 4, "expected the four bundled scenes, found {files:?}");
    for f in files {
        let scene = Scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
        scene.validate().unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        // Written back out, it reads back equal.
        let text = scene.to_ron_string().expect("serializes");
        assert_eq!(Scene::from_str(&text, &f).unwrap_or_else(|e| panic!("{e}\n{text}")), scene);
    }
}

#[test]
fn every_bundled_script_loads_and_fits_its_scene() {
    let files = ron_files(&scenes_dir().join("scripts"));
    assert!(files.len() >= 4, "expected a script per scene, found {files:?}");
    for f in files {
        let script = Script::load(&f).unwrap_or_else(|e| panic!("{e}"));
        assert!(script.duration_steps() > 0, "{}", f.display());
        // `NAME.ron` goes with scene `NAME.ron`; variants `NAME_something.ron` with it too.
        let mut scene_path = scenes_dir().join(f.file_name().expect("file name"));
        if !scene_path.exists() {
            let stem = f.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
            let base = stem.split('_').next().unwrap_or(stem);
            scene_path = scenes_dir().join(format!("{base}.ron"));
        }
        let scene = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{e}"));
        script.check_against(&scene).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let text = script.to_ron_string().expect("serializes");
        assert_eq!(Script::from_str(&text, &f).unwrap_or_else(|e| panic!("{e}\n{text}")), script);
    }
}

#[test]
fn embedded_default_is_the_file() {
    let on_disk = std::fs::read_to_string(scenes_dir().join("durotomy.ron")).expect("read");
    assert_eq!(DEFAULT_SCENE, on_disk);
    let scene = Scene::default_scene().unwrap_or_else(|e| panic!("{e}"));
    let Tissue::Layers(l) = &scene.tissue else { panic!("the dural flap has layers") };
    assert_eq!(l.layers.len(), 2);
    assert!(l.connective.is_some());
    let goals = scene.goals.as_ref().expect("the default exercise has goals");
    assert!(goals.incision.len() >= 4, "a U-shaped incision");
    assert!(!goals.steps.is_empty(), "a checklist");
}

#[test]
fn a_short_scene_gets_its_defaults() {
    let src = r#"Scene(title: "Short", tissue: Layers((surface: Plane(width: 0.05, depth: 0.05), layers: [(name: "skin")])))"#;
    let scene = Scene::from_str(src, "short.ron").unwrap_or_else(|e| panic!("{e}"));
    let Tissue::Layers(l) = &scene.tissue else { panic!("layers") };
    assert_eq!(l.resolution, [48, 48]);
    assert_eq!(scene.instruments.len(), 3);
    assert_eq!(scene.simulation.rate_hz, 1000);
    let cam = scene.trainee_camera();
    assert!(cam.eye[1] > 0.0 && cam.eye[2] > 0.0);
    assert_eq!(l.u_fractions().len(), 48);
    assert_eq!(l.u_fractions()[47], 1.0);
}

/// The RON blocks of `scenes/README.md`, in order.
fn readme_blocks() -> Vec<String> {
    let text = std::fs::read_to_string(scenes_dir().join("README.md")).expect("read README");
    text.split("```ron\n").skip(1).filter_map(|b| b.split("```").next()).map(str::to_owned).collect()
}

#[test]
fn readme_examples_load() {
    let blocks = readme_blocks();
    assert_eq!(blocks.len(), 3, "the minimal scene, the script example and the recording example");
    dissect::scene::Recording::from_str(&blocks[2], "README.md").unwrap_or_else(|e| panic!("{e}"));
    Scene::from_str(&blocks[0], "README.md").unwrap_or_else(|e| panic!("{e}"));
    let script = Script::from_str(&blocks[1], "README.md").unwrap_or_else(|e| panic!("{e}"));
    let default = Scene::default_scene().unwrap_or_else(|e| panic!("{e}"));
    script.check_against(&default).unwrap_or_else(|e| panic!("{e}"));
    // The example is the default scene's script, as the README says.
    let file = Script::load(scenes_dir().join("scripts/durotomy.ron")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(script, file, "the README's example is scripts/durotomy.ron");
}
