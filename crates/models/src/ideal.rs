//! The `IdealCompensator` FMU: the true friction and gravity torques of an arm, with the ports
//! of every compensator ([`CompensatorPorts`]): "perfect compensation". Friction at exactly
//! zero velocity is 0 (the true value there is any torque up to breakaway). It has the arm's
//! tunable drift parameters ([`DriftPorts`]), so it stays the true model of an arm that drifts
//! when a host changes both alike.

use std::path::Path;

use neurarm_fmi_export::{Model, ModelDescription, ModelError, StaticModel, TableBuilder, Values};
use neurarm_physics::arm::{gravity_torques_into, ArmData, ArmParams, OperatingChange};
use serde::{Deserialize, Serialize};

use crate::ports::{drift_error, CompensatorPorts, DriftPorts, Parts};
use crate::{describe, BuildError, ModelKind};

/// Spec of an ideal compensator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdealCompensatorSpec {
    /// The arm.
    pub arm: ArmParams,
    /// Start value of `enable_friction`.
    pub enable_friction: bool,
    /// Start value of `enable_gravity`.
    pub enable_gravity: bool,
}

impl ModelKind for IdealCompensatorSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        Ok(Box::new(IdealCompensatorModel::new(identifier, self.arm.clone(), (self.enable_friction, self.enable_gravity))?))
    }

    fn equations_html(&self) -> &'static str {
        "<p><code>tau_friction_i = f_i(qd_i)</code> (the arm's own friction law, 0 at rest), \
<code>tau_gravity = g(q)</code> (the arm's gravity torques), <code>tau_comp_i</code> their enabled sum; \
the arm changed by the drift parameters (coulomb_scale_i, viscous_scale_i, payload_mass, payload_offset) as \
the PlanarArm FMU changes it.</p>"
    }
}

/// The ideal compensator behind the FMU.
pub struct IdealCompensatorModel {
    description: ModelDescription,
    /// The arm as configured.
    base: ArmParams,
    /// The arm changed by the drift parameters: the one compensated.
    arm: ArmParams,
    drift: DriftPorts,
    change: OperatingChange,
    change_applied: bool,
    ports: CompensatorPorts,
    data: ArmData,
    angles: Vec<f64>,
    gravity: Vec<f64>,
}

impl IdealCompensatorModel {
    /// The ideal compensator of `arm`, its switches starting as `enable` (friction, gravity).
    pub fn new(identifier: &str, arm: ArmParams, enable: (bool, bool)) -> Result<Self, BuildError> {
        arm.validate()?;
        let n = arm.dof();
        let mut b = TableBuilder::new();
        let ports = CompensatorPorts::declare(&mut b, n, Parts { friction: true, gravity: true, source: "true" }, enable);
        let drift = DriftPorts::declare(&mut b, n);
        let text = format!("Ideal compensator: the true friction and gravity torques of a {n}-joint planar arm (neurarm)");
        let description = describe(identifier, text, b.finish())?;
        Ok(Self {
            description,
            data: ArmData::new(&arm),
            base: arm.clone(),
            arm,
            drift,
            change: OperatingChange::none(n),
            change_applied: true,
            ports,
            angles: vec![0.0; n],
            gravity: vec![0.0; n],
        })
    }
}

impl StaticModel for IdealCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        if self.drift.read(values, &mut self.change) || !self.change_applied {
            self.change_applied = false;
            self.change
                .apply_into(&self.base, &mut self.arm)
                .map_err(|e| ModelError::msg(format!("the arm cannot take the change: {}", drift_error(&e))))?;
            self.change_applied = true;
        }
        let p = &self.ports;
        let use_friction = values[p.enable_friction];
        let use_gravity = values[p.enable_gravity];
        values.read_reals(&p.q, &mut self.angles);
        if use_gravity {
            gravity_torques_into(&self.arm, &mut self.data, &self.angles, &mut self.gravity);
        } else {
            self.gravity.fill(0.0);
        }
        for i in 0..p.joints() {
            let f = if use_friction { self.arm.friction[i].torque(values[p.qd[i]]) } else { 0.0 };
            p.write(values, i, f, self.gravity[i]);
        }
        Ok(())
    }
}
