//! The FMI 2.0 C ABI over [`Instance`]: pointer checks, string conversion, and a
//! `catch_unwind` around every entry point so no panic crosses into the host. The
//! [`export_fmi2!`](crate::export_fmi2) macro emits the `extern "C"` symbols and calls these.
//!
//! The functions are public for that macro (and for tests that drive an instance through the
//! C ABI without a shared library); a model author calls none of them.

use std::ffi::{c_char, c_int, c_void, CString};
use std::path::PathBuf;

use crate::instance::{Function, Instance, LogSink, Status};
use crate::model::ModelFactory;
use crate::raw::{self, catch_panic, slice, slice_mut, str_arg, Refused};
use crate::uri::ResourceUriError;

/// `fmi2Component`.
pub type Component = *mut c_void;
/// `fmi2FMUstate`.
pub use crate::raw::FmuState;
/// `fmi2CallbackLogger`: printf-style and variadic.
pub type Logger = unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    /// Logger; required.
    pub logger: Option<Logger>,
    /// Allocator (unused: the FMU declares `canNotUseMemoryManagementFunctions`).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// Deallocator (unused).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// Asynchronous step callback (unused).
    pub step_finished: Option<unsafe extern "C" fn(*mut c_void, c_int)>,
    /// Passed back to the logger.
    pub component_environment: *mut c_void,
}

/// `fmi2OK` etc. as the C ABI returns them.
pub type RawStatus = c_int;
/// `fmi2CoSimulation`.
pub const FMI2_COSIMULATION: c_int = 1;
/// `fmi2DoStepStatus`, `fmi2PendingStatus`, `fmi2LastSuccessfulTime`, `fmi2Terminated`.
pub const STATUS_KINDS: [&str; 4] = ["fmi2DoStepStatus", "fmi2PendingStatus", "fmi2LastSuccessfulTime", "fmi2Terminated"];

/// The host's logger and environment, callable from the instance.
struct HostLogger {
    logger: Logger,
    environment: *mut c_void,
    name: CString,
}

// SAFETY: the FMI standard lets an instance be used from any thread, one call at a time; the
// logger and its environment belong to the host, which must accept calls from that thread.
unsafe impl Send for HostLogger {}

impl HostLogger {
    fn log(&self, status: Status, category: &str, message: &str) {
        // The message is passed as the format string: escape '%' and drop NULs.
        let text = CString::new(message.replace('%', "%%").replace('\0', "")).expect("NULs removed");
        let category = CString::new(category.replace('\0', "")).expect("NULs removed");
        // SAFETY: the logger was given by the host for this purpose; all strings are valid C
        // strings that outlive the call, and no variadic arguments are used by the format.
        unsafe { (self.logger)(self.environment, self.name.as_ptr(), status as c_int, category.as_ptr(), text.as_ptr()) }
    }
}

/// What an `fmi2Component` points to.
pub struct Wrapper {
    instance: Instance,
    /// Keeps the strings returned by `fmi2GetString` alive until the next call.
    strings: Vec<CString>,
}

// The contract of the `unsafe fn`s below, which the FMI 2.0 standard sets for the host: `c`
// is NULL or a component that `instantiate` returned and `free_instance` has not freed, with
// no other call on it running ("`c` as in the FMI 2.0 standard"); an array is NULL or points
// to as many elements as the length passed with it; a string is NULL or NUL-terminated; all
// are the host's, valid until the call returns ("arguments as in the FMI 2.0 standard").

/// Runs `body` on the instance behind `c`, turning a panic into `fmi2Fatal`.
///
/// # Safety
/// `c` as in the FMI 2.0 standard.
unsafe fn with(c: Component, name: &str, body: impl FnOnce(&mut Wrapper) -> Status) -> RawStatus {
    // SAFETY: `c` is NULL or a live `Wrapper` of `instantiate`, used by this call alone (this
    // function's contract), which is what `guarded::<Wrapper>` asks.
    unsafe { raw::guarded(c, name, body) }
}

impl raw::HoldsInstance for Wrapper {
    fn instance(&mut self) -> &mut Instance {
        &mut self.instance
    }
}

