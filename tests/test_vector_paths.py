"""The vector path and the baseline path give the same trajectories, bit for
bit (issue 42).

The core's loops over stages, components and pairs are written with four
doubles as one value (pfvi_lanes, pfvi.h); on x86-64 Linux the hot ones are
compiled twice (target_clones: an AVX2 clone chosen at load time where the
processor has it, and the baseline SSE2 path). Each lane is the scalar
operation, rounded alike, so both must give the same bits. This test builds
the core from the source tree without the clones (PFVI_NO_CLONES) into a
temporary folder and runs benchmarks/same_bits.py's runs (every scheme and
fitting, s = 2 ... 8, the three step controls, the pages' scenes, flybys,
retrograde crossings, test particles of both types, softening, outputs, a
reversal, contacts and MEGNO) with both builds.
"""
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
import rebound

import rebound_pfvi

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import same_bits  # noqa: E402

pytestmark = pytest.mark.slow


def avx2():
    try:
        return " avx2" in Path("/proc/cpuinfo").read_text()
    except OSError:
        return False


def clones_in(core):
    """Whether the installed core holds AVX2 clones (GCC on x86-64 Linux)."""
    out = subprocess.run(["nm", str(core)], capture_output=True, text=True)
    return out.returncode == 0 and ".avx2" in out.stdout


@pytest.fixture(scope="module")
def baseline_build(tmp_path_factory):
    """The core without its AVX2 clones, beside a copy of the package."""
    if not (ROOT / "setup.py").exists() or not (ROOT / "rebound_pfvi" / "csrc" / "pfvi.h").exists():
        pytest.skip("needs the source tree (setup.py, rebound_pfvi/csrc) beside the tests")
    if platform.machine() != "x86_64" or not sys.platform.startswith("linux") or shutil.which("nm") is None:
        pytest.skip("the clones exist on x86-64 Linux with GCC (and nm to see them)")
    core = Path(rebound_pfvi.__file__).parent / ("_pfvi_core" + sysconfig.get_config_var("EXT_SUFFIX"))
    if not clones_in(core):
        pytest.skip(f"the core under test ({core}) has no AVX2 clones to compare")
    if not avx2():
        pytest.skip("this processor has no AVX2: both builds would run the baseline path")
    work = tmp_path_factory.mktemp("no-clones")
    env = dict(os.environ, CFLAGS="-DPFVI_NO_CLONES")
    build = subprocess.run([sys.executable, "setup.py", "build_ext", "--build-lib", str(work / "lib"),
                            "--build-temp", str(work / "tmp")], cwd=ROOT, env=env, capture_output=True, text=True)
    if build.returncode != 0:
        pytest.skip(f"cannot build the core here: {build.stderr.strip().splitlines()[-1:]}")
    package = work / "lib" / "rebound_pfvi"
    for source in Path(rebound_pfvi.__file__).parent.glob("*.py"):
        shutil.copy(source, package / source.name)
    built = package / core.name
    assert built.exists() and not clones_in(built)
    # The core finds REBOUND's library beside its package (RUNPATH $ORIGIN/..).
    site = Path(rebound.__file__).resolve().parent.parent
    librebound = "librebound" + sysconfig.get_config_var("EXT_SUFFIX")
    (work / "lib" / librebound).symlink_to(site / librebound)
    return work / "lib"


def test_the_baseline_build_is_the_one_its_children_load(baseline_build):
    out = subprocess.run(["env", f"PYTHONPATH={baseline_build}", sys.executable, "-P", "-c",
                          "import rebound_pfvi._core as c; print(c._path)"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().startswith(str(baseline_build))


@pytest.mark.parametrize("name", same_bits.RUNS)
def test_vector_and_baseline_paths_give_the_same_bits(baseline_build, name):
    vector = same_bits.run([sys.executable], name)
    baseline = same_bits.run([f"PYTHONPATH={baseline_build}", sys.executable], name)
    assert "error" not in vector, vector
    assert vector == baseline   # the real trajectory and the variational particles
