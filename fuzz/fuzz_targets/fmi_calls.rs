//! (a) Random sequences of FMI calls with random arguments against every model, through the
//! exported C functions. The input picks a model kind, how to instantiate it (mostly right,
//! sometimes with a bad argument), then up to 64 calls; numbers come from a table of values
//! that break things (0, NaN, ±inf, 1e300, the largest double, denormals), small decimals,
//! powers of ten or raw bits. Besides the checks of `check_status`, the target frees every
//! FMU state and the instance, so LeakSanitizer sees any leak.

#![no_main]

use std::ffi::{c_int, CString};

use libfuzzer_sys::arbitrary::{self, Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use neurarm_fuzz::*;

/// A number for an argument.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Num {
    Special(u8),
    Decimal(i16),
    Power(i8),
    Bits(u64),
}

const SPECIAL: [f64; 14] =
    [0.0, -0.0, 1.0, -1.0, 1e-3, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e300, f64::MAX, f64::MIN_POSITIVE, 5e-324, 1.7e308];

impl Num {
    fn value(self) -> f64 {
        match self {
            Num::Special(i) => SPECIAL[i as usize % SPECIAL.len()],
            Num::Decimal(d) => d as f64 / 100.0,
            Num::Power(p) => 10f64.powi((p % 40) as i32),
            Num::Bits(b) => f64::from_bits(b),
        }
    }
}

/// A value reference: mostly one of the model's variables of the call's type.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Var {
    Known(u16),
    Settable(u16),
    Raw(u32),
}

impl Var {
    fn vr(self, fixture: &Fixture, base: usize) -> u32 {
        let pick = |list: &[u32], i: u16| if list.is_empty() { i as u32 } else { list[i as usize % list.len()] };
        match self {
            Var::Known(i) => pick(&fixture.vrs[base], i),
            Var::Settable(i) if base == 0 => pick(&fixture.settable_reals, i),
            Var::Settable(i) => pick(&fixture.vrs[base], i),
            Var::Raw(v) => v,
        }
    }
}

/// How a serialized state is altered before it is read back.
#[derive(Arbitrary, Debug)]
enum Edit {
    None,
    Flip { at: u16, xor: u8 },
    PutNumber { at: u16, value: Num },
    Truncate { to: u16 },
}

#[derive(Arbitrary, Debug)]
enum Call {
    Setup {
        tolerance: Option<Num>,
        start: Num,
        stop: Option<Num>,
    },
    Enter,
    Exit,
    Terminate,
    Reset,
    DebugLogging {
        on: bool,
        categories: Vec<u8>,
    },
    GetReal(Vec<Var>),
    SetReal(Vec<(Var, Num)>),
    GetInteger(Vec<Var>),
    SetInteger(Vec<(Var, i32)>),
    GetBoolean(Vec<Var>),
    SetBoolean(Vec<(Var, i32)>),
    GetString(Vec<Var>),
    SetString(Vec<(Var, String)>),
    /// From the FMU's own time (when `at` is None) or from `at`, by `h`.
    DoStep {
        at: Option<Num>,
        h: Num,
    },
    GetState(u8),
    SetState(u8),
    FreeState(u8),
    SerializeRoundTrip {
        from: u8,
        to: u8,
        edit: Edit,
        fix_checksum: bool,
    },
    Status {
        which: u8,
        kind: i8,
    },
    Unsupported(u8),
    NullArguments(u8),
}

/// How to call fmi2Instantiate.
#[derive(Arbitrary, Debug)]
enum Instantiation {
    Right,
    Right2,
    Right3,
    EmptyName,
    WrongGuid,
    NoResources,
    RelativeResources,
    ModelExchange,
}

#[derive(Arbitrary, Debug)]
struct Input {
    model: u8,
    instantiation: Instantiation,
    logging: bool,
    calls: Vec<Call>,
}

const SLOTS: usize = 4;
const CATEGORIES: [&std::ffi::CStr; 5] = [c"logStatusError", c"logStatusWarning", c"logCalls", c"logAll", c""];

