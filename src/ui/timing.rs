//! Frame and simulation times over the last seconds, for the plot and the monitor.

use std::collections::VecDeque;

/// How much history the plot keeps, seconds.
pub const WINDOW_S: f64 = 6.0;

/// One frame's times.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameSample {
    /// Wall time since the session started, seconds.
    pub t: f64,
    /// Time since the previous frame, milliseconds.
    pub frame_ms: f32,
    /// Time spent stepping the simulation in this frame, milliseconds.
    pub sim_ms: f32,
    /// Mean step time in this frame, microseconds (0 when no step ran).
    pub step_us: f32,
    /// Steps run in this frame.
    pub steps: u32,
}

/// The pace a simulation thread kept over its last full second (measured by the thread itself).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ThreadPace {
    /// Steps run in that second.
    pub steps_per_second: f32,
    /// Mean step time, microseconds.
    pub mean_step_us: f32,
    /// Worst deviation of the interval between two step starts from the step length, microseconds.
    pub worst_jitter_us: f32,
    /// 99th percentile of a step start's lateness after its deadline, microseconds.
    pub p99_late_us: f32,
    /// Steps between the frame input was given on and the step it reached the world.
    pub input_lag_steps: u64,
    /// Whether the thread gave up deadlines it could not keep.
    pub behind: bool,
    /// Whether the thread has real-time scheduling.
    pub realtime: bool,
    /// How it was scheduled at its start, in a few words ("real-time (RealtimeKit)", "normal priority").
    pub priority: &'static str,
    /// With normal priority, how to grant it real-time (one sentence).
    pub how_to_grant: Option<&'static str>,
}

/// A rolling history of [`FrameSample`]s, and the simulation thread's pace when there is one.
#[derive(Clone, Debug, Default)]
pub struct Timing {
    samples: VecDeque<FrameSample>,
    pace: Option<ThreadPace>,
}

impl Timing {
    /// Adds a frame and forgets what is older than the plotted window (six seconds).
    pub fn push(&mut self, sample: FrameSample) {
        self.samples.push_back(sample);
        while self.samples.front().is_some_and(|s| sample.t - s.t > WINDOW_S) {
            self.samples.pop_front();
        }
    }

    /// Sets the simulation thread's pace (the steps then run apart from the frames).
    pub fn set_pace(&mut self, pace: ThreadPace) {
        self.pace = Some(pace);
    }

    /// The simulation thread's pace, when the world steps on a thread of its own.
    pub fn pace(&self) -> Option<&ThreadPace> {
        self.pace.as_ref()
    }

    /// The samples, oldest first.
    pub fn samples(&self) -> &VecDeque<FrameSample> {
        &self.samples
    }

    /// Frames per second over the last second.
    pub fn fps(&self) -> f32 {
        let Some(last) = self.samples.back() else { return 0.0 };
        let recent: Vec<&FrameSample> = self.samples.iter().filter(|s| last.t - s.t < 1.0).collect();
        let ms: f32 = recent.iter().map(|s| s.frame_ms).sum();
        if ms > 0.0 { 1000.0 * recent.len() as f32 / ms } else { 0.0 }
    }

    /// Simulated steps per wall-clock second over the last second (the thread's count when there is one).
    pub fn steps_per_second(&self) -> f32 {
        if let Some(p) = &self.pace {
            return p.steps_per_second;
        }
        let Some(last) = self.samples.back() else { return 0.0 };
        let recent = self.samples.iter().filter(|s| last.t - s.t < 1.0);
        let (steps, ms) = recent.fold((0u32, 0.0f32), |(n, ms), s| (n + s.steps, ms + s.frame_ms));
        if ms > 0.0 { 1000.0 * steps as f32 / ms } else { 0.0 }
    }

    /// Mean step time over the last second, microseconds.
    pub fn mean_step_us(&self) -> f32 {
        if let Some(p) = &self.pace {
            return p.mean_step_us;
        }
        let Some(last) = self.samples.back() else { return 0.0 };
        let recent = self.samples.iter().filter(|s| last.t - s.t < 1.0 && s.steps > 0);
        let (n, us) =
            recent.fold((0u32, 0.0f32), |(n, us), s| (n + s.steps, us + s.step_us * s.steps as f32));
        if n > 0 { us / n as f32 } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_a_window_and_measures_rates() {
        let mut t = Timing::default();
        for k in 0..1000 {
            t.push(FrameSample {
                t: k as f64 * 0.02,
                frame_ms: 20.0,
                sim_ms: 5.0,
                step_us: 250.0,
                steps: 20,
            });
        }
        assert!(t.samples().len() <= (WINDOW_S / 0.02) as usize + 1);
        assert!((t.fps() - 50.0).abs() < 0.5);
        assert!((t.steps_per_second() - 1000.0).abs() < 5.0);
        assert!((t.mean_step_us() - 250.0).abs() < 0.1);
    }
}
