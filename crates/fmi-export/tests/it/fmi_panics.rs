//! No panic crosses the C ABI: a model that panics gives fmi2Fatal (and a log entry naming the
//! place), after which the instance only refuses, and a factory that panics gives NULL. Nothing
//! of it is printed on the host's console: the host hears of it through its logger.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;
use std::sync::Mutex;

use neurarm_fmi_export::fmi2::abi::{self, CallbackFunctions, Logger};
use neurarm_fmi_export::{DefaultExperiment, Model, ModelDescription, ModelError, TableBuilder, Values};

struct Bomb(ModelDescription);

fn description() -> ModelDescription {
    let mut b = TableBuilder::new();
    let u = b.input("u", None, 0.0, "input");
    b.output("y", None, "output", &[u]);
    ModelDescription::new("Bomb", "panics in fmi2DoStep", b.finish()).unwrap().with_default_experiment(DefaultExperiment {
        start_time: 0.0,
        stop_time: 1.0,
        step_size: 0.1,
    })
}

impl Model for Bomb {
    fn description(&self) -> &ModelDescription {
        &self.0
    }
    fn initialize(&mut self, _: &mut Values, _: f64) -> Result<(), ModelError> {
        Ok(())
    }
    fn do_step(&mut self, _: &mut Values, _: f64, _: f64) -> Result<(), ModelError> {
        panic!("boom in do_step")
    }
    fn reset(&mut self) {}
    fn save_state(&self, _: &mut Vec<u8>) {}
    fn load_state(&mut self, _: &Values, _: &[u8]) -> Result<(), ModelError> {
        Ok(())
    }
}

fn bomb(_: Option<&Path>) -> Result<Box<dyn Model>, ModelError> {
    Ok(Box::new(Bomb(description())))
}

fn exploding_factory(_: Option<&Path>) -> Result<Box<dyn Model>, ModelError> {
    panic!("factory exploded")
}

static LOG: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "C" fn capture(_: *mut c_void, _: *const c_char, _: c_int, _: *const c_char, message: *const c_char) {
    // SAFETY: the layer logs with `message` a NUL-terminated string that lives until the
    // callback returns (`HostLogger::log`), the format of a call without variadic arguments.
    LOG.lock().unwrap().push(unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned());
}

#[test]
fn panics_become_fatal_and_never_unwind_into_the_host() {
    // SAFETY: a non-variadic logger receives the same first five arguments on this ABI,
    // as ctypes-based hosts such as fmpy rely on.
    let logger: Logger = unsafe { std::mem::transmute(capture as unsafe extern "C" fn(_, _, _, _, _)) };
    let callbacks = CallbackFunctions {
        logger: Some(logger),
        allocate_memory: None,
        free_memory: None,
        step_finished: None,
        component_environment: std::ptr::null_mut(),
    };
    let dir = tempfile::tempdir().unwrap();
    let uri = CString::new(format!("file://{}", dir.path().display())).unwrap();
    let guid = CString::new(description().guid()).unwrap();
    let name = CString::new("bomb").unwrap();
    // SAFETY: name, GUID and URI are NUL-terminated strings and `callbacks` a valid
    // `fmi2CallbackFunctions`, all outliving the calls; each `c` is used from `instantiate`
    // until `free_instance` only, the value arrays are temporaries or locals of the length given.
    unsafe {
        let c = abi::instantiate(bomb, name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &callbacks, 0, 0);
        assert!(!c.is_null());
        assert_eq!(abi::setup_experiment(c, 0, 0.0, 0.0, 0, 0.0), 0);
        assert_eq!(abi::enter_initialization_mode(c), 0);
        assert_eq!(abi::exit_initialization_mode(c), 0);
        assert_eq!(abi::do_step(c, 0.0, 0.1, 1), 4, "fmi2Fatal");
        assert!(LOG
            .lock()
            .unwrap()
            .iter()
            .any(|m| m.contains("fmi2DoStep: internal error (boom in do_step, at ") && m.contains("fmi_panics.rs:")));
        // Afterwards every call is refused with fmi2Fatal; freeing still works.
        assert_eq!(abi::do_step(c, 0.0, 0.1, 1), 4);
        assert_eq!(abi::reset(c), 4);
        let mut y = 0.0;
        assert_eq!(abi::get_real(c, [1u32].as_ptr(), 1, &mut y), 4);
        abi::free_instance(c);

        let c = abi::instantiate(exploding_factory, name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &callbacks, 0, 0);
        assert!(c.is_null());
        assert!(LOG.lock().unwrap().iter().any(|m| m.contains("fmi2Instantiate: internal error (factory exploded, at ")));
    }
}

#[test]
fn a_caught_panic_prints_nothing_on_the_hosts_console() {
    // This test program, run again with only the test above and its output not captured: the
    // panics it causes inside the FMU calls must not reach stderr.
    if std::env::var_os("NEURARM_PANIC_CHILD").is_some() {
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let run = |filter: &str| {
        std::process::Command::new(&exe)
            .args([filter, "--exact", "--nocapture", "--test-threads=1"])
            .env("NEURARM_PANIC_CHILD", "1")
            .output()
            .unwrap()
    };
    let out = run("fmi_panics::panics_become_fatal_and_never_unwind_into_the_host");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed"), "the test ran");
    assert!(!stderr.contains("boom") && !stderr.contains("exploded") && !stderr.contains("panicked"), "{stderr}");
}
