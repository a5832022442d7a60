//! Every bundled exercise (a scene with goals) scores honestly: each of its scripts scores what the
//! script's comment says (`// Score: A to B, passes.`), its careful script passes and its careless one
//! fails, and a session that only hovers or only lifts the tissue once scores under 10.

use std::path::{Path, PathBuf};

use dissect::runner;
use dissect::scene::{Action, Point, Scene, Script};
use dissect::simulation::InstrumentKind;
use dissect::training::Assessment;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// The bundled scenes with goals, by file stem.
fn exercises() -> Vec<(String, Scene)> {
    let mut out: Vec<(String, Scene)> = std::fs::read_dir(scenes_dir())
        .expect("scenes")
        .filter_map(|e| {
            let path = e.ok()?.path();
            if path.extension()? != "ron" {
                return None;
            }
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            scene.goals.as_ref()?;
            Some((path.file_stem()?.to_str()?.to_string(), scene))
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn play(scene: &Scene, script: &Script, label: &str) -> Assessment {
    let out = runner::run(scene, label, script, label, None, None).unwrap_or_else(|e| panic!("{e}"));
    out.metrics.assessment.unwrap_or_else(|| panic!("{label}: the scene has goals"))
}

/// `(low, high, passes)` from the script's `// Score: A to B, passes.` (or `fails`) line.
fn promise(text: &str, path: &Path) -> (f32, f32, bool) {
    let line = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("// Score:"))
        .unwrap_or_else(|| panic!("{}: no `// Score: A to B, passes.` line", path.display()));
    let words: Vec<&str> = line.split([' ', ',', '.']).filter(|w| !w.is_empty()).collect();
    match words.as_slice() {
        [a, "to", b, verdict] => (
            a.parse().unwrap_or_else(|_| panic!("{}: bad score {a}", path.display())),
            b.parse().unwrap_or_else(|_| panic!("{}: bad score {b}", path.display())),
            match *verdict {
                "passes" => true,
                "fails" => false,
                v => panic!("{}: `{v}`, expected passes or fails", path.display()),
            },
        ),
        _ => panic!("{}: `{line}`, expected `A to B, passes` or `A to B, fails`", path.display()),
    }
}

#[test]
fn every_script_scores_what_its_comment_says() {
    let exercises = exercises();
    assert!(exercises.len() >= 2, "the dural flap and the meninges exercises");
    for (stem, scene) in &exercises {
        let mut scripts: Vec<PathBuf> = std::fs::read_dir(scenes_dir().join("scripts"))
            .expect("scripts")
            .filter_map(|e| Some(e.ok()?.path()))
            .filter(|p| {
                p.file_stem()
                    .and_then(|s| s.to_str())
                    .is_some_and(|s| s == stem || s.starts_with(&format!("{stem}_")))
            })
            .collect();
        scripts.sort();
        let names: Vec<String> =
            scripts.iter().filter_map(|p| Some(p.file_stem()?.to_str()?.to_string())).collect();
        for kind in ["careful", "careless"] {
            assert!(names.contains(&format!("{stem}_{kind}")), "{stem}: no {kind} script in {names:?}");
        }
        for path in &scripts {
            let text = std::fs::read_to_string(path).expect("read");
            let (low, high, passes) = promise(&text, path);
            let script = Script::from_str(&text, path).unwrap_or_else(|e| panic!("{e}"));
            let a = play(scene, &script, &path.display().to_string());
            assert!(
                (low..=high).contains(&a.score) && a.passed == passes,
                "{}: scored {:.1} ({}), its comment says {low} to {high} ({}); {:?}",
                path.display(),
                a.score,
                if a.passed { "passed" } else { "failed" },
                if passes { "passes" } else { "fails" },
                a.feedback
            );
            let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
            if name.ends_with("_careful") {
                assert!(a.passed, "{name} passes");
            }
            if name.ends_with("_careless") {
                assert!(!a.passed, "{name} fails");
            }
            assert!(!a.feedback.is_empty() && a.feedback.len() <= 2, "{name}: {:?}", a.feedback);
        }
    }
}

#[test]
fn hovering_or_one_lift_alone_scores_under_10() {
    for (stem, scene) in exercises() {
        let top = match &scene.tissue {
            dissect::scene::Tissue::Layers(l) => l.layers.first().map_or(0.0, |l| l.offset),
            dissect::scene::Tissue::Volume(_) => 0.0,
        };
        // The forceps wander over the tissue without touching it.
        let mut hover = vec![Action::Select(InstrumentKind::Forceps)];
        for k in 0..20 {
            let (u, v) = (0.2 + 0.6 * (k % 5) as f32 / 4.0, 0.2 + 0.6 * (k / 5) as f32 / 3.0);
            hover.push(Action::MoveTo { to: Point::Surface(u, v, top + 0.01), steps: 100 });
        }
        // One grasp in the middle, lifted 2 cm and held.
        let lift = vec![
            Action::Select(InstrumentKind::Forceps),
            Action::Grasp(Point::Surface(0.5, 0.5, top)),
            Action::MoveTo { to: Point::Surface(0.5, 0.5, top + 0.02), steps: 600 },
            Action::Wait(400),
        ];
        for (name, actions) in [("hover", hover), ("one lift", lift)] {
            let a = play(&scene, &Script(actions), &format!("{stem}: {name}"));
            assert!(a.score < 10.0, "{stem}: {name} scored {:.1}: {:?}", a.score, a.breakdown);
            assert!(!a.passed, "{stem}: {name} passed");
        }
    }
}

#[test]
fn the_coach_says_what_holds_a_lift_and_never_asks_for_cuts_outside_the_target() {
    for (stem, scene) in exercises() {
        let top = match &scene.tissue {
            dissect::scene::Tissue::Layers(l) => l.layers.first().map_or(0.0, |l| l.offset),
            dissect::scene::Tissue::Volume(_) => 0.0,
        };
        let lift = Script(vec![
            Action::Select(InstrumentKind::Forceps),
            Action::Grasp(Point::Surface(0.5, 0.5, top)),
            Action::MoveTo { to: Point::Surface(0.5, 0.5, top + 0.02), steps: 600 },
            Action::Wait(3500),
        ]);
        let out = runner::run(&scene, &stem, &lift, "lift", None, None).unwrap_or_else(|e| panic!("{e}"));
        let assessor = out.assessor.as_ref().expect("goals");
        let advice =
            assessor.advice(&out.world).unwrap_or_else(|| panic!("{stem}: no advice for a held lift"));
        let expected = if scene.goals.as_ref().is_some_and(|g| !g.incision.is_empty()) {
            "finish the incision"
        } else {
            "uncut fibres under the target"
        };
        assert!(advice.text.contains(expected), "{stem}: {advice:?}");
    }
    // At the end of the careful session, with the flap folded back, the fibres said to hold it are
    // only the few target fibres left uncut (the many stretched fibres beyond the target are not the
    // trainee's to cut, and are never counted).
    let (_, scene) = exercises().into_iter().find(|(s, _)| s == "durotomy").expect("the default exercise");
    let script = Script::load(scenes_dir().join("scripts/durotomy_careful.ron")).expect("script");
    let out = runner::run(&scene, "durotomy", &script, "careful", None, None).expect("run");
    let assessor = out.assessor.as_ref().expect("goals");
    let a = assessor.assessment(&out.world);
    let held = assessor.holding_fibres(&out.world);
    assert!(
        held <= a.target_links - a.target_links_cut,
        "{held} of {} uncut",
        a.target_links - a.target_links_cut
    );
}

#[test]
fn the_report_is_small_summary_first_and_its_plot_peaks_where_the_panel_does() {
    let (_, scene) = exercises().into_iter().find(|(s, _)| s == "durotomy").expect("the default exercise");
    let mut script = Script::load(scenes_dir().join("scripts/durotomy_careful.ron")).expect("script");
    // A longer session: 20 s of waiting after the work (2000 samples, sampled down to the report's 240).
    script.0.push(Action::Wait(20_000));
    let out = runner::run(&scene, "durotomy", &script, "careful", None, None).expect("run");
    let assessor = out.assessor.as_ref().expect("goals");
    let report = assessor.report(&out.world, &scene.title, dissect::training::utc_now_string());
    let text = serde_json::to_string_pretty(&report).expect("json");
    assert!(text.len() < 200_000, "report.json is {} bytes", text.len());
    let at = |key: &str| text.find(&format!("\"{key}\"")).unwrap_or_else(|| panic!("no {key}"));
    let order = ["title", "date", "passed", "score", "feedback", "goals", "assessment", "history"];
    for w in order.windows(2) {
        assert!(at(w[0]) < at(w[1]), "{} before {}", w[0], w[1]);
    }
    assert!(report.history.len() <= dissect::training::REPORT_SAMPLES);
    let peak = report.history.iter().map(|s| s.stretch).fold(1.0, f32::max);
    assert_eq!(peak, report.assessment.peak_stretch, "the plot's peak is the panel's");
    assert!(report.passed && report.title == scene.title && report.feedback.len() <= 2);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("report_plot");
    std::fs::create_dir_all(&dir).expect("dir");
    dissect::training::write_plot(&dir.join("report.png"), &report).expect("plot");
    dissect::training::write_report(&dir.join("report.json"), &report).expect("json");
}

/// The default exercise's checklist ticks "Lift the flap's free edge" only once the U is cut: the dura
/// grasped and lifted before the incision leaves that step unticked (and the score at 0), the careful
/// script, which lifts after the U, ticks every step.
#[test]
fn the_lift_step_ticks_only_once_the_incision_has_freed_the_flap() {
    let (_, scene) = exercises().into_iter().find(|(s, _)| s == "durotomy").expect("the default exercise");
    let goals = scene.goals.as_ref().expect("goals");
    let lift_step = goals
        .steps
        .iter()
        .position(|s| s.done == dissect::training::StepCheck::Grasp)
        .expect("a Grasp step in the checklist");
    let early = Script(vec![
        Action::Select(InstrumentKind::Forceps),
        Action::Grasp(Point::Surface(0.5, 0.68, 0.003)),
        Action::MoveTo { to: Point::Surface(0.5, 0.68, 0.009), steps: 300 },
        Action::Wait(200),
        Action::Release,
        Action::Wait(100),
    ]);
    let a = play(&scene, &early, "durotomy: lift before the U");
    assert!(!a.steps_done[lift_step], "lifting the uncut dura ticked the lift step: {:?}", a.steps_done);
    assert!(a.steps_done.iter().all(|d| !d), "{:?}", a.steps_done);
    let careful = Script::load(scenes_dir().join("scripts/durotomy_careful.ron")).expect("script");
    let a = play(&scene, &careful, "durotomy: careful");
    assert!(a.steps_done.iter().all(|&d| d), "the careful opening ticks every step: {:?}", a.steps_done);
}
