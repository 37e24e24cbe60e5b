//! What the FMI 2.0 and FMI 3.0 C APIs share below their own names: arrays from the
//! pointers and lengths a host passes, and the FMU-state functions (get, set, free,
//! serialise), which are the same calls on an [`Instance`] in both versions. Messages name
//! the function of the instance's API ([`Instance::api`]).

use std::ffi::{c_char, c_void, CStr};

use crate::instance::{Api, Function, Instance, Snapshot, Status};

/// An FMU state handle as both C APIs pass it (`fmi2FMUstate`, `fmi3FMUState`): a boxed
/// [`Snapshot`].
pub type FmuState = *mut c_void;

/// A string argument, or `None` for NULL or text that is not UTF-8.
///
/// # Safety
/// `p` is NULL or a valid C string that outlives the returned reference.
pub unsafe fn str_arg<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        unsafe { CStr::from_ptr(p) }.to_str().ok()
    }
}

/// The array at `p` of `n` elements; empty for `n == 0` whatever `p` is, `None` for NULL.
///
/// # Safety
/// A non-null `p` points to `n` valid elements that outlive the returned slice.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// As [`slice`], writable.
///
/// # Safety
/// A non-null `p` points to `n` writable elements, not aliased, that outlive the slice.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
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

unsafe fn store_state(state: *mut FmuState, snap: Snapshot) {
    unsafe {
        if (*state).is_null() {
            *state = Box::into_raw(Box::new(snap)) as FmuState;
        } else {
            *(*state as *mut Snapshot) = snap;
        }
    }
}

/// Get FMU state: a new state in `*state`, or the one it points to overwritten.
///
/// # Safety
/// `state` is NULL or points to NULL or to a state of this FMU.
pub unsafe fn get_fmu_state(instance: &mut Instance, state: *mut FmuState) -> Status {
    if state.is_null() {
        return null_argument(instance, "fmi2GetFMUstate", state_word(instance));
    }
    match instance.get_state() {
        Ok(snap) => {
            unsafe { store_state(state, snap) };
            Status::Ok
        }
        Err(s) => s,
    }
}

/// Set FMU state.
///
/// # Safety
/// `state` is NULL or a state of this FMU (from get or deserialise).
pub unsafe fn set_fmu_state(instance: &mut Instance, state: FmuState) -> Status {
    match unsafe { (state as *const Snapshot).as_ref() } {
        Some(snap) => instance.set_state(snap),
        None => null_argument(instance, "fmi2SetFMUstate", state_word(instance)),
    }
}

/// Free FMU state: frees `*state` and sets it to NULL.
///
/// # Safety
/// `state` is NULL or points to NULL or to a state of this FMU.
pub unsafe fn free_fmu_state(instance: &mut Instance, state: *mut FmuState) -> Status {
    if let Err(s) = instance.check_phase("fmi2FreeFMUstate", Function::FmuState) {
        return s;
    }
    unsafe {
        if !state.is_null() && !(*state).is_null() {
            drop(Box::from_raw(*state as *mut Snapshot));
            *state = std::ptr::null_mut();
        }
    }
    Status::Ok
}

/// Serialised FMU state size [bytes] into `*size`.
///
/// # Safety
/// `state` is NULL or a state of this FMU; `size` is NULL or writable.
pub unsafe fn serialized_fmu_state_size(instance: &mut Instance, state: FmuState, size: *mut usize) -> Status {
    match (unsafe { (state as *const Snapshot).as_ref() }, size.is_null()) {
        (Some(snap), false) => match instance.serialize(snap) {
            Ok(bytes) => {
                unsafe { *size = bytes.len() };
                Status::Ok
            }
            Err(s) => s,
        },
        _ => null_argument(instance, "fmi2SerializedFMUstateSize", &format!("{} or size", state_word(instance))),
    }
}

/// Serialise FMU state into `out`, whose `size` must be the one the size function gave.
///
/// # Safety
/// `state` is NULL or a state of this FMU; `out` is NULL or `size` writable bytes.
pub unsafe fn serialize_fmu_state(instance: &mut Instance, state: FmuState, out: *mut u8, size: usize) -> Status {
    match (unsafe { (state as *const Snapshot).as_ref() }, unsafe { slice_mut(out, size) }) {
        (Some(snap), Some(out)) => match instance.serialize(snap) {
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
        },
        _ => null_argument(instance, "fmi2SerializeFMUstate", &format!("{} or serializedState", state_word(instance))),
    }
}

/// Deserialise FMU state: a truncated, altered or foreign buffer is refused.
///
/// # Safety
/// `bytes` is NULL or `size` readable bytes; `state` is NULL or points to NULL or to a state
/// of this FMU.
pub unsafe fn deserialize_fmu_state(instance: &mut Instance, bytes: *const u8, size: usize, state: *mut FmuState) -> Status {
    match (unsafe { slice(bytes, size) }, state.is_null()) {
        (Some(bytes), false) => match instance.deserialize(bytes) {
            Ok(snap) => {
                unsafe { store_state(state, snap) };
                Status::Ok
            }
            Err(s) => s,
        },
        _ => null_argument(instance, "fmi2DeSerializeFMUstate", &format!("serializedState or {}", state_word(instance))),
    }
}
