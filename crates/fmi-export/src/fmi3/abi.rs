//! The FMI 3.0 Co-Simulation C API over the shared [`Instance`]: pointer checks, value
//! reference translation ([`Fmi3Variables`]), string conversion, and a `catch_unwind` around
//! every entry point so no panic crosses into the host. The [`export_fmi3!`](crate::export_fmi3)
//! macro emits the `extern "C"` symbols and calls these.
//!
//! The rules (state machine, settable variables, NaN refusal, FMU states) are the instance's,
//! the same as behind the FMI 2.0 API; messages name the FMI 3.0 functions. Event mode,
//! clocks, intermediate update, derivatives, Model Exchange and Scheduled Execution are not
//! offered (`hasEventMode="false"`): their functions exist, log why and return `fmi3Error`
//! (instantiation returns NULL).
//!
//! The functions are public for that macro and for tests; a model author calls none of them.

use std::ffi::{c_char, c_int, c_void, CString};
use std::path::PathBuf;

use crate::instance::{Api, Function, Instance, InstantiateError, LogSink, Status};
use crate::raw::{self, catch_panic, slice, slice_mut, str_arg, Refused};
use crate::ModelFactory;

use super::description::{Fmi3Type, Fmi3Variables};

/// `fmi3Instance`.
pub type Fmi3Instance = *mut c_void;
/// `fmi3FMUState`.
pub use crate::raw::FmuState;
/// `fmi3Status` as the C API returns it (the values of [`Status`], without `Pending`).
pub type RawStatus = c_int;
/// `fmi3LogMessageCallback`: not variadic in FMI 3.0, the message is plain text.
pub type LogMessage = unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char);
/// `fmi3IntermediateUpdateCallback`: never called (no intermediate update, no early return).
pub type IntermediateUpdate = unsafe extern "C" fn(*mut c_void, f64, bool, bool, bool, bool, *mut bool, *mut f64);
/// `fmi3ClockUpdateCallback`: never called (no Scheduled Execution).
pub type ClockUpdate = unsafe extern "C" fn(*mut c_void);
/// `fmi3LockPreemptionCallback` and `fmi3UnlockPreemptionCallback`: never called (no
/// Scheduled Execution).
pub type Preemption = unsafe extern "C" fn();

/// The host's logger and environment, callable from the instance.
struct HostLogger {
    logger: Option<LogMessage>,
    environment: *mut c_void,
}

// SAFETY: an FMI instance may be used from any thread, one call at a time; the logger and its
// environment belong to the host, which must accept calls from that thread.
unsafe impl Send for HostLogger {}

impl HostLogger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(logger) = self.logger else { return };
        let text = CString::new(message.replace('\0', "")).expect("NULs removed");
        let category = CString::new(category.replace('\0', "")).expect("NULs removed");
        // SAFETY: the logger was given by the host for this purpose; both strings are valid C
        // strings that outlive the call.
        unsafe { logger(self.environment, status as c_int, category.as_ptr(), text.as_ptr()) }
    }
}

/// What an `fmi3Instance` points to.
pub struct Wrapper {
    instance: Instance,
    variables: Fmi3Variables,
    /// The FMI 2.0 value references of the current call (kept to avoid an allocation per call).
    scratch: Vec<u32>,
    /// Keeps the strings returned by `fmi3GetString` alive until the next call.
    strings: Vec<CString>,
}

impl Wrapper {
    /// Translates `vrs` of type `wanted` into the instance's value references in `scratch`; an
    /// unknown reference, one of another type or a value count other than one per reference
    /// (all variables are scalars) is refused with a log entry.
    fn translate(&mut self, function: &str, wanted: Fmi3Type, vrs: &[u32], n_values: usize) -> Result<(), Status> {
        if n_values != vrs.len() {
            return Err(self.instance.error(&format!(
                "{function}: nValues = {n_values} for nValueReferences = {}: every variable of this FMU is a scalar, so they must be equal",
                vrs.len()
            )));
        }
        self.scratch.clear();
        for &vr in vrs {
            match self.variables.get(vr) {
                Some((t, fmi2_vr)) if t == wanted => self.scratch.push(fmi2_vr),
                Some((t, _)) => {
                    let name = &self.instance.description().variables[vr as usize].name;
                    return Err(self.instance.error(&format!(
                        "{function}: value reference {vr} ('{name}') is a {} variable, not {}{}",
                        t.name(),
                        wanted.name(),
                        if t == Fmi3Type::Enumeration { " (read and set enumerations with fmi3GetInt64/fmi3SetInt64)" } else { "" }
                    )));
                }
                None => return Err(self.instance.error(&format!("{function}: unknown value reference {vr}"))),
            }
        }
        Ok(())
    }
}

// The contract of the `unsafe fn`s below, which the FMI 3.0 standard sets for the host: `c`
// is NULL or an instance that `instantiate_co_simulation` returned and `free_instance` has
// not freed, with no other call on it running ("`c` as in the FMI 3.0 standard"); an array
// is NULL or points to as many elements as the length passed with it; a string is NULL or
// NUL-terminated; all are the host's, valid until the call returns ("arguments as in the FMI
// 3.0 standard").

