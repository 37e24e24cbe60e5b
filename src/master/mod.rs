//! A co-simulation master for FMI 2.0 Co-Simulation FMUs, over the `fmi` crate. It knows
//! nothing of robots: it loads `.fmu` files, sets parameters by name, connects outputs to
//! inputs by name, steps at a fixed communication step and records chosen variables.
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

mod capture;
mod spec;
pub mod ssp;

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::fmi2::schema::{Causality as SchemaCausality, ScalarVariableElement};
use fmi::traits::FmiImport;

pub use spec::{ConnectionSpec, FmuEntry, SimulationSpec, SystemSpec};

/// How units are stepped within one communication step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// One after another, each passing its new outputs on before the next steps.
    #[default]
    GaussSeidel,
    /// All from the same inputs, then all outputs passed on.
    Jacobi,
}

/// A value to set: the base type follows the variable, with integers accepted for reals.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// A Boolean.
    Boolean(bool),
    /// An integer (also accepted by Real variables).
    Integer(i64),
    /// A real.
    Real(f64),
    /// A string.
    String(String),
}

/// What went wrong, where and when. `unit` names the FMU (as named in the system),
/// `variable` the variable if one is concerned, `time` the communication point [s] if the
/// simulation had started; `log` holds the FMU's own messages logged during the failing call.
#[derive(Clone, Debug, PartialEq)]
pub struct MasterError {
    /// The unit concerned.
    pub unit: Option<String>,
    /// The variable concerned.
    pub variable: Option<String>,
    /// Communication point [s].
    pub time: Option<f64>,
    /// What happened.
    pub message: String,
    /// Messages the FMU logged in the failing call.
    pub log: Vec<String>,
}

impl MasterError {
    fn new(message: impl Into<String>) -> Self {
        Self { unit: None, variable: None, time: None, message: message.into(), log: Vec::new() }
    }
    fn unit(mut self, unit: &str) -> Self {
        self.unit = Some(unit.to_owned());
        self
    }
    fn variable(mut self, variable: &str) -> Self {
        self.variable = Some(variable.to_owned());
        self
    }
    fn at(mut self, time: f64) -> Self {
        self.time = Some(time);
        self
    }
}

impl fmt::Display for MasterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.unit, &self.variable) {
            (Some(u), Some(v)) => write!(f, "FMU '{u}', variable '{v}'")?,
            (Some(u), None) => write!(f, "FMU '{u}'")?,
            (None, Some(v)) => write!(f, "variable '{v}'")?,
            (None, None) => write!(f, "system")?,
        }
        if let Some(t) = self.time {
            write!(f, " at t = {t} s")?;
        }
        write!(f, ": {}", self.message)?;
        for line in &self.log {
            write!(f, "\n  FMU log: {line}")?;
        }
        Ok(())
    }
}

impl std::error::Error for MasterError {}

/// A variable's base type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    /// fmi2Real.
    Real,
    /// fmi2Integer.
    Integer,
    /// fmi2Boolean.
    Boolean,
    /// fmi2String.
    String,
    /// An enumeration (not supported in connections).
    Enumeration,
}

/// A variable of a loaded FMU.
#[derive(Clone, Debug)]
pub struct VariableInfo {
    /// Value reference.
    pub value_reference: u32,
    /// Base type.
    pub base: BaseType,
    /// Causality as written in the model description ("input", "output", ...).
    pub causality: &'static str,
}

/// One loaded FMU: the unzipped import (kept alive for the binary) and its instance.
pub struct Unit {
    name: String,
    path: PathBuf,
    variables: HashMap<String, VariableInfo>,
    /// Value references of inputs that some output depends on directly.
    feedthrough_inputs: Vec<u32>,
    instance: InstanceCS,
    _import: Fmi2Import,
}

