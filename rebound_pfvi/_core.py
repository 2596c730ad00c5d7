"""Loads the C core, checks it against the running rebound, registers "pfvi".

Everything here runs once per process, at the first ``import rebound_pfvi``:
the running rebound is checked against the supported range before the core
is loaded (a rebound 4.x lacks the functions the core links to), and against
the version the core was compiled with after; either mismatch is an
ImportError that names both versions and the command that rebuilds.
"""
import ctypes
import json
import os
import sys
import sysconfig
from importlib import metadata
from typing import Optional
from urllib.parse import unquote, urlparse

import rebound

INTEGRATOR_NAME = "pfvi"
#: Why versions outside the supported range are excluded (the range itself is
#: pyproject.toml's, read from the installed package's metadata).
RANGE_REASON = ("4.x has no integrator registry; a rebound newer than the range is untested "
                "until its headers are checked")


def supported_range() -> Optional[str]:
    """The rebound requirement of the installed rebound_pfvi (pyproject.toml's
    [project] dependencies), e.g. ">=5.0,<5.3"; None when rebound_pfvi is not
    installed (run from a source tree)."""
    from packaging.requirements import Requirement

    try:
        requires = metadata.requires("rebound_pfvi") or []
    except metadata.PackageNotFoundError:
        return None
    found = [r for r in map(Requirement, requires) if r.name == "rebound" and r.marker is None]
    return str(found[0].specifier) if found else None


def rebuild_command() -> str:
    """The command that rebuilds rebound_pfvi against the running rebound: pip
    on the source folder it was installed from, when pip recorded one."""
    source = "<the rebound_pfvi source folder>"
    try:
        direct = json.loads(metadata.distribution("rebound_pfvi").read_text("direct_url.json") or "{}")
    except (metadata.PackageNotFoundError, json.JSONDecodeError):
        direct = {}
    url = urlparse(direct.get("url", ""))
    if "dir_info" in direct and url.scheme == "file":
        source = unquote(url.path)
    return f"{sys.executable} -m pip install --force-reinstall --no-deps {source}"


def range_mismatch(running: str, supported: Optional[str]) -> Optional[str]:
    """The error for a running rebound outside the supported range, or None."""
    from packaging.specifiers import SpecifierSet

    if supported is None or SpecifierSet(supported).contains(running, prereleases=True):
        return None
    return (f"rebound_pfvi supports rebound{supported} ({RANGE_REASON}), but rebound {running} is "
            f"running. Install a rebound in the range and rebuild rebound_pfvi against it: "
            f"{sys.executable} -m pip install 'rebound{supported}' && {rebuild_command()}")


def abi_mismatch(compiled: str, running: str, running_c: str,
                 sizes_compiled: tuple, sizes_running: tuple) -> Optional[str]:
    """The error for a core compiled against another rebound than the running
    one (its version, or the sizes of struct reb_simulation and reb_particle),
    or None."""
    if (compiled, sizes_compiled) == (running, sizes_running) and running_c == running:
        return None
    return (f"rebound_pfvi's C core was compiled against rebound {compiled} "
            f"(sizeof(struct reb_simulation) = {sizes_compiled[0]}, sizeof(struct reb_particle) = "
            f"{sizes_compiled[1]}) but rebound {running} (C library {running_c}, sizes "
            f"{sizes_running[0]} and {sizes_running[1]}) is running. Rebuild rebound_pfvi against the "
            f"running rebound: {rebuild_command()}")


