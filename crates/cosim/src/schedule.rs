//! The order of a system's work, worked out once before the first step.
//!
//! # Resolving connections, per variable
//! An output that depends directly on an input (`ModelStructure/Outputs`) must be read after
//! that input was set. The dependencies form a graph over the outputs that feed connections:
//! output `a.y` → output `b.z` when `a.y` is connected to an input of `b` that `b.z` depends on
//! directly. A cycle in it is an algebraic loop and is refused, naming its variables; units
//! whose outputs only *look* circular at the level of units (`a.y1` → `b.u`, `b.y` → `a.u2`,
//! with `a.y1` not depending on `a.u2`) are not a loop. The outputs are read in a topological
//! order of this graph, grouped into *passes*: consecutive outputs of one unit read in one
//! get call per access class (`fmi2GetReal`, ...; `fmi3GetFloat64`, ... when every value
//! reference is of that one type, else one call per variable), each passed on with one set
//! call per target and class. A unit can have several passes (`a.y1` before `b`, `a.y2` after
//! it).
//!
//! # Stepping order (Gauss–Seidel)
//! Topological over the connections between units; a cycle is cut at its first unit (in
//! declaration order) without direct feedthrough, or else at its first unit.

use std::ffi::CString;

use crate::error::MasterError;
use crate::interface::BaseType;
use crate::system::System;

/// Inputs of one unit of one access type fed by one pass: set in one call.
#[derive(Debug)]
pub(crate) struct Transfer {
    /// Integer for enumerations.
    pub base: BaseType,
    pub to: usize,
    /// Value references of the inputs set.
    pub vrs: Vec<u32>,
    /// For each, its index in the pass's read list of that type.
    pub from: Vec<usize>,
    /// Passes of the target whose outputs depend on these inputs (all later in the order).
    pub wakes: Vec<usize>,
}

/// Outputs of one unit read together and passed on.
#[derive(Debug)]
pub(crate) struct Pass {
    pub unit: usize,
    /// Value references to read, per access type (Real, Integer, Boolean, String).
    pub reads: [Vec<u32>; 4],
    pub transfers: Vec<Transfer>,
}

/// Position of an access type in [`Pass::reads`].
pub(crate) fn slot(base: BaseType) -> usize {
    match base.access() {
        BaseType::Real => 0,
        BaseType::Integer => 1,
        BaseType::Boolean => 2,
        // Strings; Binary and Clock are never connected.
        _ => 3,
    }
}

/// Precomputed passes and orders, with the buffers they need.
#[derive(Debug)]
pub(crate) struct Schedule {
    /// In resolve order.
    pub passes: Vec<Pass>,
    /// Per unit: its passes.
    pub unit_passes: Vec<Vec<usize>>,
    pub step_order: Vec<usize>,
    /// Position of each unit in the step order.
    step_position: Vec<usize>,
    /// Per pass: the step positions of the units its values reach, directly or through
    /// direct feedthrough, sorted.
    reach: Vec<Vec<usize>>,
    pub buf_real: Vec<f64>,
    pub buf_int: Vec<i64>,
    pub buf_bool: Vec<i32>,
    pub buf_str: Vec<CString>,
    pub set_real: Vec<f64>,
    pub set_int: Vec<i64>,
    pub set_bool: Vec<i32>,
    pub set_str: Vec<CString>,
    /// Passes whose outputs changed and have yet to be passed on.
    pub dirty: Vec<bool>,
}

/// An output that feeds a connection: (unit, position in its variables).
type Node = (usize, usize);

/// The outputs feeding connections and the edges between them (`edges[i]`: the nodes whose
/// value depends directly on node `i`'s), in a deterministic order.
fn dependency_graph(system: &System) -> (Vec<Node>, Vec<Vec<usize>>) {
    let mut nodes: Vec<Node> = system.links().iter().map(|l| (l.from_unit, l.from_index)).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let position = |n: Node| nodes.binary_search(&n).ok();
    let mut edges = vec![Vec::new(); nodes.len()];
    for l in system.links() {
        let from = position((l.from_unit, l.from_index)).expect("every link source is a node");
        let target = &system.units()[l.to_unit].interface;
        for (index, v) in target.variables.iter().enumerate() {
            if v.direct_inputs.contains(&l.to_index) {
                if let Some(to) = position((l.to_unit, index)) {
                    if !edges[from].contains(&to) {
                        edges[from].push(to);
                    }
                }
            }
        }
    }
    (nodes, edges)
}