/// Runs `body` on the instance behind `c`, turning a panic into `fmi3Fatal`.
///
/// # Safety
/// `c` as in the FMI 3.0 standard.
unsafe fn with(c: Fmi3Instance, name: &str, body: impl FnOnce(&mut Wrapper) -> Status) -> RawStatus {
    // SAFETY: `c` is NULL or a live `Wrapper` of `instantiate_co_simulation`, used by this call
    // alone (this function's contract), which is what `guarded::<Wrapper>` asks.
    unsafe { raw::guarded(c, name, body) }
}

impl raw::HoldsInstance for Wrapper {
    fn instance(&mut self) -> &mut Instance {
        &mut self.instance
    }
}

fn null_argument(w: &Wrapper, function: &str, what: &str) -> Status {
    w.instance.error(&format!("{function}: {what} is NULL"))
}

/// `fmi3InstantiateCoSimulation`: NULL, after logging why (when a logger was given), for an
/// empty name, a wrong instantiation token, event mode asked for (this FMU has none), a
/// resource path that is not UTF-8, or a factory that fails. The factory gets the resource
/// folder (which may not exist), or `None` when the host passed none.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
#[allow(clippy::too_many_arguments)] // mirrors the C signature
pub unsafe fn instantiate_co_simulation(
    factory: ModelFactory,
    instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate_variables: *const u32,
    _n_required_intermediate_variables: usize,
    instance_environment: *mut c_void,
    log_message: Option<LogMessage>,
) -> Fmi3Instance {
    let host = || HostLogger { logger: log_message, environment: instance_environment };
    let fail = |why: &dyn std::fmt::Display| {
        host().log(Status::Error, "logStatusError", &format!("fmi3InstantiateCoSimulation: {why}"));
        std::ptr::null_mut()
    };
    let result = catch_panic(|| -> Result<Fmi3Instance, Refused> {
        // SAFETY: `instance_name` is NULL or a NUL-terminated string of the host's, valid for the
        // call (this function's contract); the name is copied before the call returns.
        let name = unsafe { str_arg(instance_name) }.unwrap_or("");
        if name.trim().is_empty() {
            return Err(Refused::Name("FMI 3.0 asks for at least one other character"));
        }
        if event_mode_used {
            return Err(Refused::EventMode);
        }
        // SAFETY: `instantiation_token` and `resource_path` are NULL or NUL-terminated strings of
        // the host's, valid for the call (this function's contract); both are read before it returns.
        let token = unsafe { str_arg(instantiation_token) }.ok_or(Refused::NullOrNotUtf8("instantiation token"))?;
        // SAFETY: as for `instantiation_token`.
        let resources = match unsafe { str_arg(resource_path) } {
            Some(path) => Some(PathBuf::from(path)),
            None if resource_path.is_null() => None,
            None => return Err(Refused::NotUtf8("resource path")),
        };
        let model = factory(resources.as_deref()).map_err(Refused::Model)?;
        let variables = Fmi3Variables::new(model.description());
        let sink_host = host();
        let sink: LogSink = Box::new(move |status, category, message| sink_host.log(status, category, message));
        let instance = Instance::new(name, token, model, sink, logging_on).map_err(in_fmi3_words)?.with_api(Api::Fmi3);
        Ok(Box::into_raw(Box::new(Wrapper { instance, variables, scratch: Vec::new(), strings: Vec::new() })) as Fmi3Instance)
    });
    match result {
        Ok(Ok(c)) => c,
        Ok(Err(refused)) => fail(&refused),
        Err(why) => fail(&format_args!("internal error ({why})")),
    }
}

/// An instance's refusal in FMI 3.0's words: the model's GUID is its instantiation token.
fn in_fmi3_words(error: InstantiateError) -> Refused {
    match error {
        InstantiateError::WrongGuid { given, expected } => Refused::WrongToken { given, expected },
        other => Refused::Instance(other),
    }
}

/// `fmi3InstantiateModelExchange` and `fmi3InstantiateScheduledExecution`: this FMU offers
/// Co-Simulation only; logs why and returns NULL.
///
/// # Safety
/// `log_message` is NULL or the host's logger for `instance_environment`.
pub unsafe fn instantiate_other(function: &str, instance_environment: *mut c_void, log_message: Option<LogMessage>) -> Fmi3Instance {
    let host = HostLogger { logger: log_message, environment: instance_environment };
    let _ = catch_panic(|| host.log(Status::Error, "logStatusError", &format!("{function}: this FMU supports only Co-Simulation")));
    std::ptr::null_mut()
}

/// `fmi3FreeInstance`.
///
/// # Safety
/// `c` is NULL or an instance from [`instantiate_co_simulation`] not freed before.
pub unsafe fn free_instance(c: Fmi3Instance) {
    if !c.is_null() {
        // SAFETY: a non-null `c` is the `Box<Wrapper>` that `instantiate_co_simulation` leaked and
        // nothing has freed (this function's contract); the host makes no call on it after this one.
        let _ = catch_panic(|| drop(unsafe { Box::from_raw(c as *mut Wrapper) }));
    }
}

