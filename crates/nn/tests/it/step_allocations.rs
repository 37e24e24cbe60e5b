//! A training epoch allocates nothing but the GEMM library's packing buffers: a counting global
//! allocator watches the training thread.

use neurarm_test_support::allocations as counting;

use nalgebra::DMatrix;
use neurarm_nn::lm::{gemm_calls, train_with_threads};
use neurarm_nn::TrainSettings;

#[test]
fn training_epochs_allocate_only_the_gemm_buffers() {
    let x = DMatrix::from_fn(2, 300, |r, c| ((c * (r + 3)) % 17) as f64 / 8.0 - 1.0);
    let t = DMatrix::from_fn(3, 300, |r, c| (x[(0, c)] * (r + 1) as f64).sin() + x[(1, c)] * x[(1, c)]);
    let settings = TrainSettings { hidden: 8, epochs: 40, max_fail: usize::MAX, ..Default::default() };
    // Count from the end of epoch 1's callback to epoch 40's: that span is epochs 2…40 whole
    // (linearise, solves, trial evaluations, validation). One thread, so that every GEMM call
    // is made on this one.
    let (per_linearisation, per_trial) = gemm_calls(2, 8, 3);
    let mut epochs_seen = 0;
    let mut counted = None;
    let mut gemms = 0;
    train_with_threads(&x, &t, &settings, 1, &mut |e| {
        if e.epoch == 1 {
            counting::start();
        } else {
            gemms += per_linearisation + per_trial * e.trials;
            if e.epoch == settings.epochs {
                counted = Some(counting::stop());
            }
        }
        epochs_seen += 1;
    })
    .unwrap();
    counting::stop();
    assert_eq!(epochs_seen, 40, "training ran all epochs");
    // Our own code allocates nothing; matrixmultiply allocates its packing buffer once per
    // call: the Gram matrix of [z; ã] by row panels, and each Cholesky factorisation's block
    // rows.
    assert!(gemms >= 39, "{gemms} GEMM calls");
    assert_eq!(counted, Some(gemms), "allocations during 39 epochs");
}
