//! Guards the headless renderer end to end on a real adapter (lavapipe in CI): a synthetic two-layer
//! scene, intact and cut, must match the golden images `tests/golden/two_layers{,_cut}.png` within a
//! tolerance; cutting a band out of the upper layer must change the picture there and nowhere far from
//! it; fibres must show between the layers; each instrument must be drawn at its pose; the planned
//! incision is marked along all of its points.
//!
//! Regenerate the golden with `DISSECT_BLESS=1 cargo test --test render_headless`, then look at it.
//! Renders of each run are written to `target/render-test/` for inspection.

use std::path::PathBuf;

use dissect::render::{self, Gpu, Offscreen, OrbitCamera, SceneRenderer, Style, demo};
use dissect::simulation::{CameraSpec, Snapshot};
use glam::{Vec2, Vec3};

const WIDTH: u32 = 480;
const HEIGHT: u32 = 320;

/// Tolerance against the golden image: at most 1 % of pixels may differ by more than 8/255 on any
/// channel. The same backend renders byte-identical images run after run, but Vulkan (lavapipe) and GL
/// (llvmpipe) rasterise edges and MSAA coverage slightly differently, which touches a fraction of a
/// percent of pixels (edges of the sheets, fibres and jaws); a real regression (a missing layer, wrong
/// lighting, a moved camera) changes far more than 1 %.
const CHANNEL_TOLERANCE: u8 = 8;
const MAX_DIFFERING_FRACTION: f64 = 0.01;

fn gpu() -> Gpu {
    match Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!(
            "render tests need a graphics adapter and none was found. {e}\n\
             CI installs lavapipe (mesa-vulkan-drivers); without Vulkan, GL (llvmpipe via EGL) is tried."
        ),
    }
}

fn camera() -> OrbitCamera {
    // Looking down at 45° onto the middle of the square from the +Z side.
    let d = 0.11_f32;
    let s = std::f32::consts::FRAC_1_SQRT_2;
    OrbitCamera::from_spec(&CameraSpec { eye: [0.0, d * s, d * s], target: [0.0, 0.0, 0.0], fov_y_deg: 45.0 })
}

fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/render-test");
    std::fs::create_dir_all(&dir).expect("create target/render-test");
    dir
}

const N: u32 = 32;
const FIBRE_STEP: u32 = 2;

fn scene() -> Snapshot {
    demo::two_layers(N, N, FIBRE_STEP)
}

/// Half-width (metres) of the band cut out of the upper layer along Z, and its extent in Z.
const CUT_HALF_WIDTH: f32 = 0.004;
const CUT_HALF_LENGTH: f32 = 0.028;

fn in_band(x: f32, z: f32) -> bool {
    x.abs() < CUT_HALF_WIDTH && z.abs() < CUT_HALF_LENGTH
}

/// The scene with a band of upper-layer triangles and the fibres under it removed, as a cut would; the
/// lips of the cut retract outwards and up, stretching the fibres still attached to them into the gap.
fn cut_scene() -> Snapshot {
    let mut snap = scene();
    let upper = &mut snap.layers[0];
    let rest = upper.positions.clone();
    upper.triangles.retain(|t| {
        let c = t.iter().fold(Vec3::ZERO, |acc, &i| acc + Vec3::from(rest[i as usize])) / 3.0;
        !in_band(c.x, c.z)
    });
    upper.topology_version += 1;
    for p in &mut upper.positions {
        let w = (1.0 - (p[0].abs() - CUT_HALF_WIDTH) / 0.008).clamp(0.0, 1.0)
            * (1.0 - p[2].abs() / CUT_HALF_LENGTH).clamp(0.0, 1.0).sqrt();
        p[0] += p[0].signum() * 0.003 * w;
        p[1] += 0.002 * w;
    }
    demo::connect(&mut snap, N, N, FIBRE_STEP as usize);
    let keep: Vec<bool> = snap.fibres.iter().map(|[bottom, _]| !in_band(bottom[0], bottom[2])).collect();
    let mut k = keep.iter();
    snap.fibres.retain(|_| k.next().copied().unwrap_or(true));
    let mut k = keep.iter();
    snap.fibre_sites.retain(|_| k.next().copied().unwrap_or(true));
    let mut k = keep.iter();
    snap.fibre_stretch.retain(|_| k.next().copied().unwrap_or(true));
    snap.cut_path = (0..=8)
        .map(|k| [0.0, demo::sheet_height(0.0, 0.0, 1.0) + 0.0005, -0.02 + 0.005 * k as f32])
        .collect();
    snap
}

