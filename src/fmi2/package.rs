//! Packaging an FMU: `modelDescription.xml`, `binaries/linux64/<id>.so`, `resources/` and
//! `documentation/index.html` in a zip, written atomically.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::description::{Causality, Kind, ModelDescription};
use crate::table::readable_file;

/// File name of the FMU binary that `cargo build --release` makes.
pub const BINARY_NAME: &str = "libneurarm_fmu.so";

/// Finds the FMU binary: `$NEURARM_FMU_BINARY` if set, else beside the running program (or
/// one folder up, for test binaries in `target/*/deps`).
pub fn find_binary() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("NEURARM_FMU_BINARY") {
        let p = PathBuf::from(p);
        return if p.is_file() { Ok(p) } else { Err(format!("NEURARM_FMU_BINARY={} is not a file", p.display())) };
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate the running program: {e}"))?;
    let dir = exe.parent().ok_or("the running program has no folder")?;
    for candidate in [dir.join(BINARY_NAME), dir.join("..").join(BINARY_NAME)] {
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    Err(format!(
        "the FMU binary {BINARY_NAME} is not beside {}; build it with `cargo build --release -p neurarm-fmu` \
         (scripts/run does), or point NEURARM_FMU_BINARY at it",
        exe.display()
    ))
}

/// Writes `path` as a `.fmu` with `binary` as `binaries/linux64/<identifier>.so` and
/// `resources` as `(name, content)` pairs under `resources/`; `equations_html` goes into the
/// documentation beside the table of variables. Nothing is left at `path` on failure.
pub fn write_fmu(
    path: &Path,
    description: &ModelDescription,
    binary: &Path,
    resources: &[(&str, Vec<u8>)],
    equations_html: &str,
) -> std::io::Result<()> {
    let binary_bytes = std::fs::read(binary).map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", binary.display())))?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let tmp = tempfile::Builder::new().permissions(readable_file()).prefix(".neurarm-").suffix(".fmu.tmp").tempfile_in(dir)?;
    let mut zip = zip::ZipWriter::new(tmp.reopen()?);
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let exe_options = options.unix_permissions(0o755);
    let mut add = |name: String, bytes: &[u8], opts: zip::write::SimpleFileOptions| -> std::io::Result<()> {
        zip.start_file(name, opts).map_err(std::io::Error::other)?;
        zip.write_all(bytes)
    };
    add("modelDescription.xml".into(), description.to_xml().as_bytes(), options)?;
    add(format!("binaries/linux64/{}.so", description.model_identifier), &binary_bytes, exe_options)?;
    for (name, bytes) in resources {
        add(format!("resources/{name}"), bytes, options)?;
    }
    add("documentation/index.html".into(), documentation_html(description, equations_html).as_bytes(), options)?;
    zip.finish().map_err(std::io::Error::other)?.sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// `documentation/index.html`: the model's equations and a table of its variables.
pub fn documentation_html(d: &ModelDescription, equations_html: &str) -> String {
    let mut rows = String::new();
    for v in &d.variables {
        let (unit, start) = match &v.kind {
            Kind::Real { unit, start } => (unit.to_string(), start.map(|s| s.to_string()).unwrap_or_default()),
            Kind::Integer { start } => (String::new(), start.map(|s| s.to_string()).unwrap_or_default()),
            Kind::Boolean { start } => (String::new(), start.map(|s| s.to_string()).unwrap_or_default()),
            Kind::String { start } => (String::new(), start.clone().unwrap_or_default()),
        };
        let causality = match v.causality {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        };
        rows += &format!(
            "<tr><td><code>{}</code></td><td>{causality}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&v.name),
            escape(&unit),
            escape(&start),
            escape(&v.description)
        );
    }
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{name}</title>\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}td,th{{padding:2px 8px;text-align:left}}</style>\
         </head><body>\n<h1>{name}</h1>\n<p>{desc}</p>\n<h2>Equations</h2>\n{equations_html}\n\
         <h2>Variables</h2>\n<table>\n<tr><th>name</th><th>causality</th><th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n\
         <p>Generated by neurarm {version}. FMI 2.0 Co-Simulation; GUID <code>{guid}</code>.</p>\n</body></html>\n",
        name = escape(&d.model_name),
        desc = escape(&d.description),
        version = env!("CARGO_PKG_VERSION"),
        guid = escape(&d.guid()),
    )
}
