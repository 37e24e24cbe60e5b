//! Small nets with fixed weights for the models' tests.

use nalgebra::{DMatrix, DVector};
use neurarm_physics::nn::{MinMaxScaling, Mlp, Signal, StopReason, TrainReport, TrainSettings, WeightsFile};

/// A small net with fixed weights, written as a weights file.
pub fn net_file(n_in: usize, hidden: usize, n_out: usize) -> WeightsFile {
    let f = |a: usize, b: usize| ((a * 7 + b * 3) % 11) as f64 / 8.0 - 0.6;
    let net = Mlp {
        iw: DMatrix::from_fn(hidden, n_in, f),
        b1: DVector::from_fn(hidden, |j, _| f(j, 1)),
        lw: DMatrix::from_fn(n_out, hidden, f),
        b2: DVector::from_fn(n_out, |k, _| f(k, 2)),
        input_scaling: MinMaxScaling { min: vec![-3.0; n_in], max: vec![3.0; n_in] },
        output_scaling: MinMaxScaling { min: vec![-2.0; n_out], max: vec![2.0; n_out] },
    };
    let signals = |p: &str, n: usize| (1..=n).map(|i| Signal { name: format!("{p}_{i}"), unit: String::new() }).collect();
    let report = TrainReport {
        epochs: 0,
        best_epoch: 0,
        stop_reason: StopReason::Epochs,
        restart: 0,
        train_mse: 0.0,
        validation_mse: None,
        test_mse: None,
        counts: [0; 3],
    };
    WeightsFile::new(&net, signals("x", n_in), signals("y", n_out), TrainSettings::default(), report)
}
