"""The master (`neurarm simulate system.toml`) runs the Modelica Reference-FMUs, FMI 3.0 and
FMI 2.0, with the same results as fmpy; and the Reference-FMUs' own simulator, fmusim, runs
every FMU neurarm writes, FMI 3.0 and 2.0, with the same results as fmpy.

Neither the Reference-FMUs nor fmusim are in the repository (they are built from the public
sources, see README "Checking against the Reference-FMUs"), so these tests run only when told
where they are:

- `NEURARM_REFERENCE_FMUS=DIR`: DIR holds `fmi3/<Model>.fmu` and `fmi2/<Model>.fmu`;
- `NEURARM_FMUSIM=PATH`: the fmusim binary.

Otherwise they are skipped, saying which variable is missing.
"""
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

REFERENCE = os.environ.get("NEURARM_REFERENCE_FMUS")
FMUSIM = os.environ.get("NEURARM_FMUSIM")

needs_reference = pytest.mark.skipif(not REFERENCE, reason="NEURARM_REFERENCE_FMUS is not set")
needs_fmusim = pytest.mark.skipif(not FMUSIM, reason="NEURARM_FMUSIM is not set")

# Feedthrough's inputs set to values that exercise every type the master passes: fractions
# (Float32 gets the nearest f32 on both sides), negative and wide integers, a Boolean, a
# string, an enumeration item.
FEEDTHROUGH_FMI3 = {
    "Float64_continuous_input": 0.1,
    "Float64_discrete_input": -2.5,
    "Float32_continuous_input": 0.1,
    "Float32_discrete_input": 3.75,
    "Int8_input": -100,
    "UInt8_input": 200,
    "Int16_input": -30000,
    "UInt16_input": 60000,
    "Int32_input": -2_000_000_000,
    "UInt32_input": 4_000_000_000,
    "Int64_input": -(2**53) + 1,
    "UInt64_input": 2**53 - 1,
    "Boolean_input": True,
    "String_input": "neurarm",
    "Enumeration_input": 2,
    "Float64_tunable_parameter": 7.25,
}
FEEDTHROUGH_FMI2 = {
    "Float64_continuous_input": 0.1,
    "Float64_discrete_input": -2.5,
    "Int32_input": -2_000_000_000,
    "Boolean_input": True,
    "String_input": "neurarm",
    "Enumeration_input": 2,
    "Float64_tunable_parameter": 7.25,
}

MODELS = ["BouncingBall", "Dahlquist", "Stair", "VanDerPol", "Feedthrough"]


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v + '"'
    return repr(v)


def recorded_variables(md):
    """Every scalar output of a type both tools record (no Binary, no Clock)."""
    skip = {"Binary", "Clock"}
    return [
        v
        for v in md.modelVariables
        if v.causality == "output" and v.type not in skip and not v.dimensions
    ]


def experiment(md):
    d = md.defaultExperiment
    stop = float(d.stopTime) if d and d.stopTime else 2.0
    step = float(d.stepSize) if d and d.stepSize else stop / 100
    return stop, step


