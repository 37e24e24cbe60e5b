//! A system being simulated: its units instantiated, initialised and stepped at a fixed
//! communication step.
//!
//! # Stepping
//! At every communication point t_n all outputs are valid at t_n. Connections are *resolved*
//! by walking the units so that a unit whose outputs depend directly on its inputs (direct
//! feedthrough, from `ModelStructure/Outputs`) comes after the units that feed it; a cycle
//! of such units is an algebraic loop and is refused.
//! - [`Algorithm::GaussSeidel`] (default): units step one after another; after each step its
//!   new outputs are passed on at once, so a unit later in the order steps with its
//!   providers' values at t_{n+1}. The order is a topological order of the connection graph;
//!   a cycle is cut at its first unit (in declaration order) without direct feedthrough.
//! - [`Algorithm::Jacobi`]: every unit steps from t_n with the inputs of t_n, then all
//!   connections are resolved.
//!
//! With one stateful unit in a loop (an arm and static controllers) both give the same
//! result; with two (two integrators in a loop) Gauss–Seidel is the symplectic Euler update
//! and Jacobi the explicit one.

use fmi::fmi2::instance::{CoSimulation, Common};

use crate::capture;
use crate::error::MasterError;
use crate::interface::{BaseType, Causality};
use crate::recording::Recorder;
use crate::schedule::Schedule;
use crate::spec::{Algorithm, Value};
use crate::system::{check_value, split_name, System};
use crate::unit::Unit;

/// A system being simulated. The recorded rows stay available whatever happens.
pub struct Simulation {
    system: System,
    units: Vec<Unit>,
    schedule: Schedule,
    time: f64,
    start: f64,
    step: f64,
    steps_taken: u64,
    algorithm: Algorithm,
    recorder: Recorder,
}

/// A resolved Real variable of a running simulation.
#[derive(Clone, Copy, Debug)]
pub struct Handle {
    unit: usize,
    value_reference: u32,
    settable: bool,
}

impl System {
    /// Instantiates every unit and initialises them at `start` [s] for steps of `step` [s];
    /// `record` lists the variables ("unit.variable") to record at each communication point.
    pub fn initialize(self, start: f64, step: f64, algorithm: Algorithm, record: &[String]) -> Result<Simulation, MasterError> {
        if !(step > 0.0 && step.is_finite()) {
            return Err(MasterError::new(format!("the communication step must be positive, not {step}")));
        }
        let schedule = Schedule::new(&self)?;
        let recorder = Recorder::new(record.to_vec(), self.recordable(record)?);
        let units = self.units().iter().map(Unit::load).collect::<Result<Vec<_>, _>>()?;
        let mut sim = Simulation { system: self, units, schedule, time: start, step, steps_taken: 0, start, algorithm, recorder };
        sim.start_up()?;
        Ok(sim)
    }
}

impl Simulation {
    fn start_up(&mut self) -> Result<(), MasterError> {
        let start = self.start;
        for u in &mut self.units {
            let mark = capture::mark();
            u.instance.setup_experiment(None, start, None).map_err(|e| u.fail("fmi2SetupExperiment", e, mark, None))?;
        }
        for k in 0..self.system.settings().len() {
            let s = &self.system.settings()[k];
            let (unit, variable, value) = (s.unit, s.variable.clone(), s.value.clone());
            self.set_value(unit, &variable, &value)?;
        }
        for u in &mut self.units {
            let mark = capture::mark();
            u.instance.enter_initialization_mode().map_err(|e| u.fail("fmi2EnterInitializationMode", e, mark, None))?;
        }
        self.resolve_all(None)?;
        for u in &mut self.units {
            let mark = capture::mark();
            u.instance.exit_initialization_mode().map_err(|e| u.fail("fmi2ExitInitializationMode", e, mark, None))?;
        }
        self.resolve_all(Some(start))?;
        self.recorder.record(&mut self.units, self.time)?;
        Ok(())
    }

    fn set_value(&mut self, ui: usize, name: &str, value: &Value) -> Result<(), MasterError> {
        let info = self.system.units()[ui].variable(name)?;
        let (vr, base) = ([info.value_reference], info.base);
        let unit = &mut self.units[ui];
        let mark = capture::mark();
        let r = match value {
            Value::Real(x) => unit.instance.set_real(&vr, &[*x]).map(|_| ()),
            Value::Integer(i) if base == BaseType::Real => unit.instance.set_real(&vr, &[*i as f64]).map(|_| ()),
            Value::Integer(i) => unit.instance.set_integer(&vr, &[*i as i32]).map(|_| ()),
            Value::Boolean(b) => unit.instance.set_boolean(&vr, &[*b as i32]).map(|_| ()),
            Value::String(s) => {
                let c = std::ffi::CString::new(s.as_str())
                    .map_err(|_| MasterError::new("a string holds a NUL byte").unit(&unit.name).variable(name))?;
                unit.instance.set_string(&vr, &[c])
            }
        };
        r.map_err(|e| {
            let mut x = unit.fail("fmi2Set", e, mark, None).variable(name);
            x.message = format!("setting {value:?} refused: {}", x.message);
            x
        })
    }

