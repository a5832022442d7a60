//! Guards the renderer against memory that grows frame after frame on the adapter CI has (lavapipe):
//! drawing the same scene 300 times must leave the process's resident memory where it was.
//!
//! Regression: the tissue's vertex shader computed its distances to the exercise's regions with a loop
//! over the regions (one `if` per region); Mesa's lavapipe 22.3 kept memory on every such draw and
//! never gave it back, so the trainer grew by 5 to 8 MB a second under software Vulkan. The shader is
//! now branch-free there. This test failed with the loop (161 MB over the 300 draws); it passes
//! trivially on a driver that never leaked. Linux only (it reads `/proc/self/status`).

use dissect::render::{Gpu, OFFSCREEN_FORMAT, Offscreen, OrbitCamera, SceneRenderer, Style, demo};
use dissect::simulation::CameraSpec;

/// Resident memory, bytes (`None` where `/proc` is missing).
fn resident() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb = status.lines().find_map(|l| l.strip_prefix("VmRSS:"))?.split_whitespace().next()?;
    kb.parse::<u64>().ok().map(|kb| kb * 1024)
}

/// Draws the scene `n` times, each frame waited for (so nothing is merely queued).
fn draw(gpu: &Gpu, renderer: &SceneRenderer, offscreen: &Offscreen, camera: &OrbitCamera, n: usize) {
    for _ in 0..n {
        let index = offscreen.render(gpu, renderer, camera);
        let _ = gpu.device.poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None });
    }
}

#[test]
fn drawing_the_same_scene_again_does_not_grow_memory() {
    let Some(_) = resident() else { return };
    let gpu = match Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!("render tests need a graphics adapter (CI installs lavapipe): {e}"),
    };
    let mut renderer = SceneRenderer::with_samples(&gpu, OFFSCREEN_FORMAT, Style::default(), 1);
    renderer.update(&gpu, &demo::two_layers(24, 24, 4)).expect("upload");
    let offscreen = Offscreen::new(&gpu, &renderer, 160, 120).expect("target");
    let camera =
        OrbitCamera::from_spec(&CameraSpec { eye: [0.0, 0.08, 0.08], target: [0.0; 3], fov_y_deg: 45.0 });
    // Warm up: pipelines compiled, staging and pools at their working size.
    draw(&gpu, &renderer, &offscreen, &camera, 60);
    let before = resident().unwrap_or(0);
    draw(&gpu, &renderer, &offscreen, &camera, 300);
    let after = resident().unwrap_or(0);
    let grown_mb = after.saturating_sub(before) as f64 / 1e6;
    assert!(
        grown_mb < 8.0,
        "resident memory grew by {grown_mb:.1} MB over 300 draws of the same scene ({} on {})",
        "a driver or renderer leak",
        gpu.describe()
    );
}
