//! The resource location URIs hosts pass to `fmi2Instantiate`, and the folders they name on
//! Unix and on Windows (both checked on any machine: the conversion takes the platform as an
//! argument), including the forms Windows hosts send.

use neurarm_fmi_export::uri::{resource_path, PathStyle};

/// (URI, Unix folder or `Err`, Windows folder or `Err`); `Err` stands for any error. On Unix a
/// drive-letter URI names the folder its path spells (`/C:/x` is a legal Unix path): only the
/// Windows build reads the letter as a drive.
type Folder = Result<&'static str, ()>;

const TABLE: &[(&str, Folder, Folder)] = &[
    // Unix hosts (fmpy, OpenModelica, libcosim on Linux).
    ("file:///home/u/run/resources", Ok("/home/u/run/resources"), Ok(r"\home\u\run\resources")),
    ("file:/home/u/run/resources", Ok("/home/u/run/resources"), Ok(r"\home\u\run\resources")),
    ("file://localhost/home/u/resources", Ok("/home/u/resources"), Ok(r"\home\u\resources")),
    ("FILE://LocalHost/tmp/x", Ok("/tmp/x"), Ok(r"\tmp\x")),
    ("file:///tmp/with%20space/%C3%A9t%C3%A9", Ok("/tmp/with space/été"), Ok(r"\tmp\with space\été")),
    ("file:///tmp/a%23b/resources/", Ok("/tmp/a#b/resources/"), Ok(r"\tmp\a#b\resources\")),
    // Windows hosts: fmpy and Simulink (`file:///C:/…`), Dymola (`file:/C:/…`), old forms.
    (
        "file:///C:/Users/u/AppData/Local/Temp/fmu/resources",
        Ok("/C:/Users/u/AppData/Local/Temp/fmu/resources"),
        Ok(r"C:\Users\u\AppData\Local\Temp\fmu\resources"),
    ),
    ("file:/C:/work/fmu/resources", Ok("/C:/work/fmu/resources"), Ok(r"C:\work\fmu\resources")),
    ("file://localhost/D:/fmu/resources", Ok("/D:/fmu/resources"), Ok(r"D:\fmu\resources")),
    ("file:///c|/fmu/resources", Ok("/c|/fmu/resources"), Ok(r"c:\fmu\resources")),
    ("file:///C%3A/fmu/my%20resources", Ok("/C:/fmu/my resources"), Ok(r"C:\fmu\my resources")),
    ("file:///C:", Ok("/C:"), Ok(r"C:\")),
    ("file:C:/fmu/resources", Err(()), Ok(r"C:\fmu\resources")),
    // Backslashes, raw or percent-encoded, as some Windows tools write them.
    (r"file:///C:\Program Files\fmu\resources", Ok(r"/C:\Program Files\fmu\resources"), Ok(r"C:\Program Files\fmu\resources")),
    ("file:///C:%5Cfmu%5Cresources", Ok(r"/C:\fmu\resources"), Ok(r"C:\fmu\resources")),
    (r"file:\\\C:\fmu\resources", Err(()), Ok(r"C:\fmu\resources")),
    // Shares: a host name is the UNC server; on Unix there is nothing to map it to.
    ("file://server/share/fmu/resources", Err(()), Ok(r"\\server\share\fmu\resources")),
    ("file:////server/share/fmu/resources", Ok("//server/share/fmu/resources"), Ok(r"\\server\share\fmu\resources")),
    (r"file://server\share\fmu", Err(()), Ok(r"\\server\share\fmu")),
    // Not a local file URI at all.
    ("http://example.org/resources", Err(()), Err(())),
    ("/home/u/resources", Err(()), Err(())),
    ("C:/fmu/resources", Err(()), Err(())),
    ("file:relative/resources", Err(()), Err(())),
    ("file:", Err(()), Err(())),
    ("", Err(()), Err(())),
    ("file:///tmp/%FF", Err(()), Err(())),
    ("file:///tmp/a%00b", Err(()), Err(())),
    ("file://///share", Ok("///share"), Err(())),
];

#[test]
fn every_uri_of_the_table_names_its_folder_on_unix_and_on_windows() {
    let mut wrong = Vec::new();
    for &(uri, unix, windows) in TABLE {
        for (style, want) in [(PathStyle::Unix, unix), (PathStyle::Windows, windows)] {
            let got = resource_path(uri, style);
            let ok = match (&got, want) {
                (Ok(path), Ok(want)) => path == want,
                (Err(error), Err(())) => error.to_string().contains(uri),
                _ => false,
            };
            if !ok {
                wrong.push(format!("{uri:?} on {style:?}: {got:?}, want {want:?}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{} of {} conversions wrong:\n{}", wrong.len(), 2 * TABLE.len(), wrong.join("\n"));
}

#[test]
fn the_native_style_is_the_platform_the_code_runs_on() {
    assert_eq!(PathStyle::native() == PathStyle::Windows, cfg!(windows));
}
