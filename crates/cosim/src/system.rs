//! A system of FMUs, validated as it is built and before anything is instantiated: units
//! with their interfaces read from their `modelDescription.xml`, the values set before
//! initialisation, and the connections resolved to value references. Both the simulation
//! ([`System::initialize`]) and the SSP writer ([`crate::ssp`]) take a `System`, so every
//! check is made once, here.

use std::path::{Path, PathBuf};

use crate::error::MasterError;
use crate::interface::{BaseType, Causality, Interface, VariableInfo};
use crate::spec::{SystemSpec, Value};

/// One unit of the system: a name, the `.fmu` it comes from, and that FMU's interface.
#[derive(Clone, Debug)]
pub struct UnitPlan {
    /// The unit's name in the system (its instance name).
    pub name: String,
    /// The `.fmu` file.
    pub path: PathBuf,
    /// What its `modelDescription.xml` says.
    pub interface: Interface,
}

impl UnitPlan {
    /// A variable by name; the error names the unit, the variable and the file.
    pub fn variable(&self, name: &str) -> Result<&VariableInfo, MasterError> {
        self.interface
            .get(name)
            .ok_or_else(|| MasterError::new(format!("no such variable in {}", self.path.display())).unit(&self.name).variable(name))
    }
}

/// A connection from an output to an input, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// Index of the source unit.
    pub from_unit: usize,
    /// Name of the output.
    pub from_variable: String,
    /// Its value reference.
    pub from_vr: u32,
    /// Its position in the source's [`Interface::variables`].
    pub from_index: usize,
    /// Index of the target unit.
    pub to_unit: usize,
    /// Name of the input.
    pub to_variable: String,
    /// Its value reference.
    pub to_vr: u32,
    /// Its position in the target's [`Interface::variables`].
    pub to_index: usize,
    /// The base type of both.
    pub base: BaseType,
    /// The input feeds some output of its unit directly.
    pub feeds_through: bool,
}

/// A value set on a unit's variable before initialisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// Index of the unit.
    pub unit: usize,
    /// The variable's name.
    pub variable: String,
    /// The value (checked against the variable's type).
    pub value: Value,
}

/// A system of units and connections, checked and resolved; nothing is instantiated until
/// [`System::initialize`].
#[derive(Clone, Debug, Default)]
pub struct System {
    units: Vec<UnitPlan>,
    links: Vec<Link>,
    settings: Vec<Setting>,
}

/// A variable named "unit.variable".
pub(crate) fn split_name(full: &str) -> Result<(&str, &str), MasterError> {
    full.split_once('.').ok_or_else(|| MasterError::new(format!("'{full}' must be written as unit.variable")))
}

/// Checks that `value` fits variable `info` of `interface` and gives what is passed to the
/// FMU: integers may set reals; an enumeration takes one of its items, by value or by name.
/// The error says why; the caller names the unit and the variable.
pub(crate) fn check_value(interface: &Interface, info: &VariableInfo, value: &Value) -> Result<Value, MasterError> {
    if info.is_array || !info.base.is_connectable() {
        let what = if info.is_array { "an array".to_owned() } else { format!("a {}", info.base.name()) };
        return Err(MasterError::new(format!("the variable is {what}, which this master does not set")));
    }
    let (base, class) = (info.base, info.base.access());
    let ok = matches!(
        (base, class, value),
        (_, BaseType::Real, Value::Real(_) | Value::Integer(_))
            | (BaseType::Enumeration, _, Value::Integer(_) | Value::String(_))
            | (_, BaseType::Integer, Value::Integer(_))
            | (BaseType::Boolean, _, Value::Boolean(_))
            | (BaseType::String, _, Value::String(_))
    );
    if !ok {
        return Err(MasterError::new(format!("type mismatch: the variable is {:?}, the value {value:?}", info.base)));
    }
    if let (Some((low, high)), Value::Integer(i)) = (base.integer_range(), value) {
        if base != BaseType::Enumeration && !(low..=high).contains(&i128::from(*i)) {
            let name = if base == BaseType::Integer { "an fmi2Integer".to_owned() } else { format!("a {}", base.name()) };
            return Err(MasterError::new(format!("{i} does not fit {name}")));
        }
    }
    match (base, value) {
        (_, Value::Integer(i)) if class == BaseType::Real => Ok(Value::Real(*i as f64)),
        (BaseType::Enumeration, _) => {
            let items = interface.enumeration_of(info).map_or(&[][..], |e| &e.items[..]);
            let found = items.iter().find(|(name, v)| match value {
                Value::Integer(i) => v == i,
                Value::String(s) => name == s,
                _ => false,
            });
            match found {
                Some((_, v)) => Ok(Value::Integer(*v)),
                None => {
                    let listed: Vec<String> = items.iter().map(|(n, v)| format!("{n} = {v}")).collect();
                    Err(MasterError::new(format!(
                        "{value:?} is not an item of type {} ({})",
                        info.declared_type.as_deref().unwrap_or("?"),
                        listed.join(", ")
                    )))
                }
            }
        }
        (BaseType::String, Value::String(s)) if s.contains('\0') => Err(MasterError::new("a string holds a NUL byte")),
        _ => Ok(value.clone()),
    }
}