impl Unit {
    /// Loads `path` and instantiates it as `name` (the instance name, used in messages).
    pub fn load(name: &str, path: &Path) -> Result<Self, MasterError> {
        capture::install();
        let err = |m: String| MasterError::new(m).unit(name);
        let import: Fmi2Import = fmi::import::from_path(path).map_err(|e| err(format!("cannot load {}: {e}", path.display())))?;
        let md = import.model_description();
        if md.co_simulation.is_none() {
            return Err(err(format!("{} is not a Co-Simulation FMU", path.display())));
        }
        let mut variables = HashMap::new();
        let mut by_index = Vec::new();
        for v in &md.model_variables.variables {
            let base = match &v.elem {
                ScalarVariableElement::Real(_) => BaseType::Real,
                ScalarVariableElement::Integer(_) => BaseType::Integer,
                ScalarVariableElement::Boolean(_) => BaseType::Boolean,
                ScalarVariableElement::String => BaseType::String,
                ScalarVariableElement::Enumeration => BaseType::Enumeration,
            };
            let causality = match v.causality {
                SchemaCausality::Parameter => "parameter",
                SchemaCausality::CalculatedParameter => "calculatedParameter",
                SchemaCausality::Input => "input",
                SchemaCausality::Output => "output",
                SchemaCausality::Independent => "independent",
                _ => "local",
            };
            by_index.push((v.value_reference, causality));
            variables.insert(v.name.clone(), VariableInfo { value_reference: v.value_reference, base, causality });
        }
        let xml_path = import.archive_path().join("modelDescription.xml");
        let xml = std::fs::read_to_string(&xml_path).map_err(|e| err(format!("reading its modelDescription.xml: {e}")))?;
        let deps = spec::output_dependencies(&xml).map_err(|e| err(format!("modelDescription.xml: {e}")))?;
        let inputs: Vec<u32> = by_index.iter().filter(|(_, c)| *c == "input").map(|(vr, _)| *vr).collect();
        let mut feedthrough_inputs = Vec::new();
        for d in deps {
            let listed: Vec<u32> = match d {
                // No `dependencies` attribute: the output may depend on every input.
                None => inputs.clone(),
                Some(list) => list
                    .iter()
                    .filter_map(|&i| by_index.get((i as usize).wrapping_sub(1)))
                    .filter(|(_, c)| *c == "input")
                    .map(|(vr, _)| *vr)
                    .collect(),
            };
            for vr in listed {
                if !feedthrough_inputs.contains(&vr) {
                    feedthrough_inputs.push(vr);
                }
            }
        }
        let before = capture::mark();
        let instance = import.instantiate_cs(name, false, false).map_err(|e| {
            let mut x = err(format!("fmi2Instantiate of {} failed: {e}", path.display()));
            x.log = capture::since(before, name);
            x
        })?;
        Ok(Self { name: name.to_owned(), path: path.to_owned(), variables, feedthrough_inputs, instance, _import: import })
    }

    /// The unit's name in the system.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The `.fmu` it was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A variable by name.
    pub fn variable(&self, name: &str) -> Result<&VariableInfo, MasterError> {
        self.variables.get(name).ok_or_else(|| MasterError::new("no such variable in the FMU").unit(&self.name).variable(name))
    }

    /// Names of all variables.
    pub fn variable_names(&self) -> impl Iterator<Item = &str> {
        self.variables.keys().map(String::as_str)
    }

    fn has_feedthrough(&self) -> bool {
        !self.feedthrough_inputs.is_empty()
    }

    fn fail(&self, call: &str, status: impl fmt::Debug, since: usize, time: Option<f64>) -> MasterError {
        let mut e = MasterError::new(format!("{call} returned {status:?}")).unit(&self.name);
        e.time = time;
        e.log = capture::since(since, &self.name);
        e
    }
}

/// A connection resolved to value references.
#[derive(Clone, Debug)]
struct Link {
    from_unit: usize,
    from_vr: u32,
    to_unit: usize,
    to_vr: u32,
    base: BaseType,
    /// The target input feeds an output of its unit directly.
    feeds_through: bool,
}

/// A system of units and connections, before it is initialised.
pub struct System {
    units: Vec<Unit>,
    links: Vec<Link>,
    /// (unit, variable, value) set before initialisation.
    settings: Vec<(usize, String, Value)>,
}

/// A variable named "unit.variable".
fn split_name(full: &str) -> Result<(&str, &str), MasterError> {
    full.split_once('.').ok_or_else(|| MasterError::new(format!("'{full}' must be written as unit.variable")))
}

impl System {
    /// An empty system.
    pub fn new() -> Self {
        Self { units: Vec::new(), links: Vec::new(), settings: Vec::new() }
    }

