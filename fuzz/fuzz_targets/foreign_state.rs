//! (h) FMU states across instances and models. Two instances, of the model kinds the first two
//! bytes pick (the same kind or two), each brought to a phase the third byte picks; the owner
//! saves states, and the input then hands the other one its handles, made-up handles, and its
//! serialized bytes (edited or not), in an order the rest of the input gives. A handle of
//! another instance, a freed one or a made-up one must be refused with a log entry and nothing
//! changed; bytes of another model must be refused; bytes of the same model are accepted. After
//! each input both instances still step. Both are freed with states left unfreed, so
//! LeakSanitizer sees any state that outlives its instance.

#![no_main]

use neurarm_fmi_export::fmi2::abi::{Component, FmuState};
use libfuzzer_sys::arbitrary::{self, Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use neurarm_fuzz::*;

/// What the host does next.
#[derive(Arbitrary, Debug)]
enum Move {
    /// The owner saves a state (into a new handle, or over one it holds).
    Save { reuse: Option<u8> },
    /// The owner frees one of its handles.
    Free { which: u8 },
    /// The other instance is given one of the owner's handles: set, serialize, free or reuse.
    Foreign { which: u8, how: u8 },
    /// The other instance is given a number that was never a handle (or an address).
    MadeUp { bits: u64, how: u8 },
    /// The other instance reads the owner's serialized state, edited at `at` if given.
    Bytes { which: u8, edit: Option<(u16, u8)> },
}

/// Brings a fresh instance of `fixture` to phase `phase`: instantiated, initialized, or
/// stepped a few times.
fn started(fixture: &Fixture, phase: u8) -> Component {
    let c = instantiate(fixture);
    assert!(!c.is_null(), "{}: {:?}", fixture.name, log_since(0));
    unsafe {
        if phase % 3 >= 1 {
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(c), OK);
            assert_eq!(fmi2ExitInitializationMode(c), OK, "{}: {:?}", fixture.name, log_since(0));
        }
        if phase % 3 == 2 {
            for k in 0..3 {
                assert_eq!(fmi2DoStep(c, k as f64 * 1e-3, 1e-3, 1), OK, "{}: {:?}", fixture.name, log_since(0));
            }
        }
    }
    c
}

/// Calls `call` and checks that it was refused with a logged reason.
fn refused(what: &str, call: impl FnOnce() -> i32) {
    let from = log_len();
    let status = call();
    check_status(what, status, from);
    assert_eq!(status, ERROR, "{what} accepted a foreign handle: {:?}", log_since(from));
}

