//! What the FMI 2.0 and FMI 3.0 C APIs share below their own names: arrays from the
//! pointers and lengths a host passes, and the FMU-state functions (get, set, free,
//! serialise), which are the same calls on an [`Instance`] in both versions. Messages name
//! the function of the instance's API ([`Instance::api`]).

use std::ffi::{c_char, c_int, c_void, CStr};

use crate::instance::{Api, Function, Instance, Phase, StateHandle, Status};

/// An FMU state handle as both C APIs pass it (`fmi2FMUstate`, `fmi3FMUState`): a
/// [`StateHandle`] of the instance, never an address (the instance keeps its states and frees
/// those left with it).
pub type FmuState = *mut c_void;

/// A string argument, or `None` for NULL or text that is not UTF-8.
///
/// # Safety
/// `p` is NULL or a NUL-terminated C string, unchanged while the returned reference lives.
pub unsafe fn str_arg<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        // SAFETY: `p` is not NULL, so by this function's contract it is a NUL-terminated
        // string that stays valid and unchanged for 'a.
        unsafe { CStr::from_ptr(p) }.to_str().ok()
    }
}

/// The array at `p` of `n` elements; empty for `n == 0` whatever `p` is, `None` for NULL.
///
/// # Safety
/// A non-null `p` points to an array of `n` initialised, aligned elements (a C array the
/// host owns), not written while the returned slice lives.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: `p` is not NULL and `n > 0`, so by this function's contract it is the
        // start of `n` initialised, aligned elements that stay valid and unwritten for 'a.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// As [`slice`], writable.
///
/// # Safety
/// A non-null `p` points to an array of `n` initialised, aligned, writable elements (a C
/// array the host owns), reached through no other pointer while the returned slice lives.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: `p` is not NULL and `n > 0`, so by this function's contract it is the
        // start of `n` initialised, aligned, writable elements, used only through this slice for 'a.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// Why an instantiate function of either API returns NULL: the text it logs, after the