/// `fmi3SetDebugLogging`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_debug_logging(c: Fmi3Instance, on: bool, n: usize, categories: *const *const c_char) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `categories` is NULL or `n` pointers, each NULL
    // or a NUL-terminated string, all the host's for the call (this function's contract).
    unsafe {
        with(c, "fmi3SetDebugLogging", |w| {
            let Some(ptrs) = slice(categories, n) else {
                return null_argument(w, "fmi3SetDebugLogging", "categories");
            };
            let mut names = Vec::with_capacity(n);
            for &p in ptrs {
                match str_arg(p) {
                    Some(s) => names.push(s),
                    None => return w.instance.error("fmi3SetDebugLogging: a category is NULL or not UTF-8"),
                }
            }
            w.instance.set_debug_logging(on, &names)
        })
    }
}

/// `fmi3EnterInitializationMode`: the experiment's tolerance, start and stop time, then
/// initialization mode.
///
/// # Safety
/// `c` as in the FMI 3.0 standard.
pub unsafe fn enter_initialization_mode(
    c: Fmi3Instance,
    tolerance_defined: bool,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance (this function's contract); the rest are values.
    unsafe {
        with(c, "fmi3EnterInitializationMode", |w| {
            let s = w.instance.setup_experiment(tolerance_defined.then_some(tolerance), start_time, stop_time_defined.then_some(stop_time));
            if s != Status::Ok {
                return s;
            }
            w.instance.enter_initialization_mode()
        })
    }
}

macro_rules! simple {
    ($($(#[$doc:meta])* $fn_name:ident => $method:ident, $c_name:literal;)*) => {$(
        $(#[$doc])*
        ///
        /// # Safety
        /// `c` as in the FMI 3.0 standard.
        pub unsafe fn $fn_name(c: Fmi3Instance) -> RawStatus {
            // SAFETY: `c` is NULL or a live instance (this function's contract).
            unsafe { with(c, $c_name, |w| w.instance.$method()) }
        }
    )*};
}

simple! {
    /// `fmi3ExitInitializationMode`: the model reads its parameters; the instance is in step mode.
    exit_initialization_mode => exit_initialization_mode, "fmi3ExitInitializationMode";
    /// `fmi3Terminate`.
    terminate => terminate, "fmi3Terminate";
    /// `fmi3Reset`.
    reset => reset, "fmi3Reset";
}

/// The part every `fmi3Get<Type>` shares: the arrays from their pointers, the value
/// references checked against `ty` and translated into `w.scratch`, then `read` fills `out`.
///
/// # Safety
/// `c` as in the FMI 3.0 standard; `vr` is NULL or `n` value references and `values` NULL or
/// room for `n_values` values, the host's for the call.
#[allow(clippy::too_many_arguments)] // the C arguments, and what differs per type
unsafe fn get_values<T>(
    c: Fmi3Instance,
    function: &str,
    ty: Fmi3Type,
    vr: *const u32,
    n: usize,
    values: *mut T,
    n_values: usize,
    read: impl FnOnce(&mut Wrapper, &mut [T]) -> Status,
) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `vr` is NULL or `n` value references and `values`
    // NULL or room for `n_values` values, the host's for the call (this function's contract),
    // which is what `slice` and `slice_mut` ask.
    unsafe {
        with(c, function, |w| match (slice(vr, n), slice_mut(values, n_values)) {
            (Some(vr), Some(out)) => match w.translate(function, ty, vr, out.len()) {
                Ok(()) => read(w, out),
                Err(s) => s,
            },
            _ => null_argument(w, function, "valueReferences[] or values[]"),
        })
    }
}

/// As [`get_values`] for `fmi3Set<Type>`: `write` gets the host's value references (for
/// messages) and values.
///
/// # Safety
/// `c` as in the FMI 3.0 standard; `vr` is NULL or `n` value references and `values` NULL or
/// `n_values` values, the host's for the call.
#[allow(clippy::too_many_arguments)] // the C arguments, and what differs per type
unsafe fn set_values<T>(
    c: Fmi3Instance,
    function: &str,
    ty: Fmi3Type,
    vr: *const u32,
    n: usize,
    values: *const T,
    n_values: usize,
    write: impl FnOnce(&mut Wrapper, &[u32], &[T]) -> Status,
) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `vr` is NULL or `n` value references and `values`
    // NULL or `n_values` values, the host's for the call (this function's contract), which is
    // what `slice` asks.
    unsafe {
        with(c, function, |w| match (slice(vr, n), slice(values, n_values)) {
            (Some(vr), Some(v)) => match w.translate(function, ty, vr, v.len()) {
                Ok(()) => write(w, vr, v),
                Err(s) => s,
            },
            _ => null_argument(w, function, "valueReferences[] or values[]"),
        })
    }
}

/// `fmi3GetFloat64`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_float64(c: Fmi3Instance, vr: *const u32, n: usize, values: *mut f64, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `get_values` asks.
    unsafe { get_values(c, "fmi3GetFloat64", Fmi3Type::Float64, vr, n, values, n_values, |w, out| w.instance.get_real(&w.scratch, out)) }
}

