//! Quality checks of a paper run's written outputs against the arm's own laws, computed
//! here (not taken from the run's figures): shared by the example arms' and the family's tests.

use std::path::Path;

use neurarm_nn::WeightsFile;
use neurarm_physics::config::ArmConfig;

/// Friction of the run in `out` on the simulated arm `config` and the real arm `real`: every
/// identified pair of the simulated arm within 0.02 N·m of the law, or 0.5 % of the joint's
/// breakaway torque where that is more (the pair at rest aside),
/// the pairs spanning ≤ 0.2 to ≥ 4.9 rad/s both ways, and, with `net_limit`, every friction
/// net, simulated and real, within that share of the joint's largest friction torque (RMS over
/// 0.2 ≤ |q̇| ≤ 5 rad/s). Returns the worst net's share on the simulated and on the real arm.
pub fn check_friction(out: &Path, config: &ArmConfig, real: &ArmConfig, net_limit: Option<f64>) -> (f64, f64) {
    let joints = config.arm.dof();
    let mut worst_share = [0.0f64; 2];
    for joint in 0..joints {
        let law = config.arm.friction[joint];
        let text = std::fs::read_to_string(out.join(format!("data/friction_sim_joint{}.csv", joint + 1))).unwrap();
        let (mut worst, mut fastest, mut slowest) = (0.0f64, [0.0f64; 2], [f64::INFINITY; 2]);
        let mut speeds: [Vec<f64>; 2] = Default::default();
        for line in text.lines().skip(1) {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            if v[0] == 0.0 {
                continue; // the pair at rest: friction there is anything between the breakaway torques
            }
            worst = worst.max((v[1] - law.torque(v[0])).abs());
            let side = usize::from(v[0] < 0.0);
            fastest[side] = fastest[side].max(v[0].abs());
            slowest[side] = slowest[side].min(v[0].abs());
            speeds[side].push(v[0].abs());
        }
        // Levels 0.1 rad/s apart, binned by 0.05: where constant torques jumped a gap (friction
        // falling with speed), speed-held levels fill it, so no two neighbours lie 0.3 rad/s apart
        // up to the runs' top speed (5 rad/s; a climb that jumped past it once, and went back,
        // keeps that level beyond it).
        for side in &mut speeds {
            side.sort_by(f64::total_cmp);
            let gap =
                side.windows(2).filter(|w| w[0] < 5.0).map(|w| (w[1] - w[0], w[0])).fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
            assert!(gap.0 < 0.3, "{joints} joints, joint {}: no pair between {:.3} and {:.3} rad/s", joint + 1, gap.1, gap.1 + gap.0);
        }
        eprintln!(
            "{joints} joints, joint {}: pairs within {worst:.1e} N·m of the law, speeds {slowest:.2?}–{fastest:.2?} rad/s",
            joint + 1
        );
        // 0.02 N·m, or 0.5 % of the joint's breakaway torque on joints above 4 N·m: the
        // lowest speed-controlled level sits on the Stribeck peak, where a heavy joint's pair
        // (an 8-joint arm's first joint, 35.7 N·m breakaway) was 0.10 N·m (0.28 %) off.
        let tolerance = 0.02f64.max(0.005 * law.breakaway(1.0).max(law.breakaway(-1.0)));
        assert!(
            worst < tolerance,
            "{joints} joints, joint {}: identified friction off the law by {worst} N·m (tolerance {tolerance} N·m)",
            joint + 1
        );
        assert!(
            fastest.iter().all(|&f| f >= 4.9) && slowest.iter().all(|&s| s <= 0.2),
            "joint {}: speeds {slowest:?}–{fastest:?}",
            joint + 1
        );
        for (k, (tag, arm)) in [("sim", config), ("real", real)].into_iter().enumerate() {
            let net = WeightsFile::read(&out.join(format!("nets/friction_{tag}_joint{}.json", joint + 1))).unwrap().network().unwrap();
            let law = arm.arm.friction[joint];
            let (mut sq, mut count, mut largest) = (0.0, 0, 0.0f64);
            for k in 0..=4800 {
                for sign in [1.0, -1.0] {
                    let v = sign * (0.2 + k as f64 * 1e-3);
                    sq += (net.evaluate(&[v])[0] - law.torque(v)).powi(2);
                    largest = largest.max(law.torque(v).abs());
                    count += 1;
                }
            }
            let share = (sq / count as f64).sqrt() / largest;
            worst_share[k] = worst_share[k].max(share);
            if let Some(limit) = net_limit {
                assert!(
                    share < limit,
                    "{joints} joints, {tag} joint {}: net off the law by {:.2} % of {largest} N·m",
                    joint + 1,
                    100.0 * share
                );
            }
        }
    }
    (worst_share[0], worst_share[1])
}

/// The written gravity net of the run in `out` on the arm `config`: it is 2π-periodic in every
/// angle (to 1e-12 N·m), and its RMS and largest error against the arm's gravity (base turned
/// 90°) over 2000 random poses in [0, 2π)ⁿ, per joint as shares of the joint's own largest
/// torque.
pub fn gravity_whole_turn(out: &Path, config: &ArmConfig) -> (Vec<f64>, Vec<f64>) {
    use neurarm_physics::arm::gravity_torques;
    use rand::{Rng, SeedableRng};
    let n = config.arm.dof();
    let net = WeightsFile::read(&out.join("nets/gravity.json")).unwrap().network().unwrap();
    let vertical = config.arm.clone().with_base_angle(std::f64::consts::FRAC_PI_2);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2024);
    let (mut sq, mut max, mut largest) = (vec![0.0; n], vec![0.0f64; n], vec![0.0f64; n]);
    let poses = 2000;
    for _ in 0..poses {
        let q: Vec<f64> = (0..n).map(|_| rng.gen::<f64>() * std::f64::consts::TAU).collect();
        let (guess, truth) = (net.evaluate(&q), gravity_torques(&vertical, &q));
        for i in 0..n {
            let mut turned = q.clone();
            turned[i] += std::f64::consts::TAU * if rng.gen::<bool>() { 1.0 } else { -3.0 };
            let again = net.evaluate(&turned);
            assert!(again.iter().zip(&guess).all(|(a, b)| (a - b).abs() <= 1e-12), "not periodic in q_{}: {again:?} vs {guess:?}", i + 1);
            let e = guess[i] - truth[i];
            sq[i] += e * e;
            max[i] = max[i].max(e.abs());
            largest[i] = largest[i].max(truth[i].abs());
        }
    }
    let rms: Vec<f64> = (0..n).map(|i| (sq[i] / poses as f64).sqrt() / largest[i]).collect();
    let max: Vec<f64> = (0..n).map(|i| max[i] / largest[i]).collect();
    eprintln!("{n} joints, gravity net over the whole turn: RMS {rms:.4?}, largest {max:.4?} of each joint's largest torque");
    (rms, max)
}
