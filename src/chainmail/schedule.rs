//! Thread scheduling for the whole-body sweep and the tear scan of a large region: two halves of the
//! work (or pieces of it, taken in turn) run at once, on the calling thread and on one of rayon's
//! pool's, with a short spin-wait instead of sleeping. Knows nothing of bodies: the relaxation's
//! bands (`relax/bands.rs`) and the tissue's tear scan (`tissue/scan.rs`) call it.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
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
/// last piece, the caller does not spin for one; a caller outside the pool then still waits (blocking,
/// rayon's scope) until a pool thread has run the job, which finds no piece left, as it waits in
/// [`here_and_there`]; a worker of the pool ([`worker_pool`]) takes the job back and runs it itself.
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
        // A pool thread woken ahead (`wake_ahead`) stops waiting and takes the job just spawned.
        TURNS.fetch_add(1, Ordering::Release);
        run();
        // The pool thread, if it has started, may hold a piece (it took it before the caller found
        // none left: the counter orders both).
        if started.load(Ordering::SeqCst) {
            spin_until(&done);
        }
    });
}

/// How many times [`in_turns`] has handed work to the pool: what a thread woken ahead waits for.
static TURNS: AtomicU64 = AtomicU64::new(0);

/// Longest a thread woken ahead waits for [`in_turns`] before it goes back to the pool.
const AHEAD: Duration = Duration::from_micros(300);

/// Wakes one pool thread ahead of an [`in_turns`] that the caller is about to run (the tear scan of
/// a large region, after contact): the woken thread spins until that call hands out its pieces (or
/// [`AHEAD`] has passed), then takes them with the caller. A pool thread asleep when the work is
/// handed out takes tens of microseconds to wake on this project's virtual machines, and in the
/// careful exercise's lifts the caller had then taken most of the pieces itself: 17 of 589 went to
/// the pool thread (200 split scans at 256 x 192, 2026-11-28, the machine busy with a build). Does
/// nothing on one thread. Runs nothing of the caller's: results do not change.
pub(crate) fn wake_ahead() {
    if rayon::current_num_threads() < 2 {
        return;
    }
    let seen = TURNS.load(Ordering::Acquire);
    rayon::spawn(move || {
        let start = Instant::now();
        while TURNS.load(Ordering::Acquire) == seen && start.elapsed() < AHEAD {
            for _ in 0..64 {
                std::hint::spin_loop();
            }
        }
    });
}

/// Makes the calling thread a worker of a new rayon pool of its own (thread 0; the others, named
/// `name-1` and on, help it), as many threads as rayon's global pool would have (`RAYON_NUM_THREADS`,
/// else the machine's cores). The pool lasts while the value is kept; the thread stays a worker until
/// it is dropped.
///
/// Why: `here_and_there` and `in_turns` hand half of the work to a pool thread inside a rayon
/// scope, and a scope waits until every job spawned in it has run. Called from outside the pool, the
/// caller cannot run that job itself: when no pool thread has started it by the time the caller has
/// done all the work (a machine whose other cores are busy: the trainer's windows drawing with a
/// software rasteriser), the caller blocks until the scheduler gives a pool thread a core, up to a
/// tick (4 ms here) in the middle of a step. Called from a worker of the pool, the spawned job waits
/// in the caller's own queue, and at the scope's end the caller takes it back and runs it (finding
/// nothing left to do) unless a helper has taken it already. Nothing else changes: each piece of work
/// still runs once, and its result does not depend on which thread ran it.
pub fn worker_pool(name: &str) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    let name = name.to_string();
    rayon::ThreadPoolBuilder::new().use_current_thread().thread_name(move |i| format!("{name}-{i}")).build()
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

    /// A worker of its own pool whose helpers are all busy is not held up: the scope's job comes back
    /// to the caller, which runs it itself, and every piece runs once. (Were the caller not thread 0
    /// of the pool, the first assertion fails.)
    #[test]
    fn a_worker_does_not_wait_for_busy_helpers() {
        let result = std::thread::spawn(|| {
            let pool = worker_pool("test").expect("pool");
            assert_eq!(rayon::current_thread_index(), Some(0), "the caller is the pool's thread 0");
            let helpers = pool.current_num_threads() - 1;
            if helpers == 0 {
                return None; // one core: no helper to be busy
            }
            // Every helper busy until the pieces are done (or 3 s have passed).
            let (release, busy) =
                (std::sync::Arc::new(AtomicBool::new(false)), std::sync::Arc::new(AtomicUsize::new(0)));
            for _ in 0..helpers {
                let (release, busy) = (release.clone(), busy.clone());
                pool.spawn(move || {
                    busy.fetch_add(1, Ordering::SeqCst);
                    let t = Instant::now();
                    while !release.load(Ordering::SeqCst) && t.elapsed() < Duration::from_secs(3) {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                });
            }
            let t = Instant::now();
            while busy.load(Ordering::SeqCst) < helpers {
                if t.elapsed() > Duration::from_secs(2) {
                    return None; // the helpers were not scheduled: nothing to measure
                }
                std::thread::sleep(Duration::from_millis(1));
            }
            let runs: Vec<AtomicUsize> = (0..9).map(|_| AtomicUsize::new(0)).collect();
            let t = Instant::now();
            in_turns(runs.len(), |k| {
                runs[k].fetch_add(1, Ordering::SeqCst);
            });
            let took = t.elapsed();
            release.store(true, Ordering::SeqCst);
            Some((took, runs.iter().all(|r| r.load(Ordering::SeqCst) == 1)))
        });
        let Some((took, once)) = result.join().expect("thread") else { return };
        assert!(once, "every piece runs once");
        assert!(took < Duration::from_secs(1), "the caller waited {took:?} for a busy helper");
    }

    /// A thread woken ahead takes its share of the pieces, each once; woken for work that never
    /// comes, it goes back to the pool within `AHEAD`, and the pool's next work runs as usual.
    #[test]
    fn a_thread_woken_ahead_takes_pieces_or_goes_back() {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            pool.install(|| {
                wake_ahead();
                std::thread::sleep(Duration::from_micros(100));
                let runs: Vec<AtomicUsize> = (0..37).map(|_| AtomicUsize::new(0)).collect();
                in_turns(runs.len(), |k| {
                    runs[k].fetch_add(1, Ordering::SeqCst);
                });
                assert!(runs.iter().all(|r| r.load(Ordering::SeqCst) == 1), "{threads} threads");
                // Woken for nothing: the pool thread is free again after `AHEAD`.
                wake_ahead();
                std::thread::sleep(AHEAD + Duration::from_millis(5));
                let t = Instant::now();
                let (a, b) = rayon::join(|| 1, || 2);
                assert_eq!((a, b), (1, 2));
                assert!(t.elapsed() < Duration::from_secs(1), "{threads} threads: {:?}", t.elapsed());
            });
        }
    }

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
