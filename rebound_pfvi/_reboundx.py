"""REBOUNDx operators with pfvi (issue 40, item 2).

REBOUNDx 5.1's ``rx.add_operator(op)`` places an operator by the integrator's
name ("ias15" and "bs": once after the step with the whole dt; "whfast",
"leapfrog": half before, half after) and adds nothing for a name it does not
know, such as "pfvi", with only its generic "do not change the integrator"
warning. pfvi takes adaptive steps as IAS15 does, so an operator belongs where
IAS15 puts it: after the step, with the step REBOUND reports as done
(dt_last_done). This module makes ``add_operator`` do that for "pfvi", as
``rx.add_operator(op, dtfraction=1., timing="post")`` would; recorders and
explicit placements are REBOUNDx's own. With an operator added the operators
are post-timestep modifications, so outputs are REBOUND's own: the step is
cut at each requested time and the operator acts over exactly the time the
state lived (docs/outputs.md).

REBOUNDx is not imported here: the method is wrapped when, and if, the user
imports it (``reboundx.extras``). From C, call
``rebx_add_operator_step(rebx, op, 1., REBX_TIMING_POST)``.
"""
import importlib.abc
import importlib.machinery
import sys
from types import ModuleType
from typing import Any, Optional

_MODULE = "reboundx.extras"


def _patch(extras: ModuleType) -> None:
    cls = extras.Extras
    if getattr(cls.add_operator, "_pfvi", False):
        return
    original = cls.add_operator
    recorder = extras.REBX_OPERATOR_TYPE["recorder"]

    def add_operator(self: Any, operator: Any, dtfraction: Optional[float] = None, timing: str = "post") -> Any:
        if (dtfraction is None and isinstance(operator, extras.Operator) and self._sim
                and self._sim.contents.integrator.name == b"pfvi"
                and operator._operator_type != recorder):
            # IAS15's placement (REBOUNDx's rebx_add_operator for "ias15").
            return original(self, operator, dtfraction=1.0, timing="post")
        return original(self, operator, dtfraction, timing)

    add_operator.__doc__ = original.__doc__
    setattr(add_operator, "__wrapped__", original)
    setattr(add_operator, "_pfvi", True)
    cls.add_operator = add_operator


class _Finder(importlib.abc.MetaPathFinder):
    """Wraps Extras.add_operator once reboundx.extras is executed."""

    def find_spec(self, name: str, path: Any, target: Any = None) -> Any:
        if name != _MODULE:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path, target)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        execute = spec.loader.exec_module

        def exec_module(module: ModuleType) -> None:
            execute(module)
            _patch(module)

        setattr(spec.loader, "exec_module", exec_module)  # this module's loader only
        return spec


def install() -> None:
    """Wraps add_operator now if REBOUNDx is imported, else when it is."""
    if _MODULE in sys.modules:
        _patch(sys.modules[_MODULE])
    elif not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
