//! `neurarm eval`: a trained network applied to the input columns of a CSV; writes the inputs
//! and the net's outputs.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use neurarm::output::describe;
use neurarm::table::{write_atomic, NumericTable};
use neurarm_nn::WeightsFile;

/// The arguments of `neurarm eval`. Its help text is the doc of `Command::Eval` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct EvalArgs {
    /// Weights file (JSON).
    #[arg(long, short = 'n')]
    net: PathBuf,
    /// Input CSV with the net's input columns.
    #[arg(long, short = 'd')]
    data: PathBuf,
    /// Output CSV (`-`: standard output).
    #[arg(long, short = 'o')]
    output: PathBuf,
}

/// Runs `neurarm eval`.
pub fn run(args: EvalArgs) -> Result<()> {
    let EvalArgs { net, data, output } = args;
    let weights = WeightsFile::read(&net)?;
    let mlp = weights.network()?;
    let names: Vec<&str> = weights.inputs.iter().map(|s| s.name.as_str()).collect();
    let table = NumericTable::read(&data, &names)?;
    let columns: Vec<&[f64]> = names.iter().map(|n| table.column(n).expect("required")).collect();
    let mut header: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    header.extend(weights.outputs.iter().map(|s| s.name.clone()));
    let mut rows = Vec::with_capacity(table.rows());
    for r in 0..table.rows() {
        let x: Vec<f64> = columns.iter().map(|c| c[r]).collect();
        let y = mlp.evaluate(&x);
        // Checked before anything is written: an input far outside the net's training
        // range can overflow it, and a table with inf in it is no result.
        if let Some(k) = y.iter().position(|v| !v.is_finite()) {
            bail!(
                "{}, line {}: the net's output '{}' is {} for these inputs (far outside the range it was trained on?); nothing was written",
                data.display(),
                table.line(r),
                weights.outputs[k].name,
                neurarm_physics::arm::show_number(y[k])
            );
        }
        let mut row = x;
        row.extend(y);
        rows.push(row);
    }
    write_atomic(&output, &header, rows.into_iter()).with_context(|| format!("writing {}", describe(&output)))?;
    eprintln!("wrote {} rows to {}", table.rows(), describe(&output));
    Ok(())
}