    /// Passes the outputs of the dirty units on, in resolve order; a target whose outputs
    /// follow its inputs becomes dirty in turn, unless (in a Gauss–Seidel sweep, `position`
    /// being the step position just done) it will step later and nobody needs it before.
    fn resolve_dirty(&mut self, time: Option<f64>, position: Option<usize>) -> Result<(), MasterError> {
        for i in 0..self.schedule.resolve_order.len() {
            let u = self.schedule.resolve_order[i];
            if !self.schedule.dirty[u] {
                continue;
            }
            self.schedule.dirty[u] = false;
            if self.schedule.transfers[u].is_empty() {
                continue;
            }
            let plan = &mut self.schedule;
            let units = &mut self.units;
            let mark = capture::mark();
            let (nr, ni, nb) = (plan.out_real[u].len(), plan.out_int[u].len(), plan.out_bool[u].len());
            if nr > 0 {
                units[u]
                    .instance
                    .get_real(&plan.out_real[u], &mut plan.buf_real[..nr])
                    .map_err(|e| units[u].fail("fmi2GetReal", e, mark, time))?;
            }
            if ni > 0 {
                units[u]
                    .instance
                    .get_integer(&plan.out_int[u], &mut plan.buf_int[..ni])
                    .map_err(|e| units[u].fail("fmi2GetInteger", e, mark, time))?;
            }
            if nb > 0 {
                units[u]
                    .instance
                    .get_boolean(&plan.out_bool[u], &mut plan.buf_bool[..nb])
                    .map_err(|e| units[u].fail("fmi2GetBoolean", e, mark, time))?;
            }
            for t in &plan.transfers[u] {
                let m = t.vrs.len();
                let target = &mut units[t.to];
                let r = match t.base {
                    BaseType::Real => {
                        for (v, &k) in plan.set_real.iter_mut().zip(&t.from) {
                            *v = plan.buf_real[k];
                        }
                        target.instance.set_real(&t.vrs, &plan.set_real[..m])
                    }
                    BaseType::Integer => {
                        for (v, &k) in plan.set_int.iter_mut().zip(&t.from) {
                            *v = plan.buf_int[k];
                        }
                        target.instance.set_integer(&t.vrs, &plan.set_int[..m])
                    }
                    _ => {
                        for (v, &k) in plan.set_bool.iter_mut().zip(&t.from) {
                            *v = plan.buf_bool[k];
                        }
                        target.instance.set_boolean(&t.vrs, &plan.set_bool[..m])
                    }
                };
                r.map_err(|e| {
                    let names: Vec<&str> = self
                        .system
                        .links()
                        .iter()
                        .filter(|l| l.to_unit == t.to && l.base == t.base && t.vrs.contains(&l.to_vr))
                        .map(|l| l.to_variable.as_str())
                        .collect();
                    target.fail("fmi2Set (connection)", e, mark, time).variable(&names.join(", "))
                })?;
            }
            for g in 0..self.schedule.transfers[u].len() {
                let (to, feeds) = (self.schedule.transfers[u][g].to, self.schedule.transfers[u][g].feeds);
                if feeds && !self.schedule.can_wait(to, position) {
                    self.schedule.dirty[to] = true;
                }
            }
        }
        Ok(())
    }

    fn resolve_all(&mut self, time: Option<f64>) -> Result<(), MasterError> {
        self.schedule.dirty.fill(true);
        self.resolve_dirty(time, None)
    }

    /// Records every `k`-th communication point only (k ≥ 1; the first is always recorded).
    pub fn record_every(&mut self, k: u64) {
        self.recorder.every = k.max(1);
    }

    /// One communication step from the current time.
    pub fn step(&mut self) -> Result<(), MasterError> {
        let t = self.time;
        let h = self.step;
        match self.algorithm {
            Algorithm::GaussSeidel => {
                for i in 0..self.schedule.step_order.len() {
                    let u = self.schedule.step_order[i];
                    self.do_step(u, t, h)?;
                    self.schedule.dirty[u] = true;
                    self.resolve_dirty(Some(t), Some(i))?;
                }
            }
            Algorithm::Jacobi => {
                for u in 0..self.units.len() {
                    self.do_step(u, t, h)?;
                }
                self.resolve_all(Some(t))?;
            }
        }
        self.steps_taken += 1;
        // Times from the step count, so long runs do not accumulate rounding.
        self.time = self.start + self.steps_taken as f64 * h;
        if self.steps_taken % self.recorder.every == 0 {
            self.recorder.record(&mut self.units, self.time)?;
        }
        Ok(())
    }

