//! Assessment: cutting only the target's fibres and separating the layers scores higher than cutting
//! through the upper layer and outside the target, and the damage is counted where it happened.

mod common;

use dissect::runner::{Episode, Player, Source};
use dissect::scene::{Action, Point};
use dissect::simulation::{InstrumentKind, World, WorldConfig};
use dissect::tissue::CutDepth;
use dissect::training::{Assessor, Goals, Region};

fn goals() -> Goals {
    Goals {
        forbidden: vec![Region::Rect { u: (0.0, 1.0), v: (0.85, 1.0) }],
        stretch_limit: 1.6,
        separation: 0.003,
        time_limit_s: Some(30.0),
        ..Goals::new(Region::Rect { u: (0.3, 0.7), v: (0.3, 0.7) })
    }
}

fn play(actions: Vec<Action>) -> dissect::training::Assessment {
    let world = World::new(common::plane(25), WorldConfig::default());
    let assessor = Assessor::new(goals(), &world);
    let mut episode = Episode::new(world, Some(assessor), Source::Script(Player::new(actions)));
    while episode.world().step_count() < 20_000 && episode.step().is_some() {}
    let assessor = episode.assessor().expect("assessor");
    assessor.assessment(episode.world())
}

fn strokes(depth: CutDepth, v0: f32, v1: f32, u0: f32, u1: f32, h: f32) -> Vec<Action> {
    (0..=8)
        .map(|k| {
            let v = v0 + (v1 - v0) * k as f32 / 8.0;
            Action::Cut { path: vec![Point::Surface(u0, v, h), Point::Surface(u1, v, h)], depth, steps: 40 }
        })
        .collect()
}

#[test]
fn careful_scores_above_careless() {
    let mut careful = vec![Action::Select(InstrumentKind::Scalpel)];
    careful.extend(strokes(CutDepth::Between, 0.34, 0.66, 0.34, 0.66, 0.0015));
    careful.extend([
        Action::Grasp(Point::Surface(0.5, 0.5, 0.003)),
        Action::MoveTo { to: Point::Surface(0.5, 0.5, 0.012), steps: 300 },
        Action::Wait(50),
    ]);
    let mut careless = vec![Action::Select(InstrumentKind::Scalpel)];
    careless.extend(strokes(CutDepth::Upper, 0.2, 0.95, 0.1, 0.9, 0.003));
    careless.extend(strokes(CutDepth::Between, 0.1, 0.95, 0.1, 0.9, 0.0015));
    careless.extend([
        Action::Grasp(Point::Surface(0.5, 0.5, 0.003)),
        Action::MoveTo { to: Point::Surface(0.5, 0.5, 0.03), steps: 100 },
    ]);
    let a = play(careful);
    let b = play(careless);
    assert!(a.completion > 0.9, "careful completion {}", a.completion);
    assert_eq!(a.layer_links_cut, 0);
    assert_eq!(a.forbidden_links_broken, 0);
    assert!(a.connective_cut_outside < b.connective_cut_outside / 4);
    assert!(a.separation_m > 0.002, "careful separation {}", a.separation_m);
    assert!(b.layer_links_cut > 0 && b.connective_cut_outside > 0 && b.forbidden_links_broken > 0);
    assert!(a.score > b.score, "careful {} vs careless {}", a.score, b.score);
    let sum: f32 = a.breakdown.iter().map(|i| i.points).sum();
    assert!((sum.clamp(0.0, 100.0) - a.score).abs() < 1e-4, "the breakdown adds up to the score");
}
