"""Issue 41: a REBOUNDx built in one venv and taken from pip's wheel cache in
another links that venv's librebound, so the process holds two copies of
REBOUND's C library and "pfvi" is registered in one only. `import
rebound_pfvi` refuses with an ImportError naming pfvi, both copies and the
fix (without the check the import failed with REBOUND's bare "Integrator not
found.")."""
import shutil
import subprocess
import sys

import pytest

import rebound_pfvi  # noqa: F401
from rebound_pfvi import _core

FIX = "pip install --no-cache-dir --force-reinstall reboundx"


def test_the_message_names_pfvi_both_copies_and_the_fix():
    assert _core.two_librebounds_message(["/a/librebound.so"], "/a/librebound.so") is None
    message = _core.two_librebounds_message(["/a/librebound.so", "/b/librebound.so"], "/a/librebound.so")
    assert '"pfvi" can be registered in one copy only' in message
    assert "/a/librebound.so" in message and "/b/librebound.so" in message and FIX in message


def test_maps_reading_keeps_librebound_and_not_libreboundx(tmp_path):
    maps = tmp_path / "maps"
    maps.write_text(
        "7f00-7f01 r-xp 00000000 08:01 1 /v1/site-packages/librebound.cpython-311-x86_64-linux-gnu.so\n"
        "7f01-7f02 r--p 00001000 08:01 1 /v1/site-packages/librebound.cpython-311-x86_64-linux-gnu.so\n"
        "7f02-7f03 r-xp 00000000 08:01 2 /v1/site-packages/libreboundx.cpython-311-x86_64-linux-gnu.so\n"
        "7f03-7f04 rw-p 00000000 00:00 0 \n"
        "7f04-7f05 r-xp 00000000 08:01 3 /v2/site-packages/librebound.cpython-311-x86_64-linux-gnu.so\n")
    assert _core.loaded_librebounds(str(maps)) == [
        "/v1/site-packages/librebound.cpython-311-x86_64-linux-gnu.so",
        "/v2/site-packages/librebound.cpython-311-x86_64-linux-gnu.so"]
    assert _core.loaded_librebounds(str(tmp_path / "absent")) == []


def test_this_process_has_one_librebound():
    _core.check_one_librebound()  # no error


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
def test_a_second_librebound_loaded_before_the_import_is_named(tmp_path):
    """What a REBOUNDx from another venv does, simulated: a copy of
    librebound at another path is loaded before `import rebound_pfvi`."""
    import rebound

    copy = tmp_path / "other-venv" / "librebound.cpython-311-x86_64-linux-gnu.so"
    copy.parent.mkdir()
    shutil.copy(rebound.clibrebound._name, copy)
    code = (f"import ctypes, warnings, rebound; ctypes.CDLL({str(copy)!r}); "
            "warnings.simplefilter('always'); import rebound_pfvi")
    run = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, cwd=tmp_path,
                         timeout=120)
    assert run.returncode == 1, run.stderr
    assert "ImportError: rebound_pfvi: this process has loaded 2 copies" in run.stderr, run.stderr
    assert str(copy) in run.stderr and FIX in run.stderr