/// Turns a resource location URI into a folder path of this platform (which may not exist):
/// the forms hosts pass on Unix and Windows, see [`crate::uri`].
pub fn resource_folder(uri: &str) -> Result<PathBuf, ResourceUriError> {
    crate::uri::resource_path(uri, crate::uri::PathStyle::native()).map(PathBuf::from)
}

/// `fmi2Instantiate`: NULL, after logging why, for an empty name, a wrong GUID, missing
/// callbacks or logger, a resource location that is no local file URI, a model type other
/// than co-simulation, or a factory that fails. The factory gets the resources folder (which
/// may not exist), or `None` when the host passed no resource location.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
#[allow(clippy::too_many_arguments)] // mirrors fmi2Instantiate's C signature
pub unsafe fn instantiate(
    factory: ModelFactory,
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> Component {
    // SAFETY: per the standard, `functions` points to the host's callbacks if non-null.
    let Some(functions) = (unsafe { functions.as_ref() }) else { return std::ptr::null_mut() };
    let Some(logger) = functions.logger else { return std::ptr::null_mut() };
    // SAFETY: `instance_name` is NULL or a NUL-terminated string of the host's, valid for the
    // call (this function's contract); the name is copied before the call returns.
    let name = unsafe { str_arg(instance_name) }.unwrap_or("");
    let host =
        |name: &str| HostLogger { logger, environment: functions.component_environment, name: CString::new(name).unwrap_or_default() };
    let fail = |why: &dyn std::fmt::Display| {
        host(name).log(Status::Error, "logStatusError", &format!("fmi2Instantiate: {why}"));
        std::ptr::null_mut()
    };
    let result = catch_panic(|| -> Result<Component, Refused> {
        if instance_name.is_null() || name.trim().is_empty() {
            return Err(Refused::Name("FMI 2.0 asks for a non-empty name"));
        }
        if fmu_type != FMI2_COSIMULATION {
            return Err(Refused::FmuType(fmu_type));
        }
        // SAFETY: `guid` and `resource_location` are NULL or NUL-terminated strings of the host's,
        // valid for the call (this function's contract); both are read before it returns.
        let guid = unsafe { str_arg(guid) }.ok_or(Refused::NullOrNotUtf8("GUID"))?;
        // SAFETY: as for `guid`.
        let resources = match unsafe { str_arg(resource_location) } {
            Some(location) => Some(resource_folder(location)?),
            None if resource_location.is_null() => None,
            None => return Err(Refused::NotUtf8("resource location")),
        };
        let model = factory(resources.as_deref()).map_err(Refused::Model)?;
        let sink_host = host(name);
        let sink: LogSink = Box::new(move |status, category, message| sink_host.log(status, category, message));
        let instance = Instance::new(name, guid, model, sink, logging_on != 0)?;
        Ok(Box::into_raw(Box::new(Wrapper { instance, strings: Vec::new() })) as Component)
    });
    match result {
        Ok(Ok(c)) => c,
        Ok(Err(refused)) => fail(&refused),
        Err(why) => fail(&format_args!("internal error ({why})")),
    }
}

/// `fmi2FreeInstance`.
///
/// # Safety
/// `c` is NULL or a component from [`instantiate`] not freed before.
pub unsafe fn free_instance(c: Component) {
    if !c.is_null() {
        // SAFETY: a non-null `c` is the `Box<Wrapper>` that `instantiate` leaked and nothing has
        // freed (this function's contract); the host makes no call on it after this one.
        let _ = catch_panic(|| drop(unsafe { Box::from_raw(c as *mut Wrapper) }));
    }
}

/// `fmi2SetDebugLogging`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn set_debug_logging(c: Component, on: c_int, n: usize, categories: *const *const c_char) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `categories` is NULL or `n` pointers, each NULL
    // or a NUL-terminated string, all the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2SetDebugLogging", |w| {
            let Some(ptrs) = slice(categories, n) else {
                return w.instance.error("fmi2SetDebugLogging: categories is NULL");
            };
            let mut names = Vec::with_capacity(n);
            for &p in ptrs {
                match str_arg(p) {
                    Some(s) => names.push(s),
                    None => return w.instance.error("fmi2SetDebugLogging: a category is NULL or not UTF-8"),
                }
            }
            w.instance.set_debug_logging(on != 0, &names)
        })
    }
}

