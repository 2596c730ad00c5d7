"""rebound_pfvi: a phase-fitted discrete Lagrangian integrator for REBOUND.

A variational integrator after O. T. Kosmas and D. S. Vlachos,
"Phase-fitted Discrete Lagrangian Integrators": s Gauss-Lobatto nodes (order
2s - 2), an interpolation that can be fitted to a local frequency, and a
time-symmetric step control sized from every orbit's and encounter's time
scale. Importing this package registers the integrator "pfvi" with REBOUND::

    import rebound
    import rebound_pfvi

    sim = rebound.Simulation()
    sim.add(m=1.)
    sim.add(m=1e-3, a=1., e=0.5)
    sim.integrator = "pfvi"          # adaptive: no sim.dt needed
    sim.integrate(10.)
    print(sim.integrator.n_steps)

Options and statistics are integrator fields, saved in Simulationarchives
(import rebound_pfvi before loading an archive that uses it: see
Simulationarchives below). The lists below are generated from the C core's
own field list when the package is imported.
"""
import ctypes as _ctypes
import math as _math
import operator as _operator
from typing import Any, Dict, Tuple

from ._core import INTEGRATOR_NAME, lib as _lib
from . import _reboundx

_reboundx.install()  # rx.add_operator(op) places operators for "pfvi" as for IAS15

__version__ = "0.1.0"
__all__ = ["INTEGRATOR_NAME", "DEFAULTS", "ARCHIVE_FAILURE", "ARCHIVE_RECIPE",
           "FITTINGS", "FREQUENCIES", "CENTRES", "STEP_CONTROLS", "STAGES", "seed_coefficients",
           "gamma", "two_point_coefficients", "lobatto", "stage_coefficients", "stage_differentiation"]

def _option_values(field):
    """The values of an option, from the C core's one list of them."""
    names = []
    while (name := _lib.pfvi_option_value_name(field.encode(), len(names))) is not None:
        names.append(name.decode())
    return tuple(names)


#: Values of the ``fitting`` field, in the order of the C enum.
FITTINGS = _option_values("fitting")
#: Values of the ``frequency`` field, in the order of the C enum.
FREQUENCIES = _option_values("frequency")
#: Values of the ``centre`` field, in the order of the C enum.
CENTRES = _option_values("centre")
#: Values of the ``step_control`` field, in the order of the C enum.
STEP_CONTROLS = _option_values("step_control")
def _stages():
    low, high = _ctypes.c_int(), _ctypes.c_int()
    _lib.pfvi_stages_range(_ctypes.byref(low), _ctypes.byref(high))
    return tuple(range(low.value, high.value + 1))


#: Allowed values of the ``stages`` field, from the C core.
STAGES = _stages()


def _fields():
    """(options, statistics) of the integrator, each {name: (default, documentation)},
    as the C core documents and sets them for a new simulation."""
    import rebound

    sim = rebound.Simulation()
    sim.integrator = INTEGRATOR_NAME
    options, statistics = {}, {}
    for fd in sim.integrator.callbacks.field_descriptor_list:
        if fd.documentation:
            name, doc = fd.name.decode(), fd.documentation.decode()
            kind = statistics if doc.startswith("Statistic:") else options
            value = getattr(sim.integrator, name)
            # Plain Python values (REBOUND returns its own str subclass for enums).
            value = str(value) if isinstance(value, str) else int(value) if isinstance(value, int) else float(value)
            kind[name] = (value, doc)
    return options, statistics


_OPTIONS, _STATISTICS = _fields()
#: pfvi's options as a new simulation has them, from the C core (the one
#: source: the comparisons, the stability cases and the examples read them here).
DEFAULTS: Dict[str, Any] = {name: value for name, (value, _) in _OPTIONS.items()}
# What an option takes, named in the error for a value of the wrong type.
_FIELD_KINDS = {name: {int: "an int", float: "a real number", str: "one of its names, a string"}[type(value)]
                for name, value in DEFAULTS.items()}


def _first_sentence(text: str) -> str:
    head = text.split(". ")[0].rstrip(".")
    return head if len(head) <= 160 else head[:157] + "..."


