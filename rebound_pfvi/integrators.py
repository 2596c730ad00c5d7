"""One way to set up an integrator from (family, options): the comparisons,
the stability cases, the paper's figures, the examples and the benchmarks all
configure their integrators here.

    configure(sim, "pfvi", dt=0.01, stages=4, fitting="phase", epsilon=1e-8)
    configure(sim, "ias15", epsilon=1e-9)
    configure(sim, "bs", eps=1e-10)          # BS's eps_abs and eps_rel
    configure(sim, "whfast", dt=1e-3, corrector=11)
    configure(sim, "trace", dt=1e-3)            # r_crit_hill, peri_crit_eta: REBOUND's

Options are the integrator's own fields (``help(sim.integrator)``), set after
``sim.integrator = family``; ``dt`` is ``sim.dt``. An unknown family or option
raises ValueError naming it; a bad value is the integrator's to refuse (pfvi's
when the next step starts).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping

if TYPE_CHECKING:
    import rebound

#: The integrator families the comparisons know. TRACE and MERCURIUS run at
#: REBOUND's defaults for their switching (TRACE: r_crit_hill 3,
#: peri_crit_eta 1, peri_mode "FULL_BS"; MERCURIUS: r_crit_hill 3) unless a
#: setting names them; their knob, like WHFast's and LEAPFROG's, is the step.
FAMILIES = ("pfvi", "ias15", "whfast", "leapfrog", "bs", "trace", "mercurius")

#: WHFast's symplectic corrector (Wisdom, Holman & Touma 1996), compare's
#: line beside plain WHFast, with safe_mode 0 as REBOUND advises for it: in safe
#: mode every step is synchronized, which applies the corrector and its
#: inverse each step (measured: 33x the wall time on the outer solar system
#: at 1000 steps per period, the same error).
WHFAST_CORRECTED = (("corrector", 11), ("safe_mode", 0))

#: pfvi's frequency and centre as the seed prints its scheme (K&V: the
#: curvature frequency, the harmonic model about the coordinate origin);
#: with fitting "phase" or "phase-literal" they reproduce its figures.
SEED_MODEL: dict[str, Any] = {"frequency": "curvature", "centre": "origin"}
#: The fittings that are the seed's scheme (with SEED_MODEL).
SEED_FITTINGS = ("phase", "phase-literal")


def pfvi_options(options: Mapping[str, Any]) -> dict[str, Any]:
    """The options a pfvi run sets: those named, and for the seed's fittings
    the seed's frequency and centre unless named; everything else stays
    pfvi's default (:data:`rebound_pfvi.DEFAULTS`)."""
    opts = dict(options)
    if opts.get("fitting") in SEED_FITTINGS:
        opts = {**SEED_MODEL, **opts}
    return opts


def pfvi_label(options: Mapping[str, Any]) -> str:
    """A pfvi line's name from its options: "pfvi s=8" at the defaults, the
    options that differ from them after s ("pfvi s=4 exact", "pfvi s=6
    reversible"), and "pfvi seed s=4 phase reversible" for the seed's scheme
    (its fittings, with its frequency and centre)."""
    from . import DEFAULTS

    opts = pfvi_options(options)
    seed = opts.get("fitting") in SEED_FITTINGS
    label = "pfvi seed" if seed else "pfvi"
    label += f" s={opts.get('stages', DEFAULTS['stages'])}"
    model = SEED_MODEL if seed else {}
    for name in ("fitting", "step_control", "frequency", "centre", "u_max", "omega"):
        if name in opts and opts[name] != model.get(name, DEFAULTS[name]):
            value = opts[name]
            label += f" {value}" if name in ("fitting", "step_control") else f" {name}={value}"
    return label


def integrator_fields(sim: rebound.Simulation) -> set:
    """The settable fields of sim's integrator (REBOUND's field descriptors)."""
    descriptors = sim.integrator.callbacks.field_descriptor_list
    return {fd.name.decode() for fd in descriptors} if descriptors else set()


def configure(sim: rebound.Simulation, family: str, dt: float | None = None, **options: Any) -> rebound.Simulation:
    """Sets ``sim.integrator = family`` and then each option; returns sim."""
    if family not in FAMILIES:
        raise ValueError(f"family={family!r} is not an integrator family; allowed: {', '.join(FAMILIES)}")
    sim.integrator = family
    if family == "bs" and "eps" in options:
        eps = options.pop("eps")
        options.update(eps_abs=eps, eps_rel=eps)
    fields = integrator_fields(sim)
    for name, value in options.items():
        if name not in fields:
            raise ValueError(f"{name}={value!r} is not an option of {family}; it has: {', '.join(sorted(fields))}")
        try:
            setattr(sim.integrator, name, value)
        except (TypeError, ValueError) as error:
            if f"integrator.{name}" in str(error):
                raise
            # (REBOUND's own say only "must be real number, not str")
            raise type(error)(f"integrator.{name} = {value!r} for {family}: {error}") from None
    if dt is not None:
        sim.dt = dt
    return sim
