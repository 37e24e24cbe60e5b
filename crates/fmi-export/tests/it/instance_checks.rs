//! The layer's own refusals of values that parse but cannot be used (issue 14), on a model
//! that knows nothing of them: `y = k·u` with a state `s` (the running sum of y) and a model
//! that may write NaN. Steps past the stop time, times a double cannot move, tolerances that
//! are not finite and positive, start values that are not finite, results that are not
//! finite, and FMU states with numbers that are not finite all fail with a logged reason.

use std::sync::{Arc, Mutex};

use neurarm_fmi_export::codec::{Put, Reader};
use neurarm_fmi_export::instance::{Instance, InstantiateError, Status};
use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, TableBuilder, Values};

struct Scale {
    description: ModelDescription,
    u: RealVar,
    y: RealVar,
    k: RealVar,
    sum: f64,
}

impl Scale {
    fn new(k: f64) -> Self {
        let mut b = TableBuilder::new();
        let u = b.input("u", None, 0.0, "input");
        let y = b.output("y", None, "k·u", &[u]);
        let k = b.tunable("k", None, k, "gain");
        Self { description: ModelDescription::new("Scale", "y = k u", b.finish()).unwrap(), u, y, k, sum: 0.0 }
    }
}

impl Model for Scale {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, values: &mut Values, _: f64) -> Result<(), ModelError> {
        values[self.y] = values[self.k] * values[self.u];
        Ok(())
    }
    fn update_outputs(&mut self, values: &mut Values, t: f64) -> Result<(), ModelError> {
        self.initialize(values, t)
    }
    fn do_step(&mut self, values: &mut Values, t: f64, _: f64) -> Result<(), ModelError> {
        self.initialize(values, t)?;
        self.sum += values[self.y];
        Ok(())
    }
    fn reset(&mut self) {
        self.sum = 0.0;
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_f64s(&[self.sum]);
    }
    fn load_state(&mut self, _: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let sum = r.finite_f64s("sum", 1)?;
        r.finish()?;
        self.sum = sum[0];
        Ok(())
    }
}

type Log = Arc<Mutex<Vec<String>>>;

fn instance(k: f64) -> (Instance, Log) {
    let model = Scale::new(k);
    let guid = model.description().guid();
    let log: Log = Arc::default();
    let sink = log.clone();
    let i = Instance::new("x", &guid, Box::new(model), Box::new(move |_, _, m| sink.lock().unwrap().push(m.to_owned())), false).unwrap();
    (i, log)
}

fn logged(log: &Log, text: &str) -> bool {
    log.lock().unwrap().iter().any(|m| m.contains(text))
}