def _fields_doc() -> str:
    """The module docstring's part generated from the core's field list."""
    lines = ["", "Options (``sim.integrator.<name>``; default, and what it is: "
             "``help(sim.integrator)`` has each in full)::", ""]
    for name, (value, doc) in _OPTIONS.items():
        lines.append(f"    {name} = {value!r}: {_first_sentence(doc)}")
    lines += ["", "Statistics (counted since the integrator was set)::", ""]
    for name, (_, doc) in _STATISTICS.items():
        lines.append(f"    {name}: {_first_sentence(doc[len('Statistic:'):].strip())}")
    return "\n".join(lines) + "\n"


def _show_options_and_statistics():
    """repr(sim.integrator) for "pfvi": its documented fields (options, then
    statistics), not the scratch saved for archives (compensation, the
    predictor's stage accelerations: pointers). REBOUND's own repr lists every
    field; it is kept for every other integrator."""
    from rebound.integrator import IntegratorConfiguration

    generic = IntegratorConfiguration.__repr__
    if getattr(generic, "_pfvi", False):
        return

    def __repr__(self):
        if self.name != INTEGRATOR_NAME.encode():
            return generic(self)
        shown = [f"name={INTEGRATOR_NAME}"]
        for fd in self.callbacks.field_descriptor_list:
            if fd.documentation:
                name = fd.name.decode()
                shown.append(f"{name}={getattr(self, name)}")
        return f"<{type(self).__module__}.{type(self).__name__} object at {hex(id(self))}, {', '.join(shown)}>"

    __repr__._pfvi = True
    IntegratorConfiguration.__repr__ = __repr__


_show_options_and_statistics()
#: Loading a Simulationarchive written with pfvi: what goes wrong without
#: ``import rebound_pfvi`` and the recipe (help(rebound_pfvi), README.md and
#: docs/integrator.md show it; tests/test_archive_recipe.py runs it).
ARCHIVE_FAILURE = (
    'REBOUND finds an integrator only once it is registered, and importing rebound_pfvi is what registers'
    ' "pfvi". In a process that has not imported it, an archive written with pfvi fails in REBOUND\'s '
    'words, which do not name pfvi (REBOUND reads the file before any code of rebound_pfvi can run): '
    'rebound.Simulationarchive(path)[-1] gives a RuntimeWarning that "The binary file seems to be '
    'corrupted" (REBOUND skips the fields it does not know) and raises "RuntimeError: Integrator not '
    'found." at load; rebound.Simulation(path) gives the same warning, sim.integrator reads "ias15", and '
    'sim.integrate() raises "RuntimeError: Integrator not found." The fix: import rebound_pfvi before '
    'loading.'
)
ARCHIVE_RECIPE = """\
import rebound
import rebound_pfvi  # registers "pfvi": import it before loading an archive written with it

sim = rebound.Simulation()
sim.add(m=1.0)
sim.add(m=1e-3, a=1.0, e=0.5)
sim.integrator = "pfvi"
sim.save_to_file("pfvi-archive.bin", interval=1.0, delete_file=True)
sim.integrate(3.0)

loaded = rebound.Simulationarchive("pfvi-archive.bin")[-1]  # or rebound.Simulation("pfvi-archive.bin")
print(loaded.integrator, loaded.t, loaded.integrator.n_steps == sim.integrator.n_steps)  # pfvi 3.0 True
loaded.integrate(4.0)
"""


def _archive_doc() -> str:
    """The module docstring's part on Simulationarchives."""
    return ("\nSimulationarchives: " + ARCHIVE_FAILURE + " For example::\n\n"
            + "".join(f"    {line}\n" if line else "\n" for line in ARCHIVE_RECIPE.splitlines()))


__doc__ = (__doc__ or "") + _fields_doc() + _archive_doc()


