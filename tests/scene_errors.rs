//! Bad scenes get one message that says what is wrong and what is expected, at the exact line and
//! column of the offending text.

use dissect::scene::{Scene, SceneError, Script};

/// A small valid scene; each test changes one thing in it.
const BASE: &str = r#"Scene(
    title: "Test",
    tissue: Layers((
        surface: Box(width: 0.08, depth: 0.06, height: 0.02),
        resolution: (64, 48),
        layers: [
            (name: "upper", offset: 0.003,
             material: (limits: Relative(max_stretch: 1.3, min_compress: 0.8, max_shear: 0.25), stiffness: 1.0)),
            (name: "lower", offset: 0.0),
        ],
        connective: (density: 0.5, min_gap: 0.0005),
    )),
)
"#;

fn load(from: &str, to: &str) -> SceneError {
    assert!(BASE.contains(from), "{from}");
    let src = BASE.replacen(from, to, 1);
    match Scene::from_str(&src, "bad.ron") {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => e,
    }
}

fn expect(e: SceneError, line_col: &str, parts: &[&str]) {
    let text = e.to_string();
    let want = format!("bad.ron:{line_col}: ");
    assert!(text.starts_with(&want), "expected {want}..., got {text}");
    assert!(!text.contains('\n'), "one line: {text}");
    for p in parts {
        assert!(text.contains(p), "expected {p:?} in {text}");
    }
}