    /// Loads `path` as unit `name`.
    pub fn add_fmu(&mut self, name: &str, path: &Path) -> Result<&mut Self, MasterError> {
        if name.is_empty() || name.contains('.') {
            return Err(MasterError::new("a unit name must be non-empty and hold no '.'").unit(name));
        }
        if self.units.iter().any(|u| u.name == name) {
            return Err(MasterError::new("two units have this name").unit(name));
        }
        let unit = Unit::load(name, path)?;
        self.units.push(unit);
        Ok(self)
    }

    /// The units, in declaration order.
    pub fn units(&self) -> &[Unit] {
        &self.units
    }

    fn unit_index(&self, name: &str) -> Result<usize, MasterError> {
        self.units.iter().position(|u| u.name == name).ok_or_else(|| MasterError::new("no unit of this name in the system").unit(name))
    }

    /// Sets a parameter (or an unconnected input's value) before initialisation.
    pub fn set(&mut self, unit: &str, variable: &str, value: Value) -> Result<&mut Self, MasterError> {
        let u = self.unit_index(unit)?;
        let info = self.units[u].variable(variable)?;
        check_value(info, &value).map_err(|m| MasterError::new(m).unit(unit).variable(variable))?;
        if !matches!(info.causality, "parameter" | "input") {
            let article = if info.causality.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" };
            return Err(MasterError::new(format!("{article} {} cannot be set; only parameters and inputs", info.causality)).unit(unit).variable(variable));
        }
        self.settings.push((u, variable.to_owned(), value));
        Ok(self)
    }

    /// Connects output `from` ("unit.variable") to input `to`. A `*` in both names stands for
    /// the same text, so "arm.q_*" → "ctrl.q_*" connects every matching output.
    pub fn connect(&mut self, from: &str, to: &str) -> Result<&mut Self, MasterError> {
        let (fu, fv) = split_name(from)?;
        let (tu, tv) = split_name(to)?;
        let (fi, ti) = (self.unit_index(fu)?, self.unit_index(tu)?);
        let pairs: Vec<(String, String)> = match (fv.split_once('*'), tv.split_once('*')) {
            (Some((fp, fs)), Some((tp, ts))) => {
                let mut names: Vec<&str> = self.units[fi]
                    .variable_names()
                    .filter(|n| n.len() >= fp.len() + fs.len() && n.starts_with(fp) && n.ends_with(fs))
                    .collect();
                names.sort_unstable();
                let found: Vec<_> = names
                    .into_iter()
                    .filter(|n| self.units[fi].variables[*n].causality == "output")
                    .map(|n| (n.to_owned(), format!("{tp}{}{ts}", &n[fp.len()..n.len() - fs.len()])))
                    .collect();
                if found.is_empty() {
                    return Err(MasterError::new(format!("no output matches '{fv}'")).unit(fu));
                }
                found
            }
            (None, None) => vec![(fv.to_owned(), tv.to_owned())],
            _ => return Err(MasterError::new(format!("'{from}' → '{to}': use '*' in both names or in neither"))),
        };
        for (fv, tv) in pairs {
            let src = self.units[fi].variable(&fv)?.clone();
            let dst = self.units[ti].variable(&tv)?.clone();
            if src.causality != "output" {
                return Err(MasterError::new(format!("a connection must start at an output, not a {}", src.causality)).unit(fu).variable(&fv));
            }
            if dst.causality != "input" {
                return Err(MasterError::new(format!("a connection must end at an input, not a {}", dst.causality)).unit(tu).variable(&tv));
            }
            if src.base != dst.base || matches!(src.base, BaseType::String | BaseType::Enumeration) {
                return Err(MasterError::new(format!("type mismatch: {fu}.{fv} is {:?}, {tu}.{tv} is {:?} (Real, Integer and Boolean connect to their own type)", src.base, dst.base))
                    .unit(tu)
                    .variable(&tv));
            }
            if self.links.iter().any(|l| l.to_unit == ti && l.to_vr == dst.value_reference) {
                return Err(MasterError::new("this input is already connected").unit(tu).variable(&tv));
            }
            let feeds_through = self.units[ti].feedthrough_inputs.contains(&dst.value_reference);
            self.links.push(Link { from_unit: fi, from_vr: src.value_reference, to_unit: ti, to_vr: dst.value_reference, base: src.base, feeds_through });
        }
        Ok(self)
    }

