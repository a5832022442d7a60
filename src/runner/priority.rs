//! The simulation thread's scheduling: real-time where the system grants it.
//!
//! The simulation thread must start each step within a fraction of a millisecond of its deadline
//! while the windows draw. On a machine without a GPU the drawing is software (lavapipe), whose
//! rasterising threads keep every core busy; a thread of normal priority that wakes for its deadline
//! then often waits for the scheduler's next tick behind them (4 ms at this kernel's 250 Hz tick).
//! With real-time scheduling (`SCHED_FIFO`, [`realtime`]) it runs the moment its deadline comes.
//! Linux grants that to root, to a program with `CAP_SYS_NICE`, or to a user with a real-time
//! priority limit (`ulimit -r`; e.g. `@audio - rtprio 95` in `/etc/security/limits.conf`, as audio
//! and haptics set-ups have). Elsewhere the thread keeps normal scheduling. The thread gives real-time
//! scheduling up while it runs without deadlines (a seek) and while its steps take most of their
//! period ([`super::thread`]), so it never holds a core the windows need.
//!
//! Native Linux only (the browser has no threads here). Must not import wgpu, winit or egui.

use thread_priority::{
    NormalThreadSchedulePolicy, RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue,
    ThreadSchedulePolicy,
};

/// The simulation thread's real-time priority (`SCHED_FIFO`, 1 to 99): low among real-time threads,
/// above every normal one.
pub const REALTIME_PRIORITY: u8 = 10;

/// Makes the calling thread real-time (`SCHED_FIFO` at [`REALTIME_PRIORITY`]); the error says why
/// not (usually: no permission).
pub fn realtime() -> Result<(), String> {
    let value = ThreadPriorityValue::try_from(REALTIME_PRIORITY).map_err(|e| e.to_string())?;
    thread_priority::set_thread_priority_and_policy(
        thread_priority::thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| match e {
        thread_priority::Error::OS(1) => "no permission for real-time scheduling (EPERM)".to_string(),
        e => format!("no real-time scheduling: {e}"),
    })
}

/// Puts the calling thread back to normal scheduling at nice 0 (always allowed from real-time, where
/// nice 0 is where the thread started).
pub fn normal() -> Result<(), String> {
    let value = ThreadPriorityValue::try_from(NICE_0).map_err(|e| e.to_string())?;
    thread_priority::set_thread_priority_and_policy(
        thread_priority::thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Other),
    )
    .map_err(|e| format!("cannot return to normal scheduling: {e}"))
}

/// Whether the calling thread has real-time scheduling now.
pub fn is_realtime() -> bool {
    matches!(thread_priority::thread_schedule_policy(), Ok(ThreadSchedulePolicy::Realtime(_)))
}

/// The crate's cross-platform priority that it maps to nice 0 under the normal policy on Linux
/// (`nice = trunc(39 (1 − p / 99)) − 20`: 48 gives trunc(20.1) − 20 = 0; the test checks it).
const NICE_0: u8 = 48;

#[cfg(test)]
mod tests {
    use super::*;

    /// The calling thread's nice value, as the kernel reports it.
    fn nice() -> Option<i32> {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
        // Field 19 counted after the command's closing parenthesis (the command may hold spaces).
        stat[stat.rfind(')')? + 1..].split_whitespace().nth(16)?.parse().ok()
    }

    #[test]
    fn a_thread_takes_real_time_scheduling_where_granted_and_gives_it_back() {
        std::thread::spawn(|| {
            let start = nice();
            match realtime() {
                Ok(()) => {
                    assert!(is_realtime());
                    normal().expect("back to normal");
                    assert!(!is_realtime());
                    assert_eq!(nice(), Some(0), "nice 0 again");
                }
                Err(why) => {
                    assert!(!is_realtime(), "refused ({why}) yet real-time");
                    assert_eq!(nice(), start, "a refusal changes nothing");
                }
            }
        })
        .join()
        .expect("the thread ran");
    }
}
