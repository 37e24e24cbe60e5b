//! Every function that `export_fmi2!` and `export_fmi3!` generate has the signature its FMI
//! header declares: checked when this test COMPILES, against `fmi-sys` (bindgen over the
//! official `fmi2FunctionTypes.h` and `fmi3FunctionTypes.h`). Each exported function is
//! coerced to a function pointer and related to the header's `fmi…TYPE`, argument by argument
//! and the result, through [`Arg`]; a missing or extra argument, another width, a pointer
//! for a value, `*const` for `*mut`, `bool` for an `int`, fails the build. The checks are
//! `const _` items of this test program: the FMU binaries carry nothing of them.
//!
//! Where the layer declares its own type for one of the header's, the relation lists it:
//! - the header's C enums (`fmi2Status`, `fmi2Type`, `fmi2StatusKind`, `fmi3Status`,
//!   `fmi3DependencyKind`, `fmi3IntervalQualifier`), which bindgen types `c_uint` on this
//!   target (`c_int` on MSVC), are `c_int` in the layer: the same 32 bits for their values
//!   0 to 5. This holds for a signature's own arguments and result, and for an output array
//!   of enum values; never behind other pointers;
//! - `fmi2CallbackFunctions` is the layer's [`CallbackFunctions`], checked below field by
//!   field (type, offset) and as a whole (size, alignment).
//!
//! The last test makes sure the list checked here is the list the macros export.

use std::ffi::{c_int, c_uint, c_void};
use std::path::Path;

use fmi_sys::fmi2::{self as h2, fmi2CallbackFunctions};
use fmi_sys::fmi3 as h3;
use neurarm_fmi_export::fmi2::abi::CallbackFunctions;
use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, StaticModel, TableBuilder, Unit, Values};

/// A pass-through `y = u`, the model the macros below serve.
struct Echo {
    description: ModelDescription,
    u: RealVar,
    y: RealVar,
}

impl StaticModel for Echo {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        values[self.y] = values[self.u];
        Ok(())
    }
}

fn factory(_resources: Option<&Path>) -> Result<Box<dyn Model>, ModelError> {
    let mut b = TableBuilder::new();
    let u = b.input("u", Unit::SECOND, 0.0, "Input");
    let y = b.output("y", Unit::SECOND, "u", &[u]);
    Ok(Box::new(Echo { description: ModelDescription::new("Echo", "y = u", b.finish())?, u, y }))
}

// The exported functions, in modules `fmi2_exports` and `fmi3_exports` of this crate.
neurarm_fmi_export::export_fmi2!(factory);
neurarm_fmi_export::export_fmi3!(factory);

/// `Self`, as the layer writes it inside a C signature, is the header's type `H`: the same
/// type, or the layer's own declaration of it (a pointer to, or a pointer type of, one).
trait Abi<H> {}

/// `Self`, an argument or result type of a C function the layer declares, is the header's
/// `H`: an [`Abi`] pair, or one of the header's C enums (as the module documentation says).
trait Arg<H> {}

/// `Self`, an `extern "C"` function pointer type of the layer, is `H`, the header's pointer
/// type to such a function (bindgen makes each an `Option`, NULL being `None`).
trait Function<H> {}

macro_rules! same {
    ($($t:ty),*) => {$(impl Abi<$t> for $t {})*};
}
same!((), bool, f32, f64, i8, u8, i16, u16, i32, u32, i64, u64, usize, c_void);

impl<T: Abi<H>, H> Abi<*const H> for *const T {}
impl<T: Abi<H>, H> Abi<*mut H> for *mut T {}
impl<F: Function<Option<G>>, G> Abi<Option<G>> for Option<F> {}
impl Abi<fmi2CallbackFunctions> for CallbackFunctions {}

impl<T: Abi<H>, H> Arg<H> for T {}
impl Arg<c_uint> for c_int {}
impl Arg<*mut c_uint> for *mut c_int {}

