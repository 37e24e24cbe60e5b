//! A system being simulated: its units instantiated, initialised and stepped at a fixed
//! communication step.
//!
//! # Stepping
//! At every communication point t_n all outputs are valid at t_n. Connections are *resolved*
//! per output variable: an output that depends directly on an input (direct feedthrough,
//! from `ModelStructure/Outputs`) is read after the output feeding that input was passed on;
//! a cycle of such dependencies is an algebraic loop and is refused by name (see the
//! schedule's documentation).
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
//!
//! # Ending a run
//! [`Simulation::run_until`] steps to a stop time and says how the run ended ([`RunEnd`]):
//! - it lands on the stop time: when the span is not a whole number of steps, the last step
//!   is shortened to end there, if every unit can handle a variable communication step
//!   (`canHandleVariableCommunicationStepSize`); if one cannot, the run ends at the last whole
//!   step before the stop time and a notice ([`Simulation::notices`]) says which unit;
//! - a unit that discards a step (`fmi2Discard`, `fmi3Discard`; e.g. a model that reached its
//!   own end)
//!   ends the run at the last communication point every unit completed, which is the last
//!   recorded one; with [`OnDiscard::Error`] it is an error instead;
//! - an interrupt flag ([`Simulation::interrupt_on`]) ends it at the next communication point.

use std::ffi::CString;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::capture;
use crate::error::{DiscardedStep, MasterError};
use crate::interface::Variability;
use crate::interface::{BaseType, Causality};
use crate::recording::{Recorder, Rows};
use crate::schedule::Schedule;
use crate::spec::{Algorithm, EventSpec, OnDiscard, Value};
use crate::system::{check_value, split_name, System};
use crate::unit::{SharedBinaries, Stepped, Unit};

/// Steps shorter than this fraction of the communication step are not taken: the stop time
/// counts as reached.
const STEP_TOLERANCE: f64 = 1e-9;

/// How a call of [`Simulation::run_until`] ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunEnd {
    /// At the stop time, or at the last whole step before it when a unit cannot shorten its
    /// last step (then [`Simulation::notices`] says so).
    Completed,
    /// A unit discarded a step; the run ended at the last communication point every unit
    /// completed.
    Discarded {
        /// The unit that discarded.
        unit: String,
        /// The communication point the discarded step started from [s]: where the run ended.
        time: f64,
        /// What the unit said.
        status: DiscardedStep,
        /// What it logged in the call.
        log: Vec<String>,
    },
    /// A unit completed a step and asked to end the simulation (FMI 3.0 `terminateSimulation`;
    /// FMI 2.0 `fmi2Discard` with `fmi2Terminated` and `fmi2LastSuccessfulTime` at the step's
    /// end): every unit finished that step, its row is recorded, and the run ended there.
    EndRequested {
        /// The unit that asked (the first, if several did in one step).
        unit: String,
        /// The end of that step [s]: where the run ended.
        time: f64,
    },
    /// The interrupt flag was raised; the run ended at `time` [s].
    Interrupted {
        /// The last communication point [s].
        time: f64,
    },
}

/// A system being simulated. The recorded rows stay available whatever happens.
pub struct Simulation {
    system: System,
    units: Vec<Unit>,
    schedule: Schedule,
    time: f64,
    /// The communication point whole steps are counted from [s]: the start, or the end of
    /// the last shortened step.
    anchor: f64,
    step: f64,
    steps_taken: u64,
    algorithm: Algorithm,
    recorder: Recorder,
    on_discard: OnDiscard,
    /// Why no more steps can be taken, once a unit discarded one.
    ended: Option<MasterError>,
    /// The unit that completed a step asking to end the simulation.
    end_requested: Option<String>,
    interrupt: Option<Arc<AtomicBool>>,
    notices: Vec<String>,
    /// Scheduled changes, in time order ([`Simulation::schedule`]).
    events: Vec<Scheduled>,
    /// The communication point the events were last applied at.
    events_applied_at: Option<f64>,
}