    /// Builds a system from a spec; relative FMU paths are taken from `base`.
    pub fn from_spec(spec: &SystemSpec, base: &Path) -> Result<Self, MasterError> {
        let mut system = Self::new();
        for f in &spec.fmu {
            system.add_fmu(&f.name, &base.join(&f.path))?;
            let mut names: Vec<_> = f.parameters.iter().collect();
            names.sort_by(|a, b| a.0.cmp(b.0));
            for (k, v) in names {
                system.set(&f.name, k, v.clone())?;
            }
        }
        for c in &spec.connection {
            system.connect(&c.from, &c.to)?;
        }
        Ok(system)
    }

    /// Order in which connections are resolved: each unit after those feeding its direct
    /// feedthrough inputs. An algebraic loop is an error naming its units.
    fn resolve_order(&self) -> Result<Vec<usize>, MasterError> {
        let n = self.units.len();
        let mut indegree = vec![0usize; n];
        for l in self.links.iter().filter(|l| l.feeds_through) {
            indegree[l.to_unit] += 1;
        }
        let mut order = Vec::with_capacity(n);
        let mut done = vec![false; n];
        while order.len() < n {
            let Some(u) = (0..n).find(|&u| !done[u] && indegree[u] == 0) else {
                let names: Vec<_> = (0..n).filter(|&u| !done[u]).map(|u| self.units[u].name.as_str()).collect();
                return Err(MasterError::new(format!(
                    "algebraic loop: the outputs of {} depend directly on each other's inputs, so no order resolves them",
                    names.join(", ")
                )));
            };
            done[u] = true;
            order.push(u);
            for l in self.links.iter().filter(|l| l.feeds_through && l.from_unit == u) {
                indegree[l.to_unit] -= 1;
            }
        }
        Ok(order)
    }

    /// Gauss–Seidel stepping order: topological over all connections; a cycle is cut at its
    /// first unit (declaration order) without direct feedthrough.
    fn step_order(&self) -> Result<Vec<usize>, MasterError> {
        let n = self.units.len();
        let mut indegree = vec![0usize; n];
        for l in &self.links {
            if l.from_unit != l.to_unit {
                indegree[l.to_unit] += 1;
            }
        }
        let mut order = Vec::with_capacity(n);
        let mut done = vec![false; n];
        while order.len() < n {
            let u = (0..n)
                .find(|&u| !done[u] && indegree[u] == 0)
                .or_else(|| (0..n).find(|&u| !done[u] && !self.units[u].has_feedthrough()))
                .ok_or_else(|| MasterError::new("a cycle of units that all have direct feedthrough cannot be stepped in order"))?;
            done[u] = true;
            order.push(u);
            for l in self.links.iter().filter(|l| l.from_unit == u && l.to_unit != u) {
                indegree[l.to_unit] = indegree[l.to_unit].saturating_sub(1);
            }
        }
        Ok(order)
    }

    /// Initialises every unit at `start` [s] for steps of `step` [s]; `record` lists the
    /// variables ("unit.variable") to record at each communication point.
    pub fn initialize(self, start: f64, step: f64, algorithm: Algorithm, record: &[String]) -> Result<Simulation, MasterError> {
        if !(step > 0.0 && step.is_finite()) {
            return Err(MasterError::new(format!("the communication step must be positive, not {step}")));
        }
        let resolve_order = self.resolve_order()?;
        let step_order = self.step_order()?;
        let mut recorded = Vec::new();
        for full in record {
            let (u, v) = split_name(full)?;
            let ui = self.unit_index(u)?;
            let info = self.units[ui].variable(v)?;
            if matches!(info.base, BaseType::String | BaseType::Enumeration) {
                return Err(MasterError::new("only Real, Integer and Boolean variables can be recorded").unit(u).variable(v));
            }
            recorded.push((ui, info.value_reference, info.base));
        }
        let mut sim = Simulation {
            plan: Plan::new(&self, resolve_order, step_order),
            system: self,
            time: start,
            step,
            steps_taken: 0,
            start,
            algorithm,
            columns: record.to_vec(),
            recorded,
            rows: Vec::new(),
            record_every: 1,
        };
        sim.start_up()?;
        Ok(sim)
    }
}

impl Default for System {
    fn default() -> Self {
        Self::new()
    }
}

