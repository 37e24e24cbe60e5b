//! A weights file that parses but holds no usable net is refused by name (issue 14's fuzzing
//! findings): weights beyond [`read_limits`].

use neurarm_nn::{read_limits, MinMaxScaling, Mlp, Signal, StopReason, TrainReport, TrainSettings, WeightsFile};

fn weights(hidden: usize) -> WeightsFile {
    let net = Mlp {
        iw: nalgebra::DMatrix::from_element(hidden, 1, 0.5),
        b1: nalgebra::DVector::from_element(hidden, 0.1),
        lw: nalgebra::DMatrix::from_element(1, hidden, -0.3),
        b2: nalgebra::DVector::from_element(1, 0.2),
        input_scaling: MinMaxScaling { min: vec![-2.0], max: vec![2.0] },
        output_scaling: MinMaxScaling { min: vec![-1.0], max: vec![1.0] },
    };
    let signal = |name: &str| vec![Signal { name: name.into(), unit: String::new() }];
    let report = TrainReport {
        epochs: 1,
        best_epoch: 1,
        stop_reason: StopReason::Epochs,
        restart: 0,
        train_mse: 0.0,
        validation_mse: None,
        test_mse: None,
        counts: [10, 0, 0],
    };
    WeightsFile::new(&net, signal("x"), signal("y"), TrainSettings::default(), report)
}

#[test]
fn weights_beyond_what_a_trained_net_holds_are_refused() {
    weights(3).network().unwrap();
    let mut big = weights(3);
    big.lw[0][0] = 1.7e308; // finite, but the output is -inf (the finding: eval wrote -inf)
    let e = WeightsFile::from_json(&big.to_json(), "big.json").unwrap_err().to_string();
    assert!(e.contains("big.json: a weight or bias is 1.7e308: beyond ±1e8"), "{e}");
    let mut big = weights(3);
    big.b1[2] = -2e8;
    assert!(big.network().unwrap_err().to_string().contains("a weight or bias is -200000000"));
    let mut wide = weights(3);
    wide.output_scaling.max[0] = 1e300;
    assert!(wide.network().unwrap_err().to_string().contains("a scaling bound is 1e300: beyond ±1e15"));
    let e = weights(read_limits::HIDDEN + 1).network().unwrap_err().to_string();
    assert!(e.contains("10001 hidden neurons: a net may have at most 10000"), "{e}");
    let mut many = weights(2);
    many.inputs = (0..=read_limits::SIGNALS).map(|i| Signal { name: format!("x{i}"), unit: String::new() }).collect();
    assert!(many.network().unwrap_err().to_string().contains("1025 inputs"));
    // A net at the limits is read and evaluates to finite numbers in its range.
    let mut edge = weights(3);
    edge.lw[0][1] = 1e8;
    edge.output_scaling = MinMaxScaling { min: vec![-1e15], max: vec![1e15] };
    let net = edge.network().unwrap();
    for x in [-2.0, 0.0, 2.0] {
        assert!(net.mlp.evaluate(&[x])[0].is_finite());
    }
}
