//! Shared set-up for the tissue tests.
#![allow(dead_code)]

use dissect::chainmail::Material;
use dissect::scene::{Scene, Tissue as SceneTissue};
use dissect::simulation::World;
use dissect::surface::Surface;
use dissect::tissue::{ConnectiveSpec, LayerSpec, LayeredSpec, Pinning, Tissue, TissueSpec};

pub const WIDTH: f32 = 0.06;
pub const GAP: f32 = 0.003;

pub fn two_layers(n: usize, surface: Surface, pinned: Pinning) -> LayeredSpec {
    LayeredSpec {
        surface,
        resolution: [n, n],
        u_coords: None,
        v_coords: None,
        layers: vec![
            LayerSpec {
                name: "dura".into(),
                color: [0.86, 0.72, 0.55, 1.0],
                offset: GAP,
                material: Material { tear_ratio: Some(3.0), ..Material::relative(1.15, 0.85, 0.3) },
            },
            LayerSpec {
                name: "arachnoid".into(),
                color: [0.85, 0.45, 0.45, 1.0],
                offset: 0.0,
                material: Material { tear_ratio: Some(3.0), ..Material::relative(1.15, 0.85, 0.3) },
            },
        ],
        connective: Some(ConnectiveSpec {
            material: Material { stiffness: 0.3, tear_ratio: None, ..Material::relative(2.0, 0.5, 0.5) },
            density: 1.0,
            min_gap: 0.0005,
            spacing: 0.0,
        }),
        pinned,
    }
}

pub fn plane(n: usize) -> Tissue {
    Tissue::build(&TissueSpec::Layered(two_layers(
        n,
        Surface::Plane { width: WIDTH, depth: WIDTH },
        Pinning::Boundary,
    )))
    .expect("tissue")
}

/// The meninges scene (`scenes/meninges.ron`) at another resolution, built.
pub fn meninges(nu: u32, nv: u32) -> World {
    let mut scene =
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meninges.ron")).expect("meninges scene");
    if let SceneTissue::Layers(l) = &mut scene.tissue {
        l.resolution = [nu, nv];
    }
    scene.build_world(false).expect("world")
}

/// How many cases a property test runs: `PROPTEST_CASES` when set (for long runs before landing:
/// `ProptestConfig::with_cases` alone ignores it), else the test's own `default`.
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// How far the top face of an `n³` block (element `i + n·((n − 1) + n·k)` at column `i`, row `k`) lies
/// inside a ball of radius `r` centred at `ball` (y up), metres: 0 when no element is inside.
pub fn deepest_inside_ball(pos: &[[f32; 3]], n: usize, ball: [f32; 3], r: f32) -> f32 {
    let mut inside = 0.0f32;
    for k in 0..n {
        for i in 0..n {
            let p = pos[i + n * ((n - 1) + n * k)];
            let l2 = (p[0] - ball[0]).powi(2) + (p[2] - ball[2]).powi(2);
            if l2 < r * r {
                inside = inside.max(p[1] - (ball[1] - (r * r - l2).sqrt()));
            }
        }
    }
    inside
}
