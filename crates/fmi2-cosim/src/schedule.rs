//! The order of a system's work, worked out once before the first step: in which order
//! connections are resolved, in which order units step (Gauss–Seidel), and, per unit, which
//! outputs it gives and where they go, grouped so that each target gets one `fmi2Set*` call
//! per source and type.

use crate::error::MasterError;
use crate::interface::BaseType;
use crate::system::System;

/// The inputs of one unit of one base type fed by one source unit: set in one call.
#[derive(Debug)]
pub(crate) struct Transfer {
    pub base: BaseType,
    pub to: usize,
    /// Value references of the inputs set.
    pub vrs: Vec<u32>,
    /// For each, its index in the source unit's read list of that type.
    pub from: Vec<usize>,
    /// Some of these inputs feed the target's outputs directly.
    pub feeds: bool,
}

/// Precomputed orders and transfers, with the buffers they need.
#[derive(Debug)]
pub(crate) struct Schedule {
    pub resolve_order: Vec<usize>,
    pub step_order: Vec<usize>,
    /// Position of each unit in the step order.
    step_position: Vec<usize>,
    /// Per unit: the units its outputs go to.
    consumers: Vec<Vec<usize>>,
    /// Per unit: value references to read, by type.
    pub out_real: Vec<Vec<u32>>,
    pub out_int: Vec<Vec<u32>>,
    pub out_bool: Vec<Vec<u32>>,
    /// Per unit: its outputs' transfers, one per (target unit, type).
    pub transfers: Vec<Vec<Transfer>>,
    pub buf_real: Vec<f64>,
    pub buf_int: Vec<i32>,
    pub buf_bool: Vec<i32>,
    pub set_real: Vec<f64>,
    pub set_int: Vec<i32>,
    pub set_bool: Vec<i32>,
    /// Units whose outputs changed and have yet to be passed on.
    pub dirty: Vec<bool>,
}

/// Order in which connections are resolved: each unit after those feeding its direct
/// feedthrough inputs. An algebraic loop is an error naming its units.
fn resolve_order(system: &System) -> Result<Vec<usize>, MasterError> {
    let units = system.units();
    let links = system.links();
    let n = units.len();
    let mut indegree = vec![0usize; n];
    for l in links.iter().filter(|l| l.feeds_through) {
        indegree[l.to_unit] += 1;
    }
    let mut order = Vec::with_capacity(n);
    let mut done = vec![false; n];
    while order.len() < n {
        let Some(u) = (0..n).find(|&u| !done[u] && indegree[u] == 0) else {
            let names: Vec<_> = (0..n).filter(|&u| !done[u]).map(|u| units[u].name.as_str()).collect();
            return Err(MasterError::new(format!(
                "algebraic loop: the outputs of {} depend directly on each other's inputs, so no order resolves them",
                names.join(", ")
            )));
        };
        done[u] = true;
        order.push(u);
        for l in links.iter().filter(|l| l.feeds_through && l.from_unit == u) {
            indegree[l.to_unit] -= 1;
        }
    }
    Ok(order)
}

/// Gauss–Seidel stepping order: topological over all connections; a cycle is cut at its
/// first unit (declaration order) without direct feedthrough.
fn step_order(system: &System) -> Result<Vec<usize>, MasterError> {
    let units = system.units();
    let links = system.links();
    let n = units.len();
    let mut indegree = vec![0usize; n];
    for l in links {
        if l.from_unit != l.to_unit {
            indegree[l.to_unit] += 1;
        }
    }
    let mut order = Vec::with_capacity(n);
    let mut done = vec![false; n];
    while order.len() < n {
        let u = (0..n)
            .find(|&u| !done[u] && indegree[u] == 0)
            .or_else(|| (0..n).find(|&u| !done[u] && !units[u].interface.has_feedthrough()))
            .ok_or_else(|| MasterError::new("a cycle of units that all have direct feedthrough cannot be stepped in order"))?;
        done[u] = true;
        order.push(u);
        for l in links.iter().filter(|l| l.from_unit == u && l.to_unit != u) {
            indegree[l.to_unit] = indegree[l.to_unit].saturating_sub(1);
        }
    }
    Ok(order)
}

impl Schedule {
    /// The schedule of `system`; fails on an algebraic loop.
    pub fn new(system: &System) -> Result<Self, MasterError> {
        let resolve_order = resolve_order(system)?;
        let step_order = step_order(system)?;
        let n = system.units().len();
        let (mut out_real, mut out_int, mut out_bool) = (vec![Vec::new(); n], vec![Vec::new(); n], vec![Vec::new(); n]);
        let mut transfers: Vec<Vec<Transfer>> = (0..n).map(|_| Vec::new()).collect();
        let mut consumers = vec![Vec::new(); n];
        for l in system.links() {
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
        Ok(Self {
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
        })
    }

    /// Within a Gauss–Seidel sweep, after the unit at `position` has stepped: whether `unit`,
    /// whose inputs just changed, may leave its outputs unread until it steps itself. It may
    /// when it steps later in this sweep and none of its consumers steps before it: then no
    /// one would use the outputs in between (they are read again once it has stepped).
    pub fn can_wait(&self, unit: usize, position: Option<usize>) -> bool {
        let Some(now) = position else { return false };
        let at = self.step_position[unit];
        at > now && self.consumers[unit].iter().all(|&c| self.step_position[c] <= now || self.step_position[c] > at)
    }
}
