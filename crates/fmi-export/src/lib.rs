//! Write FMI 2.0 and FMI 3.0 Co-Simulation FMUs in Rust, from one model.
//!
//! A model implements [`Model`] (or the simpler [`StaticModel`], for outputs that are a
//! function of inputs, parameters and time) over one table of variables built with
//! [`TableBuilder`]. From that table this crate makes both `modelDescription.xml`
//! ([`ModelDescription::to_xml`] for FMI 2.0, [`fmi3::description::to_xml`] for FMI 3.0) and
//! the dispatch of the C ABIs, so they cannot disagree. The layer does the rest of the
//! standards:
//!
//! - every `fmi2*` function of the Co-Simulation interface as an `extern "C"` symbol
//!   ([`export_fmi2!`], module [`fmi2`]), and every `fmi3*` function ([`export_fmi3!`], module
//!   [`fmi3`]), each behind `catch_unwind`: a panic becomes `fmi2Fatal`/`fmi3Fatal`, never an
//!   unwind into the host; one library can carry both;
//! - one state machine for both versions (FMI 2.0 section 4.2.4) and argument checks
//!   ([`instance`]): a call in the wrong state or with a bad argument (unknown value reference, wrong type, a variable
//!   that may not be set now, NaN, a step of 0) returns `fmi2Error` and logs why;
//! - FMU states (`fmi2GetFMUstate`, `fmi2SetFMUstate`), held by the instance that saved them
//!   behind numeric handles (a foreign handle is refused, never read; states left unfreed go
//!   with the instance), and their serialisation, versioned, bound to the GUID and checksummed
//!   ([`codec`] for a model's own part);
//! - the GUID, a hash of the model description, checked at instantiation;
//! - units declared by the models that use them ([`Unit`]): `UnitDefinitions` lists those;
//! - packaging into a `.fmu` ([`fmi2::write_fmu`], [`fmi3::write_fmu`], the shared
//!   [`package`] checks; feature `package`, on by default).
//!
//! It depends on no numerics and no robotics: it serves anyone's Rust model.
//!
//! # Example
//!
//! A first-order lag `T y' = u − y`, integrated exactly over each step with the input held,
//! driven here in process through [`Instance`], as a host would through the C ABI.
//!
//! ```
//! use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, TableBuilder, Unit, Values};
//! use neurarm_fmi_export::codec::{Put, Reader};
//! use neurarm_fmi_export::instance::{Instance, Status};
//!
//! const VOLT: Unit = Unit::new("V").kg(1).m(2).s(-3).ampere(-1);
//!
//! struct Lag { description: ModelDescription, u: RealVar, y: RealVar, t: RealVar, state: f64 }
//!
//! impl Lag {
//!     fn new() -> Result<Self, ModelError> {
//!         let mut b = TableBuilder::new();
//!         let u = b.input("u", VOLT, 0.0, "Input");
//!         let y = b.output("y", VOLT, "Lagged input", &[]);
//!         let t = b.parameter("T", Unit::SECOND, 0.5, "Time constant");
//!         let description = ModelDescription::new("Lag", "First-order lag", b.finish())?;
//!         Ok(Self { description, u, y, t, state: 0.0 })
//!     }
//! }
//!
//! impl Model for Lag {
//!     fn description(&self) -> &ModelDescription { &self.description }
//!     fn initialize(&mut self, values: &mut Values, _start: f64) -> Result<(), ModelError> {
//!         if !(values[self.t] > 0.0) {
//!             return Err(ModelError::msg(format!("T = {} must be > 0", values[self.t])));
//!         }
//!         values[self.y] = self.state;
//!         Ok(())
//!     }
//!     fn do_step(&mut self, values: &mut Values, _time: f64, h: f64) -> Result<(), ModelError> {
//!         let decay = (-h / values[self.t]).exp();
//!         self.state = values[self.u] + (self.state - values[self.u]) * decay;
//!         values[self.y] = self.state;
//!         Ok(())
//!     }
//!     fn reset(&mut self) { self.state = 0.0 }
//!     fn save_state(&self, out: &mut Vec<u8>) { out.put_f64(self.state) }
//!     fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
//!         let mut r = Reader::new(bytes);
//!         let state = r.f64()?;
//!         r.finish()?;
//!         self.state = state;
//!         Ok(())
//!     }
//! }
//!
//! // In the model's cdylib: every fmi2* symbol, serving the models this factory makes.
//! fn factory(_resources: Option<&std::path::Path>) -> Result<Box<dyn Model>, ModelError> {
//!     Ok(Box::new(Lag::new()?))
//! }
//! neurarm_fmi_export::export_fmi2!(factory);
//! neurarm_fmi_export::export_fmi3!(factory);
//!
//! # fn main() -> Result<(), ModelError> {
//! let model = Lag::new()?;
//! let xml = model.description().to_xml();
//! assert!(xml.contains(r#"<Unit name="V">"#) && xml.contains(r#"<BaseUnit kg="1" m="2" s="-3" A="-1"/>"#));
//!
//! let guid = model.description().guid();
//! let log = Box::new(|status: Status, _category: &str, message: &str| eprintln!("{status:?}: {message}"));
//! let mut lag = Instance::new("lag", &guid, Box::new(model), log, false).expect("the GUID matches");
//! let (u, y) = (1, 2); // value references, in the order the table was built (time is 0)
//! assert_eq!(lag.do_step(0.0, 0.1), Status::Error, "fmi2DoStep before initialization is refused");
//! assert_eq!(lag.setup_experiment(None, 0.0, None), Status::Ok);
//! assert_eq!(lag.enter_initialization_mode(), Status::Ok);
//! assert_eq!(lag.exit_initialization_mode(), Status::Ok);
//! assert_eq!(lag.set_real(&[u], &[f64::NAN]), Status::Error, "NaN is refused, nothing set");
//! assert_eq!(lag.set_real(&[u], &[2.0]), Status::Ok);
//! for k in 0..10 {
//!     assert_eq!(lag.do_step(k as f64 * 0.1, 0.1), Status::Ok);
//! }
//! let mut out = [0.0];
//! assert_eq!(lag.get_real(&[y], &mut out), Status::Ok);
//! assert!((out[0] - 2.0 * (1.0 - (-2.0f64).exp())).abs() < 1e-12); // y(1 s) = 2 (1 − e^(−1/T))
//! # Ok(())
//! # }
//! ```
//!
//! # Packaging
//!
//! With the cdylib built, [`fmi2::write_fmu`] (or [`fmi3::write_fmu`]) zips `modelDescription.xml`, the library as
//! `binaries/<platform>/<modelIdentifier>.<ext>`, any resource files and an HTML page of the
//! variables into the `.fmu`, written to a temporary file and renamed, so a failure leaves
//! nothing behind. The factory reads `resources/` at instantiation: one binary can serve
//! several FMUs that differ in their resources.
//!
//! # Flags
//!
//! The FMUs declare `canHandleVariableCommunicationStepSize`, `canGetAndSetFMUstate`,
//! `canSerializeFMUstate` and `canNotUseMemoryManagementFunctions` (Rust's allocator is used);
//! directional derivatives, input derivatives and asynchronous steps are not offered, and
//! their functions return `fmi2Error` with a log entry.

#![warn(missing_docs)]

pub mod codec;
pub mod description;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod model;
#[cfg(feature = "package")]
pub mod package;
/// Pointer and string handling shared by the C APIs and their macros; not public API.
#[doc(hidden)]
pub mod raw;
pub mod table;
pub mod uri;
mod xml;

pub use description::{
    Causality, DefaultExperiment, DescriptionError, EnumerationItem, EnumerationType, Kind, ModelDescription, Unit, Variability, Variable,
};
pub use instance::Instance;
pub use model::{Discard, Model, ModelError, ModelFactory, StaticModel, Values};
pub use table::{BooleanVar, IntegerVar, RealVar, StringVar, TableBuilder};