/// `fmi3SetFloat64`: NaN and infinities are refused, nothing set.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_float64(c: Fmi3Instance, vr: *const u32, n: usize, values: *const f64, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `set_values` asks.
    unsafe { set_values(c, "fmi3SetFloat64", Fmi3Type::Float64, vr, n, values, n_values, |w, _, v| w.instance.set_real(&w.scratch, v)) }
}

/// `fmi3GetInt32`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_int32(c: Fmi3Instance, vr: *const u32, n: usize, values: *mut i32, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `get_values` asks.
    unsafe { get_values(c, "fmi3GetInt32", Fmi3Type::Int32, vr, n, values, n_values, |w, out| w.instance.get_integer(&w.scratch, out)) }
}

/// `fmi3SetInt32`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_int32(c: Fmi3Instance, vr: *const u32, n: usize, values: *const i32, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `set_values` asks.
    unsafe { set_values(c, "fmi3SetInt32", Fmi3Type::Int32, vr, n, values, n_values, |w, _, v| w.instance.set_integer(&w.scratch, v)) }
}

/// `fmi3GetInt64`: the enumeration variables.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_int64(c: Fmi3Instance, vr: *const u32, n: usize, values: *mut i64, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `get_values` asks.
    unsafe {
        get_values(c, "fmi3GetInt64", Fmi3Type::Enumeration, vr, n, values, n_values, |w, out| {
            let mut narrow = vec![0i32; out.len()];
            let s = w.instance.get_integer(&w.scratch, &mut narrow);
            if s == Status::Ok {
                for (o, v) in out.iter_mut().zip(narrow) {
                    *o = i64::from(v);
                }
            }
            s
        })
    }
}

/// `fmi3SetInt64`: the enumeration variables, each only to one of its type's items.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_int64(c: Fmi3Instance, vr: *const u32, n: usize, values: *const i64, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `set_values` asks.
    unsafe {
        set_values(c, "fmi3SetInt64", Fmi3Type::Enumeration, vr, n, values, n_values, |w, vr, v| {
            let mut narrow = Vec::with_capacity(v.len());
            for (&x, &r) in v.iter().zip(vr) {
                match i32::try_from(x) {
                    Ok(x) => narrow.push(x),
                    Err(_) => {
                        let name = &w.instance.description().variables[r as usize].name;
                        return w.instance.error(&format!("fmi3SetInt64: {x} is not an item of '{name}'; nothing was set"));
                    }
                }
            }
            w.instance.set_integer(&w.scratch, &narrow)
        })
    }
}

/// `fmi3GetBoolean`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_boolean(c: Fmi3Instance, vr: *const u32, n: usize, values: *mut bool, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `get_values` asks.
    unsafe { get_values(c, "fmi3GetBoolean", Fmi3Type::Boolean, vr, n, values, n_values, |w, out| w.instance.get_boolean(&w.scratch, out)) }
}

/// `fmi3SetBoolean`. Each value is read as a byte (any non-zero byte is true), so a host's
/// `bool` outside 0 and 1 cannot make an invalid Rust `bool`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_boolean(c: Fmi3Instance, vr: *const u32, n: usize, values: *const u8, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `set_values` asks; the values are read as bytes, so no invalid `bool` is made.
    unsafe {
        set_values(c, "fmi3SetBoolean", Fmi3Type::Boolean, vr, n, values, n_values, |w, _, v| {
            let b: Vec<bool> = v.iter().map(|&x| x != 0).collect();
            w.instance.set_boolean(&w.scratch, &b)
        })
    }
}

/// `fmi3GetString`: the strings stay valid until the next call on this instance.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_string(c: Fmi3Instance, vr: *const u32, n: usize, values: *mut *const c_char, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `get_values` asks. The pointers written point into `w.strings`, which outlives the call
    // as the standard asks.
    unsafe {
        get_values(c, "fmi3GetString", Fmi3Type::String, vr, n, values, n_values, |w, out| {
            let mut s = vec![String::new(); out.len()];
            let status = w.instance.get_string(&w.scratch, &mut s);
            if status == Status::Ok {
                w.strings = s.into_iter().map(|x| CString::new(x.replace('\0', "")).expect("NULs removed")).collect();
                for (o, cs) in out.iter_mut().zip(&w.strings) {
                    *o = cs.as_ptr();
                }
            }
            status
        })
    }
}

/// `fmi3SetString`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn set_string(c: Fmi3Instance, vr: *const u32, n: usize, values: *const *const c_char, n_values: usize) -> RawStatus {
    // SAFETY: arguments as in the FMI 3.0 standard (this function's contract), which is what
    // `set_values` asks; each value is NULL or a NUL-terminated string for the call, copied
    // before it returns.
    unsafe {
        set_values(c, "fmi3SetString", Fmi3Type::String, vr, n, values, n_values, |w, _, v| {
            let mut strings = Vec::with_capacity(v.len());
            for &p in v {
                match str_arg(p) {
                    Some(s) => strings.push(s.to_owned()),
                    None => return w.instance.error("fmi3SetString: a value is NULL or not UTF-8; nothing was set"),
                }
            }
            w.instance.set_string(&w.scratch, &strings)
        })
    }
}