fn check_value(info: &VariableInfo, value: &Value) -> Result<(), String> {
    let ok = matches!(
        (info.base, value),
        (BaseType::Real, Value::Real(_) | Value::Integer(_))
            | (BaseType::Integer, Value::Integer(_))
            | (BaseType::Boolean, Value::Boolean(_))
            | (BaseType::String, Value::String(_))
    );
    if !ok {
        return Err(format!("type mismatch: the variable is {:?}, the value {value:?}", info.base));
    }
    if let Value::Integer(i) = value {
        if info.base == BaseType::Integer && i32::try_from(*i).is_err() {
            return Err(format!("{i} does not fit an fmi2Integer"));
        }
    }
    Ok(())
}

/// The inputs of one unit of one base type fed by one source unit: set in one call.
struct Transfer {
    base: BaseType,
    to: usize,
    /// Value references of the inputs set.
    vrs: Vec<u32>,
    /// For each, its index in the source unit's read list of that type.
    from: Vec<usize>,
    /// Some of these inputs feed the target's outputs directly.
    feeds: bool,
}

/// Precomputed transfers: per unit, the outputs it gives and where they go.
struct Plan {
    resolve_order: Vec<usize>,
    step_order: Vec<usize>,
    /// Position of each unit in the step order.
    step_position: Vec<usize>,
    /// Per unit: the units its outputs go to.
    consumers: Vec<Vec<usize>>,
    /// Per unit: value references to read, by type.
    out_real: Vec<Vec<u32>>,
    out_int: Vec<Vec<u32>>,
    out_bool: Vec<Vec<u32>>,
    /// Per unit: its outputs' transfers, one per (target unit, type).
    transfers: Vec<Vec<Transfer>>,
    buf_real: Vec<f64>,
    buf_int: Vec<i32>,
    buf_bool: Vec<i32>,
    set_real: Vec<f64>,
    set_int: Vec<i32>,
    set_bool: Vec<i32>,
    dirty: Vec<bool>,
}

impl Plan {
    fn new(system: &System, resolve_order: Vec<usize>, step_order: Vec<usize>) -> Self {
        let n = system.units.len();
        let (mut out_real, mut out_int, mut out_bool) = (vec![Vec::new(); n], vec![Vec::new(); n], vec![Vec::new(); n]);
        let mut transfers: Vec<Vec<Transfer>> = (0..n).map(|_| Vec::new()).collect();
        let mut consumers = vec![Vec::new(); n];
        for l in &system.links {
            let list = match l.base {
                BaseType::Real => &mut out_real[l.from_unit],
                BaseType::Integer => &mut out_int[l.from_unit],
                _ => &mut out_bool[l.from_unit],
            };
            let k = list.iter().position(|&v| v == l.from_vr).unwrap_or_else(|| {
                list.push(l.from_vr);
                list.len() - 1
            });
            let group = match transfers[l.from_unit].iter().position(|t| t.to == l.to_unit && t.base == l.base) {
                Some(g) => g,
                None => {
                    transfers[l.from_unit].push(Transfer { base: l.base, to: l.to_unit, vrs: Vec::new(), from: Vec::new(), feeds: false });
                    transfers[l.from_unit].len() - 1
                }
            };
            let t = &mut transfers[l.from_unit][group];
            t.vrs.push(l.to_vr);
            t.from.push(k);
            t.feeds |= l.feeds_through;
            if !consumers[l.from_unit].contains(&l.to_unit) {
                consumers[l.from_unit].push(l.to_unit);
            }
        }
        let widest = |v: &Vec<Vec<u32>>| v.iter().map(Vec::len).max().unwrap_or(0);
        let widest_set = |base: BaseType| transfers.iter().flatten().filter(|t| t.base == base).map(|t| t.vrs.len()).max().unwrap_or(0);
        let mut step_position = vec![0; n];
        for (i, &u) in step_order.iter().enumerate() {
            step_position[u] = i;
        }
        Self {
            buf_real: vec![0.0; widest(&out_real)],
            buf_int: vec![0; widest(&out_int)],
            buf_bool: vec![0; widest(&out_bool)],
            set_real: vec![0.0; widest_set(BaseType::Real)],
            set_int: vec![0; widest_set(BaseType::Integer)],
            set_bool: vec![0; widest_set(BaseType::Boolean)],
            resolve_order,
            step_order,
            step_position,
            consumers,
            out_real,
            out_int,
            out_bool,
            transfers,
            dirty: vec![false; n],
        }
    }