#[test]
fn base_is_valid() {
    Scene::from_str(BASE, "bad.ron").unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn misspelt_field() {
    let e = load("stiffness: 1.0", "stifness: 1.0");
    assert!(matches!(e, SceneError::Parse { .. }));
    expect(
        e,
        "8:97",
        &["unknown field `stifness`", "`limits`, `stiffness`, `tear_ratio`", "did you mean `stiffness`"],
    );
}

#[test]
fn misspelt_field_of_the_limits() {
    // `Relative` refuses unknown fields (it once ignored them, and RON reported `max_stretch` missing).
    let e = load("max_stretch: 1.3", "max_strech: 1.3");
    expect(e, "8:42", &["unknown field `max_strech`", "did you mean `max_stretch`?"]);
}

#[test]
fn string_where_a_number_belongs() {
    let e = load("width: 0.08", "width: \"wide\"");
    assert!(matches!(e, SceneError::Parse { .. }));
    expect(e, "4:29", &["expected a number"]);
}

#[test]
fn stretch_limit_below_one() {
    let e = load("max_stretch: 1.3", "max_stretch: 0.5");
    assert!(matches!(e, SceneError::Invalid { .. }));
    expect(e, "8:55", &["tissue.layers[0].material.limits.max_stretch is 0.5", "expected at least 1"]);
}

#[test]
fn nan() {
    let e = load("min_compress: 0.8", "min_compress: NaN");
    expect(e, "8:74", &["tissue.layers[0].material.limits.min_compress is NaN", "expected a finite number"]);
}

#[test]
fn resolution_too_large() {
    let e = load("resolution: (64, 48)", "resolution: (100000, 100000)");
    expect(
        e,
        "5:21",
        &["tissue.resolution is (100000, 100000) with 2 layer(s)", "20000000000 elements", "1048576", "MiB"],
    );
}

#[test]
fn resolution_too_small_points_at_the_axis() {
    let e = load("resolution: (64, 48)", "resolution: (64, 1)");
    expect(e, "5:26", &["tissue.resolution[1] is 1", "at least 2"]);
}

#[test]
fn layers_in_the_wrong_order() {
    let e = load("offset: 0.003", "offset: -0.001");
    expect(e, "7:37", &["tissue.layers[0].offset is -0.001", "0 or more"]);
    let e = load("(name: \"lower\", offset: 0.0)", "(name: \"lower\", offset: 0.004)");
    expect(e, "7:37", &["tissue.layers[0].offset is 0.003", "more than the lower layer's offset (0.004)"]);
}

#[test]
fn min_gap_not_below_the_gap() {
    let e = load("min_gap: 0.0005", "min_gap: 0.003");
    expect(e, "11:45", &["tissue.connective.min_gap is 0.003", "less than the gap between the layers"]);
}

#[test]
fn density_out_of_range() {
    let e = load("density: 0.5", "density: 0.0");
    expect(e, "11:31", &["tissue.connective.density is 0", "(0, 1]"]);
}

#[test]
fn fibre_spacing_below_zero() {
    let e = load("min_gap: 0.0005)", "min_gap: 0.0005, spacing: -0.001)");
    expect(e, "11:62", &["tissue.connective.spacing is -0.001", "at least 0 metres"]);
}

#[test]
fn colour_out_of_range() {
    let e =
        load("(name: \"lower\", offset: 0.0)", "(name: \"lower\", offset: 0.0, color: (0.5, 1.5, 0.5, 1.0))");
    expect(e, "9:55", &["tissue.layers[1].color[1] is 1.5", "[0, 1]"]);
}

#[test]
fn missing_required_field() {
    let e = load("    title: \"Test\",\n", "");
    expect(e, "12:1", &["missing field `title`"]);
}

#[test]
fn syntax_error() {
    let e = load("resolution: (64, 48),", "resolution: (64, 48)");
    expect(e, "6:9", &[]);
}

#[test]
fn whole_number_with_a_decimal_point() {
    let e = load("    title: \"Test\",\n", "    title: \"Test\",\n    simulation: (rate_hz: 1000.5),\n");
    expect(e, "3:31", &["whole number"]);
}

#[test]
fn rate_out_of_range() {
    let e = load("    title: \"Test\",\n", "    title: \"Test\",\n    simulation: (rate_hz: 10),\n");
    expect(e, "3:27", &["simulation.rate_hz is 10", "[50, 20000]"]);
}

#[test]
fn fem_parameters() {
    let src = "Scene(title: \"V\", tissue: Volume((size: (0.04, 0.04, 0.04),\n  model: Fem((young_modulus: 3000.0, poisson_ratio: 0.5)))))";
    let e = Scene::from_str(src, "bad.ron").expect_err("Poisson 0.5");
    expect(e, "2:53", &["tissue.model.poisson_ratio is 0.5", "(-1, 0.5)"]);
    let ok = src.replace("0.5)", "0.45)");
    Scene::from_str(&ok, "ok.ron").unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn poisson_ratio_belongs_to_volumes() {
    // A layer has no cells to relax: its material's Poisson's ratio is refused where it is written.
    let e = load("stiffness: 1.0)", "stiffness: 1.0, poisson_ratio: 0.45)");
    expect(e, "8:128", &["poisson_ratio is Some(0.45), expected None", "a layer has none"]);
    // A volume's must lie in (-1, 0.5).
    let src =
        "Scene(title: \"V\", tissue: Volume((size: (0.04, 0.04, 0.04),\n  material: (poisson_ratio: 0.5))))";
    let e = Scene::from_str(src, "bad.ron").expect_err("Poisson 0.5");
    expect(e, "2:29", &["tissue.material.poisson_ratio is 0.5", "(-1, 0.5)"]);
    let ok = src.replace("0.5)", "0.45)");
    Scene::from_str(&ok, "ok.ron").unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn wrapped_axis_has_no_edge() {
    let src = "Scene(title: \"C\", tissue: Layers((surface: Cylinder(radius: 0.01, length: 0.05),\n  layers: [(name: \"w\")], pinned: Edges([VMin, UMax]))))";
    let e = Scene::from_str(src, "bad.ron").expect_err("UMax on a cylinder");
    expect(e, "2:47", &["tissue.pinned[1] is UMax", "u wraps around"]);
}

#[test]
fn script_errors_point_at_the_value() {
    let src = "Script([\n    Select(Forceps),\n    Grasp(Surface(0.5, 1.5, 0.0)),\n])";
    let e = Script::from_str(src, "bad.ron").expect_err("v 1.5");
    expect(e, "3:24", &["action 2 (Grasp): the v fraction is 1.5", "[0, 1]"]);

    let src = "Script([\n    Select(Scalpel),\n    Cut(path: [Surface(0.1, 0.1, 0.0), World(0.0, NaN, 0.0)], depth: Upper, steps: 10),\n])";
    let e = Script::from_str(src, "bad.ron").expect_err("NaN");
    expect(e, "3:51", &["action 2 (Cut).path[1]: y is NaN"]);

    let src = "Script([\n    Select(Probe),\n    MoveTo(to: World(0.0, 0.0, 0.0), steps: 0),\n])";
    let e = Script::from_str(src, "bad.ron").expect_err("0 steps");
    expect(e, "3:45", &["steps is 0", "at least 1"]);

    let src = "Script([\n    Grasp(World(0.0, 0.0, 0.0)),\n])";
    let e = Script::from_str(src, "bad.ron").expect_err("no forceps");
    expect(e, "2:5", &["action 1 (Grasp) uses the Forceps", "Select(Forceps)"]);

    let src = "Script([\n    Select(Forceps),\n    Grap(World(0.0, 0.0, 0.0)),\n])";
    let e = Script::from_str(src, "bad.ron").expect_err("typo");
    expect(e, "3:5", &["unknown choice `Grap`", "did you mean `Grasp`"]);
}
