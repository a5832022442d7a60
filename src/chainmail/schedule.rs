//! Thread scheduling for the whole-body sweep and the tear scan of a large region: two halves of the
//! work (or pieces of it, taken in turn) run at once, on the calling thread and on one of rayon's
//! pool's, with a short spin-wait instead of sleeping. Knows nothing of bodies: the relaxation's
//! bands (`relax/bands.rs`) and the tissue's tear scan (`tissue/scan.rs`) call it.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::time::Duration;

use web_time::Instant;

/// How long the calling thread waits for the pool's half by spinning before it blocks.
const SPIN: Duration = Duration::from_millis(2);

/// Runs `here` on the calling thread and `there` on the thread pool, and returns both results.
///
/// `rayon::join` called from outside the pool hands both halves to the pool and puts the caller to
/// sleep until they are done: on this project's virtual machines waking the sleeping threads costs
/// tens of microseconds, as much as a quarter of a whole-body sweep. Here only one pool thread is
/// woken, and the caller, once done with its own half, spins briefly rather than sleeping (and
/// then blocks as usual, which also lets a pool thread calling this run the other half itself).
/// If no pool thread has started `there` by the time `here` is done (a machine busy with other
/// work), the caller runs it itself rather than wait for one: either way each half runs once,
/// so the results do not depend on which thread ran it.
pub(crate) fn here_and_there<A, B>(here: A, there: B) -> (f32, f32)
where
    A: FnOnce() -> f32,
    B: FnOnce() -> f32 + Send,
{
    let task = Mutex::new(Some(there));
    // Whoever takes the task first runs it.
    let take = || task.lock().ok().and_then(|mut t| t.take());
    let far = AtomicU32::new(0f32.to_bits());
    let done = AtomicBool::new(false);
    let near = rayon::in_place_scope(|s| {
        s.spawn(|_| {
            if let Some(there) = take() {
                far.store(there().to_bits(), Ordering::Relaxed);
            }
            done.store(true, Ordering::Release);
        });
        let near = here();
        if let Some(there) = take() {
            far.store(there().to_bits(), Ordering::Relaxed);
        } else {
            spin_until(&done);
        }
        near
    });
    (near, f32::from_bits(far.load(Ordering::Relaxed)))
}

/// Runs `work` on every piece `0..pieces`, each once, on the calling thread and one pool thread at
/// once: each takes the next piece not yet taken until none is left, so that the two finish
/// together however unevenly the pieces cost (halves of a tear scan's region can differ by half:
/// one layer lifted, the other at rest). What each piece does must not depend on which thread ran
/// it or when (the caller keeps each piece's results apart and joins them in order).
///
/// As [`here_and_there`]: one pool thread is woken, and the caller spins briefly for the pool's last
/// piece rather than sleeping. If no pool thread has started by the time the caller has taken the
/// last piece, the caller does not spin for one; rayon's scope still waits (blocking) until a pool
/// thread has run the job, which then finds no piece left, as it waits in [`here_and_there`].
pub(crate) fn in_turns<W>(pieces: usize, work: W)
where
    W: Fn(usize) + Sync,
{
    let next = AtomicUsize::new(0);
    let run = || {
        loop {
            let k = next.fetch_add(1, Ordering::SeqCst);
            if k >= pieces {
                break;
            }
            work(k);
        }
    };
    let started = AtomicBool::new(false);
    let done = AtomicBool::new(false);
    rayon::in_place_scope(|s| {
        s.spawn(|_| {
            started.store(true, Ordering::SeqCst);
            run();
            done.store(true, Ordering::SeqCst);
        });
        run();
        // The pool thread, if it has started, may hold a piece (it took it before the caller found
        // none left: the counter orders both).
        if started.load(Ordering::SeqCst) {
            spin_until(&done);
        }
    });
}

/// Spins until `done` is set or [`SPIN`] has passed (the scope's end then blocks as usual).
fn spin_until(done: &AtomicBool) {
    let start = Instant::now();
    while !done.load(Ordering::Acquire) && start.elapsed() < SPIN {
        for _ in 0..64 {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every piece runs once, whichever thread takes it, with a pool of two threads and of one.
    #[test]
    fn every_piece_runs_once() {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            let runs: Vec<AtomicUsize> = (0..37).map(|_| AtomicUsize::new(0)).collect();
            pool.install(|| {
                in_turns(runs.len(), |k| {
                    runs[k].fetch_add(1, Ordering::SeqCst);
                })
            });
            assert!(runs.iter().all(|r| r.load(Ordering::SeqCst) == 1), "{threads} threads");
        }
    }
}