/// `fmi2SetupExperiment`.
///
/// # Safety
/// `c` as in the FMI 2.0 standard.
pub unsafe fn setup_experiment(c: Component, tol_defined: c_int, tol: f64, start: f64, stop_defined: c_int, stop: f64) -> RawStatus {
    // SAFETY: `c` is NULL or a live component (this function's contract); the rest are values.
    unsafe {
        with(c, "fmi2SetupExperiment", |w| {
            w.instance.setup_experiment((tol_defined != 0).then_some(tol), start, (stop_defined != 0).then_some(stop))
        })
    }
}

macro_rules! simple {
    ($(#[$doc:meta] $fn_name:ident => $method:ident, $c_name:literal;)*) => {$(
        #[$doc]
        ///
        /// # Safety
        /// `c` as in the FMI 2.0 standard.
        pub unsafe fn $fn_name(c: Component) -> RawStatus {
            // SAFETY: `c` is NULL or a live component (this function's contract).
            unsafe { with(c, $c_name, |w| w.instance.$method()) }
        }
    )*};
}

simple! {
    /// `fmi2EnterInitializationMode`.
    enter_initialization_mode => enter_initialization_mode, "fmi2EnterInitializationMode";
    /// `fmi2ExitInitializationMode`.
    exit_initialization_mode => exit_initialization_mode, "fmi2ExitInitializationMode";
    /// `fmi2Terminate`.
    terminate => terminate, "fmi2Terminate";
    /// `fmi2Reset`.
    reset => reset, "fmi2Reset";
}

fn null_argument(w: &Wrapper, function: &str, what: &str) -> Status {
    w.instance.error(&format!("{function}: {what} is NULL"))
}

/// `fmi2GetReal`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_real(c: Component, vr: *const u32, n: usize, value: *mut f64) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` is NULL or `n` value references and
    // `value` NULL or room for `n` values, the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2GetReal", |w| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(out)) => w.instance.get_real(vr, out),
            _ => null_argument(w, "fmi2GetReal", "vr[] or value[]"),
        })
    }
}

/// `fmi2GetInteger`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_integer(c: Component, vr: *const u32, n: usize, value: *mut c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` is NULL or `n` value references and
    // `value` NULL or room for `n` values, the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2GetInteger", |w| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(out)) => w.instance.get_integer(vr, out),
            _ => null_argument(w, "fmi2GetInteger", "vr[] or value[]"),
        })
    }
}

/// `fmi2GetBoolean`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_boolean(c: Component, vr: *const u32, n: usize, value: *mut c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` is NULL or `n` value references and
    // `value` NULL or room for `n` values, the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2GetBoolean", |w| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(out)) => {
                let mut b = vec![false; n];
                let s = w.instance.get_boolean(vr, &mut b);
                if s == Status::Ok {
                    for (o, v) in out.iter_mut().zip(b) {
                        *o = v as c_int;
                    }
                }
                s
            }
            _ => null_argument(w, "fmi2GetBoolean", "vr[] or value[]"),
        })
    }
}

/// `fmi2GetString`: the returned pointers stay valid until the next call on this instance.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_string(c: Component, vr: *const u32, n: usize, value: *mut *const c_char) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` is NULL or `n` value references and
    // `value` NULL or room for `n` pointers, the host's for the call (this function's contract).
    // The pointers written point into `w.strings`, which outlives the call as the standard asks.
    unsafe {
        with(c, "fmi2GetString", |w| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(out)) => {
                let mut s = vec![String::new(); n];
                let status = w.instance.get_string(vr, &mut s);
                if status == Status::Ok {
                    w.strings = s.into_iter().map(|x| CString::new(x.replace('\0', "")).expect("NULs removed")).collect();
                    for (o, cs) in out.iter_mut().zip(&w.strings) {
                        *o = cs.as_ptr();
                    }
                }
                status
            }
            _ => null_argument(w, "fmi2GetString", "vr[] or value[]"),
        })
    }
}

/// `fmi2SetReal`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn set_real(c: Component, vr: *const u32, n: usize, value: *const f64) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` and `value` are NULL or `n` elements each,
    // the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2SetReal", |w| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(v)) => w.instance.set_real(vr, v),
            _ => null_argument(w, "fmi2SetReal", "vr[] or value[]"),
        })
    }
}

