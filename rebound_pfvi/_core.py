"""Loads the C core, checks it against the running rebound, registers "pfvi".

Everything here runs once per process, at the first ``import rebound_pfvi``.
"""
import ctypes
import os
import sysconfig

import rebound

INTEGRATOR_NAME = "pfvi"

_path = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                     "_pfvi_core" + sysconfig.get_config_var("EXT_SUFFIX"))
try:
    lib = ctypes.CDLL(_path)
except OSError as error:
    raise ImportError(f"rebound_pfvi: cannot load its C core {_path}: {error}. "
                      "Reinstall rebound_pfvi (pip install .) so that the core is compiled.") from error

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
lib.pfvi_density_of.restype = ctypes.c_int
lib.pfvi_density_of.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_double)]
lib.pfvi_stages_range.restype = None
lib.pfvi_stages_range.argtypes = [ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int)]
lib.pfvi_two_point_coefficients.restype = ctypes.c_int
lib.pfvi_two_point_coefficients.argtypes = [ctypes.c_double, ctypes.c_double, ctypes.c_double,
                                            ctypes.c_int, ctypes.POINTER(ctypes.c_double)]


def _check_abi():
    compiled = lib.pfvi_rebound_version_compiled().decode()
    running = rebound.__version__
    running_c = ctypes.c_char_p.in_dll(rebound.clibrebound, "reb_version_str").value.decode()
    size_compiled = lib.pfvi_sizeof_simulation()
    size_running = ctypes.sizeof(rebound.Simulation)
    particle_compiled = lib.pfvi_sizeof_particle()
    particle_running = ctypes.sizeof(rebound.Particle)
    if (compiled, size_compiled, particle_compiled) != (running, size_running, particle_running) \
            or running_c != running:
        raise ImportError(
            f"rebound_pfvi was compiled against rebound {compiled} "
            f"(sizeof(struct reb_simulation) = {size_compiled}, sizeof(struct reb_particle) = "
            f"{particle_compiled}) but rebound {running} (C library {running_c}, sizes "
            f"{size_running} and {particle_running}) is running. Install rebound=={compiled}, or "
            "rebuild rebound_pfvi against the running rebound: "
            "pip install --no-build-isolation --force-reinstall --no-deps <rebound_pfvi source>")


_check_abi()
# Once per process: REBOUND 5.2.2 hangs on a second custom registration, so the
# C side also looks the name up in REBOUND's registry before registering.
lib.pfvi_register()
