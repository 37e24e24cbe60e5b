//! Two small signal blocks with answers known in closed form, `Integrator` and `Gain`. They
//! test masters (ours and others): loops of them have exact discrete solutions.

use std::path::Path;

use neurarm_fmi_export::codec::{Put, Reader};
use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, StaticModel, TableBuilder, Values};
use serde::{Deserialize, Serialize};

use crate::names;
use crate::{describe, BuildError, ModelKind};

/// Spec of an integrator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorSpec {
    /// Start value of y0.
    pub y0: f64,
}

impl ModelKind for IntegratorSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        Ok(Box::new(IntegratorModel::new(identifier, self.y0)?))
    }

    fn equations_html(&self) -> &'static str {
        "<p><code>y' = u</code>, <code>y(t0) = y0</code>. The input is held over a \
communication step, so a step of h gives <code>y ← y + h·u</code> exactly. No direct feedthrough.</p>"
    }
}

/// Spec of a gain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainSpec {
    /// Start value of k.
    pub k: f64,
}

impl ModelKind for GainSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        Ok(Box::new(GainModel::new(identifier, self.k)?))
    }

    fn equations_html(&self) -> &'static str {
        "<p><code>y = k·u</code>, static, with direct feedthrough from u to y; k is tunable.</p>"
    }
}

/// `y' = u`, `y(t0) = y0`: over a step of h with the input held, `y += h·u` exactly.
/// No direct feedthrough: `y` does not depend on `u` at the same instant.
pub struct IntegratorModel {
    description: ModelDescription,
    u: RealVar,
    y: RealVar,
    y0: RealVar,
    state: f64,
}

/// `y` left the range of finite numbers.
#[derive(Debug, thiserror::Error)]
#[error("y overflowed to {0}")]
struct Overflow(f64);

impl IntegratorModel {
    /// An integrator FMU named `identifier` starting at `y0`.
    pub fn new(identifier: &str, y0: f64) -> Result<Self, BuildError> {
        let mut b = TableBuilder::new();
        let u = b.input(names::BLOCK_INPUT, None, 0.0, "Input: the derivative of y");
        let y = b.output(names::BLOCK_OUTPUT, None, "Integral of u from y0", &[]);
        let y0 = b.parameter(names::BLOCK_START, None, y0, "Initial value of y");
        let description =
            describe(identifier, "Integrator y' = u with the input held over each step (neurarm test block)".into(), b.finish())?;
        Ok(Self { description, u, y, y0, state: 0.0 })
    }
}

impl Model for IntegratorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), ModelError> {
        self.state = values[self.y0];
        values[self.y] = self.state;
        Ok(())
    }

    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), ModelError> {
        let next = self.state + step * values[self.u];
        if !next.is_finite() {
            return Err(Overflow(next).into());
        }
        self.state = next;
        values[self.y] = next;
        Ok(())
    }

    fn reset(&mut self) {
        self.state = 0.0;
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_f64s(&[self.state]);
    }

    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let s = r.finite_f64s("y", 1)?;
        r.finish()?;
        self.state = s[0];
        Ok(())
    }
}

/// `y = k·u`, static: direct feedthrough from `u` to `y`. `k` is tunable.
pub struct GainModel {
    description: ModelDescription,
    u: RealVar,
    y: RealVar,
    k: RealVar,
}

impl GainModel {
    /// A gain FMU named `identifier` with gain `k`.
    pub fn new(identifier: &str, k: f64) -> Result<Self, BuildError> {
        let mut b = TableBuilder::new();
        let u = b.input(names::BLOCK_INPUT, None, 0.0, "Input");
        let y = b.output(names::BLOCK_OUTPUT, None, "k·u", &[u]);
        let k = b.tunable(names::BLOCK_GAIN, None, k, "Gain");
        let description = describe(identifier, "Static gain y = k·u (neurarm test block)".into(), b.finish())?;
        Ok(Self { description, u, y, k })
    }
}

impl StaticModel for GainModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        values[self.y] = values[self.k] * values[self.u];
        Ok(())
    }
}