/// The getters and setters of the types this FMU has no variables of (`fmi3GetFloat32`,
/// `fmi3SetUInt8`, `fmi3GetBinary`, `fmi3GetClock`, …): `fmi3OK` for no value references in a
/// state that allows the call, else `fmi3Error` naming the first reference and what it is.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn no_such_type(c: Fmi3Instance, function: &str, type_name: &str, setter: bool, vr: *const u32, n: usize) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `vr` is NULL or `n` value references of the
    // host's for the call (this function's contract); the values are never touched.
    unsafe {
        with(c, function, |w| {
            let phase = if setter { Function::SetOther } else { Function::GetValues };
            if let Err(s) = w.instance.check_phase(function, phase) {
                return s;
            }
            let Some(vr) = slice(vr, n) else { return null_argument(w, function, "valueReferences[]") };
            match vr.first() {
                None => Status::Ok,
                Some(&r) => match w.variables.get(r) {
                    Some((t, _)) => {
                        let name = &w.instance.description().variables[r as usize].name;
                        w.instance.error(&format!("{function}: value reference {r} ('{name}') is a {} variable, not {type_name}", t.name()))
                    }
                    None => w.instance.error(&format!("{function}: unknown value reference {r} (this FMU has no {type_name} variables)")),
                },
            }
        })
    }
}

/// `fmi3GetFMUState`: a new state, or the one `*state` points to overwritten.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn get_fmu_state(c: Fmi3Instance, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `state` is NULL or the host's handle, readable
    // and writable for the call (this function's contract), as `raw::get_fmu_state` asks.
    unsafe { with(c, "fmi3GetFMUState", |w| raw::get_fmu_state(&mut w.instance, state)) }
}

/// `fmi3SetFMUState`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard: `state` from this FMU.
pub unsafe fn set_fmu_state(c: Fmi3Instance, state: FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance (this function's contract); `state` is a number,
    // never read through.
    unsafe { with(c, "fmi3SetFMUState", |w| raw::set_fmu_state(&mut w.instance, state)) }
}

/// `fmi3FreeFMUState`: frees `*state` and sets it to NULL.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn free_fmu_state(c: Fmi3Instance, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `state` is NULL or the host's handle, readable
    // and writable for the call (this function's contract), as `raw::free_fmu_state` asks.
    unsafe { with(c, "fmi3FreeFMUState", |w| raw::free_fmu_state(&mut w.instance, state)) }
}

/// `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn serialized_fmu_state_size(c: Fmi3Instance, state: FmuState, size: *mut usize) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `size` is NULL or the host's writable `size_t`
    // for the call (this function's contract), as `raw::serialized_fmu_state_size` asks.
    unsafe { with(c, "fmi3SerializedFMUStateSize", |w| raw::serialized_fmu_state_size(&mut w.instance, state, size)) }
}

/// `fmi3SerializeFMUState`: `size` must be what `fmi3SerializedFMUStateSize` said.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn serialize_fmu_state(c: Fmi3Instance, state: FmuState, out: *mut u8, size: usize) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `out` is NULL or `size` writable bytes of the
    // host's for the call (this function's contract), as `raw::serialize_fmu_state` asks.
    unsafe { with(c, "fmi3SerializeFMUState", |w| raw::serialize_fmu_state(&mut w.instance, state, out, size)) }
}

/// `fmi3DeserializeFMUState`: a truncated, altered or foreign buffer is refused.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
pub unsafe fn deserialize_fmu_state(c: Fmi3Instance, bytes: *const u8, size: usize, state: *mut FmuState) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; `bytes` is NULL or `size` readable bytes and
    // `state` NULL or the host's readable and writable handle, for the call (this function's
    // contract), as `raw::deserialize_fmu_state` asks.
    unsafe { with(c, "fmi3DeserializeFMUState", |w| raw::deserialize_fmu_state(&mut w.instance, bytes, size, state)) }
}

