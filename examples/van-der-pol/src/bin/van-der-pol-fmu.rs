//! Writes `VanDerPol.fmu` from the built library: `van-der-pol-fmu [OUT.fmu]` (default
//! `VanDerPol.fmu`).

use std::process::ExitCode;

fn main() -> ExitCode {
    let out = std::env::args_os().nth(1).unwrap_or_else(|| "VanDerPol.fmu".into());
    let written = van_der_pol::package::built_binaries().and_then(|libs| van_der_pol::package::write_fmu(&libs, out.as_ref()));
    match written {
        Ok(()) => {
            eprintln!("wrote {}", out.to_string_lossy());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
