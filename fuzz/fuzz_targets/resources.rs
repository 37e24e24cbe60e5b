//! (d) The resources an FMU reads at instantiation: the input is `resources/neurarm.toml`,
//! optionally followed by a NUL and the text of a file `fuzz.json` beside it (a spec may name
//! it as a weights file; the fixtures' nets `friction_1.json` … `gravity.json` are there
//! too). The same spec is built in process; the FMU must instantiate exactly when that
//! succeeds, with the same GUID, and otherwise return NULL with a logged reason. An FMU that
//! instantiates is initialized and stepped, its outputs read.

#![no_main]

use std::ffi::CString;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use neurarm_fuzz::*;
use neurarm_models::FmuSpec;

fn resources() -> &'static (tempfile::TempDir, std::path::PathBuf, CString) {
    static DIR: OnceLock<(tempfile::TempDir, std::path::PathBuf, CString)> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let resources = dir.path().join("resources");
        let nets: Vec<(String, String)> = compensator_nets().into_iter().map(|(n, f)| (n, f.to_json())).collect();
        write_resources(&resources, "", &nets);
        let uri = CString::new(format!("file://{}", resources.display())).expect("no NUL");
        (dir, resources, uri)
    })
}

fuzz_target!(|data: &[u8]| {
    let (_, dir, uri) = resources();
    let (spec_bytes, extra) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    std::fs::write(dir.join(neurarm_models::SPEC_FILE), spec_bytes).expect("write the spec");
    std::fs::write(dir.join("fuzz.json"), extra).expect("write the extra file");
    clear_log();
    // The model as the factory makes it, built in process.
    let built = std::str::from_utf8(spec_bytes)
        .ok()
        .and_then(|text| FmuSpec::from_toml(text).ok())
        .and_then(|spec| spec.build_from(Some(dir)).ok());
    let guid = built.as_ref().map_or_else(|| "{none}".to_owned(), |m| m.description().guid());
    let guid = CString::new(guid).expect("no NUL in a GUID");
    let c = unsafe { fmi2Instantiate(c"fuzz".as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), callbacks(), 0, 0) };
    if c.is_null() {
        assert!(built.is_none(), "the model builds in process but fmi2Instantiate refused it: {:?}", log_since(0));
        assert!(log_since(0).iter().any(|(s, m)| *s == ERROR && !m.is_empty()), "NULL without a logged reason");
        return;
    }
    let description = built.expect("fmi2Instantiate accepted a spec that does not build in process").description().clone();
    let reals: Vec<u32> = description
        .variables
        .iter()
        .filter(|v| v.base_type() == neurarm_fmi_export::description::BaseType::Real)
        .map(|v| v.value_reference)
        .collect();
    unsafe {
        let from = log_len();
        let s = fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
        check_status("fmi2SetupExperiment", s, from);
        let s = fmi2EnterInitializationMode(c);
        check_status("fmi2EnterInitializationMode", s, from);
        get_reals_checked(c, &reals);
        let from = log_len();
        let s = fmi2ExitInitializationMode(c);
        check_status("fmi2ExitInitializationMode", s, from);
        if s == OK {
            for k in 0..3 {
                let from = log_len();
                let s = fmi2DoStep(c, k as f64 * 1e-3, 1e-3, 1);
                check_status("fmi2DoStep", s, from);
                get_reals_checked(c, &reals);
                if s != OK {
                    break;
                }
            }
        }
        fmi2FreeInstance(c);
    }
});
