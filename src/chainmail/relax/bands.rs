//! The whole-body sweep cut into bands of slabs, one per thread: each band sees halo copies of the
//! slabs beyond its ends, so the result does not depend on the cut. The calling thread sweeps one
//! band itself (`schedule.rs`).

use super::grid::Band;
use crate::chainmail::body::Body;
use crate::chainmail::schedule::here_and_there;
use crate::chainmail::workspace::Workspace;

/// Bodies of fewer elements sweep on one thread: a second one costs more to start than it saves.
const PARALLEL_MIN: usize = 1 << 15;
/// Fewest slabs a band has.
const BAND_MIN: usize = 4;

/// Scratch slabs a sweep split `depth` times needs: two per band, two halos per split.
fn scratch_slabs(depth: u32) -> usize {
    (0..depth).fold(2, |s, _| 2 * s + 2)
}

impl Body {
    /// One Jacobi sweep over every element through the grid fast path, in place, with the
    /// workspace's spare positions as scratch; `None` if this body has no stencil, its neighbours
    /// reach across a seam of the slowest axis, or it is too short. Returns the largest move.
    ///
    /// Large bodies are cut into bands swept on the pool's threads, each seeing copies of the
    /// slabs beyond its ends: the result does not depend on the cut.
    pub(crate) fn sweep_grid(&mut self, ws: &mut Workspace) -> Option<f32> {
        let simd = ws.simd();
        let (stencil, scratch) = (ws.stencil.as_mut()?, &mut ws.next[..]);
        let n = self.pos.len();
        let slab = stencil.slab;
        if !stencil.slab_local || slab == 0 || !n.is_multiple_of(slab) || scratch.len() < 2 * slab {
            return None;
        }
        let slabs = n / slab;
        let threads = if n >= PARALLEL_MIN { rayon::current_num_threads() } else { 1 };
        // One band per thread (the calling thread sweeps one of them); one thread sweeps alone.
        let mut depth = 0;
        while threads > 1
            && (1 << (depth + 1)) <= threads
            && slabs >> (depth + 1) >= BAND_MIN
            && scratch_slabs(depth + 1) * slab <= scratch.len()
        {
            depth += 1;
        }
        if stencil.revision != self.revision {
            stencil.refresh(self);
        }
        let mut pos = std::mem::take(&mut self.pos);
        let (first, region, prev, next) = (0, &mut pos[..], None, None);
        let change = match stencil.offs.len() {
            4 => {
                let band = Band::<4> { body: self, stencil, simd, first, region, prev, next, scratch };
                Some(sweep_range(band, depth, true))
            }
            6 => {
                let band = Band::<6> { body: self, stencil, simd, first, region, prev, next, scratch };
                Some(sweep_range(band, depth, true))
            }
            _ => None,
        };
        self.pos = pos;
        change
    }
}

/// Sweeps the band's slabs, split `depth` times into bands run in parallel (`top`: called from
/// outside the pool).
fn sweep_range<const W: usize>(band: Band<'_, W>, depth: u32, top: bool) -> f32 {
    let slab = band.stencil.slab;
    let half = band.region.len() / slab / 2;
    if depth == 0 || half == 0 {
        // Each band is compiled once per instruction set and the widest the level and the CPU
        // allow is chosen at run time (AVX-512 or AVX2 on x86-64, single floats elsewhere). Rows
        // too short for AVX-512's sixteen elements take AVX2's eight.
        #[cfg(target_arch = "x86_64")]
        if band.stencil.dims[0] < 2 + 16
            && let Some(v3) = band.simd.v3()
        {
            return pulp::Simd::vectorize(v3, band);
        }
        return band.simd.arch().dispatch(band);
    }
    let Band { body, stencil, simd, first, region, prev, next, scratch } = band;
    let (halos, rest) = scratch.split_at_mut(2 * slab);
    let (left_last, right_first) = halos.split_at_mut(slab);
    left_last.copy_from_slice(&region[(half - 1) * slab..half * slab]);
    right_first.copy_from_slice(&region[half * slab..(half + 1) * slab]);
    let (left, right) = region.split_at_mut(half * slab);
    let (left_scratch, right_scratch) = rest.split_at_mut(rest.len() / 2);
    let left = Band::<W> {
        body,
        stencil,
        simd,
        first,
        region: left,
        prev,
        next: Some(right_first),
        scratch: left_scratch,
    };
    let right = Band::<W> {
        body,
        stencil,
        simd,
        first: first + half,
        region: right,
        prev: Some(left_last),
        next,
        scratch: right_scratch,
    };
    let (left, right) = (|| sweep_range(left, depth - 1, false), || sweep_range(right, depth - 1, false));
    // Inside the pool a plain `join`; from outside it, the calling thread takes a band itself.
    let (a, b) = if top { here_and_there(right, left) } else { rayon::join(left, right) };
    a.max(b)
}