fn instantiate_as(fixture: &Fixture, how: &Instantiation, logging: bool) -> neurarm_fmi_export::fmi2::abi::Component {
    let (name, guid, uri): (&std::ffi::CStr, &std::ffi::CStr, Option<&std::ffi::CStr>) = match how {
        Instantiation::EmptyName => (c"", &fixture.guid, Some(&fixture.uri)),
        Instantiation::WrongGuid => (c"x", c"{00000000-0000-0000-0000-000000000000}", Some(&fixture.uri)),
        Instantiation::NoResources => (c"x", &fixture.guid, None),
        Instantiation::RelativeResources => (c"x", &fixture.guid, Some(c"resources")),
        _ => (c"x", &fixture.guid, Some(&fixture.uri)),
    };
    let kind = if matches!(how, Instantiation::ModelExchange) { 0 } else { 1 };
    let from = log_len();
    let c = unsafe {
        fmi2Instantiate(name.as_ptr(), kind, guid.as_ptr(), uri.map_or(std::ptr::null(), |u| u.as_ptr()), callbacks(), 0, logging as c_int)
    };
    let right = matches!(how, Instantiation::Right | Instantiation::Right2 | Instantiation::Right3);
    assert_eq!(!c.is_null(), right, "{how:?}: {:?}", log_since(from));
    if c.is_null() {
        assert!(log_since(from).iter().any(|(s, _)| *s == ERROR), "fmi2Instantiate failed without logging why");
    }
    c
}

