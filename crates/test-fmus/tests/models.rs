//! The test models through the export layer's instance, as a host drives them: the statuses
//! and refusals a master relies on.

use neurarm_fmi_export::instance::{Instance, Status};
use neurarm_test_fmus::TestModel;

fn instance(model: TestModel) -> Instance {
    let built = model.build().unwrap();
    let guid = built.description().guid();
    Instance::new("t", &guid, built, Box::new(|_, _, _| {}), false).unwrap()
}

fn started(model: TestModel) -> Instance {
    let mut i = instance(model);
    assert_eq!(i.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    i
}

/// The Counter, initialised with its stop time at 0.25 s and the Boolean parameter `flag`
/// (value references: retry 0, finish 1) set to `value`.
fn counter_stopping_at_a_quarter_second(flag: u32, value: bool) -> Instance {
    let mut c = instance(TestModel::Counter);
    assert_eq!(c.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(c.set_real(&[2], &[0.25]), Status::Ok, "stop_at (Real value references: time 0, t_last 1, stop_at 2)");
    assert_eq!(c.set_boolean(&[flag], &[value]), Status::Ok, "Boolean parameter {flag}");
    assert_eq!(c.enter_initialization_mode(), Status::Ok);
    assert_eq!(c.exit_initialization_mode(), Status::Ok);
    c
}

#[test]
fn the_counter_discards_from_its_stop_time_and_says_whether_to_terminate() {
    for (retry, terminated) in [(false, true), (true, false)] {
        let mut c = counter_stopping_at_a_quarter_second(0, retry);
        assert_eq!(c.do_step(0.0, 0.125), Status::Ok);
        assert_eq!(c.do_step(0.125, 0.125), Status::Ok);
        assert_eq!(c.do_step(0.25, 0.125), Status::Discard);
        assert_eq!(c.last_successful_time(), Ok(0.25));
        assert_eq!(c.terminated_status(), Ok(terminated));
        let mut count = [0];
        assert_eq!(c.get_integer(&[0], &mut count), Status::Ok);
        assert_eq!(count, [2], "nothing of the discarded step was done");
        assert_eq!(c.do_step(0.25, 0.125), Status::Error, "no step after a discard without restoring a state");
        assert_eq!(c.terminate(), Status::Ok);
    }
}

#[test]
fn the_counter_can_take_the_step_to_its_stop_time_and_then_ask_to_end() {
    let mut c = counter_stopping_at_a_quarter_second(1, true);
    assert_eq!(c.do_step(0.0, 0.125), Status::Ok);
    // FMI 2.0 can say a step was taken before the request to end only through a discard whose
    // last successful time is the step's end.
    assert_eq!(c.do_step(0.125, 0.125), Status::Discard);
    assert_eq!((c.last_successful_time(), c.terminated_status()), (Ok(0.25), Ok(true)));
    let (mut count, mut t_last) = ([0], [0.0]);
    assert_eq!(c.get_integer(&[0], &mut count), Status::Ok);
    assert_eq!(c.get_real(&[1], &mut t_last), Status::Ok);
    assert_eq!((count, t_last), ([2], [0.25]), "the step was taken");
    assert_eq!(c.do_step(0.25, 0.125), Status::Error, "no step after the request to end");
    assert_eq!(c.terminate(), Status::Ok);
}

#[test]
fn a_fixed_step_model_refuses_another_step_size() {
    let mut clock = started(TestModel::FixedStep);
    assert!(!clock.description().can_handle_variable_step);
    assert_eq!(clock.do_step(0.0, 0.25), Status::Ok);
    assert_eq!(clock.do_step(0.25, 0.1), Status::Error);
    assert_eq!(clock.do_step(0.25, 0.25), Status::Ok, "the refused call changed nothing");
    let xml = clock.description().to_xml();
    assert!(xml.contains(r#"canHandleVariableCommunicationStepSize="false""#), "{xml}");
}

#[test]
fn an_enumeration_takes_only_its_items() {
    let mut m = instance(TestModel::Modes);
    // shape (Integer value reference 0) is of type Shape: 1, 2, 3.
    assert_eq!(m.set_integer(&[0], &[3]), Status::Ok);
    assert_eq!(m.set_integer(&[0], &[4]), Status::Error);
    assert_eq!(m.set_integer(&[0], &[0]), Status::Error);
    let xml = m.description().to_xml();
    assert!(xml.contains(r#"<SimpleType name="Shape">"#) && xml.contains(r#"<Item name="ramp" value="3""#), "{xml}");
    assert!(xml.contains(r#"<Enumeration declaredType="Shape" start="1"/>"#), "{xml}");
}

#[test]
fn an_output_with_a_start_value_is_exact_and_settable_before_initialization_only() {
    let mut h = instance(TestModel::Hold);
    // Real value references: time 0, u 1, y 2.
    assert_eq!(h.set_real(&[2], &[5.0]), Status::Ok);
    assert_eq!(h.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(h.enter_initialization_mode(), Status::Ok);
    assert_eq!(h.set_real(&[2], &[6.0]), Status::Ok, "in initialization mode too");
    assert_eq!(h.exit_initialization_mode(), Status::Ok);
    let mut y = [0.0];
    assert_eq!(h.get_real(&[2], &mut y), Status::Ok);
    assert_eq!(y, [6.0]);
    assert_eq!(h.set_real(&[2], &[7.0]), Status::Error, "not once running");
    let xml = h.description().to_xml();
    let hold_y = xml.split("<ScalarVariable").find(|v| v.contains(r#"name="y""#)).unwrap();
    assert!(hold_y.contains(r#"initial="exact""#) && hold_y.contains(r#"start="0""#), "{hold_y}");
    assert!(!xml.contains("<InitialUnknowns>"), "an exact output is no initial unknown: {xml}");
}
