//! Keeps what FMUs log, so an error can quote the FMU's own reason.
//!
//! The `fmi` crate passes every FMU log call to the `log` crate: for FMI 2.0 with the
//! instance name as target, for FMI 3.0 with the log category as target and no instance name.
//! Calls into an FMU run on the caller's thread, so a thread-local list suffices: [`mark`]
//! before a call, [`since`] after it to get that instance's messages (FMI 3.0: every message
//! logged during the call, which can only come from the instance called).

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
        // FMU messages come through the fmi crate's C loggers: module path "logger" (FMI 2.0,
        // target the instance) or "fmu" (FMI 3.0, target the category).
        let (instance, line) = match record.module_path() {
            Some("logger") => (record.target().to_owned(), format!("[{}] {}", record.level(), record.args())),
            Some("fmu") => (String::new(), format!("[{}] [{}] {}", record.level(), record.target(), record.args())),
            _ => return,
        };
        MESSAGES.with(|m| {
            let mut m = m.borrow_mut();
            m.0 += 1;
            m.1.push((instance, line));
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

/// Messages of instance `name` logged on this thread after `mark` (with those of FMI 3.0
/// instances, which do not say whose they are).
pub fn since(mark: usize, name: &str) -> Vec<String> {
    MESSAGES.with(|m| {
        let m = m.borrow();
        let newer = m.0.saturating_sub(mark).min(m.1.len());
        m.1[m.1.len() - newer..].iter().filter(|(t, _)| t == name || t.is_empty()).map(|(_, l)| l.clone()).collect()
    })
}