/// Whether a `*` pattern part may capture `text`: characters without `_` or `.` (possibly
/// none), so `q_*` matches `q_1` and `q_tip` but never the longer name `q_meas_1`, and `y*`
/// matches `y` and `y2`.
fn capturable(text: &str) -> bool {
    !text.contains(['_', '.'])
}

/// The (output, input) variable pairs a connection from `from_var` of one unit to `to_var`
/// of another stands for, given the names of the source's outputs. With a `*` in both names,
/// every output that is the text before the `*`, a captured part, and the text after it
/// (sorted by name), mapped to the target name with the same part in place of its `*`; the
/// captured part holds no `_` or `.` (and may be empty), so a pattern never captures a longer
/// name (`arm.q_*` matches `q_1`, not `q_meas_1`). With no `*`, the one pair as given.
/// `from` and `to` are the full names, for messages; the caller names the source unit.
pub fn expand_connection<'a>(
    from: &str,
    to: &str,
    from_var: &str,
    to_var: &str,
    outputs: impl IntoIterator<Item = &'a str>,
) -> Result<Vec<(String, String)>, MasterError> {
    if from_var.matches('*').count() > 1 || to_var.matches('*').count() > 1 {
        return Err(MasterError::new(format!("'{from}' → '{to}': a name holds at most one '*'")));
    }
    match (from_var.split_once('*'), to_var.split_once('*')) {
        (Some((fp, fs)), Some((tp, ts))) => {
            let mut names: Vec<&str> = outputs
                .into_iter()
                .filter(|n| n.len() >= fp.len() + fs.len() && n.starts_with(fp) && n.ends_with(fs))
                .filter(|n| capturable(&n[fp.len()..n.len() - fs.len()]))
                .collect();
            names.sort_unstable();
            names.dedup();
            if names.is_empty() {
                return Err(MasterError::new(format!("no output matches '{from_var}' ('*' stands for a part without '_' or '.')")));
            }
            Ok(names.into_iter().map(|n| (n.to_owned(), format!("{tp}{}{ts}", &n[fp.len()..n.len() - fs.len()]))).collect())
        }
        (None, None) => Ok(vec![(from_var.to_owned(), to_var.to_owned())]),
        _ => Err(MasterError::new(format!("'{from}' → '{to}': use '*' in both names or in neither"))),
    }
}

impl System {
    /// An empty system.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the FMU at `path` as unit `name`, reading its interface (the FMU is not loaded).
    pub fn add_fmu(&mut self, name: &str, path: &Path) -> Result<&mut Self, MasterError> {
        if name.is_empty() || name.contains('.') {
            return Err(MasterError::new("a unit name must be non-empty and hold no '.'").unit(name));
        }
        if self.units.iter().any(|u| u.name == name) {
            return Err(MasterError::new("two units have this name").unit(name));
        }
        let interface = Interface::read(path).map_err(|e| MasterError::new(e.to_string()).unit(name))?;
        self.units.push(UnitPlan { name: name.to_owned(), path: path.to_owned(), interface });
        Ok(self)
    }

    /// The units, in declaration order.
    pub fn units(&self) -> &[UnitPlan] {
        &self.units
    }

    /// The connections, each output → input pair once, in the order they were made.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// The values set before initialisation, in the order they were set (one per variable).
    pub fn settings(&self) -> &[Setting] {
        &self.settings
    }

    /// The index of unit `name`.
    pub fn unit_index(&self, name: &str) -> Result<usize, MasterError> {
        self.units.iter().position(|u| u.name == name).ok_or_else(|| MasterError::new("no unit of this name in the system").unit(name))
    }