#[test]
fn a_start_value_that_is_not_finite_fails_instantiation_by_name() {
    let model = Scale::new(f64::NAN);
    let guid = model.description().guid();
    match Instance::new("x", &guid, Box::new(model), Box::new(|_, _, _| {}), false) {
        Err(e @ InstantiateError::NonFiniteStart { .. }) => assert_eq!(e.to_string(), "the start value of 'k' is NaN, not a finite number"),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn steps_past_the_stop_time_or_that_do_not_move_the_time_are_refused_and_change_nothing() {
    let (mut i, log) = instance(2.0);
    assert_eq!(i.setup_experiment(Some(1e-6), 0.0, Some(1.0)), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    for h in [1.5, 1e300, 1.0 + 1e-6] {
        assert_eq!(i.do_step(0.0, h), Status::Error, "h = {h}");
    }
    assert!(logged(&log, "at t = 0 s a step of 1.5 s was requested, past the stop time 1 s set at initialization (by 0.5 s)"));
    assert!(logged(&log, "a step of 1e300 s from t = 0 s would end at 1e300 s, beyond 8589934592 s"));
    assert_eq!(i.time(), 0.0);
    assert_eq!(i.do_step(0.0, 0.5), Status::Ok);
    assert_eq!(i.do_step(0.5, 0.5 + 1e-12), Status::Error, "1e-12 s is 4504 ulps past the stop time");
    assert_eq!(i.do_step(0.5, 0.5 + f64::EPSILON), Status::Ok, "one ulp past is rounding");
    // After fmi2Reset the stop time is gone with the experiment.
    assert_eq!(i.reset(), Status::Ok);
    assert_eq!(i.setup_experiment(None, 1e17, None), Status::Error, "beyond the time horizon");
    assert_eq!(i.setup_experiment(None, 1e9, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    assert_eq!(i.do_step(1e9, 1e-20), Status::Error, "1e9 + 1e-20 is 1e9");
    assert!(logged(&log, "a step of 1e-20 s from t = 1000000000 s ends at 1000000000, not at a later time a double can hold"));
    assert_eq!(i.do_step(1e9, 100.0), Status::Ok);
    assert_eq!(i.do_step(1e9 + 100.0, 1e-3), Status::Ok);
}

#[test]
fn tolerances_and_stop_times_that_are_not_usable_are_refused() {
    for tolerance in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
        let (mut i, log) = instance(2.0);
        assert_eq!(i.setup_experiment(Some(tolerance), 0.0, None), Status::Error, "{tolerance}");
        assert!(logged(&log, "must be finite and > 0"));
        assert_eq!(i.setup_experiment(Some(1e-4), 0.0, None), Status::Ok, "the refusal changed nothing");
    }
    let (mut i, log) = instance(2.0);
    assert_eq!(i.setup_experiment(None, 0.0, Some(f64::INFINITY)), Status::Error);
    assert!(logged(&log, "stop time inf is not finite"));
}

#[test]
fn a_result_that_is_not_finite_fails_the_call_and_is_never_read_back() {
    let (mut i, log) = instance(1e300);
    assert_eq!(i.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.set_real(&[1], &[1e300]), Status::Ok);
    let mut y = [0.0];
    assert_eq!(i.get_real(&[2], &mut y), Status::Error, "initial unknowns");
    assert!(logged(&log, "fmi2GetReal: the model computed inf for 'y', not a finite number"));
    assert_eq!(i.exit_initialization_mode(), Status::Error);
    assert!(logged(&log, "fmi2ExitInitializationMode: the model computed inf for 'y'"));
    // In the error state values may be read, but not this one.
    log.lock().unwrap().clear();
    assert_eq!(i.get_real(&[2], &mut y), Status::Error);
    assert!(logged(&log, "for 'y'"));
}

#[test]
fn states_with_numbers_that_are_not_finite_are_refused_by_the_layer_and_the_model() {
    let (mut i, log) = instance(2.0);
    assert_eq!(i.setup_experiment(None, 0.5, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    assert_eq!(i.set_real(&[1], &[0.625]), Status::Ok);
    assert_eq!(i.do_step(0.5, 0.25), Status::Ok);
    let snapshot = i.get_state().unwrap();
    let bytes = i.serialize(&snapshot).unwrap();
    // Each of u = 0.625, y = 1.25, the model's sum 1.25 and the times 0.75 and 0.5 replaced by
    // a number that is not finite, the checksum recomputed: refused, naming what.
    let find = |v: f64| (0..bytes.len() - 8).filter(|&k| bytes[k..k + 8] == v.to_le_bytes()).collect::<Vec<_>>();
    let alter = |at: usize, v: f64| {
        let mut b = bytes.clone();
        b[at..at + 8].copy_from_slice(&v.to_le_bytes());
        let n = b.len() - 4;
        let crc = crc32fast::hash(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
        b
    };
    let (u, y_and_sum, time, start) = (find(0.625), find(1.25), find(0.75), find(0.5));
    assert_eq!((u.len(), y_and_sum.len(), time.len(), start.len()), (1, 2, 2, 1), "the time also as the variable `time`");
    for (at, why) in [
        (u[0], "the state holds NaN for 'u'"),
        (y_and_sum[0], "the state holds NaN for 'y'"),
        (time[0], "the state's time is NaN"),
        (time[1], "the state holds NaN for 'time'"),
        (start[0], "the state's start time is NaN"),
    ] {
        assert!(i.deserialize(&alter(at, f64::NAN)).is_err());
        assert!(logged(&log, why), "{why}");
    }
    // The model's own number is the model's to check, when the state is set.
    let restored = i.deserialize(&alter(y_and_sum[1], f64::INFINITY)).unwrap();
    assert_eq!(i.set_state(&restored), Status::Error);
    assert!(logged(&log, "sum[0] = inf is not a finite number"));
    assert_eq!(i.set_state(&i.deserialize(&bytes).unwrap()), Status::Ok);
}

#[test]
fn no_state_is_saved_after_a_call_left_a_result_that_is_not_finite() {
    // Found by fuzzing fmu_state: a restored state stepped into an infinite output; the state
    // then saved held it and fmi2DeSerializeFMUstate refused its own FMU's state.
    let (mut i, log) = instance(1e300);
    assert_eq!(i.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    let good = i.get_state().unwrap();
    assert_eq!(i.set_real(&[1], &[1e300]), Status::Ok);
    assert_eq!(i.do_step(0.0, 0.1), Status::Error);
    assert!(matches!(i.get_state(), Err(Status::Error)), "no state of a failed call");
    assert!(logged(&log, "fmi2GetFMUstate: the model computed inf for 'y', not a finite number, left by a failed call"));
    // An earlier state restores the instance, which then saves states again.
    assert_eq!(i.set_state(&good), Status::Ok);
    let again = i.get_state().unwrap();
    let bytes = i.serialize(&again).unwrap();
    assert!(i.deserialize(&bytes).is_ok());
}