def run_master(neurarm, fmu, tmp, start_values, names, stop, step):
    params = ", ".join(f"{k} = {toml_value(v)}" for k, v in start_values.items())
    record = ", ".join(f'"u.{n}"' for n in names)
    system = tmp / f"{fmu.stem}.toml"
    system.write_text(
        f'[[fmu]]\nname = "u"\npath = "{fmu}"\nparameters = {{ {params} }}\n\n'
        f"[simulation]\nstop = {stop!r}\nstep = {step!r}\nrecord = [{record}]\n"
    )
    out = tmp / f"{fmu.stem}.csv"
    run = subprocess.run([neurarm, "simulate", system, "-o", out], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return read_csv(out)


def read_csv(path):
    """A CSV as a header and rows of text fields (strings may be quoted, without commas)."""
    lines = pathlib.Path(path).read_text().splitlines()
    header = [h.strip('"') for h in lines[0].split(",")]
    return header, [[f.strip('"') for f in line.split(",")] for line in lines[1:]]


def same(a, b, what):
    """Values of one column: numbers to 1e-12 relative, text exactly."""
    for k, (x, y) in enumerate(zip(a, b)):
        try:
            fx, fy = float(x), float(y)
        except ValueError:
            assert x == y, f"{what}, row {k}: {x!r} != {y!r}"
            continue
        assert math.isclose(fx, fy, rel_tol=1e-12, abs_tol=1e-12), f"{what}, row {k}: {fx!r} != {fy!r}"


def fmpy_columns(result, names):
    cols = {}
    for n in names:
        col = result[n]
        if col.dtype.kind in "SUO":
            cols[n] = [c.decode() if isinstance(c, bytes) else str(c) for c in col]
        elif col.dtype.kind == "b":
            cols[n] = [str(int(c)) for c in col]
        else:
            cols[n] = [repr(float(c)) if col.dtype.kind == "f" else str(int(c)) for c in col]
    return cols


@needs_reference
@pytest.mark.parametrize("version", ["fmi3", "fmi2"])
@pytest.mark.parametrize("model", MODELS)
def test_master_runs_the_reference_fmus_as_fmpy(neurarm, tmp_path, version, model):
    fmu = pathlib.Path(REFERENCE) / version / f"{model}.fmu"
    assert fmu.exists(), f"{fmu} is missing"
    md = read_model_description(fmu)
    stop, step = experiment(md)
    start = {}
    if model == "Feedthrough":
        start = FEEDTHROUGH_FMI3 if version == "fmi3" else FEEDTHROUGH_FMI2
    names = [v.name for v in recorded_variables(md)]
    header, rows = run_master(neurarm, fmu, tmp_path, start, names, stop, step)
    assert header == ["time"] + [f"u.{n}" for n in names]
    # Feedthrough passes its inputs on: the values set reached the FMU.
    for k, v in start.items():
        out = k.replace("_input", "_output")
        if k.endswith("_input") and out in names and not isinstance(v, str):
            got = float(rows[0][names.index(out) + 1])
            assert math.isclose(got, float(v), rel_tol=1e-7), f"{out}: {got} for {v}"
    # fmpy records no String variables: the master's must be the input passed through.
    strings = [v.name for v in recorded_variables(md) if v.type == "String"]
    for n in strings:
        assert {r[names.index(n) + 1] for r in rows} == {start["String_input"]}, n
    numeric = [n for n in names if n not in strings]
    result = simulate_fmu(
        str(fmu),
        fmi_type="CoSimulation",
        stop_time=stop,
        output_interval=step,
        start_values=start,
        output=numeric,
    )
    # fmpy records the same communication points (a discard or a request to terminate ends
    # both runs at the same time).
    assert len(rows) == len(result), f"{len(rows)} rows, fmpy {len(result)}"
    times = [r[0] for r in rows]
    same(times, [repr(float(t)) for t in result["time"]], f"{model} time")
    cols = fmpy_columns(result, numeric)
    for n in numeric:
        j = names.index(n) + 1
        same([r[j] for r in rows], cols[n], f"{model} {version} {n}")
    assert len(rows) > 10


def neurarm_fmus(paper):
    fmus = sorted((paper / "fmu").glob("*.fmu")) + sorted((paper / "fmu" / "fmi3").glob("*.fmu"))
    assert len(fmus) >= 8, fmus
    return fmus


def fmusim(fmu, out, stop, step, start_values):
    cmd = [FMUSIM, "--interface-type", "cs", "--stop-time", repr(stop), "--output-interval", repr(step)]
    for k, v in start_values.items():
        cmd += ["--start-value", k, toml_value(v).strip('"')]
    for v in recorded_variables(read_model_description(fmu)):
        cmd += ["--output-variable", v.name]
    cmd += ["--output-file", str(out), str(fmu)]
    return subprocess.run(cmd, capture_output=True, text=True)


@needs_fmusim
def test_fmusim_runs_every_neurarm_fmu_as_fmpy(paper, tmp_path):
    """Each FMU of the paper run, free (inputs at their start values) for 0.5 s in steps of
    10 ms: fmusim's outputs equal fmpy's to 1e-12."""
    stop, step = 0.5, 0.01
    for fmu in neurarm_fmus(paper):
        out = tmp_path / f"{fmu.parent.name}-{fmu.stem}.csv"
        run = fmusim(fmu, out, stop, step, {})
        assert run.returncode == 0, f"{fmu.name}: {run.stdout}{run.stderr}"
        header, rows = read_csv(out)
        md = read_model_description(fmu)
        names = [v.name for v in recorded_variables(md)]
        assert header == ["time"] + names, f"{fmu.name}: {header}"
        result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=stop, output_interval=step, output=names)
        assert len(rows) == len(result), f"{fmu.name}: {len(rows)} rows, fmpy {len(result)}"
        cols = fmpy_columns(result, names)
        for j, n in enumerate(names, start=1):
            same([r[j] for r in rows], cols[n], f"{fmu.name} {n}")
