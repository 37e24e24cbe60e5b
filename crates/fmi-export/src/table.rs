//! Building a variable table, and the typed handles a model keeps to its variables.
//!
//! [`TableBuilder`] numbers value references per base type in order of addition and hands back
//! a handle per variable: [`RealVar`], [`IntegerVar`], [`BooleanVar`] or [`StringVar`]. A model
//! reads and writes its variables in [`Values`](crate::Values) through these handles, so a
//! Boolean cannot be read as a Real and a value reference is never an untyped number.

use crate::description::{Causality, EnumerationType, Kind, Unit, Variability, Variable};

macro_rules! handle {
    ($(#[$doc:meta] $name:ident;)*) => {$(
        #[$doc]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// The value reference.
            pub const fn value_reference(self) -> u32 {
                self.0
            }
        }
    )*};
}

handle! {
    /// A handle on an `fmi2Real` variable.
    RealVar;
    /// A handle on an `fmi2Integer` variable.
    IntegerVar;
    /// A handle on an `fmi2Boolean` variable.
    BooleanVar;
    /// A handle on an `fmi2String` variable.
    StringVar;
}

/// The adders of the base types without a unit, alike but for the type.
macro_rules! non_real_adders {
    ($(#[$doc:meta] $name:ident, $handle:ident, $t:ty, $kind:ident;)*) => {$(
        #[$doc]
        pub fn $name(
            &mut self,
            name: impl Into<String>,
            causality: Causality,
            variability: Variability,
            start: Option<$t>,
            description: impl Into<String>,
        ) -> $handle {
            $handle(self.push(name, causality, variability, Kind::$kind { start }, description))
        }
    )*};
}

/// Builds a variable table, numbering value references per base type in order of addition.
#[derive(Debug)]
pub struct TableBuilder {
    variables: Vec<Variable>,
    counts: [u32; 4],
}

impl Default for TableBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl TableBuilder {
    /// An empty table with `time` [s], the independent variable, first.
    pub fn new() -> Self {
        let mut b = Self { variables: Vec::new(), counts: [0; 4] };
        b.push(
            "time",
            Causality::Independent,
            Variability::Continuous,
            Kind::Real { start: None, unit: Some(Unit::SECOND) },
            "Simulation time",
        );
        b
    }

    fn push(
        &mut self,
        name: impl Into<String>,
        causality: Causality,
        variability: Variability,
        kind: Kind,
        description: impl Into<String>,
    ) -> u32 {
        let slot = match kind {
            Kind::Real { .. } => 0,
            Kind::Integer { .. } | Kind::Enumeration { .. } => 1,
            Kind::Boolean { .. } => 2,
            Kind::String { .. } => 3,
        };
        let vr = self.counts[slot];
        self.counts[slot] += 1;
        self.variables.push(Variable {
            name: name.into(),
            value_reference: vr,
            causality,
            variability,
            kind,
            description: description.into(),
            output_dependencies: Vec::new(),
        });
        vr
    }

    /// Adds a real variable in `unit`, of any causality and variability.
    pub fn real(
        &mut self,
        name: impl Into<String>,
        causality: Causality,
        variability: Variability,
        start: Option<f64>,
        unit: impl Into<Option<Unit>>,
        description: impl Into<String>,
    ) -> RealVar {
        RealVar(self.push(name, causality, variability, Kind::Real { start, unit: unit.into() }, description))
    }

    non_real_adders! {
        /// Adds an integer variable.
        integer, IntegerVar, i32, Integer;
        /// Adds a Boolean variable.
        boolean, BooleanVar, bool, Boolean;
        /// Adds a string variable.
        string, StringVar, String, String;
    }

    /// Adds an enumeration variable of type `declared_type` (its values share the Integer
    /// value references and are read and set as integers).
    pub fn enumeration(
        &mut self,
        name: impl Into<String>,
        causality: Causality,
        variability: Variability,
        declared_type: &EnumerationType,
        start: Option<i32>,
        description: impl Into<String>,
    ) -> IntegerVar {
        let kind = Kind::Enumeration { declared_type: declared_type.clone(), start };
        IntegerVar(self.push(name, causality, variability, kind, description))
    }

    /// Adds a continuous real output that starts at `start`, a value the environment may set
    /// before initialization (`initial="exact"`), and depends directly on the inputs in
    /// `depends_on` after that.
    ///
    /// # Panics
    /// If an entry of `depends_on` is not a real input added before.
    pub fn output_with_start(
        &mut self,
        name: impl Into<String>,
        unit: impl Into<Option<Unit>>,
        start: f64,
        description: impl Into<String>,
        depends_on: &[RealVar],
    ) -> RealVar {
        let var = self.output(name, unit, description, depends_on);
        if let Some(Kind::Real { start: s, .. }) = self.variables.last_mut().map(|v| &mut v.kind) {
            *s = Some(start);
        }
        var
    }

    /// Adds a continuous real input with its start value, in `unit`.
    pub fn input(&mut self, name: impl Into<String>, unit: impl Into<Option<Unit>>, start: f64, description: impl Into<String>) -> RealVar {
        self.real(name, Causality::Input, Variability::Continuous, Some(start), unit, description)
    }

    /// Adds a continuous real output in `unit` that depends directly on the inputs in
    /// `depends_on` (empty: on none, the output follows the state only).
    ///
    /// # Panics
    /// If an entry of `depends_on` is not a real input added before.
    pub fn output(
        &mut self,
        name: impl Into<String>,
        unit: impl Into<Option<Unit>>,
        description: impl Into<String>,
        depends_on: &[RealVar],
    ) -> RealVar {
        let deps: Vec<usize> = depends_on
            .iter()
            .map(|input| {
                1 + self
                    .variables
                    .iter()
                    .position(|v| v.causality == Causality::Input && matches!(v.kind, Kind::Real { .. }) && v.value_reference == input.0)
                    .expect("a dependency is a real input added earlier")
            })
            .collect();
        let var = self.real(name, Causality::Output, Variability::Continuous, None, unit, description);
        self.variables.last_mut().expect("just pushed").output_dependencies = deps;
        var
    }

    /// Adds a fixed real parameter (set before initialization only), in `unit`.
    pub fn parameter(
        &mut self,
        name: impl Into<String>,
        unit: impl Into<Option<Unit>>,
        start: f64,
        description: impl Into<String>,
    ) -> RealVar {
        self.real(name, Causality::Parameter, Variability::Fixed, Some(start), unit, description)
    }

    /// Adds a tunable real parameter (settable between steps too), in `unit`.
    pub fn tunable(
        &mut self,
        name: impl Into<String>,
        unit: impl Into<Option<Unit>>,
        start: f64,
        description: impl Into<String>,
    ) -> RealVar {
        self.real(name, Causality::Parameter, Variability::Tunable, Some(start), unit, description)
    }

    /// Adds a tunable Boolean parameter.
    pub fn tunable_flag(&mut self, name: impl Into<String>, start: bool, description: impl Into<String>) -> BooleanVar {
        self.boolean(name, Causality::Parameter, Variability::Tunable, Some(start), description)
    }

    /// The finished table.
    pub fn finish(self) -> Vec<Variable> {
        self.variables
    }
}
