//! The names of the variables neurarm's FMUs declare, in one place: the models declare their
//! variables with these names and hosts (the neurarm app, system files it writes) address
//! them with the same ones, so a renamed variable cannot drift between the two.
//!
//! A constant names a variable, or a family of per-joint variables. A per-joint variable is
//! its family's name, `_` and the joint's number counted from 1, joint 1 at the base:
//! [`joint`]`(ANGLE, 1)` is `q_1`. In a system, a unit's variable is `unit.variable`
//! ([`path`], [`joint_path`]); a connection addresses every joint at once with `family_*`
//! ([`all_joints`]). Units: rad, rad/s, N·m, m, kg, s as each constant says.

// The planar arm's signals (PlanarArm; controllers and compensators share the joint ones).

/// Torque command of a joint [N·m]: the arm's input, the controllers' output.
pub const TORQUE: &str = "tau";
/// Angle of a joint [rad]: the arm's output, the controllers' and compensators' input.
pub const ANGLE: &str = "q";
/// Velocity of a joint [rad/s]: the arm's output, the controllers' and compensators' input.
pub const VELOCITY: &str = "qd";
/// Measured angle of a joint (encoder, noise) [rad]: the arm's output.
pub const MEASURED_ANGLE: &str = "q_meas";
/// Measured velocity of a joint (noise) [rad/s]: the arm's output.
pub const MEASURED_VELOCITY: &str = "qd_meas";
/// End-effector position, x [m].
pub const END_EFFECTOR_X: &str = "x";
/// End-effector position, y [m].
pub const END_EFFECTOR_Y: &str = "y";
/// End-effector velocity, x [m/s].
pub const END_EFFECTOR_XD: &str = "xd";
/// End-effector velocity, y [m/s].
pub const END_EFFECTOR_YD: &str = "yd";
/// Initial angle of a joint [rad], a parameter of the arm.
pub const START_ANGLE: &str = "q0";
/// Initial velocity of a joint [rad/s], a parameter of the arm.
pub const START_VELOCITY: &str = "qd0";

// The arm's parameters of each joint (`crate::planar_arm::JOINT_PARAMETERS`).

/// Length of a link [m].
pub const LENGTH: &str = "length";
/// Mass of a link [kg].
pub const MASS: &str = "mass";
/// Distance from a joint to the centre of mass of its link [m].
pub const CENTRE_OF_MASS: &str = "com";
/// Moment of inertia of a link about its centre of mass [kg·m²].
pub const INERTIA: &str = "inertia";
/// Coulomb friction of a joint, positive velocity [N·m].
pub const COULOMB_POS: &str = "coulomb_pos";
/// Static (breakaway) friction of a joint, positive velocity [N·m].
pub const STATIC_POS: &str = "static_pos";
/// Stribeck velocity of a joint, positive velocity [rad/s].
pub const STRIBECK_VELOCITY_POS: &str = "stribeck_velocity_pos";
/// Viscous friction coefficient of a joint at low speed, positive velocity [N·m·s/rad].
pub const VISCOUS_POS: &str = "viscous_pos";
/// Speed at which a joint's viscous slope has halved, positive velocity (0: linear) [rad/s].
pub const VISCOUS_FALLOFF_POS: &str = "viscous_falloff_pos";
/// Coulomb friction of a joint, negative velocity (magnitude) [N·m].
pub const COULOMB_NEG: &str = "coulomb_neg";
/// Static (breakaway) friction of a joint, negative velocity (magnitude) [N·m].
pub const STATIC_NEG: &str = "static_neg";
/// Stribeck velocity of a joint, negative velocity [rad/s].
pub const STRIBECK_VELOCITY_NEG: &str = "stribeck_velocity_neg";
/// Viscous friction coefficient of a joint at low speed, negative velocity [N·m·s/rad].
pub const VISCOUS_NEG: &str = "viscous_neg";
/// Speed at which a joint's viscous slope has halved, negative velocity (0: linear) [rad/s].
pub const VISCOUS_FALLOFF_NEG: &str = "viscous_falloff_neg";
/// Largest torque a joint's motor can apply (0: no limit) [N·m].
pub const TORQUE_LIMIT: &str = "torque_limit";
/// Encoder counts per revolution of a joint (0: exact angles).
pub const ENCODER_COUNTS: &str = "encoder_counts";

// The arm's parameters of the whole arm (`crate::planar_arm::ARM_PARAMETERS`).