/// The nodes in an order where each comes after those it depends on, preferring to stay on
/// one unit so its outputs are read together; an algebraic loop is an error naming its
/// variables.
fn resolve_order(system: &System, nodes: &[Node], edges: &[Vec<usize>]) -> Result<Vec<usize>, MasterError> {
    let mut indegree = vec![0usize; nodes.len()];
    for e in edges.iter().flatten() {
        indegree[*e] += 1;
    }
    let mut order = Vec::with_capacity(nodes.len());
    let mut done = vec![false; nodes.len()];
    let mut last_unit = None;
    while order.len() < nodes.len() {
        let ready = |i: &usize| !done[*i] && indegree[*i] == 0;
        let next = (0..nodes.len()).filter(ready).find(|&i| Some(nodes[i].0) == last_unit).or_else(|| (0..nodes.len()).find(ready));
        let Some(i) = next else {
            return Err(algebraic_loop(system, nodes, edges, &done));
        };
        done[i] = true;
        order.push(i);
        last_unit = Some(nodes[i].0);
        for &j in &edges[i] {
            indegree[j] -= 1;
        }
    }
    Ok(order)
}

/// The error for the nodes left when no order exists: one cycle among them, written as the
/// connections and dependencies that close it.
fn algebraic_loop(system: &System, nodes: &[Node], edges: &[Vec<usize>], done: &[bool]) -> MasterError {
    let units = system.units();
    let name = |(u, i): Node| format!("{}.{}", units[u].name, units[u].interface.variables[i].name);
    // Every node left has a predecessor left, so walking backwards from one must come round.
    let left: Vec<usize> = (0..nodes.len()).filter(|&i| !done[i]).collect();
    let predecessor = |j: usize| left.iter().copied().find(|&i| edges[i].contains(&j));
    let mut walk = vec![left[0]];
    let cycle = loop {
        let Some(p) = predecessor(*walk.last().expect("not empty")) else { break walk.clone() };
        // walk[i + 1] feeds walk[i], and p = walk[k] feeds the last: walk[k..] reversed
        // runs forward round the cycle.
        if let Some(k) = walk.iter().position(|&x| x == p) {
            let mut c = walk[k..].to_vec();
            c.reverse();
            break c;
        }
        walk.push(p);
    };
    // Told from its first output in declaration order.
    let mut cycle = cycle;
    let first = (0..cycle.len()).min_by_key(|&k| nodes[cycle[k]]).expect("a cycle is not empty");
    cycle.rotate_left(first);
    let mut text = String::new();
    for (k, &i) in cycle.iter().enumerate() {
        let next = cycle[(k + 1) % cycle.len()];
        let (to_unit, to_output) = nodes[next];
        let feeds = |l: &&crate::system::Link| {
            (l.from_unit, l.from_index) == nodes[i]
                && l.to_unit == to_unit
                && units[to_unit].interface.variables[to_output].direct_inputs.contains(&l.to_index)
        };
        let link = system.links().iter().find(feeds).expect("an edge comes from a link");
        text.push_str(&format!("{} → {}.{} ⇒ ", name(nodes[i]), units[to_unit].name, link.to_variable));
    }
    text.push_str(&name(nodes[cycle[0]]));
    MasterError::new(format!(
        "algebraic loop: {text} (→ a connection, ⇒ an output that depends directly on that input), so no order resolves these outputs"
    ))
}

/// Gauss–Seidel stepping order: topological over the connections between units; a cycle is
/// cut at its first unit (declaration order) without direct feedthrough, else at its first.
fn step_order(system: &System) -> Vec<usize> {
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
            .or_else(|| (0..n).find(|&u| !done[u]))
            .expect("a unit is left");
        done[u] = true;
        order.push(u);
        for l in links.iter().filter(|l| l.from_unit == u && l.to_unit != u) {
            indegree[l.to_unit] = indegree[l.to_unit].saturating_sub(1);
        }
    }
    order
}

/// The ordered nodes grouped into passes: a node joins the pass before it when it is of the
/// same unit and depends on none of that pass's nodes.
fn group_into_passes(order: &[usize], nodes: &[Node], edges: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for &i in order {
        match groups.last_mut() {
            Some(g) if nodes[g[0]].0 == nodes[i].0 && !g.iter().any(|&j| edges[j].contains(&i)) => g.push(i),
            _ => groups.push(vec![i]),
        }
    }
    groups
}

