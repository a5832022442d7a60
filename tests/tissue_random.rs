//! Property test: thousands of random steps with random grasps, pushes and cuts never produce NaN, never
//! move a pinned element, keep the layers apart, and replaying the same inputs gives the same bits.

mod common;

use dissect::chainmail::RelaxBudget;
use dissect::simulation::Command;
use dissect::simulation::{InstrumentKind, World, WorldConfig};
use dissect::tissue::CutDepth;
use proptest::prelude::*;

fn command() -> impl Strategy<Value = Command> {
    let p = proptest::array::uniform3(-0.04f32..0.04);
    prop_oneof![
        4 => p.prop_map(Command::MoveTo),
        1 => prop_oneof![
            Just(InstrumentKind::Forceps),
            Just(InstrumentKind::Probe),
            Just(InstrumentKind::Scalpel)
        ]
        .prop_map(Command::Select),
        1 => Just(Command::Grasp),
        1 => Just(Command::Release),
        1 => Just(Command::BeginCut),
        1 => Just(Command::EndCut),
        1 => prop_oneof![Just(CutDepth::Upper), Just(CutDepth::Between), Just(CutDepth::Lower)]
            .prop_map(Command::SetDepth),
    ]
}

fn run(commands: &[(Command, u8)]) -> Result<Vec<[f32; 3]>, TestCaseError> {
    let tissue = common::plane(12);
    let pinned: Vec<(usize, [f32; 3])> = (0..tissue.body().element_count())
        .filter(|&i| tissue.body().is_pinned(dissect::chainmail::ElementId(i as u32)))
        .map(|i| (i, tissue.body().positions()[i]))
        .collect();
    let mut world =
        World::new(tissue, WorldConfig { relax: RelaxBudget::sweeps(2), ..WorldConfig::default() });
    for (ci, (c, steps)) in commands.iter().enumerate() {
        world.push(c.clone());
        for _ in 0..*steps {
            world.step();
        }
        let t = world.tissue();
        prop_assert!(t.body().positions().iter().all(|p| p.iter().all(|x| x.is_finite())), "NaN");
        for &(i, p) in &pinned {
            prop_assert_eq!(t.body().positions()[i], p);
        }
        let sheet = t.layers()[0].count as usize;
        for i in 0..sheet {
            let (l, u) = (t.body().positions()[i], t.body().positions()[i + sheet]);
            prop_assert!(
                u[2] - l[2] >= t.min_gap() - 1e-5,
                "layers crossed at element {} after command {} ({:?}): gap {} < {}",
                i,
                ci,
                c,
                u[2] - l[2],
                t.min_gap()
            );
        }
    }
    Ok(world.tissue().body().positions().to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(24)))]
    #[test]
    fn random_sessions_stay_sane(commands in proptest::collection::vec((command(), 1u8..40), 50..120)) {
        let a = run(&commands)?;
        let b = run(&commands)?;
        prop_assert!(a.iter().zip(&b).all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)));
    }
}