    /// Within a Gauss–Seidel sweep, after the unit at `position` has stepped: whether `unit`,
    /// whose inputs just changed, may leave its outputs unread until it steps itself. It may
    /// when it steps later in this sweep and none of its consumers steps before it: then no
    /// one would use the outputs in between (they are read again once it has stepped).
    fn can_wait(&self, unit: usize, position: Option<usize>) -> bool {
        let Some(now) = position else { return false };
        let at = self.step_position[unit];
        at > now && self.consumers[unit].iter().all(|&c| self.step_position[c] <= now || self.step_position[c] > at)
    }
}

/// A system being simulated. The recorded rows stay available whatever happens.
pub struct Simulation {
    system: System,
    plan: Plan,
    time: f64,
    start: f64,
    step: f64,
    steps_taken: u64,
    algorithm: Algorithm,
    columns: Vec<String>,
    recorded: Vec<(usize, u32, BaseType)>,
    rows: Vec<Vec<f64>>,
    record_every: u64,
}

impl Simulation {
    fn start_up(&mut self) -> Result<(), MasterError> {
        let start = self.start;
        for u in &mut self.system.units {
            let mark = capture::mark();
            u.instance.setup_experiment(None, start, None).map_err(|e| u.fail("fmi2SetupExperiment", e, mark, None))?;
        }
        let settings = std::mem::take(&mut self.system.settings);
        for (ui, name, value) in &settings {
            self.set_value(*ui, name, value)?;
        }
        for u in &mut self.system.units {
            let mark = capture::mark();
            u.instance.enter_initialization_mode().map_err(|e| u.fail("fmi2EnterInitializationMode", e, mark, None))?;
        }
        self.resolve_all(None)?;
        for u in &mut self.system.units {
            let mark = capture::mark();
            u.instance.exit_initialization_mode().map_err(|e| u.fail("fmi2ExitInitializationMode", e, mark, None))?;
        }
        self.resolve_all(Some(start))?;
        self.record()?;
        Ok(())
    }

    fn set_value(&mut self, ui: usize, name: &str, value: &Value) -> Result<(), MasterError> {
        let unit = &mut self.system.units[ui];
        let vr = [unit.variable(name)?.value_reference];
        let mark = capture::mark();
        let r = match value {
            Value::Real(x) => unit.instance.set_real(&vr, &[*x]).map(|_| ()),
            Value::Integer(i) if unit.variables[name].base == BaseType::Real => unit.instance.set_real(&vr, &[*i as f64]).map(|_| ()),
            Value::Integer(i) => unit.instance.set_integer(&vr, &[*i as i32]).map(|_| ()),
            Value::Boolean(b) => unit.instance.set_boolean(&vr, &[*b as i32]).map(|_| ()),
            Value::String(s) => {
                let c = std::ffi::CString::new(s.as_str()).map_err(|_| MasterError::new("a string holds a NUL byte").unit(&unit.name).variable(name))?;
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
        for i in 0..self.plan.resolve_order.len() {
            let u = self.plan.resolve_order[i];
            if !self.plan.dirty[u] {
                continue;
            }
            self.plan.dirty[u] = false;
            if self.plan.transfers[u].is_empty() {
                continue;
            }
            let plan = &mut self.plan;
            let units = &mut self.system.units;
            let mark = capture::mark();
            let (nr, ni, nb) = (plan.out_real[u].len(), plan.out_int[u].len(), plan.out_bool[u].len());
            if nr > 0 {
                units[u].instance.get_real(&plan.out_real[u], &mut plan.buf_real[..nr]).map_err(|e| units[u].fail("fmi2GetReal", e, mark, time))?;
            }
            if ni > 0 {
                units[u].instance.get_integer(&plan.out_int[u], &mut plan.buf_int[..ni]).map_err(|e| units[u].fail("fmi2GetInteger", e, mark, time))?;
            }
            if nb > 0 {
                units[u].instance.get_boolean(&plan.out_bool[u], &mut plan.buf_bool[..nb]).map_err(|e| units[u].fail("fmi2GetBoolean", e, mark, time))?;
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
                    let names: Vec<String> = t
                        .vrs
                        .iter()
                        .filter_map(|&vr| target.variables.iter().find(|(_, v)| v.value_reference == vr && v.base == t.base).map(|(n, _)| n.clone()))
                        .collect();
                    target.fail("fmi2Set (connection)", e, mark, time).variable(&names.join(", "))
                })?;
            }
            for g in 0..self.plan.transfers[u].len() {
                let (to, feeds) = (self.plan.transfers[u][g].to, self.plan.transfers[u][g].feeds);
                if feeds && !self.plan.can_wait(to, position) {
                    self.plan.dirty[to] = true;
                }
            }
        }
        Ok(())
    }