def _refuse_integers_that_wrap():
    """sim.integrator.<field> = value for "pfvi": a statistic is read-only;
    REBOUND passes an integer
    field's value through ctypes.c_int, which wraps (stages = 2**32 + 4 ran at
    s = 4). An int that does not fit the field's C type is refused here,
    naming the field; everything else is REBOUND's own assignment (and a
    value that fits is checked by the core when the next step starts)."""
    from rebound.binarydata_field_descriptor import REB_BINARYDATA_DTYPE
    from rebound.integrator import IntegratorConfiguration

    generic = IntegratorConfiguration.__setattr__
    if getattr(generic, "_pfvi", False):
        return
    limits = {}
    for ctype in (_ctypes.c_int, _ctypes.c_uint, _ctypes.c_long, _ctypes.c_ulong):
        bits = 8 * _ctypes.sizeof(ctype)
        limits[ctype] = (-2**(bits - 1), 2**(bits - 1) - 1) if ctype(-1).value < 0 else (0, 2**bits - 1)

    def __setattr__(self, name, value):
        if self.name == INTEGRATOR_NAME.encode() and name in _STATISTICS:
            # (The docs say read-only; REBOUND wrote them: n_steps = 5 counted on from 5.)
            raise AttributeError(f"integrator.{name} is a statistic pfvi counts (read-only); not set")
        integer = None
        if self.name == INTEGRATOR_NAME.encode() and not isinstance(value, bool):
            # (any integer: numpy's int64 and 0-d integer arrays wrapped too, a hostile trial)
            try:
                integer = _operator.index(value)
            except TypeError:
                integer = None
        if integer is not None:
            descriptor = self.callbacks.field_descriptor_list.field_descriptor_for_name(name)
            low, high = limits.get(REB_BINARYDATA_DTYPE.get(descriptor.dtype), (None, None))
            if low is not None and not low <= integer <= high:
                raise ValueError(f"integrator.{name} = {integer} does not fit the field's C type "
                                 f"({low} to {high}); not set")
        if self.name != INTEGRATOR_NAME.encode():
            return generic(self, name, value)
        if _is_bool(value):
            # (ctypes stored True as 1: stages = True ran on as s = 1 and
            # was refused only at the next step)
            raise TypeError(f"integrator.{name} = {value!r} is a bool; it takes {_FIELD_KINDS.get(name, 'a number')}; "
                            f"not set")
        try:
            generic(self, name, value)
        except TypeError as error:
            # (ctypes says only "'float' object cannot be interpreted as an
            # integer": the user should learn which field and what it takes)
            kind = _FIELD_KINDS.get(name)
            wanted = f"; it takes {kind}" if kind else ""
            raise TypeError(f"integrator.{name} = {value!r} has the wrong type{wanted}; not set "
                            f"({error})") from None

    __setattr__._pfvi = True
    IntegratorConfiguration.__setattr__ = __setattr__


_refuse_integers_that_wrap()


def _is_bool(value: Any) -> bool:
    """Python's bool or numpy's (told by its type's name: numpy is not
    imported for it, and may be half imported in another thread)."""
    kind = type(value)
    return isinstance(value, bool) or (kind.__module__ == "numpy" and kind.__name__ in ("bool_", "bool"))


def _is_nan(value: Any) -> bool:
    """A NaN of any kind that converts to a float (Python's, numpy's scalars, a 0-d array)."""
    try:
        return _math.isnan(value)
    except (TypeError, ValueError):
        return False


def _tell_the_requested_time():
    """sim.integrate(tmax) for "pfvi" tells the core tmax while REBOUND's
    integrate runs. REBOUND decides whether a step finishes on tmax by
    comparing t + sim.dt with it; what pfvi shows next may lie further (a
    new simulation's first step, the run's end taken up after an output),
    and without tmax such a state past it was shown to REBOUND's collision
    search, Encounter, Escape, heartbeat and archive before the call came
    back to tmax (docs/outputs.md). Every other integrator's call is
    REBOUND's own."""
    from rebound import Simulation

    generic = Simulation.integrate
    if getattr(generic, "_pfvi", False):
        return

    begin, end, address = _lib.pfvi_request_begin, _lib.pfvi_request_end, _ctypes.addressof
    name = INTEGRATOR_NAME.encode()

    def integrate(self, tmax, exact_finish_time=1):
        if self.integrator.name != name:
            return generic(self, tmax, exact_finish_time)
        if _is_nan(tmax):
            # (REBOUND would step for ever: no t reaches NaN, and none passes it)
            raise ValueError("sim.integrate(tmax): tmax is NaN; nothing integrated")
        try:
            held = begin(address(self), tmax)
        except _ctypes.ArgumentError:
            return generic(self, tmax, exact_finish_time)   # (REBOUND's own error for such a tmax)
        try:
            return generic(self, tmax, exact_finish_time)
        finally:
            end(address(self), held)   # (what an enclosing call asked for: NaN, none)

    integrate.__doc__ = generic.__doc__
    integrate.__wrapped__ = generic
    integrate._pfvi = True
    Simulation.integrate = integrate