/// `fmi2SetInteger`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn set_integer(c: Component, vr: *const u32, n: usize, value: *const c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` and `value` are NULL or `n` elements each,
    // the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2SetInteger", |w| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(v)) => w.instance.set_integer(vr, v),
            _ => null_argument(w, "fmi2SetInteger", "vr[] or value[]"),
        })
    }
}

/// `fmi2SetBoolean`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn set_boolean(c: Component, vr: *const u32, n: usize, value: *const c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` and `value` are NULL or `n` elements each,
    // the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi2SetBoolean", |w| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(v)) => {
                let b: Vec<bool> = v.iter().map(|&x| x != 0).collect();
                w.instance.set_boolean(vr, &b)
            }
            _ => null_argument(w, "fmi2SetBoolean", "vr[] or value[]"),
        })
    }
}

/// `fmi2SetString`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn set_string(c: Component, vr: *const u32, n: usize, value: *const *const c_char) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `vr` and `value` are NULL or `n` elements each,
    // every value NULL or a NUL-terminated string, the host's for the call (this function's
    // contract); the strings are copied before it returns.
    unsafe {
        with(c, "fmi2SetString", |w| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(v)) => {
                let mut strings = Vec::with_capacity(n);
                for &p in v {
                    match str_arg(p) {
                        Some(s) => strings.push(s.to_owned()),
                        None => return w.instance.error("fmi2SetString: a value is NULL or not UTF-8; nothing was set"),
                    }
                }
                w.instance.set_string(vr, &strings)
            }
            _ => null_argument(w, "fmi2SetString", "vr[] or value[]"),
        })
    }
}

/// `fmi2GetFMUstate`: a new state, or the one `*state` points to overwritten.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_fmu_state(c: Component, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `state` is NULL or the host's handle, readable
    // and writable for the call (this function's contract), as `raw::get_fmu_state` asks.
    unsafe { with(c, "fmi2GetFMUstate", |w| raw::get_fmu_state(&mut w.instance, state)) }
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard: `state` from this FMU.
pub unsafe fn set_fmu_state(c: Component, state: FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live component (this function's contract); `state` is a number,
    // never read through.
    unsafe { with(c, "fmi2SetFMUstate", |w| raw::set_fmu_state(&mut w.instance, state)) }
}

/// `fmi2FreeFMUstate`: frees `*state` and sets it to NULL.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn free_fmu_state(c: Component, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `state` is NULL or the host's handle, readable
    // and writable for the call (this function's contract), as `raw::free_fmu_state` asks.
    unsafe { with(c, "fmi2FreeFMUstate", |w| raw::free_fmu_state(&mut w.instance, state)) }
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn serialized_fmu_state_size(c: Component, state: FmuState, size: *mut usize) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `size` is NULL or the host's writable `size_t`
    // for the call (this function's contract), as `raw::serialized_fmu_state_size` asks.
    unsafe { with(c, "fmi2SerializedFMUstateSize", |w| raw::serialized_fmu_state_size(&mut w.instance, state, size)) }
}

/// `fmi2SerializeFMUstate`: `size` must be what `fmi2SerializedFMUstateSize` said.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn serialize_fmu_state(c: Component, state: FmuState, out: *mut u8, size: usize) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `out` is NULL or `size` writable bytes of the
    // host's for the call (this function's contract), as `raw::serialize_fmu_state` asks.
    unsafe { with(c, "fmi2SerializeFMUstate", |w| raw::serialize_fmu_state(&mut w.instance, state, out, size)) }
}

/// `fmi2DeSerializeFMUstate`: a truncated, altered or foreign buffer is refused.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn deserialize_fmu_state(c: Component, bytes: *const u8, size: usize, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `bytes` is NULL or `size` readable bytes and
    // `state` NULL or the host's readable and writable handle, for the call (this function's
    // contract), as `raw::deserialize_fmu_state` asks.
    unsafe { with(c, "fmi2DeSerializeFMUstate", |w| raw::deserialize_fmu_state(&mut w.instance, bytes, size, state)) }
}