/// One variable of an [`EventSpec`], resolved and checked.
#[derive(Clone, Debug)]
struct Scheduled {
    time: f64,
    until: Option<f64>,
    unit: usize,
    variable: String,
    value_reference: u32,
    value: Value,
    /// A ramp's value at its start, read when it starts.
    from: Option<f64>,
    done: bool,
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
        if !start.is_finite() {
            return Err(MasterError::new(format!("the start time must be finite, not {start}")));
        }
        let schedule = Schedule::new(&self)?;
        let recorder = Recorder::new(record.to_vec(), self.recordable(record)?);
        let mut shared = SharedBinaries::default();
        let units = self.units().iter().map(|plan| Unit::load(plan, &mut shared)).collect::<Result<Vec<_>, _>>()?;
        let mut sim = Simulation {
            system: self,
            units,
            schedule,
            time: start,
            anchor: start,
            step,
            steps_taken: 0,
            algorithm,
            recorder,
            on_discard: OnDiscard::default(),
            ended: None,
            end_requested: None,
            interrupt: None,
            notices: Vec::new(),
            events: Vec::new(),
            events_applied_at: None,
        };
        sim.start_up(start)?;
        Ok(sim)
    }
}

impl Simulation {
    fn start_up(&mut self, start: f64) -> Result<(), MasterError> {
        for u in &mut self.units {
            let mark = capture::mark();
            u.setup(start).map_err(|e| u.fail(e, mark, None))?;
        }
        for k in 0..self.system.settings().len() {
            let s = &self.system.settings()[k];
            let (unit, variable, value) = (s.unit, s.variable.clone(), s.value.clone());
            self.set_value(unit, &variable, &value)?;
        }
        for u in &mut self.units {
            let mark = capture::mark();
            u.enter_initialization(start).map_err(|e| u.fail(e, mark, None))?;
        }
        self.resolve_all(None)?;
        for u in &mut self.units {
            let mark = capture::mark();
            u.exit_initialization().map_err(|e| u.fail(e, mark, None))?;
        }
        self.resolve_all(Some(start))?;
        self.recorder.record(&mut self.units, self.time)?;
        Ok(())
    }

    /// Sets variable `name` of unit `ui` to `value`, checked and converted for its type.
    fn set_value(&mut self, ui: usize, name: &str, value: &Value) -> Result<(), MasterError> {
        let plan = &self.system.units()[ui];
        let info = plan.variable(name)?;
        let value = check_value(&plan.interface, info, value).map_err(|e| e.unit(&plan.name).variable(name))?;
        let (vr, base) = ([info.value_reference], info.base);
        let unit = &mut self.units[ui];
        let mark = capture::mark();
        let r = match &value {
            Value::Real(x) => unit.set_real(&vr, &[*x]),
            Value::Integer(i) if base.access() == BaseType::Real => unit.set_real(&vr, &[*i as f64]),
            Value::Integer(i) => unit.set_integer(&vr, &[*i]),
            Value::Boolean(b) => unit.set_boolean(&vr, &[*b as i32]),
            Value::String(s) => {
                let c =
                    CString::new(s.as_str()).map_err(|_| MasterError::new("a string holds a NUL byte").unit(&unit.name).variable(name))?;
                unit.set_string(&vr, &[c])
            }
        };
        r.map_err(|e| {
            let mut x = unit.fail(e, mark, None).variable(name);
            x.message = format!("setting {value:?} refused: {}", x.message);
            x
        })
    }

