//! The simulation thread's scheduling: real-time where the system grants it.
//!
//! The simulation thread must start each step within a fraction of a millisecond of its deadline
//! while the windows draw. On a machine without a GPU the drawing is software (lavapipe), whose
//! rasterising threads keep every core busy; a thread of normal priority that wakes for its deadline
//! then often waits for the scheduler's next tick behind them (4 ms at this kernel's 250 Hz tick).
//! With real-time scheduling it runs the moment its deadline comes.
//!
//! [`Scheduler::acquire`] asks for it the ways desktop audio and haptics programs do, in this order
//! ([`Grant`]):
//! 1. directly (`SCHED_FIFO` at [`REALTIME_PRIORITY`]), which Linux allows root, a program with
//!    `CAP_SYS_NICE` (`setcap cap_sys_nice+ep dissect`) and a user with a real-time priority limit
//!    (`ulimit -r`; e.g. `@audio - rtprio 95` in `/etc/security/limits.conf`);
//! 2. on Linux, from RealtimeKit (`rtkit-daemon`, D-Bus `org.freedesktop.RealtimeKit1`, the service
//!    PipeWire and PulseAudio use on most desktops), through Mozilla's `audio_thread_priority`: it sets
//!    the process's `RLIMIT_RTTIME` as rtkit requires (rtkit's maximum, 200 ms by default: a real-time
//!    thread that runs that long without blocking is killed, so the thread blocks at least every
//!    [`MAX_UNBLOCKED`] while real-time) and asks `MakeThreadRealtime` (`SCHED_RR` at priority 10);
//! 3. otherwise the thread keeps normal scheduling, and [`Outcome::line`] says how to grant it.
//!
//! The thread gives real-time scheduling up while it runs without deadlines (a seek) and while its
//! steps take most of their period ([`super::thread`]), so it never holds a core the windows need,
//! and takes it back the way it was granted ([`Scheduler::resume`]).
//!
//! Native only (the browser has no threads here); RealtimeKit on Linux only, other systems ask
//! directly. Must not import wgpu, winit or egui.

use std::fmt;
use std::time::Duration;

use thread_priority::{
    NormalThreadSchedulePolicy, RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue,
    ThreadSchedulePolicy,
};

/// The simulation thread's real-time priority (1 to 99): low among real-time threads, above every
/// normal one. RealtimeKit is asked for the same (`audio_thread_priority` asks for 10; rtkit grants up
/// to 20 by default).
pub const REALTIME_PRIORITY: u8 = 10;

/// The longest a real-time thread runs without blocking: it sleeps briefly when it has not slept for
/// this long (a thread behind its deadlines never sleeps otherwise), far inside the `RLIMIT_RTTIME`
/// RealtimeKit requires (200 ms by default).
pub const MAX_UNBLOCKED: Duration = Duration::from_millis(10);

/// How the thread came to its scheduling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Grant {
    /// Real-time (`SCHED_FIFO`), set by the thread itself.
    Direct,
    /// Real-time (`SCHED_RR`), granted by RealtimeKit.
    Rtkit,
    /// Normal scheduling: no way granted real-time.
    #[default]
    Normal,
}

impl Grant {
    /// A few words for the monitor: "real-time (direct)", "real-time (RealtimeKit)", "normal priority".
    pub fn label(self) -> &'static str {
        match self {
            Grant::Direct => "real-time (direct)",
            Grant::Rtkit => "real-time (RealtimeKit)",
            Grant::Normal => "normal priority",
        }
    }
}

/// How to let the thread run real-time (one sentence, for the monitor and the log).
pub const HOW_TO_GRANT: &str = "to grant real-time: `sudo setcap cap_sys_nice+ep dissect`, or an rtprio limit \
     (`@audio - rtprio 95` in /etc/security/limits.conf, user in group audio), or run RealtimeKit \
     (package rtkit) in a desktop session";

