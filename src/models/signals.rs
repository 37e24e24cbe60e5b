//! Two small signal blocks with answers known in closed form, `Integrator` and `Gain`. They
//! test masters (ours and others): loops of them have exact discrete solutions.

use crate::fmi2::codec::{Put, Reader};
use crate::fmi2::description::{Causality, Kind, ModelDescription, TableBuilder, Variability};
use crate::fmi2::model::{Model, StaticModel, Values};

/// `y' = u`, `y(t0) = y0`: over a step of h with the input held, `y += h·u` exactly.
/// No direct feedthrough: `y` does not depend on `u` at the same instant.
pub struct IntegratorModel {
    description: ModelDescription,
    u: u32,
    y: u32,
    y0: u32,
    state: f64,
}

impl IntegratorModel {
    /// An integrator FMU named `identifier` starting at `y0`.
    pub fn new(identifier: &str, y0: f64) -> Result<Self, String> {
        let mut b = TableBuilder::new();
        let u = b.input("u", "", 0.0, "Input: the derivative of y");
        let y = b.output("y", "", "Integral of u from y0", &[]);
        let y0 = b.parameter("y0", "", y0, "Initial value of y");
        let description = ModelDescription::new(identifier, "Integrator y' = u with the input held over each step (neurarm test block)".into(), b.finish())?;
        Ok(Self { description, u, y, y0, state: 0.0 })
    }
}

impl Model for IntegratorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), String> {
        self.state = values.reals[self.y0 as usize];
        values.reals[self.y as usize] = self.state;
        Ok(())
    }

    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), String> {
        let next = self.state + step * values.reals[self.u as usize];
        if !next.is_finite() {
            return Err(format!("y overflowed to {next}"));
        }
        self.state = next;
        values.reals[self.y as usize] = next;
        Ok(())
    }

    fn reset(&mut self) {
        self.state = 0.0;
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_f64s(&[self.state]);
    }

    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), String> {
        let mut r = Reader::new(bytes);
        let s = r.f64s(1)?;
        r.finish()?;
        self.state = s[0];
        Ok(())
    }
}

/// `y = k·u`, static: direct feedthrough from `u` to `y`. `k` is tunable.
pub struct GainModel {
    description: ModelDescription,
    u: u32,
    y: u32,
    k: u32,
}

impl GainModel {
    /// A gain FMU named `identifier` with gain `k`.
    pub fn new(identifier: &str, k: f64) -> Result<Self, String> {
        let mut b = TableBuilder::new();
        let u = b.input("u", "", 0.0, "Input");
        let y = b.output("y", "", "k·u", &[u]);
        let k = b.push("k", Causality::Parameter, Variability::Tunable, Kind::Real { start: Some(k), unit: "" }, "Gain");
        let description = ModelDescription::new(identifier, "Static gain y = k·u (neurarm test block)".into(), b.finish())?;
        Ok(Self { description, u, y, k })
    }

}

impl StaticModel for GainModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values) {
        values.reals[self.y as usize] = values.reals[self.k as usize] * values.reals[self.u as usize];
    }
}

/// The equations, for `documentation/index.html`.
pub const INTEGRATOR_HTML: &str = "<p><code>y' = u</code>, <code>y(t0) = y0</code>. The input is held over a \
communication step, so a step of h gives <code>y ← y + h·u</code> exactly. No direct feedthrough.</p>";

/// The equations, for `documentation/index.html`.
pub const GAIN_HTML: &str = "<p><code>y = k·u</code>, static, with direct feedthrough from u to y; k is tunable.</p>";
