"""The FMUs' binaries for the platforms beside linux64 (scripts/build-platforms), run here:
every FMU of a quick paper run and the Van der Pol example carries linux64, win64, darwin64 and
aarch64-linux binaries; the win64 DLL runs under wine and the aarch64 library under qemu
through the same small C host (tests/cross/fmu_host.c) as the linux64 one, on the same
scenario (every real input driven, 200 steps of 1 ms), and their outputs equal linux64's within
1e-12 relative; under wine the FMUs instantiate from the resource URI forms Windows hosts pass
(drive letter, `file:/`, `file://localhost/`, backslashes, a percent-encoded space); the
universal darwin64 dylib exports, for both architectures, every fmi2 function the linux64
library exports. The agreement figures go to target/platform-agreement.json.

Skipped when the cross builds are absent, unless NEURARM_PLATFORM_TESTS=1 (scripts/test sets
it after building them), which makes their absence a failure."""
import json
import math
import os
import pathlib
import shutil
import subprocess
import zipfile

import pytest
from fmpy import read_model_description

ROOT = pathlib.Path(__file__).resolve().parents[2]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
CROSS = TARGET / "release" / "fmu-binaries"
WINE = "/usr/lib/wine/wine64"  # Debian's wine64 puts no wine64 on PATH
QEMU = "qemu-aarch64-static"
PLATFORMS = {"linux64": "so", "win64": "dll", "darwin64": "dylib", "aarch64-linux": "so"}
STEPS, STEP = 200, 1e-3
TOLERANCE = 1e-12


def required():
    return os.environ.get("NEURARM_PLATFORM_TESTS") == "1"


@pytest.fixture(scope="module")
def cross():
    missing = [p for p in ("win64", "darwin64", "aarch64-linux") if not (CROSS / p).is_dir()]
    if missing:
        if required():
            pytest.fail(f"no cross builds for {', '.join(missing)} in {CROSS}: run scripts/build-platforms")
        pytest.skip(f"no cross builds for {', '.join(missing)} (scripts/build-platforms makes them)")
    for tool in ("x86_64-w64-mingw32-gcc", "aarch64-linux-gnu-gcc", QEMU, "llvm-nm-14"):
        if shutil.which(tool) is None:
            pytest.fail(f"{tool} is missing (scripts/test installs it)")
    if not os.path.exists(WINE):
        pytest.fail(f"{WINE} is missing (Debian package wine64; scripts/test installs it)")
    return CROSS


@pytest.fixture(scope="module")
def hosts(cross, tmp_path_factory):
    """The C host built for linux64 (gcc), win64 (mingw) and aarch64 Linux, and a wine prefix."""
    d = tmp_path_factory.mktemp("hosts")
    source = ROOT / "tests" / "cross" / "fmu_host.c"
    subprocess.run(["gcc", "-O2", "-Wall", "-o", d / "host", source, "-ldl"], check=True)
    subprocess.run(["x86_64-w64-mingw32-gcc", "-O2", "-Wall", "-o", d / "host.exe", source], check=True)
    subprocess.run(["aarch64-linux-gnu-gcc", "-O2", "-Wall", "-o", d / "host-aarch64", source, "-ldl"], check=True)
    # Wine 8.0 (Debian 12) has no bcryptprimitives.dll, whose ProcessPrng Rust's standard
    # library imports on Windows (Windows 10 and later ship it): a stand-in for the prefix.
    stub = ROOT / "tests" / "cross" / "bcryptprimitives"
    subprocess.run(["x86_64-w64-mingw32-gcc", "-shared", "-O2", "-o", d / "bcryptprimitives.dll",
                    f"{stub}.c", f"{stub}.def", "-ladvapi32"], check=True)
    prefix = TARGET / "wineprefix"
    env = dict(os.environ, WINEPREFIX=str(prefix), WINEDEBUG="-all")
    if not (prefix / "system.reg").exists():
        subprocess.run([WINE, "wineboot", "-i"], env=env, capture_output=True)
        subprocess.run(["/usr/lib/wine/wineserver64", "-w"], env=env)
    shutil.copy(d / "bcryptprimitives.dll", prefix / "drive_c" / "windows" / "system32" / "bcryptprimitives.dll")
    return {"dir": d, "wine_env": env}


@pytest.fixture(scope="module")
def fmus(cross, paper, tmp_path_factory):
    """Every FMU of the quick paper run, and VanDerPol.fmu, as written with the cross builds."""
    out = tmp_path_factory.mktemp("vdp") / "VanDerPol.fmu"
    subprocess.run([TARGET / "release" / "van-der-pol-fmu", out], check=True, capture_output=True)
    return sorted((paper / "fmu").glob("*.fmu")) + [out]


def windows_path(path):
    # Wine maps the Unix root to drive Z:.
    return "Z:" + str(path).replace("/", "\\")


def scenario(md, uri):
    """Instantiate from `uri`, drive every real input, read every real output after each step."""
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    lines = [f"instantiate probe {md.guid} {uri}", f"setup 0 {STEPS * STEP}"]
    for k in range(STEPS):
        for i, vr in enumerate(inputs):
            lines.append(f"real {vr} {0.5 * math.sin(0.05 * k + 0.9 * i):.17g}")
        lines.append(f"step {k * STEP:.17g} {STEP}")
        lines.append("get " + " ".join(map(str, outputs)))
    lines.append("free")
    return "\n".join(lines) + "\n"


