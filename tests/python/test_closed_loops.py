"""The closed loops of `neurarm paper`, rerun without our master.

1. The NN-compensated tracking loop (Table 1, "sim NN") stepped by a loop written here with
   fmpy's FMU2Slave, Gauss–Seidel as textbook (set a unit's inputs from the others' current
   outputs, then step it; plant, compensator, controller in turn), reproduces the master's
   trajectory to 1e-9.
2. fmpy's `simulate_ssp` runs the loop's SSP file. It is not Gauss–Seidel: every unit steps from
   the values its connections held before the step, and connections pass values on only after all
   have stepped, starting from 0. So every connection delays by one communication step and
   direct feedthrough is never resolved (the compensator's torque reaches the arm two steps late).
   The same loop written here with that ordering reproduces fmpy's run, and the difference to the
   master is of first order in the step, as a one-step delay is. The SSP binds the start values
   on the components; `simulate_ssp` applies only a set its caller passes, so they are passed.
"""
import numpy as np
from fmpy.ssp.ssd import read_ssd, ParameterSet
from fmpy.ssp.simulation import simulate_ssp

from loops import loop_spec, master_run as run_loop, python_loop as step_loop, read_csv

LOOP = "tracking_sim_nn"
ORDER = ["arm", "comp", "ctl"]  # plant first, then what reads it, the controller last


def master_run(neurarm, paper, tmp_path, stop=None, step=None):
    return run_loop(neurarm, paper, LOOP, tmp_path, stop=stop, step=step)


def python_loop(paper, delayed, stop, step):
    return step_loop(paper, LOOP, "delayed" if delayed else "gauss-seidel", stop, step, order=ORDER)


def test_system_file_is_the_run_the_paper_recorded(neurarm, paper, tmp_path):
    master = master_run(neurarm, paper, tmp_path)
    recorded = read_csv(paper / "data" / f"{LOOP}.csv")  # every 10th step, '.' written as '_'
    for name, column in master.items():
        assert np.array_equal(column[::10], recorded[name.replace(".", "_")]), name


def test_fmu2slave_gauss_seidel_loop_reproduces_the_master(neurarm, paper, tmp_path):
    master = master_run(neurarm, paper, tmp_path)
    step = float(np.diff(master["time"][:2])[0])
    stop = master["time"][-1]
    ours = python_loop(paper, delayed=False, stop=stop, step=step)
    assert len(ours["arm.x"]) == len(master["arm.x"]) - 1
    for name, column in ours.items():
        worst = np.abs(column - master[name][1:]).max()
        assert worst <= 1e-9, f"{name}: {worst:.3e}"
    # The run is not trivial: the arm moved along the reference and friction was compensated.
    assert np.ptp(master["arm.x"]) > 0.5 and np.abs(master["ctl.error_x"]).max() < 5e-3


def fmpy_parameters(path):
    """The components' parameter bindings as the one set `simulate_ssp` takes: it applies a set
    given by the caller only, under hierarchical names ("arm.q0_1")."""
    merged = ParameterSet(name="components")
    for component in read_ssd(path).system.elements:
        for binding in component.parameterBindings:
            for values in binding.parameterValues:
                for p in values.parameters:
                    p.name = f"{component.name}.{p.name}"
                    merged.parameters.append(p)
    return merged


def fmpy_ssp(paper, stop, step):
    path = str(paper / f"{LOOP}.ssp")
    parameters = fmpy_parameters(path)
    in_spec = [(f"{f['name']}.{k}", float(v)) for f in loop_spec(paper, LOOP)["fmu"] for k, v in f.get("parameters", {}).items()]
    assert sorted((p.name, float(p.value)) for p in parameters.parameters) == sorted(in_spec)  # each, once
    result = simulate_ssp(path, start_time=0.0, stop_time=stop, step_size=step, parameter_set=parameters)
    return result[: int(round(stop / step))]  # simulate_ssp's summed time may add one step


def test_simulate_ssp_is_the_delayed_ordering_and_first_order_close(neurarm, paper, tmp_path):
    stop = 2.0
    # fmpy's run is the loop in the delayed ordering, to rounding.
    ssp = fmpy_ssp(paper, stop, 1e-3)
    delayed = python_loop(paper, delayed=True, stop=stop, step=1e-3)
    for name in ["arm.x", "arm.y", "arm.q_1", "arm.q_4", "ctl.tau_1", "ctl.tau_3"]:
        worst = np.abs(ssp[name] - delayed[name]).max()
        assert worst <= 1e-12, f"{name}: {worst:.3e}"
    # Against the master: the delay is an O(h) change of the loop, so the end-effector paths
    # differ by O(h) once the start (all connections at 0) has died out.
    gaps = {}
    for step in [1e-3, 5e-4, 2.5e-4]:
        ssp = fmpy_ssp(paper, stop, step)
        master = master_run(neurarm, paper, tmp_path, stop=stop, step=step)
        n = len(ssp)
        t = master["time"][1: n + 1]
        gap = np.hypot(ssp["arm.x"] - master["arm.x"][1: n + 1], ssp["arm.y"] - master["arm.y"][1: n + 1])
        gaps[step] = gap[t >= 0.25].max()
    print("max end-effector gap, simulate_ssp vs master [m]:", {k: f"{v:.3e}" for k, v in gaps.items()})
    assert gaps[1e-3] < 3e-3  # measured 1.8e-3 m: millimetres on a 0.7 m path
    assert 0.4 < gaps[2.5e-4] / gaps[5e-4] < 0.6  # first order: halving h halves it
