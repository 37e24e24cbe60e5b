//! `neurarm simulate system.toml`: a system file run through the master, its recording
//! written as CSV, Ctrl-C ending the run cleanly with the rows so far.

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use anyhow::Context;
use neurarm_cosim::{BaseType, MasterError, OnDiscard, RunEnd, RunOutcome, SystemSpec};

/// How a run of a system file ended, for the CLI to report.
#[derive(Debug)]
pub enum SystemRunEnd {
    /// At the stop time (or at the last whole step before it, see the notices).
    Completed,
    /// A unit discarded a step and the run ended early, as the system file allows.
    Discarded,
    /// Ctrl-C (or SIGINT) ended the run at this time [s].
    Interrupted(f64),
    /// A unit failed: the error, with the rows before it written.
    Failed(MasterError),
}

/// What a run wrote and said.
#[derive(Debug)]
pub struct SystemRun {
    /// Rows written.
    pub rows: usize,
    /// The last recorded time [s], if any row.
    pub last_time: Option<f64>,
    /// Notices of the master (a discarded step, a stop time it could not land on).
    pub notices: Vec<String>,
    /// How it ended.
    pub end: SystemRunEnd,
}

/// The flag Ctrl-C raises: installed once per process. A second Ctrl-C while the first is
/// being handled ends the process at once (a unit stuck inside a call never returns).
/// The outcome of the first installation is kept (shared: `ctrlc::Error` is no `Clone`).
fn interrupt_flag() -> Result<Arc<AtomicBool>, Arc<ctrlc::Error>> {
    static FLAG: OnceLock<Result<Arc<AtomicBool>, Arc<ctrlc::Error>>> = OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        let raised = flag.clone();
        ctrlc::set_handler(move || {
            if raised.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        })?;
        Ok(flag)
    })
    .clone()
}

/// Runs the system file at `system` and writes its recording to `output` (a CSV), also when a
/// unit fails or the run is interrupted (then with the rows so far). `on_discard` overrides
/// the file's `[simulation] on_discard`.
/// A write error keeps its `std::io::Error` in the chain (a closed pipe can be told apart).
pub fn run_system_file(system: &Path, output: &Path, on_discard: Option<OnDiscard>) -> anyhow::Result<SystemRun> {
    let text = neurarm_physics::text_file::read_text(system, neurarm_physics::text_file::MAX_CONFIG_BYTES)
        .with_context(|| format!("reading {}", system.display()))?;
    // `SystemSpec::from_toml` says what is wrong, and where, in words.
    let mut spec = SystemSpec::from_toml(&text, &system.display().to_string())?;
    if let Some(policy) = on_discard {
        spec.simulation.on_discard = policy;
    }
    let base = system.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let flag = interrupt_flag().context("cannot catch Ctrl-C")?;
    let outcome = neurarm_cosim::run(&spec, base, Some(flag)).with_context(|| system.display().to_string())?;
    write_recording(output, &outcome).with_context(|| format!("writing {}", crate::output::describe(output)))?;
    let (rows, last_time) = (outcome.rows.len(), outcome.rows.last().map(|r| r[0]));
    let end = match (outcome.end, outcome.error) {
        (_, Some(e)) => SystemRunEnd::Failed(e),
        (Some(RunEnd::Discarded { .. }), None) => SystemRunEnd::Discarded,
        (Some(RunEnd::Interrupted { time }), None) => SystemRunEnd::Interrupted(time),
        _ => SystemRunEnd::Completed,
    };
    Ok(SystemRun { rows, last_time, notices: outcome.notices, end })
}

/// A CSV field: quoted when it holds a comma, quote or line break.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// The recording as CSV: a header of the columns, then one line per row; Real values in their
/// shortest round-trip form, Integer, Boolean (0/1) and enumeration values as integers,
/// strings as text.
fn recording_csv(outcome: &RunOutcome) -> String {
    let mut out = String::new();
    let header: Vec<String> = outcome.columns.iter().map(|c| field(c)).collect();
    out.push_str(&header.join(","));
    out.push('\n');
    let string_columns: Vec<usize> = (0..outcome.column_types.len()).filter(|&c| outcome.column_types[c] == BaseType::String).collect();
    for (r, row) in outcome.rows.iter().enumerate() {
        for (c, &value) in row.iter().enumerate() {
            if c > 0 {
                out.push(',');
            }
            match outcome.column_types[c].access() {
                BaseType::Real => crate::table::push_number(&mut out, value),
                BaseType::String => {
                    let k = string_columns.iter().position(|&s| s == c).expect("a String column");
                    out.push_str(&field(outcome.texts.get(r).and_then(|t| t.get(k)).map_or("", String::as_str)));
                }
                _ => out.push_str(&format!("{}", value as i64)),
            }
        }
        out.push('\n');
    }
    out
}

fn write_recording(output: &Path, outcome: &RunOutcome) -> std::io::Result<()> {
    let text = recording_csv(outcome);
    crate::table::write_text_atomic(output, &text)?;
    std::io::stderr().flush()
}
