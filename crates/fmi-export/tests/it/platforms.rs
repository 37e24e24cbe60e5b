//! Packing several platforms' binaries: each file is checked against its platform folder
//! (format and architecture), the binaries to pack are chosen from a folder of cross builds
//! (each one asked for and missing is named), and a bad binary leaves no FMU behind.

use std::path::Path;

use neurarm_fmi_export::fmi2::write_fmu;
use neurarm_fmi_export::package::{check_binary, library_file_name, select_binaries, PLATFORM};
use neurarm_fmi_export::{ModelDescription, TableBuilder};

/// This test program: an x86_64 (or whatever this machine is) ELF on Linux.
fn this_program() -> Vec<u8> {
    std::fs::read(std::env::current_exe().unwrap()).unwrap()
}

#[test]
fn cargo_names_each_platforms_library() {
    assert_eq!(library_file_name("linux64", "m").as_deref(), Some("libm.so"));
    assert_eq!(library_file_name("aarch64-linux", "m").as_deref(), Some("libm.so"));
    assert_eq!(library_file_name("win64", "m").as_deref(), Some("m.dll"));
    assert_eq!(library_file_name("darwin64", "m").as_deref(), Some("libm.dylib"));
    assert_eq!(library_file_name("beos", "m"), None);
}

#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
#[test]
fn a_binary_is_accepted_only_in_the_folder_of_its_format_and_architecture() {
    let elf = this_program();
    check_binary("linux64", &elf).unwrap();
    for wrong in ["win64", "darwin64", "aarch64-linux", "linux32"] {
        let e = check_binary(wrong, &elf).unwrap_err().to_string();
        assert!(e.contains("Elf X86_64") && e.contains(wrong), "{wrong}: {e}");
    }
    let e = check_binary("linux64", b"#!/bin/sh\necho not a library\n").unwrap_err().to_string();
    assert!(e.contains("not a shared library"), "{e}");
    assert!(check_binary("solaris64", &elf).unwrap_err().to_string().contains("unknown platform folder"));
}

/// A folder of fake cross builds (only their names and times matter to the choice).
fn cross_folder(platforms: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let host = d.path().join("libm.so");
    std::fs::write(&host, b"host").unwrap();
    for p in platforms {
        let dir = d.path().join("cross").join(p);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join(library_file_name(p, "m").unwrap());
        std::fs::write(&file, p.as_bytes()).unwrap();
    }
    (d, host)
}

#[test]
fn every_cross_build_found_is_chosen_and_each_one_asked_for_must_exist() {
    let (d, host) = cross_folder(&["win64", "darwin64"]);
    let cross = d.path().join("cross");
    let all = select_binaries(Some(host.clone()), Some(&cross), "m", None).unwrap();
    let names: Vec<&str> = all.iter().map(|(p, _)| p.as_str()).collect();
    assert_eq!(names, [PLATFORM.0, "win64", "darwin64"]);
    assert!(all[1].1.ends_with("win64/m.dll"));

    let only = select_binaries(Some(host.clone()), Some(&cross), "m", Some(&["win64".to_owned()])).unwrap();
    assert_eq!(only.len(), 1);
    assert_eq!(only[0].0, "win64");

    let asked = ["linux64", "win64", "aarch64-linux", "darwin32"].map(String::from);
    let e = select_binaries(Some(host.clone()), Some(&cross), "m", Some(&asked)).unwrap_err().to_string();
    assert!(e.contains("aarch64-linux, darwin32") && e.contains("looked in"), "{e}");
    let e = select_binaries(Some(host.clone()), None, "m", Some(&["win64".to_owned()])).unwrap_err().to_string();
    assert!(e.contains("win64") && e.contains("no folder of cross builds"), "{e}");
    let e = select_binaries(Some(host), Some(&cross), "m", Some(&["amiga".to_owned()])).unwrap_err().to_string();
    assert!(e.contains("unknown platform \"amiga\""), "{e}");
    // No cross folder at all: the host's library alone.
    let (d2, host2) = cross_folder(&[]);
    assert_eq!(select_binaries(Some(host2), Some(&d2.path().join("none")), "m", None).unwrap().len(), 1);
}

#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
#[test]
fn a_binary_in_the_wrong_folder_fails_the_fmu_and_leaves_nothing() {
    let mut b = TableBuilder::new();
    let u = b.input("u", None, 0.0, "input");
    b.output("y", None, "output", &[u]);
    let description = ModelDescription::new("M", "test", b.finish()).unwrap();
    let d = tempfile::tempdir().unwrap();
    let program = std::env::current_exe().unwrap();
    let out = d.path().join("M.fmu");
    let e = write_fmu(&out, &description, &[("linux64", &program), ("win64", &program)], &[], "").unwrap_err();
    assert!(e.to_string().contains("not one for win64"), "{e}");
    assert!(!out.exists());
    let e = write_fmu(&out, &description, &[("linux64", &program), ("linux64", &program)], &[], "").unwrap_err();
    assert!(e.to_string().contains("twice"), "{e}");
    assert!(std::fs::read_dir(d.path()).unwrap().next().is_none(), "a temporary file was left");
    write_fmu(&out, &description, &[("linux64", Path::new(&program))], &[], "").unwrap();
    let zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    assert!(zip.file_names().any(|n| n == "binaries/linux64/M.so"));
}
