//! What several commands share: argument groups (the arm and its initial state, a log's
//! column names), loading and writing a configuration, naming an FMU, training progress, the parser of
//! input encodings, and the error of a run ended by Ctrl-C.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neurarm::output::describe;
use neurarm::table::write_text_atomic;
use neurarm_nn::InputEncoding;
use neurarm_physics::arm::ArmState;
use neurarm_physics::config::ArmConfig;

/// Which arm, and from which state: shared by the commands that simulate or export one.
#[derive(Args)]
pub struct ArmSource {
    /// Arm configuration (TOML); the default 4-link arm if omitted.
    #[arg(long, short = 'c')]
    config: Option<PathBuf>,
    /// Initial joint angles [rad], comma-separated (default: all 0).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    q0: Option<Vec<f64>>,
    /// Initial joint velocities [rad/s], comma-separated (default: all 0).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    qd0: Option<Vec<f64>>,
}

impl ArmSource {
    /// The configuration (`-c`, or the built-in arm) and the initial state (`--q0`, `--qd0`,
    /// all 0 if omitted), checked against the arm's joint count.
    pub fn load(self) -> Result<(ArmConfig, ArmState)> {
        let config = load_config(self.config)?;
        let n = config.arm.dof();
        let initial = ArmState { q: initial_vector("q0", self.q0, n)?, qd: initial_vector("qd0", self.qd0, n)? };
        Ok((config, initial))
    }
}

/// The initial vector `name` of an arm of `n` joints: as given (checked), or all 0.
fn initial_vector(name: &str, given: Option<Vec<f64>>, n: usize) -> Result<Vec<f64>> {
    let v = given.unwrap_or_else(|| vec![0.0; n]);
    if v.len() != n {
        bail!("--{name} has {} values, the arm has {n} joints", v.len());
    }
    if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        bail!("--{name}: value {} ({x}) is not a finite number", i + 1);
    }
    Ok(v)
}

/// The column names of a log; `{i}` stands for the joint number.
#[derive(Args, Clone)]
pub struct LogColumnArgs {
    /// Time column [s].
    #[arg(long, default_value = "time")]
    time_column: String,
    /// Angle columns [rad].
    #[arg(long, default_value = "q_{i}")]
    q_column: String,
    /// Speed columns [rad/s].
    #[arg(long, default_value = "qd_{i}")]
    qd_column: String,
    /// Torque columns [N·m].
    #[arg(long, default_value = "tau_{i}")]
    tau_column: String,
}

impl LogColumnArgs {
    /// The column names as the identification reads them.
    pub fn columns(&self) -> neurarm::identify::LogColumns {
        neurarm::identify::LogColumns {
            time: self.time_column.clone(),
            q: self.q_column.clone(),
            qd: self.qd_column.clone(),
            tau: self.tau_column.clone(),
        }
    }
}

/// The arm configuration in `path`, or the built-in arm.
pub fn load_config(path: Option<PathBuf>) -> Result<ArmConfig> {
    Ok(match path {
        Some(path) => ArmConfig::from_toml_file(&path)?,
        None => ArmConfig::default(),
    })
}

/// Writes `config` as TOML to `output` (`-`: standard output) as every `-o` is written, and says
/// where unless it went to standard output.
pub fn write_config(output: &Path, config: &ArmConfig) -> Result<()> {
    write_text_atomic(output, &config.to_toml_string()).with_context(|| format!("writing {}", describe(output)))?;
    if !neurarm::output::is_stdout(output) {
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}

/// The model identifier: as given, or the output file's name.
pub fn identifier_for(name: Option<String>, output: &std::path::Path, fallback: &str) -> String {
    name.unwrap_or_else(|| output.file_stem().and_then(|s| s.to_str()).unwrap_or(fallback).to_owned())
}

/// Training progress on a terminal (restart, epoch, errors, μ); nothing otherwise.
pub struct EpochBar {
    bar: ProgressBar,
    epochs: usize,
}

impl EpochBar {
    /// A bar over `epochs × restarts` epochs, or a counter when the length is not known.
    pub fn new(length: Option<(usize, usize)>) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let (bar, epochs) = match (terminal, length) {
            (false, _) => (ProgressBar::hidden(), 0),
            (true, Some((epochs, restarts))) => (ProgressBar::new(epochs.saturating_mul(restarts) as u64), epochs),
            (true, None) => (ProgressBar::new_spinner(), 0),
        };
        let template = if length.is_some() { "{bar:30} restart {prefix} {msg}" } else { "{spinner} training: restart {prefix} {msg}" };
        bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
        Self { bar, epochs }
    }

    /// Shows one epoch (errors in scaled units, as the trainer sees them).
    pub fn show(&self, e: &neurarm_nn::EpochInfo<'_>) {
        self.bar.set_prefix((e.restart + 1).to_string());
        if self.epochs > 0 {
            self.bar.set_position((e.restart * self.epochs + e.epoch) as u64);
        } else {
            self.bar.tick();
        }
        self.bar.set_message(format!("epoch {} MSE {:.3e} val {:.3e} mu {:.0e} (scaled)", e.epoch, e.train_mse, e.validation_mse, e.mu));
    }

    /// A line above the bar.
    pub fn println(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Parses a net's input encoding for clap.
pub fn parse_encoding(text: &str) -> Result<InputEncoding> {
    Ok(InputEncoding::parse(text)?)
}

/// Parses a gravity net's input encoding (one of angles) for clap.
pub fn parse_angle_encoding(text: &str) -> Result<InputEncoding> {
    let encoding = parse_encoding(text)?;
    if encoding.is_of_angles() {
        Ok(encoding)
    } else {
        let names: Vec<&str> = InputEncoding::ANGLES.iter().map(|e| e.name()).collect();
        bail!("'{text}' encodes speeds, not angles: use one of {}", names.join(", "))
    }
}

/// A run ended by Ctrl-C: its message, and exit status 130 (128 + SIGINT) as a shell gives.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// Which platforms' binaries the FMUs carry: shared by the commands that write FMUs.
#[derive(Args, Clone, Default)]
pub struct PlatformArgs {
    /// Platforms every FMU carries, comma-separated FMI folder names (linux64, win64,
    /// darwin64, aarch64-linux); an error names any not built. Default: the host's and every
    /// platform built by scripts/build-platforms.
    #[arg(long, value_delimiter = ',', global = true)]
    platforms: Option<Vec<String>>,
}

impl PlatformArgs {
    /// The platforms asked for (`None`: every one built), checked before any work starts: an
    /// unknown name or a platform not built is an error here, not after a long run.
    pub fn checked(self) -> Result<Option<Vec<String>>> {
        neurarm::export::fmu_binaries(self.platforms.as_deref()).context("--platforms")?;
        Ok(self.platforms)
    }
}
