//! Thread scheduling for the whole-body sweep and the tear scan of a large region: two halves of the
//! work run at once, one on the calling thread and one on rayon's pool, with a short spin-wait
//! instead of sleeping. Knows nothing of bodies: the relaxation's bands (`relax/bands.rs`) and the
//! tissue's tear scan (`tissue/scan.rs`) call it.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use web_time::Instant;

/// How long the calling thread waits for the pool's half by spinning before it blocks.
const SPIN: Duration = Duration::from_millis(2);

/// Runs `here` on the calling thread and `there` on the thread pool, and returns both results (the
/// second `None` only if its lock was poisoned, which no code holding it can do).
///
/// `rayon::join` called from outside the pool hands both halves to the pool and puts the caller to
/// sleep until they are done: on this project's virtual machines waking the sleeping threads costs
/// tens of microseconds, as much as a quarter of a whole-body sweep. Here only one pool thread is
/// woken, and the caller, once done with its own half, spins briefly rather than sleeping (and
/// then blocks as usual, which also lets a pool thread calling this run the other half itself).
/// If no pool thread has started `there` by the time `here` is done (a machine busy with other
/// work), the caller runs it itself rather than wait for one: either way each half runs once,
/// so the results do not depend on which thread ran it.
pub(crate) fn here_and_there<A, B, R, S>(here: A, there: B) -> (R, Option<S>)
where
    A: FnOnce() -> R,
    B: FnOnce() -> S + Send,
    S: Send,
{
    let task = Mutex::new(Some(there));
    // Whoever takes the task first runs it.
    let take = || task.lock().ok().and_then(|mut t| t.take());
    let far = Mutex::new(None);
    let keep = |s: S| {
        if let Ok(mut f) = far.lock() {
            *f = Some(s);
        }
    };
    let done = AtomicBool::new(false);
    let near = rayon::in_place_scope(|s| {
        s.spawn(|_| {
            if let Some(there) = take() {
                keep(there());
            }
            done.store(true, Ordering::Release);
        });
        let near = here();
        if let Some(there) = take() {
            keep(there());
        } else {
            let start = Instant::now();
            while !done.load(Ordering::Acquire) && start.elapsed() < SPIN {
                for _ in 0..64 {
                    std::hint::spin_loop();
                }
            }
        }
        near
    });
    // The task ran once, on one thread or the other, before the scope ended (a panic in it ends the
    // scope with that panic): its result is there unless the lock was poisoned, which only a panic
    // while holding it could do.
    (near, far.into_inner().ok().flatten())
}
