//! Small nets with fixed weights for the tests of the models and of the FMU binary.

use neurarm_nn::{InputEncoding, MinMaxScaling, NetKind, Signal, StopReason, TrainReport, TrainSettings, WeightsFile};

/// A small net of unspecified kind with fixed weights: inputs `x_i`, outputs `y_i`, no units.
pub fn net_file(n_in: usize, hidden: usize, n_out: usize) -> WeightsFile {
    let signals = |p: &str, n: usize| (1..=n).map(|i| signal(format!("{p}_{i}"), "")).collect();
    net(NetKind::Unspecified, None, signals("x", n_in), signals("y", n_out), hidden)
}

/// A small friction or gravity net with fixed weights, the units and names the compensator
/// checks for.
pub fn net(kind: NetKind, joint: Option<usize>, inputs: Vec<Signal>, outputs: Vec<Signal>, hidden: usize) -> WeightsFile {
    let value = |a: usize, b: usize| ((a * 7 + b * 3) % 11) as f64 / 8.0 - 0.6;
    let (n_in, n_out) = (inputs.len(), outputs.len());
    WeightsFile {
        format: neurarm_nn::weights::FORMAT.into(),
        version: neurarm_nn::weights::VERSION,
        encoding: InputEncoding::Raw,
        kind,
        joint,
        iw: (0..hidden).map(|h| (0..n_in).map(|i| value(h, i)).collect()).collect(),
        b1: (0..hidden).map(|h| value(h, 1)).collect(),
        lw: (0..n_out).map(|o| (0..hidden).map(|h| value(o + joint.unwrap_or(0), h)).collect()).collect(),
        b2: (0..n_out).map(|o| value(o, 2)).collect(),
        input_scaling: MinMaxScaling { min: vec![-3.0; n_in], max: vec![3.0; n_in] },
        output_scaling: MinMaxScaling { min: vec![-2.0; n_out], max: vec![2.0; n_out] },
        inputs,
        outputs,
        training: TrainSettings::default(),
        report: TrainReport {
            epochs: 0,
            best_epoch: 0,
            stop_reason: StopReason::Epochs,
            restart: 0,
            train_mse: 0.0,
            validation_mse: None,
            test_mse: None,
            counts: [0; 3],
        },
    }
}

/// A signal of a weights file.
pub fn signal(name: String, unit: &str) -> Signal {
    Signal { name, unit: unit.into() }
}