macro_rules! function {
    ($($a:ident $h:ident),*) => {
        impl<R: Arg<HR>, HR, $($a: Arg<$h>, $h),*> Function<Option<unsafe extern "C" fn($($h),*) -> HR>>
            for unsafe extern "C" fn($($a),*) -> R
        {
        }
    };
}
function!();
function!(A0 H0);
function!(A0 H0, A1 H1);
function!(A0 H0, A1 H1, A2 H2);
function!(A0 H0, A1 H1, A2 H2, A3 H3);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6, A7 H7);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6, A7 H7, A8 H8);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6, A7 H7, A8 H8, A9 H9);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6, A7 H7, A8 H8, A9 H9, A10 H10);
function!(A0 H0, A1 H1, A2 H2, A3 H3, A4 H4, A5 H5, A6 H6, A7 H7, A8 H8, A9 H9, A10 H10, A11 H11);

/// `fmi2CallbackLogger`: printf-style, variadic after the message.
impl<A0: Arg<H0>, H0, A1: Arg<H1>, H1, A2: Arg<H2>, H2, A3: Arg<H3>, H3, A4: Arg<H4>, H4>
    Function<Option<unsafe extern "C" fn(H0, H1, H2, H3, H4, ...)>> for unsafe extern "C" fn(A0, A1, A2, A3, A4, ...)
{
}

/// Compiles only if `F`, an exported function's pointer type, is `H`, its header's type.
const fn conforms<H, F: Function<H>>(_: &F) {}

/// Compiles only if a field of type `T` stands for the header's field of type `H`.
fn same_field<T: Abi<H>, H>(_: &T, _: &H) {}

// `CallbackFunctions` is `fmi2CallbackFunctions`: every field of the header's type, at the
// header's offset, in a struct of the header's size and alignment.
const _: fn(&CallbackFunctions, &fmi2CallbackFunctions) = |ours, header| {
    same_field(&ours.logger, &header.logger);
    same_field(&ours.allocate_memory, &header.allocateMemory);
    same_field(&ours.free_memory, &header.freeMemory);
    same_field(&ours.step_finished, &header.stepFinished);
    same_field(&ours.component_environment, &header.componentEnvironment);
};
const _: () = {
    use std::mem::{align_of, offset_of, size_of};
    assert!(size_of::<CallbackFunctions>() == size_of::<fmi2CallbackFunctions>());
    assert!(align_of::<CallbackFunctions>() == align_of::<fmi2CallbackFunctions>());
    assert!(offset_of!(CallbackFunctions, logger) == offset_of!(fmi2CallbackFunctions, logger));
    assert!(offset_of!(CallbackFunctions, allocate_memory) == offset_of!(fmi2CallbackFunctions, allocateMemory));
    assert!(offset_of!(CallbackFunctions, free_memory) == offset_of!(fmi2CallbackFunctions, freeMemory));
    assert!(offset_of!(CallbackFunctions, step_finished) == offset_of!(fmi2CallbackFunctions, stepFinished));
    assert!(offset_of!(CallbackFunctions, component_environment) == offset_of!(fmi2CallbackFunctions, componentEnvironment));
};

/// For each `name(_, …): TYPE` (one `_` per argument), a `const _` that compiles only if the
/// exported `module::name` conforms to `header::TYPE`; and `list`, the names checked.
macro_rules! check {
    ($list:ident = $module:ident against $header:ident { $($name:ident($($arg:tt),*): $ty:ident;)* }) => {
        $(const _: () = {
            let exported: unsafe extern "C" fn($($arg),*) -> _ = $module::$name;
            conforms::<$header::$ty, _>(&exported);
        };)*
        /// The functions checked against their header types.
        const $list: &[&str] = &[$(stringify!($name)),*];
    };
}