/// function's name.
#[derive(Debug, thiserror::Error)]
pub enum Refused {
    /// No usable instance name; the payload is the version's rule.
    #[error("the instance name is NULL, empty, white space only or not UTF-8 ({0})")]
    Name(&'static str),
    /// FMI 2.0: a model type other than co-simulation.
    #[error("fmuType {0} requested, this FMU supports only fmi2CoSimulation (1)")]
    FmuType(c_int),
    /// FMI 3.0: event mode asked for.
    #[error("eventModeUsed is true, but this FMU has no event mode (hasEventMode=\"false\")")]
    EventMode,
    /// The named string argument (GUID, instantiation token) is NULL or not UTF-8.
    #[error("the {0} is NULL or not UTF-8")]
    NullOrNotUtf8(&'static str),
    /// The named string argument (resource location or path) is not UTF-8.
    #[error("the {0} is not UTF-8")]
    NotUtf8(&'static str),
    /// FMI 2.0: the resource location names no local folder.
    #[error(transparent)]
    ResourceUri(#[from] crate::uri::ResourceUriError),
    /// FMI 3.0: the instantiation token is not the model's.
    #[error(
        "instantiation token {given} does not match this FMU's {expected}: the modelDescription.xml and the binary or resources differ"
    )]
    WrongToken {
        /// The token the host passed.
        given: String,
        /// The model's.
        expected: String,
    },
    /// The instance refuses its arguments.
    #[error(transparent)]
    Instance(#[from] crate::instance::InstantiateError),
    /// The model factory failed.
    #[error("{0}")]
    Model(crate::ModelError),
}

/// Logs that argument(s) `what` of `function` (an FMI 2.0 name) were NULL; `Error`.
pub fn null_argument(instance: &Instance, function: &str, what: &str) -> Status {
    instance.error(&format!("{}: {what} is NULL", instance.api().name(function)))
}

/// The standard's spelling of the state argument in messages.
fn state_word(instance: &Instance) -> &'static str {
    match instance.api() {
        Api::Fmi2 => "FMUstate",
        Api::Fmi3 => "FMUState",
    }
}

/// The handle `*state` holds on entry: `None` for NULL (a new state is wanted).
///
/// # Safety
/// `state` points to a readable, aligned handle.
unsafe fn handle_in(state: *mut FmuState) -> Option<StateHandle> {
    // SAFETY: `state` points to a readable handle (this function's contract).
    let handle = unsafe { *state } as StateHandle;
    (handle != 0).then_some(handle)
}

/// Get FMU state: a new state in `*state`, or the one it holds (a state of this instance)
/// overwritten.
///
/// # Safety
/// `state` is NULL or points to a readable and writable handle, for the call.
pub unsafe fn get_fmu_state(instance: &mut Instance, state: *mut FmuState) -> Status {
    if state.is_null() {
        return null_argument(instance, "fmi2GetFMUstate", state_word(instance));
    }
    // SAFETY: `state` is not NULL, so it points to the host's handle, readable and
    // writable for this call (this function's contract).
    let held = unsafe { handle_in(state) };
    match instance.save_state(held) {
        Ok(handle) => {
            // SAFETY: as above: `state` is the host's writable handle.
            unsafe { *state = handle as FmuState };
            Status::Ok
        }
        Err(s) => s,
    }
}

/// Set FMU state: `state` must be a handle this instance gave out and has not freed; the
/// handle is a number, never read through.
pub fn set_fmu_state(instance: &mut Instance, state: FmuState) -> Status {
    if state.is_null() {
        return null_argument(instance, "fmi2SetFMUstate", state_word(instance));
    }
    instance.restore_state(state as StateHandle)
}

/// Free FMU state: frees `*state` (a state of this instance) and sets it to NULL; NULL or a
/// pointer to NULL is nothing to free.
///
/// # Safety
/// `state` is NULL or points to a readable and writable handle, for the call.
pub unsafe fn free_fmu_state(instance: &mut Instance, state: *mut FmuState) -> Status {
    if let Err(s) = instance.check_phase("fmi2FreeFMUstate", Function::FmuState) {
        return s;
    }
    if state.is_null() {
        return Status::Ok;
    }
    // SAFETY: `state` is not NULL, so it points to the host's handle, readable and writable
    // for this call (this function's contract).
    let Some(handle) = (unsafe { handle_in(state) }) else { return Status::Ok };
    let status = instance.free_state(handle);
    if status == Status::Ok {
        // SAFETY: as above: `state` is the host's writable handle.
        unsafe { *state = std::ptr::null_mut() };
    }
    status
}

/// Serialised FMU state size [bytes] into `*size`.
///
/// # Safety
/// `size` is NULL or writable.
pub unsafe fn serialized_fmu_state_size(instance: &mut Instance, state: FmuState, size: *mut usize) -> Status {
    if state.is_null() || size.is_null() {
        return null_argument(instance, "fmi2SerializedFMUstateSize", &format!("{} or size", state_word(instance)));
    }
    match instance.serialize_state(state as StateHandle) {
        Ok(bytes) => {
            // SAFETY: `size` is not NULL, so it is the host's writable `size_t` (this
            // function's contract).
            unsafe { *size = bytes.len() };
            Status::Ok
        }
        Err(s) => s,
    }
}

/// Serialise FMU state into `out`, whose `size` must be the one the size function gave.
///
/// # Safety
/// `out` is NULL or `size` writable bytes.
pub unsafe fn serialize_fmu_state(instance: &mut Instance, state: FmuState, out: *mut u8, size: usize) -> Status {
    // SAFETY: `out` is NULL (refused by `slice_mut`) or the host's buffer of `size` writable
    // bytes for this call (this function's contract).
    let out = unsafe { slice_mut(out, size) };
    let (false, Some(out)) = (state.is_null(), out) else {
        return null_argument(instance, "fmi2SerializeFMUstate", &format!("{} or serializedState", state_word(instance)));
    };
    match instance.serialize_state(state as StateHandle) {
        Ok(bytes) if bytes.len() == out.len() => {
            out.copy_from_slice(&bytes);
            Status::Ok
        }
        Ok(bytes) => instance.error(&format!(
            "{}: size {size} given, the state needs {} bytes",
            instance.api().name("fmi2SerializeFMUstate"),
            bytes.len()
        )),
        Err(s) => s,
    }
}

/// Deserialise FMU state: a truncated, altered or foreign buffer is refused; the state goes to
/// a new handle in `*state`, or overwrites the state of this instance it holds.
///
/// # Safety
/// `bytes` is NULL or `size` readable bytes; `state` is NULL or points to a readable and
/// writable handle; both for the call.
pub unsafe fn deserialize_fmu_state(instance: &mut Instance, bytes: *const u8, size: usize, state: *mut FmuState) -> Status {
    // SAFETY: `bytes` is NULL (refused by `slice`) or the host's `size` readable bytes for
    // this call (this function's contract).
    let bytes = unsafe { slice(bytes, size) };
    let (Some(bytes), false) = (bytes, state.is_null()) else {
        return null_argument(instance, "fmi2DeSerializeFMUstate", &format!("serializedState or {}", state_word(instance)));
    };
    // SAFETY: `state` is not NULL, so it points to the host's handle, readable and writable
    // for this call (this function's contract).
    let held = unsafe { handle_in(state) };
    match instance.deserialize_state(bytes, held) {
        Ok(handle) => {
            // SAFETY: as above: `state` is the host's writable handle.
            unsafe { *state = handle as FmuState };
            Status::Ok
        }
        Err(s) => s,
    }
}

thread_local! {
    /// Set while [`catch_panic`] runs its closure on this thread: a panic then is the FMU's to
    /// report through the host's logger, not on the host's stderr.
    static CATCHING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Where the last panic caught on this thread happened. Plain bytes, not a `String`: a
    /// thread-local that needs dropping makes std allocate its destructor list, a block left
    /// behind when the host unloads the library.
    static PANIC_AT: std::cell::Cell<Place> = const { std::cell::Cell::new(Place::NONE) };
}

/// A source location kept without allocating: the file name's first bytes and the line.
#[derive(Clone, Copy)]
struct Place {
    file: [u8; 112],
    len: u8,
    line: u32,
}

impl Place {
    const NONE: Place = Place { file: [0; 112], len: 0, line: 0 };

    fn of(location: &std::panic::Location<'_>) -> Place {
        let mut place = Place { line: location.line(), ..Place::NONE };
        let name = location.file().as_bytes();
        let n = name.len().min(place.file.len());
        place.file[..n].copy_from_slice(&name[..n]);
        place.len = n as u8;
        place
    }

    /// `file:line`, or nothing when no place was noted.
    fn text(&self) -> String {
        match self.len {
            0 => String::new(),
            n => format!("{}:{}", String::from_utf8_lossy(&self.file[..n as usize]), self.line),
        }
    }
}

/// A panic hook as `std::panic::take_hook` returns it.
type Hook = Box<dyn Fn(&std::panic::PanicHookInfo<'_>) + Sync + Send + 'static>;

/// Installs, once, a panic hook that keeps panics inside [`catch_panic`] off stderr (the host's
/// console) and notes where they happened; any other panic goes to the hook that was there.
/// Neither hook owns heap memory of this library (the default hook and a closure that captures
/// nothing are zero-sized), so unloading the library leaves no block behind (valgrind).
fn quiet_caught_panics() {
    static PREVIOUS: std::sync::OnceLock<Hook> = std::sync::OnceLock::new();
    PREVIOUS.get_or_init(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(|info| {
            if CATCHING.with(|c| c.get()) {
                PANIC_AT.with(|p| p.set(info.location().map_or(Place::NONE, Place::of)));
            } else if let Some(previous) = PREVIOUS.get() {
                previous(info);
            }
        }));
        previous
    });
}

/// A panic caught by [`catch_panic`]: its message and, after it, where it happened.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CaughtPanic(String);

/// Runs `body`, turning a panic into its message and place (`Err`), so that no panic unwinds
/// into the host and none is printed on its console: the caller logs it through the host.
pub fn catch_panic<R>(body: impl FnOnce() -> R) -> Result<R, CaughtPanic> {
    quiet_caught_panics();
    let was = CATCHING.with(|c| c.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(body));
    CATCHING.with(|c| c.set(was));
    result.map_err(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        CaughtPanic(match PANIC_AT.with(|p| p.replace(Place::NONE)).text() {
            at if at.is_empty() => message,
            at => format!("{message}, at {at}"),
        })
    })
}

