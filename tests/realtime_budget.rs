//! A real-time simulation thread behind its deadlines still blocks now and then. RealtimeKit grants
//! real-time scheduling only to a process whose `RLIMIT_RTTIME` is set (200 ms by default), and the
//! kernel kills a process whose real-time thread runs that long without blocking; a thread behind its
//! deadlines never needs to sleep. This binary (a process of its own) sets the soft limit to 20 ms (the
//! kernel then sends SIGXCPU, which terminates it; the hard limit stays, so that RealtimeKit's client
//! may still set its own 200 ms), then steps the default exercise at 64 times its rate, far behind: the
//! process must live and step.
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
    // At 20 ms of real-time CPU without blocking the kernel terminates this process (SIGXCPU).
    let maximum = getrlimit(Resource::Rttime).maximum;
    let current = Some(maximum.map_or(20_000, |m| m.min(20_000)));
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