    fn resolve_all(&mut self, time: Option<f64>) -> Result<(), MasterError> {
        self.plan.dirty.fill(true);
        self.resolve_dirty(time, None)
    }

    fn record(&mut self) -> Result<(), MasterError> {
        if self.recorded.is_empty() {
            return Ok(());
        }
        let mut row = Vec::with_capacity(self.recorded.len() + 1);
        row.push(self.time);
        for &(u, vr, base) in &self.recorded {
            let unit = &mut self.system.units[u];
            let mark = capture::mark();
            let v = match base {
                BaseType::Real => {
                    let mut x = [0.0];
                    unit.instance.get_real(&[vr], &mut x).map(|_| x[0])
                }
                BaseType::Integer => {
                    let mut x = [0];
                    unit.instance.get_integer(&[vr], &mut x).map(|_| x[0] as f64)
                }
                _ => {
                    let mut x = [0];
                    unit.instance.get_boolean(&[vr], &mut x).map(|_| x[0] as f64)
                }
            };
            row.push(v.map_err(|e| unit.fail("fmi2Get (recording)", e, mark, Some(self.time)))?);
        }
        self.rows.push(row);
        Ok(())
    }

    /// Records every `k`-th communication point only (k ≥ 1; the first is always recorded).
    pub fn record_every(&mut self, k: u64) {
        self.record_every = k.max(1);
    }

    /// One communication step from the current time.
    pub fn step(&mut self) -> Result<(), MasterError> {
        let t = self.time;
        let h = self.step;
        match self.algorithm {
            Algorithm::GaussSeidel => {
                for i in 0..self.plan.step_order.len() {
                    let u = self.plan.step_order[i];
                    self.do_step(u, t, h)?;
                    self.plan.dirty[u] = true;
                    self.resolve_dirty(Some(t), Some(i))?;
                }
            }
            Algorithm::Jacobi => {
                for u in 0..self.system.units.len() {
                    self.do_step(u, t, h)?;
                }
                self.resolve_all(Some(t))?;
            }
        }
        self.steps_taken += 1;
        // Times from the step count, so long runs do not accumulate rounding.
        self.time = self.start + self.steps_taken as f64 * h;
        if self.steps_taken % self.record_every == 0 {
            self.record()?;
        }
        Ok(())
    }

    fn do_step(&mut self, u: usize, t: f64, h: f64) -> Result<(), MasterError> {
        let unit = &mut self.system.units[u];
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
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let unit = &mut self.system.units[ui];
        let info = unit.variable(v)?;
        if info.base != BaseType::Real {
            return Err(MasterError::new(format!("type mismatch: {:?}, not Real", info.base)).unit(u).variable(v));
        }
        let vr = [info.value_reference];
        let mut x = [0.0];
        let mark = capture::mark();
        unit.instance.get_real(&vr, &mut x).map_err(|e| unit.fail("fmi2GetReal", e, mark, Some(self.time)).variable(v))?;
        Ok(x[0])
    }

    /// Sets an input or tunable parameter between steps; the new value is passed on at once.
    pub fn set(&mut self, full: &str, value: Value) -> Result<(), MasterError> {
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let info = self.system.units[ui].variable(v)?;
        check_value(info, &value).map_err(|m| MasterError::new(m).unit(u).variable(v))?;
        if self.system.links.iter().any(|l| l.to_unit == ui && l.to_vr == info.value_reference && l.base == info.base) {
            return Err(MasterError::new("this input is connected; the connection sets it").unit(u).variable(v));
        }
        self.set_value(ui, v, &value).map_err(|e| e.at(self.time))?;
        self.plan.dirty[ui] = true;
        self.resolve_dirty(Some(self.time), None)
    }

