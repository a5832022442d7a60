//! Which SIMD instructions the engine's fast paths use. By default the widest the CPU has (pulp picks
//! at run time); `DISSECT_SIMD=avx2` or `DISSECT_SIMD=scalar` in the environment caps it, so that a
//! machine with AVX-512 can measure and test what an AVX2-only machine runs. A [`Workspace`]
//! carries its level (from the environment unless set), and every dispatch of the chain reaction and
//! of relaxation goes through it. The levels give the same chain reaction bit for bit; relaxation's
//! grid path differs between `Scalar` and the vector levels in the rounding of its fused
//! multiply-adds.
//!
//! [`Workspace`]: super::Workspace

use std::sync::OnceLock;

/// The widest vectors the engine's fast paths may use (x86-64; elsewhere pulp's own choice runs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdLevel {
    /// No explicit vectors (the compiler may still use SSE2).
    Scalar,
    /// AVX2 with FMA (pulp's `V3`): eight floats.
    Avx2,
    /// AVX-512 (pulp's `V4`): sixteen floats and mask registers.
    Avx512,
}

/// The environment variable that caps the level.
pub const SIMD_ENV: &str = "DISSECT_SIMD";

impl SimdLevel {
    /// The widest level this CPU has.
    pub fn detected() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if pulp::x86::V4::try_new().is_some() {
                return Self::Avx512;
            }
            if pulp::x86::V3::try_new().is_some() {
                return Self::Avx2;
            }
        }
        Self::Scalar
    }

    /// The default level: [`SIMD_ENV`] (`avx512`, `avx2` or `scalar`), read once per process and
    /// capped at what the CPU has; the detected level when unset or not one of those (then with a
    /// warning in the log).
    pub fn from_env() -> Self {
        static LEVEL: OnceLock<SimdLevel> = OnceLock::new();
        *LEVEL.get_or_init(|| {
            let Ok(value) = std::env::var(SIMD_ENV) else {
                return Self::detected();
            };
            match Self::parse(&value) {
                Some(level) => level.supported(),
                None => {
                    log::warn!(
                        "{SIMD_ENV}={value:?}: expected avx512, avx2 or scalar; using the CPU's widest"
                    );
                    Self::detected()
                }
            }
        })
    }

    /// A level by name: `avx512`, `avx2` or `scalar` (any case).
    pub fn parse(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "avx512" | "avx-512" => Some(Self::Avx512),
            "avx2" => Some(Self::Avx2),
            "scalar" | "none" => Some(Self::Scalar),
            _ => None,
        }
    }

    /// `self`, lowered to what this CPU has.
    pub fn supported(self) -> Self {
        self.min(Self::detected())
    }

    /// pulp's dispatcher for this level: the widest instruction set the level and the CPU allow.
    #[inline]
    pub(crate) fn arch(self) -> pulp::Arch {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(v4) = self.v4() {
                return pulp::Arch::V4(v4);
            }
            if let Some(v3) = self.v3() {
                return pulp::Arch::V3(v3);
            }
            pulp::Arch::Scalar
        }
        #[cfg(not(target_arch = "x86_64"))]
        pulp::Arch::new()
    }

    /// AVX-512, if the level allows it and the CPU has it.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    pub(crate) fn v4(self) -> Option<pulp::x86::V4> {
        if self >= Self::Avx512 { pulp::x86::V4::try_new() } else { None }
    }

    /// AVX2, if the level allows it and the CPU has it.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    pub(crate) fn v3(self) -> Option<pulp::x86::V3> {
        if self >= Self::Avx2 { pulp::x86::V3::try_new() } else { None }
    }
}

/// Hints that fetch a cache line ahead of its use, for loops that read scattered elements in an order
/// known ahead (a region's list): SSE's `prefetcht0`, through pulp's checked wrapper, where the level
/// allows AVX2 on x86-64; nothing elsewhere. A hint never faults and changes no result, only when
/// the data arrives.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prefetch {
    #[cfg(target_arch = "x86_64")]
    v3: Option<pulp::x86::V3>,
}

impl Prefetch {
    /// How many elements ahead of the one it works on a loop over a list of scattered elements asks
    /// for the next ones' data. In the careful exercise (AVX2, medians of three runs a step,
    /// 2026-11-30) the tear scan's contact and limits phase fell from 20.7-21.5 to 17.7-18.1 µs a step
    /// at 256 × 192 and from 43.9-44.6 to 35.4-35.9 at 512 × 384, with 8, 16 or 32 alike.
    pub(crate) const AHEAD: usize = 16;

    /// Hints for `level` (none below AVX2).
    pub(crate) fn new(level: SimdLevel) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            Self { v3: level.v3() }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = level;
            Self {}
        }
    }

    /// Fetches the line that holds `slice[i]` (or would: an index past the end is only a hint too).
    #[inline(always)]
    pub(crate) fn at<T>(self, slice: &[T], i: usize) {
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = self.v3 {
            v3.sse._mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(slice.as_ptr().wrapping_add(i).cast());
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (slice, i);
    }
}

impl Default for SimdLevel {
    /// [`SimdLevel::from_env`].
    fn default() -> Self {
        Self::from_env()
    }
}