/// `fmi3DoStep` from `current` [s] by `step` [s]. No event handling and no early return are
/// ever needed; `terminateSimulation` is true when the model asked to end the simulation
/// (`fmi3Discard` if it did so at the step's start, `fmi3OK` if after taking the step);
/// `lastSuccessfulTime` is the instance's time after the call.
///
/// # Safety
/// Arguments as in the FMI 3.0 standard.
#[allow(clippy::too_many_arguments)] // mirrors the C signature
pub unsafe fn do_step(
    c: Fmi3Instance,
    current: f64,
    step: f64,
    _no_set_fmu_state_prior: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance; the four output pointers are NULL (checked before
    // any write) or the host's writable variables for the call (this function's contract).
    unsafe {
        with(c, "fmi3DoStep", |w| {
            if event_handling_needed.is_null() || terminate_simulation.is_null() || early_return.is_null() || last_successful_time.is_null()
            {
                return null_argument(w, "fmi3DoStep", "eventHandlingNeeded, terminateSimulation, earlyReturn or lastSuccessfulTime");
            }
            let s = w.instance.do_step(current, step);
            *event_handling_needed = false;
            *early_return = false;
            let terminated = s == Status::Discard && w.instance.terminated_status().unwrap_or(false);
            *terminate_simulation = terminated;
            *last_successful_time = w.instance.time();
            // A step taken in full before the request to end (ModelError::finish) completed:
            // fmi3OK with terminateSimulation, where FMI 2.0 can only say fmi2Discard.
            if terminated && w.instance.time() > current {
                Status::Ok
            } else {
                s
            }
        })
    }
}

/// A function this FMU does not offer: logs `why` and returns `fmi3Error`.
///
/// # Safety
/// `c` as in the FMI 3.0 standard.
pub unsafe fn unsupported(c: Fmi3Instance, name: &str, why: &str) -> RawStatus {
    // SAFETY: `c` is NULL or a live instance (this function's contract).
    unsafe { with(c, name, |w| w.instance.error(&format!("{name}: not supported: {why}"))) }
}

/// The reason logged by the functions of event mode and clocks.
pub const NO_EVENT_MODE: &str = "this FMU has no event mode and no clocks (hasEventMode=\"false\")";
/// The reason logged by the functions of Model Exchange.
pub const CO_SIMULATION_ONLY: &str = "this FMU supports only Co-Simulation";

/// Emits every `fmi3*` function of the FMI 3.0 C API as an `extern "C"` symbol serving the
/// models `factory` makes (a [`ModelFactory`](crate::ModelFactory)): Co-Simulation
/// through the shared instance; the functions of the other interfaces log why they are not
/// offered and return `fmi3Error` (or NULL). A library may also carry `export_fmi2!`'s symbols:
/// the names do not clash, so one binary can serve an FMU's FMI 2.0 and FMI 3.0 twins.
#[macro_export]
macro_rules! export_fmi3 {
    ($factory:path) => {
        #[doc(hidden)]
        const __FMI3_EXPORT_FACTORY: $crate::ModelFactory = $factory;

        #[doc(hidden)]
        #[allow(clippy::missing_safety_doc, clippy::too_many_arguments)]
        mod fmi3_exports {
            use std::ffi::{c_char, c_int, c_void};
            use $crate::fmi3::abi::{
                self, ClockUpdate, Fmi3Instance, FmuState, IntermediateUpdate, LogMessage, Preemption, RawStatus, CO_SIMULATION_ONLY,
                NO_EVENT_MODE,
            };

            #[no_mangle]
            pub extern "C" fn fmi3GetVersion() -> *const c_char {
                c"3.0".as_ptr()
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetDebugLogging(c: Fmi3Instance, on: bool, n: usize, cats: *const *const c_char) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_debug_logging(c, on, n, cats) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateModelExchange(
                _name: *const c_char,
                _token: *const c_char,
                _resources: *const c_char,
                _visible: bool,
                _logging_on: bool,
                env: *mut c_void,
                log: Option<LogMessage>,
            ) -> Fmi3Instance {
                // SAFETY: `log` is NULL or the host's logger for `env` (the FMI 3.0 standard); nothing
                // else is read.
                unsafe { abi::instantiate_other("fmi3InstantiateModelExchange", env, log) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
                name: *const c_char,
                token: *const c_char,
                resources: *const c_char,
                visible: bool,
                logging_on: bool,
                event_mode_used: bool,
                early_return_allowed: bool,
                required: *const u32,
                n_required: usize,
                env: *mut c_void,
                log: Option<LogMessage>,
                _intermediate_update: Option<IntermediateUpdate>,
            ) -> Fmi3Instance {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged with this library's factory; `intermediate_update` is never called.
                unsafe {
                    abi::instantiate_co_simulation(
                        super::__FMI3_EXPORT_FACTORY,
                        name,
                        token,
                        resources,
                        visible,
                        logging_on,
                        event_mode_used,
                        early_return_allowed,
                        required,
                        n_required,
                        env,
                        log,
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
                _name: *const c_char,
                _token: *const c_char,
                _resources: *const c_char,
                _visible: bool,
                _logging_on: bool,
                env: *mut c_void,
                log: Option<LogMessage>,
                _clock_update: Option<ClockUpdate>,
                _lock: Option<Preemption>,
                _unlock: Option<Preemption>,
            ) -> Fmi3Instance {
                // SAFETY: `log` is NULL or the host's logger for `env` (the FMI 3.0 standard); nothing
                // else is read.
                unsafe { abi::instantiate_other("fmi3InstantiateScheduledExecution", env, log) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeInstance(c: Fmi3Instance) {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::free_instance(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterInitializationMode(
                c: Fmi3Instance,
                td: bool,
                tol: f64,
                start: f64,
                sd: bool,
                stop: f64,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::enter_initialization_mode(c, td, tol, start, sd, stop) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitInitializationMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::exit_initialization_mode(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterEventMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3EnterEventMode", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Terminate(c: Fmi3Instance) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::terminate(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3Reset(c: Fmi3Instance) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::reset(c) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFloat64(c: Fmi3Instance, vr: *const u32, n: usize, v: *mut f64, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_float64(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFloat64(c: Fmi3Instance, vr: *const u32, n: usize, v: *const f64, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_float64(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetInt32(c: Fmi3Instance, vr: *const u32, n: usize, v: *mut i32, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_int32(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetInt32(c: Fmi3Instance, vr: *const u32, n: usize, v: *const i32, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_int32(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetInt64(c: Fmi3Instance, vr: *const u32, n: usize, v: *mut i64, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_int64(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetInt64(c: Fmi3Instance, vr: *const u32, n: usize, v: *const i64, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_int64(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetBoolean(c: Fmi3Instance, vr: *const u32, n: usize, v: *mut bool, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_boolean(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetBoolean(c: Fmi3Instance, vr: *const u32, n: usize, v: *const bool, nv: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged; the values are read as bytes, so a host's `bool` other than 0 or 1
                // makes no invalid Rust `bool`.
                unsafe { abi::set_boolean(c, vr, n, v.cast::<u8>(), nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetString(
                c: Fmi3Instance,
                vr: *const u32,
                n: usize,
                v: *mut *const c_char,
                nv: usize,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_string(c, vr, n, v, nv) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetString(
                c: Fmi3Instance,
                vr: *const u32,
                n: usize,
                v: *const *const c_char,
                nv: usize,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_string(c, vr, n, v, nv) }
            }
            $crate::__fmi3_no_such_type! {
                fmi3GetFloat32 "Float32" get f32;
                fmi3GetInt8 "Int8" get i8;
                fmi3GetUInt8 "UInt8" get u8;
                fmi3GetInt16 "Int16" get i16;
                fmi3GetUInt16 "UInt16" get u16;
                fmi3GetUInt32 "UInt32" get u32;
                fmi3GetUInt64 "UInt64" get u64;
                fmi3SetFloat32 "Float32" set f32;
                fmi3SetInt8 "Int8" set i8;
                fmi3SetUInt8 "UInt8" set u8;
                fmi3SetInt16 "Int16" set i16;
                fmi3SetUInt16 "UInt16" set u16;
                fmi3SetUInt32 "UInt32" set u32;
                fmi3SetUInt64 "UInt64" set u64;
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetBinary(
                c: Fmi3Instance,
                vr: *const u32,
                n: usize,
                _sizes: *mut usize,
                _v: *mut *const u8,
                _nv: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
                // 3.0 standard); the values are never touched.
                unsafe { abi::no_such_type(c, "fmi3GetBinary", "Binary", false, vr, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetBinary(
                c: Fmi3Instance,
                vr: *const u32,
                n: usize,
                _sizes: *const usize,
                _v: *const *const u8,
                _nv: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
                // 3.0 standard); the values are never touched.
                unsafe { abi::no_such_type(c, "fmi3SetBinary", "Binary", true, vr, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetClock(c: Fmi3Instance, vr: *const u32, n: usize, _v: *mut bool) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
                // 3.0 standard); the values are never touched.
                unsafe { abi::no_such_type(c, "fmi3GetClock", "Clock", false, vr, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetClock(c: Fmi3Instance, vr: *const u32, n: usize, _v: *const bool) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
                // 3.0 standard); the values are never touched.
                unsafe { abi::no_such_type(c, "fmi3SetClock", "Clock", true, vr, n) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(c: Fmi3Instance, _vr: u32, _n: *mut usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe {
                    abi::unsupported(
                        c,
                        "fmi3GetNumberOfVariableDependencies",
                        "the dependencies are in modelDescription.xml (providesPerElementDependencies=\"false\")",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetVariableDependencies(
                c: Fmi3Instance,
                _dependent: u32,
                _element_dependent: *mut usize,
                _independents: *mut u32,
                _element_independents: *mut usize,
                _kinds: *mut c_int,
                _n: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe {
                    abi::unsupported(
                        c,
                        "fmi3GetVariableDependencies",
                        "the dependencies are in modelDescription.xml (providesPerElementDependencies=\"false\")",
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetFMUState(c: Fmi3Instance, s: *mut FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::get_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetFMUState(c: Fmi3Instance, s: FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::set_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3FreeFMUState(c: Fmi3Instance, s: *mut FmuState) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::free_fmu_state(c, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializedFMUStateSize(c: Fmi3Instance, s: FmuState, size: *mut usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::serialized_fmu_state_size(c, s, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SerializeFMUState(c: Fmi3Instance, s: FmuState, out: *mut u8, size: usize) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::serialize_fmu_state(c, s, out, size) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3DeserializeFMUState(
                c: Fmi3Instance,
                bytes: *const u8,
                size: usize,
                s: *mut FmuState,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe { abi::deserialize_fmu_state(c, bytes, size, s) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
                c: Fmi3Instance,
                _unknowns: *const u32,
                _n_unknowns: usize,
                _knowns: *const u32,
                _n_knowns: usize,
                _seed: *const f64,
                _n_seed: usize,
                _sensitivity: *mut f64,
                _n_sensitivity: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetDirectionalDerivative", "providesDirectionalDerivatives is false") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetAdjointDerivative(
                c: Fmi3Instance,
                _unknowns: *const u32,
                _n_unknowns: usize,
                _knowns: *const u32,
                _n_knowns: usize,
                _seed: *const f64,
                _n_seed: usize,
                _sensitivity: *mut f64,
                _n_sensitivity: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetAdjointDerivative", "providesAdjointDerivatives is false") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterConfigurationMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3EnterConfigurationMode", "this FMU has no structural parameters") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ExitConfigurationMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3ExitConfigurationMode", "this FMU has no structural parameters") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetIntervalDecimal(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _i: *mut f64,
                _q: *mut c_int,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetIntervalDecimal", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetIntervalFraction(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _counters: *mut u64,
                _r: *mut u64,
                _q: *mut c_int,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetIntervalFraction", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetShiftDecimal(c: Fmi3Instance, _vr: *const u32, _n: usize, _s: *mut f64) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetShiftDecimal", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetShiftFraction(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _counters: *mut u64,
                _r: *mut u64,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetShiftFraction", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetIntervalDecimal(c: Fmi3Instance, _vr: *const u32, _n: usize, _i: *const f64) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetIntervalDecimal", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetIntervalFraction(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _counters: *const u64,
                _r: *const u64,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetIntervalFraction", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetShiftDecimal(c: Fmi3Instance, _vr: *const u32, _n: usize, _s: *const f64) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetShiftDecimal", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetShiftFraction(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _counters: *const u64,
                _r: *const u64,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetShiftFraction", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3EvaluateDiscreteStates", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
                c: Fmi3Instance,
                _discrete_states_need_update: *mut bool,
                _terminate: *mut bool,
                _nominals_changed: *mut bool,
                _values_changed: *mut bool,
                _next_event_time_defined: *mut bool,
                _next_event_time: *mut f64,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3UpdateDiscreteStates", NO_EVENT_MODE) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3EnterContinuousTimeMode", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
                c: Fmi3Instance,
                _no_prior: bool,
                _enter_event_mode: *mut bool,
                _terminate: *mut bool,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3CompletedIntegratorStep", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetTime(c: Fmi3Instance, _time: f64) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetTime", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3SetContinuousStates(c: Fmi3Instance, _x: *const f64, _n: usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3SetContinuousStates", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(c: Fmi3Instance, _dx: *mut f64, _n: usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetContinuousStateDerivatives", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetEventIndicators(c: Fmi3Instance, _z: *mut f64, _n: usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetEventIndicators", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetContinuousStates(c: Fmi3Instance, _x: *mut f64, _n: usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetContinuousStates", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(c: Fmi3Instance, _x: *mut f64, _n: usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetNominalsOfContinuousStates", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(c: Fmi3Instance, _n: *mut usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetNumberOfEventIndicators", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: Fmi3Instance, _n: *mut usize) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetNumberOfContinuousStates", CO_SIMULATION_ONLY) }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3EnterStepMode(c: Fmi3Instance) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3EnterStepMode", "event mode is not used: fmi3ExitInitializationMode enters step mode") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3GetOutputDerivatives(
                c: Fmi3Instance,
                _vr: *const u32,
                _n: usize,
                _orders: *const i32,
                _v: *mut f64,
                _nv: usize,
            ) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0") }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3DoStep(
                c: Fmi3Instance,
                current: f64,
                step: f64,
                no_prior: bool,
                event_handling_needed: *mut bool,
                terminate_simulation: *mut bool,
                early_return: *mut bool,
                last_successful_time: *mut f64,
            ) -> RawStatus {
                // SAFETY: the host's arguments, valid as the FMI 3.0 standard says (see `abi`), passed
                // on unchanged.
                unsafe {
                    abi::do_step(
                        c,
                        current,
                        step,
                        no_prior,
                        event_handling_needed,
                        terminate_simulation,
                        early_return,
                        last_successful_time,
                    )
                }
            }
            #[no_mangle]
            pub unsafe extern "C" fn fmi3ActivateModelPartition(c: Fmi3Instance, _clock: u32, _time: f64) -> RawStatus {
                // SAFETY: `c` is NULL or a live instance (the FMI 3.0 standard); nothing else is read.
                unsafe { abi::unsupported(c, "fmi3ActivateModelPartition", "this FMU supports only Co-Simulation") }
            }
        }
    };
}

/// The getters and setters of types without variables, for [`export_fmi3!`].
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_no_such_type {
    ($($name:ident $type_name:literal $dir:ident $t:ty;)*) => {$(
        $crate::__fmi3_no_such_type!(@one $name $type_name $dir $t);
    )*};
    (@one $name:ident $type_name:literal get $t:ty) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: Fmi3Instance, vr: *const u32, n: usize, _v: *mut $t, _nv: usize) -> RawStatus {
            // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
            // 3.0 standard); the values are never touched.
            unsafe { abi::no_such_type(c, stringify!($name), $type_name, false, vr, n) }
        }
    };
    (@one $name:ident $type_name:literal set $t:ty) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: Fmi3Instance, vr: *const u32, n: usize, _v: *const $t, _nv: usize) -> RawStatus {
            // SAFETY: `c` is NULL or a live instance and `vr` NULL or `n` value references (the FMI
            // 3.0 standard); the values are never touched.
            unsafe { abi::no_such_type(c, stringify!($name), $type_name, true, vr, n) }
        }
    };
}