check! { FMI2_CHECKED = fmi2_exports against h2 {
    fmi2GetTypesPlatform(): fmi2GetTypesPlatformTYPE;
    fmi2GetVersion(): fmi2GetVersionTYPE;
    fmi2SetDebugLogging(_, _, _, _): fmi2SetDebugLoggingTYPE;
    fmi2Instantiate(_, _, _, _, _, _, _): fmi2InstantiateTYPE;
    fmi2FreeInstance(_): fmi2FreeInstanceTYPE;
    fmi2SetupExperiment(_, _, _, _, _, _): fmi2SetupExperimentTYPE;
    fmi2EnterInitializationMode(_): fmi2EnterInitializationModeTYPE;
    fmi2ExitInitializationMode(_): fmi2ExitInitializationModeTYPE;
    fmi2Terminate(_): fmi2TerminateTYPE;
    fmi2Reset(_): fmi2ResetTYPE;
    fmi2GetReal(_, _, _, _): fmi2GetRealTYPE;
    fmi2GetInteger(_, _, _, _): fmi2GetIntegerTYPE;
    fmi2GetBoolean(_, _, _, _): fmi2GetBooleanTYPE;
    fmi2GetString(_, _, _, _): fmi2GetStringTYPE;
    fmi2SetReal(_, _, _, _): fmi2SetRealTYPE;
    fmi2SetInteger(_, _, _, _): fmi2SetIntegerTYPE;
    fmi2SetBoolean(_, _, _, _): fmi2SetBooleanTYPE;
    fmi2SetString(_, _, _, _): fmi2SetStringTYPE;
    fmi2GetFMUstate(_, _): fmi2GetFMUstateTYPE;
    fmi2SetFMUstate(_, _): fmi2SetFMUstateTYPE;
    fmi2FreeFMUstate(_, _): fmi2FreeFMUstateTYPE;
    fmi2SerializedFMUstateSize(_, _, _): fmi2SerializedFMUstateSizeTYPE;
    fmi2SerializeFMUstate(_, _, _, _): fmi2SerializeFMUstateTYPE;
    fmi2DeSerializeFMUstate(_, _, _, _): fmi2DeSerializeFMUstateTYPE;
    fmi2GetDirectionalDerivative(_, _, _, _, _, _, _): fmi2GetDirectionalDerivativeTYPE;
    fmi2SetRealInputDerivatives(_, _, _, _, _): fmi2SetRealInputDerivativesTYPE;
    fmi2GetRealOutputDerivatives(_, _, _, _, _): fmi2GetRealOutputDerivativesTYPE;
    fmi2DoStep(_, _, _, _): fmi2DoStepTYPE;
    fmi2CancelStep(_): fmi2CancelStepTYPE;
    fmi2GetStatus(_, _, _): fmi2GetStatusTYPE;
    fmi2GetRealStatus(_, _, _): fmi2GetRealStatusTYPE;
    fmi2GetIntegerStatus(_, _, _): fmi2GetIntegerStatusTYPE;
    fmi2GetBooleanStatus(_, _, _): fmi2GetBooleanStatusTYPE;
    fmi2GetStringStatus(_, _, _): fmi2GetStringStatusTYPE;
}}

