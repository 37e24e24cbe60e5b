//! `neurarm train`: a two-layer network trained with Levenberg–Marquardt on pairs from a CSV,
//! written as a weights file that records what the net computes.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use nalgebra::DMatrix;
use neurarm::output::describe;
use neurarm::table::{write_text_atomic, NumericTable};
use neurarm_nn::lm::Damping;
use neurarm_nn::{train, InputEncoding, NetKind, Signal, TrainSettings, WeightsFile};

use super::common::{parse_encoding, EpochBar};

/// The arguments of `neurarm train`. Its help text is the doc of `Command::Train` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct TrainArgs {
    /// Training pairs (CSV with a header).
    #[arg(long, short = 'd')]
    data: PathBuf,
    /// Input columns, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    inputs: Vec<String>,
    /// Target columns, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    targets: Vec<String>,
    /// Hidden neurons.
    #[arg(long, default_value_t = 10)]
    hidden: usize,
    /// Trainings from different initial weights; the best on validation is kept.
    #[arg(long, default_value_t = 1)]
    restarts: usize,
    /// Seed of the split and the initial weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Largest number of epochs.
    #[arg(long, default_value_t = 1000)]
    epochs: usize,
    /// Validation failures in a row that stop training.
    #[arg(long, default_value_t = 6)]
    max_fail: usize,
    /// Train/validation/test fractions summing to 1: `0.7,0.15,0.15` or `0.7 0.15 0.15`.
    /// Each part used needs a few samples (training 10, validation and test 3 each:
    /// 17 samples at the default split).
    #[arg(long, value_delimiter = ',', num_args = 1..=3, default_values_t = [0.70, 0.15, 0.15])]
    split: Vec<f64>,
    /// What the net computes, recorded in the weights file so that `export compensator`
    /// can check it: friction (one joint's torque from its velocity), gravity (all joints'
    /// torques from all angles) or unspecified. Inferred when omitted: one input `qd_J` →
    /// friction of joint J; inputs `q_1…q_n` and n targets → gravity; else unspecified.
    #[arg(long, value_parser = parse_kind)]
    kind: Option<NetKind>,
    /// The joint (1-based) of a friction net; inferred from an input named `qd_J`.
    #[arg(long)]
    joint: Option<usize>,
    /// How the net sees the inputs: raw, joint-angles ((cos, sin) of each input angle
    /// [rad]), link-angles ((cos, sin) of the running sums q₁+…+qⱼ), the angle forms
    /// 2π-periodic in every input, or log-speed (each speed v [rad/s] as
    /// sign(v) ln(1 + |v| / 1 mrad/s): a friction net that must follow the Coulomb step).
    #[arg(long, value_parser = parse_encoding, default_value = "raw")]
    encoding: InputEncoding,
    /// How μ changes: trainlm (MATLAB's ×0.1 / ×10, the default) or nielsen (Nielsen's
    /// gain-ratio rule, which needs fewer epochs on the gravity benches).
    #[arg(long, value_parser = parse_damping, default_value = "trainlm")]
    damping: Damping,
    /// Output weights file (JSON; `-`: standard output).
    #[arg(long, short = 'o')]
    output: PathBuf,
}

/// Runs `neurarm train`.
pub fn run(args: TrainArgs) -> Result<()> {
    let TrainArgs { data, inputs, targets, hidden, restarts, seed, epochs, max_fail, split, kind, joint, encoding, damping, output } = args;
    let [a, b, c] = split[..] else {
        bail!("--split takes three fractions (train, validation, test), e.g. 0.7,0.15,0.15; got {}", split.len())
    };
    let settings = TrainSettings { hidden, restarts, seed, epochs, max_fail, split: [a, b, c], damping, ..Default::default() };
    let (kind, joint) = net_kind(kind, joint, &inputs, &targets)?;
    let weights = train_from_csv(&data, &inputs, &targets, encoding, settings)?;
    let weights = match kind {
        NetKind::Friction => weights.friction_of_joint(joint.expect("a friction net has a joint")),
        NetKind::Gravity => weights.gravity(),
        NetKind::Unspecified => weights,
    };
    weights.network().map_err(|e| anyhow::anyhow!("--kind {}: {e}", kind.name()))?;
    write_text_atomic(&output, &weights.to_json()).with_context(|| format!("writing {}", describe(&output)))?;
    let r = &weights.report;
    let rms = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3e}", v.sqrt()));
    let unit = weights.outputs[0].unit.as_str();
    eprintln!(
        "wrote {} ({}): {} epochs (best {}), stopped by {}; RMS error train {}, validation {}, test {} [{}] on {}/{}/{} samples",
        describe(&output),
        weights.describe(),
        r.epochs,
        r.best_epoch,
        stop_reason_text(r.stop_reason),
        rms(Some(r.train_mse)),
        rms(r.validation_mse),
        rms(r.test_mse),
        if unit.is_empty() { "target units" } else { unit },
        r.counts[0],
        r.counts[1],
        r.counts[2]
    );
    Ok(())
}

