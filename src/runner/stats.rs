//! Step-time statistics in fixed memory: the step times go into a histogram (HdrHistogram, three
//! significant digits, 1 ns to an hour), so a run of any length keeps the same few hundred kilobytes
//! where a list of every step's time grew by 4 bytes a step.

use hdrhistogram::Histogram;

use super::TimeStats;

/// Longest step time told apart, nanoseconds (an hour); longer steps count as this long in the
/// quantiles (the mean and the maximum stay exact).
const HIGHEST_NS: u64 = 3_600_000_000_000;

/// Step times so far: exact count, mean and maximum; median and 99th percentile to three significant
/// digits.
#[derive(Clone, Debug)]
pub struct StepTimes {
    histogram: Option<Histogram<u64>>,
    count: u64,
    sum_us: f64,
    max_us: f32,
}

impl Default for StepTimes {
    fn default() -> Self {
        Self::new()
    }
}

impl StepTimes {
    /// No steps yet.
    pub fn new() -> Self {
        // The bounds are constants that the crate accepts; `None` would only lose the quantiles.
        let histogram = Histogram::new_with_bounds(1, HIGHEST_NS, 3).ok();
        Self { histogram, count: 0, sum_us: 0.0, max_us: 0.0 }
    }

    /// Adds one step's time, microseconds.
    pub fn record(&mut self, us: f32) {
        let us = if us.is_finite() { us.max(0.0) } else { 0.0 };
        self.count += 1;
        self.sum_us += f64::from(us);
        self.max_us = self.max_us.max(us);
        if let Some(h) = &mut self.histogram {
            let ns = (f64::from(us) * 1e3).round().clamp(1.0, HIGHEST_NS as f64) as u64;
            h.saturating_record(ns);
        }
    }

    /// Steps recorded.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Slots the histogram keeps: fixed when it is made, whatever is recorded.
    pub fn slots(&self) -> usize {
        self.histogram.as_ref().map_or(0, Histogram::distinct_values)
    }

    /// The summary.
    pub fn stats(&self) -> TimeStats {
        if self.count == 0 {
            return TimeStats::default();
        }
        let q = |q: f64| self.histogram.as_ref().map_or(0.0, |h| h.value_at_quantile(q) as f32 * 1e-3);
        TimeStats {
            mean: (self.sum_us / self.count as f64) as f32,
            p50: q(0.5).min(self.max_us),
            p99: q(0.99).min(self.max_us),
            max: self.max_us,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_the_sorted_samples_and_memory_stays_fixed() {
        let mut times = StepTimes::new();
        let slots = times.slots();
        assert!(slots > 0);
        // A spread of step times, 0.1 µs to 50 ms, in a scrambled order.
        let mut samples: Vec<f32> =
            (0..200_000u32).map(|i| 0.1 + (i.wrapping_mul(7919) % 200_000) as f32 * 0.25).collect();
        for &s in &samples {
            times.record(s);
        }
        assert_eq!(times.slots(), slots, "no growth with the number of steps");
        let got = times.stats();
        let want = TimeStats::of(&mut samples);
        for (g, w) in [(got.p50, want.p50), (got.p99, want.p99)] {
            assert!((g - w).abs() <= 1e-3 * w + 1e-3, "{got:?} against {want:?}");
        }
        assert_eq!(got.max, want.max);
        assert!((got.mean - want.mean).abs() <= 1e-4 * want.mean, "{got:?} against {want:?}");
        // Non-finite and huge times are kept in range.
        times.record(f32::NAN);
        times.record(f32::MAX);
        assert_eq!(times.count(), 200_002);
        assert!(times.stats().p99.is_finite());
    }
}
