//! A real-time simulation thread behind its deadlines still blocks now and then. RealtimeKit grants
//! real-time scheduling only to a process whose `RLIMIT_RTTIME` is set (200 ms by default), and the
//! kernel kills a process whose real-time thread runs that long without blocking; a thread behind its
//! deadlines never needs to sleep. This binary (a process of its own) sets the soft limit to 50 ms (the
//! kernel then sends SIGXCPU, which terminates it; the hard limit stays, so that RealtimeKit's client
//! may still set its own 200 ms), then steps the default exercise at 64 times its rate, far behind: the
//! process must live and step. (The thread blocks once it has not for `MAX_UNBLOCKED`, 10 ms, after the
//! step it is in: a debug build's step with the other core streaming memory can take 10 ms more. With a
//! 20 ms limit this test was killed in 1 of 8 runs beside two `exercise_trace 512 384`, 2026-11-29;
//! a thread that never blocked would still run the whole 900 ms.)
//!
//! Meaningful where the thread gets real-time scheduling (root as in CI, `CAP_SYS_NICE`, an rtprio
//! limit, or RealtimeKit); elsewhere it says so and checks only that the thread steps.

#![cfg(target_os = "linux")]

use std::time::{Duration, Instant};

use dissect::runner::{Episode, Input, SimThread, Source};
use dissect::scene::Scene;
use rustix::process::{Resource, Rlimit, getrlimit, setrlimit};

#[test]
fn a_real_time_thread_behind_its_deadlines_outlives_rlimit_rttime() {
    // At 50 ms of real-time CPU without blocking the kernel terminates this process (SIGXCPU).
    let maximum = getrlimit(Resource::Rttime).maximum;
    let current = Some(maximum.map_or(50_000, |m| m.min(50_000)));
    setrlimit(Resource::Rttime, Rlimit { current, maximum }).expect("lowering a soft limit is allowed");
    let scene = Scene::default_scene().expect("default scene");
    let world = scene.build_world(false).expect("world");
    let mut sim = SimThread::spawn(Episode::new(world, None, Source::Live)).expect("thread");
    sim.send(Input::Speed(64.0));
    // The thread gives real-time up after its first second behind: that second is the one at risk.
    let t = Instant::now();
    let mut realtime = false;
    while t.elapsed() < Duration::from_millis(900) {
        let pace = sim.latest().pace;
        realtime |= pace.realtime && pace.rate_hz > 60_000.0;
        std::thread::sleep(Duration::from_millis(5));
    }
    let steps = sim.latest().view.step_count();
    let (episode, _) = sim.stop();
    assert!(episode.is_some(), "the thread ended cleanly");
    assert!(steps > 100, "the thread steps ({steps} steps)");
    if !realtime {
        eprintln!("not real-time here ({}): only the stepping was checked", sim.scheduling());
    }
}