    /// Passes on the outputs of the dirty passes, in resolve order; a pass whose outputs
    /// follow inputs it just received becomes dirty in turn, unless (in a Gauss–Seidel sweep,
    /// `position` being the step position just done) its unit steps later and nobody needs
    /// its outputs before.
    fn resolve_dirty(&mut self, time: Option<f64>, position: Option<usize>) -> Result<(), MasterError> {
        for p in 0..self.schedule.passes.len() {
            if !self.schedule.dirty[p] {
                continue;
            }
            self.schedule.dirty[p] = false;
            let plan = &mut self.schedule;
            let units = &mut self.units;
            let pass = &plan.passes[p];
            let u = pass.unit;
            let mark = capture::mark();
            let [reals, ints, bools, strings] = &pass.reads;
            if !reals.is_empty() {
                units[u].get_real(reals, &mut plan.buf_real[..reals.len()]).map_err(|e| units[u].fail(e, mark, time))?;
            }
            if !ints.is_empty() {
                units[u].get_integer(ints, &mut plan.buf_int[..ints.len()]).map_err(|e| units[u].fail(e, mark, time))?;
            }
            if !bools.is_empty() {
                units[u].get_boolean(bools, &mut plan.buf_bool[..bools.len()]).map_err(|e| units[u].fail(e, mark, time))?;
            }
            if !strings.is_empty() {
                units[u].get_string(strings, &mut plan.buf_str[..strings.len()]).map_err(|e| units[u].fail(e, mark, time))?;
            }
            for t in &pass.transfers {
                let m = t.vrs.len();
                let target = &mut units[t.to];
                let r = match t.base {
                    BaseType::Real => {
                        for (v, &k) in plan.set_real.iter_mut().zip(&t.from) {
                            *v = plan.buf_real[k];
                        }
                        target.set_real(&t.vrs, &plan.set_real[..m])
                    }
                    BaseType::Integer => {
                        for (v, &k) in plan.set_int.iter_mut().zip(&t.from) {
                            *v = plan.buf_int[k];
                        }
                        target.set_integer(&t.vrs, &plan.set_int[..m])
                    }
                    BaseType::Boolean => {
                        for (v, &k) in plan.set_bool.iter_mut().zip(&t.from) {
                            *v = plan.buf_bool[k];
                        }
                        target.set_boolean(&t.vrs, &plan.set_bool[..m])
                    }
                    _ => {
                        for (v, &k) in plan.set_str.iter_mut().zip(&t.from) {
                            v.clone_from(&plan.buf_str[k]);
                        }
                        target.set_string(&t.vrs, &plan.set_str[..m])
                    }
                };
                r.map_err(|e| {
                    let names: Vec<&str> = self
                        .system
                        .links()
                        .iter()
                        .filter(|l| l.to_unit == t.to && l.base.access() == t.base && t.vrs.contains(&l.to_vr))
                        .map(|l| l.to_variable.as_str())
                        .collect();
                    let mut x = target.fail(e, mark, time).variable(&names.join(", "));
                    x.message += " (passing a connection on)";
                    x
                })?;
            }
            for t in 0..self.schedule.passes[p].transfers.len() {
                for w in 0..self.schedule.passes[p].transfers[t].wakes.len() {
                    let q = self.schedule.passes[p].transfers[t].wakes[w];
                    if !self.schedule.can_wait(q, position) {
                        self.schedule.dirty[q] = true;
                    }
                }
            }
        }
        Ok(())
    }

    fn resolve_all(&mut self, time: Option<f64>) -> Result<(), MasterError> {
        self.schedule.dirty.fill(true);
        self.resolve_dirty(time, None)
    }

    /// Records every `k`-th communication point only (k ≥ 1; the first is always recorded,
    /// and so is the stop time when the last step was shortened to land on it).
    pub fn record_every(&mut self, k: u64) {
        self.recorder.every = k.max(1);
    }

    /// What a unit discarding a step does to a run: end it (the default) or fail it.
    pub fn on_discard(&mut self, policy: OnDiscard) {
        self.on_discard = policy;
    }

    /// Ends [`Simulation::run_until`] at the next communication point once `flag` is raised
    /// (e.g. from a Ctrl-C handler); the rows so far are kept.
    pub fn interrupt_on(&mut self, flag: Arc<AtomicBool>) {
        self.interrupt = Some(flag);
    }

