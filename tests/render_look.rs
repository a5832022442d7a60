//! Guards the look of the default exercise after its careful script, end to end: the scene is built,
//! the script played headless, the final snapshot drawn from the trainee's and the observer's cameras
//! and compared with `tests/golden/careful_{trainee,observer}.png` within a tolerance. Also: the
//! trainee's camera frames the work area (the tissue covers at least half of the view), the regions
//! of the goals are drawn (and vanish when toggled off), and the cut fibres leave marks.
//!
//! Regenerate the goldens with `DISSECT_BLESS=1 cargo test --test render_look`, then look at them.
//! Renders of each run are written to `target/render-test/`.

use std::path::PathBuf;

use dissect::render::{self, Gpu, Offscreen, OrbitCamera, SceneRenderer, Style};
use dissect::scene::{Scene, Script};
use dissect::simulation::Snapshot;

/// The default exercise (the dural flap) and its careful script.
const SCENE: &str = "scenes/durotomy.ron";
const SCRIPT: &str = "scenes/scripts/durotomy_careful.ron";

const WIDTH: u32 = 640;
const HEIGHT: u32 = 400;

/// Tolerance against the golden images: at most 2 % of pixels may differ by more than 12/255 on any
/// channel. The same backend gives byte-identical images run after run; Vulkan (lavapipe) and GL
/// (llvmpipe) differ on edges, thin fibres and texture filtering in a fraction of a percent of pixels,
/// and a change in the tissue's behaviour moves the lifted flap by a few pixels. A real regression in
/// the look (a lost texture, shadow, layer, region or instrument; a moved camera) changes far more.
const CHANNEL_TOLERANCE: u8 = 12;
const MAX_DIFFERING_FRACTION: f64 = 0.02;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn gpu() -> Gpu {
    match Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!("render tests need a graphics adapter and none was found. {e}"),
    }
}

/// The scene and the snapshot at the end of the careful script.
fn careful() -> (Scene, Snapshot) {
    let scene = Scene::load(root().join(SCENE)).expect("scene");
    let script = Script::load(root().join(SCRIPT)).expect("script");
    let out = dissect::runner::run(&scene, SCENE, &script, SCRIPT, None, None).expect("run");
    let mut snapshot = Snapshot::default();
    out.world.snapshot_into(&mut snapshot);
    (scene, snapshot)
}

fn draw(gpu: &Gpu, snapshot: &Snapshot, camera: &OrbitCamera, style: Style) -> image::RgbaImage {
    let mut renderer = SceneRenderer::new(gpu, render::OFFSCREEN_FORMAT, style);
    renderer.update(gpu, snapshot).expect("update");
    let offscreen = Offscreen::new(gpu, &renderer, WIDTH, HEIGHT).expect("target");
    offscreen.render(gpu, &renderer, camera);
    offscreen.read(gpu).expect("read")
}

fn differs(a: &image::Rgba<u8>, b: &image::Rgba<u8>, tolerance: u8) -> bool {
    a.0.iter().zip(b.0.iter()).any(|(x, y)| x.abs_diff(*y) > tolerance)
}

fn fraction_differing(a: &image::RgbaImage, b: &image::RgbaImage, tolerance: u8) -> f64 {
    let n = a.pixels().zip(b.pixels()).filter(|(p, q)| differs(p, q, tolerance)).count();
    n as f64 / f64::from(a.width() * a.height())
}

fn check_golden(name: &str, image: &image::RgbaImage) {
    let dir = root().join("target/render-test");
    std::fs::create_dir_all(&dir).expect("create target/render-test");
    render::save_png(image, dir.join(format!("{name}.png"))).expect("save");
    let golden_path = root().join(format!("tests/golden/{name}.png"));
    if std::env::var_os("DISSECT_BLESS").is_some() {
        render::save_png(image, &golden_path).expect("write golden");
        eprintln!("blessed {}", golden_path.display());
        return;
    }
    let golden = match image::open(&golden_path) {
        Ok(g) => g.to_rgba8(),
        Err(e) => {
            panic!("no golden at {} ({e}); run with DISSECT_BLESS=1 and look at it", golden_path.display())
        }
    };
    assert_eq!(golden.dimensions(), image.dimensions(), "{name}: golden has another size");
    let fraction = fraction_differing(image, &golden, CHANNEL_TOLERANCE);
    eprintln!("{name}: {:.3} % of pixels differ from the golden", fraction * 100.0);
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{name}: {:.2} % of pixels differ by more than {CHANNEL_TOLERANCE}/255 (allowed {:.0} %); see \
         target/render-test/{name}.png",
        fraction * 100.0,
        MAX_DIFFERING_FRACTION * 100.0
    );
}

/// One test plays the script once (it takes a while in a test build) and checks everything on it.
#[test]
fn careful_dissection_looks_as_blessed() {
    let gpu = gpu();
    let (scene, snapshot) = careful();
    assert!(snapshot.broken_fibres.iter().any(|f| f.cut), "the careful script cuts fibres");
    assert!(!snapshot.regions.is_empty(), "the goals' regions reach the snapshot");
    let trainee = OrbitCamera::from_spec(&scene.trainee_camera());
    let observer = OrbitCamera::from_spec(&scene.observer_camera());
    let trainee_image = draw(&gpu, &snapshot, &trainee, Style::default());
    check_golden("careful_trainee", &trainee_image);
    check_golden("careful_observer", &draw(&gpu, &snapshot, &observer, Style::default()));

    // The trainee's camera frames the work area: the tissue covers at least half of the view (pixels
    // that differ from the empty scene's background).
    let empty = draw(&gpu, &Snapshot::default(), &trainee, Style::default());
    let covered = fraction_differing(&trainee_image, &empty, 4);
    eprintln!("tissue covers {:.0} % of the trainee's view", covered * 100.0);
    assert!(covered >= 0.5, "the tissue covers only {:.0} % of the trainee's view", covered * 100.0);

    // Regions and marks are drawn: turning them off changes the picture, and only somewhat.
    let plain = draw(&gpu, &snapshot, &trainee, Style { show_regions: false, ..Style::default() });
    let regions = fraction_differing(&trainee_image, &plain, 12);
    assert!(regions > 0.005 && regions < 0.6, "regions change {:.2} % of the view", regions * 100.0);
    let bare = draw(&gpu, &snapshot, &trainee, Style { show_fibres: false, ..Style::default() });
    let fibres = fraction_differing(&trainee_image, &bare, 12);
    assert!(fibres > 0.001, "fibres, stubs and cut marks change {:.3} % of the view", fibres * 100.0);
}
