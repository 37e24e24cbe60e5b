//! Packing an FMI 2.0 `.fmu`: `modelDescription.xml`, the binaries in FMI 2.0's platform
//! folders (`linux64`, `win64`, `darwin64`, and FMI 3.0's `aarch64-linux`), resources and
//! documentation.

use std::path::Path;

use crate::package::{documentation_html, read_binaries, write_archive};
use crate::ModelDescription;

/// Writes `path` as a `.fmu` with each `(platform, binary)` of `binaries` as
/// `binaries/<platform>/<identifier>.<ext>` (each checked with [`check_binary`](crate::package::check_binary)) and
/// `resources` as `(name, content)` pairs under `resources/`; `equations_html` goes into the
/// documentation beside the table of variables. Nothing is left at `path` on failure.
pub fn write_fmu(
    path: &Path,
    description: &ModelDescription,
    binaries: &[(&str, &Path)],
    resources: &[(&str, Vec<u8>)],
    equations_html: &str,
) -> std::io::Result<()> {
    let libraries = read_binaries(binaries)?
        .into_iter()
        .map(|(platform, extension, bytes)| (format!("binaries/{platform}/{}.{extension}", description.model_identifier), bytes))
        .collect::<Vec<_>>();
    write_archive(path, &description.to_xml(), &libraries, resources, &documentation_html(description, equations_html))
}