    /// What the run had to tell beyond its rows (a stop time it could not land on, a unit
    /// that discarded a step), in order.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// Schedules changes while running (see [`EventSpec`] for what they do). Each variable is
    /// checked now: it must exist, be a tunable parameter or an input no connection drives,
    /// take the value's type, and be Real for a ramp. Events due at the current point (the
    /// start) are applied before the next step; the row already recorded there shows the
    /// values from initialization. Every later row shows the values after the events due at
    /// its time, those the next step uses.
    pub fn schedule(&mut self, events: &[EventSpec]) -> Result<(), MasterError> {
        let mut added = Vec::new();
        for (k, event) in events.iter().enumerate() {
            let at = |e: MasterError| {
                let mut e = e;
                e.message = format!("event {} (t = {} s): {}", k + 1, event.time, e.message);
                e
            };
            event.check().map_err(|e| at(e.into()))?;
            for (full, value) in &event.set {
                let (u, v) = split_name(full).map_err(at)?;
                let unit = self.system.unit_index(u).map_err(at)?;
                let plan = &self.system.units()[unit];
                let info = plan.variable(v).map_err(at)?;
                let fail = |m: &str| at(MasterError::new(m).unit(u).variable(v));
                let changeable = match info.causality {
                    Causality::Input => !self.system.is_connected(unit, info.value_reference, info.base),
                    Causality::Parameter => info.variability == Variability::Tunable,
                    _ => false,
                };
                if !changeable {
                    return Err(fail(match info.causality {
                        Causality::Input => "this input is connected; the connection sets it",
                        Causality::Parameter => "only a tunable parameter can change while running; this one is fixed",
                        _ => "only tunable parameters and unconnected inputs can change while running",
                    }));
                }
                check_value(&plan.interface, info, value).map_err(|e| fail(&e.message))?;
                if event.until.is_some() && info.base.access() != BaseType::Real {
                    return Err(fail("only a Real variable can be ramped"));
                }
                added.push(Scheduled {
                    time: event.time,
                    until: event.until,
                    unit,
                    variable: v.to_owned(),
                    value_reference: info.value_reference,
                    value: value.clone(),
                    from: None,
                    done: false,
                });
            }
        }
        self.events.extend(added);
        // New events due now are applied before the next step, even if others were already.
        self.events_applied_at = None;
        // Stable: equal times keep the order they were given in.
        self.events.sort_by(|a, b| a.time.total_cmp(&b.time));
        Ok(())
    }

    /// Applies the scheduled changes due at the current communication point and passes their
    /// effect on.
    fn apply_events(&mut self) -> Result<(), MasterError> {
        let t = self.time;
        if self.events.is_empty() || self.events_applied_at == Some(t) {
            return Ok(());
        }
        self.events_applied_at = Some(t);
        let due = t + STEP_TOLERANCE * self.step;
        let mut touched = false;
        for k in 0..self.events.len() {
            let e = &self.events[k];
            if e.time > due {
                break;
            }
            if e.done {
                continue;
            }
            let unit = e.unit;
            match e.until {
                None => {
                    let (variable, value) = (e.variable.clone(), e.value.clone());
                    self.set_value(unit, &variable, &value).map_err(|e| e.at(t))?;
                    self.events[k].done = true;
                }
                Some(until) => {
                    let vr = [e.value_reference];
                    let target = match e.value {
                        Value::Real(x) => x,
                        Value::Integer(i) => i as f64,
                        _ => unreachable!("checked when scheduled: a ramp is of a Real"),
                    };
                    let u = &mut self.units[unit];
                    let from = match e.from {
                        Some(x) => x,
                        None => {
                            let mut x = [0.0];
                            let mark = capture::mark();
                            u.get_real(&vr, &mut x).map_err(|err| u.fail(err, mark, Some(t)))?;
                            x[0]
                        }
                    };
                    let end = due >= until;
                    let x = if end { target } else { from + (target - from) * ((t - e.time) / (until - e.time)).clamp(0.0, 1.0) };
                    let mark = capture::mark();
                    u.set_real(&vr, &[x]).map_err(|err| u.fail(err, mark, Some(t)).variable(&self.events[k].variable))?;
                    self.events[k].from = Some(from);
                    self.events[k].done = end;
                }
            }
            self.schedule.touch_unit(unit);
            touched = true;
        }
        if touched {
            self.resolve_dirty(Some(t), None)?;
        }
        Ok(())
    }

    /// One communication step from the current time. After a unit discarded a step the
    /// system cannot go on, and every further call is an error.
    pub fn step(&mut self) -> Result<(), MasterError> {
        self.step_by(self.step)?;
        self.steps_taken += 1;
        // Times from the step count, so long runs do not accumulate rounding.
        self.time = self.anchor + self.steps_taken as f64 * self.step;
        // The row of a communication point shows the values the next step uses.
        self.apply_events()?;
        // The last row of a run a unit ends is always recorded.
        if self.steps_taken % self.recorder.every == 0 || self.end_requested.is_some() {
            self.recorder.record(&mut self.units, self.time)?;
        }
        Ok(())
    }

