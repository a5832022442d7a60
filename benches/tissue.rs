//! Tissue benches: a SurfaceChainMail step on two 256 x 256 layers, a cut across the sheet, and the
//! peer a user would otherwise pick, rapier3d 0.36 soft bodies, on the same lift and cut.
//!
//! The lift: a sheet of 257 x 257 elements 1 mm apart, border pinned, the centre grasped and lifted by
//! a fifth of the width over 60 steps. Gravity off on both sides.

use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use dissect::chainmail::{ElementId, Material, RelaxBudget};
use dissect::simulation::Command;
use dissect::simulation::{InstrumentKind, World, WorldConfig};
use dissect::surface::Surface;
use dissect::tissue::{
    ConnectiveSpec, CutDepth, CutSegment, LayerSpec, LayeredSpec, Pinning, Tissue, TissueSpec,
};
use rapier3d::prelude::*;

const H: f32 = 0.001;
const LIFT_STEPS: usize = 60;

fn layer(name: &str, offset: f32) -> LayerSpec {
    LayerSpec {
        name: name.into(),
        color: [0.8, 0.6, 0.5, 1.0],
        offset,
        material: Material { tear_ratio: None, ..Material::relative(1.2, 0.8, 0.5) },
    }
}

fn sheet(n: usize, layers: usize) -> Tissue {
    let w = (n - 1) as f32 * H;
    let spec = LayeredSpec {
        surface: Surface::Plane { width: w, depth: w },
        resolution: [n, n],
        u_coords: None,
        v_coords: None,
        layers: if layers == 2 {
            vec![layer("upper", 0.003), layer("lower", 0.0)]
        } else {
            vec![layer("sheet", 0.0)]
        },
        connective: (layers == 2).then(|| ConnectiveSpec {
            material: Material { stiffness: 0.3, ..Material::relative(2.0, 0.5, 0.5) },
            density: 1.0,
            min_gap: 0.0005,
            spacing: 0.0,
        }),
        pinned: Pinning::Boundary,
    };
    Tissue::build(&TissueSpec::Layered(spec)).expect("tissue")
}

fn grasped(tissue: Tissue) -> (World, [f32; 3]) {
    let top = 0; // the upper layer
    let n = (tissue.layers()[top].count as f32).sqrt() as u32;
    let e = ElementId(tissue.layers()[top].first + n / 2 + n * (n / 2));
    let start = tissue.world_position(e).expect("centre");
    let config = WorldConfig {
        relax: RelaxBudget { max_sweeps: 2, max_time: None, tolerance: 1e-6 },
        ..WorldConfig::default()
    };
    let mut world = World::new(tissue, config);
    world.push(Command::Select(InstrumentKind::Forceps));
    world.push(Command::GraspElement(e));
    world.step();
    (world, start)
}

fn dissect_benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("tissue");
    group.measurement_time(Duration::from_secs(5)).sample_size(20);

    // A grasp moved back and forth by three element spacings: chain reaction, normal pass, relaxation.
    let (mut world, start) = grasped(sheet(256, 2));
    group.throughput(Throughput::Elements(2 * 256 * 256));
    let mut k = 0u32;
    group.bench_function("step/two_layers_256", |b| {
        b.iter(|| {
            k += 1;
            let dx = if k.is_multiple_of(2) { 3.0 * H } else { -3.0 * H };
            world.push(Command::MoveTo([start[0] + dx, start[1] + 0.002, start[2]]));
            world.step()
        })
    });

    let base = sheet(256, 2);
    group.bench_function("cut/two_layers_256", |b| {
        b.iter_batched(
            || base.clone(),
            |mut t| {
                t.queue_cut(CutSegment {
                    from: [-0.2, 0.003, 0.0005],
                    to: [0.2, 0.003, 0.0005],
                    depth: CutDepth::Upper,
                });
                t.apply_cuts()
            },
            BatchSize::LargeInput,
        )
    });

    // The peer comparison: the same lift on one 257 x 257 layer.
    let base = sheet(257, 1);
    let lift = 0.2 * 256.0 * H;
    group.throughput(Throughput::Elements(257 * 257));
    group.bench_function("step/one_layer_257", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut done = 0;
            while done < iters {
                let (mut world, start) = grasped(base.clone());
                for s in 1..=LIFT_STEPS {
                    if done == iters {
                        break;
                    }
                    let y = start[1] + lift * s as f32 / LIFT_STEPS as f32;
                    world.push(Command::MoveTo([start[0], y, start[2]]));
                    let t = Instant::now();
                    world.step();
                    total += t.elapsed();
                    done += 1;
                }
            }
            total
        })
    });
    group.bench_function("cut/one_layer_257", |b| {
        b.iter_batched(
            || base.clone(),
            |mut t| {
                t.queue_cut(CutSegment {
                    from: [-0.2, 0.0, 0.0005],
                    to: [0.2, 0.0, 0.0005],
                    depth: CutDepth::Upper,
                });
                t.apply_cuts()
            },
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

/// rapier3d's cloth: structural, shear and bending edges, the border and the centre pinned (the
/// centre driven as a kinematic target), damping on, gravity off.
fn rapier_cloth(n: usize) -> (PhysicsWorld, SoftBodyHandle, usize, Vector) {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    let idx = |i: usize, j: usize| (i * n + j) as u32;
    let mut pinned: Vec<u32> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            if i == 0 || j == 0 || i + 1 == n || j + 1 == n {
                pinned.push(idx(i, j));
            }
        }
    }
    let centre = idx(n / 2, n / 2);
    pinned.push(centre);
    let builder = SoftBodyBuilder::cloth(Vector::ZERO, Vector::X * H, Vector::Z * H, n, n)
        .mass(1.0)
        .linear_damping(5.0)
        .pinned_particles(pinned)
        .can_sleep(false);
    let handle = world.insert_soft_body(builder);
    let start = Vector::new((n / 2) as f32 * H, 0.0, (n / 2) as f32 * H);
    (world, handle, centre as usize, start)
}

fn peer_benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("peer/rapier3d");
    group.sample_size(10).measurement_time(Duration::from_secs(10)).warm_up_time(Duration::from_secs(1));
    group.throughput(Throughput::Elements(257 * 257));
    let lift = 0.2 * 256.0 * H;
    group.bench_function("cloth_257_step", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut done = 0;
            while done < iters {
                let (mut world, handle, centre, start) = rapier_cloth(257);
                for s in 1..=LIFT_STEPS {
                    if done == iters {
                        break;
                    }
                    let target = start + Vector::Y * (lift * s as f32 / LIFT_STEPS as f32);
                    world.soft_bodies[handle].set_particle_kinematic_target(centre, target);
                    let t = Instant::now();
                    world.step();
                    total += t.elapsed();
                    done += 1;
                }
            }
            total
        })
    });
    group.bench_function("cloth_257_cut", |b| {
        b.iter_batched(
            || rapier_cloth(257),
            |(mut world, handle, _, _)| {
                let z = 128.5 * H;
                let blade =
                    [Vector::new(-1.0, -0.1, z), Vector::new(1.5, -0.1, z), Vector::new(0.25, 1.0, z)];
                world.cut_soft_body(handle, &blade).is_some()
            },
            BatchSize::PerIteration,
        )
    });
    group.finish();
}

criterion_group!(tissue, dissect_benches, peer_benches);
criterion_main!(tissue);
