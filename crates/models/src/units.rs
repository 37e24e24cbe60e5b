//! The units neurarm's models use, declared here with their SI base exponents (the FMI layer
//! lists in each `modelDescription.xml` the ones its variables use).

use neurarm_fmi_export::Unit;

/// Metre.
pub const METRE: Unit = Unit::new("m").m(1);
/// Metre per second.
pub const METRE_PER_SECOND: Unit = Unit::new("m/s").m(1).s(-1);
/// Metre per second squared.
pub const METRE_PER_SECOND_SQUARED: Unit = Unit::new("m/s2").m(1).s(-2);
/// Kilogram.
pub const KILOGRAM: Unit = Unit::new("kg").kg(1);
/// Kilogram square metre, a moment of inertia.
pub const KILOGRAM_METRE_SQUARED: Unit = Unit::new("kg.m2").kg(1).m(2);
/// Radian.
pub const RADIAN: Unit = Unit::new("rad").rad(1);
/// Radian per second.
pub const RADIAN_PER_SECOND: Unit = Unit::new("rad/s").s(-1).rad(1);
/// Newton metre (kg·m²·s⁻²), a torque.
pub const NEWTON_METRE: Unit = Unit::new("N.m").kg(1).m(2).s(-2);
/// Newton metre second per radian, a viscous friction coefficient or velocity gain.
pub const NEWTON_METRE_SECOND_PER_RADIAN: Unit = Unit::new("N.m.s/rad").kg(1).m(2).s(-1).rad(-1);
/// Newton metre per radian, a stiffness or position gain.
pub const NEWTON_METRE_PER_RADIAN: Unit = Unit::new("N.m/rad").kg(1).m(2).s(-2).rad(-1);
/// Per second, a velocity gain of the task-space law.
pub const PER_SECOND: Unit = Unit::new("1/s").s(-1);
/// Per second squared, a position gain of the task-space law.
pub const PER_SECOND_SQUARED: Unit = Unit::new("1/s2").s(-2);