    /// Every unit steps by `h` [s] from the current time, connections resolved as the
    /// algorithm says; the time is not advanced.
    fn step_by(&mut self, h: f64) -> Result<(), MasterError> {
        if let Some(e) = &self.ended {
            let mut e = e.clone();
            e.message = format!("the run has ended and cannot step on: {}", e.message);
            return Err(e);
        }
        // Events due at the start time (the later ones were applied on arrival).
        self.apply_events()?;
        let t = self.time;
        let result = match self.algorithm {
            Algorithm::GaussSeidel => (|| {
                for i in 0..self.schedule.step_order.len() {
                    let u = self.schedule.step_order[i];
                    self.do_step(u, t, h)?;
                    self.schedule.touch_unit(u);
                    self.resolve_dirty(Some(t), Some(i))?;
                }
                Ok(())
            })(),
            Algorithm::Jacobi => (|| {
                for u in 0..self.units.len() {
                    self.do_step(u, t, h)?;
                }
                self.resolve_all(Some(t))
            })(),
        };
        if let Err(e) = &result {
            if e.discard.is_some() {
                self.ended = Some(e.clone());
            }
        }
        if let (Ok(()), Some(unit)) = (&result, &self.end_requested) {
            let end = t + h;
            self.ended = Some(MasterError::new(format!("unit '{unit}' asked to end the simulation at t = {end} s")).unit(unit).at(end));
        }
        result
    }

    fn do_step(&mut self, u: usize, t: f64, h: f64) -> Result<(), MasterError> {
        let unit = &mut self.units[u];
        let mark = capture::mark();
        // Named only when a step fails: a step of the run allocates nothing.
        let prefix = unit.version().prefix();
        let call = || format!("{prefix}DoStep");
        match unit.do_step(t, h) {
            Ok(Stepped::Completed) => Ok(()),
            // FMI 2.0 says a step completed before the request to end through
            // fmi2LastSuccessfulTime at the step's end (as the Reference-FMUs do).
            Ok(Stepped::Discarded(DiscardedStep { terminated: Some(true), last_successful_time: Some(last) }))
                if (last - (t + h)).abs() <= STEP_TOLERANCE * h =>
            {
                let name = unit.name.clone();
                self.end_requested.get_or_insert(name);
                Ok(())
            }
            Ok(Stepped::CompletedEnding) => {
                let name = unit.name.clone();
                self.end_requested.get_or_insert(name);
                Ok(())
            }
            Ok(Stepped::Discarded(status)) => {
                let call = call();
                let mut e = unit.fail(crate::unit::CallError { call: call.clone(), status: "Discard".into() }, mark, Some(t));
                e.message = match (status.terminated, status.last_successful_time) {
                    (Some(true), _) => format!("the unit asks to end the simulation ({call} returned with the request to terminate)"),
                    (_, Some(last)) => {
                        format!("{call} returned Discard: the step from {t} s by {h} s was not completed (last successful time {last} s)")
                    }
                    _ => format!("{call} returned Discard: the step from {t} s by {h} s was not completed"),
                };
                e.discard = Some(Box::new(status));
                Err(e)
            }
            Err(e) => Err(unit.fail(e, mark, Some(t))),
        }
    }

