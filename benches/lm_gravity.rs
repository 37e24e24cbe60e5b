//! Levenberg–Marquardt on the paper's gravity set: a 4-25-4 net on the 2401 pairs of a 7⁴
//! grid of the default arm with its base turned 90°. Trains with our trainer, timing every
//! epoch and the test MSE after it (evaluation time excluded), and writes the scaled data,
//! split and initial weights to `$LM_BENCH_DIR` (default `target/lm-bench`) so that
//! `benches/python/lm_compare.py` runs numpy and scipy from exactly the same start.
//! Run through `scripts/bench-lm`.

use std::time::Instant;

use nalgebra::DMatrix;
use neurarm_physics::arm::{gravity_torques, ArmParams};
use neurarm_physics::nn::lm::split;
use neurarm_physics::nn::{train, MinMaxScaling, Mlp, TrainSettings};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn main() {
    if std::env::args().any(|a| a == "--test" || a == "--list") {
        return; // nothing to run under `cargo test --benches`
    }
    let arm = ArmParams::default_four_link().with_base_angle(std::f64::consts::FRAC_PI_2);
    let step = std::f64::consts::TAU / 7.0;
    let mut q = Vec::new();
    for a in 0..7 {
        for b in 0..7 {
            for c in 0..7 {
                for d in 0..7 {
                    q.push([a, b, c, d].map(|k| k as f64 * step));
                }
            }
        }
    }
    let x = DMatrix::from_fn(4, q.len(), |r, c| q[c][r]);
    let t = DMatrix::from_fn(4, q.len(), |r, c| gravity_torques(&arm, &q[c])[r]);
    // trainlm stops at 1000 epochs by default; the bench allows more so that time to the
    // target error can be measured. No early stopping: all three minimise the training error.
    // The start matters: from seed 1 trainlm (ours and the numpy loop alike) settles at a test
    // MSE of 1.1e-4 N²m² and never reaches the target; from seed 2 it does. LM_BENCH_SEED
    // picks another.
    let seed = std::env::var("LM_BENCH_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(2);
    let settings = TrainSettings { hidden: 25, epochs: 3000, max_fail: usize::MAX, min_grad: 1e-12, seed, ..Default::default() };

    // The same scaling, split and initial weights the trainer uses, for the Python peers.
    let (sx, st) = (MinMaxScaling::fit(&x), MinMaxScaling::fit(&t));
    let (xs, ts) = (sx.apply_all(&x), st.apply_all(&t));
    let [train_idx, _, test_idx] = split(q.len(), settings.split, settings.seed);
    let net0 = Mlp::nguyen_widrow(settings.hidden, sx.clone(), st.clone(), &mut ChaCha8Rng::seed_from_u64(settings.seed));
    let cols = |m: &DMatrix<f64>, idx: &[usize]| -> Vec<Vec<f64>> { idx.iter().map(|&c| m.column(c).iter().copied().collect()).collect() };
    let error_scale: Vec<f64> = (0..4).map(|k| st.error_scale(k)).collect();

    let test_mse = |theta: &[f64]| {
        let mut net = net0.clone();
        net.set_parameters(theta);
        let mut sum = 0.0;
        for &c in &test_idx {
            let y = net.evaluate(&q[c]);
            for k in 0..4 {
                sum += (y[k] - t[(k, c)]).powi(2);
            }
        }
        sum / (4 * test_idx.len()) as f64
    };
    let mut history: Vec<(f64, f64)> = Vec::new();
    let mut excluded = 0.0;
    let start = Instant::now();
    let trained = train(&x, &t, &settings, &mut |e| {
        let t0 = Instant::now();
        let mse = test_mse(e.parameters);
        let elapsed = start.elapsed().as_secs_f64() - excluded;
        history.push((elapsed, mse));
        excluded += t0.elapsed().as_secs_f64();
    })
    .unwrap();
    let total = start.elapsed().as_secs_f64() - excluded;
    let to_target = history.iter().find(|(_, m)| *m <= 1e-5).map(|(t, _)| *t);
    let report = serde_json::json!({
        "epochs": trained.report.epochs,
        "stop_reason": format!("{:?}", trained.report.stop_reason),
        "seconds": total,
        "seconds_per_epoch": total / trained.report.epochs as f64,
        "seconds_to_test_mse_1e-5": to_target,
        "final_test_mse": history.last().map(|h| h.1),
    });
    let dir = std::env::var("LM_BENCH_DIR").unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/target/lm-bench").into());
    std::fs::create_dir_all(&dir).unwrap();
    let data = serde_json::json!({
        "x_train": cols(&xs, &train_idx), "t_train": cols(&ts, &train_idx),
        "x_test": cols(&xs, &test_idx), "t_test": cols(&ts, &test_idx),
        "theta0": net0.parameters(), "hidden": settings.hidden, "error_scale": error_scale,
        "settings": settings, "neurarm": report,
    });
    std::fs::write(format!("{dir}/gravity.json"), data.to_string()).unwrap();
    println!("{report}");
}
