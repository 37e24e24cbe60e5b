//! The FMI 3.0 C API of a small model with a variable of every type (Float64 input, parameter
//! and output with direct feedthrough, Int32, Enumeration, Boolean, String), driven in process
//! through the `abi` functions as a host would through the symbols: value references are
//! positions, each type only through its own functions, the FMI 2.0 rules (state machine, NaN,
//! enumeration items) hold and messages name the fmi3 functions; the model description lists
//! what the calls serve.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::sync::Mutex;

use neurarm_fmi_export::fmi3::abi::{self, Fmi3Instance};
use neurarm_fmi_export::fmi3::description::to_xml;
use neurarm_fmi_export::{
    Causality, EnumerationType, Model, ModelDescription, ModelError, RealVar, StaticModel, TableBuilder, Unit, Values, Variability,
};

struct Gain {
    description: ModelDescription,
    u: RealVar,
    k: RealVar,
    y: RealVar,
}

fn gain() -> Gain {
    let mut b = TableBuilder::new();
    let u = b.input("u", Unit::SECOND, 1.0, "Input"); // 1
    let k = b.parameter("k", None, 2.0, "Gain"); // 2
    let y = b.output("y", Unit::SECOND, "k u", &[u]); // 3
    b.integer("count", Causality::Parameter, Variability::Fixed, Some(7), "An Int32"); // 4
    let mode = EnumerationType::new("Mode", &[("off", "Off"), ("on", "On")]);
    b.enumeration("mode", Causality::Parameter, Variability::Tunable, &mode, Some(1), "An enumeration"); // 5
    b.boolean("flag", Causality::Parameter, Variability::Tunable, Some(true), "A Boolean"); // 6
    b.string("label", Causality::Parameter, Variability::Fixed, Some("a & b".into()), "A string"); // 7
    let description = ModelDescription::new("Gain", "y = k u", b.finish()).unwrap();
    Gain { description, u, k, y }
}

impl StaticModel for Gain {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        values[self.y] = values[self.k] * values[self.u];
        Ok(())
    }
}

fn factory(_resources: Option<&std::path::Path>) -> Result<Box<dyn Model>, ModelError> {
    Ok(Box::new(gain()))
}

static LOG: Mutex<Vec<(c_int, String)>> = Mutex::new(Vec::new());

unsafe extern "C" fn logger(_env: *mut c_void, status: c_int, _category: *const c_char, message: *const c_char) {
    // SAFETY: the layer calls its logger with `message` a NUL-terminated string that lives until
    // the callback returns (`HostLogger::log`).
    let text = unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned();
    LOG.lock().unwrap().push((status, text));
}

fn last_error() -> String {
    LOG.lock().unwrap().iter().rev().find(|(s, _)| *s >= 3).map(|(_, m)| m.clone()).unwrap_or_default()
}

fn instantiate(token: &str) -> Fmi3Instance {
    let name = CString::new("g").unwrap();
    let token = CString::new(token).unwrap();
    // SAFETY: the name and token are NUL-terminated strings that outlive the call; the resource
    // path, the required variables (0 of them) and the environment are NULL, which the standard
    // allows; the logger is a function of the logger's signature that lives for the program.
    unsafe {
        abi::instantiate_co_simulation(
            factory,
            name.as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            Some(logger),
        )
    }
}

/// `fmi3DoStep`: status, (eventHandlingNeeded, terminateSimulation, earlyReturn), lastSuccessfulTime.
fn step(c: Fmi3Instance, t: f64, h: f64) -> (c_int, [bool; 3], f64) {
    let (mut flags, mut last) = ([true; 3], f64::NAN);
    let [a, b, e] = &mut flags;
    // SAFETY: `c` is the live instance of `instantiate` each caller passes, and the four output
    // pointers are locals that outlive the call.
    let status = unsafe { abi::do_step(c, t, h, true, a, b, e, &mut last) };
    (status, flags, last)
}