    fn do_step(&mut self, u: usize, t: f64, h: f64) -> Result<(), MasterError> {
        let unit = &mut self.units[u];
        let mark = capture::mark();
        unit.instance.do_step(t, h, true).map(|_| ()).map_err(|e| unit.fail("fmi2DoStep", e, mark, Some(t)))
    }

    /// Steps until `stop` [s] (to within a thousandth of a step).
    pub fn run_until(&mut self, stop: f64) -> Result<(), MasterError> {
        while self.time + 1e-3 * self.step < stop {
            self.step()?;
        }
        Ok(())
    }

    /// The current communication point [s].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The communication step [s].
    pub fn step_size(&self) -> f64 {
        self.step
    }

    /// Reads a Real variable ("unit.variable").
    pub fn get_real(&mut self, full: &str) -> Result<f64, MasterError> {
        let h = self.real_handle(full)?;
        let mut x = [0.0];
        self.get_reals(&[h], &mut x).map_err(|e| e.variable(split_name(full).map_or(full, |(_, v)| v)))?;
        Ok(x[0])
    }

    /// Sets an input or tunable parameter between steps; the new value is passed on at once.
    pub fn set(&mut self, full: &str, value: Value) -> Result<(), MasterError> {
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let info = self.system.units()[ui].variable(v)?;
        check_value(info, &value).map_err(|m| MasterError::new(m).unit(u).variable(v))?;
        if self.system.is_connected(ui, info.value_reference, info.base) {
            return Err(MasterError::new("this input is connected; the connection sets it").unit(u).variable(v));
        }
        self.set_value(ui, v, &value).map_err(|e| e.at(self.time))?;
        self.schedule.dirty[ui] = true;
        self.resolve_dirty(Some(self.time), None)
    }

    /// A handle on a Real variable ("unit.variable") for fast reads with [`Self::get_reals`]
    /// and, if it is an unconnected input or a tunable parameter, writes with [`Self::set_reals`].
    pub fn real_handle(&self, full: &str) -> Result<Handle, MasterError> {
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let info = self.system.units()[ui].variable(v)?;
        if info.base != BaseType::Real {
            return Err(MasterError::new(format!("type mismatch: {:?}, not Real", info.base)).unit(u).variable(v));
        }
        let connected = self.system.is_connected(ui, info.value_reference, BaseType::Real);
        let settable = matches!(info.causality, Causality::Input | Causality::Parameter) && !connected;
        Ok(Handle { unit: ui, value_reference: info.value_reference, settable })
    }

    /// Sets Real inputs or tunable parameters between steps and passes the effect on.
    pub fn set_reals(&mut self, handles: &[Handle], values: &[f64]) -> Result<(), MasterError> {
        assert_eq!(handles.len(), values.len(), "one value per handle");
        for (h, &x) in handles.iter().zip(values) {
            let unit = &mut self.units[h.unit];
            if !h.settable {
                return Err(MasterError::new("not settable: a connected input, an output or a local").unit(&unit.name).at(self.time));
            }
            let mark = capture::mark();
            unit.instance.set_real(&[h.value_reference], &[x]).map_err(|e| unit.fail("fmi2SetReal", e, mark, Some(self.time)))?;
            self.schedule.dirty[h.unit] = true;
        }
        self.resolve_dirty(Some(self.time), None)
    }

    /// Reads Real variables through handles.
    pub fn get_reals(&mut self, handles: &[Handle], out: &mut [f64]) -> Result<(), MasterError> {
        assert_eq!(handles.len(), out.len(), "one slot per handle");
        for (h, o) in handles.iter().zip(out.iter_mut()) {
            let unit = &mut self.units[h.unit];
            let mut x = [0.0];
            let mark = capture::mark();
            unit.instance.get_real(&[h.value_reference], &mut x).map_err(|e| unit.fail("fmi2GetReal", e, mark, Some(self.time)))?;
            *o = x[0];
        }
        Ok(())
    }

    /// Column names of the recording: "time", then the recorded variables.
    pub fn columns(&self) -> Vec<String> {
        self.recorder.columns()
    }

    /// The recorded rows (time first).
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.recorder.rows
    }

    /// Takes the recorded rows out, leaving none.
    pub fn take_rows(&mut self) -> Vec<Vec<f64>> {
        std::mem::take(&mut self.recorder.rows)
    }

    /// The system being simulated.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The units' names in Gauss–Seidel stepping order.
    pub fn step_order(&self) -> Vec<&str> {
        self.schedule.step_order.iter().map(|&u| self.units[u].name.as_str()).collect()
    }
}