check! { FMI3_CHECKED = fmi3_exports against h3 {
    fmi3GetVersion(): fmi3GetVersionTYPE;
    fmi3SetDebugLogging(_, _, _, _): fmi3SetDebugLoggingTYPE;
    fmi3InstantiateModelExchange(_, _, _, _, _, _, _): fmi3InstantiateModelExchangeTYPE;
    fmi3InstantiateCoSimulation(_, _, _, _, _, _, _, _, _, _, _, _): fmi3InstantiateCoSimulationTYPE;
    fmi3InstantiateScheduledExecution(_, _, _, _, _, _, _, _, _, _): fmi3InstantiateScheduledExecutionTYPE;
    fmi3FreeInstance(_): fmi3FreeInstanceTYPE;
    fmi3EnterInitializationMode(_, _, _, _, _, _): fmi3EnterInitializationModeTYPE;
    fmi3ExitInitializationMode(_): fmi3ExitInitializationModeTYPE;
    fmi3EnterEventMode(_): fmi3EnterEventModeTYPE;
    fmi3Terminate(_): fmi3TerminateTYPE;
    fmi3Reset(_): fmi3ResetTYPE;
    fmi3GetFloat32(_, _, _, _, _): fmi3GetFloat32TYPE;
    fmi3GetFloat64(_, _, _, _, _): fmi3GetFloat64TYPE;
    fmi3GetInt8(_, _, _, _, _): fmi3GetInt8TYPE;
    fmi3GetUInt8(_, _, _, _, _): fmi3GetUInt8TYPE;
    fmi3GetInt16(_, _, _, _, _): fmi3GetInt16TYPE;
    fmi3GetUInt16(_, _, _, _, _): fmi3GetUInt16TYPE;
    fmi3GetInt32(_, _, _, _, _): fmi3GetInt32TYPE;
    fmi3GetUInt32(_, _, _, _, _): fmi3GetUInt32TYPE;
    fmi3GetInt64(_, _, _, _, _): fmi3GetInt64TYPE;
    fmi3GetUInt64(_, _, _, _, _): fmi3GetUInt64TYPE;
    fmi3GetBoolean(_, _, _, _, _): fmi3GetBooleanTYPE;
    fmi3GetString(_, _, _, _, _): fmi3GetStringTYPE;
    fmi3GetBinary(_, _, _, _, _, _): fmi3GetBinaryTYPE;
    fmi3GetClock(_, _, _, _): fmi3GetClockTYPE;
    fmi3SetFloat32(_, _, _, _, _): fmi3SetFloat32TYPE;
    fmi3SetFloat64(_, _, _, _, _): fmi3SetFloat64TYPE;
    fmi3SetInt8(_, _, _, _, _): fmi3SetInt8TYPE;
    fmi3SetUInt8(_, _, _, _, _): fmi3SetUInt8TYPE;
    fmi3SetInt16(_, _, _, _, _): fmi3SetInt16TYPE;
    fmi3SetUInt16(_, _, _, _, _): fmi3SetUInt16TYPE;
    fmi3SetInt32(_, _, _, _, _): fmi3SetInt32TYPE;
    fmi3SetUInt32(_, _, _, _, _): fmi3SetUInt32TYPE;
    fmi3SetInt64(_, _, _, _, _): fmi3SetInt64TYPE;
    fmi3SetUInt64(_, _, _, _, _): fmi3SetUInt64TYPE;
    fmi3SetBoolean(_, _, _, _, _): fmi3SetBooleanTYPE;
    fmi3SetString(_, _, _, _, _): fmi3SetStringTYPE;
    fmi3SetBinary(_, _, _, _, _, _): fmi3SetBinaryTYPE;
    fmi3SetClock(_, _, _, _): fmi3SetClockTYPE;
    fmi3GetNumberOfVariableDependencies(_, _, _): fmi3GetNumberOfVariableDependenciesTYPE;
    fmi3GetVariableDependencies(_, _, _, _, _, _, _): fmi3GetVariableDependenciesTYPE;
    fmi3GetFMUState(_, _): fmi3GetFMUStateTYPE;
    fmi3SetFMUState(_, _): fmi3SetFMUStateTYPE;
    fmi3FreeFMUState(_, _): fmi3FreeFMUStateTYPE;
    fmi3SerializedFMUStateSize(_, _, _): fmi3SerializedFMUStateSizeTYPE;
    fmi3SerializeFMUState(_, _, _, _): fmi3SerializeFMUStateTYPE;
    fmi3DeserializeFMUState(_, _, _, _): fmi3DeserializeFMUStateTYPE;
    fmi3GetDirectionalDerivative(_, _, _, _, _, _, _, _, _): fmi3GetDirectionalDerivativeTYPE;
    fmi3GetAdjointDerivative(_, _, _, _, _, _, _, _, _): fmi3GetAdjointDerivativeTYPE;
    fmi3EnterConfigurationMode(_): fmi3EnterConfigurationModeTYPE;
    fmi3ExitConfigurationMode(_): fmi3ExitConfigurationModeTYPE;
    fmi3GetIntervalDecimal(_, _, _, _, _): fmi3GetIntervalDecimalTYPE;
    fmi3GetIntervalFraction(_, _, _, _, _, _): fmi3GetIntervalFractionTYPE;
    fmi3GetShiftDecimal(_, _, _, _): fmi3GetShiftDecimalTYPE;
    fmi3GetShiftFraction(_, _, _, _, _): fmi3GetShiftFractionTYPE;
    fmi3SetIntervalDecimal(_, _, _, _): fmi3SetIntervalDecimalTYPE;
    fmi3SetIntervalFraction(_, _, _, _, _): fmi3SetIntervalFractionTYPE;
    fmi3SetShiftDecimal(_, _, _, _): fmi3SetShiftDecimalTYPE;
    fmi3SetShiftFraction(_, _, _, _, _): fmi3SetShiftFractionTYPE;
    fmi3EvaluateDiscreteStates(_): fmi3EvaluateDiscreteStatesTYPE;
    fmi3UpdateDiscreteStates(_, _, _, _, _, _, _): fmi3UpdateDiscreteStatesTYPE;
    fmi3EnterContinuousTimeMode(_): fmi3EnterContinuousTimeModeTYPE;
    fmi3CompletedIntegratorStep(_, _, _, _): fmi3CompletedIntegratorStepTYPE;
    fmi3SetTime(_, _): fmi3SetTimeTYPE;
    fmi3SetContinuousStates(_, _, _): fmi3SetContinuousStatesTYPE;
    fmi3GetContinuousStateDerivatives(_, _, _): fmi3GetContinuousStateDerivativesTYPE;
    fmi3GetEventIndicators(_, _, _): fmi3GetEventIndicatorsTYPE;
    fmi3GetContinuousStates(_, _, _): fmi3GetContinuousStatesTYPE;
    fmi3GetNominalsOfContinuousStates(_, _, _): fmi3GetNominalsOfContinuousStatesTYPE;
    fmi3GetNumberOfEventIndicators(_, _): fmi3GetNumberOfEventIndicatorsTYPE;
    fmi3GetNumberOfContinuousStates(_, _): fmi3GetNumberOfContinuousStatesTYPE;
    fmi3EnterStepMode(_): fmi3EnterStepModeTYPE;
    fmi3GetOutputDerivatives(_, _, _, _, _, _): fmi3GetOutputDerivativesTYPE;
    fmi3DoStep(_, _, _, _, _, _, _, _): fmi3DoStepTYPE;
    fmi3ActivateModelPartition(_, _, _): fmi3ActivateModelPartitionTYPE;
}}

