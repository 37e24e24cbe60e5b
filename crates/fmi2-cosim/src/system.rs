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
    /// Index of the target unit.
    pub to_unit: usize,
    /// Name of the input.
    pub to_variable: String,
    /// Its value reference.
    pub to_vr: u32,
    /// The base type of both.
    pub base: BaseType,
    /// The input feeds an output of its unit directly.
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

/// Checks that `value` fits the variable's base type (integers may set reals).
pub(crate) fn check_value(info: &VariableInfo, value: &Value) -> Result<(), String> {
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

/// The (output, input) variable pairs a connection from `from_var` of one unit to `to_var`
/// of another stands for, given the names of the source's outputs. With a `*` in both names,
/// every output whose name has the text before and after the `*` (sorted by name), mapped to
/// the target name with the same text in place of its `*`; with none, the one pair as given.
/// `from` and `to` are the full names, for messages.
pub fn expand_connection<'a>(
    from: &str,
    to: &str,
    from_var: &str,
    to_var: &str,
    outputs: impl IntoIterator<Item = &'a str>,
) -> Result<Vec<(String, String)>, String> {
    match (from_var.split_once('*'), to_var.split_once('*')) {
        (Some((fp, fs)), Some((tp, ts))) => {
            let mut names: Vec<&str> =
                outputs.into_iter().filter(|n| n.len() >= fp.len() + fs.len() && n.starts_with(fp) && n.ends_with(fs)).collect();
            names.sort_unstable();
            names.dedup();
            if names.is_empty() {
                return Err(format!("no output matches '{from_var}'"));
            }
            Ok(names.into_iter().map(|n| (n.to_owned(), format!("{tp}{}{ts}", &n[fp.len()..n.len() - fs.len()]))).collect())
        }
        (None, None) => Ok(vec![(from_var.to_owned(), to_var.to_owned())]),
        _ => Err(format!("'{from}' → '{to}': use '*' in both names or in neither")),
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
        let interface = Interface::read(path).map_err(|e| MasterError::new(e).unit(name))?;
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
        self.links.iter().any(|l| l.to_unit == unit && l.to_vr == vr && l.base == base)
    }

    /// Sets a parameter (or an unconnected input's value) before initialisation; setting a
    /// variable again replaces its value.
    pub fn set(&mut self, unit: &str, variable: &str, value: Value) -> Result<&mut Self, MasterError> {
        let u = self.unit_index(unit)?;
        let info = self.units[u].variable(variable)?;
        check_value(info, &value).map_err(|m| MasterError::new(m).unit(unit).variable(variable))?;
        if !matches!(info.causality, Causality::Parameter | Causality::Input) {
            let what = info.causality.with_article();
            return Err(MasterError::new(format!("{what} cannot be set; only parameters and inputs")).unit(unit).variable(variable));
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
        let pairs = expand_connection(from, to, fv, tv, self.units[fi].interface.outputs()).map_err(|m| MasterError::new(m).unit(fu))?;
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
            if src.base != dst.base || !src.base.is_connectable() {
                return Err(MasterError::new(format!(
                    "type mismatch: {fu}.{fv} is {:?}, {tu}.{tv} is {:?} (Real, Integer and Boolean connect to their own type)",
                    src.base, dst.base
                ))
                .unit(tu)
                .variable(&tv));
            }
            if self.is_connected(ti, dst.value_reference, dst.base) {
                return Err(MasterError::new("this input is already connected").unit(tu).variable(&tv));
            }
            let feeds_through = self.units[ti].interface.feedthrough_inputs.contains(&dst.value_reference);
            added.push(Link {
                from_unit: fi,
                from_variable: fv,
                from_vr: src.value_reference,
                to_unit: ti,
                to_variable: tv,
                to_vr: dst.value_reference,
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
                if !info.base.is_connectable() {
                    return Err(MasterError::new("only Real, Integer and Boolean variables can be recorded").unit(u).variable(v));
                }
                Ok((ui, info.value_reference, info.base))
            })
            .collect()
    }

    /// Builds a system from a spec; relative FMU paths are taken from `base`. The spec's
    /// recorded variables are checked too.
    pub fn from_spec(spec: &SystemSpec, base: &Path) -> Result<Self, MasterError> {
        spec.simulation.check().map_err(MasterError::new)?;
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
        let outputs = ["q_1", "q_2", "qd_1", "tau_1", "q_"];
        let pairs = expand_connection("a.q_*", "b.x_*_in", "q_*", "x_*_in", outputs).unwrap();
        assert_eq!(
            pairs,
            [("q_".to_owned(), "x__in".to_owned()), ("q_1".to_owned(), "x_1_in".to_owned()), ("q_2".to_owned(), "x_2_in".to_owned())]
        );
        let e = expand_connection("a.z*", "b.z*", "z*", "z*", outputs).unwrap_err();
        assert!(e.contains("no output matches 'z*'"), "{e}");
        let e = expand_connection("a.q_*", "b.u", "q_*", "u", outputs).unwrap_err();
        assert!(e.contains("in both names or in neither"), "{e}");
        assert_eq!(expand_connection("a.y", "b.u", "y", "u", outputs).unwrap(), [("y".to_owned(), "u".to_owned())]);
    }
}
