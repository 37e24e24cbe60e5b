"""The master's test FMUs (crates/test-fmus, on the export layer) under fmpy, an independent host:
each validates (XSD, the causality/variability/initial table, TypeDefinitions, ModelStructure);
fmpy ends the Counter's run where our master does when its step from 8.8 s is discarded;
fmpy sets the Enumeration parameter and the output with initial="exact" and sees their effect;
and the Split's per-output dependencies are what fmpy reads."""
import csv
import os
import pathlib
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    tool = TARGET / "release" / "neurarm-test-fmus"
    if not tool.exists():
        subprocess.run(["cargo", "build", "--release", "--locked", "-p", "neurarm-test-fmus"], cwd=ROOT, check=True)
    out = tmp_path_factory.mktemp("test-fmus")
    subprocess.run([tool, out], check=True, capture_output=True)
    return out


@pytest.mark.parametrize("name", ["Counter", "Split", "Modes", "Hold", "FixedStep"])
def test_validates(fmus, name):
    assert validate_fmu(str(fmus / f"{name}.fmu")) == []


def test_model_structure_and_types_read_by_fmpy(fmus):
    md = read_model_description(str(fmus / "Split.fmu"))
    by_name = {v.name: v for v in md.modelVariables}
    deps = {o.variable.name: [d.name for d in o.dependencies] for o in md.outputs}
    assert deps == {"y1": ["u1"], "y2": ["u2"]}
    modes = read_model_description(str(fmus / "Modes.fmu"))
    shape = next(v for v in modes.modelVariables if v.name == "shape")
    assert shape.type == "Enumeration" and shape.declaredType.name == "Shape"
    assert [(i.name, int(i.value)) for i in shape.declaredType.items] == [("sine", 1), ("square", 2), ("ramp", 3)]
    hold = read_model_description(str(fmus / "Hold.fmu"))
    y = next(v for v in hold.modelVariables if v.name == "y")
    assert (y.causality, y.initial, y.start) == ("output", "exact", "0")
    assert not read_model_description(str(fmus / "FixedStep.fmu")).coSimulation.canHandleVariableCommunicationStepSize
    assert by_name["k"].variability == "tunable"


def test_discarded_step_ends_fmpy_where_our_master_ends(fmus, neurarm, tmp_path):
    result = simulate_fmu(str(fmus / "Counter.fmu"), stop_time=10.0, output_interval=0.1, output=["count", "t_last"])
    assert result["time"][-1] == pytest.approx(8.8, abs=1e-9)
    system = tmp_path / "counter.toml"
    system.write_text(
        f'[[fmu]]\nname = "c"\npath = "{fmus / "Counter.fmu"}"\n\n'
        '[simulation]\nstop = 10.0\nstep = 0.1\nrecord = ["c.count", "c.t_last"]\n'
    )
    out = tmp_path / "out.csv"
    subprocess.run([neurarm, "simulate", system, "-o", out], check=True, capture_output=True)
    rows = list(csv.DictReader(out.open()))
    assert float(rows[-1]["time"]) == pytest.approx(8.8, abs=1e-9)
    assert int(rows[-1]["c.count"]) == 88
    # fmpy records the point it ended at; its values there are ours.
    assert int(result["count"][-1]) == 88 and result["t_last"][-1] == pytest.approx(8.8)


def test_enumeration_and_exact_output_set_by_fmpy(fmus):
    ramp = simulate_fmu(str(fmus / "Modes.fmu"), stop_time=2.0, output_interval=0.25, start_values={"shape": 3}, output=["y", "active"])
    assert np.all(ramp["active"] == 3)
    assert np.allclose(ramp["y"], np.mod(ramp["time"], 1.0))
    held = simulate_fmu(str(fmus / "Hold.fmu"), stop_time=1.0, output_interval=0.5, start_values={"y": 5.0, "u": 2.0}, output=["y"])
    assert list(held["y"]) == [5.0, 2.0, 2.0]
