//! Limits hold: on the meninges exercise (coarsened to keep the test quick), random sessions of
//! grasps, lifts, pushes and cuts never leave an intact link outside its material's limits after a
//! step, up to rounding. Links that go past their tear ratio break (and are counted as torn).
//!
//! Where the limits could not all hold with the instrument where it is, the engine decides as
//! follows (`src/tissue/limits.rs`), and this test holds it to that: pinned elements never move;
//! elements held by the forceps' jaws give way (the tissue slips in the jaws, so the pull is cut
//! short, as pins cut a chain reaction short) rather than leave a link outside its box; the layers
//! never cross (a layer pressed between the instrument and the lower layer pushes the instrument's
//! hold back). The probe holds nothing: what it pushes may be pushed back. Since the rest shape
//! holds every limit and only pins stay put, some placement always does, and no intact link is let
//! off.

mod common;

use dissect::chainmail::LinkId;
use dissect::simulation::Command;
use dissect::simulation::{InstrumentKind, World};
use dissect::tissue::CutDepth;
use proptest::prelude::*;

/// Tolerance on a link's distance outside its box, as a share of the element spacing: the repair's
/// (`TOLERANCE` in `src/tissue/limits.rs`, a thousandth of the spacing) and a half of it more for
/// rounding.
const SLACK: f32 = 1.5e-3;

fn world(nu: u32, nv: u32) -> World {
    common::meninges(nu, nv)
}

#[derive(Clone, Debug)]
enum Act {
    To(f32, f32, f32),
    Do(Command),
}

fn act() -> impl Strategy<Value = Act> {
    prop_oneof![
        5 => (0.0f32..1.0, 0.0f32..1.0, 0.0f32..0.015).prop_map(|(u, v, h)| Act::To(u, v, h)),
        1 => prop_oneof![
            Just(InstrumentKind::Forceps),
            Just(InstrumentKind::Probe),
            Just(InstrumentKind::Scalpel)
        ]
        .prop_map(|k| Act::Do(Command::Select(k))),
        2 => Just(Act::Do(Command::Grasp)),
        1 => Just(Act::Do(Command::Release)),
        1 => Just(Act::Do(Command::BeginCut)),
        1 => Just(Act::Do(Command::EndCut)),
        1 => prop_oneof![Just(CutDepth::Upper), Just(CutDepth::Between), Just(CutDepth::Lower)]
            .prop_map(|d| Act::Do(Command::SetDepth(d))),
    ]
}

fn worst_violation(world: &World) -> (f32, u32) {
    let body = world.tissue().body();
    let mut worst = (0.0f32, 0);
    for l in 0..body.link_count() as u32 {
        let id = LinkId(l);
        if !body.link_intact(id) {
            continue;
        }
        let v = body.link_violation(id).unwrap_or(0.0);
        if v > worst.0 {
            worst = (v, l);
        }
    }
    worst
}

/// Plays `acts` (each a move there in that many steps, or a command held for that many steps) on the
/// meninges at 40 × 30 and checks every intact link after every step.
fn play(acts: &[(Act, u8)]) -> Result<(), String> {
    play_on(world(40, 30), acts, 0.0)
}

/// [`play`] on `world`, the moves' heights above the surface lowered by `down` metres.
fn play_on(mut world: World, acts: &[(Act, u8)], down: f32) -> Result<(), String> {
    let spacing = world.tissue().spacing();
    // Moves go there in small steps, as a hand does.
    let mut at = world.tissue().surface_point(0.5, 0.5, 0.003);
    for (a, steps) in acts {
        match a {
            Act::Do(c) => world.push(c.clone()),
            Act::To(..) => {}
        }
        let goal = match *a {
            Act::To(u, v, h) => world.tissue().surface_point(u, v, h - down),
            Act::Do(_) => at,
        };
        let from = at;
        for s in 1..=u32::from(*steps) {
            let f = s as f32 / f32::from(*steps);
            at = [0, 1, 2].map(|k| from[k] + f * (goal[k] - from[k]));
            world.push(Command::MoveTo(at));
            world.step();
            let (v, l) = worst_violation(&world);
            if v > SLACK * spacing {
                return Err(format!(
                    "step {}: link {} ({:?}) is {} m outside its limits ({} spacings): offset {:?}, box {:?}, counters {:?}",
                    world.step_count(),
                    l,
                    world.tissue().link_kind(LinkId(l)),
                    v,
                    v / spacing,
                    world.tissue().body().link_offset(LinkId(l)),
                    world.tissue().body().link_limits(LinkId(l)),
                    world.last_step()
                ));
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(12)))]
    #[test]
    fn no_intact_link_leaves_its_limits(acts in proptest::collection::vec((act(), 1u8..30), 1..30)) {
        let played = play(&acts);
        prop_assert!(played.is_ok(), "{}", played.err().unwrap_or_default());
    }

    /// The same on the bundled volume of elastic cells (`poisson_ratio: Some(0.45)`) at 10³: the probe
    /// pressed up to 8 mm in, the forceps pulling, the scalpel cutting; the cells' relaxation keeps
    /// every intact link within its limits too.
    #[test]
    fn no_intact_link_of_an_elastic_volume_leaves_its_limits(
        acts in proptest::collection::vec((act(), 1u8..30), 1..30)
    ) {
        let played = play_on(volume(10), &acts, 0.008);
        prop_assert!(played.is_ok(), "{}", played.err().unwrap_or_default());
    }
}

fn volume(n: u32) -> World {
    let mut scene = dissect::scene::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/volume.ron"))
        .expect("volume scene");
    if let dissect::scene::Tissue::Volume(v) = &mut scene.tissue {
        assert!(v.material.poisson_ratio.is_some(), "the bundled volume relaxes elastic cells");
        v.resolution = [n; 3];
    }
    scene.build_world(false).expect("world")
}

/// A grasp dragged 2 mm up and across stays clamped while the probe is selected (two-handed work) and
/// lifted clear; the probe's lift-away starts a settling of what it pressed, beside the clamp. Found by
/// `.ci/run`'s random sessions on 2026-11-29: the settling's coarse correction then moved a free
/// neighbour 2.3 mm beside the clamped element, the limits' repair ran out of moves bouncing against the
/// clamp (7 825), and a dura link stayed 0.63 spacings outside its box. The correction now waits while
/// the forceps clamp anything (`Tissue::relax_region`).
#[test]
fn a_clamped_drag_keeps_its_limits_while_the_probe_is_used() {
    use dissect::simulation::InstrumentKind::Probe;
    let acts = [
        (Act::To(0.7771646, 0.6480908, 0.0), 1),
        (Act::Do(Command::Grasp), 1),
        (Act::To(0.4648598, 0.8565077, 0.0018575288), 13),
        (Act::Do(Command::Select(Probe)), 11),
        (Act::To(0.39631665, 0.63910294, 0.014901154), 11),
    ];
    if let Err(e) = play(&acts) {
        panic!("{e}");
    }
}

/// Found by `no_intact_link_leaves_its_limits` (2026-11-30): the probe swept fast across the dura and
/// pressed deep at the end.
#[test]
fn a_fast_deep_probe_keeps_the_limits() {
    let acts = [
        (Act::Do(Command::Select(InstrumentKind::Probe)), 1),
        (Act::To(0.7180723, 0.4057592, 0.0056760623), 1),
        (Act::To(0.048078205, 0.500874, 0.0019941654), 6),
        (Act::To(0.5370484, 0.77836984, 0.00012209266), 14),
    ];
    let played = play(&acts);
    assert!(played.is_ok(), "{}", played.err().unwrap_or_default());
}