    /// Whether input `vr` of base type `base` of unit `unit` is set by a connection.
    pub fn is_connected(&self, unit: usize, vr: u32, base: BaseType) -> bool {
        self.links.iter().any(|l| l.to_unit == unit && l.to_vr == vr && l.base.access() == base.access())
    }

    /// Sets a variable's value before initialisation: a parameter, an unconnected input, or
    /// any other variable the standard lets a master set then (not constant, `initial` exact
    /// or approx: e.g. an output with a start value). An enumeration takes an item's value or
    /// name. Setting a variable again replaces its value.
    pub fn set(&mut self, unit: &str, variable: &str, value: Value) -> Result<&mut Self, MasterError> {
        let u = self.unit_index(unit)?;
        let info = self.units[u].variable(variable)?;
        check_value(&self.units[u].interface, info, &value).map_err(|e| e.unit(unit).variable(variable))?;
        if !info.settable_before_initialization() {
            let what = info.causality.with_article();
            let why = match info.causality {
                Causality::Independent => "the independent variable cannot be set".to_owned(),
                _ if info.variability == crate::interface::Variability::Constant => format!("{what} that is constant cannot be set"),
                _ => format!(
                    "{what} cannot be set (its initial is {}); a master sets inputs and variables with initial exact or approx (parameters, outputs with a start value)",
                    format!("{:?}", info.initial).to_lowercase()
                ),
            };
            return Err(MasterError::new(why).unit(unit).variable(variable));
        }
        match self.settings.iter_mut().find(|s| s.unit == u && s.variable == variable) {
            Some(s) => s.value = value,
            None => self.settings.push(Setting { unit: u, variable: variable.to_owned(), value }),
        }
        Ok(self)
    }

    /// Connects output `from` ("unit.variable") to input `to`. A `*` in both names stands for
    /// the same text, so "arm.q_*" → "ctrl.q_*" connects every matching output
    /// ([`expand_connection`]).
    pub fn connect(&mut self, from: &str, to: &str) -> Result<&mut Self, MasterError> {
        let (fu, fv) = split_name(from)?;
        let (tu, tv) = split_name(to)?;
        let (fi, ti) = (self.unit_index(fu)?, self.unit_index(tu)?);
        let pairs = expand_connection(from, to, fv, tv, self.units[fi].interface.outputs()).map_err(|e| e.unit(fu))?;
        // All pairs are checked before any is added, so a refused connection changes nothing.
        let mut added: Vec<Link> = Vec::with_capacity(pairs.len());
        let pattern = |mut e: MasterError| {
            if fv.contains('*') {
                e.message = format!("{} (from the pattern '{from}' → '{to}')", e.message);
            }
            e
        };
        for (fv, tv) in pairs {
            let src = self.units[fi].variable(&fv).map_err(pattern)?;
            let dst = self.units[ti].variable(&tv).map_err(pattern)?;
            if src.causality != Causality::Output {
                let what = src.causality.with_article();
                return Err(MasterError::new(format!("a connection must start at an output, not {what}")).unit(fu).variable(&fv));
            }
            if dst.causality != Causality::Input {
                let what = dst.causality.with_article();
                return Err(MasterError::new(format!("a connection must end at an input, not {what}")).unit(tu).variable(&tv));
            }
            for (unit, name, v) in [(fu, &fv, src), (tu, &tv, dst)] {
                if v.is_array || !v.base.is_connectable() {
                    let what = if v.is_array { "an array".to_owned() } else { format!("a {}", v.base.name()) };
                    return Err(MasterError::new(format!("{what} cannot be connected by this master")).unit(unit).variable(name));
                }
            }
            // Across FMI versions and widths: Real to Float64 or Float32, any integer to any
            // integer (a value that does not fit the input fails the run, naming it), an
            // enumeration to an enumeration only.
            let same_class =
                src.base.access() == dst.base.access() && (src.base == BaseType::Enumeration) == (dst.base == BaseType::Enumeration);
            if !same_class {
                return Err(MasterError::new(format!(
                    "type mismatch: {fu}.{fv} is {:?}, {tu}.{tv} is {:?} (reals connect to reals, integers to integers, enumerations, Booleans and strings to their own)",
                    src.base, dst.base
                ))
                .unit(tu)
                .variable(&tv));
            }
            if src.base == BaseType::Enumeration {
                let from_items = self.units[fi].interface.enumeration_of(src).map_or(&[][..], |e| &e.items[..]);
                let to_items = self.units[ti].interface.enumeration_of(dst).map_or(&[][..], |e| &e.items[..]);
                if let Some((name, value)) = from_items.iter().find(|(_, v)| !to_items.iter().any(|(_, w)| w == v)) {
                    return Err(MasterError::new(format!(
                        "{fu}.{fv} may give {name} = {value}, which is no item of the input's type {}",
                        dst.declared_type.as_deref().unwrap_or("?")
                    ))
                    .unit(tu)
                    .variable(&tv));
                }
            }
            if self.is_connected(ti, dst.value_reference, dst.base) || added.iter().any(|l| l.to_unit == ti && l.to_variable == tv) {
                return Err(MasterError::new("this input is already connected").unit(tu).variable(&tv));
            }
            let (from_index, to_index) =
                (self.units[fi].interface.index(&fv).expect("found above"), self.units[ti].interface.index(&tv).expect("found above"));
            let feeds_through = self.units[ti].interface.variables.iter().any(|v| v.direct_inputs.contains(&to_index));
            added.push(Link {
                from_unit: fi,
                from_variable: fv,
                from_vr: src.value_reference,
                from_index,
                to_unit: ti,
                to_variable: tv,
                to_vr: dst.value_reference,
                to_index,
                base: src.base,
                feeds_through,
            });
        }
        self.links.extend(added);
        Ok(self)
    }

