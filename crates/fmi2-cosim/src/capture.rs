//! Keeps what FMUs log, so an error can quote the FMU's own reason.
//!
//! The `fmi` crate passes every FMU log call to the `log` crate with the instance name as
//! target. Calls into an FMU run on the caller's thread, so a thread-local list suffices:
//! [`mark`] before a call, [`since`] after it to get that instance's messages.

use std::cell::RefCell;

/// Messages kept per thread; older ones are dropped.
const KEEP: usize = 256;

thread_local! {
    static MESSAGES: RefCell<(usize, Vec<(String, String)>)> = const { RefCell::new((0, Vec::new())) };
}

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Warn || metadata.target() != "fmi"
    }

    fn log(&self, record: &log::Record) {
        // FMU messages come through the fmi crate's C logger with module path "logger".
        if record.module_path() != Some("logger") {
            return;
        }
        let line = format!("[{}] {}", record.level(), record.args());
        MESSAGES.with(|m| {
            let mut m = m.borrow_mut();
            m.0 += 1;
            m.1.push((record.target().to_owned(), line));
            if m.1.len() > KEEP {
                m.1.remove(0);
            }
        });
    }

    fn flush(&self) {}
}

static LOGGER: Capture = Capture;

/// Installs the capturing logger once; if the program has its own logger, that one stays
/// and errors carry no FMU messages.
pub fn install() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if log::set_logger(&LOGGER).is_ok() {
            log::set_max_level(log::LevelFilter::Info);
        }
    });
}

/// A position in this thread's message list.
pub fn mark() -> usize {
    MESSAGES.with(|m| m.borrow().0)
}

/// Messages of instance `name` logged on this thread after `mark`.
pub fn since(mark: usize, name: &str) -> Vec<String> {
    MESSAGES.with(|m| {
        let m = m.borrow();
        let newer = m.0.saturating_sub(mark).min(m.1.len());
        m.1[m.1.len() - newer..].iter().filter(|(t, _)| t == name).map(|(_, l)| l.clone()).collect()
    })
}
