"""Builds the C core of rebound_pfvi against the installed rebound.

The core is a plain shared library loaded with ctypes (as REBOUND and
REBOUNDx do). It links to librebound by file name only and finds it at run
time through RUNPATH $ORIGIN/.., the site-packages folder holding both, so
the installed package carries no path into the build environment.

Which rebound: the one importable here. pip's isolated build gets the one
the build backend (build_backend/pfvi_build.py) asks for, the version already
installed in the target environment when it is in the supported range; a
build without isolation takes the environment's own. Either is refused
outside the range of pyproject.toml's [project] dependencies.
"""
import os
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext


class BuildAgainstRebound(build_ext):
    def build_extensions(self):
        import rebound  # the build requirement (see the docstring above)

        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "build_backend"))
        from pfvi_build import rebound_requirement

        supported = rebound_requirement()
        if not supported.specifier.contains(rebound.__version__, prereleases=True):
            raise RuntimeError(
                f"rebound_pfvi: cannot build against rebound {rebound.__version__} (at {rebound.__file__}): "
                f"the supported range is {supported} (pyproject.toml). 4.x has no integrator registry; "
                "a newer rebound is untested until its headers are checked.")
        # Always compile: the core depends on rebound's headers, which
        # setuptools does not track, so a build/ folder left by a build against
        # another rebound would otherwise be reused as it is.
        self.force = True
        site = os.path.dirname(os.path.dirname(os.path.abspath(rebound.__file__)))
        include = os.path.join(site, "src")
        librebound = "librebound" + sysconfig.get_config_var("EXT_SUFFIX")
        if not os.path.exists(os.path.join(include, "rebound.h")):
            raise RuntimeError(f"rebound {rebound.__version__} at {site} ships no src/rebound.h")
        for ext in self.extensions:
            ext.include_dirs.append(include)
            ext.define_macros.append(("PFVI_REBOUND_VERSION", '"%s"' % rebound.__version__))
            ext.library_dirs.append(site)
            ext.extra_link_args += ["-l:" + librebound, "-Wl,--enable-new-dtags,-rpath,$ORIGIN/.."]
        # The interpreter's own LDSHARED may carry absolute rpaths (pyenv does):
        # the core's only search path is $ORIGIN/..
        self.compiler.linker_so = [arg for arg in self.compiler.linker_so
                                   if not arg.startswith("-Wl,-rpath")]
        super().build_extensions()


core = Extension(
    "rebound_pfvi._pfvi_core",
    sources=[os.path.join("rebound_pfvi", "csrc", f) for f in
             ("pfvi_integrator.c", "pfvi_control.c", "pfvi_step.c", "pfvi_two_point.c", "pfvi_stages.c", "pfvi_solve.c",
              "pfvi_fitting.c", "pfvi_lobatto.c", "pfvi_osculating.c", "pfvi_centre.c", "pfvi_timescales.c", "pfvi_state.c",
               "pfvi_output.c", "pfvi_contact.c", "pfvi_gravity.c")],
    libraries=["m"],
    extra_compile_args=["-std=c99", "-O3", "-fvisibility=hidden", "-Wall", "-Wextra",
                        "-D_GNU_SOURCE", "-fno-math-errno"],
)

setup(ext_modules=[core], cmdclass={"build_ext": BuildAgainstRebound})