/// Pixels whose largest channel difference exceeds `CHANNEL_TOLERANCE`.
fn differs(a: &image::Rgba<u8>, b: &image::Rgba<u8>) -> bool {
    a.0.iter().zip(b.0.iter()).any(|(x, y)| x.abs_diff(*y) > CHANNEL_TOLERANCE)
}

/// Renders `snapshot` through the 45° camera and compares it with `tests/golden/{name}.png` (or writes the
/// golden when `DISSECT_BLESS` is set).
fn check_golden(gpu: &Gpu, name: &str, snapshot: &Snapshot) {
    let image = render::render_to_image(gpu, snapshot, &camera(), WIDTH, HEIGHT).expect("render");
    render::save_png(&image, out_dir().join(format!("{name}.png"))).expect("save");

    let golden_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("DISSECT_BLESS").is_some() {
        render::save_png(&image, &golden_path).expect("write golden");
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
    let differing = image.pixels().zip(golden.pixels()).filter(|(a, b)| differs(a, b)).count();
    let fraction = differing as f64 / f64::from(WIDTH * HEIGHT);
    eprintln!("{name}: {differing} pixels ({:.3} %) differ from the golden", fraction * 100.0);
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{name}: {:.2} % of pixels differ from the golden by more than {CHANNEL_TOLERANCE}/255 (allowed \
         {:.2} %); see target/render-test/{name}.png",
        fraction * 100.0,
        MAX_DIFFERING_FRACTION * 100.0
    );
}

#[test]
fn two_layers_match_golden() {
    let gpu = gpu();
    eprintln!("adapter: {}", gpu.describe());
    check_golden(&gpu, "two_layers", &scene());
}

#[test]
fn cut_two_layers_match_golden() {
    check_golden(&gpu(), "two_layers_cut", &cut_scene());
}

#[test]
fn cut_changes_the_band_and_nothing_far_from_it() {
    let gpu = gpu();
    let cam = camera();
    let intact = render::render_to_image(&gpu, &scene(), &cam, WIDTH, HEIGHT).expect("render intact");
    let cut = render::render_to_image(&gpu, &cut_scene(), &cam, WIDTH, HEIGHT).expect("render cut");

    // Classify each pixel by where its ray meets the upper sheet's rim plane.
    let vp = Vec2::new(WIDTH as f32, HEIGHT as f32);
    let plane_y = demo::HALF_GAP + demo::DOME;
    let (mut band, mut band_changed, mut far, mut far_changed) = (0u32, 0u32, 0u32, 0u32);
    for (x, y, a) in intact.enumerate_pixels() {
        let (o, d) = cam.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), vp);
        if d.y >= 0.0 {
            continue;
        }
        let hit = o + d * ((plane_y - o.y) / d.y);
        let changed = differs(a, cut.get_pixel(x, y));
        // Well inside the band (away from its ends and edges, where the dome and fibres blur it).
        if hit.x.abs() < CUT_HALF_WIDTH * 0.5 && hit.z.abs() < CUT_HALF_LENGTH * 0.7 {
            band += 1;
            band_changed += u32::from(changed);
        } else if hit.x.abs() > 0.02 || hit.z.abs() > 0.045 {
            far += 1;
            far_changed += u32::from(changed);
        }
    }
    assert!(band > 200 && far > 10_000, "classification found {band} band and {far} far pixels");
    let band_fraction = f64::from(band_changed) / f64::from(band);
    let far_fraction = f64::from(far_changed) / f64::from(far);
    eprintln!("band: {band_changed}/{band} changed; far: {far_changed}/{far} changed");
    assert!(band_fraction > 0.8, "only {:.1} % of the cut band changed", band_fraction * 100.0);
    assert!(far_fraction < 0.002, "{:.2} % of pixels far from the cut changed", far_fraction * 100.0);
}