/// Magnitude of gravitational acceleration [m/s²].
pub const GRAVITY: &str = "gravity";
/// Tilt of the arm's plane: 0 horizontal, π/2 vertical [rad].
pub const BASE_ANGLE: &str = "base_angle";
/// Longest RK4 sub-step inside a communication step [s].
pub const INTERNAL_STEP: &str = "internal_step";
/// Standard deviation of the noise on measured angles [rad].
pub const ANGLE_NOISE_STD: &str = "q_noise_std";
/// Standard deviation of the noise on measured velocities [rad/s].
pub const VELOCITY_NOISE_STD: &str = "qd_noise_std";
/// Seed of the measurement noise (an Integer).
pub const NOISE_SEED: &str = "noise_seed";

// Drift while running (`crate::ports::DriftPorts`): the arm's and the ideal compensator's.

/// Factor on a joint's Coulomb and static friction [-] (1: as configured).
pub const COULOMB_SCALE: &str = "coulomb_scale";
/// Factor on a joint's viscous friction [-] (1: as configured).
pub const VISCOUS_SCALE: &str = "viscous_scale";
/// Point mass held at the tip [kg] (0: none).
pub const PAYLOAD_MASS: &str = "payload_mass";
/// Position of the payload beyond the tip along the last link [m].
pub const PAYLOAD_OFFSET: &str = "payload_offset";

// Every compensator's ports (`crate::ports::CompensatorPorts`).

/// Friction part of a joint's compensating torque [N·m], a compensator's output.
pub const FRICTION_TORQUE: &str = "tau_friction";
/// Gravity part of a joint's compensating torque [N·m], a compensator's output.
pub const GRAVITY_TORQUE: &str = "tau_gravity";
/// Compensating torque of a joint [N·m]: a compensator's output, a controller's input.
pub const COMPENSATION_TORQUE: &str = "tau_comp";
/// Switch adding the friction part (a Boolean).
pub const ENABLE_FRICTION: &str = "enable_friction";
/// Switch adding the gravity part (a Boolean).
pub const ENABLE_GRAVITY: &str = "enable_gravity";

// The controllers (JointController, TaskSpaceController).

/// Learning signal of a joint for an adaptive compensator: a controller's output, the
/// adaptive compensator's input.
pub const LEARNING_SIGNAL: &str = "s";
/// Weight of the position error in the learning signal, λ [1/s].
pub const LAMBDA: &str = "lambda";
/// Position gain: per joint of the joint controller [N·m/rad], one of the task-space
/// controller [1/s²].
pub const KP: &str = "kp";
/// Velocity gain: per joint of the joint controller [N·m·s/rad], one of the task-space
/// controller [1/s].
pub const KD: &str = "kd";
/// Target angle of a joint when the joint controller does not follow its sequence [rad].
pub const REFERENCE_ANGLE: &str = "q_ref";
/// Target velocity of a joint when the joint controller does not follow its sequence [rad/s].
pub const REFERENCE_VELOCITY: &str = "qd_ref";
/// Active target angle of a joint, the joint controller's output [rad].
pub const TARGET_ANGLE: &str = "q_target";
/// Follow the joint controller's built-in target sequence (a Boolean).
pub const USE_SEQUENCE: &str = "use_sequence";
/// Start the built-in sequence again after its last segment (a Boolean).
pub const REPEAT_SEQUENCE: &str = "repeat_sequence";
/// Speed a joint is commanded towards, the task-space controller's output [rad/s].
pub const INTENDED_VELOCITY: &str = "qd_intended";
/// Look-ahead of the intended velocity [s].
pub const INTENT_HORIZON: &str = "intent_horizon";
/// Reference x_d(t) of the task-space controller [m].
pub const REFERENCE_X: &str = "x_ref";
/// Reference y_d(t) of the task-space controller [m].
pub const REFERENCE_Y: &str = "y_ref";
/// Tracking error x_d − x [m].
pub const ERROR_X: &str = "error_x";
/// Tracking error y_d − y [m].
pub const ERROR_Y: &str = "error_y";
/// Null-space damping k_null [1/s].
pub const NULL_DAMPING: &str = "null_damping";
/// Null-space stiffness k_rest [1/s²].
pub const NULL_STIFFNESS: &str = "null_stiffness";
/// Rest angle of a joint the self-motion returns to [rad].
pub const REST_ANGLE: &str = "q_rest";
/// x of the reference's centre [m].
pub const CENTRE_X: &str = "centre_x";
/// y of the reference's centre [m].
pub const CENTRE_Y: &str = "centre_y";
/// Scale of the reference [-] (1: the paper's size).
pub const REFERENCE_SCALE: &str = "reference_scale";

// The adaptive compensator's law (AdaptiveCompensator).