def run(hosts, platform, library, text):
    d = hosts["dir"]
    if platform == "linux64":
        command, env = [d / "host", library], None
    elif platform == "win64":
        command, env = [WINE, d / "host.exe", windows_path(library)], hosts["wine_env"]
    else:
        command, env = [QEMU, "-L", "/usr/aarch64-linux-gnu", d / "host-aarch64", library], None
    r = subprocess.run(command, input=text, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, f"{platform} host failed on {library}: {r.stderr[-2000:]}"
    lines = r.stdout.splitlines()
    assert lines and lines[0] == "instantiated", f"{platform}: {library} did not instantiate: {r.stderr[-2000:]}"
    return [[float(x) for x in line.split()] for line in lines[1:]]


def unpack(fmu, into):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(into)
    return read_model_description(str(fmu))


def largest_relative_difference(a, b):
    """Largest |a - b| over each output's largest magnitude in the run (0 for an output that stays 0)."""
    assert len(a) == len(b) and all(len(x) == len(y) for x, y in zip(a, b))
    worst = 0.0
    for column in range(len(a[0]) if a else 0):
        scale = max(max(abs(r[column]) for r in a), max(abs(r[column]) for r in b))
        if scale > 0:
            worst = max(worst, max(abs(x[column] - y[column]) for x, y in zip(a, b)) / scale)
    return worst


def test_every_fmu_carries_every_platform(fmus):
    assert len(fmus) >= 10
    for fmu in fmus:
        md = read_model_description(str(fmu))
        names = set(zipfile.ZipFile(fmu).namelist())
        for platform, extension in PLATFORMS.items():
            assert f"binaries/{platform}/{md.coSimulation.modelIdentifier}.{extension}" in names, (fmu.name, platform)


def test_win64_and_aarch64_results_equal_linux64(fmus, hosts, tmp_path):
    agreement = {}
    for fmu in fmus:
        folder = tmp_path / fmu.stem
        md = unpack(fmu, folder)
        identifier = md.coSimulation.modelIdentifier
        results = {}
        for platform in ("linux64", "win64", "aarch64-linux"):
            library = folder / "binaries" / platform / f"{identifier}.{PLATFORMS[platform]}"
            resources = folder / "resources"
            uri = ("file:///" + windows_path(resources).replace("\\", "/")) if platform == "win64" else resources.as_uri()
            results[platform] = run(hosts, platform, library, scenario(md, uri))
        assert len(results["linux64"]) == STEPS
        # A comparison of outputs that never move would say nothing.
        assert any(len({row[c] for row in results["linux64"]}) > 1 for c in range(len(results["linux64"][0]))), fmu.name
        agreement[fmu.name] = {p: largest_relative_difference(results["linux64"], results[p]) for p in ("win64", "aarch64-linux")}
    (TARGET / "platform-agreement.json").write_text(json.dumps({"tolerance": TOLERANCE, "steps": STEPS, "fmus": agreement}, indent=1))
    print(json.dumps(agreement, indent=1))
    for name, figures in agreement.items():
        for platform, difference in figures.items():
            assert difference <= TOLERANCE, f"{name}: {platform} differs from linux64 by {difference:.3e} relative"


@pytest.mark.parametrize("form", ["file:///{drive}:/{path}", "file:/{drive}:/{path}", "file://localhost/{drive}:/{path}",
                                  "file:///{drive}:\\{backslashed}", "file:///{drive}|/{path}"])
def test_windows_resource_uri_forms(fmus, hosts, tmp_path, form):
    """The compensator (its nets are resources) under wine from each URI form, in a folder whose
    name has a space (percent-encoded where the form is a URI), gives linux64's results."""
    fmu = next(f for f in fmus if f.name == "NnCompensator.fmu")
    folder = tmp_path / "with space" / fmu.stem
    md = unpack(fmu, folder)
    resources = folder / "resources"
    relative = windows_path(resources)[3:]  # the path after "Z:\"
    uri = form.format(drive="Z", path=relative.replace("\\", "/").replace(" ", "%20"), backslashed=relative)
    text = scenario(md, uri)
    windows = run(hosts, "win64", folder / "binaries" / "win64" / "NnCompensator.dll", text)
    linux = run(hosts, "linux64", folder / "binaries" / "linux64" / "NnCompensator.so", scenario(md, resources.as_uri()))
    assert largest_relative_difference(linux, windows) <= TOLERANCE


def exported_fmi2(command):
    out = subprocess.run(command, capture_output=True, text=True, check=True).stdout
    return {line.split()[-1].lstrip("_") for line in out.splitlines() if line.split() and line.split()[-1].lstrip("_").startswith("fmi2")}


def test_darwin_dylib_exports_every_fmi2_function(fmus, tmp_path):
    for fmu in fmus:
        folder = tmp_path / fmu.stem
        md = unpack(fmu, folder)
        identifier = md.coSimulation.modelIdentifier
        linux = exported_fmi2(["nm", "-D", "--defined-only", folder / "binaries" / "linux64" / f"{identifier}.so"])
        assert len(linux) >= 30, linux
        dylib = folder / "binaries" / "darwin64" / f"{identifier}.dylib"
        for arch in ("x86_64", "arm64"):
            darwin = exported_fmi2(["llvm-nm-14", "-gU", f"--arch={arch}", dylib])
            assert darwin == linux, f"{fmu.name} ({arch}): missing {sorted(linux - darwin)}, extra {sorted(darwin - linux)}"
