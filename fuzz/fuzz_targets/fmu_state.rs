//! (b) Bytes given to `fmi2DeSerializeFMUstate` of every model kind. The first byte picks the
//! model, the second how: bit 0 recomputes the checksum (so edits get past it to the
//! decoder's other checks), bit 1 initializes the instance first. A state the FMU accepts is
//! then restored, read and stepped: it must behave like any state the FMU saved itself (no
//! NaN read back with fmi2OK, every refusal logged). One instance per model serves every
//! input, reset first (instantiation costs more than the rest of an input).

#![no_main]

use std::sync::OnceLock;

use neurarm_fmi_export::fmi2::abi::Component;
use libfuzzer_sys::fuzz_target;
use neurarm_fuzz::*;

/// One instance per fixture, made on first use and kept for the process (held in a static, so
/// LeakSanitizer sees them reachable to the end).
fn instance(model: usize) -> Component {
    static INSTANCES: OnceLock<Vec<usize>> = OnceLock::new();
    INSTANCES.get_or_init(|| fixtures().iter().map(|f| instantiate(f) as usize).collect())[model] as Component
}

fuzz_target!(|data: &[u8]| {
    let [model, how, bytes @ ..] = data else { return };
    clear_log();
    let fixtures = fixtures();
    let fixture = &fixtures[*model as usize % fixtures.len()];
    let c = instance(*model as usize % fixtures.len());
    assert!(!c.is_null(), "{:?}", log_since(0));
    assert_eq!(unsafe { fmi2Reset(c) }, OK, "{:?}", log_since(0));
    let mut bytes = bytes.to_vec();
    if how & 1 != 0 {
        fix_checksum(&mut bytes);
    }
    unsafe {
        if how & 2 != 0 {
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(c), OK);
            assert_eq!(fmi2ExitInitializationMode(c), OK);
        }
        let mut state = std::ptr::null_mut();
        let from = log_len();
        let status = fmi2DeSerializeFMUstate(c, bytes.as_ptr(), bytes.len(), &mut state);
        check_status("fmi2DeSerializeFMUstate", status, from);
        assert_eq!(status == OK, !state.is_null(), "a state exactly when accepted");
        if status == OK {
            let from = log_len();
            let status = fmi2SetFMUstate(c, state);
            check_status("fmi2SetFMUstate", status, from);
            get_reals_checked(c, &fixture.vrs[0]);
            let mut t = 0.0;
            let from = log_len();
            let s = fmi2GetRealStatus(c, 2, &mut t);
            check_status("fmi2GetRealStatus", s, from);
            if s == OK {
                assert!(t.is_finite(), "restored time {t}");
                for _ in 0..3 {
                    let from = log_len();
                    let s = fmi2DoStep(c, t, 1e-3, 1);
                    check_status("fmi2DoStep", s, from);
                    if s != OK {
                        break;
                    }
                    t += 1e-3;
                    get_reals_checked(c, &fixture.vrs[0]);
                }
            }
            // The restored state serialises again and reads back.
            if let Some(again) = serialized_state(c) {
                let mut other = std::ptr::null_mut();
                let from = log_len();
                let s = fmi2DeSerializeFMUstate(c, again.as_ptr(), again.len(), &mut other);
                check_status("fmi2DeSerializeFMUstate", s, from);
                assert_eq!(s, OK, "a state the FMU saved is refused: {:?}", log_since(from));
                assert_eq!(fmi2FreeFMUstate(c, &mut other), OK);
            }
            assert_eq!(fmi2FreeFMUstate(c, &mut state), OK);
        }
    }
});