_tell_the_requested_time()


def _check_stages(s):
    # (an integer of any kind; 3.0 and True were taken for 3 and 1)
    try:
        index = None if _is_bool(s) else _operator.index(s)
    except TypeError:
        index = None
    if index not in STAGES:
        raise ValueError(f"s={s!r} is not valid; allowed: {', '.join(map(str, STAGES))}")
    return index


def _real(name: str, value: Any, at_least: Any = None, above: Any = None, below: Any = None) -> float:
    """value as a float, refused by name where it is not a finite real number
    (the inspection functions returned NaN for NaN, and a limited omega of
    10 for omega = NaN) or lies below at_least, at or below above, or at or
    above below."""
    if isinstance(value, bool):
        raise TypeError(f"{name}={value!r} is a bool; it takes a real number")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}={value!r} is not a real number") from None
    if (not _math.isfinite(x) or (at_least is not None and x < at_least) or (above is not None and not x > above)
            or (below is not None and not x < below)):
        bounds = "".join(((f" and >= {at_least}" if at_least is not None else ""),
                          (f" and > {above}" if above is not None else ""),
                          (f" and < {below}" if below is not None else "")))
        raise ValueError(f"{name}={value!r} is not valid; it must be finite{bounds}")
    return x


def _finite_out(values: Any, what: str) -> None:
    """Refuses a result that overflowed (u near the largest double: 1e308 gave
    inf and NaN back without a word)."""
    if not all(_math.isfinite(x) for x in values):
        raise ValueError(f"{what}: the result overflows (not finite)")


def seed_coefficients(u: float, c: float) -> Tuple[float, ...]:
    """The seed's fitted interpolation coefficients (b, bbar, B, Bbar) at node c.

    ``q^j = b q_k + bbar q_k+1`` and ``h qdot^j = B q_k + Bbar q_k+1`` with
    u = omega h (seed section 3). At u = 0 they are the linear limits.
    """
    out = (_ctypes.c_double * 4)()
    _lib.pfvi_seed_coefficients(_real("u", u), _real("c", c), out)
    _finite_out(out, f"seed_coefficients(u={u!r}, c={c!r})")
    return tuple(out)


def gamma(u: float) -> float:
    """gamma(u) = u cot(u): the factor by which the printed two-point Ld scales
    the exact discrete Lagrangian of the oscillator, and its momenta."""
    value = _lib.pfvi_gamma(_real("u", u))
    _finite_out((value,), f"gamma(u={u!r})")
    return value


def two_point_coefficients(omega: float, h: float, u_max: float = 1.0, fitting: str = "phase") -> Dict[str, Any]:
    """Coefficients of one two-point step, as used by the C core.

    Returns a dict with omega (after limiting), cos_u, h_sinc_u,
    omega_sin_u, half_kick, gamma and ``limited``. Raises ValueError naming
    the argument for an unknown fitting, and when u lies at a pole.
    """
    if fitting not in FITTINGS:
        raise ValueError(f"fitting={fitting!r} is not valid; allowed: {', '.join(FITTINGS)}")
    omega = 0.0 if fitting == "none" else _real("omega", omega, at_least=0.0)
    h = _real("h", h)
    u_max = _real("u_max", u_max, above=0.0, below=_math.pi)
    out = (_ctypes.c_double * 6)()
    status = _lib.pfvi_two_point_coefficients(omega, h, u_max,
                                              int(fitting == "phase-literal"), out)
    if status < 0:
        raise ValueError(f"omega*h = {omega * h!r} lies at a pole of the two-point coefficients")
    keys = ("omega", "cos_u", "h_sinc_u", "omega_sin_u", "half_kick", "gamma")
    _finite_out(out, f"two_point_coefficients(omega={omega!r}, h={h!r})")
    result: Dict[str, Any] = dict(zip(keys, out))
    result["limited"] = bool(status == 1)
    return result