/// What a C handle (`fmi2Component`, `fmi3Instance`) points to: a wrapper around an instance.
pub trait HoldsInstance {
    /// The instance inside.
    fn instance(&mut self) -> &mut Instance;
}

/// The guard around every call of both C APIs that takes an instance: `Error` for NULL, `Fatal`
/// once a panic was caught, a call trace when logging is on, and `body` run so that a panic
/// becomes `Fatal` (logged, the instance then only freed) instead of unwinding into the host.
///
/// # Safety
/// `c` is NULL or a handle the API's instantiate function returned for a `W`, not freed, on
/// which no other call runs meanwhile (FMI allows one call at a time per instance).
pub unsafe fn guarded<W: HoldsInstance>(c: *mut c_void, name: &str, body: impl FnOnce(&mut W) -> Status) -> c_int {
    if c.is_null() {
        return Status::Error as c_int;
    }
    // SAFETY: `c` is not NULL, so it is the `Box<W>` the instantiate function leaked and no
    // free has reclaimed (this function's contract); the host makes one call at a time on
    // an instance, so this is the only reference to it until the call returns.
    let wrapper = unsafe { &mut *(c as *mut W) };
    if wrapper.instance().phase() == Phase::Fatal {
        return Status::Fatal as c_int;
    }
    wrapper.instance().trace(|| name.to_string());
    match catch_panic(|| body(&mut *wrapper)) {
        Ok(s) => s as c_int,
        Err(why) => {
            let instance = wrapper.instance();
            instance.error(&format!("{name}: internal error ({why}); the instance can only be freed"));
            instance.set_fatal();
            Status::Fatal as c_int
        }
    }
}
