//! ChainMail engine benches: the chain reaction (rigid: every element moves; soft: a local drag), one
//! relaxation sweep, and a lift's cone (the distances from the held elements, `docs/implicit-lift.md`)
//! over the careful meninges exercise's final lift. Figures go to the README's performance table as ns
//! per element.

use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use dissect::chainmail::{
    Body, Cone, ElementId, Lattice, Material, Pass, RelaxBudget, RelaxRegion, Workspace,
};
use dissect::runner::Player;
use dissect::scene::{Scene, Script};

/// A small deterministic generator, so the benches' inputs are seeded.
struct Lcg(u64);
impl Lcg {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
    }
}

fn propagate(c: &mut Criterion, name: &str, lattice: Lattice, material: Material, step: f32) {
    let n = lattice.element_count();
    propagate_from(c, name, lattice, material, step, n / 2);
}

/// The chain reaction with element `source` moved back and forth.
fn propagate_from(
    c: &mut Criterion,
    name: &str,
    lattice: Lattice,
    material: Material,
    step: f32,
    source: usize,
) {
    let mut body = Body::new(lattice, material).expect("body");
    let mut ws = Workspace::new(&body);
    let src = ElementId(source as u32);
    // One dry run tells how many elements a move of this size carries.
    let p = body.position(src).expect("source");
    let moved = body.deform(&mut ws, src, [p[0] + step, p[1] + step, p[2]], Pass::All).expect("deform").moved;
    let mut group = c.benchmark_group("chainmail/propagate");
    group.throughput(Throughput::Elements(moved as u64));
    group.measurement_time(Duration::from_secs(4));
    let mut rng = Lcg(7);
    let mut sign = -1.0f32;
    group.bench_function(name, |b| {
        b.iter(|| {
            let p = body.position(src).expect("source");
            let jitter = 0.1 * step * rng.next_f32();
            sign = -sign;
            let t = [p[0] + sign * (step + jitter), p[1] + sign * step, p[2]];
            body.deform(&mut ws, src, t, Pass::All).expect("deform").moved
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    let h = 0.001;
    propagate(c, "sheet_512_rigid", Lattice::sheet(512, 512, h).expect("sheet"), Material::rigid(), 2.0 * h);
    // The same with the grasp in the middle of the middle row (the source above is its first element):
    // half of each row then moves down the row, half up.
    propagate_from(
        c,
        "sheet_512_rigid_centre",
        Lattice::sheet(512, 512, h).expect("sheet"),
        Material::rigid(),
        2.0 * h,
        256 * 512 + 256,
    );
    propagate(
        c,
        "sheet_1024_soft",
        Lattice::sheet(1024, 1024, h).expect("sheet"),
        Material::relative(1.2, 0.8, 0.3),
        3.0 * h,
    );
    propagate(
        c,
        "volume_64_rigid",
        Lattice::volume(64, 64, 64, h).expect("volume"),
        Material::rigid(),
        2.0 * h,
    );

    let lattice = Lattice::sheet(512, 512, h).expect("sheet");
    let mut body = Body::new(lattice, Material::relative(1.2, 0.8, 0.3)).expect("body");
    let mut ws = Workspace::new(&body);
    let mut rng = Lcg(11);
    for _ in 0..200 {
        let e = ElementId((rng.next_f32() * body.element_count() as f32) as u32);
        let p = body.position(e).expect("e");
        let t = [
            p[0] + 0.01 * (rng.next_f32() - 0.5),
            p[1] + 0.01 * (rng.next_f32() - 0.5),
            0.005 * rng.next_f32(),
        ];
        body.deform(&mut ws, e, t, Pass::All).expect("deform");
    }
    let mut group = c.benchmark_group("chainmail/relax");
    group.throughput(Throughput::Elements(body.element_count() as u64));
    group.measurement_time(Duration::from_secs(4));
    group.bench_function("sheet_512", |b| {
        b.iter_batched_ref(
            || (),
            |_| body.relax(&mut ws, RelaxBudget::sweeps(1), RelaxRegion::All),
            BatchSize::SmallInput,
        )
    });
    group.finish();
}

/// The meninges' body and the elements the forceps hold at step `at` of the careful script, at `nu × nv`.
fn held_at(nu: u32, nv: u32, at: u64) -> (Body, Vec<ElementId>) {
    let scene = Scene::from_str(include_str!("../scenes/meninges.ron"), "meninges.ron")
        .expect("scene")
        .with_resolution(nu, nv);
    let script =
        Script::from_str(include_str!("../scenes/scripts/meninges_careful.ron"), "careful").expect("script");
    let mut world = scene.build_world(false).expect("world");
    let mut player = Player::new(script.0);
    while world.step_count() < at {
        player.feed(&mut world);
        world.step();
    }
    let tissue = world.tissue();
    (tissue.body().clone(), tissue.held().collect())
}

/// A lift's cone from the held elements at the careful exercise's final lift (step 1 290), grown
/// as far as a 5 mm lift reaches: what a lift kept as a distance field would settle over a lift
/// (the tent under the jaws), element by element in order of distance.
fn cone(c: &mut Criterion) {
    let mut group = c.benchmark_group("chainmail/cone");
    group.measurement_time(Duration::from_secs(4));
    for (nu, nv) in [(256, 192), (512, 384)] {
        let (body, held) = held_at(nu, nv, 1_290);
        let mut cone = Cone::new();
        cone.start(&body, &held);
        let settled = cone.grow(&body, 0.005);
        group.throughput(Throughput::Elements(settled as u64));
        group.bench_function(format!("meninges_lift_{nu}x{nv}"), |b| {
            b.iter(|| {
                cone.start(&body, &held);
                cone.grow(&body, 0.005)
            })
        });
        println!("chainmail/cone/meninges_lift_{nu}x{nv}: {} held, {settled} elements settled", held.len());
    }
    group.finish();
}

criterion_group!(chainmail, benches, cone);
criterion_main!(chainmail);
