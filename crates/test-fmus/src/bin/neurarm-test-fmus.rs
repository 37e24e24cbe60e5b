//! Writes every test FMU into a folder: `neurarm-test-fmus DIR`.

use std::path::PathBuf;
use std::process::ExitCode;

use neurarm_test_fmus::{fmu_in, TestModel};

fn main() -> ExitCode {
    let Some(dir) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: neurarm-test-fmus DIR   (writes Counter.fmu, Split.fmu, … into DIR)");
        return ExitCode::FAILURE;
    };
    for model in TestModel::ALL {
        match fmu_in(&dir, model) {
            Ok(path) => println!("{}", path.display()),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    ExitCode::SUCCESS
}
