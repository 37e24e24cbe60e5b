"""benches/python/null_damping_scan.py sets the controller's null-space damping in a system file
and leaves every other unit as it was."""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benches" / "python"))

import null_damping_scan  # noqa: E402

ARM = '[[fmu]]\nname = "arm"\npath = "../fmu/PlanarArm.fmu"\n\n[fmu.parameters]\nq0_1 = 0.5\n\n'
CONNECTION = '[[connection]]\nfrom = "ctl.tau_*"\nto = "arm.tau_*"\n'


def test_a_controller_without_parameters_gets_a_table_of_its_own():
    text = ARM + '[[fmu]]\nname = "ctl"\npath = "../fmu/TaskSpaceController.fmu"\n\n' + CONNECTION
    out = null_damping_scan.with_null_damping(text, 20.0)
    assert out.count("null_damping = 20.0") == 1
    ctl = out[out.index('name = "ctl"'):out.index("[[connection]]")]
    assert "[fmu.parameters]\nnull_damping = 20.0" in ctl
    assert out.startswith(ARM) and out.endswith(CONNECTION)


def test_a_controller_with_parameters_gets_the_damping_added_or_replaced():
    text = ARM + '[[fmu]]\nname = "ctl"\npath = "c.fmu"\n\n[fmu.parameters]\nkp = 900.0\n\n' + CONNECTION
    out = null_damping_scan.with_null_damping(text, 5.0)
    assert "[fmu.parameters]\nnull_damping = 5.0\nkp = 900.0" in out and out.startswith(ARM)
    again = null_damping_scan.with_null_damping(out, 40.0)
    assert again.count("null_damping") == 1 and "null_damping = 40.0" in again and "kp = 900.0" in again


def test_a_system_without_a_controller_is_refused():
    try:
        null_damping_scan.with_null_damping(ARM + CONNECTION, 10.0)
    except SystemExit as e:
        assert "ctl" in str(e)
    else:
        raise AssertionError("no controller: refused")