#[test]
fn update_reuses_buffers_and_rejects_bad_layers() {
    let gpu = gpu();
    let mut renderer = render::SceneRenderer::new(&gpu, render::OFFSCREEN_FORMAT, render::Style::default());
    let mut snap = scene();
    renderer.update(&gpu, &snap).expect("first update");
    assert_eq!(renderer.layer_triangles(), 2 * 2 * u64::from((N - 1) * (N - 1)));
    // Moving vertices without a topology change keeps the index count.
    for p in &mut snap.layers[0].positions {
        p[1] += 0.001;
    }
    renderer.update(&gpu, &snap).expect("moved");
    assert_eq!(renderer.layer_triangles(), 2 * 2 * u64::from((N - 1) * (N - 1)));
    let steady = renderer.stats();
    assert_eq!((steady.updates, steady.index_rebuilds, steady.reallocations), (2, 2, 0), "{steady:?}");
    // A cut (fewer triangles, new topology_version) rebuilds that layer's indices only, without growing.
    let cut = cut_scene();
    renderer.update(&gpu, &cut).expect("cut");
    let after = renderer.stats();
    assert_eq!((after.index_rebuilds, after.reallocations), (3, 0), "{after:?}");
    // A layer that grows reallocates its vertex buffers.
    let mut bigger = demo::two_layers(2 * N, N, FIBRE_STEP);
    bigger.layers[0].topology_version = 99;
    bigger.layers[1].topology_version = 99;
    renderer.update(&gpu, &bigger).expect("grown");
    assert!(renderer.stats().reallocations >= 4, "{:?}", renderer.stats());
    snap = bigger;
    // Dropping a normal is reported, not drawn.
    snap.layers[1].normals.pop();
    let err = renderer.update(&gpu, &snap).expect_err("normals missing");
    assert!(err.to_string().contains("layer 1"), "{err}");
}

/// Pixels close to the fibre colour (pale cream: brighter in blue than any lit tissue).
fn fibre_like(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0;
    r > 200 && g > 200 && b > 150 && g > 215
}

#[test]
fn fibres_show_between_the_layers_from_a_low_side_view() {
    let gpu = gpu();
    // Low, close and from the front right: the 4 mm gap between the sheets' front edges shows.
    let cam = OrbitCamera::from_spec(&CameraSpec {
        eye: [0.035, 0.012, 0.075],
        target: [0.0, 0.0, 0.035],
        fov_y_deg: 45.0,
    });
    let side = render::render_to_image(&gpu, &scene(), &cam, 1280, 800).expect("render side");
    render::save_png(&side, out_dir().join("two_layers_side.png")).expect("save");
    let trainee = render::render_to_image(&gpu, &cut_scene(), &camera(), 1280, 800).expect("render");
    render::save_png(&trainee, out_dir().join("two_layers_cut_1280.png")).expect("save");
    let fibre_pixels = side.pixels().filter(|p| fibre_like(p)).count();
    assert!(fibre_pixels > 500, "only {fibre_pixels} fibre-coloured pixels in the side view");
    let without = {
        let mut snap = scene();
        snap.fibres.clear();
        render::render_to_image(&gpu, &snap, &cam, 1280, 800).expect("render without fibres")
    };
    let left = without.pixels().filter(|p| fibre_like(p)).count();
    assert!(left < fibre_pixels / 20, "{left} fibre-coloured pixels without fibres");
}

#[test]
fn each_instrument_is_drawn_at_its_pose() {
    use dissect::simulation::{InstrumentKind, InstrumentPose};
    let gpu = gpu();
    let cam =
        OrbitCamera::from_spec(&CameraSpec { eye: [0.0, 0.06, 0.06], target: [0.0; 3], fov_y_deg: 45.0 });
    let mut snap = scene();
    snap.instrument = None;
    let bare = render::render_to_image(&gpu, &snap, &cam, WIDTH, HEIGHT).expect("render bare");
    for (kind, closed) in
        [(InstrumentKind::Probe, false), (InstrumentKind::Forceps, true), (InstrumentKind::Scalpel, false)]
    {
        snap.instrument = Some(InstrumentPose {
            kind,
            tip: [0.0, demo::HALF_GAP + demo::DOME + 0.001, 0.0],
            axis: Vec3::new(0.3, 1.0, 0.4).normalize().to_array(),
            roll: 0.3,
            closed,
        });
        let image = render::render_to_image(&gpu, &snap, &cam, WIDTH, HEIGHT).expect("render");
        render::save_png(&image, out_dir().join(format!("instrument_{kind:?}.png").to_lowercase()))
            .expect("save");
        // The tip sits at the middle of the view: the instrument must cover pixels around it.
        let (tip_px, _) = cam
            .project(
                Vec3::from(snap.instrument.map(|p| p.tip).unwrap_or_default()),
                Vec2::new(WIDTH as f32, HEIGHT as f32),
            )
            .expect("tip in view");
        let near_tip = image
            .enumerate_pixels()
            .filter(|(x, y, p)| {
                Vec2::new(*x as f32, *y as f32).distance(tip_px) < 40.0 && differs(p, bare.get_pixel(*x, *y))
            })
            .count();
        assert!(near_tip > 60, "{kind:?}: only {near_tip} pixels near the tip changed");
    }
}

