//! Benches of the linear FEM reference model against ChainMail on the same 16³ block: the load-time
//! precomputation (condensation and explicit inverse), one FEM step (a grasped node moved:
//! 3 × 3 solve and selective multiplication) and one ChainMail step (deformation of one top node and
//! 10 relaxation sweeps). Moves are drawn from a seeded generator.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dissect::chainmail::{Body, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace};
use dissect::fem::{Base, ElasticMaterial, FemModel, ImposeWork, LoadOptions, Split, Supports, TetMesh};

const N: usize = 16;
const H: f64 = 0.005;

/// A small seeded generator (xorshift64*), uniform in [-1, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn load() -> FemModel {
    let mesh = TetMesh::block([N; 3], H, Split::Six).expect("mesh");
    let supports = Supports::base(&mesh, Base::Clamped);
    FemModel::load(mesh, ElasticMaterial::default(), &supports, &LoadOptions::default(), |_| {})
        .expect("load")
}

fn fem(c: &mut Criterion) {
    let mut g = c.benchmark_group("fem/precompute");
    g.sample_size(10).measurement_time(Duration::from_secs(30)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements((N * N * N) as u64));
    g.bench_function("block_16", |b| b.iter(|| black_box(load())));
    g.finish();

    let model = load();
    let top = model.mesh().node_at(N / 2, N - 1, N / 2).expect("top");
    let mut u = vec![0.0; model.condensed_dofs()];
    let mut rng = Rng(0x5eed_f00d);
    let mut work = ImposeWork::default();
    let step = 0.02 * (N - 1) as f64 * H;
    let mut g = c.benchmark_group("fem/smvm");
    g.throughput(Throughput::Elements(model.surface_nodes().len() as u64));
    g.bench_function("block_16", |b| {
        b.iter(|| {
            let d = [step * rng.next(), step * rng.next(), step * rng.next()];
            black_box(model.impose_with(&[(top, d)], &mut u, &mut work).expect("impose"));
        })
    });
    g.finish();
}

fn chainmail(c: &mut Criterion) {
    let lattice = Lattice::volume(N, N, N, H as f32).expect("lattice");
    let mut body = Body::new(lattice, Material::relative(1.2, 0.7, 0.3)).expect("body");
    for i in 0..N {
        for k in 0..N {
            let e = body.lattice().element_at(i, 0, k).expect("base");
            body.set_pinned(e, true).expect("pin");
        }
    }
    let top: ElementId = body.lattice().element_at(N / 2, N - 1, N / 2).expect("top");
    body.set_held(top, true).expect("hold");
    let rest = body.lattice().rest_positions()[top.index()];
    let mut ws = Workspace::new(&body);
    let mut rng = Rng(0x5eed_f00d);
    let step = (0.02 * (N - 1) as f64 * H) as f32;
    let mut g = c.benchmark_group("chainmail/step");
    g.throughput(Throughput::Elements((N * N * N) as u64));
    g.bench_function("volume_16", |b| {
        b.iter(|| {
            let target = [0, 1, 2].map(|k| rest[k] + step * rng.next() as f32);
            black_box(body.deform(&mut ws, top, target, Pass::All).expect("deform"));
            black_box(body.relax(&mut ws, RelaxBudget::sweeps(10), RelaxRegion::All));
        })
    });
    g.finish();
}

criterion_group!(benches, fem, chainmail);
criterion_main!(benches);
