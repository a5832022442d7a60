//! The render bench's frame (`render/frame/meninges_1x`: both views of the 64 × 48 demo snapshot,
//! 1280 × 800 each, single-sampled, one submission, waited for) run a fixed number of times, with the
//! process's CPU time beside the wall time. On a machine shared with builds the wall time of a software
//! rasteriser swings with the load; the CPU time it takes per frame swings far less, so two renderers
//! are compared by both, back to back:
//!
//! ```sh
//! cargo run --release --example frame_cost -- 60          # the default look
//! cargo run --release --example frame_cost -- 60 bare     # without fibres and shadows
//! ```
//! prints `wall ms/frame` and `cpu ms/frame` (user + system of every thread, lavapipe's included; Linux
//! only, read from /proc/self/stat; 0 elsewhere).
//!
//! A scene's own tissue through its own cameras instead of the demo snapshot (the scene at rest, or
//! after a script), e.g. the default exercise at two resolutions:
//! ```sh
//! cargo run --release --example frame_cost -- 60 scene scenes/durotomy.ron [scenes/scripts/durotomy_careful.ron]
//! ```

use std::time::Instant;

use dissect::render::{self, Gpu, Offscreen, OrbitCamera, SceneRenderer, Style, demo};
use dissect::simulation::CameraSpec;

/// User + system CPU seconds of this process so far (all threads), from /proc/self/stat.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // Fields after the command name (which is in parentheses and may hold spaces).
    let Some(rest) = stat.rsplit(')').next() else { return 0.0 };
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line: 12 and 13 after the name.
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames: u32 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(60);
    let style = match args.get(2).map(String::as_str) {
        Some("bare") => Style { show_fibres: false, shadows: false, ..Style::default() },
        _ => Style::default(),
    };
    let gpu = match Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => {
            eprintln!("frame_cost needs a graphics adapter: {e}");
            std::process::exit(1);
        }
    };
    let mut trainee = CameraSpec { eye: [0.0, 0.078, 0.078], target: [0.0; 3], fov_y_deg: 45.0 };
    let mut observer = CameraSpec { eye: [0.09, 0.05, 0.06], target: [0.0; 3], fov_y_deg: 40.0 };
    let demo_sheet = args.get(2).map(String::as_str) != Some("scene");
    let mut snapshot = if demo_sheet {
        demo::two_layers(64, 48, 2)
    } else {
        match scene_snapshot(args.get(3), args.get(4)) {
            Ok((snapshot, cameras)) => {
                trainee = cameras.trainee.unwrap_or(trainee);
                observer = cameras.observer.unwrap_or(observer);
                snapshot
            }
            Err(e) => {
                eprintln!("frame_cost: {e}");
                std::process::exit(1);
            }
        }
    };
    let mut renderer = SceneRenderer::with_samples(&gpu, render::OFFSCREEN_FORMAT, style, 1);
    let (trainee, observer) = (OrbitCamera::from_spec(&trainee), OrbitCamera::from_spec(&observer));
    let views = match (Offscreen::new(&gpu, &renderer, 1280, 800), Offscreen::new(&gpu, &renderer, 1280, 800))
    {
        (Ok(a), Ok(b)) => [(a, trainee), (b, observer)],
        _ => {
            eprintln!("frame_cost: could not make the two 1280 x 800 targets");
            std::process::exit(1);
        }
    };
    let mut phase = 0.0_f32;
    // The first five frames warm up (shader compilation, first allocations) and are not counted.
    let (mut wall, mut cpu) = (Instant::now(), cpu_seconds());
    for i in 0..frames + 5 {
        if i == 5 {
            (wall, cpu) = (Instant::now(), cpu_seconds());
        }
        phase += 0.1;
        let lift = 0.0005 * phase.sin();
        if demo_sheet {
            for p in &mut snapshot.layers[0].positions {
                p[1] = demo::sheet_height(p[0], p[2], 1.0) + lift;
            }
        }
        if let Err(e) = renderer.update(&gpu, &snapshot) {
            eprintln!("frame_cost: {e}");
            std::process::exit(1);
        }
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for (offscreen, camera) in &views {
            offscreen.record(&gpu, &renderer, &mut encoder, camera);
        }
        let index = gpu.queue.submit([encoder.finish()]);
        if let Err(e) = gpu.device.poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
        {
            eprintln!("frame_cost: {e}");
            std::process::exit(1);
        }
    }
    let n = f64::from(frames.max(1));
    println!(
        "{} frames: wall {:.1} ms/frame, cpu {:.1} ms/frame ({})",
        frames,
        wall.elapsed().as_secs_f64() * 1e3 / n,
        (cpu_seconds() - cpu) * 1e3 / n,
        gpu.describe()
    );
}

/// The snapshot of `scene` at rest, or at the end of `script`, and the scene's cameras.
fn scene_snapshot(
    scene: Option<&String>,
    script: Option<&String>,
) -> Result<(dissect::simulation::Snapshot, dissect::scene::Cameras), String> {
    let path = scene.ok_or("expected a scene file after `scene`")?;
    let scene = dissect::scene::Scene::load(path).map_err(|e| e.to_string())?;
    let script = match script {
        Some(s) => dissect::scene::Script::load(s).map_err(|e| e.to_string())?,
        None => dissect::scene::Script(Vec::new()),
    };
    let out =
        dissect::runner::run(&scene, path, &script, "frame_cost", None, None).map_err(|e| e.to_string())?;
    let mut snapshot = dissect::simulation::Snapshot::default();
    out.world.snapshot_into(&mut snapshot);
    Ok((snapshot, scene.cameras))
}