/// The names of the functions an export macro emits: the `fn fmi…` in its source after
/// `macro_rules! <name>`, and for FMI 3.0 the getters and setters of types without variables
/// (`fmi3GetFloat32 "Float32" get f32;` lines).
fn exported(source: &str, macro_name: &str) -> Vec<String> {
    let body = &source[source.find(&format!("macro_rules! {macro_name}")).expect("the macro")..];
    let mut names = Vec::new();
    for line in body.lines().map(str::trim) {
        let name = match line.find("extern \"C\" fn fmi") {
            Some(at) => &line[at + "extern \"C\" fn ".len()..],
            None if line.starts_with("fmi3") && line.contains(" \"") => line,
            None => continue,
        };
        names.push(name.chars().take_while(|c| c.is_ascii_alphanumeric()).collect());
    }
    names.sort();
    names
}

fn sorted(list: &[&str]) -> Vec<String> {
    let mut names: Vec<String> = list.iter().map(|s| s.to_string()).collect();
    names.sort();
    names
}

#[test]
fn every_exported_function_is_checked_against_its_header() {
    let fmi2 = exported(include_str!("../../src/fmi2/abi.rs"), "export_fmi2");
    let fmi3 = exported(include_str!("../../src/fmi3/abi.rs"), "export_fmi3");
    assert_eq!(sorted(FMI2_CHECKED), fmi2);
    assert_eq!(sorted(FMI3_CHECKED), fmi3);
    // FMI 2.0: the common and Co-Simulation functions; FMI 3.0: every function of the header.
    assert_eq!((fmi2.len(), fmi3.len()), (34, 75));
}
