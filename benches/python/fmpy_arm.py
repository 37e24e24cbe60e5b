"""fmpy driving the PlanarArm FMU step by step (FMU2Slave: setReal of 4 torques, doStep,
getReal of 12 outputs), the same loop as benches/fmu_step.rs; prints, as JSON, seconds per step
(the median of the runs) and the outputs after the first run's 1000 steps from the start.

usage: fmpy_arm.py PlanarArm.fmu [RUNS=5]"""
import json
import shutil
import sys
import time

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

fmu_path = sys.argv[1]
runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
STEPS = 1000
OUTPUTS = ["q_1", "q_2", "q_3", "q_4", "qd_1", "qd_2", "qd_3", "qd_4", "x", "y", "xd", "yd"]
md = read_model_description(fmu_path)
vr = {v.name: v.valueReference for v in md.modelVariables}
unzipped = extract(fmu_path)
try:
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    start = {"q0_1": 0.3, "qd0_1": 1.0, "q0_2": -0.5, "qd0_2": -2.0, "q0_3": 0.7, "qd0_3": 1.5, "q0_4": -0.2, "qd0_4": 3.0}
    fmu.setReal([vr[k] for k in start], list(start.values()))
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    inputs = [vr[f"tau_{i}"] for i in range(1, 5)]
    outputs = [vr[n] for n in OUTPUTS]
    tau = [2.0, -1.0, 0.5, 0.2]
    state = fmu.getFMUState()
    samples, after = [], None
    for _ in range(runs):
        fmu.setFMUState(state)
        t0 = time.perf_counter()
        for k in range(STEPS):
            fmu.setReal(inputs, tau)
            fmu.doStep(currentCommunicationPoint=k * 1e-3, communicationStepSize=1e-3)
            values = fmu.getReal(outputs)
        samples.append((time.perf_counter() - t0) / STEPS)
        after = after or dict(zip(OUTPUTS, values))
    fmu.freeFMUState(state)
    fmu.terminate()
    fmu.freeInstance()
finally:
    shutil.rmtree(unzipped, ignore_errors=True)
samples.sort()
print(json.dumps({"seconds_per_step": samples[len(samples) // 2], "steps": STEPS, "outputs": after}))
