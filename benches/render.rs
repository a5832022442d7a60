//! Renderer frame cost on whatever adapter `Gpu::headless` finds (lavapipe on the CI machines: a CPU
//! floor, not the product's speed on a GPU).
//!
//! `render/frame/meninges`: one frame of the app's two views (trainee and observer cameras) of a 64 × 48
//! two-layer snapshot, each 1280 × 800 with 4× MSAA: the snapshot upload (`update`), both passes, one
//! submission and a blocking `device.poll` until the GPU is done. No readback. Throughput counts the
//! layer triangles drawn across both views. `render/frame/meninges_1x`: the same, single-sampled.
//! `render/frame/meninges_1x_bare`: single-sampled without fibres and shadows (the difference is what
//! they cost). `render/frame/meninges_1x_128x96`: single-sampled, sheets of 128 × 96 vertices (over the
//! demo's 8 cm square: 0.63 mm apart along x, 0.84 mm along z, which the renderer draws quad by quad);
//! `render/frame/meninges_1x_128x128`: 0.63 mm both ways, which it draws in cells of 2 × 2 quads where
//! nothing is cut, as it draws the default exercise's 128 × 96 (see `render::geometry::cell_quads`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dissect::render::{self, Gpu, Offscreen, OrbitCamera, SceneRenderer, Style, demo};
use dissect::simulation::CameraSpec;

fn frame(c: &mut Criterion) {
    let gpu = match Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => panic!("the render bench needs a graphics adapter: {e}"),
    };
    eprintln!("adapter: {}", gpu.describe());
    let mut group = c.benchmark_group("render/frame");
    group.sample_size(20);
    // 4x MSAA (the default) and single-sampled (what a window on a CPU adapter may choose).
    let bare = Style { show_fibres: false, shadows: false, ..Style::default() };
    for (name, samples, style, size) in [
        ("meninges", 4, Style::default(), (64, 48)),
        ("meninges_1x", 1, Style::default(), (64, 48)),
        ("meninges_1x_bare", 1, bare, (64, 48)),
        ("meninges_1x_128x96", 1, Style::default(), (128, 96)),
        ("meninges_1x_128x128", 1, Style::default(), (128, 128)),
    ] {
        two_views(&gpu, &mut group, name, samples, style, size);
    }
    group.finish();
}

fn two_views(
    gpu: &Gpu,
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    samples: u32,
    style: Style,
    (nu, nv): (u32, u32),
) {
    let mut snapshot = demo::two_layers(nu, nv, 2);
    let mut renderer = SceneRenderer::with_samples(gpu, render::OFFSCREEN_FORMAT, style, samples);
    renderer.update(gpu, &snapshot).expect("update");
    let trainee =
        OrbitCamera::from_spec(&CameraSpec { eye: [0.0, 0.078, 0.078], target: [0.0; 3], fov_y_deg: 45.0 });
    let observer =
        OrbitCamera::from_spec(&CameraSpec { eye: [0.09, 0.05, 0.06], target: [0.0; 3], fov_y_deg: 40.0 });
    let views = [
        (Offscreen::new(gpu, &renderer, 1280, 800).expect("trainee target"), trainee),
        (Offscreen::new(gpu, &renderer, 1280, 800).expect("observer target"), observer),
    ];

    group.throughput(Throughput::Elements(renderer.layer_triangles() * views.len() as u64));
    let mut phase = 0.0_f32;
    group.bench_function(name, |b| {
        b.iter(|| {
            // Move the upper sheet a little each frame, as the simulation would.
            phase += 0.1;
            let lift = 0.0005 * phase.sin();
            for p in &mut snapshot.layers[0].positions {
                p[1] = demo::sheet_height(p[0], p[2], 1.0) + lift;
            }
            renderer.update(gpu, &snapshot).expect("update");
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            for (offscreen, camera) in &views {
                offscreen.record(gpu, &renderer, &mut encoder, camera);
            }
            let index = gpu.queue.submit([encoder.finish()]);
            gpu.device
                .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                .expect("poll");
        })
    });
}

criterion_group!(benches, frame);
criterion_main!(benches);