/// What asking for real-time scheduling came to: the way that granted it, and why each way tried
/// before it (or every way, when none did) refused.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// How the thread is scheduled.
    pub grant: Grant,
    /// The ways that refused, in the order tried, each with its reason.
    pub refused: Vec<(Grant, String)>,
}

impl Outcome {
    /// Whether the thread runs real-time.
    pub fn realtime(&self) -> bool {
        self.grant != Grant::Normal
    }

    /// Tries `ways` in order until one grants real-time scheduling (and tries no further).
    pub fn first_granted<F: FnOnce() -> Result<(), String>>(
        ways: impl IntoIterator<Item = (Grant, F)>,
    ) -> Self {
        let mut refused = Vec::new();
        for (grant, ask) in ways {
            match ask() {
                Ok(()) => return Self { grant, refused },
                Err(why) => refused.push((grant, why)),
            }
        }
        Self { grant: Grant::Normal, refused }
    }

    /// One line for the log and the window: "simulation thread: real-time (RealtimeKit)", or, with
    /// normal scheduling, why and how to grant it.
    pub fn line(&self) -> String {
        let mut line = format!("simulation thread: {}", self.grant.label());
        if self.grant == Grant::Normal {
            let why: Vec<String> = self
                .refused
                .iter()
                .map(|(way, why)| match way {
                    Grant::Direct => format!("direct request: {why}"),
                    Grant::Rtkit => format!("RealtimeKit: {why}"),
                    Grant::Normal => why.clone(),
                })
                .collect();
            if !why.is_empty() {
                line += &format!(" ({})", why.join("; "));
            }
            line += "; steps may start milliseconds late while the windows draw; ";
            line += HOW_TO_GRANT;
        }
        line
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.line())
    }
}

/// One way to ask real-time scheduling for the calling thread.
type Ask = fn() -> Result<(), String>;

/// The calling thread's real-time scheduling: how it was granted, and the means to give it up and
/// take it back that way. Lives on the thread it was made on.
pub struct Scheduler {
    grant: Grant,
    realtime: bool,
    #[cfg(target_os = "linux")]
    info: Option<audio_thread_priority::RtPriorityThreadInfo>,
}

impl fmt::Debug for Scheduler {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Scheduler").field("grant", &self.grant).field("realtime", &self.realtime).finish()
    }
}

impl Scheduler {
    /// Asks real-time scheduling for the calling thread, each way in turn (see the module's notes).
    pub fn acquire() -> (Self, Outcome) {
        #[cfg(target_os = "linux")]
        let info = audio_thread_priority::get_current_thread_info().ok();
        let ways: &[(Grant, Ask)] = &[
            (Grant::Direct, realtime),
            #[cfg(target_os = "linux")]
            (Grant::Rtkit, rtkit),
        ];
        let outcome = Outcome::first_granted(ways.iter().copied());
        let scheduler = Self {
            grant: outcome.grant,
            realtime: outcome.realtime(),
            #[cfg(target_os = "linux")]
            info,
        };
        (scheduler, outcome)
    }

    /// How the thread was granted real-time scheduling (whether it holds it now or not).
    pub fn grant(&self) -> Grant {
        self.grant
    }

    /// Whether the thread holds real-time scheduling now.
    pub fn realtime(&self) -> bool {
        self.realtime
    }

    /// Takes real-time scheduling again, the way it was granted (nothing when it never was). A
    /// refusal is final: the thread keeps normal scheduling from then on ([`Grant::Normal`]) and asks
    /// no more (a RealtimeKit that refuses, rate-limits or hangs would otherwise be asked every second,
    /// and each ask holds the thread for a D-Bus round trip).
    pub fn resume(&mut self) -> Result<(), String> {
        if self.realtime || self.grant == Grant::Normal {
            return Ok(());
        }
        let asked = match self.grant {
            #[cfg(target_os = "linux")]
            Grant::Rtkit => rtkit(),
            _ => realtime(),
        };
        match asked {
            Ok(()) => {
                self.realtime = true;
                Ok(())
            }
            Err(why) => {
                let way = self.grant;
                self.grant = Grant::Normal;
                Err(format!(
                    "simulation thread: {} refused real-time scheduling again ({why}): normal priority from now on",
                    match way {
                        Grant::Rtkit => "RealtimeKit",
                        _ => "the system",
                    }
                ))
            }
        }
    }