def lobatto(s: int) -> Tuple[Any, Any, Any]:
    """The Gauss-Lobatto rule of the s-stage discrete Lagrangian, as the C core computes it.

    Returns numpy arrays ``(c, w, a)``: nodes on [0, 1], weights, and the
    differentiation matrix ``a[k, j]`` with ``sum_j a[k, j] c[j]**n = n c[k]**(n-1)``
    (seed section 6).
    """
    import numpy as np

    s = _check_stages(s)
    c, w, a = (_ctypes.c_double * s)(), (_ctypes.c_double * s)(), (_ctypes.c_double * (s * s))()
    _lib.pfvi_lobatto_table(s, c, w, a)
    return np.array(c), np.array(w), np.array(a).reshape(s, s)


def nystrom(s: int) -> Tuple[Any, Any, Any]:
    """The classical (u = 0) s-stage step as the C core takes it: Lobatto
    IIIA-IIIB in Runge-Kutta-Nystrom form, in units of the weights w.

    Returns numpy arrays ``(c_nu, nu, mu_hat)``: the stage positions are
    ``Q_i = q + c_nu[i] h v + h**2 sum_j nu[i, j] w[j] A_j``, the stage
    velocities (for velocity-dependent forces) ``V_i = v + h sum_j mu_hat[i, j]
    w[j] A_j``. c_nu and nu lie on a grid of 2**-50 on which the identities of
    symplecticity and symmetry hold exactly in doubles (docs/roundoff.md).
    """
    import numpy as np

    s = _check_stages(s)
    c, nu, mu_hat = (_ctypes.c_double * s)(), (_ctypes.c_double * (s * s))(), (_ctypes.c_double * (s * s))()
    _lib.pfvi_nystrom_table(s, c, nu, mu_hat)
    return np.array(c), np.array(nu).reshape(s, s), np.array(mu_hat).reshape(s, s)


def stage_coefficients(s: int, u: float) -> Dict[str, Any]:
    """The fitted stage coefficients of the s-stage step at u = omega h.

    Returns a dict of numpy arrays over the nodes: the seed's ``b``, ``bbar``,
    ``B``, ``Bbar``, the combinations ``beta_m`` = b + bbar - 1 and ``beta_d``
    = B + Bbar, and the scalars ``gamma`` (the momentum normalisation of
    fitting "phase") and ``det_ratio`` (determinant of the stage matrix over
    its value at u = 0; steps where it is below 1e-3 are refused).
    """
    import numpy as np

    s = _check_stages(s)
    out = (_ctypes.c_double * (2 + 6 * s))()
    _lib.pfvi_stage_coefficients(s, _real("u", u), out)
    _finite_out(out, f"stage_coefficients(s={s}, u={u!r})")
    values = np.array(out)
    result: Dict[str, Any] = {"gamma": float(values[0]), "det_ratio": float(values[1])}
    for k, name in enumerate(("b", "bbar", "B", "Bbar", "beta_m", "beta_d")):
        result[name] = values[2 + k * s: 2 + (k + 1) * s]
    return result


def stage_differentiation(s: int, u: float, fitting: str = "exact") -> Any:
    """The differentiation matrix ``a[k, j]`` (the slope of correction function j
    at node k) that the s-stage step of ``fitting`` uses at u = omega h.

    The rule's (``lobatto(s)[2]``) for every fitting but "exact", whose
    interior columns are corrected so that the stationarity equations hold
    on the oscillator's exact path (docs/method.md).
    """
    import numpy as np

    s = _check_stages(s)
    if fitting not in FITTINGS:
        raise ValueError(f"fitting={fitting!r} is not valid; allowed: {', '.join(FITTINGS)}")
    out = (_ctypes.c_double * (s * s))()
    _lib.pfvi_stage_differentiation(s, _real("u", u), FITTINGS.index(fitting), out)
    _finite_out(out, f"stage_differentiation(s={s}, u={u!r})")
    return np.array(out).reshape(s, s)