    /// Resolves variables to record ("unit.variable") to (unit, value reference, base type).
    pub fn recordable(&self, names: &[String]) -> Result<Vec<(usize, u32, BaseType)>, MasterError> {
        names
            .iter()
            .map(|full| {
                let (u, v) = split_name(full)?;
                let ui = self.unit_index(u)?;
                let info = self.units[ui].variable(v)?;
                if info.is_array || !info.base.is_connectable() {
                    let what = if info.is_array { "an array".to_owned() } else { format!("a {}", info.base.name()) };
                    return Err(MasterError::new(format!("{what} cannot be recorded by this master")).unit(u).variable(v));
                }
                Ok((ui, info.value_reference, info.base))
            })
            .collect()
    }

    /// Builds a system from a spec; relative FMU paths are taken from `base`. The spec's
    /// recorded variables are checked too.
    pub fn from_spec(spec: &SystemSpec, base: &Path) -> Result<Self, MasterError> {
        spec.simulation.check()?;
        if spec.fmu.is_empty() {
            return Err(MasterError::new("the system has no FMU"));
        }
        let mut system = Self::new();
        for f in &spec.fmu {
            system.add_fmu(&f.name, &base.join(&f.path))?;
            for (k, v) in &f.parameters {
                system.set(&f.name, k, v.clone())?;
            }
        }
        for c in &spec.connection {
            system.connect(&c.from, &c.to)?;
        }
        system.recordable(&spec.simulation.record)?;
        Ok(system)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_expand_to_sorted_pairs() {
        let outputs = ["q_1", "q_2", "qd_1", "tau_1", "q_", "q_meas_1", "q_tip", "q_1.x"];
        let pairs = expand_connection("a.q_*", "b.x_*_in", "q_*", "x_*_in", outputs).unwrap();
        let owned = |v: &[(&str, &str)]| v.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect::<Vec<_>>();
        // q_ (nothing captured) too, but not q_meas_1 or q_1.x (longer names).
        assert_eq!(pairs, owned(&[("q_", "x__in"), ("q_1", "x_1_in"), ("q_2", "x_2_in"), ("q_tip", "x_tip_in")]));
        let pairs = expand_connection("a.q_meas_*", "b.q_*", "q_meas_*", "q_*", outputs).unwrap();
        assert_eq!(pairs, owned(&[("q_meas_1", "q_1")]));
        let e = expand_connection("a.z*", "b.z*", "z*", "z*", outputs).unwrap_err();
        assert!(e.message.contains("no output matches 'z*'"), "{e}");
        let e = expand_connection("a.q_*", "b.u", "q_*", "u", outputs).unwrap_err();
        assert!(e.message.contains("in both names or in neither"), "{e}");
        let e = expand_connection("a.*_*", "b.*_*", "*_*", "*_*", outputs).unwrap_err();
        assert!(e.message.contains("at most one '*'"), "{e}");
        assert_eq!(expand_connection("a.y", "b.u", "y", "u", outputs).unwrap(), owned(&[("y", "u")]));
    }
}