/// Reads the pairs, checks them, trains with progress on a terminal, and wraps the result.
fn train_from_csv(
    data: &std::path::Path,
    inputs: &[String],
    targets: &[String],
    encoding: InputEncoding,
    settings: TrainSettings,
) -> Result<WeightsFile> {
    let required: Vec<&str> = inputs.iter().chain(targets).map(String::as_str).collect();
    if let Some(name) = required.iter().enumerate().find_map(|(i, n)| required[..i].contains(n).then_some(n)) {
        bail!("column '{name}' is named twice in --inputs/--targets");
    }
    let table = NumericTable::read(data, &required)?;
    for name in inputs {
        let column = table.column(name).expect("required");
        if column.iter().all(|&v| v == column[0]) {
            bail!(
                "{}: input column '{name}' is constant ({} in all {} rows): it carries nothing to learn from",
                data.display(),
                column[0],
                table.rows()
            );
        }
    }
    let matrix = |names: &[String]| {
        let cols: Vec<&[f64]> = names.iter().map(|n| table.column(n).expect("required")).collect();
        DMatrix::from_fn(names.len(), table.rows(), |r, c| cols[r][c])
    };
    let raw = matrix(inputs);
    neurarm_nn::lm::check_settings(&settings, encoding.features(inputs.len()), targets.len(), table.rows())
        .with_context(|| data.display().to_string())?;
    if let Some(warning) = neurarm_nn::lm::time_series_warning(&raw) {
        eprintln!("warning: {}: {warning}", data.display());
    }
    let weights = neurarm_nn::lm::weight_count(encoding.features(inputs.len()), settings.hidden, targets.len()).unwrap_or(0);
    let training_values = neurarm_nn::lm::split(table.rows(), settings.split, settings.seed)[0].len() * targets.len();
    if weights > training_values {
        eprintln!(
            "notice: the net has {weights} weights for {training_values} training target values: it can fit noise; validation stopping is what holds it"
        );
    }
    let (x, t) = (encoding.encode_all(&raw), matrix(targets));
    let bar = EpochBar::new(Some((settings.epochs, settings.restarts)));
    let trained = train(&x, &t, &settings, &mut |e| bar.show(e));
    bar.finish();
    let trained = trained?;
    // A unit in the header (`qd_1 [rad/s]`) is the unit; otherwise it is guessed from the name.
    let signals = |names: &[String]| {
        names.iter().map(|n| Signal { name: n.clone(), unit: table.unit(n).map_or_else(|| unit_of(n), str::to_owned) }).collect()
    };
    Ok(WeightsFile::new(&trained.net, signals(inputs), signals(targets), settings, trained.report).with_encoding(encoding))
}

/// A unit guessed from a column name by the project's naming: q… rad, qd… rad/s, tau… N.m.
fn unit_of(name: &str) -> String {
    let unit = if name.starts_with("qd") {
        "rad/s"
    } else if name.starts_with('q') {
        "rad"
    } else if name.starts_with("tau") {
        "N.m"
    } else {
        ""
    };
    unit.to_owned()
}

/// Parses a damping rule for clap.
fn parse_damping(text: &str) -> Result<Damping> {
    match text.trim() {
        "trainlm" => Ok(Damping::Trainlm),
        "nielsen" => Ok(Damping::Nielsen),
        other => bail!("unknown damping '{other}': use trainlm or nielsen"),
    }
}

/// Parses a net kind for clap.
fn parse_kind(text: &str) -> Result<NetKind> {
    Ok(NetKind::parse(text)?)
}

/// A stop reason as words.
fn stop_reason_text(reason: neurarm_nn::StopReason) -> &'static str {
    use neurarm_nn::StopReason::*;
    match reason {
        Epochs => "the epoch limit",
        Goal => "the error goal",
        MinGradient => "a vanishing gradient",
        MuMax => "mu reaching its limit",
        ValidationFailures => "validation failures",
    }
}

/// The joint J of a column named `<prefix>J`.
fn joint_of(name: &str, prefix: &str) -> Option<usize> {
    name.strip_prefix(prefix)?.parse().ok().filter(|&j| j >= 1)
}

/// The kind and joint of a net to be trained: as given, or inferred from the column names
/// (documented on `train --kind`).
fn net_kind(kind: Option<NetKind>, joint: Option<usize>, inputs: &[String], targets: &[String]) -> Result<(NetKind, Option<usize>)> {
    let friction_joint = match inputs {
        [only] if targets.len() == 1 => joint_of(only, "qd_"),
        _ => None,
    };
    let is_gravity = inputs.len() == targets.len() && inputs.iter().enumerate().all(|(i, n)| joint_of(n, "q_") == Some(i + 1));
    let kind = kind.unwrap_or(if friction_joint.is_some() || joint.is_some() {
        NetKind::Friction
    } else if is_gravity {
        NetKind::Gravity
    } else {
        NetKind::Unspecified
    });
    match kind {
        NetKind::Friction => {
            if inputs.len() != 1 || targets.len() != 1 {
                bail!(
                    "a friction net has one input (the joint's velocity) and one target (its torque), not {} and {}",
                    inputs.len(),
                    targets.len()
                );
            }
            match (joint, friction_joint) {
                (Some(0), _) => bail!("--joint 0: joints are numbered from 1"),
                (Some(j), Some(named)) if j != named => {
                    bail!("--joint {j} but the input is '{}', the velocity of joint {named}", inputs[0])
                }
                (Some(j), _) | (None, Some(j)) => Ok((kind, Some(j))),
                (None, None) => {
                    bail!("a friction net needs its joint: give --joint J (the input '{}' does not name it as qd_J)", inputs[0])
                }
            }
        }
        _ if joint.is_some() => bail!("--joint is for friction nets; this one is {}", kind.name()),
        NetKind::Gravity if inputs.len() != targets.len() => {
            bail!("a gravity net has one torque target per angle input, not {} inputs and {} targets", inputs.len(), targets.len())
        }
        _ => Ok((kind, None)),
    }
}