/// Adapt the nets' output layers (a Boolean).
pub const ADAPT: &str = "adapt";
/// Adaptation gain of the friction nets, γ.
pub const GAIN_FRICTION: &str = "gain_friction";
/// Adaptation gain of the gravity net, γ.
pub const GAIN_GRAVITY: &str = "gain_gravity";
/// Leakage σ [1/s].
pub const LEAKAGE: &str = "leakage";
/// Largest change of a friction torque the adaptation may make [N·m].
pub const BOUND_FRICTION: &str = "bound_friction";
/// Largest change of a gravity torque the adaptation may make [N·m].
pub const BOUND_GRAVITY: &str = "bound_gravity";
/// Largest change of a joint's friction torque the adapted net now makes [N·m].
pub const ADAPTED_FRICTION: &str = "adapted_friction";
/// Largest change of a joint's gravity torque the adapted net now makes [N·m].
pub const ADAPTED_GRAVITY: &str = "adapted_gravity";
/// Folder to write the adapted nets into at the end (a String).
pub const NETS_FOLDER: &str = "nets_folder";

// The test blocks (Integrator, Gain).

/// A test block's input u.
pub const BLOCK_INPUT: &str = "u";
/// A test block's output y.
pub const BLOCK_OUTPUT: &str = "y";
/// The integrator's initial output y0.
pub const BLOCK_START: &str = "y0";
/// The gain's factor k.
pub const BLOCK_GAIN: &str = "k";

/// Every name above, each once ([`BLOCK_OUTPUT`] is [`END_EFFECTOR_Y`]).
pub const ALL: &[&str] = &[
    TORQUE,
    ANGLE,
    VELOCITY,
    MEASURED_ANGLE,
    MEASURED_VELOCITY,
    END_EFFECTOR_X,
    END_EFFECTOR_Y,
    END_EFFECTOR_XD,
    END_EFFECTOR_YD,
    START_ANGLE,
    START_VELOCITY,
    LENGTH,
    MASS,
    CENTRE_OF_MASS,
    INERTIA,
    COULOMB_POS,
    STATIC_POS,
    STRIBECK_VELOCITY_POS,
    VISCOUS_POS,
    VISCOUS_FALLOFF_POS,
    COULOMB_NEG,
    STATIC_NEG,
    STRIBECK_VELOCITY_NEG,
    VISCOUS_NEG,
    VISCOUS_FALLOFF_NEG,
    TORQUE_LIMIT,
    ENCODER_COUNTS,
    GRAVITY,
    BASE_ANGLE,
    INTERNAL_STEP,
    ANGLE_NOISE_STD,
    VELOCITY_NOISE_STD,
    NOISE_SEED,
    COULOMB_SCALE,
    VISCOUS_SCALE,
    PAYLOAD_MASS,
    PAYLOAD_OFFSET,
    FRICTION_TORQUE,
    GRAVITY_TORQUE,
    COMPENSATION_TORQUE,
    ENABLE_FRICTION,
    ENABLE_GRAVITY,
    LEARNING_SIGNAL,
    LAMBDA,
    KP,
    KD,
    REFERENCE_ANGLE,
    REFERENCE_VELOCITY,
    TARGET_ANGLE,
    USE_SEQUENCE,
    REPEAT_SEQUENCE,
    INTENDED_VELOCITY,
    INTENT_HORIZON,
    REFERENCE_X,
    REFERENCE_Y,
    ERROR_X,
    ERROR_Y,
    NULL_DAMPING,
    NULL_STIFFNESS,
    REST_ANGLE,
    CENTRE_X,
    CENTRE_Y,
    REFERENCE_SCALE,
    ADAPT,
    GAIN_FRICTION,
    GAIN_GRAVITY,
    LEAKAGE,
    BOUND_FRICTION,
    BOUND_GRAVITY,
    ADAPTED_FRICTION,
    ADAPTED_GRAVITY,
    NETS_FOLDER,
    BLOCK_INPUT,
    BLOCK_START,
    BLOCK_GAIN,
];

/// The variable of joint `j` (counted from 1) of `family`: `joint(ANGLE, 2)` is `q_2`.
pub fn joint(family: &str, j: usize) -> String {
    format!("{}{j}", joint_prefix(family))
}

/// What every joint's variable of `family` starts with, `q_`.
pub fn joint_prefix(family: &str) -> String {
    format!("{family}_")
}

/// The joint (counted from 1) whose variable of `family` `name` is: `joint_of("q_2", ANGLE)`
/// is 2; `None` for a name of another family or without a number.
pub fn joint_of(name: &str, family: &str) -> Option<usize> {
    name.strip_prefix(family)?.strip_prefix('_')?.parse().ok()
}