/// The pass reading the outputs of nodes `group` (of one unit) and passing them on over every
/// link from them; `pass_of_node` gives each node's pass, for the passes a transfer wakes.
fn build_pass(system: &System, nodes: &[Node], group: &[usize], pass_of_node: &[usize]) -> Pass {
    let unit = nodes[group[0]].0;
    let interface = &system.units()[unit].interface;
    let mut pass = Pass { unit, reads: Default::default(), transfers: Vec::new() };
    for &i in group {
        let v = &interface.variables[nodes[i].1];
        pass.reads[slot(v.base)].push(v.value_reference);
    }
    for l in system.links().iter().filter(|l| l.from_unit == unit && group.iter().any(|&i| nodes[i].1 == l.from_index)) {
        let s = slot(l.base);
        let k = pass.reads[s].iter().position(|&vr| vr == l.from_vr).expect("read above");
        let base = l.base.access();
        let t = match pass.transfers.iter().position(|t| t.to == l.to_unit && t.base == base) {
            Some(t) => t,
            None => {
                pass.transfers.push(Transfer { base, to: l.to_unit, vrs: Vec::new(), from: Vec::new(), wakes: Vec::new() });
                pass.transfers.len() - 1
            }
        };
        let t = &mut pass.transfers[t];
        t.vrs.push(l.to_vr);
        t.from.push(k);
        // Passes of the target holding outputs that depend on this input.
        let target = &system.units()[l.to_unit].interface;
        for (j, &(u, index)) in nodes.iter().enumerate() {
            if u == l.to_unit && target.variables[index].direct_inputs.contains(&l.to_index) && !t.wakes.contains(&pass_of_node[j]) {
                t.wakes.push(pass_of_node[j]);
            }
        }
    }
    pass
}

/// What each pass reaches, as sorted step positions: its targets, and what the passes it
/// wakes reach (later in the order, so computed first going backwards).
fn reach(passes: &[Pass], step_position: &[usize]) -> Vec<Vec<usize>> {
    let mut reach: Vec<Vec<usize>> = vec![Vec::new(); passes.len()];
    for p in (0..passes.len()).rev() {
        let mut r: Vec<usize> = Vec::new();
        for t in &passes[p].transfers {
            r.push(step_position[t.to]);
            for &q in &t.wakes {
                r.extend_from_slice(&reach[q]);
            }
        }
        r.sort_unstable();
        r.dedup();
        reach[p] = r;
    }
    reach
}

impl Schedule {
    /// The schedule of `system`; fails on an algebraic loop.
    pub fn new(system: &System) -> Result<Self, MasterError> {
        let n = system.units().len();
        let (nodes, edges) = dependency_graph(system);
        let order = resolve_order(system, &nodes, &edges)?;
        let groups = group_into_passes(&order, &nodes, &edges);
        let mut pass_of_node = vec![0; nodes.len()];
        for (p, g) in groups.iter().enumerate() {
            for &i in g {
                pass_of_node[i] = p;
            }
        }
        let mut unit_passes = vec![Vec::new(); n];
        let mut passes: Vec<Pass> = Vec::with_capacity(groups.len());
        for (p, g) in groups.iter().enumerate() {
            let pass = build_pass(system, &nodes, g, &pass_of_node);
            unit_passes[pass.unit].push(p);
            passes.push(pass);
        }

        let step_order = step_order(system);
        let mut step_position = vec![0; n];
        for (i, &u) in step_order.iter().enumerate() {
            step_position[u] = i;
        }
        let reach = reach(&passes, &step_position);

        let widest_read = |s: usize| passes.iter().map(|p| p.reads[s].len()).max().unwrap_or(0);
        let widest_set =
            |base: BaseType| passes.iter().flat_map(|p| &p.transfers).filter(|t| t.base == base).map(|t| t.vrs.len()).max().unwrap_or(0);
        Ok(Self {
            buf_real: vec![0.0; widest_read(0)],
            buf_int: vec![0; widest_read(1)],
            buf_bool: vec![0; widest_read(2)],
            buf_str: vec![CString::default(); widest_read(3)],
            set_real: vec![0.0; widest_set(BaseType::Real)],
            set_int: vec![0; widest_set(BaseType::Integer)],
            set_bool: vec![0; widest_set(BaseType::Boolean)],
            set_str: vec![CString::default(); widest_set(BaseType::String)],
            dirty: vec![false; passes.len()],
            passes,
            unit_passes,
            step_order,
            step_position,
            reach,
        })
    }

    /// Marks every pass of `unit` dirty (its outputs changed).
    pub fn touch_unit(&mut self, unit: usize) {
        for &p in &self.unit_passes[unit] {
            self.dirty[p] = true;
        }
    }

    /// Within a Gauss–Seidel sweep, after the unit at step position `now` has stepped: whether
    /// pass `pass`, whose unit's inputs just changed, may stay unread until that unit steps
    /// itself. It may when the unit steps later in this sweep and no unit its values reach
    /// (directly or through direct feedthrough) steps in between: no one would use them
    /// before they are read again after its step.
    pub fn can_wait(&self, pass: usize, now: Option<usize>) -> bool {
        let Some(now) = now else { return false };
        let at = self.step_position[self.passes[pass].unit];
        at > now && self.reach[pass].iter().all(|&c| c <= now || c > at)
    }
}