    /// Gives real-time scheduling up (back to normal scheduling at nice 0).
    pub fn release(&mut self) -> Result<(), String> {
        if !self.realtime {
            return Ok(());
        }
        match self.grant {
            // Set by RealtimeKit with `SCHED_RESET_ON_FORK`, which a thread without `CAP_SYS_NICE`
            // must keep: the crate's demotion keeps it.
            #[cfg(target_os = "linux")]
            Grant::Rtkit => match self.info {
                Some(info) => audio_thread_priority::demote_thread_from_real_time(info)
                    .map_err(|e| format!("cannot return to normal scheduling: {e}"))?,
                None => normal()?,
            },
            _ => normal()?,
        }
        self.realtime = false;
        Ok(())
    }
}

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
        thread_priority::Error::OS(1) => {
            "no permission (not root, no CAP_SYS_NICE, rtprio limit 0)".to_string()
        }
        e => format!("refused: {e}"),
    })
}

/// Asks RealtimeKit to make the calling thread real-time (setting the process's `RLIMIT_RTTIME` to
/// rtkit's maximum first, as rtkit requires).
#[cfg(target_os = "linux")]
fn rtkit() -> Result<(), String> {
    // The crate's budget is frames / rate, capped at rtkit's maximum: one second asks for the
    // maximum, so the soft and hard limits are both rtkit's.
    audio_thread_priority::promote_current_thread_to_real_time(1000, 1000)
        .map(|_handle| ())
        .map_err(|e| rtkit_reason(&e.to_string()))
}

/// A refusal of RealtimeKit in a few words (the crate's message is long and nested).
#[cfg(target_os = "linux")]
fn rtkit_reason(message: &str) -> String {
    let message = message.replace("AudioThreadPriorityError: ", "");
    if message.contains("ServiceUnknown") || message.contains("was not provided by any .service") {
        "not installed or not running".to_string()
    } else if message.contains("Failed to connect to socket") || message.contains("NoServer") {
        "no system D-Bus".to_string()
    } else if message.contains("setrlimit") {
        format!("cannot set RLIMIT_RTTIME as it requires ({message})")
    } else if message.contains("NoReply") {
        "no answer".to_string()
    } else if message.contains("AccessDenied") || message.contains("Operation not permitted") {
        "refused (the user is not in an active desktop session, or polkit denies it)".to_string()
    } else {
        message
    }
}

/// Puts the calling thread back to normal scheduling at nice 0 (always allowed from real-time set by
/// the thread itself, where nice 0 is where the thread started).
pub fn normal() -> Result<(), String> {
    let value = ThreadPriorityValue::try_from(NICE_0).map_err(|e| e.to_string())?;
    thread_priority::set_thread_priority_and_policy(
        thread_priority::thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Other),
    )
    .map_err(|e| format!("cannot return to normal scheduling: {e}"))
}