/// `fmi2DoStep`.
///
/// # Safety
/// `c` as in the FMI 2.0 standard.
pub unsafe fn do_step(c: Component, current: f64, step: f64, _no_prior: c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component (this function's contract); the rest are values.
    unsafe { with(c, "fmi2DoStep", |w| w.instance.do_step(current, step)) }
}

/// A function the FMU declares it does not support: `fmi2Error` with a log entry (after the
/// state check, so an illegal call is reported as such).
///
/// # Safety
/// `c` as in the FMI 2.0 standard.
pub unsafe fn unsupported(c: Component, name: &str, function: Function, why: &str) -> RawStatus {
    // SAFETY: `c` is NULL or a live component (this function's contract).
    unsafe {
        with(c, name, |w| match w.instance.check_phase(name, function) {
            Err(s) => s,
            Ok(()) => w.instance.error(&format!("{name}: not supported: {why}")),
        })
    }
}

fn kind_name(kind: c_int) -> &'static str {
    usize::try_from(kind).ok().and_then(|k| STATUS_KINDS.get(k)).copied().unwrap_or("an unknown status kind")
}

/// `fmi2GetRealStatus`: only `fmi2LastSuccessfulTime`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_real_status(c: Component, kind: c_int, value: *mut f64) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `value` is NULL (checked before the write) or
    // the host's writable real for the call (this function's contract).
    unsafe {
        with(c, "fmi2GetRealStatus", |w| {
            if value.is_null() {
                return null_argument(w, "fmi2GetRealStatus", "value");
            }
            if kind != 2 {
                return w.instance.error(&format!("fmi2GetRealStatus: {} has no Real value", kind_name(kind)));
            }
            match w.instance.last_successful_time() {
                Ok(t) => {
                    *value = t;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
}

/// `fmi2GetBooleanStatus`: only `fmi2Terminated`.
///
/// # Safety
/// Arguments as in the FMI 2.0 standard.
pub unsafe fn get_boolean_status(c: Component, kind: c_int, value: *mut c_int) -> RawStatus {
    // SAFETY: `c` is NULL or a live component; `value` is NULL (checked before the write) or
    // the host's writable `fmi2Boolean` for the call (this function's contract).
    unsafe {
        with(c, "fmi2GetBooleanStatus", |w| {
            if value.is_null() {
                return null_argument(w, "fmi2GetBooleanStatus", "value");
            }
            if kind != 3 {
                return w.instance.error(&format!("fmi2GetBooleanStatus: {} has no Boolean value", kind_name(kind)));
            }
            match w.instance.terminated_status() {
                Ok(b) => {
                    *value = b as c_int;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
}

/// `fmi2GetStatus`, `fmi2GetIntegerStatus`, `fmi2GetStringStatus`: these ask about
/// asynchronous steps, which this FMU never takes (it never returns `fmi2Pending`).
///
/// # Safety
/// `c` as in the FMI 2.0 standard.
pub unsafe fn status_without_value(c: Component, name: &str, kind: c_int) -> RawStatus {
    let why = format!("{} is only defined after fmi2DoStep returned fmi2Pending, which this FMU never does", kind_name(kind));
    // SAFETY: `c` is NULL or a live component (this function's contract), all `unsupported`
    // asks.
    unsafe { unsupported(c, name, Function::GetStatus, &why) }
}

/// Emits every FMI 2.0 common and co-simulation function as an `extern "C"` symbol, for a
/// `cdylib` that serves the models `factory` (a [`ModelFactory`](crate::ModelFactory)) makes.
/// Invoke it once, at the crate's top level.
#[macro_export]
macro_rules! export_fmi2 {
    ($factory:path) => {
        // Bound here, where `$factory` resolves as the caller wrote it.
        #[doc(hidden)]
        const __FMI2_EXPORT_FACTORY: $crate::ModelFactory = $factory;

        #[doc(hidden)]
        mod fmi2_exports {
            use std::ffi::{c_char, c_int};
            use $crate::fmi2::abi::{self, CallbackFunctions, Component, FmuState, RawStatus};
            use $crate::instance::Function;

            #[no_mangle]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
                c"default".as_ptr()
            }
            #[no_mangle]
            pub extern "C" fn fmi2GetVersion() -> *const c_char {
                c"2.0".as_ptr()
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetDebugLogging(c: Component, on: c_int, n: usize, cats: *const *const c_char) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_debug_logging(c, on, n, cats) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Instantiate(
                name: *const c_char,
                fmu_type: c_int,
                guid: *const c_char,
                resources: *const c_char,
                functions: *const CallbackFunctions,
                visible: c_int,
                logging_on: c_int,
            ) -> Component {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged with this library's factory.
                unsafe { abi::instantiate(super::__FMI2_EXPORT_FACTORY, name, fmu_type, guid, resources, functions, visible, logging_on) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeInstance(c: Component) {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::free_instance(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetupExperiment(c: Component, td: c_int, tol: f64, start: f64, sd: c_int, stop: f64) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::setup_experiment(c, td, tol, start, sd, stop) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Component) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::enter_initialization_mode(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Component) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::exit_initialization_mode(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Terminate(c: Component) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::terminate(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2Reset(c: Component) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::reset(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetReal(c: Component, vr: *const u32, n: usize, v: *mut f64) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_real(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetInteger(c: Component, vr: *const u32, n: usize, v: *mut c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_integer(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBoolean(c: Component, vr: *const u32, n: usize, v: *mut c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_boolean(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetString(c: Component, vr: *const u32, n: usize, v: *mut *const c_char) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_string(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetReal(c: Component, vr: *const u32, n: usize, v: *const f64) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_real(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetInteger(c: Component, vr: *const u32, n: usize, v: *const c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_integer(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetBoolean(c: Component, vr: *const u32, n: usize, v: *const c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_boolean(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetString(c: Component, vr: *const u32, n: usize, v: *const *const c_char) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_string(c, vr, n, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, s: *mut FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, s: FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, s: *mut FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::free_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(c: Component, s: FmuState, size: *mut usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::serialized_fmu_state_size(c, s, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(c: Component, s: FmuState, out: *mut c_char, size: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged; its `fmi2Byte` buffer (a `char` array) is written as bytes.
                unsafe { abi::serialize_fmu_state(c, s, out.cast::<u8>(), size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(c: Component, b: *const c_char, size: usize, s: *mut FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged; its `fmi2Byte` buffer (a `char` array) is read as bytes.
                unsafe { abi::deserialize_fmu_state(c, b.cast::<u8>(), size, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
                c: Component,
                _unknown: *const u32,
                _n_unknown: usize,
                _known: *const u32,
                _n_known: usize,
                _dv_known: *const f64,
                _dv_unknown: *mut f64,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe {
                    abi::unsupported(
                        c,
                        "fmi2GetDirectionalDerivative",
                        Function::GetDirectionalDerivative,
                        "providesDirectionalDerivative is false",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: Component,
                _vr: *const u32,
                _n: usize,
                _order: *const c_int,
                _v: *const f64,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe {
                    abi::unsupported(c, "fmi2SetRealInputDerivatives", Function::SetRealInputDerivatives, "canInterpolateInputs is false")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: Component,
                _vr: *const u32,
                _n: usize,
                _order: *const c_int,
                _v: *mut f64,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe {
                    abi::unsupported(c, "fmi2GetRealOutputDerivatives", Function::GetRealOutputDerivatives, "maxOutputDerivativeOrder is 0")
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2DoStep(c: Component, t: f64, h: f64, no_prior: c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::do_step(c, t, h, no_prior) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2CancelStep(c: Component) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::unsupported(c, "fmi2CancelStep", Function::CancelStep, "steps are never asynchronous") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStatus(c: Component, kind: c_int, _v: *mut c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::status_without_value(c, "fmi2GetStatus", kind) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, kind: c_int, v: *mut f64) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_real_status(c, kind, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(c: Component, kind: c_int, _v: *mut c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::status_without_value(c, "fmi2GetIntegerStatus", kind) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(c: Component, kind: c_int, v: *mut c_int) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_boolean_status(c, kind, v) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi2GetStringStatus(c: Component, kind: c_int, _v: *mut *const c_char) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 2.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::status_without_value(c, "fmi2GetStringStatus", kind) }
            }
        }
    };
}
