//! The Van der Pol oscillator `ẍ = μ (1 − x²) ẋ − x + u` as an FMI 2.0 Co-Simulation FMU on
//! `neurarm-fmi-export`: model, variable table, state and C ABI. [`package`] makes the `.fmu`.

pub mod package;

use neurarm_fmi_export::codec::{Put, Reader};
use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, TableBuilder, Values};

/// The oscillator: a variable table and the state (x, ẋ).
pub struct VanDerPol {
    description: ModelDescription,
    vars: [RealVar; 6],
    state: [f64; 2],
}

impl VanDerPol {
    /// The model: input `u`, outputs `x`, `v` = ẋ, tunable `mu`, start values `x0`, `v0`.
    pub fn new() -> Result<Self, ModelError> {
        let mut b = TableBuilder::new();
        let u = b.input("u", None, 0.0, "Forcing");
        let x = b.output("x", None, "Position", &[]);
        let v = b.output("v", None, "Velocity dx/dt", &[]);
        let mu = b.tunable("mu", None, 1.0, "Damping parameter");
        let x0 = b.parameter("x0", None, 2.0, "Initial position");
        let v0 = b.parameter("v0", None, 0.0, "Initial velocity");
        let description = ModelDescription::new("VanDerPol", "Van der Pol oscillator (neurarm-fmi-export example)", b.finish())?;
        Ok(Self { description, vars: [u, x, v, mu, x0, v0], state: [0.0; 2] })
    }
}

/// The right-hand side (ẋ, v̇) at `s` with forcing `u`.
fn rhs(s: [f64; 2], mu: f64, u: f64) -> [f64; 2] {
    [s[1], mu * (1.0 - s[0] * s[0]) * s[1] - s[0] + u]
}

impl Model for VanDerPol {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start: f64) -> Result<(), ModelError> {
        self.state = [values[self.vars[4]], values[self.vars[5]]];
        values.write_reals(&self.vars[1..3], &self.state);
        Ok(())
    }

    /// Classic RK4 in equal sub-steps of at most 1 ms, the input held over the step.
    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), ModelError> {
        let (mu, u) = (values[self.vars[3]], values[self.vars[0]]);
        let n = (step / 1e-3).ceil().max(1.0);
        let h = step / n;
        for _ in 0..n as usize {
            let s = self.state;
            let at = |k: [f64; 2], c: f64| rhs([s[0] + c * k[0], s[1] + c * k[1]], mu, u);
            let k1 = rhs(s, mu, u);
            let k2 = at(k1, h / 2.0);
            let k3 = at(k2, h / 2.0);
            let k4 = at(k3, h);
            self.state = [0, 1].map(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
        if !self.state.iter().all(|x| x.is_finite()) {
            return Err(ModelError::msg(format!("the state diverged to {:?} (mu = {mu}, u = {u})", self.state)));
        }
        values.write_reals(&self.vars[1..3], &self.state);
        Ok(())
    }

    fn reset(&mut self) {
        self.state = [0.0; 2];
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_f64s(&self.state);
    }

    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let s = r.f64s(2)?;
        r.finish()?;
        self.state = [s[0], s[1]];
        Ok(())
    }
}

fn factory(_resources: Option<&std::path::Path>) -> Result<Box<dyn Model>, ModelError> {
    Ok(Box::new(VanDerPol::new()?))
}

neurarm_fmi_export::export_fmi2!(factory);