const OK: c_int = 0;
const ERROR: c_int = 3;

#[test]
fn every_type_through_its_own_functions() {
    let token = gain().description.guid();
    assert!(instantiate("{wrong}").is_null());
    assert!(last_error().contains("instantiation token"), "{}", last_error());
    let c = instantiate(&token);
    assert!(!c.is_null());
    // SAFETY: `c` is live from `instantiate` until `free_instance`, the last call; every array
    // passed is a local or a temporary of the statement, of the length given with it (the values
    // count matches except where a mismatch is the point), so all outlive their call; `s[0]` is
    // read before the next call on `c`, while the string it points into is still kept.
    unsafe {
        let mut y = [0.0];
        assert_eq!(step(c, 0.0, 0.1).0, ERROR);
        assert!(last_error().starts_with("fmi3DoStep: illegal call sequence"), "{}", last_error());
        assert_eq!(abi::enter_initialization_mode(c, false, 0.0, 0.0, true, 1.0), OK);
        assert_eq!(abi::set_float64(c, [1].as_ptr(), 1, [3.0].as_ptr(), 1), OK);
        assert_eq!(abi::exit_initialization_mode(c), OK);
        assert_eq!(abi::get_float64(c, [3].as_ptr(), 1, y.as_mut_ptr(), 1), OK);
        assert_eq!(y[0], 6.0);
        // direct feedthrough: a new input shows in the output before the next step
        assert_eq!(abi::set_float64(c, [1].as_ptr(), 1, [0.5].as_ptr(), 1), OK);
        assert_eq!(abi::get_float64(c, [3].as_ptr(), 1, y.as_mut_ptr(), 1), OK);
        assert_eq!(y[0], 1.0);
        // Int32, Enumeration (as Int64), Boolean, String by their positions
        let mut i = [0i32];
        assert_eq!(abi::get_int32(c, [4].as_ptr(), 1, i.as_mut_ptr(), 1), OK);
        assert_eq!(i[0], 7);
        let mut e = [0i64];
        assert_eq!(abi::get_int64(c, [5].as_ptr(), 1, e.as_mut_ptr(), 1), OK);
        assert_eq!(e[0], 1);
        assert_eq!(abi::set_int64(c, [5].as_ptr(), 1, [2i64].as_ptr(), 1), OK);
        assert_eq!(abi::set_int64(c, [5].as_ptr(), 1, [3i64].as_ptr(), 1), ERROR);
        assert!(last_error().contains("not an item of 'mode'"), "{}", last_error());
        assert_eq!(abi::set_int64(c, [5].as_ptr(), 1, [1i64 << 40].as_ptr(), 1), ERROR);
        assert_eq!(abi::get_int64(c, [5].as_ptr(), 1, e.as_mut_ptr(), 1), OK);
        assert_eq!(e[0], 2);
        let mut b = [false];
        assert_eq!(abi::get_boolean(c, [6].as_ptr(), 1, b.as_mut_ptr(), 1), OK);
        assert!(b[0]);
        assert_eq!(abi::set_boolean(c, [6].as_ptr(), 1, [0u8].as_ptr(), 1), OK);
        assert_eq!(abi::get_boolean(c, [6].as_ptr(), 1, b.as_mut_ptr(), 1), OK);
        assert!(!b[0]);
        let mut s = [std::ptr::null::<c_char>()];
        assert_eq!(abi::get_string(c, [7].as_ptr(), 1, s.as_mut_ptr(), 1), OK);
        assert_eq!(CStr::from_ptr(s[0]).to_str().unwrap(), "a & b");
        // each type only through its functions; references are positions, unique over types
        assert_eq!(abi::get_int32(c, [5].as_ptr(), 1, i.as_mut_ptr(), 1), ERROR);
        assert!(last_error().contains("fmi3GetInt64"), "{}", last_error());
        assert_eq!(abi::get_float64(c, [4].as_ptr(), 1, y.as_mut_ptr(), 1), ERROR);
        assert!(last_error().contains("'count') is a Int32 variable, not Float64"), "{}", last_error());
        assert_eq!(abi::get_float64(c, [8].as_ptr(), 1, y.as_mut_ptr(), 1), ERROR);
        assert!(last_error().contains("unknown value reference 8"), "{}", last_error());
        assert_eq!(abi::get_float64(c, [3].as_ptr(), 1, y.as_mut_ptr(), 2), ERROR);
        assert!(last_error().contains("scalar"), "{}", last_error());
        assert_eq!(abi::no_such_type(c, "fmi3GetFloat32", "Float32", false, [3].as_ptr(), 1), ERROR);
        assert_eq!(abi::no_such_type(c, "fmi3GetFloat32", "Float32", false, std::ptr::null(), 0), OK);
        // the FMI 2.0 rules, named as FMI 3.0 functions
        assert_eq!(abi::set_float64(c, [1].as_ptr(), 1, [f64::NAN].as_ptr(), 1), ERROR);
        assert!(last_error().starts_with("fmi3SetFloat64: NaN for 'u' is not a finite number"), "{}", last_error());
        assert_eq!(abi::set_float64(c, [2].as_ptr(), 1, [5.0].as_ptr(), 1), ERROR, "k is fixed");
        let (status, flags, last) = step(c, 0.0, 0.1);
        assert_eq!((status, flags, last), (OK, [false; 3], 0.1));
        assert_eq!(step(c, 0.1, 1.0).0, ERROR);
        assert!(last_error().contains("past the stop time 1 s"), "{}", last_error());
        // FMU state through serialisation, and a damaged one refused
        let mut state: abi::FmuState = std::ptr::null_mut();
        assert_eq!(abi::get_fmu_state(c, &mut state), OK);
        let mut size = 0usize;
        assert_eq!(abi::serialized_fmu_state_size(c, state, &mut size), OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(abi::serialize_fmu_state(c, state, bytes.as_mut_ptr(), size), OK);
        bytes[size / 2] ^= 1;
        let mut other: abi::FmuState = std::ptr::null_mut();
        assert_eq!(abi::deserialize_fmu_state(c, bytes.as_ptr(), size, &mut other), ERROR);
        assert!(last_error().starts_with("fmi3DeserializeFMUState: invalid state: checksum mismatch"), "{}", last_error());
        assert_eq!(abi::free_fmu_state(c, &mut state), OK);
        assert!(state.is_null());
        assert_eq!(abi::terminate(c), OK);
        assert_eq!(abi::reset(c), OK);
        assert_eq!(abi::enter_initialization_mode(c, false, 0.0, 0.0, false, 0.0), OK);
        abi::free_instance(c);
    }
}

#[test]
fn the_description_serves_what_the_calls_serve() {
    let g = gain();
    let xml = to_xml(&g.description);
    for expected in [
        r#"fmiVersion="3.0""#,
        r#"<Float64 name="time" valueReference="0""#,
        r#"<Float64 name="u" valueReference="1" description="Input" causality="input" variability="continuous" unit="s" start="1"/>"#,
        r#"<Int32 name="count" valueReference="4""#,
        r#"<Enumeration name="mode" valueReference="5" description="An enumeration" causality="parameter" variability="tunable" declaredType="Mode" initial="exact" start="1"/>"#,
        r#"<Boolean name="flag" valueReference="6""#,
        r#"<Start value="a &amp; b"/>"#,
        r#"<EnumerationType name="Mode">"#,
        r#"<Output valueReference="3" dependencies="1" dependenciesKind="dependent"/>"#,
        r#"<InitialUnknown valueReference="3"/>"#,
        r#"hasEventMode="false""#,
    ] {
        assert!(xml.contains(expected), "missing {expected} in\n{xml}");
    }
    assert!(xml.contains(&format!(r#"instantiationToken="{}""#, g.description.guid())));
}
