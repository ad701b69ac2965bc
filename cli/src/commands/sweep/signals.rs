//! The sweep's signals: the first SIGINT, SIGTERM or SIGHUP stops new runs and goes once to
//! the runs under way (which finish their recordings and exit); a second goes to them too (they
//! then quit at once) and ends the sweep. The runs are in their own process groups, so a
//! terminal's Ctrl-C reaches the sweep alone and each run receives every signal exactly once.

use std::process::{Child, Command};
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::Mutex;

/// The first signal (0: none yet).
static SIGNAL: AtomicI32 = AtomicI32::new(0);
/// The runs under way; a signal goes to them under this lock, and a run starts under it only
/// while no signal has come, so none is missed.
static CHILDREN: Mutex<Vec<u32>> = Mutex::new(Vec::new());

/// From now on, the signals stop the sweep as the module says.
pub fn watch() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("critterbox-sweep-signals".into())
            .spawn(move || {
                for sig in signals.forever() {
                    let first = SIGNAL
                        .compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst)
                        .is_ok();
                    for &pid in children().iter() {
                        // SAFETY: kill(2) only sends a signal, to a child not yet waited for.
                        unsafe {
                            libc::kill(pid as libc::pid_t, sig);
                        }
                    }
                    if !first {
                        std::process::exit(128 + sig);
                    }
                }
            });
    });
}

/// The signal that stopped the sweep, if one did.
pub fn interrupted() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    }
}

fn children() -> std::sync::MutexGuard<'static, Vec<u32>> {
    CHILDREN.lock().unwrap_or_else(|e| e.into_inner())
}

/// Starts a run unless a signal came: `None` then.
pub fn spawn(cmd: &mut Command) -> Option<std::io::Result<Child>> {
    let mut pids = children();
    if interrupted().is_some() {
        return None;
    }
    let child = cmd.spawn();
    if let Ok(c) = &child {
        pids.push(c.id());
    }
    Some(child)
}

/// The run `pid` has been waited for: no signal goes to it any more.
pub fn forget(pid: u32) {
    children().retain(|&p| p != pid);
}