fuzz_target!(|data: &[u8]| {
    let [a, b, phase, rest @ ..] = data else { return };
    clear_log();
    let fixtures = fixtures();
    let (fa, fb) = (&fixtures[*a as usize % fixtures.len()], &fixtures[*b as usize % fixtures.len()]);
    let owner = started(fa, *phase);
    let other = started(fb, *phase / 3);
    let same_model = fa.guid == fb.guid;
    let mut held: Vec<FmuState> = Vec::new();
    let mut freed: Vec<FmuState> = Vec::new();
    let mut u = Unstructured::new(rest);
    let Ok(moves) = Vec::<Move>::arbitrary(&mut u) else { return };
    unsafe {
        for m in moves.into_iter().take(32) {
            let pick = |list: &[FmuState], i: u8| (!list.is_empty()).then(|| list[i as usize % list.len()]);
            match m {
                Move::Save { reuse } => {
                    let mut state = reuse.and_then(|i| pick(&held, i)).unwrap_or(std::ptr::null_mut());
                    let was = state;
                    let from = log_len();
                    let status = fmi2GetFMUstate(owner, &mut state);
                    check_status("fmi2GetFMUstate", status, from);
                    if status == OK {
                        assert!(!state.is_null());
                        if was.is_null() {
                            held.push(state);
                        } else {
                            assert_eq!(state, was, "a reused handle stays");
                        }
                    }
                }
                Move::Free { which } => {
                    if let Some(mut state) = pick(&held, which) {
                        let handle = state;
                        assert_eq!(fmi2FreeFMUstate(owner, &mut state), OK);
                        assert!(state.is_null());
                        held.retain(|&s| s != handle);
                        freed.push(handle);
                        // A freed handle is unknown to its own instance too.
                        refused("fmi2SetFMUstate of a freed state", || fmi2SetFMUstate(owner, handle));
                    }
                }
                Move::Foreign { which, how } => {
                    let Some(handle) = pick(&held, which).or_else(|| pick(&freed, which)) else { continue };
                    foreign_call(other, handle, how);
                }
                Move::MadeUp { bits, how } => {
                    let handle = bits as usize as FmuState;
                    if handle.is_null() || held.contains(&handle) || freed.contains(&handle) {
                        continue;
                    }
                    foreign_call(other, handle, how);
                    foreign_call(owner, handle, how);
                }
                Move::Bytes { which, edit } => {
                    let Some(handle) = pick(&held, which) else { continue };
                    let Some(mut bytes) = serialized(owner, handle) else { continue };
                    if let Some((at, xor)) = edit {
                        let at = at as usize % bytes.len();
                        bytes[at] ^= xor.max(1);
                    }
                    let mut state = std::ptr::null_mut();
                    let from = log_len();
                    let status = fmi2DeSerializeFMUstate(other, bytes.as_ptr(), bytes.len(), &mut state);
                    check_status("fmi2DeSerializeFMUstate", status, from);
                    if edit.is_some() || !same_model {
                        assert_eq!(status, ERROR, "bytes of another model or edited: {:?}", log_since(from));
                    } else {
                        assert_eq!(status, OK, "a state of the same model: {:?}", log_since(from));
                    }
                    if status == OK {
                        let from = log_len();
                        let s = fmi2SetFMUstate(other, state);
                        check_status("fmi2SetFMUstate", s, from);
                        assert_eq!(fmi2FreeFMUstate(other, &mut state), OK);
                    }
                }
            }
        }
        // Both instances still work: each restores its own latest state, or resets.
        for (c, fixture, state) in [(owner, fa, held.last().copied()), (other, fb, None)] {
            let from = log_len();
            let restored = state.map(|s| fmi2SetFMUstate(c, s));
            if let Some(s) = restored {
                check_status("fmi2SetFMUstate", s, from);
            }
            get_reals_checked(c, &fixture.vrs[0]);
        }
        // States left unfreed go with their instance.
        fmi2FreeInstance(owner);
        fmi2FreeInstance(other);
    }
});

/// The other instance is handed `handle`: set, serialize, free or save over it, by `how`.
unsafe fn foreign_call(c: Component, handle: FmuState, how: u8) {
    unsafe {
        match how % 4 {
            0 => refused("fmi2SetFMUstate of a foreign handle", || fmi2SetFMUstate(c, handle)),
            1 => {
                let mut size = 0;
                refused("fmi2SerializedFMUstateSize of a foreign handle", || fmi2SerializedFMUstateSize(c, handle, &mut size));
            }
            2 => {
                let mut state = handle;
                refused("fmi2FreeFMUstate of a foreign handle", || fmi2FreeFMUstate(c, &mut state));
                assert_eq!(state, handle, "a refused free leaves the handle");
            }
            _ => {
                let mut state = handle;
                refused("fmi2GetFMUstate over a foreign handle", || fmi2GetFMUstate(c, &mut state));
            }
        }
    }
}

/// The serialized bytes of the owner's state `handle`.
unsafe fn serialized(c: Component, handle: FmuState) -> Option<Vec<u8>> {
    unsafe {
        let mut size = 0;
        if fmi2SerializedFMUstateSize(c, handle, &mut size) != OK {
            return None;
        }
        let mut bytes = vec![0u8; size];
        (fmi2SerializeFMUstate(c, handle, bytes.as_mut_ptr(), size) == OK).then_some(bytes)
    }
}