/// Whether the calling thread has real-time scheduling now (`SCHED_FIFO` or `SCHED_RR`, as the kernel
/// reports it: `pthread_getschedparam` adds RealtimeKit's `SCHED_RESET_ON_FORK` to the policy, which
/// `thread_priority` does not parse).
pub fn is_realtime() -> bool {
    #[cfg(target_os = "linux")]
    {
        // Field 41 of the thread's stat, counted after the command's closing parenthesis (the command
        // may hold spaces): the policy, 1 for FIFO and 2 for RR.
        let policy = std::fs::read_to_string("/proc/thread-self/stat").ok().and_then(|stat| {
            let rest = &stat[stat.rfind(')')? + 1..];
            rest.split_whitespace().nth(38)?.parse::<u32>().ok()
        });
        matches!(policy, Some(1 | 2))
    }
    #[cfg(not(target_os = "linux"))]
    {
        matches!(thread_priority::thread_schedule_policy(), Ok(ThreadSchedulePolicy::Realtime(_)))
    }
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
            let (mut scheduler, outcome) = Scheduler::acquire();
            assert_eq!(scheduler.grant(), outcome.grant);
            if outcome.realtime() {
                assert!(is_realtime(), "{outcome}");
                assert!(scheduler.realtime());
                scheduler.release().expect("back to normal");
                assert!(!is_realtime());
                assert_eq!(nice(), Some(0), "nice 0 again");
                scheduler.resume().expect("real-time again, the same way");
                assert!(is_realtime());
                scheduler.release().expect("back to normal");
            } else {
                assert!(!is_realtime(), "refused ({outcome}) yet real-time");
                assert_eq!(nice(), start, "a refusal changes nothing");
                assert_eq!(outcome.refused.first().map(|r| r.0), Some(Grant::Direct), "asked directly first");
                assert!(scheduler.resume().is_ok() && !is_realtime(), "nothing to take back");
            }
        })
        .join()
        .expect("the thread ran");
    }

    #[test]
    fn the_ways_are_tried_in_order_until_one_grants() {
        type Way = Box<dyn FnOnce() -> Result<(), String>>;
        let refuse = |why: &'static str| -> Way { Box::new(move || Err(why.to_string())) };
        let grant = || -> Way { Box::new(|| Ok(())) };
        let never = || -> Way { Box::new(|| panic!("asked after a grant")) };

        let direct = Outcome::first_granted([(Grant::Direct, grant()), (Grant::Rtkit, never())]);
        assert_eq!(direct, Outcome { grant: Grant::Direct, refused: vec![] });
        assert_eq!(direct.line(), "simulation thread: real-time (direct)");

        let rtkit = Outcome::first_granted([(Grant::Direct, refuse("EPERM")), (Grant::Rtkit, grant())]);
        assert_eq!(rtkit.grant, Grant::Rtkit);
        assert_eq!(rtkit.refused, vec![(Grant::Direct, "EPERM".to_string())]);
        assert_eq!(rtkit.line(), "simulation thread: real-time (RealtimeKit)");

        let normal =
            Outcome::first_granted([(Grant::Direct, refuse("EPERM")), (Grant::Rtkit, refuse("not running"))]);
        assert!(!normal.realtime());
        let line = normal.line();
        assert!(
            line.starts_with(
                "simulation thread: normal priority (direct request: EPERM; RealtimeKit: not running); "
            ),
            "{line}"
        );
        assert!(line.ends_with(HOW_TO_GRANT), "{line}");
        assert!(!line.contains('\n'), "one line");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn realtime_kit_refusals_read_plainly() {
        assert_eq!(
            rtkit_reason(
                "AudioThreadPriorityError: org.freedesktop.DBus.Error.FileNotFound:Failed to connect to socket /run/dbus/system_bus_socket: No such file or directory"
            ),
            "no system D-Bus"
        );
        assert_eq!(
            rtkit_reason(
                "AudioThreadPriorityError: org.freedesktop.DBus.Error.ServiceUnknown:The name org.freedesktop.RealtimeKit1 was not provided by any .service files"
            ),
            "not installed or not running"
        );
        assert_eq!(
            rtkit_reason("AudioThreadPriorityError: Thread promotion error (Operation not permitted)"),
            "refused (the user is not in an active desktop session, or polkit denies it)"
        );
        assert!(
            rtkit_reason("AudioThreadPriorityError: setrlimit (Operation not permitted (os error 1))")
                .starts_with("cannot set RLIMIT_RTTIME"),
            "a limit the process may not set is not polkit's refusal"
        );
    }
}