def load_error(path: str, error: OSError) -> str:
    """The error for a core that does not load. The core finds REBOUND's C
    library through its RUNPATH only, the folder that holds rebound_pfvi
    (relocatable, tests/test_archive_and_registration.py); a rebound installed
    elsewhere (a venv made with --system-site-packages and the system's
    rebound) is not found, and rebuilding would not help: say where each is
    and put a rebound beside rebound_pfvi."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(path)))
    site = os.path.dirname(os.path.dirname(os.path.abspath(rebound.__file__)))
    librebound = "librebound" + sysconfig.get_config_var("EXT_SUFFIX")
    if os.path.realpath(here) != os.path.realpath(site) and not os.path.exists(os.path.join(here, librebound)):
        return (f"rebound_pfvi: cannot load its C core {path}: {error}. The core looks for REBOUND's "
                f"C library {librebound} in {here}, where rebound_pfvi is installed, but the running "
                f"rebound {rebound.__version__} is installed in {site} (a venv with "
                f"--system-site-packages and the system's rebound?). Install the same rebound into this "
                f"environment: {sys.executable} -m pip install --ignore-installed --no-deps "
                f"'rebound=={rebound.__version__}'")
    return (f"rebound_pfvi: cannot load its C core {path}: {error}. "
            f"Rebuild it against the running rebound {rebound.__version__}: {rebuild_command()}")


_error = range_mismatch(rebound.__version__, supported_range())
if _error is not None:
    raise ImportError(_error)

_path = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                     "_pfvi_core" + sysconfig.get_config_var("EXT_SUFFIX"))
try:
    lib = ctypes.CDLL(_path)
except OSError as error:
    raise ImportError(load_error(_path, error)) from error

lib.pfvi_rebound_version_compiled.restype = ctypes.c_char_p
lib.pfvi_rebound_version_compiled.argtypes = []
lib.pfvi_sizeof_simulation.restype = ctypes.c_size_t
lib.pfvi_sizeof_simulation.argtypes = []
lib.pfvi_sizeof_particle.restype = ctypes.c_size_t
lib.pfvi_sizeof_particle.argtypes = []
lib.pfvi_register.restype = ctypes.c_int
lib.pfvi_register.argtypes = []
lib.pfvi_seed_coefficients.restype = None
lib.pfvi_seed_coefficients.argtypes = [ctypes.c_double, ctypes.c_double, ctypes.POINTER(ctypes.c_double)]
lib.pfvi_gamma.restype = ctypes.c_double
lib.pfvi_gamma.argtypes = [ctypes.c_double]
lib.pfvi_lobatto_table.restype = ctypes.c_int
lib.pfvi_lobatto_table.argtypes = [ctypes.c_int] + [ctypes.POINTER(ctypes.c_double)] * 3
lib.pfvi_nystrom_table.restype = ctypes.c_int
lib.pfvi_nystrom_table.argtypes = [ctypes.c_int] + [ctypes.POINTER(ctypes.c_double)] * 3
lib.pfvi_stage_coefficients.restype = ctypes.c_int
lib.pfvi_stage_coefficients.argtypes = [ctypes.c_int, ctypes.c_double, ctypes.POINTER(ctypes.c_double)]
lib.pfvi_option_value_name.restype = ctypes.c_char_p
lib.pfvi_option_value_name.argtypes = [ctypes.c_char_p, ctypes.c_int]
lib.pfvi_stage_differentiation.restype = ctypes.c_int
lib.pfvi_stage_differentiation.argtypes = [ctypes.c_int, ctypes.c_double, ctypes.c_int, ctypes.POINTER(ctypes.c_double)]
lib.pfvi_partners.restype = ctypes.c_int
lib.pfvi_partners.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)]
lib.pfvi_two_alone.restype = ctypes.c_int
lib.pfvi_two_alone.argtypes = [ctypes.c_void_p]
lib.pfvi_density_of.restype = ctypes.c_int
lib.pfvi_density_of.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_double)]
lib.pfvi_options_check.restype = ctypes.c_int
lib.pfvi_options_check.argtypes = [ctypes.c_void_p]
lib.pfvi_request_begin.restype = ctypes.c_double
lib.pfvi_request_begin.argtypes = [ctypes.c_void_p, ctypes.c_double]
lib.pfvi_request_end.restype = None
lib.pfvi_request_end.argtypes = [ctypes.c_void_p, ctypes.c_double]
lib.pfvi_stages_range.restype = None
lib.pfvi_stages_range.argtypes = [ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int)]
lib.pfvi_two_point_coefficients.restype = ctypes.c_int
lib.pfvi_two_point_coefficients.argtypes = [ctypes.c_double, ctypes.c_double, ctypes.c_double,
                                            ctypes.c_int, ctypes.POINTER(ctypes.c_double)]


def _check_abi():
    running_c = ctypes.c_char_p.in_dll(rebound.clibrebound, "reb_version_str").value.decode()
    error = abi_mismatch(lib.pfvi_rebound_version_compiled().decode(), rebound.__version__, running_c,
                         (lib.pfvi_sizeof_simulation(), lib.pfvi_sizeof_particle()),
                         (ctypes.sizeof(rebound.Simulation), ctypes.sizeof(rebound.Particle)))
    if error is not None:
        raise ImportError(error)


_check_abi()

#: The fix for a REBOUNDx linked to another environment's librebound (pip's
#: wheel cache hands a reboundx built in one venv to another, its runpath
#: still naming the first venv's rebound).
REBOUNDX_FIX = "pip install --no-cache-dir --force-reinstall reboundx"


def loaded_librebounds(maps: str = "/proc/self/maps") -> list:
    """The distinct librebound files this process has loaded (Linux: from
    /proc/self/maps; elsewhere an empty list, nothing to compare)."""
    try:
        with open(maps) as f:
            lines = f.read().splitlines()
    except OSError:
        return []
    found = []
    for line in lines:
        path = line.split(None, 5)[5] if len(line.split(None, 5)) == 6 else ""
        name = os.path.basename(path)
        if name.startswith("librebound") and not name.startswith("libreboundx") and ".so" in name:
            real = os.path.realpath(path)
            if real not in found:
                found.append(real)
    return found


def two_librebounds_message(paths: list, ours: str) -> Optional[str]:
    """The warning for more than one librebound in the process, or None."""
    others = [p for p in paths if p != ours]
    if not others:
        return None
    return (f"rebound_pfvi: this process has loaded {len(paths)} copies of REBOUND's C library: rebound's "
            f"{ours} and {', '.join(others)} (loaded by another package, usually REBOUNDx taken from pip's wheel "
            f"cache and built against another environment's rebound). \"pfvi\" can be registered in one copy "
            f"only, and simulations of the other fail with \"Integrator not found.\" Fix: "
            f"{sys.executable} -m {REBOUNDX_FIX}")


def check_one_librebound() -> None:
    """Raises ImportError when a second librebound is loaded: the core may
    have bound to either copy (the dynamic linker takes the first loaded one
    of that name), and registering then fails with REBOUND's bare
    "Integrator not found." (measured with a REBOUNDx whose runpath names
    another venv)."""
    ours = os.path.realpath(getattr(rebound, "__libpath__", None) or rebound.clibrebound._name)
    message = two_librebounds_message(loaded_librebounds(), ours)
    if message is not None:
        raise ImportError(message)


check_one_librebound()
# Once per process: REBOUND 5.2.2 hangs on a second custom registration, so the
# C side also looks the name up in REBOUND's registry before registering.
lib.pfvi_register()