    /// Steps until `stop` [s]: whole communication steps, and a last shorter one that lands on
    /// `stop` when the span is not a whole number of steps and every unit can handle a
    /// variable step (else the run ends at the last whole step and a notice says why). A unit
    /// that discards a step ends the run there ([`RunEnd::Discarded`], the rows so far kept)
    /// unless [`OnDiscard::Error`] makes it an error; a raised interrupt flag ends it at the
    /// next communication point.
    pub fn run_until(&mut self, stop: f64) -> Result<RunEnd, MasterError> {
        let span = ((stop - self.time) / self.step).ceil();
        if span.is_finite() && span > 0.0 {
            self.reserve_steps(span.min(u32::MAX as f64) as usize);
        }
        loop {
            let remaining = stop - self.time;
            if remaining <= STEP_TOLERANCE * self.step {
                return Ok(RunEnd::Completed);
            }
            if self.interrupt.as_ref().is_some_and(|f| f.load(Ordering::Relaxed)) {
                return Ok(RunEnd::Interrupted { time: self.time });
            }
            let outcome = if remaining >= (1.0 - STEP_TOLERANCE) * self.step {
                self.step()
            } else {
                if let Some(u) = self.system.units().iter().find(|u| !u.interface.can_handle_variable_step) {
                    self.notices.push(format!(
                        "the run ends at t = {} s, {remaining} s before the stop time {stop} s: unit '{}' cannot take a shorter last step (canHandleVariableCommunicationStepSize is false)",
                        self.time, u.name
                    ));
                    return Ok(RunEnd::Completed);
                }
                self.step_by(remaining).and_then(|()| {
                    self.time = stop;
                    self.anchor = stop;
                    self.steps_taken = 0;
                    self.apply_events()?;
                    self.recorder.record(&mut self.units, self.time)
                })
            };
            match outcome {
                Ok(()) if self.end_requested.is_some() => {
                    let unit = self.end_requested.clone().expect("checked");
                    self.notices.push(format!(
                        "unit '{unit}' completed the step to t = {} s and asks to end the simulation; the run ends there",
                        self.time
                    ));
                    return Ok(RunEnd::EndRequested { unit, time: self.time });
                }
                Ok(()) => {}
                Err(e) if e.discard.is_some() && self.on_discard == OnDiscard::Stop => {
                    let unit = e.unit.clone().unwrap_or_default();
                    let status = *e.discard.clone().expect("checked");
                    let terminated = match status.terminated {
                        Some(true) => "it asks to end the simulation",
                        Some(false) => "it does not ask to end the simulation",
                        None => "it could not say why",
                    };
                    self.notices.push(format!(
                        "unit '{unit}' discarded the step from t = {} s ({terminated}); the run ends at t = {} s, the last communication point every unit completed",
                        self.time, self.time
                    ));
                    return Ok(RunEnd::Discarded { unit, time: self.time, status, log: e.log });
                }
                Err(e) => return Err(e),
            }
        }
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
        if self.system.is_connected(ui, info.value_reference, info.base) {
            return Err(MasterError::new("this input is connected; the connection sets it").unit(u).variable(v));
        }
        self.set_value(ui, v, &value).map_err(|e| e.at(self.time))?;
        self.schedule.touch_unit(ui);
        self.resolve_dirty(Some(self.time), None)
    }

    /// A handle on a Real variable ("unit.variable") for fast reads with [`Self::get_reals`]
    /// and, if it is an unconnected input or a tunable parameter, writes with [`Self::set_reals`].
    pub fn real_handle(&self, full: &str) -> Result<Handle, MasterError> {
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let info = self.system.units()[ui].variable(v)?;
        if info.base.access() != BaseType::Real || info.is_array {
            return Err(MasterError::new(format!("type mismatch: {:?}, not a scalar Real", info.base)).unit(u).variable(v));
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
            unit.set_real(&[h.value_reference], &[x]).map_err(|e| unit.fail(e, mark, Some(self.time)))?;
            self.schedule.touch_unit(h.unit);
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
            unit.get_real(&[h.value_reference], &mut x).map_err(|e| unit.fail(e, mark, Some(self.time)))?;
            *o = x[0];
        }
        Ok(())
    }

    /// Column names of the recording: "time", then the recorded variables.
    pub fn columns(&self) -> Vec<String> {
        self.recorder.columns()
    }

    /// The base type of each column ("time" is Real).
    pub fn column_types(&self) -> Vec<BaseType> {
        self.recorder.column_types()
    }

    /// The recorded rows (time first). Integer, Boolean (0 or 1) and enumeration values are
    /// exact in an f64; a String column holds NaN here and its text in [`Self::texts`].
    pub fn rows(&self) -> &Rows {
        &self.recorder.rows
    }

    /// Per recorded row, the values of the String columns in column order.
    pub fn texts(&self) -> &[Vec<String>] {
        &self.recorder.texts
    }

    /// Takes the recorded rows out, leaving none.
    pub fn take_rows(&mut self) -> Vec<Vec<f64>> {
        self.recorder.take()
    }

    /// Makes room to record `steps` more communication steps, so that stepping through them
    /// allocates nothing ([`Self::run_until`] makes room for its span itself).
    pub fn reserve_steps(&mut self, steps: usize) {
        self.recorder.reserve(steps.div_ceil(self.recorder.every.max(1) as usize) + 1);
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