    /// A handle on a Real variable ("unit.variable") for fast reads with [`Self::get_reals`]
    /// and, if it is an unconnected input or a tunable parameter, writes with [`Self::set_reals`].
    pub fn real_handle(&self, full: &str) -> Result<Handle, MasterError> {
        let (u, v) = split_name(full)?;
        let ui = self.system.unit_index(u)?;
        let info = self.system.units[ui].variable(v)?;
        if info.base != BaseType::Real {
            return Err(MasterError::new(format!("type mismatch: {:?}, not Real", info.base)).unit(u).variable(v));
        }
        let connected = self.system.links.iter().any(|l| l.to_unit == ui && l.to_vr == info.value_reference && l.base == BaseType::Real);
        let settable = matches!(info.causality, "input" | "parameter") && !connected;
        Ok(Handle { unit: ui, value_reference: info.value_reference, settable })
    }

    /// Sets Real inputs or tunable parameters between steps and passes the effect on.
    pub fn set_reals(&mut self, handles: &[Handle], values: &[f64]) -> Result<(), MasterError> {
        assert_eq!(handles.len(), values.len(), "one value per handle");
        for (h, &x) in handles.iter().zip(values) {
            let unit = &mut self.system.units[h.unit];
            if !h.settable {
                return Err(MasterError::new("not settable: a connected input, an output or a local").unit(&unit.name).at(self.time));
            }
            let mark = capture::mark();
            unit.instance.set_real(&[h.value_reference], &[x]).map_err(|e| unit.fail("fmi2SetReal", e, mark, Some(self.time)))?;
            self.plan.dirty[h.unit] = true;
        }
        self.resolve_dirty(Some(self.time), None)
    }

    /// Reads Real variables through handles.
    pub fn get_reals(&mut self, handles: &[Handle], out: &mut [f64]) -> Result<(), MasterError> {
        assert_eq!(handles.len(), out.len(), "one slot per handle");
        for (h, o) in handles.iter().zip(out.iter_mut()) {
            let unit = &mut self.system.units[h.unit];
            let mut x = [0.0];
            let mark = capture::mark();
            unit.instance.get_real(&[h.value_reference], &mut x).map_err(|e| unit.fail("fmi2GetReal", e, mark, Some(self.time)))?;
            *o = x[0];
        }
        Ok(())
    }

    /// Column names of the recording: "time", then the recorded variables.
    pub fn columns(&self) -> Vec<String> {
        std::iter::once("time".to_owned()).chain(self.columns.iter().cloned()).collect()
    }

    /// The recorded rows (time first).
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.rows
    }

    /// Takes the recorded rows out, leaving none.
    pub fn take_rows(&mut self) -> Vec<Vec<f64>> {
        std::mem::take(&mut self.rows)
    }

    /// The units, for inspection.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The units' names in Gauss–Seidel stepping order.
    pub fn step_order(&self) -> Vec<&str> {
        self.plan.step_order.iter().map(|&u| self.system.units[u].name.as_str()).collect()
    }
}

/// A resolved Real variable of a running simulation.
#[derive(Clone, Copy, Debug)]
pub struct Handle {
    unit: usize,
    value_reference: u32,
    settable: bool,
}

/// What [`run`] gives back: the recording, and the error that stopped it early, if any.
pub struct RunOutcome {
    /// Column names, "time" first.
    pub columns: Vec<String>,
    /// Rows recorded (up to the failure, if there was one).
    pub rows: Vec<Vec<f64>>,
    /// Why the run stopped before `stop`.
    pub error: Option<MasterError>,
}

/// Builds and runs a described system; relative paths are taken from `base`. Errors before
/// the first step are returned as `Err`; a failure during the run keeps the rows so far.
pub fn run(spec: &SystemSpec, base: &Path) -> Result<RunOutcome, MasterError> {
    let s = &spec.simulation;
    let system = System::from_spec(spec, base)?;
    let mut sim = system.initialize(s.start, s.step, s.algorithm, &s.record)?;
    sim.record_every(s.record_every);
    let error = sim.run_until(s.stop).err();
    Ok(RunOutcome { columns: sim.columns(), rows: sim.take_rows(), error })
}
