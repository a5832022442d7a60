//! The fixed-step clock: real time accumulates, the simulation consumes it in fixed steps, a frame's
//! catch-up is capped so that a slow machine falls behind instead of freezing. The clock reads no time
//! itself (its owner, the world, is handed elapsed time), so it runs alike on native and in a browser.

use std::time::Duration;

/// Frame deltas longer than this are cut (a debugger pause, a dragged window).
pub const MAX_FRAME_DELTA: Duration = Duration::from_millis(250);

/// A time accumulator that hands out fixed steps.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedClock {
    step: Duration,
    accumulated: Duration,
    max_steps_per_frame: u32,
    behind: bool,
}

impl FixedClock {
    /// A clock of `rate_hz` steps per second that runs at most `max_steps_per_frame` steps per frame.
    pub fn new(rate_hz: f64, max_steps_per_frame: u32) -> Self {
        let rate = if rate_hz.is_finite() && rate_hz > 0.0 { rate_hz } else { 1000.0 };
        Self {
            step: Duration::from_secs_f64(1.0 / rate),
            accumulated: Duration::ZERO,
            max_steps_per_frame: max_steps_per_frame.max(1),
            behind: false,
        }
    }

    /// The fixed step.
    pub fn step(&self) -> Duration {
        self.step
    }

    /// Adds a frame's real time; returns how many steps to run now.
    pub fn advance(&mut self, frame: Duration) -> u32 {
        self.accumulated += frame.min(MAX_FRAME_DELTA);
        let due = (self.accumulated.as_nanos() / self.step.as_nanos().max(1)) as u64;
        let run = due.min(self.max_steps_per_frame as u64) as u32;
        self.accumulated -= self.step * run;
        // Whatever could not be run this frame is dropped: the simulation runs slower than real time.
        self.behind = due > run as u64;
        if self.behind {
            self.accumulated = Duration::ZERO;
        }
        run
    }

    /// Whether the last frame had to drop time (the simulation is slower than real time).
    pub fn is_behind(&self) -> bool {
        self.behind
    }

    /// How far into the next step real time has gone, in `[0, 1)`, for interpolation.
    pub fn alpha(&self) -> f32 {
        (self.accumulated.as_secs_f64() / self.step.as_secs_f64()) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hands_out_fixed_steps_and_caps_catch_up() {
        let mut c = FixedClock::new(1000.0, 50);
        assert_eq!(c.advance(Duration::from_millis(16)), 16);
        assert!(!c.is_behind());
        assert_eq!(c.advance(Duration::from_millis(100)), 50);
        assert!(c.is_behind());
        assert_eq!(c.advance(Duration::from_secs(10)), 50);
    }
}