/// The pattern a system's connection uses for the variables of `family` of every joint:
/// `q_*`.
pub fn all_joints(family: &str) -> String {
    format!("{}*", joint_prefix(family))
}

/// The variable `variable` of the unit `unit` of a system: `path("arm", "q_1")` is `arm.q_1`.
pub fn path(unit: &str, variable: &str) -> String {
    format!("{unit}.{variable}")
}

/// Joint `j`'s (counted from 1) variable of `family` in the unit `unit`: `arm.q_1`.
pub fn joint_path(unit: &str, family: &str, j: usize) -> String {
    path(unit, &joint(family, j))
}

/// The variables of `family` of joints 1 … `n` in the unit `unit`: `arm.q_1` … `arm.q_n`.
pub fn joint_paths(unit: &str, family: &str, n: usize) -> Vec<String> {
    (1..=n).map(|j| joint_path(unit, family, j)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use neurarm_fmi_export::Model;
    use neurarm_physics::arm::ArmParams;
    use neurarm_test_support::nets::net_file;

    /// One model of every kind, with friction and gravity parts where it has them.
    fn models() -> Vec<Box<dyn Model>> {
        use crate::*;
        let arm = ArmParams::default_four_link();
        let nets: Vec<_> = (0..4)
            .map(|j| {
                let mut net = net_file(1, 3, 1);
                net.b2[0] += 0.1 * j as f64;
                net
            })
            .collect();
        let gravity = net_file(4, 3, 4);
        let law = AdaptationLaw::default();
        vec![
            FmuSpec::planar_arm("A", neurarm_physics::config::ArmConfig::default()).build().unwrap(),
            Box::new(joint::JointControllerModel::new("J", 4, 1.0, 0.0, true).unwrap()),
            Box::new(task_space::TaskSpaceControllerModel::new("T", arm.clone(), Default::default(), ([0.0; 2], 1.0), &[0.3; 4]).unwrap()),
            Box::new(ideal::IdealCompensatorModel::new("I", arm, (true, true)).unwrap()),
            Box::new(compensator::NnCompensatorModel::new("N", 4, &nets, Some(&gravity), (true, true), 0).unwrap()),
            Box::new(adaptive::AdaptiveCompensatorModel::new("D", 4, &nets, Some(&gravity), (true, true), law, 0).unwrap()),
            Box::new(signals::IntegratorModel::new("S", 0.0).unwrap()),
            Box::new(signals::GainModel::new("G", 1.0).unwrap()),
        ]
    }

    #[test]
    fn every_variable_a_model_declares_is_named_here_and_every_name_is_declared() {
        let mut used = std::collections::BTreeSet::new();
        for model in models() {
            // Time is the FMI layer's, not the model's.
            for v in model.description().variables.iter().filter(|v| v.causality != neurarm_fmi_export::Causality::Independent) {
                let family = ALL.iter().find(|&&f| v.name == f || joint_of(&v.name, f).is_some_and(|j| v.name == joint(f, j)));
                let family = family.unwrap_or_else(|| panic!("{} of {} has no name in names", v.name, model.description().model_name));
                used.insert(*family);
            }
        }
        let unused: Vec<&str> = ALL.iter().copied().filter(|f| !used.contains(f)).collect();
        assert!(unused.is_empty(), "named but declared by no model: {unused:?}");
        let distinct: std::collections::BTreeSet<&str> = ALL.iter().copied().collect();
        assert_eq!(distinct.len(), ALL.len(), "a name is listed twice");
    }

    #[test]
    fn per_joint_names_count_from_one() {
        assert_eq!(joint(ANGLE, 1), "q_1");
        assert_eq!(joint(MEASURED_VELOCITY, 12), "qd_meas_12");
        assert_eq!(joint_of("qd_meas_12", MEASURED_VELOCITY), Some(12));
        assert_eq!(joint_of("qd_meas_12", VELOCITY), None);
        assert_eq!(joint_of("q_noise_std", ANGLE), None);
        assert_eq!(all_joints(COMPENSATION_TORQUE), "tau_comp_*");
        assert_eq!(joint_path("arm", ANGLE, 2), "arm.q_2");
        assert_eq!(joint_paths("ctl", TORQUE, 2), ["ctl.tau_1", "ctl.tau_2"]);
    }

    #[test]
    fn messages_name_the_variables() {
        assert_eq!(crate::planar_arm::ArmError::NegativeSeed(-1).to_string(), "noise_seed = -1 must be >= 0");
    }
}
