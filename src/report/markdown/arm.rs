//! The arm: its links and friction, where the "real" arm comes from, the reference curve, the
//! loops' gains and which speed the task-space compensators are fed.

use std::fmt::Write as _;

use super::list;
use crate::experiments::paper::PaperRun;
use crate::experiments::RealOrigin;

/// Appends the section "The arm".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    link_table(s, run);
    origin_and_reference(s, run);
    gains_and_speeds(s, run);
}

/// The heading and one row per link: geometry, mass and friction.
fn link_table(s: &mut String, run: &PaperRun) {
    let setup = &run.results.setup;
    let _ = writeln!(s, "## The arm\n");
    let _ = writeln!(s, "| link | length [m] | mass [kg] | centre of mass [m] | Coulomb +/− [N·m] | viscous +/− [N·m·s/rad] |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for (i, (l, f)) in setup.nominal.arm.links.iter().zip(&setup.nominal.arm.friction).enumerate() {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} / {} | {} / {} |",
            i + 1,
            l.length_m,
            l.mass_kg,
            l.com_m,
            f.positive.coulomb_nm,
            f.negative.coulomb_nm,
            f.positive.viscous_nms_rad,
            f.negative.viscous_nms_rad
        );
    }
}

/// Where the "real" arm comes from and where the reference curve lies.
fn origin_and_reference(s: &mut String, run: &PaperRun) {
    let setup = &run.results.setup;
    let origin = match &setup.real_origin {
        RealOrigin::Emulated => "emulated from the nominal arm (labelled \"emulated real\" throughout): each joint's friction \
            made asymmetric, with Stribeck break-away (static 1.4 × / 1.1 × Coulomb), viscous friction falling with speed at joints 2 and 3, \
            measurement noise (0.0005 rad, 0.02 rad/s) and 16-bit encoders; see `emulated_real_arm`"
            .to_owned(),
        RealOrigin::Given { source } => format!("the configuration given with `--real` ({source}): the user's belief of the real robot"),
    };
    let _ = writeln!(s, "\nThe \"real\" arm is {origin}. Its configuration is in `results.json` (`setup.real`).\n");
    let [cx, cy] = setup.reference_centre_m;
    let [near, far] = setup.reference_distance_m;
    let _ = writeln!(
        s,
        "The reference is the paper's curve scaled by {:.3} and centred at ({cx:.3}, {cy:.3}) m (default: scale = the reach in m, \
         centre (0.45 R, 0.10 R)); it stays {near:.3}–{far:.3} m from the first joint. The tracking run starts on it, with its velocity, \
         at a pose found by inverse kinematics.\n",
        setup.reference_scale
    );
}

/// The loops' gains and the speed the task-space compensators are fed.
fn gains_and_speeds(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let settings = &r.settings;
    let setup = &r.setup;
    let _ = writeln!(
        s,
        "Gains: task space K_p = {} 1/s², K_d = {} 1/s, null-space damping {} 1/s (acceleration level: the same for any arm). \
         Joint-space loop K_p = {} N·m/rad, K_d = {} N·m·s/rad per joint{}. The gravity sweep holds the joints by computed torque from the gravity-free rigid-body model at {} rad/s.\n",
        settings.tracking_gains.kp,
        settings.tracking_gains.kd,
        settings.tracking_gains.null_damping,
        list(&r.joint_loop.kp),
        list(&r.joint_loop.kd),
        if settings.scale_joint_gains {
            format!(
                " ({} and {} for the built-in arm, times the arm's gravity load relative to it, {:.4}, capped so no joint is faster \
                 than the built-in arm's fastest; see `joint_loop_gains`)",
                settings.joint_kp, settings.joint_kd, setup.gravity_scale
            )
        } else {
            " (as given)".to_owned()
        },
        crate::experiments::gravity::GRAVITY_HOLD_RAD_S
    );
    let _ = writeln!(
        s,
        "{}\n",
        match settings.intent_horizon {
            None => "The task-space loops' compensators are fed the measured joint speeds (the paper's).".to_owned(),
            Some(h) => format!(
                "The task-space loops' compensators are fed the speed the controller commands {h} s ahead, q̇ + {h} u (`--intent-horizon`; \
                 the lead {h} u dropped where it points against a moving joint), not the measured one, so a joint at rest is \
                 compensated the way the law moves it."
            ),
        }
    );
}