#[test]
fn eye_between_the_layers_does_not_smear_fibres_behind_it() {
    let gpu = gpu();
    // The eye sits inside the fibre forest: many fibres end behind it and must be clipped, not flipped.
    let cam = OrbitCamera::from_spec(&CameraSpec {
        eye: [0.001, 0.0, 0.02],
        target: [0.0, 0.0, -0.02],
        fov_y_deg: 60.0,
    });
    let image = render::render_to_image(&gpu, &scene(), &cam, WIDTH, HEIGHT).expect("render");
    render::save_png(&image, out_dir().join("between_layers.png")).expect("save");
    let fibre_pixels = image.pixels().filter(|p| fibre_like(p)).count();
    let fraction = fibre_pixels as f64 / f64::from(WIDTH * HEIGHT);
    assert!(fibre_pixels > 100, "no fibres seen between the layers");
    assert!(
        fraction < 0.3,
        "{:.0} % of the view is fibre-coloured: strands behind the eye smeared",
        fraction * 100.0
    );
}

#[test]
fn render_in_draws_only_inside_its_rect() {
    let gpu = gpu();
    let mut renderer = render::SceneRenderer::new(&gpu, render::OFFSCREEN_FORMAT, render::Style::default());
    renderer.update(&gpu, &scene()).expect("update");
    let offscreen = render::Offscreen::new(&gpu, &renderer, WIDTH, HEIGHT).expect("target");
    let half = WIDTH / 2;
    offscreen.render_in(&gpu, &renderer, &camera(), [half as f32, 0.0, half as f32, HEIGHT as f32]);
    let image = offscreen.read(&gpu).expect("read");
    render::save_png(&image, out_dir().join("render_in_right_half.png")).expect("save");
    let black = |p: &image::Rgba<u8>| p.0[..3].iter().all(|&c| c < 3);
    let left_drawn = image.enumerate_pixels().filter(|(x, _, p)| *x < half && !black(p)).count();
    let right_black = image.enumerate_pixels().filter(|(x, _, p)| *x >= half && black(p)).count();
    assert_eq!(left_drawn, 0, "pixels drawn outside the rect");
    assert_eq!(right_black, 0, "pixels inside the rect left uncovered");
}

/// The planned incision's violet marker: blue well above green (the tissue is tan, pink or grey).
fn marker_like(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    b > g + 40 && r > g && b > 70
}

#[test]
fn the_planned_incision_is_drawn_through_all_its_points() {
    let gpu = gpu();
    let mut snap = scene();
    snap.regions.clear();
    snap.instrument = None;
    // A zigzag of nine points (eight segments) across the upper sheet; the renderer once drew only
    // the first six points.
    snap.incision =
        (0..9).map(|k| [0.15 + 0.0875 * k as f32, if k % 2 == 0 { 0.35 } else { 0.65 }]).collect();
    let image = render::render_to_image(&gpu, &snap, &camera(), WIDTH, HEIGHT).expect("render");
    render::save_png(&image, out_dir().join("incision_nine_points.png")).expect("save");
    let viewport = Vec2::new(WIDTH as f32, HEIGHT as f32);
    let on_sheet = |uv: [f32; 2]| {
        let (x, z) = (demo::EXTENT * (uv[0] - 0.5), demo::EXTENT * (uv[1] - 0.5));
        Vec3::new(x, demo::sheet_height(x, z, 1.0), z)
    };
    // Every segment shows marker pixels near its middle (its dashes are a period of 1/45 apart).
    for (k, w) in snap.incision.windows(2).enumerate() {
        let mid = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
        let (px, _) = camera().project(on_sheet(mid), viewport).expect("segment in view");
        let near = image
            .enumerate_pixels()
            .filter(|(x, y, p)| Vec2::new(*x as f32, *y as f32).distance(px) < 12.0 && marker_like(p))
            .count();
        assert!(near >= 4, "segment {k} of the incision: {near} marker pixels near its middle");
    }
    // Hidden with the regions (G), and nowhere far from the line.
    let plain = Style { show_regions: false, ..Style::default() };
    let mut renderer = SceneRenderer::new(&gpu, render::OFFSCREEN_FORMAT, plain);
    renderer.update(&gpu, &snap).expect("update");
    let offscreen = Offscreen::new(&gpu, &renderer, WIDTH, HEIGHT).expect("target");
    offscreen.render(&gpu, &renderer, &camera());
    let hidden = offscreen.read(&gpu).expect("read");
    assert_eq!(
        hidden.pixels().filter(|p| marker_like(p)).count(),
        0,
        "the marker shows with the regions off"
    );
}