fn run(input: Input) {
    clear_log();
    let fixtures = fixtures();
    let fixture = &fixtures[input.model as usize % fixtures.len()];
    let c = instantiate_as(fixture, &input.instantiation, input.logging);
    if c.is_null() {
        return;
    }
    let mut slots: [neurarm_fmi_export::fmi2::abi::FmuState; SLOTS] = [std::ptr::null_mut(); SLOTS];
    // Steps of an arm may each take up to its work bound (a fraction of a second, many times
    // that under the sanitizer): a few per input keep every input within the time limit while
    // still reaching the bound.
    let mut steps_left = 8;
    for call in input.calls.iter().take(64) {
        let from = log_len();
        let (name, status): (&str, c_int) = unsafe {
            match call {
                Call::Setup { tolerance, start, stop } => (
                    "fmi2SetupExperiment",
                    fmi2SetupExperiment(
                        c,
                        tolerance.is_some() as c_int,
                        tolerance.map_or(0.0, Num::value),
                        start.value(),
                        stop.is_some() as c_int,
                        stop.map_or(0.0, Num::value),
                    ),
                ),
                Call::Enter => ("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)),
                Call::Exit => ("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)),
                Call::Terminate => ("fmi2Terminate", fmi2Terminate(c)),
                Call::Reset => ("fmi2Reset", fmi2Reset(c)),
                Call::DebugLogging { on, categories } => {
                    let names: Vec<*const std::ffi::c_char> =
                        categories.iter().take(8).map(|&i| CATEGORIES[i as usize % CATEGORIES.len()].as_ptr()).collect();
                    ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, *on as c_int, names.len(), names.as_ptr()))
                }
                Call::GetReal(vars) => {
                    let vrs: Vec<u32> = vars.iter().take(32).map(|v| v.vr(fixture, 0)).collect();
                    ("fmi2GetReal", get_reals_checked(c, &vrs))
                }
                Call::SetReal(pairs) => {
                    let (vrs, values): (Vec<u32>, Vec<f64>) = pairs.iter().take(32).map(|(v, x)| (v.vr(fixture, 0), x.value())).unzip();
                    ("fmi2SetReal", fmi2SetReal(c, vrs.as_ptr(), vrs.len(), values.as_ptr()))
                }
                Call::GetInteger(vars) => {
                    let vrs: Vec<u32> = vars.iter().take(32).map(|v| v.vr(fixture, 1)).collect();
                    let mut out = vec![0; vrs.len()];
                    ("fmi2GetInteger", fmi2GetInteger(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()))
                }
                Call::SetInteger(pairs) => {
                    let (vrs, values): (Vec<u32>, Vec<c_int>) = pairs.iter().take(32).map(|(v, x)| (v.vr(fixture, 1), *x)).unzip();
                    ("fmi2SetInteger", fmi2SetInteger(c, vrs.as_ptr(), vrs.len(), values.as_ptr()))
                }
                Call::GetBoolean(vars) => {
                    let vrs: Vec<u32> = vars.iter().take(32).map(|v| v.vr(fixture, 2)).collect();
                    let mut out = vec![0; vrs.len()];
                    ("fmi2GetBoolean", fmi2GetBoolean(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()))
                }
                Call::SetBoolean(pairs) => {
                    let (vrs, values): (Vec<u32>, Vec<c_int>) = pairs.iter().take(32).map(|(v, x)| (v.vr(fixture, 2), *x)).unzip();
                    ("fmi2SetBoolean", fmi2SetBoolean(c, vrs.as_ptr(), vrs.len(), values.as_ptr()))
                }
                Call::GetString(vars) => {
                    let vrs: Vec<u32> = vars.iter().take(32).map(|v| v.vr(fixture, 3)).collect();
                    let mut out = vec![std::ptr::null(); vrs.len()];
                    let s = fmi2GetString(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr());
                    if s == OK {
                        for p in &out {
                            assert!(!p.is_null());
                            let _ = std::ffi::CStr::from_ptr(*p).to_bytes().len();
                        }
                    }
                    ("fmi2GetString", s)
                }
                Call::SetString(pairs) => {
                    let strings: Vec<CString> =
                        pairs.iter().take(8).map(|(_, s)| CString::new(s.replace('\0', "")).expect("NULs removed")).collect();
                    let vrs: Vec<u32> = pairs.iter().take(8).map(|(v, _)| v.vr(fixture, 3)).collect();
                    let ptrs: Vec<*const std::ffi::c_char> = strings.iter().map(|s| s.as_ptr()).collect();
                    ("fmi2SetString", fmi2SetString(c, vrs.as_ptr(), vrs.len(), ptrs.as_ptr()))
                }
                Call::DoStep { at, h } => {
                    if steps_left == 0 {
                        continue;
                    }
                    steps_left -= 1;
                    let t = match at {
                        Some(t) => t.value(),
                        None => {
                            let mut t = 0.0;
                            let from = log_len();
                            let s = fmi2GetRealStatus(c, 2, &mut t);
                            check_status("fmi2GetRealStatus", s, from);
                            assert!(s != OK || t.is_finite(), "fmi2LastSuccessfulTime {t}");
                            t
                        }
                    };
                    ("fmi2DoStep", fmi2DoStep(c, t, h.value(), 1))
                }
                Call::GetState(slot) => {
                    let slot = &mut slots[*slot as usize % SLOTS];
                    if !slot.is_null() {
                        // Overwriting a state the FMU made is allowed; keep it simple and free it.
                        assert_eq!(fmi2FreeFMUstate(c, slot), OK);
                    }
                    let s = fmi2GetFMUstate(c, slot);
                    assert!(s == OK || slot.is_null(), "a failed fmi2GetFMUstate left a state");
                    ("fmi2GetFMUstate", s)
                }
                Call::SetState(slot) => {
                    let state = slots[*slot as usize % SLOTS];
                    if state.is_null() {
                        continue;
                    }
                    ("fmi2SetFMUstate", fmi2SetFMUstate(c, state))
                }
                Call::FreeState(slot) => ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut slots[*slot as usize % SLOTS])),
                Call::SerializeRoundTrip { from: source, to, edit, fix_checksum: fix } => {
                    let state = slots[*source as usize % SLOTS];
                    if state.is_null() {
                        continue;
                    }
                    let mut size = 0;
                    let s = fmi2SerializedFMUstateSize(c, state, &mut size);
                    check_status("fmi2SerializedFMUstateSize", s, from);
                    if s != OK {
                        continue;
                    }
                    let mut bytes = vec![0u8; size];
                    let s = fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size);
                    check_status("fmi2SerializeFMUstate", s, from);
                    if s != OK {
                        continue;
                    }
                    match edit {
                        Edit::None => {}
                        Edit::Flip { at, xor } => {
                            let i = *at as usize % bytes.len();
                            bytes[i] ^= xor;
                        }
                        Edit::PutNumber { at, value } => {
                            let i = *at as usize % bytes.len().saturating_sub(8).max(1);
                            let end = (i + 8).min(bytes.len());
                            bytes[i..end].copy_from_slice(&value.value().to_le_bytes()[..end - i]);
                        }
                        Edit::Truncate { to } => bytes.truncate(*to as usize % (bytes.len() + 1)),
                    }
                    if *fix {
                        fix_checksum(&mut bytes);
                    }
                    let slot = &mut slots[*to as usize % SLOTS];
                    if !slot.is_null() {
                        assert_eq!(fmi2FreeFMUstate(c, slot), OK);
                    }
                    let s = fmi2DeSerializeFMUstate(c, bytes.as_ptr(), bytes.len(), slot);
                    assert!(s == OK || slot.is_null(), "a failed fmi2DeSerializeFMUstate left a state");
                    ("fmi2DeSerializeFMUstate", s)
                }
                Call::Status { which, kind } => {
                    let kind = *kind as c_int;
                    match which % 5 {
                        0 => {
                            let mut v = 0;
                            ("fmi2GetStatus", fmi2GetStatus(c, kind, &mut v))
                        }
                        1 => {
                            let mut v = 0.0;
                            let s = fmi2GetRealStatus(c, kind, &mut v);
                            assert!(s != OK || v.is_finite());
                            ("fmi2GetRealStatus", s)
                        }
                        2 => {
                            let mut v = 0;
                            ("fmi2GetIntegerStatus", fmi2GetIntegerStatus(c, kind, &mut v))
                        }
                        3 => {
                            let mut v = 0;
                            ("fmi2GetBooleanStatus", fmi2GetBooleanStatus(c, kind, &mut v))
                        }
                        _ => {
                            let mut v = std::ptr::null();
                            ("fmi2GetStringStatus", fmi2GetStringStatus(c, kind, &mut v))
                        }
                    }
                }
                Call::Unsupported(which) => {
                    let vr = [1u32];
                    let order = [1 as c_int];
                    let mut v = [0.0];
                    match which % 4 {
                        0 => (
                            "fmi2GetDirectionalDerivative",
                            fmi2GetDirectionalDerivative(c, vr.as_ptr(), 1, vr.as_ptr(), 1, v.as_ptr(), v.as_mut_ptr()),
                        ),
                        1 => ("fmi2SetRealInputDerivatives", fmi2SetRealInputDerivatives(c, vr.as_ptr(), 1, order.as_ptr(), v.as_ptr())),
                        2 => (
                            "fmi2GetRealOutputDerivatives",
                            fmi2GetRealOutputDerivatives(c, vr.as_ptr(), 1, order.as_ptr(), v.as_mut_ptr()),
                        ),
                        _ => ("fmi2CancelStep", fmi2CancelStep(c)),
                    }
                }
                Call::NullArguments(which) => {
                    let null_u32 = std::ptr::null::<u32>();
                    match which % 9 {
                        0 => ("fmi2GetReal", fmi2GetReal(c, null_u32, 2, std::ptr::null_mut())),
                        1 => ("fmi2SetReal", fmi2SetReal(c, null_u32, 2, std::ptr::null())),
                        2 => ("fmi2GetString", fmi2GetString(c, null_u32, 1, std::ptr::null_mut())),
                        3 => ("fmi2SetString", fmi2SetString(c, null_u32, 1, std::ptr::null())),
                        4 => ("fmi2GetFMUstate", fmi2GetFMUstate(c, std::ptr::null_mut())),
                        5 => ("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(c, std::ptr::null_mut(), std::ptr::null_mut())),
                        6 => ("fmi2DeSerializeFMUstate", fmi2DeSerializeFMUstate(c, std::ptr::null(), 4, std::ptr::null_mut())),
                        7 => ("fmi2GetRealStatus", fmi2GetRealStatus(c, 2, std::ptr::null_mut())),
                        _ => ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, 1, 2, std::ptr::null())),
                    }
                }
            }
        };
        check_status(name, status, from);
    }
    unsafe {
        for slot in &mut slots {
            if !slot.is_null() {
                assert_eq!(fmi2FreeFMUstate(c, slot), OK, "{:?}", log_since(0));
            }
        }
        fmi2FreeInstance(c);
    }
}

fuzz_target!(|data: &[u8]| {
    if let Ok(input) = Input::arbitrary_take_rest(Unstructured::new(data)) {
        run(input);
    }
});
