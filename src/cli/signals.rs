//! SIGINT (Ctrl-C), SIGTERM (a scheduler's time limit, `scancel`, pre-emption) and SIGHUP (a closed
//! terminal or session). In a render the first asks it to stop at the next block and keep what is
//! finished; a second, or any to a command that has nothing to keep, ends the process at once after
//! removing its temporary files. Either way the exit status is 128 + the signal's number, what a
//! shell reports for a process the signal killed (130, 143, 129).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

use super::console::note;

/// Set by the first signal to a render: it stops at the next block and writes what is finished.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// The first signal received (0 before any).
static FIRST: AtomicI32 = AtomicI32::new(0);

/// Whether the command keeps its finished work on a first signal (a render), rather than ending.
static KEEPS: AtomicBool = AtomicBool::new(false);

/// Handles the three signals from here on. With `keeps`, the first sets [`STOP`] and the command
/// goes on to write what is finished; otherwise every signal ends the process at once.
pub fn handle(keeps: bool) {
    static THREAD: OnceLock<()> = OnceLock::new();
    KEEPS.store(keeps, Ordering::SeqCst);
    THREAD.get_or_init(|| {
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            // Without handlers the signals keep their default action: they end the process.
            return;
        };
        std::thread::spawn(move || {
            for signal in signals.forever() {
                let first = FIRST.compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst);
                if first.is_ok() && KEEPS.load(Ordering::SeqCst) {
                    STOP.store(true, Ordering::SeqCst);
                    continue;
                }
                whitted::files::remove_temporaries();
                if first.is_err() {
                    note(format!(
                        "whitted: {} again: stopped at once; nothing more is written",
                        name(signal)
                    ));
                }
                std::process::exit(status(signal).into());
            }
        });
    });
}

/// The first signal received, if any.
pub fn received() -> Option<i32> {
    match FIRST.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The exit status after `signal`: 128 + its number.
pub fn status(signal: i32) -> u8 {
    u8::try_from(128 + signal).unwrap_or(u8::MAX)
}

/// How a note names `signal`: Ctrl-C for SIGINT, else its name.
pub fn name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "Ctrl-C",
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "a signal",
    }
}
